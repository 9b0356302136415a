"""OpenPBR: the OpenPBR Surface 1.1 material (Academy Software Foundation), as a mixture of lobes."""
from __future__ import annotations

import numpy as np

from .. import _core
from ._mitsuba_export import check_approximate as _check_approximate
from .base import BxDF, _rgb, _scalar, core_value, fmt_param, fmt_value
from .registry import KnobDecl

__all__ = ["OpenPBR", "NOT_MODELLED"]

#: The modelled parameters in the MaterialX nodedef's order (the constructor's), each with its
#: bounds: name -> (lo, hi, lo_open, rgb); hi None: unbounded; lo_open: strictly above lo (the
#: IORs). specular_color is unbounded above: the spec's own metal examples reach 1.39.
_BOUNDS = {
    "base_weight": (0.0, 1.0, False, False),
    "base_color": (0.0, 1.0, False, True),
    "base_metalness": (0.0, 1.0, False, False),
    "base_diffuse_roughness": (0.0, 1.0, False, False),
    "specular_weight": (0.0, None, False, False),
    "specular_color": (0.0, None, False, True),
    "specular_roughness": (0.0, 1.0, False, False),
    "specular_roughness_anisotropy": (0.0, 1.0, False, False),
    "specular_ior": (0.0, None, True, False),
    "transmission_weight": (0.0, 1.0, False, False),
    "transmission_color": (0.0, 1.0, False, True),
    "subsurface_weight": (0.0, 1.0, False, False),
    "subsurface_color": (0.0, 1.0, False, True),
    "subsurface_scatter_anisotropy": (-1.0, 1.0, False, False),
    "coat_weight": (0.0, 1.0, False, False),
    "coat_color": (0.0, 1.0, False, True),
    "coat_roughness": (0.0, 1.0, False, False),
    "coat_roughness_anisotropy": (0.0, 1.0, False, False),
    "coat_ior": (0.0, None, True, False),
    "coat_darkening": (0.0, 1.0, False, False),
    "fuzz_weight": (0.0, 1.0, False, False),
    "fuzz_color": (0.0, 1.0, False, True),
    "fuzz_roughness": (0.0, 1.0, False, False),
    "thin_film_weight": (0.0, 1.0, False, False),
    "thin_film_thickness": (0.0, None, False, False),
    "thin_film_ior": (0.0, None, True, False),
}

#: Inputs of ``open_pbr_surface`` that this model does not model: name -> (default, what it is).
#: A non-default value raises ValueError (``from_materialx(..., approximate=True)`` drops them
#: with a warning); ``subsurface_radius`` and ``subsurface_radius_scale`` are accepted and
#: ignored (the subsurface slab is a diffuse lobe here), ``transmission_dispersion_abbe_number``
#: is ignored at ``transmission_dispersion_scale`` 0 and ``emission_color`` at
#: ``emission_luminance`` 0.
NOT_MODELLED = {
    "transmission_depth": (0.0, "the interior medium's extinction depth (a volume)"),
    "transmission_scatter": ((0.0, 0.0, 0.0), "the interior medium's scattering (a volume)"),
    "transmission_scatter_anisotropy": (0.0, "the interior medium's phase function (a volume)"),
    "transmission_dispersion_scale": (0.0, "dispersion (a wavelength-dependent IOR)"),
    "emission_luminance": (0.0, "emission (an EDF, not a BSDF)"),
    "geometry_opacity": (1.0, "cut-out opacity (a null lobe; use bk.Mask)"),
}
#: Accepted and ignored (see NOT_MODELLED).
_IGNORED = ("subsurface_radius", "subsurface_radius_scale", "transmission_dispersion_abbe_number",
            "emission_color")

_COMPENSATION = ("turquin", "none")
_LAYERING = ("albedo-scaling", "reciprocal")


def _lobe_settings(param):
    """keep (the input's weight) then drop (0); only keep when the lobe is absent."""
    return lambda q: (q[param], 0.0) if float(q[param]) > 0 else (q[param],)


def _lobe_labels(param):
    return lambda q: ("keep", "drop") if float(q[param]) > 0 else ("keep",)


def _same(v, default) -> bool:
    return bool(np.all(np.asarray(v, dtype=np.float64) == np.asarray(default, dtype=np.float64)))


class OpenPBR(BxDF):
    """OpenPBR Surface 1.1 (Academy Software Foundation; MaterialX ``open_pbr_surface``).

    The industry's common uber-material: a base that mixes metal, glossy-diffuse dielectric,
    subsurface and translucent slabs, under a coat and a fuzz layer, with a thin film on the base.
    The parameters are the MaterialX input names with the spec's defaults. The layer and mix
    operators are reduced to a mixture of lobes with albedo scaling, as the spec's "Reduction to
    a mixture of lobes" section and its MaterialX reference do::

        f      = F f_fuzz + (1 - F E_fuzz(mu_o)) f_coated
        f_coated = C f_coat + lerp(1, T_coat (1 - E_coat(mu_o)), C) Dk f_base
        f_base = lerp(f_R + (1 - T)(1 - E_R(mu_o)) lerp(f_EON, f_sss, S) + T f_T, f_metal, M)

    with F, C, M, T, S = ``fuzz_weight``, ``coat_weight``, ``base_metalness``,
    ``transmission_weight``, ``subsurface_weight``; f_R / f_T the GGX dielectric reflection and
    transmission at the IOR that ``specular_weight`` modulates (tinted by ``specular_color`` /
    ``transmission_color``), f_metal the GGX conductor with the F82-tint Fresnel (F0 =
    ``base_weight base_color``, edge ``specular_color``), f_EON the energy-preserving Oren-Nayar
    diffuse, f_sss ``subsurface_color / pi``, f_coat the coat's GGX reflection, T_coat the coat's
    view-dependent absorption, Dk its darkening, f_fuzz Zeltner et al.'s LTC sheen, and E the
    albedos of the lobes, tabulated at construction. Thin film (Belcour & Barla 2017) replaces
    the base's reflection Fresnel by a ``thin_film_weight`` blend with the Airy reflectance.

    Parameters
    ----------
    base_weight, base_color, base_metalness, base_diffuse_roughness
        The base: weight and colour (RGB in [0, 1]) of the diffuse albedo and of the metal's F0,
        the metal fraction, and the EON roughness.
    specular_weight, specular_color, specular_roughness, specular_roughness_anisotropy, specular_ior
        The base's specular interface: reflectivity multiplier (>= 0, through the IOR), Fresnel
        tint and the metal's edge tint (RGB >= 0: above 1, as seven of the spec's example metals,
        it lifts the Fresnel factor, which is clamped at 1), roughness r (alpha = r^2), anisotropy
        (x is the rougher axis), IOR.
    transmission_weight, transmission_color
        The translucent fraction of the dielectric base and its on-surface tint.
    subsurface_weight, subsurface_color, subsurface_scatter_anisotropy
        The subsurface fraction and its colour (a Lambertian lobe here); the anisotropy g splits
        the thin-walled sheet's diffuse light into (1 - g)/2 reflected and (1 + g)/2 transmitted.
    coat_weight, coat_color, coat_roughness, coat_roughness_anisotropy, coat_ior, coat_darkening
        The coat: coverage, the square of its normal-incidence transmittance, its GGX lobe, IOR,
        and how much of its physical darkening of the base is kept (1: all).
    fuzz_weight, fuzz_color, fuzz_roughness
        The fuzz layer (Zeltner 2022 sheen): coverage, colour, roughness.
    thin_film_weight, thin_film_thickness, thin_film_ior
        The thin film on the base: coverage, thickness in micrometres, IOR.
    geometry_thin_walled : bool, default False
        A two-sided thin sheet instead of a solid's boundary.
    compensation : {"turquin", "none"}, keyword-only
        Multiple-scattering compensation of the GGX lobes (Turquin 2019, with the dielectric's
        transmission normalized to the reflection's complement), or single scattering. A
        ``tradeoff`` knob.
    layering : {"albedo-scaling", "reciprocal"}, keyword-only
        The layering's albedo scaling by (1 - E(mu_o)) (energy conserving, not reciprocal; the
        spec's reference), or by sqrt((1 - E(mu_o))(1 - E(mu_i))) (reciprocal, not energy
        conserving). A ``tradeoff`` knob.

    The other ``open_pbr_surface`` inputs (``transmission_depth``, ``transmission_scatter``,
    ``transmission_scatter_anisotropy``, ``transmission_dispersion_scale``,
    ``emission_luminance``, ``geometry_opacity``) are accepted only at their defaults:
    ``NOT_MODELLED`` says why; ``subsurface_radius``, ``subsurface_radius_scale``,
    ``transmission_dispersion_abbe_number`` and ``emission_color`` are accepted and ignored.

    Raises
    ------
    ValueError
        A parameter out of its range or a non-default unmodelled input (the message names it).

    Notes
    -----
    Roughness 0 gives alpha 1e-3: no lobe is a delta. Seen from below (``wo.z < 0``) the material
    is its bare dielectric interface (weight (1 - M) T); thin-walled, it is the same from both
    sides. The albedos are tabulated over the isotropic or, for an anisotropic lobe, the
    anisotropic GGX (48 cosines x 9 azimuths, Gauss-Legendre over visible normals, within ~4e-3
    of the exact albedos): a construction costs ~3 ms (~30 ms anisotropic). Parameters are uniform (no per-element
    arrays: the albedo tables depend on them); no spectral mode; no gradients; Mitsuba 3 has no
    OpenPBR plugin. The float64 reference is ``bsdfkit.testing.openpbr_ref``.

    References
    ----------
    OpenPBR Surface specification v1.1.1 (Academy Software Foundation, 2026). J. Portsmouth et al.,
    "EON" (JCGT 2025). T. Zeltner, B. Burley, M. J.-Y. Chiang, "Practical Multiple-Scattering Sheen
    Using Linearly Transformed Cosines" (SIGGRAPH Talks 2022). L. Belcour, P. Barla, "A Practical
    Extension to Microfacet Theory for the Modeling of Varying Iridescence" (SIGGRAPH 2017).
    P. Kutz et al., "Novel aspects of the Adobe Standard Material" (2021). E. Turquin, "Practical
    multiple scattering compensation for microfacet models" (2019).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m = bk.OpenPBR(base_color=[0.8, 0.2, 0.1], coat_weight=1.0)
    >>> m.describe()
    'OpenPBR base=(0.8, 0.2, 0.1), r=0.3, coat=1'
    """

    __slots__ = ()

    aliases = ("open_pbr_surface",)  # "open_pbr" is the class's own snake_case name
    description = "OpenPBR Surface 1.1 (ASWF): metal, dielectric, coat, fuzz, thin film"
    examples = {
        "red, coat, fuzz": ("openpbr base_color=0.7,0.05,0.05 specular_roughness=0.4 coat_weight=1 coat_roughness=0.25 "
                            "fuzz_weight=0.3"),
        "default": "openpbr",
        "gold": "openpbr base_color=1,0.78,0.34 base_metalness=1 specular_color=0.98,0.9,0.6 specular_roughness=0.25",
        "frosted glass": "openpbr transmission_weight=1 specular_roughness=0.4 base_color=1,1,1",
        "velvet": "openpbr base_color=0.3,0.02,0.1 specular_roughness=0.6 fuzz_weight=1 fuzz_color=0.8,0.3,0.5 fuzz_roughness=0.4",
        "soap film": "openpbr base_color=0,0,0 thin_film_weight=1 thin_film_thickness=0.4 thin_film_ior=1.33 specular_roughness=0.3",
        "brushed metal": "openpbr base_color=0.9,0.9,0.92 base_metalness=1 specular_roughness=0.5 specular_roughness_anisotropy=0.8",
        "everything": ("openpbr base_color=0.8,0.5,0.3 base_metalness=0.2 specular_roughness=0.4 transmission_weight=0.3 "
                       "coat_weight=0.5 coat_roughness=0.25 fuzz_weight=0.3 thin_film_weight=0.5 thin_film_thickness=0.4"),
        "paper (thin-walled)": "openpbr base_color=0.9,0.9,0.85 subsurface_weight=0.6 subsurface_color=0.9,0.9,0.85 geometry_thin_walled=true specular_roughness=0.7",
    }
    energy_conserving, exact_eval, two_sided, transmission, delta_only = True, True, True, True, False
    reciprocal = False
    mitsuba = None
    varying_params: dict = {}
    knobs = (
        KnobDecl("compensation", _COMPENSATION, "approximation",
                 "GGX multiple-scattering compensation (Turquin 2019) or single scattering"),
        KnobDecl("fuzz", _lobe_settings("fuzz_weight"), "approximation",
                 "fuzz layer: keep, or drop (fuzz_weight = 0)", param="fuzz_weight",
                 labels=_lobe_labels("fuzz_weight"), lobe=True),
        KnobDecl("thin_film", _lobe_settings("thin_film_weight"), "approximation",
                 "thin-film iridescence: keep, or drop (thin_film_weight = 0)", param="thin_film_weight",
                 labels=_lobe_labels("thin_film_weight"), lobe=True),
        KnobDecl("coat", _lobe_settings("coat_weight"), "approximation",
                 "coat layer: keep, or drop (coat_weight = 0)", param="coat_weight",
                 labels=_lobe_labels("coat_weight"), lobe=True),
        KnobDecl("layering", _LAYERING, "approximation",
                 "albedo scaling (1 - E(mu_o)), energy conserving; or sqrt((1 - E(mu_o))(1 - E(mu_i))), reciprocal"),
    )

    def __init__(self, base_weight=1.0, base_color=(0.8, 0.8, 0.8), base_metalness=0.0, base_diffuse_roughness=0.0,
                 specular_weight=1.0, specular_color=(1.0, 1.0, 1.0), specular_roughness=0.3,
                 specular_roughness_anisotropy=0.0, specular_ior=1.5, transmission_weight=0.0,
                 transmission_color=(1.0, 1.0, 1.0), subsurface_weight=0.0, subsurface_color=(0.8, 0.8, 0.8),
                 subsurface_scatter_anisotropy=0.0, coat_weight=0.0, coat_color=(1.0, 1.0, 1.0), coat_roughness=0.0,
                 coat_roughness_anisotropy=0.0, coat_ior=1.6, coat_darkening=1.0, fuzz_weight=0.0,
                 fuzz_color=(1.0, 1.0, 1.0), fuzz_roughness=0.5, thin_film_weight=0.0, thin_film_thickness=0.5,
                 thin_film_ior=1.4, geometry_thin_walled=False, *, compensation="turquin",
                 layering="albedo-scaling", **unmodelled):
        """An OpenPBR material: the parameters are described in the class docstring
        (``help(bsdfkit.OpenPBR)``); a bad value raises ValueError naming the parameter."""
        given = dict(locals())
        for k, v in unmodelled.items():
            if k in _IGNORED:
                continue
            if k not in NOT_MODELLED:
                raise TypeError(f"OpenPBR() got an unexpected keyword argument {k!r}")
            default, what = NOT_MODELLED[k]
            if not _same(v, default):
                raise ValueError(f"{k}: not modelled by bsdfkit.OpenPBR ({what}); only its default {default} "
                                 "is accepted (bk.from_materialx(..., approximate=True) drops it with a warning)")
        p = {k: (_rgb if rgb else _scalar)(given[k], k, lo=lo, hi=hi, lo_open=lo_open)
             for k, (lo, hi, lo_open, rgb) in _BOUNDS.items()}
        if not isinstance(geometry_thin_walled, (bool, np.bool_)):
            raise TypeError(f"geometry_thin_walled: expected True or False, got {geometry_thin_walled!r}")
        p["geometry_thin_walled"] = bool(geometry_thin_walled)
        if compensation not in _COMPENSATION:
            raise ValueError(f"compensation: must be one of {list(_COMPENSATION)}, got {compensation!r}")
        if layering not in _LAYERING:
            raise ValueError(f"layering: must be one of {list(_LAYERING)}, got {layering!r}")
        super().__init__(**p, compensation=compensation, layering=layering)

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def _make_core(self):
        return _core.OpenPBR(**{k: core_value(v) for k, v in self._params.items()})

    def _no_spectral_reason(self) -> str:
        return ("wavelengths: OpenPBR has no spectral mode yet (its albedo tables and thin film are RGB); "
                "call without wavelengths= for RGB")

    def describe(self) -> str:
        p = self._params
        parts = [f"base={fmt_value(p['base_color'])}", f"r={fmt_value(p['specular_roughness'])}"]
        for k, label in (("base_metalness", "metal"), ("transmission_weight", "transmission"),
                         ("subsurface_weight", "subsurface"), ("coat_weight", "coat"), ("fuzz_weight", "fuzz"),
                         ("thin_film_weight", "film")):
            if float(p[k]) != 0.0:
                parts.append(f"{label}={fmt_value(p[k])}")
        if p["geometry_thin_walled"]:
            parts.append("thin-walled")
        return "OpenPBR " + ", ".join(parts)

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Raises NotImplementedError: Mitsuba 3 has no OpenPBR plugin (a draft only)."""
        _check_approximate(approximate)
        raise NotImplementedError("Mitsuba 3 has no OpenPBR plugin (PR #1919 is a draft); "
                                  "bsdfkit.testing.openpbr_ref is the float64 reference")
