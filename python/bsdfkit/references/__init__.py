"""Deprecated: the test references moved to :mod:`bsdfkit.testing` (same submodules)."""
from .._deprecated import warn
from ..testing import *  # noqa: F401,F403
from ..testing import _configure_llvm_env, _drjit_backend  # noqa: F401

warn("bsdfkit.references", "bsdfkit.testing")
