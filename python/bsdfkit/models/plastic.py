"""Plastic: a Lambertian base under a dielectric coating (Mitsuba 3 ``plastic`` / ``roughplastic``)."""
from __future__ import annotations

import numpy as np

from .. import _core
from . import _mitsuba_export as _me
from . import _spectral as _sp
from .base import (_MASKING, MIN_ALPHA, BxDF, _masking, _rgb, _scalar, core_value, fmt_value, masking_knob,
                   rgb_dict)
from .registry import KnobDecl

#: below this alpha the coating is smooth (Mitsuba's plastic instead of roughplastic)
SMOOTH_ALPHA = 1e-3

__all__ = ["Plastic"]


def _bool(x, name: str) -> bool:
    if not isinstance(x, (bool, np.bool_)):
        raise TypeError(f"{name}: expected a bool, got {type(x).__name__}")
    return bool(x)


class Plastic(BxDF):
    """Diffuse base under a smooth or GGX-rough dielectric coating: Mitsuba 3's ``plastic``
    (``alpha`` < 1e-3) and ``roughplastic`` (GGX, ``sample_visible``), reproduced exactly.

    f = Ks F(wo.wh) D G / (4 cos_o cos_i)   [rough coating only; the smooth one is a delta lobe]
      + R / (1 - Fdr) * T(cos_o) T(cos_i) / (pi eta^2)   [``nonlinear=True``: R / (1 - R Fdr)]

    Parameters
    ----------
    reflectance : float or RGB or Spectrum, optional
        Diffuse albedo R of the base, scalar or RGB in [0, 1] (Mitsuba ``diffuse_reflectance``).
    eta : float, optional
        Relative IOR of the coating, inside over outside (Mitsuba ``int_ior / ext_ior``);
        > 0 and != 1 (Mitsuba rejects index-matched rough coatings). Default 1.49
        (polypropylene, Mitsuba's default).
    alpha : float, optional
        Isotropic GGX alpha of the coating (not pbrt's remapped roughness); < 1e-3 gives the
        smooth coating (a delta reflection lobe), otherwise it is floored at 1e-4.
    nonlinear : bool, optional
        Mitsuba's ``nonlinear`` knob (a modelling choice). False: the internal
        reflections are summed as 1 / (1 - Fdr), which keeps the diffuse colour as given.
        True: R / (1 - R Fdr), the physical sum of the base's inter-reflections (colours
        saturate and darken, as in real wet/varnished materials).
    masking : {"correlated", "separable"}, optional
        The coating's masking-shadowing, "correlated" (height-correlated Smith, pbrt-v4;
        the default) or "separable" (G1 G1, what Mitsuba uses: pass it to reproduce Mitsuba
        exactly; ``from_mitsuba`` does). The default is not Mitsuba's because every bsdfkit
        microfacet model defaults to pbrt-v4's height-correlated masking (the physically
        consistent one), and a changed default would silently change the material of every
        existing spec string and script that omits it; instead ``to_mitsuba`` refuses a rough
        correlated model (``approximate=True`` exports it with a warning stating the difference).
    specular_reflectance : float or RGB or Spectrum, optional
        Multiplier Ks on the coating's reflection, scalar or RGB >= 0 (physically 1; Mitsuba
        ``specular_reflectance``).

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Notes
    -----
    T and Fdr: smooth coating, T = 1 - F (exact dielectric Fresnel) and Fdr = Mitsuba's fitted
    diffuse Fresnel reflectance of 1/eta (Egan & Hilgeman 1973 / d'Eon & Irving 2011). Rough
    coating, T(cos) is Mitsuba's 64-entry table of the GGX interface's directional
    transmittance, linearly interpolated, and Fdr = 2 * mean(R_int(mu) mu) of the internal
    directional reflectance over the same nodes; both are computed at construction exactly as
    Mitsuba computes them (a Gauss-Legendre product rule through Mitsuba's visible-normal warp),
    in float64, once per (alpha, eta) (a small cache shares them between the float, double and
    gradient kernels). Sampling: the coating lobe with probability w k / (w k + (1 - w)(1 - k)),
    k = F(cos_o) or 1 - T(cos_o), w = mean(Ks) / (mean(R) + mean(Ks)); otherwise a cosine-
    weighted direction. The rough lobe is sampled with Mitsuba's visible-normal map, so samples
    equal Mitsuba's for the same uniforms.

    Gradients: ``eval_grad`` differentiates reflectance, eta, alpha and specular_reflectance
    through the same code, the rough coat's tables included (their derivatives in alpha and eta
    are those of the quadrature as computed); one-sided points: ``bsdfkit.fitting.grad``.

    Two-sided: a ``wo`` below the surface sees the mirrored material (Mitsuba's plugins are
    one-sided and are compared inside ``twosided``). No transmission.

    Differences from pbrt-v3's ``plastic`` material: pbrt-v3 has no coating model at all: it
    adds a Lambertian lobe ``Kd / pi`` (no Fresnel transmittance, no internal reflection, no
    1/eta^2) to a Torrance-Sparrow lobe ``Ks F D G / (4 cos cos)`` with a *fixed* dielectric
    Fresnel of eta = 1.5 (``FresnelDielectric(1.5, 1)``), Trowbridge-Reitz (or Beckmann) D with
    ``roughness`` remapped by default, and it samples the two lobes with equal probability. Its
    sum can exceed 1 (no energy exchange between the lobes); this model conserves energy
    (for Ks <= 1). pbrt-v4 replaced plastic by ``coateddiffuse`` (``bsdfkit.CoatedDiffuse``).

    Spectral mode (``wavelengths=``): ``reflectance`` and ``specular_reflectance`` may be
    ``bsdfkit.Spectrum`` values (RGB ones are uplifted, Jakob & Hanika 2019, bounded) and are
    evaluated per wavelength; ``eta`` is a scalar (as Mitsuba's ``int_ior``: the rough coating's
    tables belong to one IOR). The lobe weight w uses the spectral means over [360, 830] nm
    (Mitsuba's ``Texture::mean()`` in its spectral variants), so spectral-mode pdf equals
    Mitsuba ``llvm_ad_spectral``'s; RGB mode projects spectra to linear sRGB under D65.
    """

    __slots__ = ()

    aliases = ("roughplastic",)
    examples = {"red, rough coat": "plastic reflectance=0.8,0.1,0.1 alpha=0.2",
                "smooth plastic": "plastic reflectance=0.5",
                "rough, nonlinear, separable (Mitsuba)":
                    "plastic reflectance=0.8,0.1,0.1 alpha=0.1 nonlinear=True masking=separable"}
    description = "diffuse base under a smooth or rough dielectric coat (Mitsuba plastic / roughplastic)"
    energy_conserving, exact_eval, reciprocal, two_sided, transmission, delta_only = True, True, True, True, False, False
    mitsuba = "roughplastic"
    # bk.fit bounds (eval_grad: every parameter; alpha from the rough coat's 1e-3 up, eta > 1)
    param_ranges = {"reflectance": (0.0, 1.0), "eta": (1.001, 4.0), "alpha": (1e-3, 2.0),
                    "specular_reflectance": (0.0, 1.0)}
    varying_params = {"reflectance": 3, "eta": 1, "alpha": 1, "specular_reflectance": 3}
    knobs = (masking_knob(lambda q: "smooth coating (alpha < 1e-3): a mirror has no masking"
                          if q["alpha"] < SMOOTH_ALPHA else None),
             KnobDecl("nonlinear", (False, True), "modelling",
                      "internal reflections: R / (1 - Fdr) (keeps the colour) or R / (1 - R Fdr) (saturates)"))

    def __init__(self, reflectance=0.5, eta=1.49, alpha=0.0, nonlinear=False, masking="correlated",
                 specular_reflectance=1.0):
        """A Plastic: the parameters are described in the class docstring (``help(bsdfkit.Plastic)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        eta = _scalar(eta, "eta", lo=0.0, lo_open=True, varying=True)
        if np.any(np.asarray(eta) == 1.0):
            at = "" if np.ndim(eta) == 0 else f" (at index {tuple(int(i) for i in np.argwhere(eta == 1.0)[0])})"
            raise ValueError(f"eta: must differ from 1{at} (an index-matched coating is not a plastic; "
                             "use Diffuse)")
        super().__init__(reflectance=_sp.spectrum_or_rgb(reflectance, "reflectance", lo=0.0, hi=1.0, varying=True),
                         eta=eta, alpha=_scalar(alpha, "alpha", lo=0.0, varying=True),
                         nonlinear=_bool(nonlinear, "nonlinear"), masking=_masking(masking),
                         specular_reflectance=_sp.spectrum_or_rgb(specular_reflectance, "specular_reflectance",
                                                                  lo=0.0, varying=True))

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def _make_core(self):
        p = self._params
        return _core.Plastic(reflectance=core_value(_sp.rgb_of(p["reflectance"], "reflectance")), eta=p["eta"],
                             alpha=p["alpha"], nonlinear=p["nonlinear"], masking=_MASKING[p["masking"]],
                             specular_reflectance=core_value(_sp.rgb_of(p["specular_reflectance"], "reflectance")))

    def _spectral_inputs(self) -> dict:
        # batch_spectral.h PlasticSpectral: R and Ks per wavelength; the lobe weight from their
        # means over [360, 830] nm (Mitsuba's Texture::mean() in its spectral variants)
        p = self._params
        r, ks = p["reflectance"], p["specular_reflectance"]
        rm, sm = _sp.spectral_mean(r, "reflectance"), _sp.spectral_mean(ks, "reflectance")
        return dict(spec_weight=sm / (rm + sm) if rm + sm > 0 else 0.5,
                    has_diffuse=_sp.spectral_max(r, "reflectance") > 0)

    def _spectral_core_kwargs(self) -> dict:
        kw = self._core.params
        if kw["alpha"] < SMOOTH_ALPHA:
            kw["alpha"] = 0.0  # the smooth coat
        return kw

    def cost_family(self) -> str:
        return "Plastic" + ("/smooth" if np.all(self._params["alpha"] < SMOOTH_ALPHA) else "/rough")

    def describe(self) -> str:
        a = self._params["alpha"]
        if np.ndim(a):
            return f"Plastic R={_sp.fmt_param(self._params['reflectance'])}, α per element"
        return f"Plastic R={_sp.fmt_param(self._params['reflectance'])}, " + (f"α={a:.2g}" if a >= SMOOTH_ALPHA else "smooth")

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """The Mitsuba 3 plugin dictionary of this material: ``twosided{plastic}`` (smooth coating)
        or ``twosided{roughplastic}`` (ggx, visible-normal sampling); spectra are written as their
        RGB values (what RGB mode uses).

        Mitsuba's ``roughplastic`` has the separable Smith masking: a rough model with
        ``masking="correlated"`` (the default) raises ``MitsubaExportError`` (a
        NotImplementedError and a ValueError) stating the measured difference;
        ``approximate=True`` exports the separable version and warns with
        ``MitsubaApproximationWarning`` stating it. A smooth coating has no masking and exports
        exactly with either setting."""
        self._refuse_varying("to_mitsuba")
        approximate = _me.check_approximate(approximate)
        p = self._params
        inner = {"diffuse_reflectance": rgb_dict(_sp.rgb_of(p["reflectance"], "reflectance")),
                 "int_ior": float(p["eta"]), "ext_ior": 1.0, "nonlinear": bool(p["nonlinear"])}
        ks = _sp.rgb_of(p["specular_reflectance"], "reflectance")
        if np.any(np.asarray(ks) != 1.0):
            inner["specular_reflectance"] = rgb_dict(ks)
        if p["alpha"] < SMOOTH_ALPHA:
            inner["type"] = "plastic"
        else:
            inner.update(type="roughplastic", distribution="ggx", alpha=max(float(p["alpha"]), MIN_ALPHA),
                         sample_visible=True)
        d = {"type": "twosided", "bsdf": inner}
        if inner["type"] == "roughplastic" and p["masking"] != "separable":
            from ..interop.mitsuba import from_mitsuba
            _me.refuse_or_warn(self, from_mitsuba(d), [_me.MASKING_REASON.format(plugin="roughplastic")],
                               approximate)
        return d

    @property
    def transmittance_table(self) -> np.ndarray:
        """The coating's directional transmittance T(cos) at cos = i / 63, i = 0..63 (float64):
        the rough table (Mitsuba's ``m_external_transmittance``), or 1 - F for a smooth coating."""
        return np.asarray(self._core.transmittance_table)
