"""Compiled report templates, cached on disk (Jinja's bytecode cache).

Compiling the two report templates (HTML and Typst) takes a tenth of a second or more on every
run; Jinja can keep the compiled code, keyed by the template's source checksum and by the
Jinja and Python versions, so an edited template or an upgrade is never served stale.  The cache
lives in :func:`designkit.cache.cache_dir` ``("templates")``; when that folder cannot be created
or written, or a cache file cannot be read or written, the template is compiled in memory as
before: the cache can only save time, never fail a report.
"""

from __future__ import annotations

import contextlib
import os
from functools import cache
from typing import Any

__all__ = ["bytecode_cache"]


@cache
def bytecode_cache() -> Any:
    """A :class:`jinja2.FileSystemBytecodeCache` in designkit's cache folder that ignores I/O errors,
    or None when the folder is not writable."""
    import jinja2

    from designkit.cache import cache_dir

    class TolerantCache(jinja2.FileSystemBytecodeCache):
        def load_bytecode(self, bucket: Any) -> None:
            with contextlib.suppress(OSError, EOFError, ValueError):
                super().load_bytecode(bucket)

        def dump_bytecode(self, bucket: Any) -> None:
            with contextlib.suppress(OSError):
                super().dump_bytecode(bucket)

    folder = cache_dir("templates")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    if not os.access(folder, os.W_OK | os.X_OK):
        return None
    return TolerantCache(str(folder))
