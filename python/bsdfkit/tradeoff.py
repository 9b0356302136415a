"""Deprecated: use :mod:`bsdfkit.tuning` (and :func:`bsdfkit.plot.pareto`).

``bsdfkit.tradeoff`` is the function :func:`bsdfkit.tuning.tradeoff`; this module, imported by
old code as ``bsdfkit.tradeoff``, is callable like it so that the name keeps working either way.
"""
import sys
import types

from ._deprecated import warn
from .plot._pareto import pareto  # noqa: F401
from .tuning import *  # noqa: F401,F403
from .tuning import configs as _configs, costs as _costs, errors as _errors, report as _report
from .tuning import tradeoff as _tradeoff

warn("the module bsdfkit.tradeoff", "bsdfkit.tuning (the function bsdfkit.tradeoff is unchanged)")


def __getattr__(name):
    for mod in (_configs, _errors, _costs, _report):
        if hasattr(mod, name):
            return getattr(mod, name)
    raise AttributeError(f"module 'bsdfkit.tradeoff' has no attribute {name!r}")


class _CallableModule(types.ModuleType):
    def __call__(self, *args, **kwargs):
        return _tradeoff(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
