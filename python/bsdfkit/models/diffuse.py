"""Lambertian models: pbrt-v4's DiffuseBxDF and DiffuseTransmissionBxDF."""
from __future__ import annotations

from .. import _core
from . import _spectral as _sp
from ._mitsuba_export import check_approximate as _check_approximate
from .base import BxDF, core_value, rgb_dict

__all__ = ["Diffuse", "DiffuseTransmission"]


class Diffuse(BxDF):
    """Lambertian reflection, f = reflectance / pi on wo's side (pbrt-v4 ``DiffuseBxDF``).

    Two-sided. Spectral mode (``wavelengths=``): an RGB reflectance is uplifted (Jakob & Hanika
    2019, bounded); RGB mode: a spectrum is projected to linear sRGB under D65.

    Parameters
    ----------
    reflectance : float or RGB or Spectrum, optional
        Scalar or RGB in [0, 1], or a ``bsdfkit.Spectrum`` with values in [0, 1] (default 0.5).

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> m = bk.Diffuse([0.8, 0.4, 0.2])
    >>> m.eval(bk.direction(0.3, 0.0), bk.direction(1.0, 2.0)) * np.pi
    array([0.8, 0.4, 0.2])
    """

    __slots__ = ()

    aliases = ("lambert",)
    description = "Lambertian reflection (pbrt-v4 DiffuseBxDF)"
    examples = {"grey 0.8": "diffuse 0.8", "orange": "diffuse 0.8,0.5,0.2", "black": "diffuse 0"}
    energy_conserving, exact_eval, two_sided, transmission, delta_only = True, True, True, False, False
    reciprocal = True
    mitsuba = "diffuse"
    param_ranges = {"reflectance": (0.0, 1.0)}  # fitting bounds (bk.fit)
    varying_params = {"reflectance": 3}

    def __init__(self, reflectance=0.5):
        """A Diffuse: the parameters are described in the class docstring (``help(bsdfkit.Diffuse)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        super().__init__(reflectance=_sp.spectrum_or_rgb(reflectance, "reflectance", lo=0.0, hi=1.0, varying=True))

    @classmethod
    def _from_params(cls, p):
        return cls(p["reflectance"])

    def _make_core(self):
        return _core.Diffuse(reflectance=core_value(_sp.rgb_of(self._params["reflectance"], "reflectance")))

    def describe(self) -> str:
        return f"Diffuse R={_sp.fmt_param(self._params['reflectance'])}"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """``twosided{diffuse}`` with the RGB reflectance (a spectrum's RGB value, as RGB mode
        uses). Always exact; ``approximate`` is accepted for uniformity."""
        self._refuse_varying("to_mitsuba")
        _check_approximate(approximate)
        r = _sp.rgb_of(self.reflectance, "reflectance")
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": rgb_dict(r)}}



class DiffuseTransmission(BxDF):
    """Lambertian reflection plus Lambertian transmission (pbrt-v4 ``DiffuseTransmissionBxDF``).

    f = reflectance / pi on wo's side, transmittance / pi across the surface. Each RGB in [0, 1]
    or a ``bsdfkit.Spectrum`` in [0, 1]. Lobes are sampled in proportion to their largest channel
    (in spectral mode: their largest value over the 4 wavelengths, as pbrt-v4).

    Parameters
    ----------
    reflectance, transmittance : float or RGB or Spectrum, optional
        Each scalar or RGB in [0, 1], or a ``bsdfkit.Spectrum`` in [0, 1] (default 0.25 each).

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> m = bk.DiffuseTransmission(0.3, 0.5)
    >>> m.eval(bk.direction(0.3, 0.0), -bk.direction(0.5, 1.0)) * np.pi   # across the surface
    array([0.5, 0.5, 0.5])
    """

    __slots__ = ()

    aliases = ("difftrans",)
    description = "Lambertian reflection plus Lambertian transmission (pbrt-v4 DiffuseTransmissionBxDF)"
    examples = {"R 0.5, T 0.4": "difftrans 0.5 0.4", "coloured": "difftrans 0.3,0.5,0.1 0.6,0.2,0.4",
                "transmission only": "difftrans 0 0.7", "reflection only": "difftrans 0.6 0"}
    energy_conserving, exact_eval, two_sided, transmission, delta_only = True, True, True, True, False
    reciprocal = True
    mitsuba = None
    param_ranges = {"reflectance": (0.0, 1.0), "transmittance": (0.0, 1.0)}  # fitting bounds (bk.fit)
    varying_params = {"reflectance": 3, "transmittance": 3}

    def __init__(self, reflectance=0.25, transmittance=0.25):
        """A DiffuseTransmission: the parameters are described in the class docstring (``help(bsdfkit.DiffuseTransmission)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        super().__init__(reflectance=_sp.spectrum_or_rgb(reflectance, "reflectance", lo=0.0, hi=1.0, varying=True),
                         transmittance=_sp.spectrum_or_rgb(transmittance, "transmittance", lo=0.0, hi=1.0,
                                                           varying=True))

    @classmethod
    def _from_params(cls, p):
        return cls(p["reflectance"], p["transmittance"])

    def _make_core(self):
        p = self._params
        return _core.DiffuseTransmission(reflectance=core_value(_sp.rgb_of(p["reflectance"], "reflectance")),
                                         transmittance=core_value(_sp.rgb_of(p["transmittance"], "reflectance")))

    def describe(self) -> str:
        p = self._params
        return f"DiffuseTransmission R={_sp.fmt_param(p['reflectance'])}, T={_sp.fmt_param(p['transmittance'])}"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Raises NotImplementedError: Mitsuba 3 has no diffuse-transmission plugin."""
        _check_approximate(approximate)
        raise NotImplementedError(
            "Mitsuba 3 has no diffuse-transmission BSDF plugin; use "
            "bsdfkit.testing.drjit_models.diffuse_transmission_f_pdf as the reference")

