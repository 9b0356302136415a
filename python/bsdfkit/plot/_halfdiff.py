"""Rusinkiewicz half/difference angle images."""
from __future__ import annotations

import math

import numpy as np

from .._enums import TransportMode
from ._common import (_as_labels, _as_models, _check_channel, _check_int, _contours, _finite, _fmt,
                      _legend_proxies, _new_figure, _note_all_zero, _positive_max, _quantity, _scalar_image,
                      _select, _set_data)
from ..models.describe import describe

__all__ = ["halfdiff"]


def _halfdiff_dirs(theta_h, theta_d, phi_h, phi_d):
    """Rusinkiewicz (θh, φh, θd, φd) -> (wo, wi) (radians in, broadcast): wi = Rz(φh) Ry(θh) d and
    wo = Rz(φh) Ry(θh) d', d = direction(θd, φd), d' = d mirrored about the half vector's z."""
    theta_h, theta_d, phi_h, phi_d = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64)
                                                           for a in (theta_h, theta_d, phi_h, phi_d)))
    sd, cd = np.sin(theta_d), np.cos(theta_d)
    d = np.stack([sd * np.cos(phi_d), sd * np.sin(phi_d), cd], -1)

    def rot(v):
        ch, sh = np.cos(theta_h), np.sin(theta_h)
        x = ch * v[..., 0] + sh * v[..., 2]
        z = -sh * v[..., 0] + ch * v[..., 2]
        y = v[..., 1]
        cp, sp = np.cos(phi_h), np.sin(phi_h)
        return np.stack([cp * x - sp * y, sp * x + cp * y, z], -1)

    wi = rot(d)
    wo = rot(d * np.array([-1.0, -1.0, 1.0]))
    return wo, wi


def halfdiff(model_or_list, phi_d=90.0, sqrt_theta_h=True, log=True, cosine=False, channel="luminance", ax=None,
             res=128, label=None, *, phi_h=0.0, title=None, legend=True, colorbar=True, cmap="inferno",
             log_decades=4.0, vmax=None, grazing_deg=85.0, mode=TransportMode.Radiance, quantity=None):
    """θh × θd image of ``f`` (or ``f |cos θi|``) in Rusinkiewicz half/difference coordinates at a
    fixed ``phi_d`` and ``phi_h``.

    θh (the half vector's angle from the normal) runs across, θd (the angle between ωi and the
    half vector) up, both 0..90°. Configurations with ωo or ωi below the horizon (none at
    φd = 90°; θh + θd > 90° at φd = 0°) are not reflection and are drawn gray (NaN in the data).
    Transmission is not part of this view. A list of models: the first is the image, every model
    is drawn as iso-value lines.

    Parameters
    ----------
    model_or_list : BxDF or list of BxDF
        The model(s); several are overlaid, each in its own colour.
    phi_d : float, optional
        Difference azimuth, degrees (default 90°, Disney BRDF Explorer's slice).
    sqrt_theta_h : bool, optional
        Space θh as √θh (as in MERL and BRDF Explorer) so that the specular peak near θh = 0 gets
        room; tick labels stay in degrees.
    log : bool, optional
        Logarithmic colour scale over ``log_decades`` decades (default True).
    cosine : bool, optional
        Plot ``f |cos θi|`` instead of ``f``.
    channel : {"luminance", "r", "g", "b", "rgb"}, optional
        Luminance (0.2126 R + 0.7152 G + 0.0722 B), one channel, or all three.
    ax : matplotlib Axes, optional
        A rectilinear Axes to draw into (created if None).
    res : int, optional
        Pixels per axis.
    label : str or list of str, optional
        Legend label(s) (default: ``model.describe()``).
    title : str, optional
        None: a title stating what is plotted; "" : none.
    legend : bool, optional
        Draw the legend.
    phi_h : float, optional
        Half-vector azimuth, degrees (matters for anisotropic models only).
    colorbar : bool, optional
        Draw the colour bar.
    cmap : str, optional
        Matplotlib colour map.
    log_decades : float, optional
        Decades shown on a log scale.
    vmax : float, optional
        Top of the colour scale. f of microfacet models grows without bound towards θd = 90° (ωo
        and ωi grazing: the 1/(cos θo cos θi) factor), which would leave the rest of the image
        black. So by default (None) the scale tops out at the largest value with both ωo and ωi
        within ``grazing_deg`` of the normal; larger values are drawn in the top colour (the
        colorbar's upper arrow) and the true maximum is in the title.
    grazing_deg : float, optional
        See ``vmax``.
    mode : TransportMode, optional
        Passed to ``eval`` / ``sample`` (default Radiance).
    quantity : str, optional
        The label of the plotted value with its unit, as in :func:`hemisphere`.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes; ``ax.bsdfkit_data`` has ``value`` (list per model, (res, res) or (res, res, 3),
        rows θd, columns θh, NaN where invalid), ``theta_h_deg`` (res,), ``theta_d_deg`` (res,),
        ``wo``/``wi`` ((res, res, 3)), ``valid`` ((res, res) bool), ``phi_d``, ``phi_h``,
        ``sqrt_theta_h``, ``label``, ``model``, ``vmax``, ``cosine``, ``channel``, ``log``.

    Raises
    ------
    ValueError
        An ``ax`` that is not rectilinear.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> ax = bkplot.halfdiff(bk.Conductor.from_metal("Cu", alpha=0.2), res=32)
    >>> ax.bsdfkit_data["value"][0].shape
    (32, 32)
    """
    models = _as_models(model_or_list)
    labels = _as_labels(label, len(models))
    channel = _check_channel(channel)
    phi_d, phi_h = _finite(phi_d, "phi_d"), _finite(phi_h, "phi_h")
    res = _check_int(res, "res", 8)
    if ax is None:
        ax = _new_figure((6.4, 5.0)).add_subplot()
    elif getattr(ax, "name", None) != "rectilinear":
        raise ValueError("ax: halfdiff() needs a rectilinear Axes")

    u = (np.arange(res) + 0.5) / res
    th_deg = 90.0 * (u * u if sqrt_theta_h else u)
    td_deg = 90.0 * u
    TD, TH = np.meshgrid(np.radians(td_deg), np.radians(th_deg), indexing="ij")
    wo, wi = _halfdiff_dirs(TH, TD, math.radians(phi_h), math.radians(phi_d))
    valid = (wo[..., 2] > 0) & (wi[..., 2] > 0)
    entries = []
    for m, lab in zip(models, labels):
        f = m.eval(wo, wi, mode=mode)
        if cosine:
            f = f * np.abs(wi[..., 2:3])
        val = np.array(_select(f, channel), dtype=np.float64)
        val[~valid] = np.nan
        entries.append(dict(model=m, label=lab if lab is not None else describe(m), value=val))
    true_max = _positive_max([entries[0]["value"]])
    inner = valid & (np.minimum(wo[..., 2], wi[..., 2]) >= math.cos(math.radians(grazing_deg)))

    def robust(es):   # the colour scale ignores the grazing blow-up (see the docstring)
        return _positive_max([np.where(inner[..., None] if e["value"].ndim == 3 else inner, e["value"], np.nan)
                              for e in es]) or _positive_max([e["value"] for e in es])

    vmax_all = robust(entries) if vmax is None else vmax
    if vmax is None:
        vmax = robust(entries[:1])
    clipped = true_max > vmax * (1 + 1e-9)
    extent = (0.0, 1.0 if sqrt_theta_h else 90.0, 0.0, 90.0)
    xs = u if sqrt_theta_h else th_deg
    im, _ = _scalar_image(ax, entries[0]["value"], extent, log=log, log_decades=log_decades, vmax=vmax, cmap=cmap,
                          origin="lower", aspect="auto", channel=channel)
    handles = []
    if len(entries) > 1:
        _contours(ax, entries, xs, td_deg, log=log, log_decades=log_decades, vmax=vmax_all, handles=handles)
    if sqrt_theta_h:
        ticks = [0, 2, 5, 10, 20, 30, 45, 60, 90]
        ax.set_xticks([math.sqrt(t / 90.0) for t in ticks])
        ax.set_xticklabels([f"{t}" for t in ticks])
        ax.set_xlabel("θh, half vector from the normal [°] (√θh spacing)")
    else:
        ax.set_xticks(np.arange(0, 91, 15))
        ax.set_xlabel("θh, half vector from the normal [°]")
    ax.set_yticks(np.arange(0, 91, 15))
    ax.set_ylabel("θd, ωi from the half vector [°]")
    if np.any(~valid):
        from matplotlib.patches import Patch

        handles.append(Patch(fc="0.85", ec="0.6", label="ωo or ωi below the horizon"))
    q = _quantity(cosine) if quantity is None else str(quantity)
    cb = None
    if colorbar and im is not None:
        cb = ax.figure.colorbar(im, ax=ax, shrink=0.85, pad=0.02,
                                extend={(True, True): "both", (True, False): "min", (False, True): "max"}.get(
                                    (bool(log), bool(clipped)), "neither"))
        cb.set_label(f"{q}{' (log scale)' if log else ''}")
    if title is None:
        title = (f"{q}, half/difference slice φd = {phi_d:g}°" + (f", φh = {phi_h:g}°" if phi_h else "")
                 + f" ({channel}{', log' if log else ''})\n" + (f"{entries[0]['label']}   " if len(entries) == 1 else "")
                 + f"max = {_fmt(true_max)}" + (" (at grazing)" if clipped else ""))
    if title:
        ax.set_title(title, fontsize="medium")
    if legend:
        _legend_proxies(ax, handles, loc="upper right")
    _note_all_zero(ax, entries)
    data = dict(kind="halfdiff", value=[e["value"] for e in entries], theta_h_deg=th_deg, theta_d_deg=td_deg,
                wo=wo, wi=wi, valid=valid, phi_d=phi_d, phi_h=phi_h, sqrt_theta_h=bool(sqrt_theta_h),
                label=[e["label"] for e in entries], model=[e["model"] for e in entries], vmax=vmax,
                max=true_max, cosine=bool(cosine), channel=channel, log=bool(log), colorbar=cb)
    return _set_data(ax, data)
