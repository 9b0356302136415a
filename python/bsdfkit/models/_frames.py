"""World-space directions in the array API: ``normal=`` and ``tangent=`` of ``eval``, ``pdf``,
``sample`` and ``albedo`` (issue 47 item 2, shading frames).

A call with ``normal=`` takes ``wo`` / ``wi`` in world space. Each element's frame (s, t, n) is

* ``n`` = the normal (checked: finite, ``|n|^2`` within 1e-4 of 1; then normalised in float64);
* with ``tangent=``: ``s`` = the tangent, which must be a unit vector (same tolerance) and
  perpendicular to the normal (``|s . n| <= 1e-4``; so a tangent parallel to the normal is refused,
  and nothing is silently Gram-Schmidt-ed into shape). The residual allowed by that tolerance is
  removed (``s - n (n . s)``, normalised) so that the frame is orthonormal to rounding;
  ``t = n x s`` (right-handed: ``s x t = n``);
* without a tangent: Duff et al. 2017's branchless basis of ``n``, the construction of pbrt-v4's
  ``CoordinateSystem`` and Mitsuba 3's ``coordinate_system`` (so the frame is ``mi.Frame3f(n)``'s).
  For n = (0, 0, 1) it is the identity (s = x, t = y); for n = (0, 0, -1) it is (x, -y, -z).

Directions go to the local frame as ``(w . s, w . t, w . n)``, the model runs as in a local call,
and ``sample``'s ``wi`` comes back as ``x s + y t + z n`` (the other fields are frame-free). The
frames and both rotations are computed in float64 and the results rounded to each direction's own
kernel dtype: float32 directions stay float32 (the normal's and tangent's dtypes choose nothing).
With n = (0, 0, 1) the rotations are exact, so the call equals the local call bit for bit.

Bad input raises ValueError naming the argument (``normal`` / ``tangent``) and its first bad index;
batch shapes that do not broadcast name every shape. Dask arrays (``eval``, ``pdf``) are
transformed blockwise; the index then is that of a bad element (each block checks its own).
"""
from __future__ import annotations

import numpy as np

from .._arrays import as_dirs, broadcast_batch
from .._dask import is_dask_array
from .._validate import raise_bad

__all__ = ["frame", "to_local", "to_world", "eval", "pdf", "sample", "albedo", "forget_frame"]

_TOL = 1e-4   # |w|^2 - 1 of every unit input (the kernels' direction tolerance) and |tangent . normal|


def _dot(a, b):
    """Row dot products in a fixed order (einsum's summation order depends on the memory layout,
    and a Dask block must give the bits of the eager call)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _cross(a, b):
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], -1)


def _index(i: int, shape: tuple, offset=None) -> tuple:
    idx = np.unravel_index(i, shape) if shape else ()
    if offset is not None:
        idx = tuple(int(j) + int(o) for j, o in zip(idx, offset))
    return tuple(int(j) for j in idx)


def _check_unit(a: np.ndarray, name: str, offset=None) -> np.ndarray:
    """``a`` (..., 3) as float64 after checking every vector is finite and unit within _TOL."""
    a64 = np.asarray(a, dtype=np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        bad = ~(np.abs(_dot(a64, a64) - 1) <= _TOL)
    if bad.any():
        i = int(np.argmax(bad.reshape(-1)))
        v = a64.reshape(-1, 3)[i]
        raise ValueError(f"{name}: must be finite unit vectors (|{name}|^2 = 1 within {_TOL:g}; normalize them "
                         f"first); the first bad one, at index {_index(i, bad.shape, offset)}, is {v.tolist()} "
                         f"with |{name}| = {np.sqrt(np.dot(v, v)):.6g}")
    return a64


def _normalized(a: np.ndarray) -> np.ndarray:
    return a / np.sqrt(_dot(a, a))[..., None]


def _duff(n: np.ndarray):
    """(s, t) of unit normals n (..., 3): Duff et al. 2017, "Building an Orthonormal Basis, Revisited"."""
    x, y, z = n[..., 0], n[..., 1], n[..., 2]
    sign = np.copysign(1.0, z)
    a = -1.0 / (sign + z)
    b = x * y * a
    s = np.stack([1.0 + sign * (x * x * a), sign * b, -sign * x], -1)
    t = np.stack([b, sign + y * (y * a), -y], -1)
    return s, t


def frame(normal, tangent=None, offset=None):
    """The (s, t, n) float64 arrays of the frames of ``normal`` (..., 3) and the optional
    ``tangent`` (..., 3) (broadcast together), after the checks of the module docstring.
    ``offset``: added to reported indices (a Dask block's position)."""
    n = _normalized(_check_unit(as_dirs(normal, "normal"), "normal", offset))
    if tangent is None:
        s, t = _duff(n)
        return s, t, n
    t_in = _normalized(_check_unit(as_dirs(tangent, "tangent"), "tangent", offset))
    shape = broadcast_batch(("normal", "tangent"), n.shape[:-1], t_in.shape[:-1])
    n, t_in = np.broadcast_to(n, shape + (3,)), np.broadcast_to(t_in, shape + (3,))
    d = _dot(n, t_in)
    bad = ~(np.abs(d) <= _TOL)
    if bad.any():
        i = int(np.argmax(bad.reshape(-1)))
        raise ValueError(f"tangent: must be perpendicular to normal (|tangent . normal| <= {_TOL:g}; a tangent "
                         f"parallel to the normal spans no frame); the first bad one, at index "
                         f"{_index(i, shape, offset)}, has tangent . normal = {float(d.reshape(-1)[i]):.6g}")
    s = _normalized(t_in - n * d[..., None])
    return s, _cross(n, s), n


def _dtype(w: np.ndarray):
    return np.float32 if w.dtype == np.float32 else np.float64


def _alloc(shape, dtype, like):
    """An (N, 3) result in Fortran order when ``like`` is an (N, 3) array of planes (the layout the
    compiled fast path reads without transposing, and eval's result follows), else C order."""
    fortran = like.ndim == 2 and like.flags.f_contiguous and not like.flags.c_contiguous and len(shape) == 2
    return np.empty(shape, dtype, order="F" if fortran else "C")


def to_local(w, fr, name="w", check=True):
    """World directions ``w`` (..., 3) in the frames ``fr`` = (s, t, n): (w . s, w . t, w . n), computed
    in float64, rounded to the kernel dtype of ``w`` (float32 stays float32, anything else float64)."""
    w = as_dirs(w, name)
    if check:   # the compiled door would count them too, but per element of the broadcast batch
        w64 = np.asarray(w, dtype=np.float64)
        with np.errstate(invalid="ignore", over="ignore"):
            raise_bad(name, int(np.count_nonzero(~(np.abs(_dot(w64, w64) - 1) <= _TOL))))
    s, t, n = fr
    shape = np.broadcast_shapes(w.shape, s.shape)
    out = _alloc(shape, _dtype(w), w)
    x, y, z = (np.asarray(w[..., k], dtype=np.float64) for k in range(3))
    for k, e in enumerate((s, t, n)):
        out[..., k] = x * e[..., 0] + y * e[..., 1] + z * e[..., 2]
    return out


def to_world(v: np.ndarray, fr, out=None) -> np.ndarray:
    """Local directions ``v`` (..., 3) to world space, x s + y t + z n in float64, written into
    ``out`` (default: a new array of v's dtype and layout)."""
    s, t, n = fr
    x, y, z = (np.asarray(v[..., k], dtype=np.float64)[..., None] for k in range(3))
    w = x * s + y * t + z * n
    if out is None:
        out = _alloc(w.shape, v.dtype, v)
    out[...] = w
    return out


def _frames_of(normal, tangent, *dirs):
    """The frames, after the argument checks: tangent needs normal, and every batch shape
    (the directions' and the frame's) must broadcast."""
    if normal is None:
        raise ValueError("tangent: given without normal= (the tangent is the x axis of the frame whose z axis is "
                         "the normal)")
    fr = frame(normal, tangent)
    names = tuple(name for name, _ in dirs) + (("normal",) if tangent is None else ("normal", "tangent"))
    shapes = tuple(as_dirs(w, name).shape[:-1] for name, w in dirs) + (np.shape(normal)[:-1],)
    if tangent is not None:
        shapes += (np.shape(tangent)[:-1],)
    broadcast_batch(names, *shapes)
    return fr


def _any_dask(*xs) -> bool:
    return any(x is not None and type(x) is not np.ndarray and is_dask_array(x) for x in xs)


# ------------------------------------------------------------------------------------- the ops

def eval(model, wo, wi, mode, out, wavelengths, normal, tangent):
    if _any_dask(wo, wi, normal, tangent):
        wo, wi = _dask_local(wo, wi, normal, tangent)
        return model.eval(wo, wi, mode, out, wavelengths=wavelengths)
    fr = _frames_of(normal, tangent, ("wo", wo), ("wi", wi))
    return model.eval(to_local(wo, fr, "wo"), to_local(wi, fr, "wi"), mode, out, wavelengths=wavelengths)


def pdf(model, wo, wi, mode, sample_flags, out, wavelengths, normal, tangent):
    if _any_dask(wo, wi, normal, tangent):
        wo, wi = _dask_local(wo, wi, normal, tangent)
        return model.pdf(wo, wi, mode, sample_flags, out, wavelengths=wavelengths)
    fr = _frames_of(normal, tangent, ("wo", wo), ("wi", wi))
    return model.pdf(to_local(wo, fr, "wo"), to_local(wi, fr, "wi"), mode, sample_flags, out,
                     wavelengths=wavelengths)


def sample(model, wo, uc, u, n, seed, mode, sample_flags, out, wavelengths, normal, tangent):
    fr = _frames_of(normal, tangent, ("wo", wo))
    r = model.sample(to_local(wo, fr, "wo"), uc, u, n=n, seed=seed, mode=mode, sample_flags=sample_flags,
                     out=out, wavelengths=wavelengths)
    cos = np.abs(r.wi[..., 2]).astype(r.f.dtype)   # SampleResult.weight's |cos| to the shading normal
    if out is not None:
        to_world(r.wi, fr, out=r.wi)
    else:
        object.__setattr__(r, "wi", to_world(r.wi, fr))
    r.__dict__["_cos_wi"] = cos
    return r


def forget_frame(out) -> None:
    """A local ``sample`` into ``out``: drop the cosines an earlier world-space call into it left."""
    d = getattr(out, "__dict__", None)
    if d is not None:
        d.pop("_cos_wi", None)


def albedo(model, wo, n_samples, seed, mode, wavelengths, normal, tangent):
    fr = _frames_of(normal, tangent, ("wo", wo))
    return model.albedo(to_local(wo, fr, "wo"), n_samples, seed, mode, wavelengths=wavelengths)


# ------------------------------------------------------------------------------------- Dask

def _local_block(w, n, *t, block_info=None):
    """One block of a Dask direction array in the local frame (checks and words as eager calls, the
    reported index shifted to the block's place in the whole array)."""
    offset = None
    if block_info is not None and None in block_info:
        offset = [lo for lo, _ in block_info[None]["array-location"][:-1]]
    fr = frame(n, t[0] if t else None, offset=offset)
    return to_local(w, fr, "w", check=False)


def _dask_local(wo, wi, normal, tangent):
    """wo and wi as lazy Dask arrays of local directions (``dask_eval`` then runs the model)."""
    import dask.array as da

    from .._dask import _as_dask_dirs
    if normal is None:
        _frames_of(normal, tangent)   # the words of "tangent without normal"
    arrs = {"wo": _as_dask_dirs(wo, "wo"), "wi": _as_dask_dirs(wi, "wi"), "normal": _as_dask_dirs(normal, "normal")}
    if tangent is not None:
        arrs["tangent"] = _as_dask_dirs(tangent, "tangent")
    names = tuple(arrs)
    broadcast_batch(names, *(a.shape[:-1] for a in arrs.values()))
    shape = np.broadcast_shapes(*(a.shape for a in arrs.values()))
    full = [a.rechunk({-1: 3}) for a in da.broadcast_arrays(*arrs.values())]   # map_blocks aligns the chunks
    n_t = full[2:]
    out = []
    for name, w in zip(("wo", "wi"), full[:2]):
        dt = np.dtype(np.float32) if arrs[name].dtype == np.float32 else np.dtype(np.float64)
        out.append(da.map_blocks(_local_block, w, *n_t, name=f"bsdfkit-local-{name}-" + da.core.tokenize(w, *n_t),
                                 dtype=dt, meta=np.empty((0,) * len(shape), dt)))
    return out
