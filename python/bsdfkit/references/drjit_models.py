"""Deprecated alias of :mod:`bsdfkit.testing.drjit_models` (the same module object)."""
import sys

from ..testing import drjit_models as _target

sys.modules[__name__] = _target
