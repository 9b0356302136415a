"""Deprecated alias of :mod:`bsdfkit.models.spec` (the same module object)."""
import sys

from .models import spec as _target

sys.modules[__name__] = _target
