"""Deprecated alias of :mod:`bsdfkit.testing.mitsuba` (the same module object)."""
import sys

from ..testing import mitsuba as _target

sys.modules[__name__] = _target
