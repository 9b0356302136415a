"""A user-defined BSDF from numpy functions: ``bk.Custom(f=..., pdf=None, sample=None, name=...)``.

Plugs one's own formula (BRDF Explorer's most used feature) into everything that takes a model:
the ``bsdfkit.plot`` views, ``albedo``, ``plot.difference`` and comparisons. The functions are
called on numpy arrays (vectorized, no per-direction loop) in the local shading frame, with the
package's conventions (z the normal, ``wo`` and ``wi`` unit vectors pointing away from the
surface, f without the cosine):

* ``f(wo, wi) -> (..., 3)`` (or ``(...)``, grey), ``wo``/``wi`` float64 ``(..., 3)`` broadcast;
* ``pdf(wo, wi) -> (...)``, the solid-angle density of ``sample`` (required with ``sample``);
* ``sample(wo, uc, u) -> wi`` ``(..., 3)``, with ``uc`` ``(...)`` and ``u`` ``(..., 2)`` in [0, 1).

Without ``sample`` (and ``pdf``) wi is drawn from the cosine-weighted hemisphere on wo's side
(both hemispheres, half each, with ``transmission=True``), which is what ``albedo`` and the
sampling view then use. Values are computed in float64 (float32 inputs give float32 outputs).
``ValueError`` naming the function is raised when ``f`` or ``pdf`` returns negative or
non-finite values, or values beyond the largest number of the call's dtype (3.4e38 for float32
inputs), or a shape that does not broadcast to the batch; when ``sample`` returns anything but
finite unit vectors of the batch's shape (a direction it cannot draw is a unit vector whose
``pdf`` is 0); and when ``albedo``'s estimate (the mean of f |cos| / pdf) overflows. Two Custom models
are equal when they wrap the same functions with the same name; ``repr`` shows the functions'
names (it cannot be evaluated back). Pickling works for module-level functions.

Parameters
----------
f : callable
    ``f(wo, wi) -> (..., 3)`` (or ``(...)``, grey), the BSDF without the cosine.
pdf : callable, optional
    ``pdf(wo, wi) -> (...)``, the solid-angle density of ``sample``; given with ``sample``.
sample : callable, optional
    ``sample(wo, uc, u) -> wi``; given with ``pdf``. Neither: cosine-weighted sampling.
name : str, optional
    A non-empty name (legends, ``repr``); default "custom".
transmission : bool, optional
    True: f is defined on both sides of the surface (cosine sampling covers both hemispheres).

Raises
------
TypeError
    A function that is not callable, a name that is not a non-empty str.
ValueError
    ``pdf`` without ``sample`` or the reverse; bad values from the functions (above).

Examples
--------
>>> import numpy as np, bsdfkit as bk
>>> def f(wo, wi):   # a Lambertian of albedo 0.5, with its wo's-side test
...     same = (wo[..., 2] * wi[..., 2] > 0)[..., None]
...     return np.where(same, 0.5 / np.pi, 0.0) * np.ones(3)
>>> m = bk.Custom(f, name="half grey")
>>> np.allclose(m.albedo(bk.direction(0.5, 0.0), n_samples=4096), 0.5)
True
"""
from __future__ import annotations

import numpy as np

from .._arrays import (MAX_ALBEDO_SAMPLES, as_dirs, broadcast_batch, c_buffer, check_int, check_out, flatten_to,
                       kernel_dtype, planes_order, sample_uniforms)
from .._enums import BxDFFlags, ReflTrans
from .base import SampleResult, BxDF, _mode, _raise_bad, _sample_result, _sflags

__all__ = ["Custom"]

_TOL = 1e-4  # the kernels' unit-vector tolerance on |w|^2


def _bad(w) -> int:
    return int(np.count_nonzero(~(np.abs(np.einsum("...i,...i->...", w, w) - 1) <= _TOL)))


def _bad_uniform(u) -> int:
    return int(np.count_nonzero(~((u >= 0) & (u <= 1))))  # NaN fails both


def _check_fits(v: np.ndarray, dtype, what: str) -> None:
    """``v`` (finite, >= 0) must be representable in the output dtype: a float32 call stored
    1e39 as inf before."""
    dtype = np.dtype(dtype)
    top = float(np.finfo(dtype).max)
    if v.size and float(v.max()) > top:
        raise ValueError(f"{what}: returned values up to {float(v.max()):.6g}, beyond {dtype.name}'s max {top:.6g} "
                         f"(the call's dtype)")


def _raise_counts(counts, names) -> None:
    for name, c in zip(names, counts if isinstance(counts, tuple) else (counts,)):
        _raise_bad(name, c)


def _new_sample_out(batch, dtype) -> SampleResult:
    def a(shape, dt):
        return np.empty(shape, dt)
    return _sample_result((a(batch + (3,), dtype), a(batch + (3,), dtype), a(batch, dtype), a(batch, np.uint8),
                           a(batch, dtype), a(batch, bool), a(batch, bool)))


class _PyCore:
    """The ``_core`` model interface implemented in numpy around the user's functions: its door
    (eval / pdf / sample / albedo taking the arguments as given, as cpp/bindings/bind_model.h's)
    converts and checks them with bsdfkit._arrays, then runs the row functions below, which
    write into preallocated outputs."""

    def __init__(self, p):
        self.p = p
        self.flags = int(BxDFFlags.GlossyReflection | (BxDFFlags.GlossyTransmission if p["transmission"] else 0))

    # ---- the door
    @staticmethod
    def _pair(wo, wi):
        wo, wi = as_dirs(wo, "wo"), as_dirs(wi, "wi")
        return wo, wi, broadcast_batch(("wo", "wi"), wo.shape[:-1], wi.shape[:-1]), kernel_dtype(wo, wi)

    def eval(self, wo, wi, mode=0, out=None):
        md = _mode(mode)
        wo, wi, batch, dtype = self._pair(wo, wi)
        out = check_out(out, batch + (3,), dtype, order=planes_order(batch, wo, wi), fortran_ok=len(batch) == 1)
        if out.size:
            buf = c_buffer(out)
            _raise_counts(self._eval_rows(flatten_to(wo, batch, (3,), dtype), flatten_to(wi, batch, (3,), dtype), md,
                                          buf.reshape(-1, 3)), ("wo", "wi"))
            if buf is not out:
                np.copyto(out, buf)
        return out

    def pdf(self, wo, wi, mode=0, sflags=3, out=None):
        md, sf = _mode(mode), _sflags(sflags)
        wo, wi, batch, dtype = self._pair(wo, wi)
        out = check_out(out, batch, dtype)
        if out.size:
            _raise_counts(self._pdf_rows(flatten_to(wo, batch, (3,), dtype), flatten_to(wi, batch, (3,), dtype), md, sf,
                                         out.reshape(-1)), ("wo", "wi"))
        return out

    def sample(self, wo, uc=None, u=None, mode=0, sflags=3, out=None, n=None, seed=None):
        md, sf = _mode(mode), _sflags(sflags)
        wo = as_dirs(wo, "wo")
        uc, u, dtype, batch = sample_uniforms(wo, uc, u, n, seed)
        res = _new_sample_out(batch, dtype) if out is None else out
        if out is not None:
            want = {"wi": (batch + (3,), dtype), "f": (batch + (3,), dtype), "pdf": (batch, dtype),
                    "flags": (batch, np.dtype(np.uint8)), "eta": (batch, dtype), "valid": (batch, np.dtype(bool)),
                    "pdf_is_proportional": (batch, np.dtype(bool))}
            for name, (shape, dt) in want.items():
                try:
                    check_out(getattr(out, name), shape, dt)
                except (TypeError, ValueError) as e:
                    raise type(e)(f"out.{name}: {str(e)[len('out: '):]}") from None
        if res.pdf.size:
            ucf = np.ascontiguousarray(np.broadcast_to(uc, batch), dtype=dtype).reshape(-1)
            uf = np.ascontiguousarray(np.broadcast_to(u, batch + (2,)), dtype=dtype).reshape(-1, 2)
            _raise_counts(self._sample_rows(flatten_to(wo, batch, (3,), dtype), ucf, uf, md, sf,
                                            *(getattr(res, k).reshape((-1, 3) if k in ("wi", "f") else -1)
                                              for k in ("wi", "f", "pdf", "flags", "eta", "valid",
                                                        "pdf_is_proportional"))), ("wo", "uc", "u"))
        return res if out is not None else tuple(getattr(res, k) for k in ("wi", "f", "pdf", "flags", "eta", "valid",
                                                                           "pdf_is_proportional"))

    def albedo(self, wo, n_samples=65536, seed=0, mode=0):
        md = _mode(mode)
        wo = as_dirs(wo, "wo")
        n_samples = check_int(n_samples, "n_samples", 1, MAX_ALBEDO_SAMPLES)
        seed = check_int(seed, "seed", 0)
        batch, dtype = wo.shape[:-1], kernel_dtype(wo)
        out = np.empty(batch + (3,), dtype)
        if out.size:
            _raise_counts(self._albedo_rows(np.ascontiguousarray(wo, dtype=dtype).reshape(-1, 3), n_samples,
                                            seed & 0xFFFFFFFFFFFFFFFF, md, out.reshape(-1, 3)), ("wo",))
        return out

    def _f(self, wo, wi, dtype=np.float64):
        v = np.asarray(self.p["f"](wo, wi), dtype=np.float64)
        batch = np.broadcast_shapes(wo.shape[:-1], wi.shape[:-1])
        if v.shape == batch:
            v = v[..., None]
        try:
            v = np.broadcast_to(v, batch + (3,))
        except ValueError:
            raise ValueError(f"f ({self.p['name']}): returned shape {v.shape}; expected {batch + (3,)} "
                             f"or {batch}") from None
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ValueError(f"f ({self.p['name']}): returned negative or non-finite values")
        _check_fits(v, dtype, f"f ({self.p['name']})")
        same = wo[..., 2] * wi[..., 2] > 0
        keep = (wo[..., 2] != 0) & (same | self.p["transmission"])
        return np.where(keep[..., None], v, 0.0)

    def _pdf(self, wo, wi, sf=3, dtype=np.float64):
        if self.p["pdf"] is not None:
            p = np.asarray(self.p["pdf"](wo, wi), dtype=np.float64)
            batch = np.broadcast_shapes(wo.shape[:-1], wi.shape[:-1])
            try:
                p = np.broadcast_to(p, batch)
            except ValueError:
                raise ValueError(f"pdf ({self.p['name']}): returned shape {p.shape}; expected {batch}") from None
            if not np.all(np.isfinite(p)) or np.any(p < 0):
                raise ValueError(f"pdf ({self.p['name']}): returned negative or non-finite values")
            _check_fits(p, dtype, f"pdf ({self.p['name']})")
        else:
            p = np.abs(wi[..., 2]) / np.pi * (0.5 if self.p["transmission"] else 1.0)
        same = wo[..., 2] * wi[..., 2] > 0
        allowed = np.where(same, bool(sf & ReflTrans.Reflection), bool(sf & ReflTrans.Transmission))
        allowed &= same | self.p["transmission"]
        return np.where(allowed & (wo[..., 2] != 0), p, 0.0)

    # Each entry point counts the bad inputs first and returns the counts (BxDF raises naming the
    # input) before calling the user's functions: a non-unit wo would otherwise come back as a
    # complaint about what the functions returned.
    def _eval_rows(self, wo, wi, mode, out):
        bad = _bad(wo), _bad(wi)
        if any(bad):
            return bad
        out[...] = self._f(wo.astype(np.float64), wi.astype(np.float64), out.dtype)
        return bad

    def _pdf_rows(self, wo, wi, mode, sf, out):
        bad = _bad(wo), _bad(wi)
        if any(bad):
            return bad
        out[...] = self._pdf(wo.astype(np.float64), wi.astype(np.float64), sf, out.dtype)
        return bad

    def _draw(self, wo, uc, u):
        if self.p["sample"] is not None:
            wi = np.asarray(self.p["sample"](wo, uc, u), dtype=np.float64)
            if wi.shape != wo.shape:
                raise ValueError(f"sample ({self.p['name']}): returned shape {wi.shape}; expected {wo.shape}")
            bad = _bad(wi)
            if bad:
                raise ValueError(f"sample ({self.p['name']}): returned {bad} direction(s) that are not finite unit "
                                 "vectors (|wi|^2 must equal 1 within 1e-4; mark a direction it cannot draw by "
                                 "pdf = 0)")
            return wi
        r, phi = np.sqrt(u[..., 0]), 2 * np.pi * u[..., 1]        # Malley: cosine-weighted
        z = np.sqrt(np.maximum(0.0, 1 - u[..., 0]))
        side = np.where(wo[..., 2] < 0, -1.0, 1.0)
        if self.p["transmission"]:
            side = np.where(uc < 0.5, side, -side)
        return np.stack([r * np.cos(phi), r * np.sin(phi), side * z], -1)

    def _sample_rows(self, wo, uc, u, mode, sf, wi_out, f_out, pdf_out, flags_out, eta_out, valid_out, prop_out):
        bad = _bad(wo), _bad_uniform(uc), _bad_uniform(u)
        if any(bad):
            return bad
        n = len(uc)
        wo64 = np.broadcast_to(wo.astype(np.float64), (n, 3))
        uc64 = np.minimum(uc.astype(np.float64), 1 - 2 ** -53)
        u64 = np.minimum(u.astype(np.float64), 1 - 2 ** -53)
        wi = self._draw(wo64, uc64, u64)
        f = self._f(wo64, wi, f_out.dtype)
        p = self._pdf(wo64, wi, sf, pdf_out.dtype)
        ok = (p > 0) & np.any(f > 0, axis=-1) & (wi[:, 2] != 0)
        wi_out[...] = np.where(ok[:, None], wi, np.array([0.0, 0.0, 1.0]))  # invalid: the normal
        f_out[...] = np.where(ok[:, None], f, 0.0)
        pdf_out[...] = np.where(ok, p, 0.0)
        refl = wo64[:, 2] * wi[:, 2] > 0
        flags_out[...] = np.where(ok, np.where(refl, int(BxDFFlags.GlossyReflection),
                                               int(BxDFFlags.GlossyTransmission)), 0)
        eta_out[...] = 1.0
        valid_out[...] = ok
        prop_out[...] = False
        return bad

    def _albedo_rows(self, wo, n_samples, seed, mode, out):
        bad = _bad(wo)
        if bad:
            return bad
        rng = np.random.default_rng(seed)
        chunk = max(1, 1_000_000 // max(1, len(wo)))
        acc = np.zeros((len(wo), 3))
        done = 0
        while done < n_samples:  # Ctrl-C lands between chunks (plain Python)
            k = min(chunk, n_samples - done)
            wo_k = np.repeat(wo.astype(np.float64), k, axis=0)
            uc, u = rng.random(len(wo_k)), rng.random((len(wo_k), 2))
            wi = self._draw(wo_k, uc, u)
            f, p = self._f(wo_k, wi, out.dtype), self._pdf(wo_k, wi, dtype=out.dtype)
            w = np.where(p > 0, np.abs(wi[:, 2]) / np.where(p > 0, p, 1.0), 0.0)
            with np.errstate(over="ignore", invalid="ignore"):
                acc += (f * w[:, None]).reshape(len(wo), k, 3).sum(1)
            done += k
        est = acc / n_samples
        top = float(np.finfo(out.dtype).max)
        if not (np.all(np.isfinite(est)) and float(est.max(initial=0.0)) <= top):
            raise ValueError(f"f ({self.p['name']}): the albedo estimate (the mean of f |cos| / pdf) overflows "
                             f"{out.dtype.name} (max {top:.6g})")
        out[...] = est
        return 0


class Custom(BxDF, register=False):  # a user model: not in the registry of shipped models
    __doc__ = __doc__

    __slots__ = ()

    def __init__(self, f, pdf=None, sample=None, name="custom", transmission=False):
        if not callable(f):
            raise TypeError(f"f: expected a function f(wo, wi) -> (..., 3), got {type(f).__name__}")
        for arg, v in (("pdf", pdf), ("sample", sample)):
            if v is not None and not callable(v):
                raise TypeError(f"{arg}: expected a function or None, got {type(v).__name__}")
        if (sample is None) != (pdf is None):
            raise ValueError("pdf, sample: give both (the density of your sampler) or neither (cosine sampling)")
        if not isinstance(name, str) or not name:
            raise TypeError(f"name: expected a non-empty str, got {name!r}")
        super().__init__(f=f, pdf=pdf, sample=sample, name=name, transmission=bool(transmission))

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def _make_core(self):
        return _PyCore(self._params)

    def _key(self):
        return tuple((k, v) for k, v in self._params.items())

    def describe(self) -> str:
        return self._params["name"]

    def __repr__(self):
        def fn(v):
            return "None" if v is None else getattr(v, "__qualname__", repr(v))
        p = self._params
        return (f"Custom(f={fn(p['f'])}, pdf={fn(p['pdf'])}, sample={fn(p['sample'])}, name={p['name']!r}, "
                f"transmission={p['transmission']})")
