"""The door of the Python composite models (``bsdfkit.models.composite``): eval / pdf / sample /
albedo taking the arguments as given, converted and checked as the compiled door does
(cpp/bindings/bind_model.h; ``bsdfkit._arrays``, the words of ``base._bad_message``), then the
model's row functions on flat arrays.

Rows: every direction, uniform, wavelength and per-element parameter array reaches the model as
an array of ``N`` rows (the call's batch, flattened) or of 1 row (a single item, broadcast by
numpy), in the call's dtype (float32 only when every direction is float32); per-element
parameters in that dtype too, so a per-element call and a loop of scalar models run the same
arithmetic. Children are called through their public methods (their own door).
"""
from __future__ import annotations

import math

import numpy as np

from .._validate import check_array

from .._arrays import (MAX_ALBEDO_SAMPLES, as_dirs, broadcast_batch, c_buffer, check_int, check_out, flatten_to,
                       kernel_dtype, planes_order, sample_uniforms)
from .base import SampleResult, _mode, _raise_bad, _sflags, digest  # noqa: F401  (digest re-exported)
from ._spectral import check_wavelengths

__all__ = ["Door", "take", "child_eval", "child_pdf", "child_sample", "array_param", "digest"]

_TOL = 1e-4   # the kernels' unit-vector tolerance on |w|^2 (bind_model.h)
_FIELDS = ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional")


def _bad_dirs(w) -> int:
    return int(np.count_nonzero(~(np.abs(np.einsum("...i,...i->...", w, w) - 1) <= _TOL)))


def _bad_uniform(u) -> int:
    return int(np.count_nonzero(~((u >= 0) & (u <= 1))))


def _raise_lam(lam):
    bad = ~np.all(np.isfinite(lam) & (lam >= 360.0) & (lam <= 830.0), axis=-1)
    c = int(np.count_nonzero(bad))
    if c:
        raise ValueError(f"wavelengths: {c} row(s) of 4 hold values that are not finite or outside [360, 830] nm")


def array_param(x, name: str, tail: tuple = (), lo=None, hi=None):
    """A per-element parameter: a Python float (a scalar) or a read-only float64 array of trailing
    shape ``tail``. Non-finite or out-of-range entries raise ValueError naming the parameter and the
    first bad index (``bsdfkit._validate.check_array``)."""
    return check_array(x, name, tail, lo=lo, hi=hi)


def take(a, idx):
    """Rows ``idx`` of a row array (a 1-row array broadcasts: returned as is)."""
    if a is None or np.ndim(a) == 0 or len(a) == 1:
        return a
    return a[idx]


def _check_varying_child(m, rows):
    """A child with per-element parameters runs on the composite's rows (flattened, and for some
    operations subsets or repeats of them): supported while its arrays are flat with one value
    per row of the call; otherwise a clear refusal instead of a misleading broadcasting error."""
    names = getattr(m, "varying", ())
    if not names:
        return
    vp = type(m).varying_params
    for k in names:
        v = m._params[k]
        shape = v.shape if vp[k] == 1 else v.shape[:-1]
        if shape != (rows,):
            raise NotImplementedError(
                f"{type(m).__name__} inside a composite: per-element parameters ({', '.join(names)}) are supported "
                f"there only as flat arrays with one value per element of the composite's call ({rows} here, "
                f"{k} has shape {shape}), and not in the composite's albedo; flatten the maps and the "
                "directions, or evaluate the inner model directly")


def _rows(wo, wi) -> int:
    return math.prod(np.broadcast_shapes(np.shape(wo)[:-1], np.shape(wi)[:-1]))


def _is_model(v) -> bool:
    return hasattr(v, "_params") and hasattr(v, "varying")


def _is_composite(m) -> bool:
    return getattr(type(m), "_param_tails", None) is not None and hasattr(m, "_children")


def _map_arrays(m, fn):
    """``m`` with ``fn(array, tail)`` applied to each of its per-element arrays: a compiled model's
    varying parameters, a composite's own row arrays and, recursively, its children's. Uniform
    models are returned as they are."""
    if _is_composite(m):
        tails, own = type(m)._param_tails, m._param_arrays()
        p = {}
        for k, v in m._params.items():
            if _is_model(v):
                p[k] = _map_arrays(v, fn)
            elif isinstance(v, np.ndarray) and k in own and v.ndim > len(tails.get(k, ())):
                p[k] = fn(v, tails.get(k, ()))
            else:
                p[k] = v
        return type(m)._from_params(p)
    names = getattr(m, "varying", ())
    if not names:
        return m
    vp = type(m).varying_params
    p = dict(m._params)
    for k in names:
        p[k] = fn(m._params[k], () if vp[k] == 1 else (3,))
    return type(m)._from_params(p)


def row_view(m, rows):
    """The child ``m`` on the composite's rows ``rows`` (an index array; None: all of them): its
    per-element arrays, one value per row of the composite's call, indexed by ``rows``, so that a
    subset of rows (a Mix's sampled child, a TwoSided side, a Mask's nested rows) runs the child
    with its own values (a 1-row array broadcasts and stays)."""
    return m if rows is None else _map_arrays(m, lambda v, t: v[rows] if len(v) > 1 else v)


def flat_view(m, batch):
    """Model ``m`` (a child of a composite called with batch shape ``batch``) with its per-element
    arrays broadcast to the batch and flattened to one value per row of the composite's call (the
    rows the children run on)."""
    return _map_arrays(m, lambda v, t: np.ascontiguousarray(np.broadcast_to(v, tuple(batch) + t)).reshape((-1,) + t))


def _child_shapes(m) -> list:
    """(name, batch shape) of every per-element array inside the children of composite ``m``
    (recursively): they broadcast with the composite's call like its own arrays."""
    out = []
    for k, c in m._params.items():
        if not _is_model(c):
            continue
        if _is_composite(c):
            tails = type(c)._param_tails
            for name, v in c._param_arrays().items():
                if isinstance(v, np.ndarray):
                    out.append((f"{k}.{name}", v.shape[:v.ndim - len(tails.get(name, ()))]))
            out += [(f"{k}.{n}", s) for n, s in _child_shapes(c)]
        else:
            vp = type(c).varying_params
            for name in c.varying:
                v = c._params[name]
                out.append((f"{k}.{name}", v.shape if vp[name] == 1 else v.shape[:-1]))
    return out


def _flat_composite(m, batch):
    """Composite ``m`` with its children as flat views for a call of batch shape ``batch`` (itself
    when no child has per-element parameters)."""
    if not _child_shapes(m):
        return m
    p = {k: flat_view(v, batch) if _is_model(v) else v for k, v in m._params.items()}
    return type(m)._from_params(p)


def child_eval(m, wo, wi, md, lam, rows=None):
    m = row_view(m, rows)
    _check_varying_child(m, _rows(wo, wi))
    return m.eval(wo, wi, md) if lam is None else m.eval(wo, wi, md, wavelengths=lam)


def child_pdf(m, wo, wi, md, sf, lam, rows=None):
    m = row_view(m, rows)
    _check_varying_child(m, _rows(wo, wi))
    return m.pdf(wo, wi, md, sf) if lam is None else m.pdf(wo, wi, md, sf, wavelengths=lam)


def child_sample(m, wo, uc, u, md, sf, lam, rows=None):
    m = row_view(m, rows)
    _check_varying_child(m, _rows(wo, np.zeros(np.shape(uc) + (3,))))
    if lam is None:
        return m.sample(wo, uc, u, mode=md, sample_flags=sf)
    return m.sample(wo, uc, u, mode=md, sample_flags=sf, wavelengths=lam)


def empty_sample(n, dtype, nch, spectral):
    """Row arrays of a sample call, every row invalid (wi = +z, f = pdf = 0, eta = 1)."""
    d = {"wi": np.zeros((n, 3), dtype), "f": np.zeros((n, nch), dtype), "pdf": np.zeros(n, dtype),
         "flags": np.zeros(n, np.uint8), "eta": np.ones(n, dtype), "valid": np.zeros(n, bool),
         "pdf_is_proportional": np.zeros(n, bool)}
    d["wi"][:, 2] = 1
    if spectral:
        d["terminated"] = np.zeros(n, bool)
    return d


def put_sample(rows: dict, idx, s: SampleResult):
    """Writes a child's SampleResult into rows ``idx``."""
    for k in _FIELDS:
        rows[k][idx] = getattr(s, k)
    if "terminated" in rows and s.terminated is not None:
        rows["terminated"][idx] = s.terminated


class Door:
    """The ``_core`` interface of a composite model ``m``: ``m._param_arrays()`` (name -> per-element
    parameter: a float or an array of trailing shape ``m._param_tails[name]``), ``m._check_dirs``
    (False: the children get wo and wi unchanged and their doors count bad ones) and the row
    functions ``m._eval_rows(wo, wi, md, lam, P, out)``, ``m._pdf_rows(wo, wi, md, sf, lam, P, out)``
    (``out``: the (N, channels) / (N,) result rows, which they may fill and return),
    ``m._sample_rows(wo, uc, u, md, sf, lam, P, n)`` (a dict of row arrays, see empty_sample)."""

    def __init__(self, m):
        self.m = m

    @property
    def flags(self) -> int:
        return self.m._flags()

    # ---- arguments
    def _params(self, batch, dtype):
        """The per-element parameters as rows of the batch (1 row for a scalar), in dtype."""
        out = {"_n": math.prod(batch)}
        ints = getattr(self.m, "_int_params", ())
        for name, v in self.m._param_arrays().items():
            tail = self.m._param_tails.get(name, ())
            dt = np.int64 if name in ints else dtype
            if isinstance(v, np.ndarray):
                out[name] = flatten_to(v, batch, tail, dt)
            else:
                out[name] = np.asarray(v, dtype=dt).reshape((1,) + tail)
        return out

    def _shapes(self):
        names, shapes = [], []
        for name, v in self.m._param_arrays().items():
            if isinstance(v, np.ndarray):
                tail = self.m._param_tails.get(name, ())
                names.append(name)
                shapes.append(v.shape[:v.ndim - len(tail)])
        for name, shape in _child_shapes(self.m):   # the children's per-element arrays broadcast too
            names.append(name)
            shapes.append(shape)
        return tuple(names), tuple(shapes)

    def _lam(self, wavelengths):
        return None if wavelengths is None else check_wavelengths(wavelengths)

    # ---- eval / pdf
    def _pair(self, wo, wi, lam):
        wo, wi = as_dirs(wo, "wo"), as_dirs(wi, "wi")
        pn, ps = self._shapes()
        names, shapes = ("wo", "wi") + pn, (wo.shape[:-1], wi.shape[:-1]) + ps
        if lam is not None:
            names, shapes = names + ("wavelengths",), shapes + (lam.shape[:-1],)
        batch = broadcast_batch(names, *shapes)
        dtype = kernel_dtype(wo, wi)
        return wo, wi, batch, dtype

    def _rows(self, wo, wi, lam, batch, dtype):
        if self.m._check_dirs:   # else the children's doors count them: they get wo and wi as given
            _raise_bad("wo", _bad_dirs(wo))
            _raise_bad("wi", _bad_dirs(wi))
        lr = None
        if lam is not None:
            _raise_lam(lam)
            lr = flatten_to(lam, batch, (4,), np.float64)
        return (flatten_to(wo, batch, (3,), dtype), flatten_to(wi, batch, (3,), dtype), lr,
                self._params(batch, dtype))

    def eval(self, wo, wi, mode=0, out=None, wavelengths=None):
        md = _mode(mode)
        lam = self._lam(wavelengths)
        wo, wi, batch, dtype = self._pair(wo, wi, lam)
        nch = 3 if lam is None else 4
        if lam is None:
            out = check_out(out, batch + (3,), dtype, order=planes_order(batch, wo, wi), fortran_ok=len(batch) == 1)
        else:
            out = check_out(out, batch + (4,), dtype)
        if out.size:
            wor, wir, lr, P = self._rows(wo, wi, lam, batch, dtype)
            buf = c_buffer(out)
            b2 = buf.reshape(-1, nch)
            res = _flat_composite(self.m, batch)._eval_rows(wor, wir, md, lr, P, b2)
            if res is not b2:
                b2[...] = res
            if buf is not out:
                np.copyto(out, buf)
        return out

    def pdf(self, wo, wi, mode=0, sflags=3, out=None, wavelengths=None):
        md, sf = _mode(mode), _sflags(sflags)
        lam = self._lam(wavelengths)
        wo, wi, batch, dtype = self._pair(wo, wi, lam)
        out = check_out(out, batch, dtype)
        if out.size:
            wor, wir, lr, P = self._rows(wo, wi, lam, batch, dtype)
            o1 = out.reshape(-1)
            res = _flat_composite(self.m, batch)._pdf_rows(wor, wir, md, sf, lr, P, o1)
            if res is not o1:
                o1[...] = res
        return out

    # ---- sample
    def sample(self, wo, uc=None, u=None, mode=0, sflags=3, out=None, n=None, seed=None, wavelengths=None):
        md, sf = _mode(mode), _sflags(sflags)
        lam = self._lam(wavelengths)
        if lam is not None and out is not None:
            raise ValueError("out: not supported with wavelengths= (spectral sample results are allocated)")
        wo = as_dirs(wo, "wo")
        pn, ps = self._shapes()
        if lam is not None:
            pn, ps = pn + ("wavelengths",), ps + (lam.shape[:-1],)
        uc, u, dtype, batch = sample_uniforms(wo, uc, u, n, seed, pn, ps)
        _raise_bad("wo", _bad_dirs(wo))
        _raise_bad("uc", _bad_uniform(uc))
        _raise_bad("u", _bad_uniform(u))
        nch = 3 if lam is None else 4
        count = math.prod(batch)
        if count:
            lr = None
            if lam is not None:
                _raise_lam(lam)
                lr = flatten_to(lam, batch, (4,), np.float64)
            ucf = np.ascontiguousarray(np.broadcast_to(uc, batch), dtype=dtype).reshape(-1)
            uf = np.ascontiguousarray(np.broadcast_to(u, batch + (2,)), dtype=dtype).reshape(-1, 2)
            rows = _flat_composite(self.m, batch)._sample_rows(flatten_to(wo, batch, (3,), dtype), ucf, uf, md, sf, lr,
                                       self._params(batch, dtype), count)
        else:
            rows = empty_sample(0, dtype, nch, lam is not None)
        shaped = {k: v.reshape(batch + v.shape[1:]).astype(v.dtype, copy=False) for k, v in rows.items()}
        if out is not None:
            if type(out) is not SampleResult:
                raise TypeError(f"out: expected a SampleResult (e.g. an earlier result of sample), got "
                                f"{type(out).__name__}")
            for k in _FIELDS:
                dst = getattr(out, k)
                try:
                    check_out(dst, shaped[k].shape, shaped[k].dtype)
                except (TypeError, ValueError) as e:
                    raise type(e)(f"out.{k}: {str(e)[len('out: '):]}") from None
                np.copyto(dst, shaped[k])
            return out
        r = object.__new__(SampleResult)
        r.__dict__.update({k: shaped[k] for k in _FIELDS})
        r.__dict__["terminated"] = shaped.get("terminated")
        return r

    # ---- albedo
    def albedo(self, wo, n_samples=65536, seed=0, mode=0, wavelengths=None):
        md = _mode(mode)
        lam = self._lam(wavelengths)
        wo = as_dirs(wo, "wo")
        n_samples = check_int(n_samples, "n_samples", 1, MAX_ALBEDO_SAMPLES)
        seed = check_int(seed, "seed", 0)
        pn, ps = self._shapes()
        names, shapes = ("wo",) + pn, (wo.shape[:-1],) + ps
        if lam is not None:
            names, shapes = names + ("wavelengths",), shapes + (lam.shape[:-1],)
        batch = broadcast_batch(names, *shapes)
        dtype = kernel_dtype(wo)
        nch = 3 if lam is None else 4
        out = np.empty(batch + (nch,), dtype)
        count = math.prod(batch)
        if not count:
            return out
        _raise_bad("wo", _bad_dirs(wo))
        wof = np.ascontiguousarray(np.broadcast_to(wo, batch + (3,)), dtype=dtype).reshape(-1, 3)
        P = {k: np.ascontiguousarray(np.broadcast_to(v, (count,) + v.shape[1:])) for k, v in
             self._params(batch, dtype).items() if k != "_n"}
        lr = None
        if lam is not None:
            _raise_lam(lam)
            lr = np.ascontiguousarray(np.broadcast_to(lam, batch + (4,)), dtype=np.float64).reshape(-1, 4)
        acc = np.zeros((count, nch))
        chunk = max(1, min(n_samples, (1 << 18) // count))
        done, c = 0, 0
        while done < n_samples:   # plain Python between chunks: Ctrl-C lands here
            k = min(chunk, n_samples - done)
            rng = np.random.default_rng([seed, c])
            uc, u = rng.random(count * k).astype(dtype), rng.random((count * k, 2)).astype(dtype)
            rep = {key: np.repeat(v, k, axis=0) for key, v in P.items()}
            rep["_n"] = count * k
            rows = self.m._sample_rows(np.repeat(wof, k, axis=0), uc, u, md, 3,
                                       None if lr is None else np.repeat(lr, k, axis=0), rep, count * k)
            ok = rows["valid"] & (rows["pdf"] > 0)
            w = np.where(ok, np.abs(rows["wi"][:, 2].astype(np.float64)) / np.where(ok, rows["pdf"], 1), 0.0)
            acc += (rows["f"].astype(np.float64) * w[:, None]).reshape(count, k, nch).sum(1)
            done += k
            c += 1
        out.reshape(-1, nch)[...] = acc / n_samples
        return out
