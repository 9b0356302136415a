"""``difference(a, b)``: the relative difference of two models in the polar, hemisphere and
θh×θd views (what notebook 04 built by hand)."""
from __future__ import annotations

import numpy as np

from ..models.base import BxDF
from ..models.custom import Custom
from ..models.describe import describe

_VIEWS = ("polar", "hemisphere", "halfdiff")


def difference_model(a: BxDF, b: BxDF, floor: float = 1e-3) -> Custom:
    """A :class:`bsdfkit.Custom` whose value is the relative difference per channel
    ``|f_b - f_a| / max(|f_a|, floor * max f_a)``.

    Parameters
    ----------
    a : BxDF
        The reference.
    b : BxDF
        The model compared with it.
    floor : float, optional
        > 0, relative to ``a``'s largest value over the pair batch, so that near-zero regions do
        not explode (default 1e-3).

    Returns
    -------
    Custom
        A model whose "f" is the relative difference (any view can draw it).

    Raises
    ------
    TypeError
        ``a`` or ``b`` not a bsdfkit model.
    ValueError
        A floor <= 0.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> d = bkplot.difference_model(bk.Diffuse(0.5), bk.Diffuse(0.55))
    >>> d.eval(bk.direction(0.3, 0.0), bk.direction(0.6, 1.0)).round(6)
    array([0.1, 0.1, 0.1])
    """
    if not isinstance(a, BxDF) or not isinstance(b, BxDF):
        raise TypeError("a, b: expected two bsdfkit models")
    if not floor > 0:
        raise ValueError(f"floor: must be > 0, got {floor!r}")

    def rel(wo, wi):
        fa, fb = a.eval(wo, wi), b.eval(wo, wi)
        scale = floor * max(float(np.max(fa)) if fa.size else 0.0, 1e-300)
        return np.abs(fb - fa) / np.maximum(np.abs(fa), scale)
    transmission = bool((int(a.flags) | int(b.flags)) & 2)
    return Custom(f=rel, name="|f_b − f_a| / f_a", transmission=transmission)


def difference(a: BxDF, b: BxDF, view="polar", *, floor=1e-3, ax=None, **kwargs):
    """Plots the relative difference of ``b`` against the reference ``a`` in one view.

    The plotted value is :func:`difference_model`'s ``|f_b - f_a| / max(|f_a|, floor max f_a)``
    (1 = 100 %); delta lobes are not compared (eval reports them as 0). The colour bar / radius is
    labelled as that relative difference (dimensionless), not as f.

    Parameters
    ----------
    a : BxDF
        The reference.
    b : BxDF
        The model compared with it.
    view : {"polar", "hemisphere", "halfdiff"}, optional
        :func:`polar`, :func:`hemisphere` or :func:`halfdiff`.
    floor : float, optional
        As :func:`difference_model`'s.
    ax : matplotlib Axes, optional
        Where to draw.
    **kwargs
        Passed to the view (theta_o, channel, log, ...); ``cosine=True`` is refused (a ratio has
        no cosine factor).

    Returns
    -------
    matplotlib.axes.Axes
        The view's Axes.

    Raises
    ------
    ValueError
        An unknown view, ``cosine=True``, a floor <= 0.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> ax = bkplot.difference(bk.Conductor.from_metal("Cu", alpha=0.3),
    ...                        bk.Conductor.from_metal("Cu", alpha=0.3, fresnel="schlick"))
    >>> bool(max(v.max() for v in ax.bsdfkit_data["value"]) < 0.2)
    True
    """
    from ._halfdiff import halfdiff
    from ._hemisphere import hemisphere
    from ._polar import polar
    fns = {"polar": polar, "hemisphere": hemisphere, "halfdiff": halfdiff}
    if view not in fns:
        raise ValueError(f"view: must be one of {', '.join(map(repr, _VIEWS))}, got {view!r}")
    if kwargs.get("cosine"):
        raise ValueError("cosine: the relative difference |f_b - f_a| / f_a is the same with or without the "
                         "cosine factor; leave cosine unset")
    kwargs.pop("cosine", None)
    kwargs.setdefault("quantity", "|f_b − f_a| / f_a (relative, 1 = 100 %)")
    m = difference_model(a, b, floor)
    import textwrap
    kwargs.setdefault("title", "relative difference |f_b − f_a| / f_a\n" + "\n".join(
        textwrap.shorten(f"{k} = {describe(x)}", 70) for k, x in (("a", a), ("b", b))))
    return fns[view](m, ax=ax, **kwargs)
