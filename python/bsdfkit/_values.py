"""Model and texture parameters as values: hashable keys, ``repr`` text and content digests of
arrays (``==``, ``hash`` and ``repr`` never print or compare a million numbers one by one)."""
from __future__ import annotations

import hashlib

import numpy as np


def digest(a: np.ndarray) -> str:
    """Content digest of an array parameter (hash, ==, repr without printing the values)."""
    h = hashlib.blake2b(digest_size=10)
    h.update(str((a.shape, a.dtype.str)).encode())
    h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def key_value(v):
    """A parameter value as a hashable key: a small 1-D array (an RGB value) by its values, a
    larger array (per-element parameters) by its shape and content digest."""
    if isinstance(v, np.ndarray):
        return tuple(v.tolist()) if v.ndim == 1 and v.size <= 12 else ("array", v.shape, digest(v))
    return v


def fmt_param(v) -> str:
    """A parameter value in ``repr``: Python's shortest round-trip floats; an array of more than
    12 values as its shape and digest (that repr cannot be evaluated back)."""
    if isinstance(v, np.ndarray):
        if v.size > 12:
            return f"<array {v.shape} digest {digest(v)}>"
        if v.ndim == 1:
            return "[" + ", ".join(repr(float(x)) for x in v) + "]"
        return repr(v.tolist())
    return repr(v)
