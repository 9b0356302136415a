"""Array plumbing shared by every model: validation, dtype choice, broadcasting, out=."""
from __future__ import annotations

import math
import numbers

import numpy as np

from ._validate import check_int  # noqa: F401  (re-exported: the door's callers import it from here)

__all__ = ["as_dirs", "kernel_dtype", "flatten_to", "check_out", "as_uniform"]


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
    return a  # values in [0, 1] (no NaN): counted by the sample kernel (cpp/include/bsdfkit/batch.h)


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


def _canonical(a: np.ndarray, dtype) -> np.ndarray:
    """`a` viewed with numpy's canonical descriptor of `dtype`: an unpickled array (e.g. a Dask
    block) carries an equal but distinct descriptor object, which the bindings' dtype check
    (identity, bind_model.h is_dtype) would refuse."""
    dtype = np.dtype(dtype)
    return a if a.dtype is dtype else a.view(dtype)


def flatten_to(a: np.ndarray, batch: tuple, tail: tuple, dtype) -> np.ndarray:
    """Rows of `a` for the kernel: 1 row if `a` is a single item, else one per batch element."""
    if a.shape[: a.ndim - len(tail)] == batch:
        return _canonical(np.ascontiguousarray(a, dtype=dtype), dtype).reshape((-1,) + tail)
    if math.prod(a.shape[: a.ndim - len(tail)]) == 1:
        return _canonical(np.ascontiguousarray(a, dtype=dtype), dtype).reshape((1,) + tail)
    return _canonical(np.ascontiguousarray(np.broadcast_to(a, batch + tail), dtype=dtype), dtype).reshape((-1,) + tail)


def planes_order(batch: tuple, *arrays: np.ndarray) -> str:
    """eval's result layout: "F" (Fortran order: the x, y, z planes, as the compiled fast path
    returns, cpp/bindings/bind_model.h) when the batch is 1-D of more than one element and
    every direction array of the full batch is a Fortran-order (N, 3) array, else "C" (numpy's
    order='K' rule)."""
    full = [a for a in arrays if a.shape[:-1] == batch]
    if len(batch) != 1 or batch[0] < 2 or not full:
        return "C"
    return "F" if all(a.flags.f_contiguous and not a.flags.c_contiguous for a in full) else "C"


def check_out(out, shape: tuple, dtype, order: str = "C", fortran_ok: bool = False) -> np.ndarray:
    """Validates a user-supplied output array or allocates one (in `order`). fortran_ok: a
    Fortran-order `out` is accepted too (eval's (N, 3) planes); the caller then writes through
    a C-order buffer (write_out)."""
    if out is None:
        return np.empty(shape, dtype=dtype, order=order)
    if not isinstance(out, np.ndarray):
        raise TypeError(f"out: expected a numpy.ndarray, got {type(out).__name__}")
    if out.dtype != dtype:
        raise TypeError(f"out: dtype must be {dtype} for these inputs, got {out.dtype}")
    if out.shape != shape:
        raise ValueError(f"out: shape must be {shape}, got {out.shape}")
    if fortran_ok and out.flags.f_contiguous and out.flags.writeable:
        return out
    if not out.flags.c_contiguous or not out.flags.writeable:
        raise ValueError("out: must be a writeable C-contiguous array" +
                         (" or a writeable Fortran-order (N, 3) array" if fortran_ok else ""))
    return out


def c_buffer(out: np.ndarray) -> np.ndarray:
    """`out` itself when C-contiguous, else a C-order scratch array of its shape and dtype whose
    values the caller copies into `out` (np.copyto) after the kernel."""
    return out if out.flags.c_contiguous else np.empty(out.shape, dtype=out.dtype)


def check_real(x, name: str) -> float:
    """A finite real scalar (bool, strings and arrays refused), as float."""
    if isinstance(x, bool) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name}: expected a real number, got {type(x).__name__}")
    v = float(x)
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {v}")
    return v


# albedo's n_samples: 2**40 samples per direction run for hours already; beyond 2**63 the C++
# side cannot even take the number. Its twin: bind_model.h PyModel::kMaxAlbedoSamples.
MAX_ALBEDO_SAMPLES = 2 ** 40


_M64 = np.uint64(0xFFFFFFFFFFFFFFFF)
#: The stream constant of seeded ``sample`` uniforms (cpp/bindings/bind_model.h fill_uniforms).
_SAMPLE_STREAM = 0x5A3D1E


def _mix64(z: np.ndarray) -> np.ndarray:
    """SplitMix64's finaliser (Steele, Lea, Flood 2014) on uint64 arrays (wrapping arithmetic),
    the hash of cpp/include/bsdfkit/core/rng.h mix64."""
    z = z + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


def seeded_uniforms(seed, batch: tuple, dtype):
    """``sample(n=, seed=)``'s uniforms ``uc`` (batch) and ``u`` (batch + (2,)) of element i from a
    counter hash of (seed, i), as the compiled door draws them (bind_model.h fill_uniforms): the
    same values in RGB and spectral mode, for any thread count. ``seed``: an integer >= 0 (used
    modulo 2**64) or None (drawn from the system's entropy)."""
    import secrets
    if seed is None:
        seed = secrets.randbits(64)
    elif isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise TypeError(f"seed: expected a non-negative integer or None, got {type(seed).__name__}")
    elif seed < 0:
        raise ValueError(f"seed: must be >= 0 (or None), got {seed}")
    dtype = np.dtype(dtype)
    n = math.prod(batch)
    with np.errstate(over="ignore"):
        s = _mix64(np.array([int(seed) & 0xFFFFFFFFFFFFFFFF], np.uint64))
        h = _mix64(_mix64(s ^ np.arange(n, dtype=np.uint64)) ^ np.uint64(_SAMPLE_STREAM))
        bits = [_mix64(h ^ np.uint64(k)) for k in (1, 2, 3)]
    if dtype == np.float32:
        uni = [(b >> np.uint64(40)).astype(np.float32) * np.float32(2.0 ** -24) for b in bits]
    else:
        uni = [(b >> np.uint64(11)).astype(np.float64) * 2.0 ** -53 for b in bits]
    return uni[0].reshape(batch), np.stack(uni[1:], -1).reshape(batch + (2,))


def sample_uniforms(wo: np.ndarray, uc, u, n, seed, names: tuple = (), shapes: tuple = ()):
    """The uniforms of a ``sample`` call: drawn from ``seed`` when ``n`` is given
    (:func:`seeded_uniforms`), else the user's ``uc``, ``u`` (their ranges are counted by the
    kernel). ``names``/``shapes``: further batch inputs besides ``wo`` (e.g. wavelengths).
    Returns (uc, u, dtype, batch). The RGB models' door does this in C++ (bind_model.h); the
    spectral calls and ``Custom`` use this one."""
    if n is not None:
        if uc is not None or u is not None:
            raise ValueError("n: give either n (and seed) or the uniforms uc and u, not both")
        n = check_int(n, "n", 0)
        batch = broadcast_batch(("wo",) + names + ("n",), wo.shape[:-1], *shapes, (n,))
        dtype = kernel_dtype(wo)
        uc, u = seeded_uniforms(seed, batch, dtype)
        return uc, u, dtype, batch
    if uc is None or u is None:
        raise ValueError("uc, u: pass both uniforms, or n= and seed=")
    uc, u = as_uniform(uc, "uc", ()), as_uniform(u, "u", (2,))
    dtype = kernel_dtype(wo, uc, u)
    batch = broadcast_batch(("wo", "uc", "u") + names, wo.shape[:-1], uc.shape, u.shape[:-1], *shapes)
    return uc, u, dtype, batch
