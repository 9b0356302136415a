"""Deprecated alias of :mod:`bsdfkit.testing.drjit_filament` (the same module object)."""
import sys

from ..testing import drjit_filament as _target

sys.modules[__name__] = _target
