"""One BLAS thread while a frame is tracked.

The tracker's matrix products are small (a few thousand rows by a few dozen columns): BLAS
workers on other cores save little on them and, on a two-core machine, stall the tracker while
they wait for the core that reads the next frame (``core.sequence``), and once woken they spin
there (``sched_yield``) for a while after the product is done: a frame's every product, the
backdrops' learning from it included, runs on one thread. The thread count is put back after
each frame, so the rest of the process (Blender, other add-ons) keeps its own.

This talks to the OpenBLAS that numpy's wheels bundle, found beside numpy; with any other BLAS
it does nothing.
"""

from __future__ import annotations

import ctypes
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache
from pathlib import Path

import numpy as np

# the names OpenBLAS builds give the thread-count calls: numpy's 64-bit-index build, numpy
# 2's scipy-openblas, and a plain build
_PREFIXES = ("openblas_", "scipy_openblas_")
_SUFFIXES = ("64_", "")


@cache
def _thread_calls() -> tuple[ctypes._CFuncPtr, ctypes._CFuncPtr] | None:
    """(get, set) of numpy's OpenBLAS thread count, or None where there is none."""
    here = Path(np.__file__).parent
    for folder in (here.parent / "numpy.libs", here / ".dylibs", here / ".libs"):
        for path in sorted(folder.glob("*openblas*")) if folder.is_dir() else ():
            try:
                lib = ctypes.CDLL(str(path))  # the copy numpy loaded: same file, same handle
            except OSError:
                continue
            for prefix in _PREFIXES:
                for suffix in _SUFFIXES:
                    get = getattr(lib, f"{prefix}get_num_threads{suffix}", None)
                    put = getattr(lib, f"{prefix}set_num_threads{suffix}", None)
                    if get is not None and put is not None:
                        get.restype, put.argtypes = ctypes.c_int, [ctypes.c_int]
                        return get, put
    return None


def blas_threads() -> int | None:
    """The number of threads numpy's OpenBLAS uses now (None: not an OpenBLAS found here)."""
    calls = _thread_calls()
    return None if calls is None else int(calls[0]())


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the body with numpy's OpenBLAS on one thread, then put the count back."""
    calls = _thread_calls()
    if calls is None:
        yield
        return
    get, put = calls
    before = get()
    put(1)
    try:
        yield
    finally:
        put(before)
