"""Principled: Mitsuba 3's ``principled`` BSDF (the Disney BSDF of Burley 2012 / 2015)."""
from __future__ import annotations

import math

import numpy as np

from .. import _core
from ._mitsuba_export import check_approximate as _check_approximate
from .base import BxDF, _rgb, _scalar, core_value, fmt_param, rgb_dict

__all__ = ["Principled", "PrincipledThin", "specular_to_eta"]

#: The weights in [0, 1] of the model, in constructor order (each may be a per-element array).
_WEIGHTS = ("roughness", "anisotropic", "metallic", "spec_trans", "spec_tint", "sheen", "sheen_tint",
            "flatness", "clearcoat", "clearcoat_gloss")
#: Mitsuba's sampling rates (keyword-only, uniform): they change the sampler and pdf, never f.
_RATES = ("main_specular_sampling_rate", "clearcoat_sampling_rate", "diffuse_reflectance_sampling_rate")


def specular_to_eta(specular: float) -> float:
    """Mitsuba 3's ``specular`` -> ``eta`` rule of ``principled``: ``eta = 2 / (1 - sqrt(0.08
    specular)) - 1``, the IOR whose normal-incidence reflectance ((eta - 1) / (eta + 1))^2 is
    ``0.08 specular`` (Burley 2012: specular 0.5 is 4 %, eta 1.5).

    Examples
    --------
    >>> from bsdfkit.models.principled import specular_to_eta
    >>> round(specular_to_eta(0.5), 12)
    1.5
    """
    s = _scalar(specular, "specular", lo=0.0, hi=1.0)
    return 2.0 / (1.0 - math.sqrt(0.08 * s)) - 1.0


def _nonzero(v) -> bool:
    """Mitsuba's "has the lobe" test (principledhelpers.h get_flag): a parameter given as a
    nonzero number or as a map (a per-element array, like Mitsuba's textures)."""
    return isinstance(v, np.ndarray) and v.ndim > 0 or float(v) != 0.0



class _PrincipledFamily:
    """What Principled and PrincipledThin share: construction from their parameters, the _core
    class of the same name, no spectral mode, ``describe`` and the Mitsuba dictionary. A class
    names its ``_core_name``, its ``_weights`` (roughness first: shown and exported when nonzero)
    and its sampling ``_rates`` (exported when not 1)."""

    __slots__ = ()

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def _make_core(self):
        return getattr(_core, self._core_name)(**{k: core_value(v) for k, v in self._params.items()})

    def _no_spectral_reason(self) -> str:
        return (f"wavelengths: {type(self).__name__} has no spectral mode: its spec_tint and sheen_tint divide "
                "base_color by the colour's luminance (Mitsuba's rule), which has no per-wavelength meaning; "
                "call without wavelengths= for RGB")

    def describe(self) -> str:
        p = self._params
        if self.varying:
            return super().describe()
        parts = [f"base={fmt_param(p['base_color'])}", f"r={fmt_param(p['roughness'])}"]
        parts += [f"{k}={fmt_param(p[k])}" for k in self._weights[1:] if float(p[k]) != 0.0]
        return f"{self._core_name} " + ", ".join(parts)

    def _mitsuba_dict(self, approximate) -> dict:
        _check_approximate(approximate)
        self._refuse_varying("to_mitsuba")
        p = self._params
        d = {"type": self.mitsuba, "base_color": rgb_dict(p["base_color"]), "eta": float(p["eta"])}
        for k in self._weights:
            if float(p[k]) != 0.0 or k == "roughness":
                d[k] = float(p[k])
        for k in self._rates:
            if float(p[k]) != 1.0:
                d[k] = float(p[k])
        return d

class Principled(_PrincipledFamily, BxDF):
    """The Disney principled BSDF as Mitsuba 3 implements it (plugin ``principled``).

    One artist-friendly material over a diffuse base, a sheen, an anisotropic GGX specular lobe
    that becomes metallic or transmissive, and a clear coat (Burley 2012, "Physically Based Shading
    at Disney"; Burley 2015, "Extending the Disney BRDF to a BSDF with Integrated Subsurface
    Scattering"), with Mitsuba 3.9's formulas and parameter names, so that ``eval`` and ``pdf``
    agree with Mitsuba's ``principled`` pointwise (to float32 rounding)::

        f = (1 - m)(1 - t) base/pi lerp(f_Burley + f_retro, f_fakeSSS, flatness)    diffuse
          + sheen (1 - m) Schlick(cos_d) lerp(1, tint, sheen_tint)                   sheen
          + F_principled D G / (4 |cos_o cos_i|)                                     main specular
          + (1 - m) t sqrt(base) (1 - F) D G eta^2 |o.h i.h| / (...)                 transmission
          + 0.25 clearcoat Schlick_0.04 D_GTR1 G_0.25                                clear coat

    with m = ``metallic``, t = ``spec_trans``, D the anisotropic GGX of alphas (r^2 / a, r^2 a),
    a = sqrt(1 - 0.9 ``anisotropic``), floored at 0.001, G Smith's separable masking, tint =
    base / luminance(base), and F_principled a blend of the dielectric Fresnel, a metallic
    Schlick term of ``base_color`` and a ``spec_tint``-tinted Schlick term.

    Parameters
    ----------
    base_color : float or (3,) array_like, default 0.5
        Base colour (RGB in [0, 1]): the diffuse albedo, the metal's F0 and, square-rooted, the
        transmission tint.
    roughness : float, default 0.5
        Roughness r in [0, 1] of the main specular lobes (alpha = r^2) and of the retro-reflection.
    anisotropic : float, default 0
        Anisotropy in [0, 1] (0: isotropic); the x axis of the shading frame is the rougher one.
    metallic : float, default 0
        Metallic weight in [0, 1].
    spec_trans : float, default 0
        Specular transmission weight in [0, 1] (1: a rough dielectric without diffuse base).
    eta : float, optional
        Relative index of refraction (inside / outside), > 0. Give ``eta`` or ``specular``, not
        both (as Mitsuba).
    specular : float, optional
        Normal-incidence reflectance control in [0, 1], converted as Mitsuba converts it:
        ``eta = 2 / (1 - sqrt(0.08 specular)) - 1`` (:func:`specular_to_eta`). Default 0.5
        (eta = 1.5) when neither is given. With transmission (``spec_trans`` nonzero) Mitsuba's
        rule replaces specular 0 by 1e-3 and eta 1 by 1.001; this class does the same.
    spec_tint : float, default 0
        Fraction in [0, 1] of the dielectric reflection tinted towards the base colour.
    sheen : float, default 0
        Sheen weight in [0, 1] (a grazing retro-reflective lobe for cloth).
    sheen_tint : float, default 0
        Fraction in [0, 1] of the sheen tinted towards the base colour.
    flatness : float, default 0
        Blend in [0, 1] from the Burley diffuse to the Hanrahan-Krueger fake subsurface lobe.
    clearcoat : float, default 0
        Clear-coat weight in [0, 1].
    clearcoat_gloss : float, default 0
        Clear-coat glossiness in [0, 1]: GTR1 alpha from 0.1 (0) to 0.001 (1).
    main_specular_sampling_rate, clearcoat_sampling_rate, diffuse_reflectance_sampling_rate : float, default 1
        Mitsuba's sampling rates (>= 0, keyword-only): the relative probability of sampling each
        lobe. They change ``sample`` and ``pdf``, never ``eval``.

    Raises
    ------
    ValueError
        A parameter out of its range (the message names it), or both ``eta`` and ``specular``.

    Notes
    -----
    Conventions of Mitsuba's plugin, kept: ``wo`` below the surface (the material's inside) sees
    only the main specular reflection (weighted by ``(1 - metallic) spec_trans`` times the
    dielectric Fresnel term) and the transmission; a material without transmission is black from
    below (``f = pdf = 0``; Mitsuba's ``pdf`` there is the specular lobe's density, though its
    sampler returns nothing). Not energy conserving (the sheen, the clear coat and the
    retro-reflection add energy) and not reciprocal in its pdf. Sampling chooses a lobe with
    Mitsuba's probabilities (which depend on the sampling rates) and samples the cosine
    hemisphere, GTR1 normals or visible GGX normals; ``pdf`` is the mixture's density (exact, so
    ``sample``'s weights are ``f cos / pdf``). Every weight, ``base_color`` included, may be a
    per-element array (``eta`` and the rates are uniform, as in Mitsuba). Spectral mode is not
    available: the tints divide the colour by its luminance, which has no per-wavelength meaning.
    Mitsuba 3's ``principled`` is the reference (``bsdfkit.testing.principled_ref``).

    References
    ----------
    B. Burley, "Physically Based Shading at Disney", SIGGRAPH 2012 course notes. B. Burley,
    "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering", SIGGRAPH 2015
    course notes. Mitsuba 3, ``src/bsdfs/principled.cpp``.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m = bk.Principled([0.8, 0.1, 0.1], roughness=0.3, clearcoat=1.0)
    >>> m.eta
    1.5
    >>> bk.Principled(specular=0.5) == bk.Principled(eta=bk.models.principled.specular_to_eta(0.5))
    True
    """

    __slots__ = ()

    aliases = ("disney", "disney_principled")
    description = "Disney BSDF (Burley 2015), Mitsuba 3 principled"
    examples = {
        "red, clear coat": "principled 0.8,0.1,0.1 roughness=0.4 clearcoat=1 clearcoat_gloss=0.5",
        "brushed metal": "principled 0.9,0.6,0.3 roughness=0.5 anisotropic=0.8 metallic=1",
        "frosted glass": "principled 0.9,0.95,1 roughness=0.6 spec_trans=0.9 eta=1.5",
        "cloth": "principled 0.2,0.3,0.7 roughness=0.9 sheen=1 sheen_tint=0.5 flatness=0.6",
        "everything": ("principled 0.6,0.5,0.3 roughness=0.5 anisotropic=0.3 metallic=0.3 spec_trans=0.4 "
                       "specular=0.4 spec_tint=0.6 sheen=0.5 sheen_tint=0.5 flatness=0.5 clearcoat=0.5 "
                       "clearcoat_gloss=0.5"),
    }
    energy_conserving, exact_eval, two_sided, transmission, delta_only = False, True, True, True, False
    reciprocal = False
    mitsuba = "principled"
    _core_name, _weights, _rates = "Principled", _WEIGHTS, _RATES
    varying_params = {"base_color": 3, **{k: 1 for k in _WEIGHTS}}

    def __init__(self, base_color=0.5, roughness=0.5, anisotropic=0.0, metallic=0.0, spec_trans=0.0, eta=None,
                 specular=None, spec_tint=0.0, sheen=0.0, sheen_tint=0.0, flatness=0.0, clearcoat=0.0,
                 clearcoat_gloss=0.0, *, main_specular_sampling_rate=1.0, clearcoat_sampling_rate=1.0,
                 diffuse_reflectance_sampling_rate=1.0):
        """A Principled BSDF: the parameters are described in the class docstring
        (``help(bsdfkit.Principled)``); a bad value raises ValueError naming the parameter."""
        given = dict(roughness=roughness, anisotropic=anisotropic, metallic=metallic, spec_trans=spec_trans,
                     spec_tint=spec_tint, sheen=sheen, sheen_tint=sheen_tint, flatness=flatness, clearcoat=clearcoat,
                     clearcoat_gloss=clearcoat_gloss)
        w = {k: _scalar(given[k], k, lo=0.0, hi=1.0, varying=True) for k in _WEIGHTS}
        has_trans = _nonzero(w["spec_trans"])
        if eta is not None and specular is not None:
            raise ValueError("eta, specular: give one of them, not both (specular sets eta, as in Mitsuba 3)")
        if eta is not None:
            e = _scalar(eta, "eta", lo=0.0, lo_open=True)
            if has_trans and e == 1.0:      # Mitsuba: eta = 1 is not plausible with transmission
                e = 1.001
        else:
            s = 0.5 if specular is None else _scalar(specular, "specular", lo=0.0, hi=1.0)
            if has_trans and s == 0.0:      # Mitsuba: specular = 0 (eta = 1) likewise
                s = 1e-3
            e = specular_to_eta(s)
        rates = {k: _scalar(v, k, lo=0.0) for k, v in zip(_RATES, (main_specular_sampling_rate,
                                                                   clearcoat_sampling_rate,
                                                                   diffuse_reflectance_sampling_rate))}
        super().__init__(base_color=_rgb(base_color, "base_color", lo=0.0, hi=1.0, varying=True),
                         roughness=w["roughness"], anisotropic=w["anisotropic"], metallic=w["metallic"],
                         spec_trans=w["spec_trans"], eta=e, **{k: w[k] for k in _WEIGHTS[4:]}, **rates)

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Mitsuba 3's ``principled`` dictionary of this material (exact: the same plugin).
        ``eta`` is written (Mitsuba's ``specular`` is converted on construction); raises
        NotImplementedError for per-element parameters."""
        return self._mitsuba_dict(approximate)


#: PrincipledThin's weights in [0, 1] (diff_trans, in [0, 2], apart).
_THIN_WEIGHTS = ("roughness", "anisotropic", "spec_trans", "spec_tint", "sheen", "sheen_tint", "flatness")
_THIN_RATES = ("specular_reflectance_sampling_rate", "specular_transmittance_sampling_rate",
               "diffuse_reflectance_sampling_rate", "diffuse_transmittance_sampling_rate")


class PrincipledThin(_PrincipledFamily, BxDF):
    """The thin-surface Disney BSDF as Mitsuba 3 implements it (plugin ``principledthin``).

    A two-sided sheet (leaves, paper, thin plastic; Burley 2015 sec. 5) with Mitsuba 3.9's formulas
    and parameter names, so that ``eval`` and ``pdf`` agree with Mitsuba's ``principledthin``
    pointwise (to float32 rounding)::

        f = t lerp(F, Schlick(tint R0(eta)), spec_tint) D G / (4 cos_o cos_i)         specular reflection
          + t base (1 - F) D' G' / (4 cos_o cos_i)    (wi mirrored up)               specular transmission
          + (1 - t)(1 - d) (base/pi lerp(f_Burley + f_retro, f_fakeSSS, flatness)
                            + sheen Schlick(cos_d) lerp(1, tint, sheen_tint))        diffuse, sheen
          + (1 - t) d base / pi                                                      diffuse transmission

    with t = ``spec_trans``, d = ``diff_trans`` / 2, F the dielectric Fresnel term of ``eta``,
    D, G the anisotropic GGX of ``roughness`` (as :class:`Principled`) and D', G' those of the
    roughness scaled by (0.65 eta - 0.35) (Burley 2015 fig. 15). Light passes the sheet without
    bending; both sides are alike.

    Parameters
    ----------
    base_color : float or (3,) array_like, default 0.5
        Base colour (RGB in [0, 1]).
    roughness : float, default 0.5
        Roughness in [0, 1] (alpha = r^2).
    anisotropic : float, default 0
        Anisotropy in [0, 1].
    spec_trans : float, default 0
        Weight in [0, 1] of the specular lobes (reflection and transmission) against the diffuse ones.
    eta : float, default 1.5
        Index of refraction of the sheet (> 0): the Fresnel term and the transmission roughness.
    spec_tint : float, default 0
        Fraction in [0, 1] of the specular reflection tinted towards the base colour.
    sheen : float, default 0
        Sheen weight in [0, 1].
    sheen_tint : float, default 0
        Fraction in [0, 1] of the sheen tinted towards the base colour.
    flatness : float, default 0
        Blend in [0, 1] from the Burley diffuse to the fake subsurface lobe.
    diff_trans : float, default 0
        Diffuse transmission in [0, 2] (Mitsuba's range: 0 none, 1 half, 2 all of the diffuse
        light transmitted).
    specular_reflectance_sampling_rate, specular_transmittance_sampling_rate, diffuse_reflectance_sampling_rate, diffuse_transmittance_sampling_rate : float, default 1
        Mitsuba's sampling rates (>= 0, keyword-only); they change ``sample`` and ``pdf``, never
        ``eval``.

    Raises
    ------
    ValueError
        A parameter out of its range (the message names it).

    Notes
    -----
    Not energy conserving (the sheen and the retro-reflection add energy) and not reciprocal (the
    transmission lobe's roughness differs from the reflection's). Every weight, ``base_color`` and
    ``eta`` may be a per-element array (Mitsuba's ``eta`` is a texture here). No spectral mode (the
    tints divide by the colour's luminance). The reference is Mitsuba 3's ``principledthin``
    (``bsdfkit.testing.principled_ref``).

    References
    ----------
    B. Burley, "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering",
    SIGGRAPH 2015 course notes. Mitsuba 3, ``src/bsdfs/principledthin.cpp``.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> leaf = bk.PrincipledThin([0.3, 0.6, 0.2], roughness=0.7, diff_trans=1.0)
    >>> bk.BxDFFlags.DiffuseTransmission in leaf.flags, bk.BxDFFlags.GlossyTransmission in leaf.flags
    (True, False)
    """

    __slots__ = ()

    aliases = ("disney_thin",)
    description = "Thin-sheet Disney BSDF, Mitsuba 3 principledthin"
    examples = {
        "leaf": "principled_thin 0.3,0.6,0.2 roughness=0.7 diff_trans=1 sheen=0.3",
        "glossy film": "principled_thin 0.9,0.8,0.6 roughness=0.6 anisotropic=0.3 spec_trans=0.7 eta=1.4 spec_tint=0.3",
        "paper": "principled_thin 0.9 roughness=0.9 diff_trans=0.6 flatness=0.8",
    }
    energy_conserving, exact_eval, two_sided, transmission, delta_only = False, True, True, True, False
    reciprocal = False
    mitsuba = "principledthin"
    _core_name, _weights, _rates = "PrincipledThin", _THIN_WEIGHTS + ("diff_trans",), _THIN_RATES
    varying_params = {"base_color": 3, "eta": 1, "diff_trans": 1, **{k: 1 for k in _THIN_WEIGHTS}}

    def __init__(self, base_color=0.5, roughness=0.5, anisotropic=0.0, spec_trans=0.0, eta=1.5, spec_tint=0.0,
                 sheen=0.0, sheen_tint=0.0, flatness=0.0, diff_trans=0.0, *, specular_reflectance_sampling_rate=1.0,
                 specular_transmittance_sampling_rate=1.0, diffuse_reflectance_sampling_rate=1.0,
                 diffuse_transmittance_sampling_rate=1.0):
        """A PrincipledThin BSDF: the parameters are described in the class docstring
        (``help(bsdfkit.PrincipledThin)``); a bad value raises ValueError naming the parameter."""
        given = dict(roughness=roughness, anisotropic=anisotropic, spec_trans=spec_trans, spec_tint=spec_tint,
                     sheen=sheen, sheen_tint=sheen_tint, flatness=flatness)
        w = {k: _scalar(given[k], k, lo=0.0, hi=1.0, varying=True) for k in _THIN_WEIGHTS}
        rates = dict(zip(_THIN_RATES, (specular_reflectance_sampling_rate, specular_transmittance_sampling_rate,
                                       diffuse_reflectance_sampling_rate, diffuse_transmittance_sampling_rate)))
        super().__init__(base_color=_rgb(base_color, "base_color", lo=0.0, hi=1.0, varying=True),
                         **{k: w[k] for k in _THIN_WEIGHTS[:3]},
                         eta=_scalar(eta, "eta", lo=0.0, lo_open=True, varying=True),
                         **{k: w[k] for k in _THIN_WEIGHTS[3:]},
                         diff_trans=_scalar(diff_trans, "diff_trans", lo=0.0, hi=2.0, varying=True),
                         **{k: _scalar(v, k, lo=0.0) for k, v in rates.items()})

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Mitsuba 3's ``principledthin`` dictionary of this material (exact: the same plugin);
        raises NotImplementedError for per-element parameters."""
        return self._mitsuba_dict(approximate)
