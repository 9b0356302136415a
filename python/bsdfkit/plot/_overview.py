"""Several views of one or more models side by side."""
from __future__ import annotations

import math

from ._common import _as_models, _check_choice, _new_figure, _quantity
from ._albedo import albedo
from ..models.describe import describe
from ._halfdiff import halfdiff
from ._hemisphere import hemisphere
from ._lobe3d import lobe3d
from ._polar import polar
from ._samples import samples

__all__ = ["VIEWS", "overview"]


#: The views of :func:`overview` (and of :func:`explore`), in their default order.
VIEWS = ("polar", "lobe3d", "hemisphere", "halfdiff", "albedo", "samples")


_PROJECTIONS = {"polar": "polar", "lobe3d": "3d"}


def overview(model_or_list, theta_o=30.0, phi_o=0.0, views=VIEWS, *, log=False, cosine=None, channel="luminance",
             fig=None, ncols=3, n_samples=100_000, albedo_samples=32768, albedo_theta=31, res=96, seed=0,
             title=None):
    """Several views of the same model(s) at one ``wo`` in one figure (the CLI ``lobes`` command,
    :func:`explore` and the notebooks use it).

    The polar slice is the plane of wo (its ``phi_plane = phi_o + 180``, so the mirror direction
    is at +θo).

    Parameters
    ----------
    model_or_list : BxDF or list of BxDF
        The model(s); several are overlaid, each in its own colour.
    theta_o, phi_o : float, optional
        wo's angle from the normal and azimuth, in degrees.
    views : sequence of str, optional
        Names from :data:`VIEWS` (default: all six).
    log : bool, optional
        Log scale in every view that has one.
    cosine : bool, optional
        f |cos θi| in every view that has it (None: f |cos| when a model is defined over the whole
        sphere with f divided by |cos| as Hair is, else f).
    channel : {"luminance", "r", "g", "b", "rgb"}, optional
        As in the views.
    fig : matplotlib Figure, optional
        A Figure to draw into (a new pyplot figure otherwise).
    ncols : int, optional
        Panels per row.
    n_samples : int, optional
        Samples of the sampling view.
    albedo_samples, albedo_theta : int, optional
        Samples per θo and θo count of the albedo view.
    res : int, optional
        Resolution of the image views.
    seed : int, optional
        Seed of the sampled views.
    title : str, optional
        The figure's title (default: the models' names and wo).

    Returns
    -------
    matplotlib.figure.Figure
        The Figure; ``fig.bsdfkit_axes`` maps each view name to its Axes (each with its
        ``bsdfkit_data``).

    Raises
    ------
    ValueError
        No view, or an unknown one.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> fig = bkplot.overview(bk.Plastic(0.5, alpha=0.2), views=("polar", "albedo"), albedo_samples=1024,
    ...                       albedo_theta=5)
    >>> sorted(fig.bsdfkit_axes)
    ['albedo', 'polar']
    """
    models = _as_models(model_or_list)
    if cosine is None:
        cosine = any(getattr(m, "full_sphere", False) for m in models)
    views = tuple(views)
    for v in views:
        _check_choice(v, "views", VIEWS)
    if not views:
        raise ValueError("views: name at least one view")
    ncols = max(1, min(ncols, len(views)))
    nrows = math.ceil(len(views) / ncols)
    if fig is None:
        fig = _new_figure((5.6 * ncols, 4.9 * nrows))
    else:
        fig.set_layout_engine("constrained")
    fig.get_layout_engine().set(w_pad=0.08, wspace=0.06, h_pad=0.08)
    # Legends and colorbars get short labels ("A: Conductor Au, α=0.2", cut at 40 characters);
    # the full descriptions go to the title, wrapped: long model names then keep the layout.
    import textwrap
    full = [describe(m) for m in models]
    if len(models) > 1:
        labels = [f"{chr(65 + i % 26)}: {textwrap.shorten(d, 40, placeholder=' …')}" for i, d in enumerate(full)]
    else:
        labels = [textwrap.shorten(full[0], 40, placeholder=" …")]
    axes = {}
    for i, v in enumerate(views):
        ax = fig.add_subplot(nrows, ncols, i + 1, projection=_PROJECTIONS.get(v))
        axes[v] = ax
        if v == "polar":
            polar(models, label=labels, theta_o=theta_o, phi_plane=phi_o + 180.0, log=log, cosine=cosine, channel=channel, ax=ax,
                  title=f"in-plane slice, {_quantity(cosine)}{' (log)' if log else ''}\nvs θi [°] (plane of ωo)",
                  legend=len(models) > 1)
        elif v == "lobe3d":
            lobe3d(models, label=labels, theta_o=theta_o, phi_o=phi_o, log=log, cosine=cosine, channel=channel, ax=ax,
                   n_theta=31, n_phi=61, legend=len(models) > 1)
        elif v == "hemisphere":
            hemisphere(models, label=labels, theta_o=theta_o, phi_o=phi_o, log=log, cosine=cosine, channel=channel, ax=ax,
                       res=res, legend=True,
                       title=f"{_quantity(cosine)} over ωi{' (log)' if log else ''}, disks seen from above")
        elif v == "halfdiff":
            halfdiff(models, label=labels, log=True, cosine=cosine, channel=channel, ax=ax, res=res,
                     title=f"{_quantity(cosine)} (log), θh × θd at φd = 90°")
        elif v == "albedo":
            albedo(models, label=labels, n_theta=albedo_theta, n_samples=albedo_samples, channel=channel, ax=ax, seed=seed,
                   title=f"directional albedo (radiance mode, {albedo_samples} samples per θo)\ndashed: white furnace ρ = 1, "
                         f"dotted: θo = {theta_o:g}°", legend=len(models) > 1)
            ax.axvline(min(theta_o, 90.0), color="k", ls=":", lw=1.0)
        elif v == "samples":
            samples(models, label=labels, theta_o=theta_o, phi_o=phi_o, n=n_samples, seed=seed, ax=ax,
                    title=f"sampling: histogram vs pdf ({n_samples:,} samples)".replace(",", " "))
    if title is None:
        names = ([f"{lab.split(':')[0]} = {d}" for lab, d in zip(labels, full)] if len(models) > 1 else full)
        width = max(60, int(fig.get_figwidth() * 12))
        title = ("\n".join(textwrap.fill(n, width, subsequent_indent="    ") for n in names)
                 + f"\nωo at θo = {theta_o:g}°, φo = {phi_o:g}°  ({channel}{', log' if log else ''}"
                 + f"{', ×cos' if cosine else ''})")
    if title:
        fig.suptitle(title, fontsize="large")
    fig.bsdfkit_axes = axes
    return fig
