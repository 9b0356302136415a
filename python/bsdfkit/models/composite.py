"""Composite models: blends and wrappers of other models, in Python over the children's compiled doors.

``Mix`` (Mitsuba 3 ``blendbsdf``, or pbrt-v4 ``MixMaterial`` with ``method="stochastic"``),
``TwoSided`` (Mitsuba ``twosided``), ``Mask`` (Mitsuba ``mask``) here; ``NormalMap`` (Mitsuba
``normalmap``) in ``normal_map``, ``BumpMap`` (Mitsuba ``bumpmap``) in ``bump_map``. Each is a registered model: value semantics, specs (a child is
written in brackets: ``mix [diffuse 0.8] [conductor metal=Au alpha=0.3] 0.3``), the contract suite,
plots, ``to_mitsuba`` and ``from_mitsuba``. Per-element parameters (``weight``, ``opacity``,
``normals``) are numpy arrays broadcasting against the call's batch shape (the directions' shape
without the last axis); results then equal a loop of scalar models element by element. ``==`` and
``hash`` compare such arrays by a content digest, and ``repr`` shows an array of more than 12
values by its shape and digest (that repr cannot be evaluated back; smaller ones print in full).

Capability flags (``energy_conserving``, ``reciprocal``, ...) are answered per instance from the
children; the class attribute is the value of the registered examples. The preview renderer takes
compiled models only and refuses these with a TypeError naming the model. Spectral mode
(``wavelengths=``) passes through to the children (it raises where a child has no spectral kernel).
"""
from __future__ import annotations

import numpy as np

from .._arrays import _mix64
from .._enums import BxDFFlags, ReflTrans
from . import _frames
from . import _mitsuba_export as _me
from ._composite_core import (Door, array_param, child_eval, child_pdf, child_sample, digest, empty_sample,
                              put_sample, take)
from .base import BxDF

__all__ = ["Mix", "TwoSided", "Mask"]

_SPECULAR = int(BxDFFlags.Specular)
_REFL, _TRANS = int(ReflTrans.Reflection), int(ReflTrans.Transmission)


class _Flag:
    """A capability flag: the class's declared value on the class, the instance's own from its
    children (``rule(model)``) on an instance."""

    def __init__(self, default, rule):
        self.default, self.rule = default, rule

    def __get__(self, obj, cls=None):
        return self.default if obj is None else bool(self.rule(obj))


def _model(x, name):
    if isinstance(x, str):   # a spec, e.g. from the CLI
        from .spec import parse_spec
        x = parse_spec(x)
    if not isinstance(x, BxDF):
        raise TypeError(f"{name}: expected a bsdfkit model (e.g. bk.Diffuse(0.8)), got {type(x).__name__}")
    return x


def _fmt(v):
    if isinstance(v, np.ndarray):
        if v.size <= 12:
            return repr(v.tolist())
        return f"<array {v.shape} digest {digest(v)}>"
    return repr(v)


class _Composite(BxDF, register=False):
    """Shared machinery of the composite models (not registered)."""

    __slots__ = ()
    _param_tails: dict = {}
    _check_dirs = True
    knobs = ()

    def _make_core(self):
        return Door(self)

    def _children(self):
        return [v for v in self._params.values() if isinstance(v, BxDF)]

    def _param_arrays(self) -> dict:
        return {}

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def _key(self):
        return tuple((k, ("array", v.shape, digest(v)) if isinstance(v, np.ndarray) else v)
                     for k, v in self._params.items())

    def __repr__(self):
        return f"{type(self).__name__}(" + ", ".join(f"{k}={_fmt(v)}" for k, v in self._params.items()) + ")"

    # the array API: the base's, with wavelengths= passed to this door (the children run spectral);
    # normal= / tangent= (world space) rotate the directions once here, the children run local
    def eval(self, wo, wi, mode=0, out=None, *, wavelengths=None, normal=None, tangent=None, uv=None, duvdx=None,
             duvdy=None):
        if normal is not None or tangent is not None:
            return _frames.eval(self, wo, wi, mode, out, wavelengths, normal, tangent)
        if wavelengths is None:
            return super().eval(wo, wi, mode, out)
        return self._core.eval(wo, wi, mode, out, wavelengths)

    def pdf(self, wo, wi, mode=0, sample_flags=ReflTrans.All, out=None, *, wavelengths=None, normal=None,
            tangent=None, uv=None, duvdx=None, duvdy=None):
        if normal is not None or tangent is not None:
            return _frames.pdf(self, wo, wi, mode, sample_flags, out, wavelengths, normal, tangent)
        if wavelengths is None:
            return super().pdf(wo, wi, mode, sample_flags, out)
        return self._core.pdf(wo, wi, mode, sample_flags, out, wavelengths)

    def sample(self, wo, uc=None, u=None, *, n=None, seed=None, mode=0, sample_flags=ReflTrans.All, out=None,
               wavelengths=None, normal=None, tangent=None, uv=None, duvdx=None, duvdy=None):
        if normal is not None or tangent is not None:
            return _frames.sample(self, wo, uc, u, n, seed, mode, sample_flags, out, wavelengths, normal, tangent)
        if out is not None:
            _frames.forget_frame(out)
        return self._core.sample(wo, uc, u, mode, sample_flags, out, n, seed, wavelengths)

    def albedo(self, wo, n_samples: int = 65536, seed: int = 0, mode=0, *, wavelengths=None, normal=None,
               tangent=None, uv=None, duvdx=None, duvdy=None):
        if normal is not None or tangent is not None:
            return _frames.albedo(self, wo, n_samples, seed, mode, wavelengths, normal, tangent)
        return self._core.albedo(wo, n_samples, seed, mode, wavelengths)

    def _flags(self) -> int:
        f = 0
        for c in self._children():
            f |= int(c.flags)
        return f

    eval.__doc__, pdf.__doc__, sample.__doc__, albedo.__doc__ = (BxDF.eval.__doc__, BxDF.pdf.__doc__,
                                                                  BxDF.sample.__doc__, BxDF.albedo.__doc__)


def _scale(x, w):
    """x (a child's fresh (N, channels) or (N,) result) times the per-row weight w ((1,) or (N,)
    rows), in place where the shapes allow: by a scalar, or channel by channel (numpy's
    broadcast of an (N, 1) operand over 3 channels is several times slower)."""
    if len(w) == 1:
        return np.multiply(x, w[0], out=x)
    if len(x) != len(w):
        return x * (w[:, None] if x.ndim == 2 else w)
    if x.ndim == 1:
        return np.multiply(x, w, out=x)
    for c in range(x.shape[1]):
        np.multiply(x[:, c], w, out=x[:, c])
    return x


def _all(attr):
    return lambda m: all(getattr(c, attr) for c in m._children())


def _any(attr):
    return lambda m: any(getattr(c, attr) for c in m._children())


# ----------------------------------------------------------------------------------------------- Mix

_STREAM = np.uint64(0x4D49584D)   # "MIXM": the stochastic choice's hash stream


def _choice_uniform(wo, key):
    """pbrt-v4 MixMaterial's ``HashFloat(p, wo, ...)`` in our terms: a uniform in [0, 1) from the
    bits of wo (rounded to float32, so float32 and float64 calls choose alike) and the per-element
    key (an integer, pbrt's position stand-in)."""
    b = np.ascontiguousarray(wo, dtype=np.float32).view(np.uint32).astype(np.uint64)
    with np.errstate(over="ignore"):
        h = _mix64(b[:, 0] ^ _STREAM)
        h = _mix64(h ^ b[:, 1])
        h = _mix64(h ^ b[:, 2])
        if key is not None:
            h = _mix64(h ^ key.astype(np.int64).view(np.uint64))
    return (h >> np.uint64(11)).astype(np.float64) * 2.0 ** -53


class Mix(_Composite):
    """Blend of two models, f = (1 - weight) f_a + weight f_b (Mitsuba 3 ``blendbsdf``).

    a, b: models (or specs). weight: in [0, 1], a float or a numpy array broadcasting against the
    call's batch shape (the directions' shape without the last axis): per element.

    ``method="linear"`` (Mitsuba ``blendbsdf``): eval and pdf are the weighted sums of the
    children's. ``sample`` picks b when ``uc <= weight`` (a otherwise), passes the child a fresh
    uniform (``uc / weight`` or ``(uc - weight) / (1 - weight)``) and returns the mixture's f and pdf
    at the sampled direction (``f = (1 - w) f_a + w f_b``, ``pdf = (1 - w) pdf_a + w pdf_b``), as
    Mitsuba 3.9 does. A delta-lobe sample returns the chosen child's f and pdf times its selection
    probability (the other child's density is of another measure; Mitsuba 3.9 adds it, a mixing of
    measures we do not copy); so does a sample with ``pdf_is_proportional`` (a stochastic child).

    ``method="stochastic"`` (pbrt-v4 ``MixMaterial``): one component per shading point, b where a
    hash of wo (its float32 bits) and the per-element integer ``key`` (pbrt hashes the position;
    default None: wo alone) is <= weight. f, pdf and sample are that component's; the choice does
    not depend on wi, so sample, eval and pdf agree exactly, but f(wo, wi) and f(wi, wo) may come
    from different components (not reciprocal). Mitsuba has no such plugin: ``to_mitsuba``
    refuses, ``approximate=True`` exports the linear blend (the choice's expectation).

    Capability flags are the children's (energy conserving if both are, ...); ``delta_only`` if both.

    Parameters
    ----------
    a, b : BxDF or str
        The two models (or their specs); ``weight`` 0 is ``a``, 1 is ``b``.
    weight : float or numpy.ndarray, default 0.5
        In [0, 1]; an array broadcasts against the call's batch shape (per element).
    method : {"linear", "stochastic"}, default "linear"
        Mitsuba's ``blendbsdf`` (linear in the weight) or pbrt-v4's ``MixMaterial`` (one
        component per shading point).
    key : numpy.ndarray of int, optional
        Per-element integers hashed with wo by ``method="stochastic"`` (pbrt hashes the position).
    """

    __slots__ = ()
    aliases = ("blend",)
    description = "Blend of two models by a weight, linear (Mitsuba blendbsdf) or one per point (pbrt-v4 mix)"
    examples = {"diffuse + gold, 0.3": "mix [diffuse 0.8,0.5,0.2] [conductor metal=Au alpha=0.3 masking=separable] 0.3",
                "glass + plastic, 0.6": "mix [dielectric 1.5 alpha=0.3 masking=separable] "
                                        "[plastic 0.5 alpha=0.2 masking=separable] 0.6",
                "stochastic": "mix [diffuse 0.9] [conductor metal=Cu alpha=0.4 masking=separable] 0.5 "
                              "method=stochastic"}
    mitsuba = "blendbsdf"
    energy_conserving = _Flag(True, _all("energy_conserving"))
    exact_eval = _Flag(True, _all("exact_eval"))
    reciprocal = _Flag(True, lambda m: m._params["method"] == "linear" and _all("reciprocal")(m))
    two_sided = _Flag(True, _all("two_sided"))
    transmission = _Flag(False, _any("transmission"))
    delta_only = _Flag(False, _all("delta_only"))

    def __init__(self, a, b, weight=0.5, method="linear", key=None):
        """A Mix: the parameters are described in the class docstring (``help(bsdfkit.Mix)``); a bad
        value raises ValueError (TypeError for a wrong type) naming the parameter (and the first bad
        index of an array)."""
        a, b = _model(a, "a"), _model(b, "b")
        w = array_param(weight, "weight", lo=0.0, hi=1.0)
        if method not in ("linear", "stochastic"):
            raise ValueError(f"method: must be 'linear' (Mitsuba blendbsdf) or 'stochastic' (pbrt-v4 MixMaterial), "
                             f"got {method!r}")
        if key is not None:
            if method != "stochastic":
                raise ValueError("key: only used by method='stochastic'")
            k = np.asarray(key)
            if k.dtype.kind not in "iu":
                raise TypeError(f"key: expected integers (one per element, pbrt's position stand-in), got dtype "
                                f"{k.dtype}")
            key = int(k) if k.ndim == 0 else k.astype(np.int64)
            if isinstance(key, np.ndarray):
                key.setflags(write=False)
        super().__init__(a=a, b=b, weight=w, method=method, key=key)

    _int_params = ("key",)

    def _param_arrays(self):
        p = {"weight": self._params["weight"]}
        if self._params["key"] is not None:
            p["key"] = self._params["key"]
        return p

    def describe(self) -> str:
        w = self._params["weight"]
        wt = f"{w:.3g}" if isinstance(w, float) else "map"
        st = ", stochastic" if self._params["method"] == "stochastic" else ""
        return f"Mix w={wt}{st}: {type(self.a).__name__} + {type(self.b).__name__}"

    # ---- the stochastic choice
    @staticmethod
    def _pick_b(wo, w, P):
        """Rows taking component b (pbrt-v4: b when amount >= 1, a when <= 0, else u <= amount)."""
        n = P["_n"]
        key = P.get("key")
        u = _choice_uniform(np.broadcast_to(wo, (n, 3)), None if key is None else np.broadcast_to(key, (n,)))
        w = np.broadcast_to(w, (n,)).astype(np.float64)
        return (w >= 1) | ((w > 0) & (u <= w))

    # ---- rows
    _check_dirs = False   # a and b get wo and wi as given: their doors count bad directions

    @staticmethod
    def _blend(xa, xb, w, out):
        """(1 - w) xa + w xb (xa, xb are the children's fresh results, scaled in place): Mitsuba's order."""
        xa, xb = _scale(xa, 1 - w), _scale(xb, w)
        if out is not None and out.shape == np.broadcast_shapes(xa.shape, xb.shape):
            return np.add(xa, xb, out=out)
        return xa + xb

    def _eval_rows(self, wo, wi, md, lam, P, out=None):
        a, b = self._params["a"], self._params["b"]
        w = P["weight"]
        if out is not None and lam is None and self._params["method"] == "linear" and \
                out.shape[0] == max(len(wo), len(wi)):   # a writes straight into the result rows
            fa = a.eval(wo, wi, md, out=out)
            return self._blend(fa, child_eval(b, wo, wi, md, lam), w, out)
        fa, fb = child_eval(a, wo, wi, md, lam), child_eval(b, wo, wi, md, lam)
        if self._params["method"] == "stochastic":
            return np.where(self._pick_b(wo, w, P)[:, None], fb, fa)
        return self._blend(fa, fb, w, out)

    def _pdf_rows(self, wo, wi, md, sf, lam, P, out=None):
        a, b = self._params["a"], self._params["b"]
        pa, pb = child_pdf(a, wo, wi, md, sf, lam), child_pdf(b, wo, wi, md, sf, lam)
        w = P["weight"]
        if self._params["method"] == "stochastic":
            return np.where(self._pick_b(wo, w, P), pb, pa)
        return self._blend(pa, pb, w, out)

    def _sample_rows(self, wo, uc, u, md, sf, lam, P, n):
        a, b = self._params["a"], self._params["b"]
        dtype = uc.dtype
        rows = empty_sample(n, dtype, 3 if lam is None else 4, lam is not None)
        w = np.broadcast_to(P["weight"], (n,))
        stochastic = self._params["method"] == "stochastic"
        if stochastic:
            pick = self._pick_b(wo, w, P)
        else:
            pick = (uc <= w) & (w > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            uc_b = np.minimum(np.where(pick, uc / np.where(w > 0, w, 1), 0), 1).astype(dtype)
            uc_a = np.minimum(np.maximum((uc - w) / np.where(w < 1, 1 - w, 1), 0), 1).astype(dtype)
        for model, other, idx, ucc, own_w, oth_w in ((a, b, np.nonzero(~pick)[0], uc_a, 1 - w, w),
                                                     (b, a, np.nonzero(pick)[0], uc_b, w, 1 - w)):
            if not len(idx):
                continue
            wo_i, lam_i = take(wo, idx), take(lam, idx)
            s = child_sample(model, wo_i, (uc if stochastic else ucc)[idx], u[idx], md, sf, lam_i, idx)
            put_sample(rows, idx, s)
            if stochastic:
                continue
            ow, tw = own_w[idx], oth_w[idx]
            # a delta lobe, or a stochastic child's sample: the chosen child's values times its
            # selection probability (Monte Carlo weight unchanged)
            mix = s.valid & ((s.flags & _SPECULAR) == 0) & ~s.pdf_is_proportional
            f, p = s.f * ow[:, None], s.pdf * ow
            j = np.nonzero(mix)[0]
            if len(j):   # Mitsuba 3.9 blendbsdf: the mixture's f and pdf at the sampled direction
                wo_j, lam_j = take(wo_i, j), take(lam_i, j)
                fo = child_eval(other, wo_j, s.wi[j], md, lam_j, idx[j])
                po = child_pdf(other, wo_j, s.wi[j], md, sf, lam_j, idx[j])
                f[j] += fo * tw[j][:, None]
                p[j] += po * tw[j]
            rows["f"][idx], rows["pdf"][idx] = f, p
            rows["valid"][idx] &= rows["pdf"][idx] > 0
        inv = ~rows["valid"]
        rows["wi"][inv] = (0, 0, 1)
        rows["f"][inv], rows["pdf"][inv], rows["flags"][inv], rows["eta"][inv] = 0, 0, 0, 1
        return rows

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """``blendbsdf`` with ``weight`` and the children's dictionaries as ``bsdf_0`` (a) and
        ``bsdf_1`` (b). A per-element weight (no uv mapping to write a bitmap with) raises
        ValueError; ``method="stochastic"`` raises MitsubaExportError (Mitsuba has no per-point
        choice), ``approximate=True`` exports the linear blend with a warning."""
        approximate = _me.check_approximate(approximate)
        p = self._params
        if isinstance(p["weight"], np.ndarray):
            raise ValueError("Mix.to_mitsuba: a per-element weight array has no Mitsuba dictionary here (Mitsuba takes "
                             "a texture at uv); export each element's scalar Mix")
        d = {"type": "blendbsdf", "weight": float(p["weight"]),
             "bsdf_0": p["a"].to_mitsuba(approximate=approximate), "bsdf_1": p["b"].to_mitsuba(approximate=approximate)}
        if p["method"] == "stochastic":
            linear = Mix(p["a"], p["b"], p["weight"])
            _me.refuse_or_warn(self, linear, ["Mitsuba 3 has no per-point choice (pbrt-v4 MixMaterial); blendbsdf is "
                                              "its expectation, the linear blend"], approximate)
        return d


# ------------------------------------------------------------------------------------------ TwoSided

def _flip(w, s):
    """w with z multiplied by the sign s."""
    out = np.array(w, copy=True)
    out[:, 2] *= s
    return out


class TwoSided(_Composite):
    """Mitsuba 3 ``twosided``: ``front`` seen from above the surface, ``back`` (default: front)
    from below, each as from above.

    wo.z > 0: f = front(wo, wi); wo.z < 0: f = back(wo', wi') with the z of both directions flipped
    (wo.z = 0: 0). Transmission across the surface is 0, as in Mitsuba (whose twosided refuses
    transmitting children): a child's transmission lobes are left out, its reflection lobes are
    sampled alone (``sample_flags=Reflection``), so ``TwoSided(bk.Dielectric(1.5, alpha=0.3))`` is
    that dielectric's reflection. bsdfkit's own models are already two-sided (mirrored below);
    TwoSided gives a surface a different back, and makes any model reflection-only.

    Parameters
    ----------
    front : BxDF or str
        The model seen from above the surface.
    back : BxDF or str, optional
        The model seen from below (each as from above); default: ``front``.
    """

    __slots__ = ()
    description = "Different models on the front and the back of a surface, reflection only (Mitsuba twosided)"
    examples = {"gold front, red back": "two_sided [conductor metal=Au alpha=0.3 masking=separable] [diffuse 0.8,0.1,0.1]",
                "glass reflection": "two_sided [dielectric 1.5 alpha=0.25 masking=separable] [diffuse 0.3]"}
    mitsuba = "twosided"
    energy_conserving = _Flag(True, _all("energy_conserving"))
    exact_eval = _Flag(True, _all("exact_eval"))
    reciprocal = _Flag(True, _all("reciprocal"))
    two_sided, transmission = True, False
    delta_only = _Flag(False, _all("delta_only"))

    def __init__(self, front, back=None):
        """A TwoSided: the parameters are described in the class docstring (``help(bsdfkit.TwoSided)``);
        a model that is not a bsdfkit model raises TypeError naming the parameter."""
        super().__init__(front=_model(front, "front"), back=None if back is None else _model(back, "back"))

    def _children(self):
        return [self.front] + ([] if self.back is None else [self.back])

    def _flags(self) -> int:
        f = 0
        for c in self._children():
            f |= int(c.flags)
        return f & ~int(BxDFFlags.Transmission) if f & int(BxDFFlags.Reflection) else 0

    def describe(self) -> str:
        back = "" if self.back is None else f" / {type(self.back).__name__}"
        return f"TwoSided {type(self.front).__name__}{back}"

    def _split(self, wo, wi, P, fn, shape_tail):
        """fn(model, rows, sign) on the front rows (wo.z > 0, sign 1) and the back rows (wo.z < 0,
        sign -1), 0 elsewhere and where wi is on the other side (no transmission)."""
        n = P["_n"]
        out = np.zeros((n,) + shape_tail, wo.dtype)
        z = np.broadcast_to(wo[:, 2], (n,))
        same = z * np.broadcast_to(wi[:, 2], (n,)) > 0
        back = self.back if self.back is not None else self.front
        for model, rows, sign in ((self.front, np.nonzero(same & (z > 0))[0], 1),
                                  (back, np.nonzero(same & (z < 0))[0], -1)):
            if len(rows):
                out[rows] = fn(model, rows, sign)
        return out

    def _eval_rows(self, wo, wi, md, lam, P, out=None):
        def fn(m, r, sign):
            return child_eval(m, _flip(take(wo, r), sign), _flip(take(wi, r), sign), md, take(lam, r), r)
        return self._split(wo, wi, P, fn, (3 if lam is None else 4,))

    def _pdf_rows(self, wo, wi, md, sf, lam, P, out=None):
        def fn(m, r, sign):
            return child_pdf(m, _flip(take(wo, r), sign), _flip(take(wi, r), sign), md, sf & _REFL, take(lam, r), r)
        return self._split(wo, wi, P, fn, ())

    def _sample_rows(self, wo, uc, u, md, sf, lam, P, n):
        rows = empty_sample(n, uc.dtype, 3 if lam is None else 4, lam is not None)
        if not sf & _REFL:
            return rows
        z = np.broadcast_to(wo[:, 2], (n,))
        back = self.back if self.back is not None else self.front
        for model, r, sign in ((self.front, np.nonzero(z > 0)[0], 1), (back, np.nonzero(z < 0)[0], -1)):
            if not len(r):
                continue
            s = child_sample(model, _flip(take(wo, r), sign), uc[r], u[r], md, _REFL, take(lam, r), r)
            put_sample(rows, r, s)
            rows["wi"][r, 2] *= sign
            rows["valid"][r] &= s.wi[:, 2] > 0
        inv = ~rows["valid"]
        rows["wi"][inv] = (0, 0, 1)
        rows["f"][inv], rows["pdf"][inv], rows["flags"][inv], rows["eta"][inv] = 0, 0, 0, 1
        return rows

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """``twosided`` with the front's (and the back's) one-sided plugin (a child exported as
        ``twosided{x}`` gives its ``x``). A transmitting child raises ValueError (Mitsuba's twosided
        refuses it; bsdfkit drops its transmission)."""
        approximate = _me.check_approximate(approximate)
        for name, c in (("front", self.front), ("back", self.back)):
            if c is not None and c.flags & BxDFFlags.Transmission:
                raise ValueError(f"TwoSided.to_mitsuba: {name} transmits; Mitsuba's twosided refuses transmitting "
                                 "BSDFs (bsdfkit's TwoSided leaves the transmission out)")

        def one(m):
            d = m.to_mitsuba(approximate=approximate)
            if d.get("type") == "twosided" and list(d) == ["type", "bsdf"]:
                d = d["bsdf"]
            return d
        if self.back is None:
            return {"type": "twosided", "bsdf": one(self.front)}
        return {"type": "twosided", "bsdf_0": one(self.front), "bsdf_1": one(self.back)}


# ---------------------------------------------------------------------------------------------- Mask

class Mask(_Composite):
    """Mitsuba 3 ``mask``: the model with opacity ``opacity``, the rest passing straight through.

    f = opacity f_model and pdf = opacity pdf_model (Mitsuba: the pdf is scaled only while the
    pass-through lobe may be sampled, i.e. ``sample_flags`` includes Transmission). ``sample``: with
    probability 1 - opacity (``uc >= opacity``) a delta transmission wi = -wo of throughput weight 1
    (f = (1 - opacity) / |cos|, pdf = 1 - opacity, flags SpecularTransmission, eta 1), else the
    model with ``uc / opacity``. opacity: in [0, 1], a float or a per-element numpy array.

    Parameters
    ----------
    model : BxDF or str
        The masked model.
    opacity : float or numpy.ndarray, default 0.5
        In [0, 1]; the rest passes straight through. An array is per element.
    """

    __slots__ = ()
    description = "A model with an opacity, the rest passing straight through (Mitsuba mask)"
    examples = {"leaf, 0.7 opaque": "mask [diffuse 0.3,0.6,0.2] 0.7",
                "rough gold, 0.4": "mask [conductor metal=Au alpha=0.3 masking=separable] 0.4"}
    mitsuba = "mask"
    energy_conserving = _Flag(True, _all("energy_conserving"))
    exact_eval = _Flag(True, _all("exact_eval"))
    reciprocal = _Flag(True, _all("reciprocal"))
    two_sided = _Flag(True, _all("two_sided"))
    transmission, delta_only = True, _Flag(False, _all("delta_only"))

    def __init__(self, model, opacity=0.5):
        """A Mask: the parameters are described in the class docstring (``help(bsdfkit.Mask)``); a bad
        value raises ValueError (TypeError for a wrong type) naming the parameter (and index)."""
        super().__init__(model=_model(model, "model"), opacity=array_param(opacity, "opacity", lo=0.0, hi=1.0))

    def _param_arrays(self):
        return {"opacity": self._params["opacity"]}

    def _flags(self) -> int:
        return int(self.model.flags) | int(BxDFFlags.SpecularTransmission)

    def describe(self) -> str:
        o = self._params["opacity"]
        return f"Mask {type(self.model).__name__}, opacity {o:.3g}" if isinstance(o, float) else \
            f"Mask {type(self.model).__name__}, opacity map"

    _check_dirs = False   # the model gets wo and wi as given: its door counts bad directions

    def _eval_rows(self, wo, wi, md, lam, P, out=None):
        return _scale(child_eval(self.model, wo, wi, md, lam), P["opacity"])

    def _pdf_rows(self, wo, wi, md, sf, lam, P, out=None):
        p = child_pdf(self.model, wo, wi, md, sf, lam)
        return _scale(p, P["opacity"]) if sf & _TRANS else p

    def _sample_rows(self, wo, uc, u, md, sf, lam, P, n):
        dtype = uc.dtype
        rows = empty_sample(n, dtype, 3 if lam is None else 4, lam is not None)
        op = np.broadcast_to(P["opacity"], (n,))
        if not sf & _TRANS:
            op = np.ones(n, dtype)   # Mitsuba: the pass-through lobe disabled, the model always
        nested = uc < op
        r = np.nonzero(nested)[0]
        if len(r):
            with np.errstate(divide="ignore", invalid="ignore"):
                ucr = np.minimum(uc[r] / op[r], 1).astype(dtype)
            s = child_sample(self.model, take(wo, r), ucr, u[r], md, sf, take(lam, r), r)
            put_sample(rows, r, s)
            rows["f"][r] = s.f * op[r, None]
            rows["pdf"][r] = s.pdf * op[r]
        t = np.nonzero(~nested)[0]
        if len(t):   # the null lobe: wi = -wo, throughput weight 1 (Mitsuba mask.cpp)
            w = np.broadcast_to(wo, (n, 3))[t]
            q = (1 - op[t]).astype(np.float64)
            c = np.abs(w[:, 2].astype(np.float64))
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                f = q / c
            ok = (q > 0) & (c > 0) & (f <= np.finfo(dtype).max)
            rows["wi"][t] = -w
            rows["f"][t] = np.where(ok, f, 0)[:, None]
            rows["pdf"][t] = np.where(ok, q, 0)
            rows["flags"][t] = int(BxDFFlags.SpecularTransmission)
            rows["eta"][t] = 1
            rows["valid"][t] = ok
            rows["pdf_is_proportional"][t] = False
        inv = ~rows["valid"]
        rows["wi"][inv] = (0, 0, 1)
        rows["f"][inv], rows["pdf"][inv], rows["flags"][inv], rows["eta"][inv] = 0, 0, 0, 1
        return rows

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """``mask`` with ``opacity`` and the model's dictionary as ``material``. A per-element
        opacity array raises ValueError (no uv mapping to write a bitmap with)."""
        approximate = _me.check_approximate(approximate)
        o = self._params["opacity"]
        if isinstance(o, np.ndarray):
            raise ValueError("Mask.to_mitsuba: a per-element opacity array has no Mitsuba dictionary here (Mitsuba "
                             "takes a texture at uv); export each element's scalar Mask")
        return {"type": "mask", "opacity": float(o), "material": self.model.to_mitsuba(approximate=approximate)}
