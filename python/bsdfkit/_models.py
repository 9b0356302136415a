"""Public model classes: validated, immutable parameter records around the compiled kernels."""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from . import _core
from ._arrays import (as_dirs, as_uniform, broadcast_batch, check_int, check_out, fast_dirs, fast_pair,
                      fast_sample_args,
                      flatten_to, kernel_dtype)
from ._enums import BxDFFlags, ReflTrans, TransportMode

__all__ = ["BxDF", "SampleResult", "Diffuse", "DiffuseTransmission", "Conductor", "Dielectric",
           "ThinDielectric", "roughness_to_alpha", "conductor_fresnel", "METALS"]

_MASKING = {"correlated": 0, "separable": 1}
# Conductor Fresnel knob -> (_core class, conductor_fresnel code), most accurate first.
_FRESNEL = {"exact": ("Conductor", 0), "schlick": ("ConductorSchlick", 1), "f82": ("ConductorF82", 2)}


# ---------------------------------------------------------------- parameter validation

def _scalar(x, name: str, *, lo=None, hi=None, lo_open=False) -> float:
    if isinstance(x, bool) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name}: expected a real number, got {type(x).__name__}")
    v = float(x)
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {v}")
    if lo is not None and (v <= lo if lo_open else v < lo):
        raise ValueError(f"{name}: must be {'>' if lo_open else '>='} {lo}, got {v}")
    if hi is not None and v > hi:
        raise ValueError(f"{name}: must be <= {hi}, got {v}")
    return v


def _rgb(x, name: str, *, lo=None, hi=None, lo_open=False) -> np.ndarray:
    a = np.asarray(x)
    if a.dtype.kind not in "fiu":
        raise TypeError(f"{name}: expected a number or 3 numbers (RGB), got dtype {a.dtype}")
    if a.ndim == 0:
        a = np.repeat(a, 3)
    if a.shape != (3,):
        raise ValueError(f"{name}: expected a number or 3 numbers (RGB), got shape {a.shape}")
    a = a.astype(np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: must be finite, got {a.tolist()}")
    if lo is not None and np.any(a <= lo if lo_open else a < lo):
        raise ValueError(f"{name}: every channel must be {'>' if lo_open else '>='} {lo}, got {a.tolist()}")
    if hi is not None and np.any(a > hi):
        raise ValueError(f"{name}: every channel must be <= {hi}, got {a.tolist()}")
    a.setflags(write=False)
    return a


def _alphas(alpha, alpha_x, alpha_y):
    a = _scalar(alpha, "alpha", lo=0.0)
    ax = a if alpha_x is None else _scalar(alpha_x, "alpha_x", lo=0.0)
    ay = a if alpha_y is None else _scalar(alpha_y, "alpha_y", lo=0.0)
    return ax, ay


def _masking(m) -> str:
    if m not in _MASKING:
        raise ValueError(f"masking: must be one of {sorted(_MASKING)}, got {m!r}")
    return m


def _fresnel(f) -> str:
    if not isinstance(f, str) or f not in _FRESNEL:
        raise ValueError(f"fresnel: must be one of {list(_FRESNEL)}, got {f!r}")
    return f


def roughness_to_alpha(roughness):
    """pbrt-v4's ``RoughnessToAlpha``: alpha = sqrt(roughness).

    pbrt-v4 applies it to ``roughness``/``uroughness``/``vroughness`` when ``remaproughness``
    is true (the default). pbrt-v4 issue #479 notes that r**2 would have been the perceptually
    linear choice; sqrt is kept for compatibility with pbrt scenes. Accepts scalars or arrays;
    roughness must be finite and >= 0.
    """
    r = np.asarray(roughness, dtype=np.float64)
    if not np.all(np.isfinite(r)) or np.any(r < 0):
        raise ValueError("roughness: must be finite and >= 0")
    out = np.sqrt(r)
    return float(out) if out.ndim == 0 else out


# ---------------------------------------------------------------- results

@dataclass(frozen=True)
class SampleResult:
    """Sampled directions and their values; arrays share the batch shape of the inputs.

    wi: (..., 3) sampled directions (outward, local frame); f: (..., 3) BSDF value (cosine
    excluded); pdf: (...) solid-angle density, or the discrete probability for a specular lobe;
    flags: (...) uint8 ``BxDFFlags`` of the sampled lobe; eta: (...) relative IOR along wi
    (1 for reflection); valid: (...) bool, False where no sample exists (then f = pdf = 0,
    wi = (0, 0, 1), the shading normal, and eta = 1: every wi is a valid ``eval`` / ``pdf`` input);
    pdf_is_proportional: (...) bool (layered models only).
    """

    wi: np.ndarray
    f: np.ndarray
    pdf: np.ndarray
    flags: np.ndarray
    eta: np.ndarray
    valid: np.ndarray
    pdf_is_proportional: np.ndarray

    @property
    def weight(self) -> np.ndarray:
        """f |cos wi| / pdf, 0 where invalid (the Monte Carlo throughput weight)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            w = self.f * (np.abs(self.wi[..., 2]) / self.pdf)[..., None]
        return np.where(self.valid[..., None], w, 0.0).astype(self.f.dtype)


_RADIANCE = TransportMode.Radiance
_ALL = ReflTrans.All


def _new_sample_result(batch, dtype) -> SampleResult:
    """An uninitialized SampleResult of the batch shape (filled by the kernel). Built without the
    frozen dataclass's __init__ (seven object.__setattr__ calls): part of a small call's fixed cost."""
    r = object.__new__(SampleResult)
    r.__dict__.update(wi=np.empty(batch + (3,), dtype), f=np.empty(batch + (3,), dtype), pdf=np.empty(batch, dtype),
                      flags=np.empty(batch, np.uint8), eta=np.empty(batch, dtype), valid=np.empty(batch, bool),
                      pdf_is_proportional=np.empty(batch, bool))
    return r


def _mode(mode) -> int:
    if isinstance(mode, str) and mode.capitalize() in TransportMode.__members__:
        return int(TransportMode[mode.capitalize()])
    try:
        return int(TransportMode(mode))
    except (ValueError, TypeError):
        raise ValueError(f"mode: must be a TransportMode, got {mode!r}") from None


def _sflags(sf) -> int:
    try:
        v = int(ReflTrans(sf))
    except (ValueError, TypeError):
        raise ValueError(f"sample_flags: must be a ReflTrans, got {sf!r}") from None
    return v


def _raise_bad(name: str, count: int) -> None:
    if count:
        raise ValueError(f"{name}: {count} direction(s) are not finite unit vectors "
                         "(|w|^2 must equal 1 within 1e-4; normalize them first)")


# ---------------------------------------------------------------- base class

class BxDF:
    """Common array API of every model (pbrt-v4 conventions).

    Directions live in the local shading frame (z is the normal), are unit vectors and point
    away from the surface, both ``wo`` (towards the viewer) and ``wi``. ``eval`` excludes the
    cosine factor; ``pdf`` is per unit solid angle. Inputs broadcast with numpy rules over
    their leading axes. float32 inputs run float32 kernels, anything else real runs float64.
    """

    _fields: tuple = ()
    __slots__ = ("_core", "_params")

    def __init__(self, **params):
        object.__setattr__(self, "_params", params)
        object.__setattr__(self, "_core", self._make_core())

    def _make_core(self):
        raise NotImplementedError

    # immutability, value semantics, pickling
    def __setattr__(self, k, v):
        raise AttributeError(f"{type(self).__name__} is immutable; build a new model instead")

    def __getattr__(self, k):
        params = object.__getattribute__(self, "_params")
        if k in params:
            return params[k]
        raise AttributeError(f"{type(self).__name__!s} has no attribute {k!r}")

    def _key(self):
        return tuple((k, tuple(v.tolist()) if isinstance(v, np.ndarray) else v) for k, v in self._params.items())

    def __eq__(self, other):
        return type(self) is type(other) and self._key() == other._key()

    def __hash__(self):
        return hash((type(self).__name__, self._key()))

    def __repr__(self):
        def fmt(v):
            if isinstance(v, np.ndarray):
                return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
            if isinstance(v, float):
                return f"{v:.6g}"
            return repr(v)
        args = ", ".join(f"{k}={fmt(v)}" for k, v in self._params.items())
        return f"{type(self).__name__}({args})"

    def __reduce__(self):
        return (_rebuild, (type(self), dict(self._params)))

    @property
    def flags(self) -> BxDFFlags:
        """The lobes this model has (``BxDFFlags``)."""
        return BxDFFlags(self._core.flags)

    # array API
    def eval(self, wo, wi, mode=TransportMode.Radiance, out=None) -> np.ndarray:
        """BSDF value f(wo, wi), cosine excluded, per RGB channel: shape (..., 3).

        Specular (delta) lobes evaluate to 0 for every given pair, as in pbrt-v4; use
        ``sample`` to reach them.
        """
        fp = fast_pair(wo, wi) if out is None else None
        if fp is not None:  # the common case, without the general path's fixed cost
            o, i, batch, dtype = fp
            out = np.empty(batch + (3,), dtype)
            if out.size:
                bo, bi = self._core.eval(o, i, 0 if mode is _RADIANCE else _mode(mode), out.reshape(-1, 3))
                if bo or bi:
                    _raise_bad("wo", bo)
                    _raise_bad("wi", bi)
            return out
        wo, wi = as_dirs(wo, "wo"), as_dirs(wi, "wi")
        dtype = kernel_dtype(wo, wi)
        batch = broadcast_batch(("wo", "wi"), wo.shape[:-1], wi.shape[:-1])
        out = check_out(out, batch + (3,), dtype)
        if out.size:
            bo, bi = self._core.eval(flatten_to(wo, batch, (3,), dtype), flatten_to(wi, batch, (3,), dtype),
                                     _mode(mode), out.reshape(-1, 3))
            _raise_bad("wo", bo)
            _raise_bad("wi", bi)
        return out

    def pdf(self, wo, wi, mode=TransportMode.Radiance, sample_flags=ReflTrans.All, out=None) -> np.ndarray:
        """Solid-angle density of ``sample`` producing wi from wo: shape (...). 0 for delta lobes."""
        fp = fast_pair(wo, wi) if out is None else None
        if fp is not None:  # the common case, without the general path's fixed cost
            o, i, batch, dtype = fp
            out = np.empty(batch, dtype)
            if out.size:
                bo, bi = self._core.pdf(o, i, 0 if mode is _RADIANCE else _mode(mode),
                                        3 if sample_flags is _ALL else _sflags(sample_flags), out.reshape(-1))
                if bo or bi:
                    _raise_bad("wo", bo)
                    _raise_bad("wi", bi)
            return out
        wo, wi = as_dirs(wo, "wo"), as_dirs(wi, "wi")
        dtype = kernel_dtype(wo, wi)
        batch = broadcast_batch(("wo", "wi"), wo.shape[:-1], wi.shape[:-1])
        out = check_out(out, batch, dtype)
        if out.size:
            bo, bi = self._core.pdf(flatten_to(wo, batch, (3,), dtype), flatten_to(wi, batch, (3,), dtype),
                                    _mode(mode), _sflags(sample_flags), out.reshape(-1))
            _raise_bad("wo", bo)
            _raise_bad("wi", bi)
        return out

    def sample(self, wo, uc=None, u=None, *, n=None, seed=None, mode=TransportMode.Radiance,
               sample_flags=ReflTrans.All) -> SampleResult:
        """Importance-sample wi given wo.

        Either pass the uniforms ``uc`` (...) (lobe choice) and ``u`` (..., 2) (direction), in
        [0, 1], or pass ``n`` (number of samples) and an optional integer ``seed``; then uniforms
        come from ``numpy.random.default_rng(seed)`` and the batch shape is broadcast(wo, (n,)).
        """
        fs = fast_sample_args(wo, uc, u) if n is None and uc is not None and u is not None else None
        if fs is not None:  # the common case, without the general path's fixed cost
            o, ucf, uf, batch, dtype = fs
            res = _new_sample_result(batch, dtype)
            if res.pdf.size:
                bo = self._core.sample(o, ucf, uf, 0 if mode is _RADIANCE else _mode(mode),
                                       3 if sample_flags is _ALL else _sflags(sample_flags),
                                       res.wi.reshape(-1, 3), res.f.reshape(-1, 3), res.pdf.reshape(-1),
                                       res.flags.reshape(-1), res.eta.reshape(-1), res.valid.reshape(-1),
                                       res.pdf_is_proportional.reshape(-1))
                _raise_bad("wo", bo)
            return res
        wo = as_dirs(wo, "wo")
        if n is not None:
            if uc is not None or u is not None:
                raise ValueError("n: give either n (and seed) or the uniforms uc and u, not both")
            n = check_int(n, "n", 0)
            batch = broadcast_batch(("wo", "n"), wo.shape[:-1], (n,))
            dtype = kernel_dtype(wo)
            if isinstance(seed, numbers.Integral) and not isinstance(seed, bool) and seed < 0:
                raise ValueError(f"seed: must be >= 0 (or None), got {seed}")
            try:
                rng = np.random.default_rng(seed)
            except (TypeError, ValueError) as e:
                raise type(e)(f"seed: {e}") from None
            uc = rng.random(batch, dtype=dtype)
            u = rng.random(batch + (2,), dtype=dtype)
        else:
            if uc is None or u is None:
                raise ValueError("uc, u: pass both uniforms, or n= and seed=")
            uc, u = as_uniform(uc, "uc", ()), as_uniform(u, "u", (2,))
            dtype = kernel_dtype(wo, uc, u)
            batch = broadcast_batch(("wo", "uc", "u"), wo.shape[:-1], uc.shape, u.shape[:-1])
        res = _new_sample_result(batch, dtype)
        if res.pdf.size:
            ucf = np.ascontiguousarray(np.broadcast_to(uc, batch), dtype=dtype).reshape(-1)
            uf = np.ascontiguousarray(np.broadcast_to(u, batch + (2,)), dtype=dtype).reshape(-1, 2)
            bo = self._core.sample(flatten_to(wo, batch, (3,), dtype), ucf, uf, _mode(mode), _sflags(sample_flags),
                                   res.wi.reshape(-1, 3), res.f.reshape(-1, 3), res.pdf.reshape(-1),
                                   res.flags.reshape(-1), res.eta.reshape(-1), res.valid.reshape(-1),
                                   res.pdf_is_proportional.reshape(-1))
            _raise_bad("wo", bo)
        return res

    def albedo(self, wo, n_samples: int = 65536, seed: int = 0, mode=TransportMode.Radiance) -> np.ndarray:
        """Directional albedo rho(wo) = integral of f |cos wi| dwi, per channel: shape (..., 3).

        Monte Carlo with ``n_samples`` importance samples per direction (pbrt-v4 ``rho``);
        deterministic for a given seed and independent of the thread count. The standard error
        falls as 1/sqrt(n_samples).
        """
        wo = as_dirs(wo, "wo")
        n_samples = check_int(n_samples, "n_samples", 1)
        seed = check_int(seed, "seed", 0)
        fd = fast_dirs(wo)
        rows, batch, dtype = fd if fd is not None else (None, wo.shape[:-1], kernel_dtype(wo))
        out = np.empty(batch + (3,), dtype)
        if out.size:
            if rows is None:
                rows = np.ascontiguousarray(wo, dtype=dtype).reshape(-1, 3)
            bo = self._core.albedo(rows, n_samples,
                                   seed & 0xFFFFFFFFFFFFFFFF, _mode(mode), out.reshape(-1, 3))
            _raise_bad("wo", bo)
        return out


def _rebuild(cls, params):
    return cls._from_params(params)


# ---------------------------------------------------------------- models

class Diffuse(BxDF):
    """Lambertian reflection, f = reflectance / pi on wo's side (pbrt-v4 ``DiffuseBxDF``).

    reflectance: scalar or RGB in [0, 1]. Two-sided.
    """

    __slots__ = ()

    def __init__(self, reflectance=0.5):
        super().__init__(reflectance=_rgb(reflectance, "reflectance", lo=0.0, hi=1.0))

    @classmethod
    def _from_params(cls, p):
        return cls(p["reflectance"])

    def _make_core(self):
        return _core.Diffuse(self._params["reflectance"].tolist())


class DiffuseTransmission(BxDF):
    """Lambertian reflection plus Lambertian transmission (pbrt-v4 ``DiffuseTransmissionBxDF``).

    f = reflectance / pi on wo's side, transmittance / pi across the surface. Each RGB in [0, 1].
    Lobes are sampled in proportion to their largest channel.
    """

    __slots__ = ()

    def __init__(self, reflectance=0.25, transmittance=0.25):
        super().__init__(reflectance=_rgb(reflectance, "reflectance", lo=0.0, hi=1.0),
                         transmittance=_rgb(transmittance, "transmittance", lo=0.0, hi=1.0))

    @classmethod
    def _from_params(cls, p):
        return cls(p["reflectance"], p["transmittance"])

    def _make_core(self):
        return _core.DiffuseTransmission(self._params["reflectance"].tolist(), self._params["transmittance"].tolist())


# RGB eta / k of common metals: Mitsuba 3's RGB projection (CIE 1931 -> linear sRGB, no D65
# weighting) of the measured spectral IOR data shipped in mitsuba-data/ior (Palik et al.
# "Handbook of Optical Constants of Solids"). Checked against Mitsuba at test time.
METALS = {
    "Cu": ((0.201006, 0.923749, 1.102215), (3.913262, 2.453045, 2.142090)),
    "Au": ((0.143036, 0.375307, 1.442045), (3.982997, 2.385556, 1.603359)),
    "Ag": ((0.155276, 0.116728, 0.138388), (4.828355, 3.122222, 2.146901)),
    "Al": ((1.657501, 0.880405, 0.521244), (9.223811, 6.269502, 4.837004)),
    "Cr": ((4.369668, 2.916505, 1.654905), (5.206547, 4.231306, 3.754699)),
}


class Conductor(BxDF):
    """Metal: perfect mirror or anisotropic Trowbridge-Reitz (GGX) microfacet reflection with a
    conductor Fresnel term (pbrt-v4 ``ConductorBxDF``; the complex Fresnel term by default).

    eta, k: real and imaginary IOR per RGB channel (eta > 0, k >= 0).
    alpha: GGX roughness (alpha, not pbrt's remapped "roughness"); alpha_x / alpha_y override it
    per tangent axis (local x / y). max(alpha_x, alpha_y) < 1e-3 makes the lobe a delta mirror
    (pbrt-v4 ``EffectivelySmooth``); otherwise each alpha is floored at 1e-4.
    masking: "correlated" (height-correlated Smith, pbrt-v4) or "separable" (G1 G1, Mitsuba 3).
    fresnel: the Fresnel term F(cos), cos = |wo . wm|, from most accurate to cheapest-ish:

    * ``"exact"`` (default): the complex Fresnel reflectance of eta + i k, unpolarised
      (pbrt-v4 ``FrComplex``).
    * ``"schlick"``: Schlick 1994, F = F0 + (1 - F0)(1 - cos)^5 with the exact normal-incidence
      reflectance F0 = ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2). Exact at 0 deg and (F = 1) at
      90 deg, but a metal's reflectance dips below F0 and changes tint near grazing
      (about 60-85 deg); Schlick rises monotonically to 1 and misses both (measured max abs
      error over ``METALS``: 0.026 for Cu, up to 0.27 for Cr).
    * ``"f82"``: F82-tint (Hoffman 2019, "Fresnel Equations Considered Harmful"; Kutz et al. 2021,
      Adobe Standard Material): Schlick minus a cos (1 - cos)^6, with a per channel chosen so
      that F equals the exact value at cos = 1/7 (~81.8 deg). Exact at 0, ~82 and 90 deg and
      follows the grazing dip (measured max abs error: 0.008 for Cu, up to 0.06 for Cr).
      Clamped to [0, 1], which only matters away from metals (e.g. eta ~ 1 with small k, where
      neither approximation is meaningful).

    F0 and a are precomputed per channel (in double) at construction, so the approximations
    cost a polynomial per direction. Sampling (visible normals) and the pdf do not depend on
    the Fresnel term. See ``bsdfkit.conductor_fresnel`` for F(cos) alone.
    Two-sided; symmetric in wo and wi.
    """

    __slots__ = ()

    def __init__(self, eta, k, alpha=0.0, alpha_x=None, alpha_y=None, masking="correlated", fresnel="exact"):
        ax, ay = _alphas(alpha, alpha_x, alpha_y)
        super().__init__(eta=_rgb(eta, "eta", lo=0.0, lo_open=True), k=_rgb(k, "k", lo=0.0),
                         alpha_x=ax, alpha_y=ay, masking=_masking(masking), fresnel=_fresnel(fresnel))

    @classmethod
    def _from_params(cls, p):
        return cls(p["eta"], p["k"], alpha_x=p["alpha_x"], alpha_y=p["alpha_y"], masking=p["masking"],
                   fresnel=p.get("fresnel", "exact"))

    @classmethod
    def from_metal(cls, name: str, roughness=None, *, alpha=None, alpha_x=None, alpha_y=None,
                   masking="correlated", fresnel="exact") -> "Conductor":
        """A measured metal by name (see ``bsdfkit.METALS``: Cu, Au, Ag, Al, Cr).

        Roughness as pbrt-v4's ``roughness`` (alpha = sqrt(roughness)) or directly as ``alpha``.
        ``fresnel`` as in ``Conductor``.
        """
        if name not in METALS:
            raise ValueError(f"name: unknown metal {name!r}; known metals: {', '.join(sorted(METALS))}")
        eta, k = METALS[name]
        return cls(eta, k, alpha=_pick_alpha(roughness, alpha), alpha_x=alpha_x, alpha_y=alpha_y, masking=masking,
                   fresnel=fresnel)

    @classmethod
    def from_reflectance(cls, reflectance, roughness=None, *, alpha=None, alpha_x=None, alpha_y=None,
                         masking="correlated", fresnel="exact") -> "Conductor":
        """pbrt-v4's artist form: eta = 1 and k = 2 sqrt(r) / sqrt(1 - r), so that the Fresnel
        reflectance at normal incidence equals r. r in [0, 1], clamped to 0.9999 (pbrt-v4 does
        the same: r = 1 would need k = inf). ``fresnel`` as in ``Conductor``."""
        r = np.minimum(_rgb(reflectance, "reflectance", lo=0.0, hi=1.0), 0.9999)
        k = 2 * np.sqrt(r) / np.sqrt(1 - r)
        return cls(1.0, k, alpha=_pick_alpha(roughness, alpha), alpha_x=alpha_x, alpha_y=alpha_y, masking=masking,
                   fresnel=fresnel)

    def _make_core(self):
        p = self._params
        core_cls = getattr(_core, _FRESNEL[p["fresnel"]][0])
        return core_cls(p["eta"].tolist(), p["k"].tolist(), p["alpha_x"], p["alpha_y"], _MASKING[p["masking"]])


def conductor_fresnel(cos_theta, eta, k, fresnel="exact") -> np.ndarray:
    """Conductor Fresnel reflectance F(cos_theta) of eta + i k, as ``Conductor(..., fresnel=)``
    uses it: float64 array of shape ``cos_theta.shape + (3,)``.

    cos_theta: cosine(s) of the angle of incidence, clamped to [0, 1]; eta (> 0), k (>= 0):
    scalar or RGB; fresnel: "exact", "schlick" or "f82" (see ``Conductor``). Computed by the
    same C++ code as the models, in double precision.
    """
    c = np.asarray(cos_theta)
    if c.dtype.kind not in "fiu":
        raise TypeError(f"cos_theta: expected real numbers, got dtype {c.dtype}")
    c = c.astype(np.float64)
    if np.any(np.isnan(c)):
        raise ValueError("cos_theta: must not be NaN")
    e, kk = _rgb(eta, "eta", lo=0.0, lo_open=True), _rgb(k, "k", lo=0.0)
    out = _core.conductor_fresnel(np.ascontiguousarray(c.reshape(-1)), e.tolist(), kk.tolist(),
                                  _FRESNEL[_fresnel(fresnel)][1])
    # rounding can leave the exact term a few ulps below 0 (eta ~ 1, k ~ 0); the models' BSDF
    # wrapper zeroes such values too
    np.maximum(out, 0.0, out=out)
    return out.reshape(c.shape + (3,))


def _pick_alpha(roughness, alpha) -> float:
    if roughness is not None and alpha is not None:
        raise ValueError("roughness, alpha: give one of them, not both")
    if roughness is not None:
        return roughness_to_alpha(_scalar(roughness, "roughness", lo=0.0))
    return 0.0 if alpha is None else alpha


class Dielectric(BxDF):
    """Glass-like interface: Fresnel-weighted reflection and refraction, smooth (delta) or
    anisotropic Trowbridge-Reitz rough (pbrt-v4 ``DielectricBxDF``).

    eta: relative IOR, inside over outside (> 0; < 1 when the outside is denser; 1 passes light
    straight through). wo may be on either side. alpha / alpha_x / alpha_y / masking as in
    ``Conductor``. In Radiance mode transmitted values are divided by eta'^2.
    """

    __slots__ = ()

    def __init__(self, eta=1.5, alpha=0.0, alpha_x=None, alpha_y=None, masking="correlated"):
        ax, ay = _alphas(alpha, alpha_x, alpha_y)
        super().__init__(eta=_scalar(eta, "eta", lo=0.0, lo_open=True), alpha_x=ax, alpha_y=ay,
                         masking=_masking(masking))

    @classmethod
    def _from_params(cls, p):
        return cls(p["eta"], alpha_x=p["alpha_x"], alpha_y=p["alpha_y"], masking=p["masking"])

    def _make_core(self):
        p = self._params
        return _core.Dielectric(p["eta"], p["alpha_x"], p["alpha_y"], _MASKING[p["masking"]])


class ThinDielectric(BxDF):
    """Thin slab of dielectric (a window pane): specular reflection and straight-through
    transmission, with the inter-reflections inside the slab summed (pbrt-v4 ``ThinDielectricBxDF``).

    eta: IOR of the slab (> 0). Both lobes are deltas; ``eval`` and ``pdf`` are 0.
    """

    __slots__ = ()

    def __init__(self, eta=1.5):
        super().__init__(eta=_scalar(eta, "eta", lo=0.0, lo_open=True))

    @classmethod
    def _from_params(cls, p):
        return cls(p["eta"])

    def _make_core(self):
        return _core.ThinDielectric(self._params["eta"])
