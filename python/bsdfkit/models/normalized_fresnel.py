"""The normalized-Fresnel exit lobe of a BSSRDF boundary (pbrt-v4 ``NormalizedFresnelBxDF``)."""
from __future__ import annotations

from .. import _core
from . import _spectral as _sp
from .base import BxDF, _scalar

__all__ = ["NormalizedFresnel", "fresnel_moment1"]


def fresnel_moment1(eta) -> float:
    """pbrt-v4's ``FresnelMoment1(eta)`` polynomial. Its convention: it fits
    int_0^1 Fr(mu, 1/eta) mu dmu, with Fr the dielectric reflectance for relative IOR 1/eta (checked
    against quadrature in the tests; about 1e-4 absolute)."""
    return _core.fresnel_moment1(_scalar(eta, "eta", lo=0.0, lo_open=True))


class NormalizedFresnel(BxDF):
    """Light leaving a subsurface-scattering boundary (pbrt-v4 ``NormalizedFresnelBxDF``; the S_w
    term of Jensen et al. 2001 / d'Eon & Irving 2011):

    f = (1 - Fr(cos wi, eta)) / (c pi),   c = 1 - 2 FresnelMoment1(1 / eta) = 1 - 2 int_0^1 Fr(mu, eta) mu dmu,

    on wo's side, 0 across; cos wi is signed as in pbrt-v4 (below the surface Fr uses 1 / eta).
    In Radiance mode f is multiplied by eta^2 (pbrt-v4's adjoint correction), so for wo above
    the surface the albedo would be 1 in Importance mode and eta^2 in Radiance mode if c were
    exact. It is pbrt-v4's polynomial fit of FresnelMoment1, so the albedo is only close to 1:
    within 2e-4 for eta in [1.05, 2.5], 6e-4 at eta = 3, and up to 0.4 % off for eta < 1 (wo in
    the denser medium: measured 0.998 .. 1.004 over eta = 0.5 .. 0.95, 1.004 at eta = 0.5), where
    the fit is worst. Cosine-weighted sampling. eta > 0.

    eta may be a ``bsdfkit.Spectrum`` (e.g. ``Spectrum.named("glass-BK7")``): in spectral mode
    (``wavelengths=``) f uses eta(lambda) per wavelength (c and the eta^2 factor too); RGB mode
    uses its value at 550 nm. The sampling does not depend on eta.

    Parameters
    ----------
    eta : float or Spectrum, optional
        Relative IOR of the boundary (> 0; default 1.33).

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> rho = bk.NormalizedFresnel(1.33).albedo(bk.direction(0.5, 0.0), mode="importance")
    >>> bool(abs(rho[0] - 1) < 0.01)
    True
    """

    __slots__ = ()
    aliases = ("bssrdf_exit",)
    examples = {"skin": "normalized_fresnel eta=1.4", "water": "normalized_fresnel eta=1.33"}
    description = "BSSRDF exit lobe (1 - Fr) / (c pi) of pbrt-v4"
    energy_conserving = True   # albedo 1 in Importance mode (eta^2 in Radiance mode: the adjoint factor)
    exact_eval = True
    reciprocal = False         # f depends on wi only, through Fr(cos wi)
    two_sided = True
    transmission = False
    delta_only = False
    mitsuba = None
    knobs = ()                 # no accuracy setting (FresnelMoment1 is pbrt-v4's fixed polynomial)
    varying_params = {"eta": 1}

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Raises NotImplementedError: Mitsuba 3 has no normalized-Fresnel plugin."""
        from ._mitsuba_export import check_approximate
        check_approximate(approximate)
        raise NotImplementedError("Mitsuba 3 has no normalized-Fresnel (BSSRDF exit) plugin; use "
                                  "bsdfkit.testing.hair_ref.normalized_fresnel_f as the reference")

    def __init__(self, eta=1.33):
        """A NormalizedFresnel: the parameters are described in the class docstring (``help(bsdfkit.NormalizedFresnel)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        super().__init__(eta=_sp.spectrum_or_scalar(eta, "eta", lo=0.0, lo_open=True, varying=True))

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def __repr__(self):
        from .base import fmt_param
        return f"NormalizedFresnel(eta={fmt_param(self._params['eta'])})"

    def _make_core(self):
        return _core.NormalizedFresnel(eta=_sp.scalar_of(self._params["eta"]))
