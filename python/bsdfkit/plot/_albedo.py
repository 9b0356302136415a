"""Directional albedo curves."""
from __future__ import annotations

import numpy as np

from .._validate import check_mode as _mode
from .._enums import TransportMode
from ._common import _RGB_COLORS, _RGB_STYLES, _as_labels, _as_models, _check_channel, _new_axes, _select
from ..models.describe import describe

__all__ = ["albedo"]


def albedo(model_or_list, n_theta=46, n_samples=8192, ax=None, channel="luminance", label=None, *,
           seed=0, mode=TransportMode.Radiance, title=None, legend=True, colors=None, linestyle="-"):
    """Directional albedo ρ(θo) = ∫ f |cos θi| dωi against θo (degrees, 0 to 89.5) with a dashed
    white-furnace line at 1.

    Monte Carlo with ``n_samples`` importance samples each (``BxDF.albedo``). Radiance-mode albedo
    of a dielectric includes the 1/η² radiance scaling of transmission; pass
    ``mode=bk.TransportMode.Importance`` for the energy balance.

    Parameters
    ----------
    model_or_list : BxDF or list of BxDF
        The model(s); several are overlaid, each in its own colour.
    n_theta : int, optional
        Equally spaced θo (the last one clamped to 89.5° to stay off the horizon).
    n_samples : int, optional
        Importance samples per θo.
    ax : matplotlib Axes, optional
        Axes to draw into (created if None).
    channel : {"luminance", "r", "g", "b", "rgb"}, optional
        Luminance, one channel, or three curves per model.
    label : str or list of str, optional
        Legend label(s) (default: ``model.describe()``).
    seed : int, optional
        Seed of the samples.
    mode : TransportMode, optional
        Passed to ``eval`` / ``sample`` (default Radiance).
    title : str, optional
        None: an automatic title; "": none.
    legend : bool, optional
        Draw the legend.
    colors : list, optional
        One colour per model.
    linestyle : str, optional
        Line style.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes; ``ax.bsdfkit_data`` holds per-model lists ``theta_deg``, ``value``
        ((n_theta,) or (n_theta, 3)), ``rgb`` ((n_theta, 3)), ``label``, ``model``, plus
        ``channel``, ``mode``; and the scalar ``n_samples`` (of the first call).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> ax = bkplot.albedo(bk.Diffuse(0.5), n_theta=4, n_samples=1024)
    >>> [round(float(v), 2) for v in ax.bsdfkit_data["value"][0]]
    [0.5, 0.5, 0.5, 0.5]
    """
    models = _as_models(model_or_list)
    labels = _as_labels(label, len(models))
    channel = _check_channel(channel)
    if isinstance(n_theta, bool) or not isinstance(n_theta, (int, np.integer)) or n_theta < 2:
        raise ValueError(f"n_theta: expected an integer >= 2, got {n_theta!r}")
    if ax is None:
        ax = _new_axes(False)
    elif getattr(ax, "name", None) == "polar":
        raise ValueError("ax: albedo() needs a rectilinear Axes, not a polar one")

    theta_deg = np.minimum(np.linspace(0.0, 90.0, int(n_theta)), 89.5)
    wo = np.stack([np.sin(np.radians(theta_deg)), np.zeros_like(theta_deg), np.cos(np.radians(theta_deg))], -1)

    data = getattr(ax, "bsdfkit_data", None)
    first = not (isinstance(data, dict) and data.get("kind") == "albedo")
    if first:
        data = dict(kind="albedo", theta_deg=[], value=[], rgb=[], label=[], model=[], channel=[], mode=[],
                    n_samples=int(n_samples))
    ymax = 1.0
    for j, (m, lab) in enumerate(zip(models, labels)):
        k = len(data["model"])
        color = colors[j] if colors is not None else f"C{k % 10}"
        lab = lab if lab is not None else describe(m)
        rgb = m.albedo(wo, n_samples=n_samples, seed=seed, mode=_mode(mode))
        val = _select(rgb, channel)
        if channel == "rgb":
            style = _RGB_STYLES[k % len(_RGB_STYLES)]
            for c in range(3):
                ax.plot(theta_deg, val[:, c], color=_RGB_COLORS[c], ls=style, lw=1.5, label=f"{lab} [{'RGB'[c]}]")
        else:
            ax.plot(theta_deg, val, color=color, ls=linestyle, lw=1.8, label=lab)
        ymax = max(ymax, float(np.max(val)))
        for key, v in (("theta_deg", theta_deg), ("value", val), ("rgb", rgb), ("label", lab), ("model", m),
                       ("channel", channel), ("mode", TransportMode(_mode(mode)))):
            data[key].append(v)

    if first:
        ax.axhline(1.0, color="0.2", ls="--", lw=1.0, zorder=1.5, label="white furnace (ρ = 1)")
    ax.set_xlim(0, 90)
    ax.set_xticks(np.arange(0, 91, 15))
    lo, hi = ax.get_ylim()
    ax.set_ylim(0.0, max(hi if not first else 0.0, ymax * 1.08, 1.08))
    ax.set_xlabel("θo, angle of ωo from the normal [°]")
    ax.set_ylabel("directional albedo ρ(θo) [unitless]")
    ax.grid(True, alpha=0.3)
    mname = TransportMode(_mode(mode)).name.lower()
    if title is None:
        title = f"Directional albedo ({channel}, {mname} mode, {n_samples} samples per θo)"
        refr = any(int(m.flags) & 2 and getattr(m, "eta", 1.0) != 1.0 and type(m).__name__ == "Dielectric"
                   for m in models)
        if refr and mname == "radiance":
            title += "\nrefraction scales radiance by 1/η²: glass < 1 (mode='importance': ρ = 1)"
    if title:
        ax.set_title(title, fontsize="medium")
    if legend:
        ax.legend(fontsize="small", loc="lower left")
    ax.bsdfkit_data = data
    return ax
