"""One row of views per model: the gallery of registered models."""
from __future__ import annotations

import numpy as np

from ._common import _as_models
from ._albedo import albedo
from ..models.describe import describe
from ._hemisphere import hemisphere
from ._polar import polar

__all__ = ["gallery"]


def gallery(models=None, theta_o=40.0, *, fig=None, res=96, albedo_samples=16384, albedo_theta=31, row_height=4.4):
    """One row per model — in-plane polar slice, hemisphere image, directional albedo (RGB and
    luminance) — at ``theta_o`` (degrees).

    Parameters
    ----------
    models : list of BxDF, optional
        The models; None: the first registered example of every class in ``bsdfkit.MODELS``
        (``bsdfkit.models.spec.example_model``; the registry refuses a class without examples, so
        the gallery never silently skips a model).
    theta_o : float, optional
        wo's angle from the normal, degrees.
    fig : matplotlib Figure, optional
        A Figure to draw into (a new pyplot figure otherwise).
    res : int, optional
        Resolution of the hemisphere images.
    albedo_samples, albedo_theta : int, optional
        Samples per θo and θo count of the albedo curves.
    row_height : float, optional
        Inches per row.

    Returns
    -------
    matplotlib.figure.Figure
        The Figure; ``fig.bsdfkit_rows`` is a list of ``(model, {"polar": ax, "hemisphere": ax,
        "albedo": ax})``.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> fig = bkplot.gallery([bk.Diffuse(0.5), bk.Dielectric(1.5)], res=24, albedo_samples=512, albedo_theta=4)
    >>> len(fig.bsdfkit_rows)
    2
    """
    if models is None:
        from ..models import MODELS
        from ..models.spec import example_model

        models = [example_model(cls) for cls in MODELS]
    models = _as_models(models)
    n = len(models)
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(17.0, row_height * n + 1.3))
    w, h = fig.get_size_inches()
    # fixed margins: constrained layout with many polar Axes triples the drawing time
    fig.subplots_adjust(left=0.45 / w, right=1 - 0.55 / w, top=1 - 1.3 / h, bottom=0.55 / h, wspace=0.35,
                        hspace=0.55)
    rows = []
    for i, m in enumerate(models):
        name = describe(m)
        a_p = fig.add_subplot(n, 3, 3 * i + 1, projection="polar")
        polar(m, theta_o=theta_o, ax=a_p, legend=False, title=f"{name}\nf [1/sr] vs θi [°], plane of ωo")
        a_h = fig.add_subplot(n, 3, 3 * i + 2)
        hemisphere(m, theta_o=theta_o, ax=a_h, res=res, title=f"{name}\nf [1/sr] over ωi (seen from above)")
        a_a = fig.add_subplot(n, 3, 3 * i + 3)
        gray = all(np.ptp(np.asarray(v)) == 0 for v in m._params.values() if isinstance(v, np.ndarray))
        if not gray:
            albedo(m, ax=a_a, n_samples=albedo_samples, n_theta=albedo_theta, channel="rgb", label="", legend=False,
                   title="")
        albedo(m, ax=a_a, n_samples=albedo_samples, n_theta=albedo_theta, label="luminance", colors=["k"],
               legend=False, title=f"{name}\ndirectional albedo ({albedo_samples} samples per θo)")
        handles, labels = a_a.get_legend_handles_labels()
        a_a.legend(handles, [lab.strip(" []") for lab in labels], fontsize="x-small", loc="lower left",
                   ncol=2)
        a_a.axvline(theta_o, color="k", ls=":", lw=1.0)
        rows.append((m, {"polar": a_p, "hemisphere": a_h, "albedo": a_a}))
    fig.suptitle(f"Every model at θo = {theta_o:g}°: in-plane slice (dashed: ωo), f over directions "
                 "(reflection and transmission disks),\ndirectional albedo (dashed: white furnace ρ = 1)",
                 fontsize="x-large", y=1 - 0.12 / h, va="top")
    fig.bsdfkit_rows = rows
    return fig
