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

The work is numpy, in chunks of 32768 elements (component planes of each chunk in cache; the
arithmetic is elementwise, so the values do not depend on the chunking): about 50 ns per element
and direction on the development machine, several times the compiled kernels' own cost for the
cheap models (a compiled frame path would remove it).

Bad input raises ValueError naming the argument (``normal`` / ``tangent``) and its first bad index;
batch shapes that do not broadcast name every shape. Dask arrays (``eval``, ``pdf``) are
transformed blockwise; the index then is that of a bad element (each block checks its own).
"""
from __future__ import annotations

import math

import numpy as np

from .._arrays import as_dirs, broadcast_batch
from .._dask import is_dask_array
from .._validate import raise_bad

__all__ = ["frame", "to_local", "to_world", "eval", "pdf", "sample", "albedo", "forget_frame"]

_TOL = 1e-4   # |w|^2 - 1 of every unit input (the kernels' direction tolerance) and |tangent . normal|
_CHUNK = 1 << 15


# The arithmetic runs on component planes, float64 arrays (3, m) of a chunk of m elements (numpy is
# several times slower on the strided columns of an (m, 3) array), in a fixed order of operations.

def _planes(a) -> np.ndarray:
    """(..., 3) -> float64 planes (3, ...), a fresh C-contiguous array."""
    return np.ascontiguousarray(np.moveaxis(a, -1, 0), dtype=np.float64)


def _dot(p, q):
    """p . q of planes, summed x, y, z in that order."""
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def _cross(a, b):
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _rows(a: np.ndarray, shape: tuple) -> np.ndarray:
    """a (..., 3) broadcast to shape + (3,), as rows (M, 3) (a view unless the broadcast needs a copy)."""
    return np.broadcast_to(a, shape + (3,)).reshape(-1, 3)


def _chunks(m: int):
    return ((i, min(m, i + _CHUNK)) for i in range(0, m, _CHUNK))


def _index(i: int, shape: tuple, offset=None) -> tuple:
    idx = np.unravel_index(i, shape) if shape else ()
    if offset is not None:
        idx = tuple(int(j) + int(o) for j, o in zip(idx, offset))
    return tuple(int(j) for j in idx)


def _duff(n: np.ndarray):
    """(s, t) planes of unit normals' planes n: Duff et al. 2017, "Building an Orthonormal Basis, Revisited"."""
    x, y, z = n
    sign = np.copysign(1.0, z)
    a = -1.0 / (sign + z)
    b = x * y * a
    return np.stack([1.0 + sign * (x * x * a), sign * b, -sign * x]), np.stack([b, sign + y * (y * a), -y])


def _frame_planes(n: np.ndarray, t=None):
    """(s, t, n) planes of checked normal (and tangent) planes, normalised here (in place)."""
    n /= np.sqrt(_dot(n, n))
    if t is None:
        s, t = _duff(n)
        return s, t, n
    t /= np.sqrt(_dot(t, t))
    s = t - n * _dot(n, t)           # the residual the tolerance allows, removed
    s /= np.sqrt(_dot(s, s))
    return s, _cross(n, s), n


# ---------------------------------------------------------------------------------------- checks

def _check_unit(a: np.ndarray, name: str, offset=None) -> None:
    """ValueError naming ``name`` and the first index of ``a`` (..., 3) that is not a finite unit vector."""
    rows = a.reshape(-1, 3)
    for i, j in _chunks(len(rows)):
        p = _planes(rows[i:j])
        with np.errstate(invalid="ignore", over="ignore"):
            bad = ~(np.abs(_dot(p, p) - 1) <= _TOL)
        if bad.any():
            k = i + int(np.argmax(bad))
            v = rows[k].astype(np.float64)
            raise ValueError(f"{name}: must be finite unit vectors (|{name}|^2 = 1 within {_TOL:g}; normalize them "
                             f"first); the first bad one, at index {_index(k, a.shape[:-1], offset)}, is "
                             f"{v.tolist()} with |{name}| = {np.sqrt(np.dot(v, v)):.6g}")


def _check(normal, tangent, offset=None):
    """(normal, tangent) as arrays after the checks of the module docstring."""
    n = as_dirs(normal, "normal")
    t = None if tangent is None else as_dirs(tangent, "tangent")
    _check_unit(n, "normal", offset)
    if t is None:
        return n, t
    _check_unit(t, "tangent", offset)
    shape = broadcast_batch(("normal", "tangent"), n.shape[:-1], t.shape[:-1])
    nr, tr = _rows(n, shape), _rows(t, shape)
    for i, j in _chunks(len(nr)):
        pn, pt = _planes(nr[i:j]), _planes(tr[i:j])
        d = _dot(pn, pt) / np.sqrt(_dot(pn, pn) * _dot(pt, pt))
        bad = ~(np.abs(d) <= _TOL)
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"tangent: must be perpendicular to normal (|tangent . normal| <= {_TOL:g}; a tangent "
                             f"parallel to the normal spans no frame); the first bad one, at index "
                             f"{_index(i + k, shape, offset)}, has tangent . normal = {float(d[k]):.6g}")
    return n, t


def _checked(normal, tangent, *dirs):
    """The checked (normal, tangent), after the argument checks: tangent needs normal, and every
    batch shape (the directions' and the frame's) must broadcast."""
    if normal is None:
        raise ValueError("tangent: given without normal= (the tangent is the x axis of the frame whose z axis is "
                         "the normal)")
    args = dirs + (("normal", normal),) + ((("tangent", tangent),) if tangent is not None else ())
    args = tuple((name, as_dirs(a, name)) for name, a in args)
    broadcast_batch(tuple(name for name, _ in args), *(a.shape[:-1] for _, a in args))
    d = dict(args)
    return _check(d["normal"], d.get("tangent"))


def frame(normal, tangent=None):
    """The (s, t, n) float64 planes (each (3, ...)) of the frames of ``normal`` (..., 3) and the
    optional ``tangent`` (..., 3), after the checks of the module docstring."""
    n, t = _check(normal, tangent)
    return _frame_planes(_planes(n), None if t is None else _planes(t))


# ------------------------------------------------------------------------------------- rotations

def _rotate(ws, n: np.ndarray, t, world: bool, dtypes, outs=None) -> list:
    """Directions ``ws`` (a list of (..., 3) arrays) rotated by the frames of the checked ``n`` /
    ``t``: to the local frame (w . s, w . t, w . n), or with ``world`` from it (x s + y t + z n);
    float64 arithmetic, each result in its ``dtypes`` entry, written into its ``outs`` entry if
    given, else a new array: Fortran-ordered when that ``w`` is an (N, 3) array of planes (the
    layout the compiled fast path reads without transposing, and eval's result follows), else
    C-ordered. One frame per element is built once per chunk for all of ``ws`` (they then share
    the broadcast shape); a single frame is built once, and each result keeps its own shape."""
    fshape = np.broadcast_shapes(n.shape[:-1], () if t is None else t.shape[:-1])
    fixed = None
    if math.prod(fshape) == 1:   # one frame for every element
        fixed = _frame_planes(_planes(n.reshape(3)), None if t is None else _planes(t.reshape(3)))
        shapes = [np.broadcast_shapes(w.shape[:-1], fshape) for w in ws]
    else:
        shapes = [np.broadcast_shapes(fshape, *(w.shape[:-1] for w in ws))] * len(ws)
    outs = list(outs or [None] * len(ws))
    for k, (w, shape, out) in enumerate(zip(ws, shapes, outs)):
        if out is None:
            fortran = len(shape) == 1 and w.ndim == 2 and w.flags.f_contiguous and not w.flags.c_contiguous
            outs[k] = np.empty(shape + (3,), dtypes[k], order="F" if fortran else "C")
    groups = [[k] for k in range(len(ws))] if fixed else [list(range(len(ws)))]
    for g in groups:
        shape = shapes[g[0]]
        rows_w = [_rows(ws[k], shape) for k in g]
        rows_out = [outs[k].reshape(-1, 3) for k in g]
        if not fixed:
            rows_n, rows_t = _rows(n, shape), None if t is None else _rows(t, shape)
        for i, j in _chunks(math.prod(shape)):
            s, tt, nn = fixed or _frame_planes(_planes(rows_n[i:j]), None if t is None else _planes(rows_t[i:j]))
            for rw, ro in zip(rows_w, rows_out):
                p = _planes(rw[i:j])
                if world:
                    for c in range(3):
                        ro[i:j, c] = p[0] * s[c] + p[1] * tt[c] + p[2] * nn[c]
                else:
                    for c, e in enumerate((s, tt, nn)):
                        ro[i:j, c] = _dot(p, e)
    return outs


def to_local(ws, n, t=None, names=None, check=True) -> list:
    """World directions ``ws`` (a list of (..., 3)) in the frames of the checked normals ``n`` (and
    tangents ``t``), each rounded to its kernel dtype (float32 stays float32, anything else float64)."""
    names = names or ["w"] * len(ws)
    ws = [as_dirs(w, name) for w, name in zip(ws, names)]
    if check:   # the compiled door would count them too, but per element of the broadcast batch
        for w, name in zip(ws, names):
            rows = w.reshape(-1, 3)
            bad = 0
            for i, j in _chunks(len(rows)):
                p = _planes(rows[i:j])
                with np.errstate(invalid="ignore", over="ignore"):
                    bad += int(np.count_nonzero(~(np.abs(_dot(p, p) - 1) <= _TOL)))
            raise_bad(name, bad)
    return _rotate(ws, n, t, False, [np.float32 if w.dtype == np.float32 else np.float64 for w in ws])


def to_world(v: np.ndarray, n, t=None, out=None) -> np.ndarray:
    """Local directions ``v`` (..., 3) to world space in the frames of the checked ``n`` / ``t``, in
    v's dtype, written into ``out`` if given."""
    return _rotate([v], n, t, True, [v.dtype], [out])[0]


def _any_dask(*xs) -> bool:
    return any(x is not None and type(x) is not np.ndarray and is_dask_array(x) for x in xs)


# ------------------------------------------------------------------------------------- the ops

def eval(model, wo, wi, mode, out, wavelengths, normal, tangent):
    if _any_dask(wo, wi, normal, tangent):
        wo, wi = _dask_local(wo, wi, normal, tangent)
        return model.eval(wo, wi, mode, out, wavelengths=wavelengths)
    n, t = _checked(normal, tangent, ("wo", wo), ("wi", wi))
    wo, wi = to_local([wo, wi], n, t, ["wo", "wi"])
    return model.eval(wo, wi, mode, out, wavelengths=wavelengths)


def pdf(model, wo, wi, mode, sample_flags, out, wavelengths, normal, tangent):
    if _any_dask(wo, wi, normal, tangent):
        wo, wi = _dask_local(wo, wi, normal, tangent)
        return model.pdf(wo, wi, mode, sample_flags, out, wavelengths=wavelengths)
    n, t = _checked(normal, tangent, ("wo", wo), ("wi", wi))
    wo, wi = to_local([wo, wi], n, t, ["wo", "wi"])
    return model.pdf(wo, wi, mode, sample_flags, out, wavelengths=wavelengths)


def sample(model, wo, uc, u, n, seed, mode, sample_flags, out, wavelengths, normal, tangent):
    nrm, t = _checked(normal, tangent, ("wo", wo))
    r = model.sample(to_local([wo], nrm, t, ["wo"])[0], uc, u, n=n, seed=seed, mode=mode, sample_flags=sample_flags,
                     out=out, wavelengths=wavelengths)
    cos = np.abs(r.wi[..., 2]).astype(r.f.dtype)   # SampleResult.weight's |cos| to the shading normal
    if out is not None:
        to_world(r.wi, nrm, t, out=r.wi)   # chunk by chunk: each chunk is read before it is written
    else:
        object.__setattr__(r, "wi", to_world(r.wi, nrm, t))
    r.__dict__["_cos_wi"] = cos
    return r


def forget_frame(out) -> None:
    """A local ``sample`` into ``out``: drop the cosines an earlier world-space call into it left."""
    d = getattr(out, "__dict__", None)
    if d is not None:
        d.pop("_cos_wi", None)


def albedo(model, wo, n_samples, seed, mode, wavelengths, normal, tangent):
    n, t = _checked(normal, tangent, ("wo", wo))
    return model.albedo(to_local([wo], n, t, ["wo"])[0], n_samples, seed, mode, wavelengths=wavelengths)


# ------------------------------------------------------------------------------------- Dask

def _local_block(w, n, *t, block_info=None):
    """One block of a Dask direction array in the local frame (checks and words as eager calls, the
    reported index shifted to the block's place in the whole array)."""
    offset = None
    if block_info is not None and None in block_info:
        offset = [lo for lo, _ in block_info[None]["array-location"][:-1]]
    n, t = _check(n, t[0] if t else None, offset)
    return to_local([w], n, t, check=False)[0]


def _dask_local(wo, wi, normal, tangent):
    """wo and wi as lazy Dask arrays of local directions (``dask_eval`` then runs the model)."""
    import dask.array as da

    from .._dask import _as_dask_dirs
    if normal is None:
        _checked(normal, tangent)   # the words of "tangent without normal"
    arrs = {"wo": _as_dask_dirs(wo, "wo"), "wi": _as_dask_dirs(wi, "wi"), "normal": _as_dask_dirs(normal, "normal")}
    if tangent is not None:
        arrs["tangent"] = _as_dask_dirs(tangent, "tangent")
    broadcast_batch(tuple(arrs), *(a.shape[:-1] for a in arrs.values()))
    ndim = len(np.broadcast_shapes(*(a.shape for a in arrs.values())))
    full = [a.rechunk({-1: 3}) for a in da.broadcast_arrays(*arrs.values())]   # map_blocks aligns the chunks
    n_t = full[2:]
    out = []
    for name, w in zip(("wo", "wi"), full[:2]):
        dt = np.dtype(np.float32) if arrs[name].dtype == np.float32 else np.dtype(np.float64)
        out.append(da.map_blocks(_local_block, w, *n_t, name=f"bsdfkit-local-{name}-" + da.core.tokenize(w, *n_t),
                                 dtype=dt, meta=np.empty((0,) * ndim, dt)))
    return out
