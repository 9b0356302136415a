"""Hemisphere images of f (disk or theta-phi projection)."""
from __future__ import annotations

import math

import numpy as np

from .._enums import BxDFFlags, TransportMode
from ._common import (_SIDES, _as_labels, _as_models, _check_channel, _check_choice, _check_int, _colorbar,
                      _contours, _disk_grid, _finite, _fmt, _new_figure, _note_all_zero, _positive_max,
                      _project, _quantity, _scalar_image, _select, _set_data, _side_signs, _thetaphi_grid,
                      _transmits, _values, _wo_dir, luminance)
from ..models.describe import describe
from ._polar import _delta_lobes, _weak_half

__all__ = ["hemisphere"]


def hemisphere(model_or_list, theta_o=30.0, phi_o=0.0, projection="disk", log=False, cosine=False,
               channel="luminance", ax=None, res=121, label=None, *, side="auto", title=None, legend=True,
               colorbar=True, cmap="inferno", log_decades=4.0, mode=TransportMode.Radiance, n_delta=4096, seed=0,
               magnify_below=0.04, quantity=None):
    """Image of ``f(wo, wi)`` (or ``f |cos θi|`` with ``cosine=True``) over every direction wi.

    ``wo = bk.direction(radians(theta_o), radians(phi_o))`` (degrees in, marked "ωo"; its mirror
    direction, azimuth ``phi_o + 180``, is marked "+"). A list of models: the first is drawn as the
    image, every model as iso-value lines in its colour (shared levels, in the legend). Delta
    (specular) lobes, which ``eval`` reports as 0, are marked with a star and their
    reflectance/transmittance.

    Parameters
    ----------
    model_or_list : BxDF or list of BxDF
        The model(s); several are overlaid, each in its own colour.
    theta_o, phi_o : float, optional
        wo's angle from the normal and azimuth, in degrees.
    projection : {"disk", "theta_phi"}, optional
        ``"disk"``: azimuthal equidistant disk seen from above (+z): a direction at angle θ from
        the side's pole (+z for the upper, -z for the lower hemisphere) and azimuth φ is drawn at
        ``(θ cos φ, θ sin φ)`` degrees, so circles are 30°, 60°, 90° from the normal. With
        ``side="both"`` the transmission disk is drawn right of the reflection disk (centre at
        x = 200°). ``"theta_phi"``: a latitude-longitude image, φ (0..360°) across and θ from +z
        (0..90°, or 0..180° with transmission) down.
    log : bool, optional
        Logarithmic colour scale spanning ``log_decades`` decades below the maximum.
    cosine : bool, optional
        Plot ``f |cos θi|`` instead of ``f``.
    channel : {"luminance", "r", "g", "b", "rgb"}, optional
        Luminance (0.2126 R + 0.7152 G + 0.0722 B), one channel, or all three.
        "rgb" is an RGB image scaled so that the maximum is white.
    ax : matplotlib Axes, optional
        Axes to draw into (created if None).
    res : int, optional
        Pixels across.
    label : str or list of str, optional
        Legend label(s) (default: ``model.describe()``).
    title : str, optional
        None: a title stating what is plotted; "" : none.
    legend : bool, optional
        Draw the legend.
    side : {"auto", "reflection", "transmission", "both"}, optional
        ``"auto"``: ``"both"`` when some model transmits, else ``"reflection"`` (wo's hemisphere).
    colorbar : bool, optional
        Draw the colour bar.
    cmap : str, optional
        Matplotlib colour map.
    log_decades : float, optional
        Decades shown on a log scale.
    mode : TransportMode, optional
        Passed to ``eval`` / ``sample`` (default Radiance).
    n_delta : int, optional
        Samples estimating each delta lobe's reflectance / transmittance.
    seed : int, optional
        Seed of those samples.
    magnify_below : float, optional
        On a linear scale with both sides shown, when the weaker side of the (first) model peaks
        below this fraction of the stronger one, its colours are scaled by a round factor (said
        above that disk; the data stay unscaled); 0 or None turns this off.
    quantity : str, optional
        The label of the plotted value with its unit (default ``"f [1/sr]"`` or
        ``"f·|cos θi| [1/sr]"``; :func:`difference` gives its relative difference's).

    Returns
    -------
    matplotlib.axes.Axes
        The Axes; ``ax.bsdfkit_data`` has ``value`` (list, per model, (H, W) or (H, W, 3), NaN
        outside the projection), ``wi`` ((H, W, 3), NaN outside), ``wo``, ``x``, ``y`` (pixel
        centres, degrees), ``extent``, ``projection``, ``sides`` (+1 upper / -1 lower hemisphere),
        ``label``, ``model``, ``delta`` (per model, as in :func:`polar`), ``vmax``, ``cosine``,
        ``channel``, ``log``, ``levels`` (contour levels, when overlaid).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> ax = bkplot.hemisphere(bk.Dielectric(1.5, alpha=0.3), theta_o=30, res=48)
    >>> [int(s) for s in ax.bsdfkit_data["sides"]]   # both hemispheres: it transmits
    [1, -1]
    """
    models = _as_models(model_or_list)
    labels = _as_labels(label, len(models))
    channel = _check_channel(channel)
    projection = _check_choice(projection, "projection", ("disk", "theta_phi"))
    side = _check_choice(side, "side", _SIDES)
    theta_o, phi_o = _finite(theta_o, "theta_o"), _finite(phi_o, "phi_o")
    res = _check_int(res, "res", 8)
    if ax is None:
        ax = _new_figure((8.8 if (side == "both" or (side == "auto" and _transmits(models))) and
                          projection == "disk" else 6.4, 4.6)).add_subplot()
    elif getattr(ax, "name", None) != "rectilinear":
        raise ValueError("ax: hemisphere() needs a rectilinear Axes")
    wo = _wo_dir(theta_o, phi_o)
    side, signs = _side_signs(side, models, wo)
    if projection == "disk":
        xs, ys, wi, extent = _disk_grid(res, signs)
        origin, aspect = "lower", "equal"
    else:
        xs, ys, wi, extent = _thetaphi_grid(res, signs)
        origin, aspect = "upper", "auto"

    entries = []
    for m, lab in zip(models, labels):
        val = _values(m, wo, wi, cosine, channel, mode)
        delta = []
        if m.flags & BxDFFlags.Specular:
            xdir = np.array([math.cos(math.radians(phi_o)), math.sin(math.radians(phi_o)), 0.0])
            for lobe in _delta_lobes(m, wo, xdir, n_delta, seed, mode):
                lobe["value"] = _select(lobe["weight"], channel)
                delta.append(lobe)
        entries.append(dict(model=m, label=lab if lab is not None else describe(m), value=val, delta=delta))
    vmax = _positive_max([entries[0]["value"]])            # the image: first model
    vmax_all = _positive_max([e["value"] for e in entries])  # the iso-lines: every model

    # a side (reflection / transmission) far weaker than the other is shown magnified by a round factor
    shown = entries[0]["value"]
    magnified = None
    if len(signs) == 2 and not log and magnify_below:
        lum0 = shown if shown.ndim == 2 else luminance(shown)
        zs = np.nan_to_num(wi[..., 2]) * signs[0]
        mag = _weak_half(np.nan_to_num(lum0).ravel(), zs.ravel(), magnify_below)
        if mag is not None:
            magnified = mag
            keep = (zs > 0) if mag[0] == "reflection" else (zs < 0)
            shown = np.where(keep[..., None] if shown.ndim == 3 else keep, shown * mag[1], shown)
    im, _ = _scalar_image(ax, shown, extent, log=log, log_decades=log_decades, vmax=vmax,
                          cmap=cmap, origin=origin, aspect=aspect, channel=channel)
    if projection == "disk":   # round disks instead of pixel staircases at their rims
        from matplotlib.patches import PathPatch
        from matplotlib.path import Path

        clip = PathPatch(Path.make_compound_path(*[Path.circle((200.0 * k, 0.0), 90.0) for k in range(len(signs))]),
                         transform=ax.transData, fc="none", ec="none")
        ax.add_patch(clip)
        ax.images[-1].set_clip_path(clip)
    handles = []
    levels = None
    if len(entries) > 1:
        levels = _contours(ax, entries, xs, ys, log=log, log_decades=log_decades, vmax=vmax_all, handles=handles)

    from matplotlib.lines import Line2D

    # guides: angle circles (disk) or the horizon (theta_phi), ωo, the mirror direction, delta lobes
    if projection == "disk":
        from matplotlib import patheffects

        halo = [patheffects.withStroke(linewidth=1.8, foreground="0.25", alpha=0.6)]   # readable on any colour
        ring = np.linspace(0, 2 * math.pi, 181)
        for k, s in enumerate(signs):
            for r in (30, 60, 90):
                if r < 90:
                    ax.plot(200 * k + r * np.cos(ring), r * np.sin(ring), color="w", lw=0.6, alpha=0.8,
                            path_effects=halo)
                    ax.text(200 * k + r * math.cos(math.radians(-60)), r * math.sin(math.radians(-60)), f"{r}°",
                            color="w", fontsize="x-small", ha="left", va="top", path_effects=halo)
                else:
                    ax.plot(200 * k + r * np.cos(ring), r * np.sin(ring), color="0.3", lw=1.0)
            which = "reflection" if s == signs[0] else "transmission"
            txt = f"{which} ({'z > 0' if s > 0 else 'z < 0'})"
            if magnified is not None and magnified[0] == which:
                txt += f", colours ×{magnified[1]:g}"
            ax.text(200 * k, 93, txt, ha="center", va="bottom", fontsize="small",
                    fontweight="bold" if magnified is not None and magnified[0] == which else "normal")
        per = (-90, -45, 0, 45, 90) if len(signs) == 1 else (-60, -30, 0, 30, 60)
        ticks = [200 * k + t for k in range(len(signs)) for t in per]
        ax.set_xticks(ticks)
        ax.set_xticklabels([f"{int(round(t - 200 * (t > 100)))}" for t in ticks])
        ax.set_yticks([-90, -45, 0, 45, 90])
        ax.set_xlabel("θ cos φ [°]  (φ = 0 to the right)")
        ax.set_ylabel("θ sin φ [°]")
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(-92, 110)
        for sp in ax.spines.values():
            sp.set_visible(False)
    else:
        if len(signs) == 2:
            ax.axhline(90, color="0.3", lw=1.0)
            txt = "reflection ↑ / transmission ↓"
            if magnified is not None:
                txt += f"   ({magnified[0]} colours ×{magnified[1]:g})"
            ax.text(358, 89, txt, ha="right", va="bottom", fontsize="x-small", color="w")
        ax.set_xticks(np.arange(0, 361, 45))
        ax.set_yticks(np.arange(extent[3], extent[2] + 1, 30))
        ax.set_xlabel("φi, azimuth [°]")
        ax.set_ylabel("θi, angle from +z [°]")

    # ωo and its mirror direction, labelled on the image (no legend needed for them)
    pos = _project(wo, projection, signs)
    if pos is not None:
        ax.plot(*pos, marker="o", ms=8, mfc="none", mec="c", mew=2, ls="none")
        ax.annotate("ωo", pos, xytext=(5, 5), textcoords="offset points", color="c", fontsize="small",
                    fontweight="bold")
    mirror = np.array([-wo[0], -wo[1], wo[2]])
    pos = _project(mirror, projection, signs)
    if pos is not None and theta_o > 0:
        ax.plot(*pos, marker="+", ms=12, mec="c", mew=1.5, ls="none")
        ax.annotate("mirror", pos, xytext=(0, -9), textcoords="offset points", color="c", fontsize="x-small",
                    ha="center", va="top")
    for k, e in enumerate(entries):
        for d in e["delta"]:
            pos = _project(d["wi"], projection, signs)
            if pos is None:
                continue
            what = "R" if d["kind"] == "reflection" else "T"
            ax.plot(*pos, marker="*", ms=13, mfc=f"C{k % 10}", mec="w", ls="none")
            ax.annotate(f"δ {what}={_fmt(d['weight'] if channel == 'rgb' else d['value'])}", pos, xytext=(6, -10),
                        textcoords="offset points", fontsize="x-small", color="k",
                        bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
    if any(e["delta"] for e in entries):
        handles.append(Line2D([], [], marker="*", ms=11, mfc="C0", mec="w", ls="none",
                              label="delta lobe (eval = 0; R/T = reflectance/transmittance)"))

    q = _quantity(cosine) if quantity is None else str(quantity)
    unit = " 1/sr" if quantity is None else ""
    cb = None
    if colorbar:
        cb = _colorbar(ax, im, f"{q}{' (log scale)' if log else ''}" + (f" — {entries[0]['label']}"
                                                                      if len(entries) > 1 else ""),
                       inset=projection == "disk")
        if cb is None and channel == "rgb":
            ax.text(0.0, -0.02, f"RGB scaled so that {_fmt(vmax)}{unit} is white", transform=ax.transAxes,
                    fontsize="x-small", va="top")
    if title is None:
        title = (f"{q} over ωi ({channel}{', log' if log else ''}), θo = {theta_o:g}°, φo = {phi_o:g}°\n"
                 + (f"{entries[0]['label']}   " if len(entries) == 1 else "") + f"max = {_fmt(vmax)}")
    if title:
        ax.set_title(title, fontsize="medium")
    if legend and handles:
        ax.legend(handles=handles, fontsize="x-small", loc="lower right" if projection == "disk" else "lower left",
                  framealpha=0.85)
    if not any(e["delta"] for e in entries):
        _note_all_zero(ax, entries)
    data = dict(kind="hemisphere", value=[e["value"] for e in entries], wi=wi, wo=wo, x=xs, y=ys, extent=extent,
                projection=projection, sides=list(signs), label=[e["label"] for e in entries],
                model=[e["model"] for e in entries], delta=[e["delta"] for e in entries], vmax=vmax,
                cosine=bool(cosine), channel=channel, log=bool(log), levels=levels, magnified=magnified,
                colorbar=cb)
    return _set_data(ax, data)
