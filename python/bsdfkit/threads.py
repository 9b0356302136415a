"""Worker threads of the array kernels, and the memory they keep for reuse."""
from __future__ import annotations

import numpy as np

from . import _core

__all__ = ["set_num_threads", "get_num_threads", "release_memory"]


# The pool keeps up to n - 1 helper threads alive: far more than any machine's cores would only
# exhaust the process's threads (set_num_threads(10**6) was accepted, 2**31 failed in pybind).
MAX_THREADS = 1024


def set_num_threads(n: int) -> None:
    """Set the number of worker threads of the array kernels.

    Results do not depend on it: every element is computed independently and reductions use
    fixed blocks.

    Parameters
    ----------
    n : int
        1 to 1024 (the default is all cores).

    Raises
    ------
    TypeError
        When ``n`` is not an integer.
    ValueError
        When ``n`` is outside [1, 1024].

    Examples
    --------
    >>> import bsdfkit as bk
    >>> before = bk.get_num_threads()
    >>> bk.set_num_threads(1)
    >>> bk.get_num_threads()
    1
    >>> bk.set_num_threads(before)
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"n: expected an integer, got {type(n).__name__}")
    if not 1 <= n <= MAX_THREADS:
        raise ValueError(f"n: number of threads must be in [1, {MAX_THREADS}], got {n}")
    _core.set_num_threads(int(n))


def get_num_threads() -> int:
    """The current number of worker threads of the array kernels (see :func:`set_num_threads`).

    Returns
    -------
    int
    """
    return _core.get_num_threads()


def release_memory() -> int:
    """Free the output blocks bsdfkit keeps for reuse.

    ``sample`` at large N puts its seven outputs in one block, and ``eval`` / ``pdf`` results from
    1 MiB on are blocks too (64-byte aligned: the memory-bound models stream into them); when a
    result is freed, its block (at most two of them, 512 MiB in all) is kept so that the next call
    finds its pages already mapped instead of faulting tens of MB in again (at N = 1e6 that cost
    more than the kernel). Call this to give that memory back, e.g. before a memory-hungry step in
    the same process.

    Returns
    -------
    int
        The number of bytes released.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.release_memory() >= 0
    True
    """
    return int(_core.release_memory())
