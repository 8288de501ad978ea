"""Keep a worker's large arrays on the heap: glibc's ``mallopt`` thresholds, set once per worker process.

Each run allocates and frees arrays of megabytes (the per-step inputs, the records).  Dask's nanny starts
workers with ``MALLOC_TRIM_THRESHOLD_=65536`` (to hand memory back to the system), and setting any such
variable freezes glibc's dynamic mmap threshold at 128 KiB: every one of those arrays is then a fresh
``mmap`` whose pages fault in on first touch and are unmapped on free.  Measured on the SIMNOG sweep (2 s
runs): 12 ms of CPU a sample in a Dask worker against 6 ms in a plain process, the difference all system
time.  Raising the mmap threshold to :data:`MMAP_THRESHOLD` and the trim threshold to :data:`TRIM_THRESHOLD`
(``mallopt``) keeps them on the heap, reused from run to run.  Without glibc nothing is changed.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools

__all__ = ["MMAP_THRESHOLD", "TRIM_THRESHOLD", "keep_large_arrays_on_the_heap"]

MMAP_THRESHOLD = 64 << 20
"""Allocations below this (bytes) come from the heap."""
TRIM_THRESHOLD = 128 << 20
"""Free memory at the top of the heap beyond this (bytes) is returned to the system."""
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # glibc's mallopt parameters (malloc.h)


@functools.lru_cache(maxsize=1)
def keep_large_arrays_on_the_heap() -> bool:
    """Set the thresholds in this process (once); True when glibc accepted them."""
    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name) if name else None
        mallopt = libc.mallopt if libc is not None else None
    except (OSError, AttributeError):
        return False
    if mallopt is None:
        return False
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))
