"""Short human-readable names of models (legend labels and titles): each class's ``describe()``."""
from __future__ import annotations

from .base import BxDF, fmt_value as _fmt  # noqa: F401  (_fmt: the plots' number format)

__all__ = ["describe"]


def describe(model: BxDF) -> str:
    """A short human-readable name of a model (``model.describe()``): legend labels and titles.

    Parameters
    ----------
    model : BxDF
        Any model.

    Returns
    -------
    str
        E.g. ``"Conductor Au, α=0.2"``.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> bkplot.describe(bk.Dielectric(1.5, alpha=0.1))
    'Dielectric η=1.5, α=0.1'
    """
    return model.describe()
