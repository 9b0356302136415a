"""Deprecated alias of :mod:`bsdfkit.models.spec` (the same module object)."""
import sys

from ._deprecated import warn
from .models import spec as _target

warn("bsdfkit._spec", "bsdfkit.models.spec")

sys.modules[__name__] = _target
