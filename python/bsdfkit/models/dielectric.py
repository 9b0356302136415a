"""Dielectric interfaces: pbrt-v4's DielectricBxDF (smooth or rough) and ThinDielectricBxDF."""
from __future__ import annotations

import numpy as np

from .. import _core
from . import _mitsuba_export as _me
from . import _spectral as _sp
from .base import (MIN_ALPHA, BxDF, _alphas, _distribution, _masking, _sample_visible, alpha_text, distribution_knob,
                   is_smooth, masking_knob, microfacet_kw)

__all__ = ["Dielectric", "ThinDielectric"]


def _dielectric_moot(what):
    def moot(q):
        if is_smooth(q):
            return f"smooth dielectric (max alpha < 1e-3): delta lobes have no {what}"
        if q["eta"] == 1.0:
            return "eta = 1: light passes straight through, no microfacets involved"
        return None
    return moot


class Dielectric(BxDF):
    """Glass-like interface: Fresnel-weighted reflection and refraction, smooth (delta) or
    anisotropic Trowbridge-Reitz (GGX) or Beckmann rough (pbrt-v4 ``DielectricBxDF``).

    wo may be on either side. In Radiance mode transmitted values are divided by eta'^2.

    eta may be a ``bsdfkit.Spectrum`` (``Spectrum.named("glass-BK7")``): a non-constant one
    disperses in spectral mode (``wavelengths=``): ``sample`` lets the first (hero) wavelength
    choose lobe and direction; a reflection keeps all 4 wavelengths (f per wavelength), a
    refraction keeps the hero only (``terminated``); ``eval`` of a transmission pair is the hero's
    alone; ``pdf`` is the hero's. In RGB mode such an eta is its value at 550 nm.

    Parameters
    ----------
    eta : float or Spectrum, optional
        Relative IOR, inside over outside (> 0; < 1 when the outside is denser; 1 passes light
        straight through). Default 1.5.
    alpha, alpha_x, alpha_y : float, optional
        GGX alpha, isotropic or per tangent axis, as in ``Conductor``; none: a smooth interface.
    masking : {"correlated", "separable"}, optional
        Masking-shadowing, as in ``Conductor``.
    distribution : {"ggx", "beckmann"}, optional
        The microfacet distribution, as in ``Conductor``; default "ggx".
    sample_visible : bool, optional
        Visible-normal sampling (default) or D(wm) cos(wm), as in ``Conductor``.

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> s = bk.Dielectric(1.5).sample(bk.direction(0.0, 0.0), n=1000, seed=0)
    >>> sorted(set(np.round(s.wi[:, 2], 6).tolist()))   # smooth: mirror or straight through
    [-1.0, 1.0]
    """

    __slots__ = ()

    aliases = ("glass",)
    description = "Glass-like interface, smooth or rough, reflection and refraction (pbrt-v4 DielectricBxDF)"
    examples = {"glass, alpha 0.2": "dielectric 1.5 alpha=0.2", "smooth glass": "dielectric 1.5",
                "rough glass 0.3": "dielectric 1.5 alpha=0.3",
                "inside water, anisotropic": "dielectric 0.75188 alpha_x=0.5 alpha_y=0.1",
                "separable masking": "dielectric 1.33 alpha=0.4 masking=separable",
                "Beckmann, separable": "dielectric 1.5 alpha=0.3 distribution=beckmann masking=separable",
                "index matched": "dielectric 1"}
    energy_conserving, exact_eval, two_sided, transmission, delta_only = True, True, True, True, False
    reciprocal = True
    mitsuba = "roughdielectric"
    # fitting bounds (bk.fit): alphas kept in the rough regime (>= 1e-3)
    param_ranges = {"eta": (1.001, 4.0), "alpha_x": (1e-3, 2.0), "alpha_y": (1e-3, 2.0)}
    varying_params = {"eta": 1, "alpha_x": 1, "alpha_y": 1}
    knobs = (masking_knob(_dielectric_moot("masking")), distribution_knob(_dielectric_moot("microfacets")))

    def __init__(self, eta=1.5, alpha=None, alpha_x=None, alpha_y=None, masking="correlated", distribution="ggx",
                 sample_visible=True):
        """A Dielectric: the parameters are described in the class docstring (``help(bsdfkit.Dielectric)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        ax, ay = _alphas(alpha, alpha_x, alpha_y, varying=True)
        super().__init__(eta=_sp.spectrum_or_scalar(eta, "eta", lo=0.0, lo_open=True, varying=True),
                         alpha_x=ax, alpha_y=ay, masking=_masking(masking),
                         distribution=_distribution(distribution), sample_visible=_sample_visible(sample_visible))

    @classmethod
    def _from_params(cls, p):
        return cls(p["eta"], alpha_x=p["alpha_x"], alpha_y=p["alpha_y"], masking=p["masking"],
                   distribution=p.get("distribution", "ggx"), sample_visible=p.get("sample_visible", True))

    def _make_core(self):
        p = self._params
        return _core.Dielectric(eta=_sp.scalar_of(p["eta"]), alpha_x=p["alpha_x"], alpha_y=p["alpha_y"],
                                **microfacet_kw(p))

    def _spectral_inputs(self) -> dict:
        return {"dispersive": _sp.is_dispersive(self._params["eta"])}  # DielectricSpectral: hero wavelength

    def cost_family(self) -> str:
        p = self._params
        return "Dielectric" + ("/smooth" if is_smooth(p) or bool(np.all(p["eta"] == 1.0)) else "/rough")

    def describe(self) -> str:
        return f"Dielectric η={_sp.fmt_param(self._params['eta'])}{alpha_text(self._params)}"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """The Mitsuba 3 plugin dictionary of this material: ``dielectric`` / ``roughdielectric``
        (the model's distribution and ``sample_visible``) with int_ior = eta, ext_ior = 1 (eta < 1 is passed as is: Mitsuba accepts int_ior <
        ext_ior); eta == 1 -> ``null`` (pbrt's pass-through). A spectral eta is written as its
        value at 550 nm (what RGB mode uses).

        Mitsuba's ``roughdielectric`` has the separable Smith masking G1(wo) G1(wi): a rough model
        with ``masking="correlated"`` (the default, pbrt-v4's) raises ``MitsubaExportError`` (a
        NotImplementedError and a ValueError) stating the measured difference;
        ``approximate=True`` exports the separable version and warns with
        ``MitsubaApproximationWarning`` stating it. Smooth and eta = 1 models export exactly.
        """
        self._refuse_varying("to_mitsuba")
        approximate = _me.check_approximate(approximate)
        eta, p = _sp.scalar_of(self.eta), self._params
        if eta == 1.0:
            # pbrt: eta == 1 is always the smooth branch, a straight pass-through with R = 0,
            # f = 1/|cos|, pdf = 1; Mitsuba's 'null' samples wo = -wi with weight 1 and pdf 1.
            return {"type": "null"}
        if is_smooth(p):
            return {"type": "dielectric", "int_ior": eta, "ext_ior": 1.0}
        d = {"type": "roughdielectric", "distribution": p["distribution"], "alpha_u": max(p["alpha_x"], MIN_ALPHA),
             "alpha_v": max(p["alpha_y"], MIN_ALPHA), "sample_visible": p["sample_visible"], "int_ior": eta,
             "ext_ior": 1.0}
        if p["masking"] != "separable":
            from ..interop.mitsuba import from_mitsuba
            _me.refuse_or_warn(self, from_mitsuba(d), [_me.MASKING_REASON.format(plugin="roughdielectric")],
                               approximate)
        return d


class ThinDielectric(BxDF):
    """Thin slab of dielectric (a window pane): specular reflection and straight-through
    transmission, with the inter-reflections inside the slab summed (pbrt-v4 ``ThinDielectricBxDF``).

    In spectral mode a dispersive slab never terminates wavelengths: both lobes keep their direction
    (mirror, straight through), the first wavelength chooses the lobe and f is that lobe's value
    per wavelength (pbrt-v4 terminates the secondaries for any non-constant eta).
    Both lobes are deltas; ``eval`` and ``pdf`` are 0.

    Parameters
    ----------
    eta : float or Spectrum, optional
        IOR of the slab (> 0; default 1.5), or a ``bsdfkit.Spectrum`` (its value at 550 nm in
        RGB mode).

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.ThinDielectric(1.5).albedo(bk.direction(0.0, 0.0), n_samples=1024)   # lossless
    array([1., 1., 1.])
    """

    __slots__ = ()

    aliases = ("thin",)
    description = "Thin slab of dielectric: specular reflection and straight transmission (pbrt-v4 ThinDielectricBxDF)"
    examples = {"window pane 1.5": "thin_dielectric 1.5", "dense 2.4": "thin_dielectric 2.4",
                "index matched": "thin_dielectric 1"}
    energy_conserving, exact_eval, two_sided, transmission, delta_only = True, True, True, True, True
    reciprocal = True
    mitsuba = "thindielectric"
    varying_params = {"eta": 1}

    def __init__(self, eta=1.5):
        """A ThinDielectric: the parameters are described in the class docstring (``help(bsdfkit.ThinDielectric)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        super().__init__(eta=_sp.spectrum_or_scalar(eta, "eta", lo=0.0, lo_open=True, varying=True))

    @classmethod
    def _from_params(cls, p):
        return cls(p["eta"])

    def _make_core(self):
        return _core.ThinDielectric(eta=_sp.scalar_of(self._params["eta"]))

    def _spectral_inputs(self) -> dict:
        return {"dispersive": _sp.is_dispersive(self._params["eta"])}

    def describe(self) -> str:
        return f"ThinDielectric η={_sp.fmt_param(self._params['eta'])}"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """``thindielectric`` with int_ior = eta (its value at 550 nm if a spectrum), ext_ior = 1;
        eta == 1 -> ``null``. Always exact (delta lobes only); ``approximate`` is accepted for
        uniformity with the other models."""
        self._refuse_varying("to_mitsuba")
        _me.check_approximate(approximate)
        eta = _sp.scalar_of(self.eta)
        return {"type": "null"} if eta == 1.0 else {"type": "thindielectric", "int_ior": eta, "ext_ior": 1.0}

