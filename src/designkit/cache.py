"""designkit's cache directory: compiled C of models and simulators, compiled report templates.

Everything cached is keyed by its content (source hash, compiler and flags, library versions),
so a stale entry is never used; deleting the directory only costs the time to rebuild.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["cache_dir"]


def cache_dir(kind: str) -> Path:
    """The cache folder for ``kind`` (e.g. ``"codegen"``, ``"templates"``); not created here.

    Returns
    -------
    pathlib.Path
        ``$DESIGNKIT_CACHE_DIR/<kind>`` if that variable is set, else
        ``$XDG_CACHE_HOME/designkit/<kind>``, else ``~/.cache/designkit/<kind>``.
    """
    root = os.environ.get("DESIGNKIT_CACHE_DIR")
    if root:
        return Path(root) / kind
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "designkit" / kind
