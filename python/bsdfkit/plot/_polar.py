"""In-plane polar lobe slices."""
from __future__ import annotations

import math

import numpy as np

from .._enums import BxDFFlags, ReflTrans, TransportMode
from ..models import BxDF
from ._common import (_RGB_COLORS, _RGB_STYLES, _as_labels, _as_models, _check_channel, _finite, _fmt,
                      _new_axes, _select, luminance)
from ..models.describe import describe

__all__ = ["polar"]


def _delta_lobes(model: BxDF, wo: np.ndarray, xdir: np.ndarray, n: int, seed: int, mode) -> list:
    """Specular lobes reached from wo: one dict per lobe with the signed in-plane angle of its
    direction (degrees), its weight (the lobe's reflectance/transmittance, RGB: the mean of
    f |cos wi| / pdf when sampling is restricted to that side) and its flags."""
    lobes = []
    for side in (ReflTrans.Reflection, ReflTrans.Transmission):
        s = model.sample(wo, n=n, seed=seed, mode=mode, sample_flags=side)
        spec = s.valid & ((s.flags & int(BxDFFlags.Specular)) != 0)
        if not spec.any():
            continue
        for fl in np.unique(s.flags[spec]):
            k = spec & (s.flags == fl)
            weight = s.weight[k].sum(axis=0) / n
            wi = s.wi[k].mean(axis=0)
            wi /= np.linalg.norm(wi)
            t = math.degrees(math.atan2(float(wi @ xdir), float(wi[2])))
            lobes.append(dict(theta_deg=t, weight=weight, wi=wi, flags=BxDFFlags(int(fl)),
                              kind="reflection" if fl & BxDFFlags.Reflection else "transmission"))
    return lobes



def _model_entries(models, labels, value, wo, xdir, n_delta: int, seed: int, mode, channel: str) -> list:
    """Per model: its label, value(model) over the plotted directions, and its delta lobes
    (specular models) with their values in `channel` — what the polar and 3D views draw."""
    entries = []
    for m, lab in zip(models, labels):
        delta = []
        if m.flags & BxDFFlags.Specular:
            for lobe in _delta_lobes(m, wo, xdir, n_delta, seed, mode):
                lobe["value"] = _select(lobe["weight"], channel)
                delta.append(lobe)
        entries.append(dict(model=m, label=lab if lab is not None else describe(m), value=value(m), delta=delta))
    return entries

def _weak_half(val, z, below):
    """(side, factor) when the weaker half of a curve peaks below ``below`` times the stronger one."""
    up = float(np.max(val[z > 0], initial=0.0))
    dn = float(np.max(val[z < 0], initial=0.0))
    weak, strong = min(up, dn), max(up, dn)
    if weak <= 0 or weak >= below * strong:
        return None
    target = 0.6 * strong / weak
    e = math.floor(math.log10(target))
    factor = max(m * 10.0 ** e for m in (1, 2, 5) if m * 10.0 ** e <= target)
    return ("reflection" if up < dn else "transmission"), factor


def polar(model_or_list, theta_o=30.0, phi_plane=0.0, log=False, cosine=False, channel="luminance",
          ax=None, n=721, label=None, *, title=None, legend=True, log_decades=4.0,
          mode=TransportMode.Radiance, n_delta=4096, seed=0, colors=None, linestyle="-",
          annotate_delta=True, magnify_below=0.04, quantity=None):
    """In-plane slice of the lobe(s) over the full circle, in a polar Axes.

    Plots ``f(wo, wi)`` (or ``f(wo, wi) |cos θi|`` with ``cosine=True``) for ``wi`` in the plane of
    azimuth ``phi_plane`` (degrees) against the signed angle θ from the normal (degrees,
    0 at the top; reflection above the horizon, transmission below). ``wo`` is at
    ``θ = -theta_o`` (dashed line), so the mirror direction is at ``θ = +theta_o``.

    Delta (specular) lobes, which ``eval`` reports as 0, are drawn as arrows along their
    direction whose length is the lobe's reflectance/transmittance (the mean of
    f |cos θi| / pdf over ``n_delta`` samples restricted to that side) and are marked "delta"
    in the legend (and, with ``annotate_delta``, at the arrow tip).

    Parameters
    ----------
    model_or_list : BxDF or list of BxDF
        The model(s); several are overlaid, each in its own colour.
    theta_o : float, optional
        wo's angle from the normal, degrees.
    phi_plane : float, optional
        Azimuth of the plotted plane, degrees.
    log : bool, optional
        Radial axis logarithmic, covering ``log_decades`` decades below the largest value (values
        below are drawn at the centre; an overlaid curve lying entirely below the range of the
        first call says so in its legend entry). The radial range (linear or log) is set by the
        values off the horizon: the samples at θi = ±90° exactly (cos θi = 0, where a value may be
        singular) are drawn but clipped at the rim instead of setting the scale.
    cosine : bool, optional
        Plot ``f |cos θi|`` instead of ``f``.
    channel : {"luminance", "r", "g", "b", "rgb"}, optional
        Luminance (0.2126 R + 0.7152 G + 0.0722 B), one channel, or all three.
    ax : matplotlib Axes, optional
        A polar Axes to draw into (created if None); calling again on the same Axes overlays and
        appends to its data (the radial mapping of the first call is kept).
    n : int, optional
        Points along the circle.
    label : str or list of str, optional
        Legend label(s) (default: ``model.describe()``).
    title : str, optional
        None: a title stating what is plotted; "" : none.
    legend : bool, optional
        Draw the legend.
    log_decades : float, optional
        Decades shown on a log radius.
    mode : TransportMode, optional
        Passed to ``eval`` / ``sample`` (default Radiance).
    n_delta : int, optional
        Samples estimating each delta lobe's reflectance / transmittance.
    seed : int, optional
        Seed of those samples.
    colors : list, optional
        One matplotlib colour per model (default: the colour cycle).
    linestyle : str, optional
        Line style of the curves.
    annotate_delta : bool, optional
        Name delta lobes at their arrow tips.
    magnify_below : float, optional
        On a linear scale, when the weaker half (reflection or transmission) peaks below this
        fraction of the stronger half, it is also drawn magnified by a round factor (labelled
        "×factor") so that it does not vanish; 0 or None turns this off.
    quantity : str, optional
        The label of the plotted value with its unit (default ``"f [1/sr]"`` or
        ``"f·|cos θi| [1/sr]"``; :func:`difference` gives its relative difference's).

    Returns
    -------
    matplotlib.axes.Axes
        The Axes. ``ax.bsdfkit_data`` is a dict of lists with one entry per model drawn:
        ``theta_deg`` (n,) signed angles, ``value`` (n,) or (n, 3) plotted values in linear units,
        ``wi`` (n, 3), ``wo`` (3,), ``theta_o``, ``phi_plane``, ``label``, ``model`` and ``delta``
        (a list of lobe dicts with ``theta_deg``, ``wi``, ``weight`` (RGB), ``value`` (channel),
        ``flags``, ``kind``), ``magnified`` (None or (side, factor) of the dotted magnified copy);
        and scalars ``channel``, ``cosine``, ``log``.

    Raises
    ------
    ValueError
        A bad channel or angle.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> ax = bkplot.polar([bk.Conductor.from_metal("Au", alpha=a) for a in (0.1, 0.3)], theta_o=45, log=True)
    >>> len(ax.bsdfkit_data["value"]), ax.bsdfkit_data["value"][0].shape
    (2, (721,))
    """
    models = _as_models(model_or_list)
    labels = _as_labels(label, len(models))
    channel = _check_channel(channel)
    theta_o = _finite(theta_o, "theta_o")
    phi_plane = _finite(phi_plane, "phi_plane")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
        raise ValueError(f"n: expected an integer >= 3, got {n!r}")
    if ax is None:
        ax = _new_axes(True)
    elif getattr(ax, "name", None) != "polar":
        raise ValueError("ax: polar() needs a polar Axes, e.g. fig.add_subplot(projection='polar')")

    phi = math.radians(phi_plane)
    xdir = np.array([math.cos(phi), math.sin(phi), 0.0])
    so, co = math.sin(math.radians(theta_o)), math.cos(math.radians(theta_o))
    wo = np.array([-so * xdir[0], -so * xdir[1], co])
    t_deg = np.linspace(-180.0, 180.0, int(n))
    t = np.radians(t_deg)
    wi = np.stack([np.sin(t) * xdir[0], np.sin(t) * xdir[1], np.cos(t)], axis=-1)
    cos_i = np.abs(wi[:, 2])

    # ---- compute everything first (log scaling needs the overall maximum)
    def value(m):
        f = m.eval(wo, wi, mode=mode)
        return _select(f * cos_i[:, None] if cosine else f, channel)

    entries = _model_entries(models, labels, value, wo, xdir, n_delta, seed, mode, channel)
    # the radial scale ignores the two samples exactly on the horizon (θi = ±90°, cos θi = 0),
    # where a model's value may be singular: one such sample set the whole scale and flattened
    # the plot (e.g. a relative difference where the reference is 0); they are clipped at the rim
    off_horizon = cos_i > 1e-9

    data = getattr(ax, "bsdfkit_data", None)
    first = not (isinstance(data, dict) and data.get("kind") == "polar")
    if first:
        data = dict(kind="polar", channel=channel, cosine=bool(cosine), log=bool(log), theta_deg=[], value=[],
                    wi=[], wo=[], theta_o=[], phi_plane=[], label=[], model=[], delta=[],
                    magnified=[])
        if log:
            vmax = max([float(np.max(e["value"][off_horizon])) for e in entries]
                       + [float(np.max(d["value"])) for e in entries for d in e["delta"]] + [0.0])
            vmax = vmax if vmax > 0 else 1.0
            data["log_floor"] = 10.0 ** (math.ceil(math.log10(vmax)) - float(log_decades))
    log = data["log"]
    floor = data.get("log_floor", 1.0)

    def rmap(v):
        v = np.asarray(v, dtype=np.float64)
        if not log:
            return v
        with np.errstate(divide="ignore"):
            return np.clip(np.log10(np.maximum(v, 0.0) / floor), 0.0, None)

    # ---- draw
    for j, e in enumerate(entries):
        k = len(data["model"])
        color = colors[j] if colors is not None else f"C{k % 10}"
        rgb_style = _RGB_STYLES[k % len(_RGB_STYLES)]
        val, lab = e["value"], e["label"]
        if log and np.any(val > 0) and float(np.max(val)) < floor:
            # an overlay below the first call's decade range: drawn clipped at the centre, and said
            lab = f"{lab} (max {float(np.max(val)):.1e} < log floor {floor:.0e}: clipped to the centre)"
        if np.any(val > 0) or not e["delta"]:   # never draw nothing; skip an all-zero curve of a delta model
            if channel == "rgb":
                for c in range(3):
                    ax.plot(t, rmap(val[:, c]), color=_RGB_COLORS[c], ls=rgb_style, lw=1.4,
                            label=f"{lab} [{'RGB'[c]}]")
            else:
                ax.plot(t, rmap(val), color=color, ls=linestyle, lw=1.6, label=lab)
        mag = _weak_half(val if channel != "rgb" else luminance(val), wi[:, 2], magnify_below) if (
            magnify_below and not log) else None
        if mag is not None:
            side, factor = mag
            keep = (wi[:, 2] > 0) if side == "reflection" else (wi[:, 2] < 0)
            if channel == "rgb":
                for c in range(3):
                    ax.plot(t, np.where(keep, val[:, c] * factor, np.nan), color=_RGB_COLORS[c], ls=":", lw=1.3,
                            label=f"{lab} [{'RGB'[c]}]: {side} ×{factor:g}")
            else:
                ax.plot(t, np.where(keep, val * factor, np.nan), color=color, ls=":", lw=1.4,
                        label=f"{lab}: {side} ×{factor:g}")
            if annotate_delta:
                i_pk = int(np.nanargmax(np.where(keep, luminance(val) if channel == "rgb" else val, np.nan)))
                ax.annotate(f"{side} ×{factor:g}", xy=(t[i_pk], float(np.max(val[i_pk])) * factor),
                            xytext=(4, 4), textcoords="offset points", fontsize="x-small",
                            color="k" if channel == "rgb" else color,
                            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
        for d in e["delta"]:
            td = math.radians(d["theta_deg"])
            what = "R" if d["kind"] == "reflection" else "T"
            pairs = [(d["value"], color)] if channel != "rgb" else list(zip(d["value"], _RGB_COLORS))
            shown = _fmt(d["weight"] if channel == "rgb" else d["value"])
            for c, (v, col) in enumerate(pairs):
                r = float(rmap(v))
                ax.plot([td, td], [0.0, r], color=col, lw=2.2, solid_capstyle="butt",
                        ls=rgb_style if channel == "rgb" else "-",
                        label=f"{lab}: delta {d['kind']}, {what}={shown}" if c == 0 else None)
                ax.annotate("", xy=(td, r), xytext=(td, 0.0),
                            arrowprops=dict(arrowstyle="-|>", color=col, lw=2.0, mutation_scale=14,
                                            shrinkA=0, shrinkB=0))
            if annotate_delta:
                # beside the arrow (not past its tip, which may be at the rim), on its right/upper side
                r = float(np.max(rmap(d["value"])))
                dx, dy = math.sin(td), math.cos(td)   # screen direction of the arrow (0 deg up, clockwise)
                px, py = (dy, -dx) if dy - dx > 0 else (-dy, dx)
                ax.annotate(f"δ {what}={shown}", xy=(td, 0.6 * r), xytext=(7 * px, 7 * py),
                            textcoords="offset points", fontsize="x-small",
                            ha="left" if px > 0.3 else "right" if px < -0.3 else "center",
                            va="bottom" if py > 0.3 else "top" if py < -0.3 else "center",
                            color="k" if channel == "rgb" else color,
                            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
        data["theta_deg"].append(t_deg)
        data["value"].append(val)
        data["wi"].append(wi)
        data["wo"].append(wo)
        data["theta_o"].append(theta_o)
        data["phi_plane"].append(phi_plane)
        data["label"].append(lab)
        data["model"].append(e["model"])
        data["delta"].append(e["delta"])
        data["magnified"].append(mag)

    # ---- axes decoration
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    ax.set_thetalim(0.0, 2 * math.pi)
    ticks = np.arange(0, 360, 30)
    ax.set_thetagrids(ticks, [f"{a if a <= 180 else a - 360}°" for a in ticks])
    drawn = [float(np.max(rmap(v[np.abs(np.abs(np.asarray(td)) - 90.0) > 1e-9])))
             for v, td in zip(data["value"], data["theta_deg"])]
    drawn += [float(np.max(rmap(d["value"]))) for ds in data["delta"] for d in ds]
    top = max(drawn + [0.0])
    if log:
        ax.set_ylim(0.0, max(top, 1.0) * 1.08)
        lf = math.log10(floor)
        rticks = [p - lf for p in range(math.ceil(lf), math.ceil(lf + top) + 1) if p - lf <= top * 1.08]
        ax.set_yticks(rticks)
        ax.set_yticklabels([f"1e{round(r + lf)}" for r in rticks])
    else:
        from matplotlib.ticker import MaxNLocator

        rmax = top * 1.08 if top > 0 else 1.0
        ax.set_ylim(0.0, rmax)
        rticks = [v for v in MaxNLocator(nbins=4).tick_values(0.0, top if top > 0 else 1.0) if 0 < v <= rmax]
        ax.set_yticks(rticks)
        ax.set_yticklabels([f"{v:g}" for v in rticks])
    ax.tick_params(axis="y", labelsize="x-small")
    ax.tick_params(axis="x", labelsize="small", pad=0)
    ax.set_rlabel_position(-112.5)  # radial tick labels lower left: away from wo, the mirror peak and refraction

    drawn_wo = data.setdefault("_wo_lines", set())
    if first:
        ax.axvline(math.radians(90), color="0.3", lw=1.2)   # the surface
        ax.axvline(math.radians(-90), color="0.3", lw=1.2)
    if theta_o not in drawn_wo:
        drawn_wo.add(theta_o)
        ax.axvline(math.radians(-theta_o), color="k", ls="--", lw=1.2, label=f"ωo (θo = {theta_o:g}°)")
        # named at the rim too: the legend is often off (overview, gallery)
        ax.annotate("ωo", xy=(math.radians(-theta_o), ax.get_ylim()[1] * 0.9), fontsize="small",
                    xytext=(-4, 0), textcoords="offset points", ha="right", va="center",
                    bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.8))
    if quantity is None:
        quantity = ("f·|cos θi|" if data["cosine"] else "f") + " [1/sr]"
    if title is None:
        title = (f"{quantity}{' (log radius)' if log else ''} vs θi [°]\n"
                 f"plane φ = {phi_plane:g}°, θo = {theta_o:g}°")
    if title:
        ax.set_title(title, fontsize="medium", pad=12)
    if legend:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.06), fontsize="small", framealpha=0.9)
    ax.bsdfkit_data = data
    return ax
