"""SVG rendering helpers: decimation, text as <text> in DejaVu Sans, determinism, artist tags."""

from __future__ import annotations

import re

import numpy as np

from designkit.display import svg


def test_minmax_decimate_keeps_extremes_and_bounds_the_length():
    t = np.linspace(0, 1, 100_001)
    y = np.sign(np.sin(2 * np.pi * 500 * t))  # chattering signal
    y[12345] = 7.0
    td, yd = svg.minmax_decimate(t, y, max_points=1000)
    assert td.size <= 1000 and np.all(np.diff(td) > 0)
    assert yd.max() == 7.0 and yd.min() == -1.0
    short = np.arange(5.0)
    assert svg.minmax_decimate(short, short)[0] is not None and svg.minmax_decimate(short, short)[0].size == 5


def _labelled(xlabel: str = "time (s)", ylabel: str = "control (N·m)"):
    def draw():
        fig, (ax,) = svg.new_figure(3.0, 2.0)
        line = ax.plot([0.0, 1.0], [0.0, 2.0], label="u")[0]
        svg.tag(fig, "control", line)
        svg.tag(fig, "control", ax.axhline(1.0))
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        return fig

    return draw


def test_text_is_svg_text_in_dejavu_sans_with_a_css_fallback():
    out = svg.render(_labelled())
    assert re.search(r"<text\b[^>]*>time \(s\)</text>", out)
    assert re.search(r"<text\b[^>]*>control \(N·m\)</text>", out)
    assert "font-family: 'DejaVu Sans', 'Arial', sans-serif" in out
    assert 'id="DejaVuSans-' not in out  # no glyph outlines


def test_render_is_deterministic_byte_for_byte():
    first, second = svg.render(_labelled()), svg.render(_labelled())
    assert first.encode("utf-8") == second.encode("utf-8")
    assert "<dc:date>" not in first


def test_tags_are_unique_ids_and_read_back_from_figure_and_svg():
    svg_text, keys, info = svg.render_tagged(_labelled())
    assert keys == ("control",) and info == {}
    assert 'id="dk-control"' in svg_text and 'id="dk-control--1"' in svg_text
    assert svg.svg_keys(svg_text) == ("control",)
    assert svg.tag_key("dk-a-b--12") == "a-b" and svg.tag_key("axes_1") is None


def test_the_figure_font_ships_with_matplotlib():
    files = svg.font_files()
    assert files and files[0].name == "DejaVuSans.ttf" and all(f.stat().st_size > 100_000 for f in files)
