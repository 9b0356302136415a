"""Array plumbing shared by every model: validation, dtype choice, broadcasting, out=."""
from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = ["as_dirs", "kernel_dtype", "flatten_to", "check_out", "as_uniform", "fast_pair", "fast_dirs", "fast_sample_args"]


def _as_real_array(x, name: str) -> np.ndarray:
    try:
        a = np.asarray(x)
    except Exception as e:  # ragged lists and the like
        raise TypeError(f"{name}: cannot be converted to a numeric array ({e})") from None
    if a.dtype.kind not in "fiu":
        raise TypeError(f"{name}: expected a real numeric array, got dtype {a.dtype}")
    return a


def as_dirs(x, name: str) -> np.ndarray:
    """`x` as an array of directions with last axis 3 (dtype kept; checked later by the kernel)."""
    a = _as_real_array(x, name)
    if a.dtype == np.float16:
        raise TypeError(f"{name}: float16 is not supported (its 11-bit significand cannot hold a unit vector to "
                        "the 1e-4 the kernels require); pass float32 (e.g. .astype(np.float32)) or float64")
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"{name}: expected an array of directions with last axis of length 3, got shape {a.shape}")
    return a


def as_uniform(x, name: str, tail: tuple) -> np.ndarray:
    a = _as_real_array(x, name)
    if a.shape[a.ndim - len(tail):] != tail or a.ndim < len(tail):
        raise ValueError(f"{name}: expected trailing shape {tail}, got {a.shape}")
    # min/max: one pass each and no temporary bool arrays; a NaN propagates and fails the test
    if a.size and not (a.min() >= 0 and a.max() <= 1):
        raise ValueError(f"{name}: sample values must lie in [0, 1] (and not be NaN)")
    return a


def kernel_dtype(*arrays: np.ndarray) -> np.dtype:
    """float32 kernels when every input is float32, float64 otherwise (numpy's promotion spirit)."""
    if all(a.dtype == np.float32 for a in arrays):
        return np.dtype(np.float32)
    return np.dtype(np.float64)


def broadcast_batch(names, *shapes) -> tuple:
    try:
        return np.broadcast_shapes(*shapes)
    except ValueError:
        desc = ", ".join(f"{n} {s}" for n, s in zip(names, shapes))
        raise ValueError(f"{' and '.join(names)}: batch shapes cannot be broadcast together ({desc})") from None


def flatten_to(a: np.ndarray, batch: tuple, tail: tuple, dtype) -> np.ndarray:
    """Rows of `a` for the kernel: 1 row if `a` is a single item, else one per batch element."""
    if a.shape[: a.ndim - len(tail)] == batch:
        return np.ascontiguousarray(a, dtype=dtype).reshape((-1,) + tail)
    if math.prod(a.shape[: a.ndim - len(tail)]) == 1:
        return np.ascontiguousarray(a, dtype=dtype).reshape((1,) + tail)
    return np.ascontiguousarray(np.broadcast_to(a, batch + tail), dtype=dtype).reshape((-1,) + tail)


def check_out(out, shape: tuple, dtype) -> np.ndarray:
    """Validates a user-supplied output array or allocates one."""
    if out is None:
        return np.empty(shape, dtype=dtype)
    if not isinstance(out, np.ndarray):
        raise TypeError(f"out: expected a numpy.ndarray, got {type(out).__name__}")
    if out.dtype != dtype:
        raise TypeError(f"out: dtype must be {dtype} for these inputs, got {out.dtype}")
    if out.shape != shape:
        raise ValueError(f"out: shape must be {shape}, got {out.shape}")
    if not out.flags.c_contiguous or not out.flags.writeable:
        raise ValueError("out: must be a writeable C-contiguous array")
    return out


def check_int(x, name: str, lo: int) -> int:
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        raise TypeError(f"{name}: expected an integer, got {type(x).__name__}")
    if x < lo:
        raise ValueError(f"{name}: must be >= {lo}, got {x}")
    return int(x)


# ---------------------------------------------------------------- fast paths
# The general path (asarray, broadcast_shapes, ascontiguousarray, ...) costs ~20 us per call,
# which dominates a call on one direction pair. These accept only the common cases -- C-contiguous
# float64 or float32 ndarrays of the same dtype whose batch shapes are equal or one of which is a
# single direction -- and return None otherwise (the caller then takes the general path, which
# also produces every error message). Values (finite, unit) are still checked by the kernel.
_F64 = np.dtype(np.float64)
_F32 = np.dtype(np.float32)


def fast_pair(wo, wi):
    """(wo rows, wi rows, batch shape, dtype) for the kernel, or None."""
    if type(wo) is not np.ndarray or type(wi) is not np.ndarray:
        return None
    dt = wo.dtype
    if (dt is not _F64 and dt is not _F32) or wi.dtype is not dt:
        return None
    so, si = wo.shape, wi.shape
    if not so or not si or so[-1] != 3 or si[-1] != 3 or not (wo.flags.c_contiguous and wi.flags.c_contiguous):
        return None
    if so == si or len(si) == 1:
        batch = so[:-1]
    elif len(so) == 1:
        batch = si[:-1]
    else:
        return None
    return wo.reshape(-1, 3), wi.reshape(-1, 3), batch, dt


def fast_dirs(wo):
    """(wo rows, batch shape, dtype) for a C-contiguous float64/float32 ndarray, or None."""
    if type(wo) is not np.ndarray:
        return None
    dt = wo.dtype
    if (dt is not _F64 and dt is not _F32) or not wo.shape or wo.shape[-1] != 3 or not wo.flags.c_contiguous:
        return None
    return wo.reshape(-1, 3), wo.shape[:-1], dt


def fast_sample_args(wo, uc, u):
    """(wo rows, uc rows, u rows, batch shape, dtype) for ``sample`` with explicit uniforms, or
    None: every argument a C-contiguous ndarray of one float dtype, uc of the batch shape, u of
    the batch shape + (2,), wo of the batch shape + (3,) or a single direction. The uniforms'
    range is checked here ([0, 1], no NaN)."""
    fp = fast_dirs(wo)
    if fp is None or type(uc) is not np.ndarray or type(u) is not np.ndarray:
        return None
    o, wb, dt = fp
    if uc.dtype is not dt or u.dtype is not dt or not (uc.flags.c_contiguous and u.flags.c_contiguous):
        return None
    batch = uc.shape
    if u.shape != batch + (2,) or (wb != batch and wb != ()):
        return None
    if u.size <= 32:  # a Python loop beats two numpy reductions on a few values
        vals = u.ravel().tolist() + uc.ravel().tolist()
        if not all(0.0 <= v <= 1.0 for v in vals):  # NaN fails the comparison too
            return None
    elif not (uc.min() >= 0 and uc.max() <= 1 and u.min() >= 0 and u.max() <= 1):
        return None  # the general path names the argument
    return o, uc.reshape(-1), u.reshape(-1, 2), batch, dt
