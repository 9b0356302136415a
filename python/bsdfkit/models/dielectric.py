"""Dielectric interfaces: pbrt-v4's DielectricBxDF (smooth or rough) and ThinDielectricBxDF."""
from __future__ import annotations

from .. import _core
from .base import BxDF, _MASKING, _alphas, _masking, _scalar

__all__ = ["Dielectric", "ThinDielectric"]


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
