"""EON: the energy-preserving Oren-Nayar rough diffuse BRDF (OpenPBR Surface's base diffuse lobe)."""
from __future__ import annotations

from .. import _core
from . import _spectral as _sp
from ._mitsuba_export import check_approximate as _check_approximate
from .base import BxDF, _scalar, core_value

__all__ = ["EON"]


class EON(BxDF):
    """Energy-preserving Oren-Nayar rough diffuse reflection ("EON"; Portsmouth, Kutz & Hill 2025).

    The base diffuse lobe of OpenPBR Surface and MaterialX's ``oren_nayar_diffuse_bsdf`` with
    ``energy_compensation=true``: Fujii's form of the qualitative Oren-Nayar model plus an
    analytic, reciprocal multiple-scattering term that restores the energy the single-scattering
    lobe loses, so a white EON passes the furnace test at every roughness::

        f      = rho/pi A (1 + r s/t)  +  rho_ms/pi (1 - E(mu_o)) (1 - E(mu_i)) / (1 - E_avg)
        s      = wi . wo - mu_i mu_o,   t = max(mu_i, mu_o) if s > 0 else 1
        A      = 1 / (1 + (1/2 - 2/(3 pi)) r)
        E(mu)  = A (1 + r G(mu) / pi)          (the single-scattering lobe's albedo, closed form)
        E_avg  = A (1 + (2/3 - 28/(15 pi)) r)
        rho_ms = rho^2 E_avg / (1 - rho (1 - E_avg))

    The directional albedo is rho E(mu_o) + rho_ms (1 - E(mu_o)): exactly 1 for a white
    reflectance, <= 1 otherwise. Rough surfaces look flatter than Lambert (less darkening towards
    the silhouette) and scatter more light back towards the light, and their colour is slightly
    darker and more saturated than ``reflectance`` (the inter-reflections between facets).

    Parameters
    ----------
    reflectance : float, (3,) array_like or bsdfkit.Spectrum, default 0.5
        Single-scattering albedo rho (OpenPBR ``base_color``), scalar or RGB in [0, 1], or a
        ``bsdfkit.Spectrum`` with values in [0, 1].
    roughness : float, default 0.0
        Roughness r in [0, 1] (OpenPBR ``base_diffuse_roughness``; the paper's sigma, used as is).
        r = 0 is exactly Lambertian reflection (``bsdfkit.Diffuse``).

    Notes
    -----
    Sampling follows the paper: a mixture of uniform-hemisphere directions and its clipped
    linearly transformed cosine (CLTC) lobe; at r = 0 it is cosine-weighted sampling.
    Two-sided (a ``wo`` below the surface sees the mirrored material); reflection only;
    reciprocal. Spectral mode (``wavelengths=``): an RGB reflectance is uplifted (Jakob & Hanika
    2019, bounded) and f, including the nonlinear rho_ms, is evaluated per wavelength; RGB mode
    projects a spectrum to linear sRGB under D65. Mitsuba 3 has no equivalent plugin; the
    float64 reference is ``bsdfkit.testing.eon_ref``.

    References
    ----------
    J. Portsmouth, P. Kutz, S. Hill, "EON: A Practical Energy-Preserving Rough Diffuse BRDF",
    Journal of Computer Graphics Techniques 14(1), 2025 (arXiv:2410.18026). Y. Fujii, "A tiny
    improvement of Oren-Nayar reflectance model" (2013). OpenPBR Surface specification, "Glossy-
    diffuse" section.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m = bk.EON([0.8, 0.5, 0.2], roughness=0.6)
    >>> m.describe()
    'EON R=(0.8, 0.5, 0.2), r=0.6'
    """

    __slots__ = ()

    aliases = ("oren_nayar_eon",)   # "eon" is the class's own snake_case name
    description = "Energy-preserving Oren-Nayar rough diffuse reflection (EON, OpenPBR's base diffuse)"
    examples = {"grey, r 0.5": "eon 0.8 0.5", "orange, r 1": "eon 0.8,0.5,0.2 1",
                "smooth (Lambert)": "eon 0.5 0"}
    energy_conserving, exact_eval, two_sided, transmission, delta_only = True, True, True, False, False
    reciprocal = True
    mitsuba = None
    param_ranges = {"reflectance": (0.0, 1.0), "roughness": (0.0, 1.0)}  # fitting bounds (bk.fit)
    varying_params = {"reflectance": 3, "roughness": 1}

    def __init__(self, reflectance=0.5, roughness=0.0):
        """An EON: the parameters are described in the class docstring (``help(bsdfkit.EON)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        super().__init__(reflectance=_sp.spectrum_or_rgb(reflectance, "reflectance", lo=0.0, hi=1.0, varying=True),
                         roughness=_scalar(roughness, "roughness", lo=0.0, hi=1.0, varying=True))

    @classmethod
    def _from_params(cls, p):
        return cls(p["reflectance"], p["roughness"])

    def _make_core(self):
        return _core.EON(reflectance=core_value(_sp.rgb_of(self._params["reflectance"], "reflectance")),
                         roughness=self._params["roughness"])

    def describe(self) -> str:
        p = self._params
        return f"EON R={_sp.fmt_param(p['reflectance'])}, r={_sp.fmt_param(p['roughness'])}"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Raises NotImplementedError: Mitsuba 3 has no Oren-Nayar-type plugin."""
        _check_approximate(approximate)
        raise NotImplementedError(
            "Mitsuba 3 has no (energy-preserving) Oren-Nayar BSDF plugin; use "
            "bsdfkit.testing.eon_ref.eval as the reference")
