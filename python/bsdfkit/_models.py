"""Deprecated: the model classes live in :mod:`bsdfkit.models` (import them from ``bsdfkit``)."""
from ._deprecated import warn
from .models.base import (_MASKING, BxDF, SampleResult, _alphas, _masking, _mode, _pick_alpha, _raise_bad,  # noqa: F401
                          _rebuild, _rgb, _scalar, _sflags, roughness_to_alpha)
from .models.conductor import METALS, Conductor, conductor_fresnel  # noqa: F401
from .models.dielectric import Dielectric, ThinDielectric  # noqa: F401
from .models.diffuse import Diffuse, DiffuseTransmission  # noqa: F401

warn("bsdfkit._models", "bsdfkit.models")
