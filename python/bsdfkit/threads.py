"""Worker threads of the array kernels."""
from __future__ import annotations

import numpy as np

from . import _core

__all__ = ["set_num_threads", "get_num_threads"]


def set_num_threads(n: int) -> None:
    """Number of worker threads for the array kernels (default: all cores). Results do not
    depend on it: every element is computed independently and reductions use fixed blocks."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"n: expected an integer, got {type(n).__name__}")
    _core.set_num_threads(int(n))


def get_num_threads() -> int:
    """Current number of worker threads of the array kernels."""
    return _core.get_num_threads()
