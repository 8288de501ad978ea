"""Headless Chromium for the layout tests: a report page laid out at a given window width, measured.

The page is loaded in an ``<iframe srcdoc>`` of exactly the width asked inside a wider window (headless
Chromium does not make windows narrower than 500 px), and a script in the page measures it and writes the
result, as JSON, into the outer page, which ``--dump-dom`` prints.
"""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

_NAMES = ("chromium", "chromium-browser", "chromium-headless-shell", "google-chrome", "google-chrome-stable")
SKIP_REASON = ("no headless Chromium on PATH (chromium, chromium-headless-shell, google-chrome): "
               "the layout checks need a browser")

# What overflows: an element wider than its parent's content box (parents that are not table parts and
# do not scroll), a scroll container whose content is wider than it, the document wider than the window;
# and the on-screen size (px) of every <text> of the figures that are displayed.
_PROBE = r"""
(function () {
  function desc(el) {
    var s = el.tagName.toLowerCase();
    if (el.id) s += '#' + el.id;
    if (typeof el.className === 'string' && el.className.trim()) s += '.' + el.className.trim().split(/\s+/).join('.');
    return s + ' "' + (el.textContent || '').trim().replace(/\s+/g, ' ').slice(0, 60) + '"';
  }
  function contentRight(p) {
    var r = p.getBoundingClientRect();
    return r.left + p.clientLeft + p.clientWidth - parseFloat(getComputedStyle(p).paddingRight);
  }
  var out = {overflow: [], scroll: [], text_px: [], figures: []};
  var all = document.querySelectorAll('body *');
  for (var i = 0; i < all.length; i++) {
    var el = all[i];
    if (el.closest('svg')) continue;
    var st = getComputedStyle(el);
    if (st.display === 'none' || st.display === 'contents' || el.getBoundingClientRect().width === 0) continue;
    if (el.closest('math') && el.tagName.toLowerCase() !== 'math') continue;
    if (st.overflowX !== 'visible' && el.scrollWidth > el.clientWidth + 1) {
      out.scroll.push((el.scrollWidth - el.clientWidth) + ' px ' + desc(el));
    }
    var p = el.parentElement, ps = p && getComputedStyle(p);
    if (p && ps.overflowX === 'visible' && ps.display.indexOf('table-') !== 0 && st.display.indexOf('table-') !== 0
        && st.display !== 'inline' && p.clientWidth > 0) {
      var over = el.getBoundingClientRect().right - contentRight(p);
      if (over > 1) out.overflow.push(Math.round(over) + ' px ' + desc(el) + ' in ' + desc(p));
    }
  }
  var svgs = document.querySelectorAll('svg.figure-svg');
  for (var k = 0; k < svgs.length; k++) {
    var svg = svgs[k];
    if (svg.getBoundingClientRect().width === 0) continue;
    var scale = svg.getScreenCTM().a, texts = svg.querySelectorAll('text'), least = Infinity;
    for (var j = 0; j < texts.length; j++) {
      var px = parseFloat(getComputedStyle(texts[j]).fontSize) * scale;
      if (texts[j].textContent.trim()) least = Math.min(least, px);
    }
    out.figures.push({id: svg.closest('figure').id, narrow: !!svg.closest('.fig-narrow'),
                      width: svg.getBoundingClientRect().width, least_text_px: least});
  }
  out.document_width = document.documentElement.scrollWidth;
  out.window_width = window.innerWidth;
  parent.document.getElementById('probe').textContent = JSON.stringify(out);
})();
"""


def browser() -> str | None:
    """The path of a headless-capable Chromium on PATH, or None."""
    for name in _NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


def measure(page: str, width: int) -> dict:
    """Lay the HTML document ``page`` out ``width`` CSS px wide in headless Chromium and measure it: lists
    ``overflow`` and ``scroll`` (descriptions of what is wider than its box), ``figures`` (each displayed
    figure's id, whether it is the narrow variant, its width and the smallest on-screen size of its text,
    px), ``document_width`` and ``window_width``."""
    inner = page.replace("</body>", f"<script>{_PROBE}</script></body>")
    outer = ('<!DOCTYPE html><html><body style="margin:0">'
             f'<iframe style="border:0;width:{width}px;height:900px" srcdoc="{html.escape(inner, quote=True)}">'
             '</iframe><pre id="probe"></pre></body></html>')
    with tempfile.TemporaryDirectory(prefix="designkit-layout-") as tmp:
        path = Path(tmp) / "page.html"
        path.write_text(outer, encoding="utf-8")
        done = subprocess.run(
            [browser(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={Path(tmp) / 'profile'}", f"--window-size={max(width, 500) + 100},1000",
             "--dump-dom", path.as_uri()],
            capture_output=True, text=True, timeout=180)
    found = re.search(r'<pre id="probe">(.*?)</pre>', done.stdout, flags=re.S)
    if found is None or not found.group(1).strip():
        raise AssertionError(f"the layout probe did not run: {done.stderr[-500:]}")
    return json.loads(html.unescape(found.group(1)))
