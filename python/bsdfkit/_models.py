"""Deprecated: the model classes live in :mod:`bsdfkit.models` (import them from ``bsdfkit``)."""
from ._deprecated import warn
from .models.base import BxDF, SampleResult, _rgb, _scalar, roughness_to_alpha  # noqa: F401
from .models.conductor import METALS, Conductor, conductor_fresnel  # noqa: F401
from .models.dielectric import Dielectric, ThinDielectric  # noqa: F401
from .models.diffuse import Diffuse, DiffuseTransmission  # noqa: F401

warn("bsdfkit._models", "bsdfkit.models")
