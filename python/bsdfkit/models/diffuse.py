"""Lambertian models: pbrt-v4's DiffuseBxDF and DiffuseTransmissionBxDF."""
from __future__ import annotations

from .. import _core
from .base import BxDF, _rgb

__all__ = ["Diffuse", "DiffuseTransmission"]


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
