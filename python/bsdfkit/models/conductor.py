"""Metals: pbrt-v4's ConductorBxDF with exact, Schlick or F82-tint Fresnel; measured metal IORs."""
from __future__ import annotations

import numpy as np

from .. import _core
from . import _spectral as _sp
from .base import (MIN_ALPHA, BxDF, _alphas, _distribution, _masking, _pick_alpha, _rgb, _sample_visible, alpha_text,
                   core_value, distribution_knob, fmt_value, is_smooth, masking_knob, microfacet_kw, rgb_dict)
from . import _mitsuba_export as _me
from .registry import KnobDecl

__all__ = ["METALS", "Conductor", "conductor_fresnel", "spectral_metals"]

from ..spectral.spectrum import Spectrum  # noqa: E402


# Conductor Fresnel knob -> (_core class, conductor_fresnel code), most accurate first.
_FRESNEL = {"exact": ("Conductor", 0), "schlick": ("ConductorSchlick", 1), "f82": ("ConductorF82", 2)}


def _fresnel(f) -> str:
    if not isinstance(f, str) or f not in _FRESNEL:
        raise ValueError(f"fresnel: must be one of {list(_FRESNEL)}, got {f!r}")
    return f


# RGB eta / k of common metals: Mitsuba 3's RGB projection (CIE 1931 -> linear sRGB, no D65
# weighting) of the measured spectral IOR data shipped in mitsuba-data/ior (Palik et al.
# "Handbook of Optical Constants of Solids"). Checked against Mitsuba at test time. These are the
# presets from_mitsuba accepts by name; every named metal (spectral_metals(): 18, pbrt-v4's,
# Mitsuba's and Johnson & Christy's, from the one table of Spectrum.named) is accepted by
# Conductor.from_metal and, as pbrt's metal-<X>-eta / -k, by from_pbrt.
METALS = {
    "Cu": ((0.201006, 0.923749, 1.102215), (3.913262, 2.453045, 2.142090)),
    "Au": ((0.143036, 0.375307, 1.442045), (3.982997, 2.385556, 1.603359)),
    "Ag": ((0.155276, 0.116728, 0.138388), (4.828355, 3.122222, 2.146901)),
    "Al": ((1.657501, 0.880405, 0.521244), (9.223811, 6.269502, 4.837004)),
    "Cr": ((4.369668, 2.916505, 1.654905), (5.206547, 4.231306, 3.754699)),
}


class Conductor(BxDF):
    """Metal: perfect mirror or anisotropic Trowbridge-Reitz (GGX) or Beckmann microfacet reflection
    with a conductor Fresnel term (pbrt-v4 ``ConductorBxDF``; the complex Fresnel term by default).

    Spectral mode (``wavelengths=``): RGB eta / k are uplifted as unbounded spectra (pbrt-v4
    ``RGBUnboundedSpectrum``); RGB mode: spectra are projected without an illuminant, as Mitsuba 3
    projects its IOR presets (``METALS`` is that projection of the Mitsuba spectra).
    max(alpha_x, alpha_y) < 1e-3 makes the lobe a delta mirror (pbrt-v4 ``EffectivelySmooth``);
    otherwise each alpha is floored at 1e-4.

    The Fresnel term F(cos), cos = |wo . wm|, from most accurate to cheapest-ish:

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

    Parameters
    ----------
    eta, k : RGB or Spectrum
        Real and imaginary IOR per RGB channel (eta > 0, k >= 0), or each a ``bsdfkit.Spectrum``
        (e.g. ``Spectrum.named("metal-Au-eta")``; ``from_metal(name, spectral=True)``).
    alpha : float, optional
        GGX roughness (alpha, not pbrt's remapped "roughness"), isotropic; none: a mirror.
    alpha_x, alpha_y : float, optional
        Given together instead of ``alpha``: per tangent axis (local x / y). One of them alone,
        or alpha with them, is a ValueError.
    masking : {"correlated", "separable"}, optional
        Height-correlated Smith (pbrt-v4; default) or G1 G1 (Mitsuba 3).
    fresnel : {"exact", "schlick", "f82"}, optional
        The Fresnel term (above); default "exact".
    distribution : {"ggx", "beckmann"}, optional
        The microfacet distribution: Trowbridge-Reitz / GGX (pbrt-v4; default) or Beckmann
        (Mitsuba 3's default; its Smith Lambda by Walter et al. 2007's rational fit, as Mitsuba
        and pbrt-v3). A modelling choice: the two are different materials at the same alpha.
    sample_visible : bool, optional
        Sample visible normals (default; Heitz & d'Eon 2014, and Jakob 2014 for Beckmann) or
        D(wm) cos(wm) (Mitsuba 3's ``sample_visible=False``). f is the same either way; the pdf
        and the samples differ.

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m = bk.Conductor([0.2, 0.92, 1.1], [3.9, 2.45, 2.14], alpha=0.2)
    >>> m == bk.Conductor(m.eta, m.k, alpha_x=0.2, alpha_y=0.2)
    True
    >>> bk.Conductor.from_metal("Au", roughness=0.04).alpha_x   # alpha = sqrt(roughness)
    0.2
    """

    __slots__ = ()

    aliases = ("metal",)
    description = "Metal: mirror, GGX or Beckmann microfacet reflection (pbrt-v4 ConductorBxDF)"
    examples = {
        "copper, alpha 0.2": "conductor metal=Cu alpha=0.2",
        "gold mirror": "conductor metal=Au",
        "aluminium, anisotropic": "conductor metal=Al alpha_x=0.4 alpha_y=0.1",
        "anisotropic, explicit eta and k": "conductor eta=0.2,0.9,1.1 k=3.9,2.4,2.1 alpha_x=0.4 alpha_y=0.08",
        "aluminium, separable masking": "conductor metal=Al alpha=0.5 masking=separable",
        "copper mirror, Schlick": "conductor metal=Cu fresnel=schlick",
        "chromium, Schlick": "conductor metal=Cr alpha=0.3 fresnel=schlick",
        "gold, F82, rough": "conductor metal=Au alpha=0.3 fresnel=f82",
        "aluminium, F82, separable": "conductor metal=Al alpha=0.5 masking=separable fresnel=f82",
        "gold, Beckmann": "conductor metal=Au alpha=0.3 distribution=beckmann",
        "aluminium, anisotropic Beckmann, separable": "conductor metal=Al alpha_x=0.5 alpha_y=0.15 "
                                                        "distribution=beckmann masking=separable",
    }
    energy_conserving, exact_eval, two_sided, transmission, delta_only = True, True, True, False, False
    reciprocal = True
    mitsuba = "roughconductor"
    # fitting bounds (bk.fit): the validated ranges, alphas kept in the rough regime (>= 1e-3)
    param_ranges = {"eta": (1e-3, 10.0), "k": (0.0, 20.0), "alpha_x": (1e-3, 2.0), "alpha_y": (1e-3, 2.0)}
    varying_params = {"eta": 3, "k": 3, "alpha_x": 1, "alpha_y": 1}
    knobs = (
        KnobDecl("fresnel", ("exact", "f82", "schlick"), "approximation",
                 "conductor Fresnel: complex (exact), F82-tint, Schlick"),
        masking_knob(lambda q: "smooth conductor (max alpha < 1e-3): a mirror has no masking" if is_smooth(q) else None),
        distribution_knob(lambda q: "smooth conductor (max alpha < 1e-3): a mirror has no microfacets"
                          if is_smooth(q) else None),
    )

    def __init__(self, eta, k, alpha=None, alpha_x=None, alpha_y=None, masking="correlated", fresnel="exact",
                 distribution="ggx", sample_visible=True):
        """A Conductor: the parameters are described in the class docstring (``help(bsdfkit.Conductor)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        ax, ay = _alphas(alpha, alpha_x, alpha_y, varying=True)
        super().__init__(eta=_sp.spectrum_or_rgb(eta, "eta", lo=0.0, lo_open=True, varying=True),
                         k=_sp.spectrum_or_rgb(k, "k", lo=0.0, varying=True),
                         alpha_x=ax, alpha_y=ay, masking=_masking(masking), fresnel=_fresnel(fresnel),
                         distribution=_distribution(distribution), sample_visible=_sample_visible(sample_visible))

    @classmethod
    def _from_params(cls, p):
        return cls(p["eta"], p["k"], alpha_x=p["alpha_x"], alpha_y=p["alpha_y"], masking=p["masking"],
                   fresnel=p.get("fresnel", "exact"), distribution=p.get("distribution", "ggx"),
                   sample_visible=p.get("sample_visible", True))

    @classmethod
    def from_metal(cls, name: str, roughness=None, *, alpha=None, alpha_x=None, alpha_y=None,
                   masking="correlated", fresnel="exact", distribution="ggx", sample_visible=True,
                   spectral: bool = False) -> "Conductor":
        """A measured metal by name: ``bsdfkit.METALS`` (Cu, Au, Ag, Al, Cr) or any name of
        ``spectral_metals()`` (also Be, CuZn, Fe, Ir, MgO, Mo, Ni_palik, Rh, Ta, Ti, TiN, TiO2, W).

        Roughness as pbrt-v4's ``roughness`` (alpha = sqrt(roughness)) or directly as ``alpha``.
        ``fresnel``, ``distribution`` and ``sample_visible`` as in ``Conductor``. ``spectral=True``: eta and k are the measured spectra
        (``bsdfkit.Spectrum``): Mitsuba 3's IOR data (``mitsuba-<name>-eta/k``, the data ``METALS``
        projects) where Mitsuba has the metal, else pbrt-v4's (``metal-<name>-eta/k``: CuZn, MgO,
        TiO2), else Johnson & Christy 1974's (``jc-<name>-eta/k``: Fe, Ti). Its RGB mode equals
        ``METALS`` within 1e-6. ``spectral=False`` with a metal outside ``METALS``: eta and k are
        those spectra projected to RGB the way ``METALS`` was made (CIE 1931 to linear sRGB, no
        illuminant weighting: ``Spectrum.to_rgb("unbounded", illuminant=None)``).
        """
        if spectral:
            names = spectral_metals()
            if name not in names:
                raise ValueError(f"name: unknown metal {name!r} for spectral=True; known: {', '.join(names)}")
            eta, k = _metal_spectra(name)
            return cls(eta, k, alpha=_pick_alpha(roughness, alpha), alpha_x=alpha_x, alpha_y=alpha_y,
                       masking=masking, fresnel=fresnel, distribution=distribution,
                   sample_visible=sample_visible)
        if name in METALS:
            eta, k = METALS[name]
        elif isinstance(name, str) and name in spectral_metals():
            eta, k = (tuple(float(v) for v in s.to_rgb("unbounded", illuminant=None)) for s in _metal_spectra(name))
        else:
            known = sorted(set(METALS) | set(spectral_metals()))
            raise ValueError(f"name: unknown metal {name!r}; known metals: {', '.join(known)}")
        return cls(eta, k, alpha=_pick_alpha(roughness, alpha), alpha_x=alpha_x, alpha_y=alpha_y, masking=masking,
                   fresnel=fresnel, distribution=distribution,
                   sample_visible=sample_visible)

    @classmethod
    def from_reflectance(cls, reflectance, roughness=None, *, alpha=None, alpha_x=None, alpha_y=None,
                         masking="correlated", fresnel="exact", distribution="ggx", sample_visible=True,
                   spectral: bool = False) -> "Conductor":
        """pbrt-v4's artist form: eta = 1 and k = 2 sqrt(r) / sqrt(1 - r), so that the Fresnel
        reflectance at normal incidence equals r. r in [0, 1], clamped to 0.9999 (pbrt-v4 does
        the same: r = 1 would need k = inf). ``fresnel``, ``distribution`` and ``sample_visible``
        as in ``Conductor``.

        Per wavelength, as pbrt-v4 (``spectral=True``, or ``reflectance`` a ``bsdfkit.Spectrum``):
        r(lambda) is the spectrum (an RGB r uplifted as a bounded reflectance) and k(lambda) =
        2 sqrt(r) / sqrt(1 - r) at every nm of [360, 830] (a sampled spectrum, linear in between).
        Otherwise k is computed per RGB channel (and uplifted as unbounded in spectral mode)."""
        if spectral or isinstance(reflectance, Spectrum):
            rs = reflectance if isinstance(reflectance, Spectrum) else Spectrum.from_rgb(
                _rgb(reflectance, "reflectance", lo=0.0, hi=1.0), "reflectance")
            _sp.spectrum_or_rgb(rs, "reflectance", lo=0.0, hi=1.0)
            r = np.minimum(rs(_sp.DENSE_WAVELENGTHS), 0.9999)
            k = Spectrum(_sp.DENSE_WAVELENGTHS, 2 * np.sqrt(r) / np.sqrt(1 - r))
            return cls(Spectrum.constant(1.0), k, alpha=_pick_alpha(roughness, alpha), alpha_x=alpha_x,
                       alpha_y=alpha_y, masking=masking, fresnel=fresnel, distribution=distribution,
                   sample_visible=sample_visible)
        r = np.minimum(_rgb(reflectance, "reflectance", lo=0.0, hi=1.0), 0.9999)
        k = 2 * np.sqrt(r) / np.sqrt(1 - r)
        return cls(1.0, k, alpha=_pick_alpha(roughness, alpha), alpha_x=alpha_x, alpha_y=alpha_y, masking=masking,
                   fresnel=fresnel, distribution=distribution,
                   sample_visible=sample_visible)

    def _make_core(self):
        p = self._params
        core_cls = getattr(_core, _FRESNEL[p["fresnel"]][0])
        return core_cls(eta=core_value(_sp.rgb_of(p["eta"], "unbounded")), k=core_value(_sp.rgb_of(p["k"], "unbounded")),
                        alpha_x=p["alpha_x"], alpha_y=p["alpha_y"], **microfacet_kw(p))

    def cost_family(self) -> str:
        return "Conductor" + ("/smooth" if is_smooth(self._params) else "/rough")

    def describe(self) -> str:
        p = self._params
        if isinstance(p["eta"], Spectrum) or isinstance(p["k"], Spectrum):
            en = p["eta"].name if isinstance(p["eta"], Spectrum) else None
            if en is not None and en.endswith("-eta") and getattr(p["k"], "name", None) == en[:-4] + "-k":
                name = en.split("-")[1] + " (spectral)"
            else:
                name = f"η={_sp.fmt_param(p['eta'])}, k={_sp.fmt_param(p['k'])}"
            return f"Conductor {name}{alpha_text(p)}"
        name = next((n for n, (eta, k) in METALS.items()
                     if np.allclose(p["eta"], eta) and np.allclose(p["k"], k)), None)
        if name is None:
            name = f"η={fmt_value(p['eta'])}, k={fmt_value(p['k'])}"
        return f"Conductor {name}{alpha_text(p)}"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """The Mitsuba 3 plugin dictionary of this material: ``twosided{conductor}`` if smooth, else
        ``twosided{roughconductor}`` (the distribution and ``sample_visible`` as the model's,
        alpha_u = alpha_x on local x).

        Exported only when it is the same material. Mitsuba's ``roughconductor`` has the separable
        Smith masking G1(wo) G1(wi) and only the exact Fresnel term, so a rough model with
        ``masking="correlated"`` (the default, pbrt-v4's) or a ``fresnel`` other than ``"exact"``
        raises ``MitsubaExportError`` (a NotImplementedError and a ValueError) naming the reason
        and the measured difference. ``approximate=True`` exports the nearest Mitsuba material
        (separable masking, exact Fresnel) and warns with ``MitsubaApproximationWarning``, stating
        the difference measured between this model and the exported one (for Au, alpha = 0.3,
        correlated: f up to ~70 % apart at grazing angles). A mirror has no masking: smooth models
        export exactly with either masking.
        """
        self._refuse_varying("to_mitsuba")
        approximate = _me.check_approximate(approximate)
        p = self._params
        eta, k = _sp.rgb_of(self.eta, "unbounded"), _sp.rgb_of(self.k, "unbounded")
        reasons = []
        if is_smooth(p):
            inner = {"type": "conductor", "eta": rgb_dict(eta), "k": rgb_dict(k)}
        else:
            inner = {"type": "roughconductor", "distribution": p["distribution"],
                     "alpha_u": max(p["alpha_x"], MIN_ALPHA), "alpha_v": max(p["alpha_y"], MIN_ALPHA),
                     "sample_visible": p["sample_visible"],
                     "eta": rgb_dict(eta), "k": rgb_dict(k)}
            if p["masking"] != "separable":
                reasons.append(_me.MASKING_REASON.format(plugin="roughconductor"))
        if p["fresnel"] != "exact":
            reasons.append(f"fresnel={p['fresnel']!r}: Mitsuba 3's conductors only have the exact complex "
                           f"Fresnel term (the reference for this one is "
                           f"bsdfkit.testing.drjit_models.conductor_f(..., fresnel={p['fresnel']!r}))")
        d = {"type": "twosided", "bsdf": inner}
        if reasons:
            from ..interop.mitsuba import from_mitsuba
            _me.refuse_or_warn(self, from_mitsuba(d), reasons, approximate)
        return d


#: Where ``from_metal(..., spectral=True)`` takes a metal's eta / k spectra, first match wins.
_METAL_SOURCES = ("mitsuba", "metal", "jc")


def spectral_metals() -> tuple:
    """The names ``Conductor.from_metal(name, spectral=True)`` accepts (Mitsuba 3's, pbrt-v4's and
    Johnson & Christy's measured metals, ``bsdfkit.Spectrum.names()``)."""
    out = []
    for n in Spectrum.names():
        parts = n.split("-")
        if len(parts) == 3 and parts[0] in _METAL_SOURCES and parts[2] == "eta" and parts[1] not in out:
            out.append(parts[1])
    return tuple(sorted(out))


def _metal_spectra(name: str):
    """(eta, k) named spectra of a metal of ``spectral_metals()`` from its first source."""
    names = Spectrum.names()
    src = next(s for s in _METAL_SOURCES if f"{s}-{name}-eta" in names)
    return Spectrum.named(f"{src}-{name}-eta"), Spectrum.named(f"{src}-{name}-k")


#: The values of ``Conductor.from_metal``'s first argument (listed by the spec parser's usage text).
Conductor.from_metal.__func__.choices = tuple(METALS) + tuple(m for m in spectral_metals() if m not in METALS)


def conductor_fresnel(cos_theta, eta, k, fresnel="exact") -> np.ndarray:
    """Conductor Fresnel reflectance F(cos_theta) of eta + i k, as ``Conductor(..., fresnel=)``
    uses it: float64 array of shape ``cos_theta.shape + (3,)``.

    Computed by the same C++ code as the models, in double precision.

    Parameters
    ----------
    cos_theta : float or array_like
        Cosine(s) of the angle of incidence, clamped to [0, 1].
    eta, k : float or RGB
        Real (> 0) and imaginary (>= 0) IOR.
    fresnel : {"exact", "schlick", "f82"}, optional
        The approximation (see ``Conductor``).

    Returns
    -------
    numpy.ndarray, shape cos_theta.shape + (3,)
        F per RGB channel, float64.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> F = bk.conductor_fresnel([1.0, 0.0], *bk.METALS["Au"])
    >>> F.shape, bool((F[1] == 1).all())   # F = 1 at grazing incidence
    ((2, 3), True)
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
