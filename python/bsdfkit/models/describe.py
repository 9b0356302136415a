"""Short human-readable names of models (legend labels and titles): each class's ``describe()``."""
from __future__ import annotations

from .base import BxDF, fmt_value as _fmt  # noqa: F401  (_fmt: the plots' number format)

__all__ = ["describe"]


def describe(model: BxDF) -> str:
    """A short human-readable name of a model, e.g. ``"Conductor Au, α=0.2"`` (``model.describe()``)."""
    return model.describe()
