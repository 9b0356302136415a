"""Deprecated alias of :mod:`bsdfkit.testing.mitsuba_scene` (the same module object)."""
import sys

from ..testing import mitsuba_scene as _target

sys.modules[__name__] = _target
