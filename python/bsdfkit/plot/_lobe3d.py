"""3-D lobe surfaces."""
from __future__ import annotations

import math

import numpy as np

from .._enums import TransportMode
from ._common import (_QUANTITY, _as_labels, _as_models, _check_channel, _check_int, _finite, _fmt,
                      _legend_proxies, _new_figure, _positive_max, _quantity, _set_data, _transmits,
                      _values, _wo_dir, luminance)
from ._polar import _model_entries

__all__ = ["lobe3d"]


def lobe3d(model_or_list, theta_o=30.0, phi_o=0.0, log=False, cosine=False, channel="luminance", ax=None,
           n_theta=46, n_phi=91, label=None, *, sphere=None, title=None, legend=True, colorbar=True,
           cmap="viridis", log_decades=3.0, view=(22.0, -70.0), mode=TransportMode.Radiance, n_delta=4096, seed=0,
           alpha=None):
    """3D lobe: the surface ``r(ωi) ωi`` with radius ``r = f(wo, wi)`` (or ``f |cos θi|``; on a log
    scale, decades above ``max · 10^-log_decades``) over the upper hemisphere, or the whole sphere.

    ``wo = bk.direction(radians(theta_o), radians(phi_o))`` is drawn as a dashed arrow, the
    surface as a gray circle, the normal as a thin line. One model: coloured by value (colorbar;
    ``channel="rgb"``: radius by luminance, colour = hue of f). Several models: one translucent
    colour each, with a legend. Delta lobes are drawn as arrows of length R (or T).

    Parameters
    ----------
    model_or_list : BxDF or list of BxDF
        The model(s); several are overlaid, each in its own colour.
    theta_o, phi_o : float, optional
        wo's angle from the normal and azimuth, in degrees.
    log : bool, optional
        Logarithmic radius over ``log_decades`` decades.
    cosine : bool, optional
        Plot ``f |cos θi|`` instead of ``f``.
    channel : {"luminance", "r", "g", "b", "rgb"}, optional
        Luminance (0.2126 R + 0.7152 G + 0.0722 B), one channel, or all three.
    ax : matplotlib Axes, optional
        A 3D Axes to draw into (created if None).
    n_theta, n_phi : int, optional
        Grid of the surface.
    label : str or list of str, optional
        Legend label(s) (default: ``model.describe()``).
    title : str, optional
        None: a title stating what is plotted; "" : none.
    legend : bool, optional
        Draw the legend.
    sphere : bool, optional
        Draw the whole sphere (default: when some model transmits).
    colorbar : bool, optional
        Draw the colour bar (one model).
    cmap : str, optional
        Matplotlib colour map.
    log_decades : float, optional
        Decades shown on a log radius.
    view : tuple of float, optional
        Camera elevation and azimuth, degrees.
    mode : TransportMode, optional
        Passed to ``eval`` / ``sample`` (default Radiance).
    n_delta : int, optional
        Samples estimating each delta lobe's reflectance / transmittance.
    seed : int, optional
        Seed of those samples.
    alpha : float, optional
        Opacity of the surfaces (default: opaque for one model, 0.35 for several).

    Returns
    -------
    mpl_toolkits.mplot3d.Axes3D
        The 3D Axes; ``ax.bsdfkit_data`` has ``theta_deg`` (n_theta,), ``phi_deg`` (n_phi,),
        ``wi`` ((n_theta, n_phi, 3)), ``value`` (list per model, (n_theta, n_phi) or
        (n_theta, n_phi, 3)), ``radius`` (list per model, (n_theta, n_phi)), ``wo``, ``label``,
        ``model``, ``delta``, ``sphere``, ``cosine``, ``channel``, ``log``, ``log_floor``.

    Raises
    ------
    ValueError
        An ``ax`` that is not a 3D Axes.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> ax = bkplot.lobe3d(bk.Conductor.from_metal("Cu", alpha=0.3), n_theta=12, n_phi=24)
    >>> ax.bsdfkit_data["radius"][0].shape
    (12, 24)
    """
    models = _as_models(model_or_list)
    labels = _as_labels(label, len(models))
    channel = _check_channel(channel)
    theta_o, phi_o = _finite(theta_o, "theta_o"), _finite(phi_o, "phi_o")
    n_theta, n_phi = _check_int(n_theta, "n_theta", 3), _check_int(n_phi, "n_phi", 4)
    if sphere is None:
        sphere = _transmits(models)
    if ax is None:
        ax = _new_figure((6.4, 6.0)).add_subplot(projection="3d")
    elif getattr(ax, "name", None) != "3d":
        raise ValueError("ax: lobe3d() needs a 3D Axes, e.g. fig.add_subplot(projection='3d')")

    from matplotlib import colormaps
    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    wo = _wo_dir(theta_o, phi_o)
    theta_deg = np.linspace(0.0, 180.0 if sphere else 90.0, n_theta)
    phi_deg = np.linspace(0.0, 360.0, n_phi)
    T, P = np.meshgrid(np.radians(theta_deg), np.radians(phi_deg), indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    xdir = np.array([math.cos(math.radians(phi_o)), math.sin(math.radians(phi_o)), 0.0])

    entries = _model_entries(models, labels, lambda m: _values(m, wo, wi, cosine, channel, mode), wo, xdir,
                             n_delta, seed, mode, channel)
    scal = [e["value"] if channel != "rgb" else luminance(e["value"]) for e in entries]
    dvals = [float(luminance(d["weight"]) if channel == "rgb" else d["value"]) for e in entries for d in e["delta"]]
    vmax = max(_positive_max(scal), max(dvals, default=0.0))
    top = vmax if vmax > 0 else 1.0
    floor = top * 10.0 ** (-log_decades) if log else None

    def rmap(v):
        v = np.nan_to_num(np.asarray(v, dtype=np.float64))
        if not log:
            return np.maximum(v, 0.0)
        with np.errstate(divide="ignore"):
            return np.clip(np.log10(np.maximum(v, 0.0) / floor), 0.0, None)

    cm = colormaps[cmap] if isinstance(cmap, str) else cmap
    norm = LogNorm(floor, top) if log else Normalize(0.0, top)
    handles = []
    radii = []
    single = len(entries) == 1
    for k, (e, v) in enumerate(zip(entries, scal)):
        r = rmap(v)
        radii.append(r)
        X, Y, Z = (r * wi[..., c] for c in range(3))
        if single:
            if channel == "rgb":
                rgb = np.nan_to_num(e["value"])
                peak = np.max(rgb, axis=-1, keepdims=True)
                fc = np.where(peak > 0, rgb / np.where(peak > 0, peak, 1.0), 0.5)
                fc = np.concatenate([fc, np.ones(fc.shape[:-1] + (1,))], -1)
            else:
                with np.errstate(invalid="ignore"):
                    fc = cm(norm(np.clip(np.nan_to_num(v), floor if log else 0.0, top)))
            fc[..., 3] = 1.0 if alpha is None else alpha
            ax.plot_surface(X, Y, Z, facecolors=fc, rstride=1, cstride=1, linewidth=0, antialiased=False,
                            shade=False)
        else:
            color = f"C{k % 10}"
            ax.plot_surface(X, Y, Z, color=color, alpha=0.35 if alpha is None else alpha, rstride=1, cstride=1,
                            linewidth=0, antialiased=False, shade=True)
            handles.append(Patch(fc=color, alpha=0.6, label=e["label"]))
        for d in e["delta"]:
            dv = float(luminance(d["weight"]) if channel == "rgb" else d["value"])
            L = float(rmap(dv))
            ax.quiver(0, 0, 0, *(d["wi"] * L), color=f"C{k % 10}" if not single else "C3", lw=2.5,
                      arrow_length_ratio=0.12)
            ax.text(*(d["wi"] * L * 1.05), f"δ {'R' if d['kind'] == 'reflection' else 'T'}={_fmt(dv)}",
                    fontsize="x-small")
    if any(e["delta"] for e in entries):
        handles.append(Line2D([], [], color="C3", lw=2.5, label="delta lobe (length = R or T)"))

    R = max([float(np.max(r)) for r in radii] + [float(rmap(v)) for v in dvals] + [0.0])
    R = R if R > 0 else 1.0
    ring = np.linspace(0, 2 * math.pi, 121)
    ax.plot(R * np.cos(ring), R * np.sin(ring), 0 * ring, color="0.5", lw=0.8)
    ax.plot([0, 0], [0, 0], [-R if sphere else 0, R], color="0.5", lw=0.6)
    ax.plot([0, wo[0] * R], [0, wo[1] * R], [0, wo[2] * R], color="k", ls="--", lw=1.5)
    ax.text(*(wo * R * 1.08), "ωo", fontsize="small", fontweight="bold")
    handles.append(Line2D([], [], color="k", ls="--", label=f"ωo (θo = {theta_o:g}°, φo = {phi_o:g}°)"))
    ax.set_xlim(-R, R)
    ax.set_ylim(-R, R)
    ax.set_zlim(-R if sphere else 0.0, R)
    ax.set_box_aspect((1, 1, 1 if sphere else 0.5))
    ax.view_init(elev=view[0], azim=view[1])
    unit = "decades" if log else "1/sr"
    ax.set_xlabel(f"x [{unit}]", fontsize="small", labelpad=-2)
    ax.set_ylabel(f"y [{unit}]", fontsize="small", labelpad=-2)
    ax.set_zlabel(f"z, normal [{unit}]", fontsize="small", labelpad=-2)
    ax.tick_params(labelsize="x-small", pad=0)
    from matplotlib.ticker import MaxNLocator

    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(4))
    q = _quantity(cosine)
    cb = None
    if colorbar and single and channel != "rgb":
        from matplotlib.cm import ScalarMappable

        cb = ax.figure.colorbar(ScalarMappable(norm=norm, cmap=cm), ax=ax, shrink=0.6, pad=0.08)
        cb.set_label(q + (" (log scale)" if log else ""))
    if title is None:
        rad = f"radius = log10({_QUANTITY[bool(cosine)]} / {floor:.2g})" if log else f"radius = {q}"
        title = (f"3D lobe, {rad}, θo = {theta_o:g}°" + (f"\n{entries[0]['label']}" if single else ""))
    if title:
        ax.set_title(title, fontsize="medium")
    if legend:
        _legend_proxies(ax, handles, loc="upper left")
    data = dict(kind="lobe3d", theta_deg=theta_deg, phi_deg=phi_deg, wi=wi, value=[e["value"] for e in entries],
                radius=radii, wo=wo, label=[e["label"] for e in entries], model=[e["model"] for e in entries],
                delta=[e["delta"] for e in entries], sphere=bool(sphere), cosine=bool(cosine), channel=channel,
                log=bool(log), log_floor=floor, vmax=vmax, colorbar=cb)
    return _set_data(ax, data)
