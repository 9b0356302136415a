"""Matplotlib views of bsdfkit models: in-plane polar lobe slices and directional albedo curves.

pyplot is imported only when a function has to create its own figure (``ax=None``), so the
module is safe under any backend, including Agg on headless machines. Every function accepts
one model or a list of models (overlaid, with a legend) and returns the Axes it drew on, with
the plotted numbers attached as ``ax.bsdfkit_data`` (a dict of per-model lists) for tests and
further processing.

Angle conventions of :func:`polar`: the slice lies in the plane of azimuth ``phi_plane``
(degrees). A direction in it is given by a signed angle ``t`` (degrees, from the normal,
positive towards azimuth ``phi_plane``) and is ``wi = (sin t cos phi, sin t sin phi, cos t)``.
``wo`` sits at ``t = -theta_o``, i.e. ``wo = bk.direction(radians(theta_o), radians(phi_plane) + pi)``,
so the mirror direction is at ``t = +theta_o``, reflection is drawn above the horizon and
transmission below it. 0 deg (the normal) is at the top of the plot.
"""
from __future__ import annotations

import math

import numpy as np

from ._enums import BxDFFlags, ReflTrans, TransportMode
from ._models import METALS, BxDF, Conductor, Dielectric, Diffuse, DiffuseTransmission, ThinDielectric

__all__ = ["pareto", "polar", "lobe3d", "hemisphere", "halfdiff", "albedo", "samples", "sample_stats", "overview", "gallery",
           "explore",
           "Explorer", "describe", "luminance", "LUMINANCE_WEIGHTS", "VIEWS"]

#: Rec. 709 / sRGB luminance weights of linear R, G, B.
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])

_CHANNELS = ("luminance", "r", "g", "b", "rgb")
_RGB_COLORS = ("tab:red", "tab:green", "tab:blue")
_RGB_STYLES = ("-", "--", ":", "-.")


# ---------------------------------------------------------------- helpers

def luminance(rgb) -> np.ndarray:
    """Luminance 0.2126 R + 0.7152 G + 0.0722 B of (..., 3) linear RGB values."""
    return np.asarray(rgb, dtype=np.float64) @ LUMINANCE_WEIGHTS


def _select(rgb, channel: str) -> np.ndarray:
    rgb = np.asarray(rgb, dtype=np.float64)
    if channel == "luminance":
        return luminance(rgb)
    if channel == "rgb":
        return rgb
    return rgb[..., "rgb".index(channel)]


def _check_channel(channel, allowed=_CHANNELS) -> str:
    if channel not in allowed:
        raise ValueError(f"channel: must be one of {', '.join(map(repr, allowed))}, got {channel!r}")
    return channel


def _as_models(model_or_list) -> list:
    models = [model_or_list] if isinstance(model_or_list, BxDF) else list(model_or_list)
    if not models:
        raise ValueError("model_or_list: expected a model or a non-empty list of models")
    for m in models:
        if not isinstance(m, BxDF):
            raise TypeError(f"model_or_list: expected bsdfkit models, got {type(m).__name__}")
    return models


def _as_labels(label, n: int):
    if label is None:
        return [None] * n
    if isinstance(label, str):
        if n != 1:
            raise ValueError(f"label: got one string for {n} models; pass a list of {n} labels")
        return [label]
    labels = list(label)
    if len(labels) != n:
        raise ValueError(f"label: got {len(labels)} labels for {n} models")
    return labels


def _finite(x, name: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)) or not math.isfinite(x):
        raise ValueError(f"{name}: expected a finite number, got {x!r}")
    return float(x)


def _fmt(v) -> str:
    v = np.asarray(v, dtype=np.float64)
    if v.ndim and np.allclose(v, v.flat[0]):
        v = v.flat[0]
    if v.ndim == 0:
        return f"{float(v):.3g}"
    return "(" + ", ".join(f"{x:.2g}" for x in v) + ")"


def describe(model: BxDF) -> str:
    """A short human-readable name of a model, e.g. ``"Conductor Au, α=0.2"``."""
    p = model._params
    alpha = ""
    if "alpha_x" in p:
        ax, ay = p["alpha_x"], p["alpha_y"]
        if max(ax, ay) < 1e-3:
            alpha = ", smooth"
        elif ax == ay:
            alpha = f", α={ax:.3g}"
        else:
            alpha = f", αx={ax:.3g}, αy={ay:.3g}"
    if isinstance(model, Diffuse):
        return f"Diffuse R={_fmt(p['reflectance'])}"
    if isinstance(model, DiffuseTransmission):
        return f"DiffuseTransmission R={_fmt(p['reflectance'])}, T={_fmt(p['transmittance'])}"
    if isinstance(model, Conductor):
        name = next((n for n, (eta, k) in METALS.items()
                     if np.allclose(p["eta"], eta) and np.allclose(p["k"], k)), None)
        if name is None:
            name = f"η={_fmt(p['eta'])}, k={_fmt(p['k'])}"
        return f"Conductor {name}{alpha}"
    if isinstance(model, Dielectric):
        return f"Dielectric η={p['eta']:.3g}{alpha}"
    if isinstance(model, ThinDielectric):
        return f"ThinDielectric η={p['eta']:.3g}"
    from ._spec import to_spec

    rest = to_spec(model).split()[1:]
    return type(model).__name__ + (" " + ", ".join(rest) if rest else "")


def _new_axes(polar_axes: bool):
    import matplotlib.pyplot as plt  # lazy: only when the caller did not give an Axes

    fig = plt.figure(figsize=(6.4, 6.4) if polar_axes else (7.0, 4.6), layout="constrained")
    return fig.add_subplot(projection="polar" if polar_axes else None)


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


# ---------------------------------------------------------------- polar lobe slice

def polar(model_or_list, theta_o=30.0, phi_plane=0.0, log=False, cosine=False, channel="luminance",
          ax=None, n=721, label=None, *, title=None, legend=True, log_decades=4.0,
          mode=TransportMode.Radiance, n_delta=4096, seed=0, colors=None, linestyle="-",
          annotate_delta=True, magnify_below=0.04):
    """In-plane slice of the lobe(s) over the full circle, in a polar Axes.

    Plots ``f(wo, wi)`` (or ``f(wo, wi) |cos θi|`` with ``cosine=True``) for ``wi`` in the plane of
    azimuth ``phi_plane`` (degrees) against the signed angle θ from the normal (degrees,
    0 at the top; reflection above the horizon, transmission below). ``wo`` is at
    ``θ = -theta_o`` (dashed line), so the mirror direction is at ``θ = +theta_o``.

    Delta (specular) lobes, which ``eval`` reports as 0, are drawn as arrows along their
    direction whose length is the lobe's reflectance/transmittance (the mean of
    f |cos θi| / pdf over ``n_delta`` samples restricted to that side) and are marked "delta"
    in the legend (and, with ``annotate_delta``, at the arrow tip).

    channel: "luminance" (0.2126 R + 0.7152 G + 0.0722 B), "r", "g", "b" or "rgb" (three curves).
    magnify_below: on a linear radius, when the weaker half (reflection or transmission) of a
    curve peaks below this fraction of the stronger half, it is also drawn magnified by a round
    factor (dotted, labelled "×factor") so that it does not vanish; 0 or None turns this off.
    log: radial axis logarithmic, covering ``log_decades`` decades below the largest value
    (values below are drawn at the centre).
    ax: a polar Axes to draw into (created if None); calling again on the same Axes overlays
    and appends to its data (the radial mapping of the first call is kept).

    Returns the Axes. ``ax.bsdfkit_data`` is a dict of lists with one entry per model drawn:
    ``theta_deg`` (n,) signed angles, ``value`` (n,) or (n, 3) plotted values in linear units,
    ``wi`` (n, 3), ``wo`` (3,), ``theta_o``, ``phi_plane``, ``label``, ``model`` and ``delta``
    (a list of lobe dicts with ``theta_deg``, ``wi``, ``weight`` (RGB), ``value`` (channel),
    ``flags``, ``kind``), ``magnified`` (None or (side, factor) of the dotted magnified copy);
    and scalars ``channel``, ``cosine``, ``log``.
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
    entries = []
    for m, lab in zip(models, labels):
        f = m.eval(wo, wi, mode=mode)
        val = _select(f * cos_i[:, None] if cosine else f, channel)
        delta = []
        if m.flags & BxDFFlags.Specular:
            for lobe in _delta_lobes(m, wo, xdir, n_delta, seed, mode):
                lobe["value"] = _select(lobe["weight"], channel)
                delta.append(lobe)
        entries.append(dict(model=m, label=lab if lab is not None else describe(m), value=val, delta=delta))

    data = getattr(ax, "bsdfkit_data", None)
    first = not (isinstance(data, dict) and data.get("kind") == "polar")
    if first:
        data = dict(kind="polar", channel=channel, cosine=bool(cosine), log=bool(log), theta_deg=[], value=[],
                    wi=[], wo=[], theta_o=[], phi_plane=[], label=[], model=[], delta=[],
                    magnified=[])
        if log:
            vmax = max([float(np.max(e["value"])) for e in entries]
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
    drawn = [float(np.max(rmap(v))) for v in data["value"]]
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
    quantity = "f·|cos θi|" if data["cosine"] else "f"
    if title is None:
        title = (f"{quantity} [1/sr]{' (log radius)' if log else ''} vs θi [°]\n"
                 f"plane φ = {phi_plane:g}°, θo = {theta_o:g}°")
    if title:
        ax.set_title(title, fontsize="medium", pad=12)
    if legend:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.06), fontsize="small", framealpha=0.9)
    ax.bsdfkit_data = data
    return ax


# ---------------------------------------------------------------- directional albedo

def albedo(model_or_list, n_theta=46, n_samples=8192, ax=None, channel="luminance", label=None, *,
           seed=0, mode=TransportMode.Radiance, title=None, legend=True, colors=None, linestyle="-"):
    """Directional albedo ρ(θo) = ∫ f |cos θi| dωi against θo (degrees, 0 to 89.5) with a
    dashed white-furnace line at 1.

    ``n_theta`` equally spaced θo (the last one clamped to 89.5° to stay off the horizon),
    Monte Carlo with ``n_samples`` importance samples each (``BxDF.albedo``). channel:
    "luminance", "r", "g", "b" or "rgb" (three curves per model). Radiance-mode albedo of a
    dielectric includes the 1/η² radiance scaling of transmission; pass
    ``mode=bk.TransportMode.Importance`` for the energy balance.

    Returns the Axes; ``ax.bsdfkit_data`` holds per-model lists ``theta_deg``, ``value``
    ((n_theta,) or (n_theta, 3)), ``rgb`` ((n_theta, 3)), ``label``, ``model``, plus
    ``channel``, ``mode``; and the scalar ``n_samples`` (of the first call).
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
        rgb = m.albedo(wo, n_samples=n_samples, seed=seed, mode=mode)
        val = _select(rgb, channel)
        if channel == "rgb":
            style = _RGB_STYLES[k % len(_RGB_STYLES)]
            for c in range(3):
                ax.plot(theta_deg, val[:, c], color=_RGB_COLORS[c], ls=style, lw=1.5, label=f"{lab} [{'RGB'[c]}]")
        else:
            ax.plot(theta_deg, val, color=color, ls=linestyle, lw=1.8, label=lab)
        ymax = max(ymax, float(np.max(val)))
        for key, v in (("theta_deg", theta_deg), ("value", val), ("rgb", rgb), ("label", lab), ("model", m),
                       ("channel", channel), ("mode", TransportMode(mode))):
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
    if title is None:
        title = f"Directional albedo ({channel}, {n_samples} samples per θo)"
    if title:
        ax.set_title(title, fontsize="medium")
    if legend:
        ax.legend(fontsize="small", loc="lower left")
    ax.bsdfkit_data = data
    return ax


# ================================================================ shared helpers of the image / 3D views

_QUANTITY = {False: "f", True: "f·|cos θi|"}
_SIDES = ("auto", "reflection", "transmission", "both")


def _quantity(cosine: bool) -> str:
    return _QUANTITY[bool(cosine)] + " [1/sr]"


def _wo_dir(theta_o: float, phi_o: float) -> np.ndarray:
    t, p = math.radians(theta_o), math.radians(phi_o)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def _values(model, wo, wi, cosine, channel, mode):
    """Channel-selected f (or f |cos θi|) at directions wi (..., 3) with NaN rows kept NaN."""
    bad = ~np.all(np.isfinite(wi), axis=-1)
    wi_ok = np.where(bad[..., None], np.array([0.0, 0.0, 1.0]), wi)
    f = model.eval(wo, wi_ok, mode=mode)
    if cosine:
        f = f * np.abs(wi_ok[..., 2:3])
    val = _select(f, channel)
    val = np.array(val, dtype=np.float64)
    val[bad] = np.nan
    return val


def _positive_max(values) -> float:
    vmax = 0.0
    for v in values:
        v = np.asarray(v, dtype=np.float64)
        if v.size and np.any(np.isfinite(v)):
            vmax = max(vmax, float(np.nanmax(v)))
    return vmax if vmax > 0 and math.isfinite(vmax) else 0.0


def _check_int(v, name, lo):
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
        raise ValueError(f"{name}: expected an integer >= {lo}, got {v!r}")
    return int(v)


def _check_choice(v, name, allowed):
    if v not in allowed:
        raise ValueError(f"{name}: must be one of {', '.join(map(repr, allowed))}, got {v!r}")
    return v


def _transmits(models) -> bool:
    """Whether a plot must show the whole sphere: a transmitting model, or one defined over the
    whole sphere (``full_sphere``, e.g. Hair)."""
    return any((m.flags & BxDFFlags.Transmission) or getattr(m, "full_sphere", False) for m in models)


def _new_figure(figsize):
    import matplotlib.pyplot as plt  # lazy: only when the caller did not give an Axes

    return plt.figure(figsize=figsize, layout="constrained")


def _legend_proxies(ax, handles, loc="upper right"):
    if handles:
        ax.legend(handles=handles, fontsize="small", loc=loc, framealpha=0.85)


def _set_data(ax, data):
    ax.bsdfkit_data = data
    return ax


def _scalar_image(ax, value, extent, *, log, log_decades, vmax, cmap, origin, aspect, channel):
    """imshow of one (H, W) (or RGB (H, W, 3)) image with NaN shown light gray; returns the
    mappable (None for RGB) and the norm."""
    from matplotlib import colormaps
    from matplotlib.colors import LogNorm, Normalize

    top = vmax if vmax > 0 else 1.0
    if channel == "rgb":
        v = np.asarray(value, dtype=np.float64)
        if log:
            floor = top * 10.0 ** (-log_decades)
            with np.errstate(divide="ignore", invalid="ignore"):
                img = np.clip(np.log10(np.maximum(v, 0.0) / floor) / log_decades, 0.0, 1.0)
        else:
            img = np.clip(v / top, 0.0, 1.0)
        alpha = np.all(np.isfinite(v), axis=-1)
        rgba = np.concatenate([np.nan_to_num(img, nan=0.85), np.ones(img.shape[:-1] + (1,))], axis=-1)
        rgba[~alpha] = (0.85, 0.85, 0.85, 1.0)
        ax.imshow(rgba, extent=extent, origin=origin, aspect=aspect, interpolation="nearest")
        return None, None
    cm = colormaps[cmap] if isinstance(cmap, str) else cmap
    cm = cm.with_extremes(bad="0.85", under=cm(0.0))
    norm = LogNorm(top * 10.0 ** (-log_decades), top) if log else Normalize(0.0, top)
    if log:   # LogNorm would mask zeros as "bad" (gray = no data): draw them in the lowest colour
        value = np.where(np.asarray(value) <= 0, top * 10.0 ** (-log_decades - 1), value)
    im = ax.imshow(np.ma.masked_invalid(value), extent=extent, origin=origin, aspect=aspect, cmap=cm, norm=norm,
                   interpolation="nearest")
    return im, norm


def _contours(ax, entries, xs, ys, *, log, log_decades, vmax, handles):
    """Iso-value lines of every entry (models overlaid) at shared levels, one colour per model."""
    from matplotlib.lines import Line2D

    from matplotlib.ticker import MaxNLocator

    top = vmax if vmax > 0 else 1.0
    if log:   # whole decades inside the colour range, at most four
        hi = math.floor(math.log10(top * 0.7))
        levels = [10.0 ** k for k in range(max(hi - 3, math.ceil(math.log10(top) - log_decades + 1)), hi + 1)]
    else:     # round numbers between 10% and 90% of the maximum
        levels = [v for v in MaxNLocator(nbins=4, steps=[1, 2, 2.5, 5, 10]).tick_values(0.1 * top, 0.9 * top)
                  if 0.1 * top <= v <= 0.9 * top]
    levels = levels or [0.5 * top]
    styles = ["-", "--", ":", "-."]
    for k, e in enumerate(entries):
        v = e["value"] if e["value"].ndim == 2 else luminance(e["value"])
        color = f"C{k % 10}"
        vv = np.nan_to_num(v)
        label = e["label"]
        if np.any(vv > levels[0]) and np.any(vv < levels[-1]) and np.ptp(vv) > 0:
            cs = ax.contour(xs, ys, np.ma.masked_invalid(v), levels=levels, colors=[color],
                            linestyles=styles[k % len(styles)], linewidths=1.3)
            ax.clabel(cs, fmt=lambda x: f"{x:g}", fontsize="x-small", inline=True)
        else:
            lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
            label += f" (no line: values {_fmt(lo)}" + (f"..{_fmt(hi)}" if hi > lo else "") + ")"
        handles.append(Line2D([], [], color=color, ls=styles[k % len(styles)], label=label))
    return levels


def _colorbar(ax, mappable, label, extend=None, inset=False):
    if mappable is None:
        return None
    if extend is None:
        extend = "min" if getattr(mappable.norm, "vmin", 0) > 0 else "neither"
    if inset:   # beside the drawn box (equal-aspect images leave the Axes box taller than the image)
        cax = ax.inset_axes([1.02, 0.05, 0.035, 0.9])
        cb = ax.figure.colorbar(mappable, cax=cax, extend=extend)
    else:
        cb = ax.figure.colorbar(mappable, ax=ax, shrink=0.85, pad=0.02, extend=extend)
    cb.set_label(label)
    return cb


def _note_all_zero(ax, entries):
    """A visible note when every model evaluates to 0 everywhere (delta lobes only)."""
    if all(not np.any(np.nan_to_num(e["value"]) > 0) for e in entries):
        ax.text(0.5, 0.5, "f = 0 for every pair of directions\n(delta lobes only: see the polar/3D arrows)",
                transform=ax.transAxes, ha="center", va="center", fontsize="small",
                bbox=dict(boxstyle="round", fc="white", ec="0.5", alpha=0.9))


# ================================================================ hemisphere image

def _side_signs(side, models, wo):
    s_wo = 1.0 if wo[2] >= 0 else -1.0
    if side == "auto":
        side = "both" if _transmits(models) else "reflection"
    return side, {"reflection": [s_wo], "transmission": [-s_wo], "both": [s_wo, -s_wo]}[side]


def _disk_grid(res, signs):
    """Azimuthal-equidistant disks (radius = angle from the side's pole, degrees), side by side
    200° apart: pixel centres xs (W,), ys (H,) and directions (H, W, 3) (NaN outside the disks)."""
    step = 180.0 / res
    width = 180.0 + 200.0 * (len(signs) - 1)
    xs = -90.0 + step * (np.arange(int(round(width / step))) + 0.5)
    ys = -90.0 + step * (np.arange(res) + 0.5)
    X, Y = np.meshgrid(xs, ys)
    wi = np.full(X.shape + (3,), np.nan)
    for k, s in enumerate(signs):
        dx = X - 200.0 * k
        r = np.hypot(dx, Y)
        inside = (r <= 90.0) & (np.abs(dx) <= 100.0)
        t, p = np.radians(r[inside]), np.arctan2(Y[inside], dx[inside])
        wi[inside] = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), s * np.cos(t)], -1)
    extent = (xs[0] - step / 2, xs[-1] + step / 2, ys[0] - step / 2, ys[-1] + step / 2)
    return xs, ys, wi, extent


def _thetaphi_grid(res, signs):
    lo = 0.0 if 1.0 in signs else 90.0
    hi = 180.0 if -1.0 in signs else 90.0
    n_t = max(2, int(round(res * (hi - lo) / 180.0)))
    dt, dp = (hi - lo) / n_t, 360.0 / (2 * res)
    ts = lo + dt * (np.arange(n_t) + 0.5)
    ps = dp * (np.arange(2 * res) + 0.5)
    T, P = np.meshgrid(np.radians(ts), np.radians(ps), indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    extent = (0.0, 360.0, hi, lo)
    return ps, ts, wi, extent


def _project(w, projection, signs):
    """(x, y) plot coordinates of a direction in the hemisphere() image, or None if not shown."""
    w = np.asarray(w, dtype=np.float64)
    if projection == "theta_phi":
        t = math.degrees(math.acos(max(-1.0, min(1.0, w[2]))))
        lo = 0.0 if 1.0 in signs else 90.0
        hi = 180.0 if -1.0 in signs else 90.0
        if not lo <= t <= hi:
            return None
        return math.degrees(math.atan2(w[1], w[0])) % 360.0, t
    for k, s in enumerate(signs):
        if s * w[2] >= 0:
            t = math.degrees(math.acos(max(-1.0, min(1.0, s * w[2]))))
            p = math.atan2(w[1], w[0])
            return 200.0 * k + t * math.cos(p), t * math.sin(p)
    return None


def hemisphere(model_or_list, theta_o=30.0, phi_o=0.0, projection="disk", log=False, cosine=False,
               channel="luminance", ax=None, res=121, label=None, *, side="auto", title=None, legend=True,
               colorbar=True, cmap="inferno", log_decades=4.0, mode=TransportMode.Radiance, n_delta=4096, seed=0,
               magnify_below=0.04):
    """Image of ``f(wo, wi)`` (or ``f |cos θi|`` with ``cosine=True``) over every direction wi.

    ``wo = bk.direction(radians(theta_o), radians(phi_o))`` (degrees in, marked "ωo"; its mirror
    direction, azimuth ``phi_o + 180``, is marked "+").

    projection:
      * ``"disk"``: azimuthal equidistant disk seen from above (+z): a direction at angle θ from
        the side's pole (+z for the upper, -z for the lower hemisphere) and azimuth φ is drawn at
        ``(θ cos φ, θ sin φ)`` degrees, so circles are 30°, 60°, 90° from the normal. With
        ``side="both"`` the transmission disk is drawn right of the reflection disk (centre at
        x = 200°).
      * ``"theta_phi"``: a latitude-longitude image, φ (0..360°) across and θ from +z (0..90°,
        or 0..180° with transmission) down.
    side: ``"auto"`` (``"both"`` when some model transmits, else ``"reflection"``),
    ``"reflection"`` (wo's hemisphere), ``"transmission"`` or ``"both"``.
    log: logarithmic colour scale spanning ``log_decades`` decades below the maximum.
    channel: "luminance", "r", "g", "b" or "rgb" (an RGB image scaled so that the maximum is white).
    A list of models: the first is drawn as the image, every model as iso-value lines in its colour
    (shared levels, in the legend). Delta (specular) lobes, which ``eval`` reports as 0, are
    marked with a star and their reflectance/transmittance.
    magnify_below: on a linear scale with both sides shown, when the weaker side of the (first)
    model peaks below this fraction of the stronger one, its colours are scaled by a round
    factor (said above that disk; the data stay unscaled); 0 or None turns this off.

    Returns the Axes; ``ax.bsdfkit_data`` has ``value`` (list, per model, (H, W) or (H, W, 3),
    NaN outside the projection), ``wi`` ((H, W, 3), NaN outside), ``wo``, ``x``, ``y`` (pixel
    centres, degrees), ``extent``, ``projection``, ``sides`` (+1 upper / -1 lower hemisphere),
    ``label``, ``model``, ``delta`` (per model, as in :func:`polar`), ``vmax``, ``cosine``,
    ``channel``, ``log``, ``levels`` (contour levels, when overlaid).
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

    q = _quantity(cosine)
    cb = None
    if colorbar:
        cb = _colorbar(ax, im, f"{q}{' (log scale)' if log else ''}" + (f" — {entries[0]['label']}"
                                                                      if len(entries) > 1 else ""),
                       inset=projection == "disk")
        if cb is None and channel == "rgb":
            ax.text(0.0, -0.02, f"RGB scaled so that {_fmt(vmax)} 1/sr is white", transform=ax.transAxes,
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


# ================================================================ half/difference image

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
             log_decades=4.0, vmax=None, grazing_deg=85.0, mode=TransportMode.Radiance):
    """θh × θd image of ``f`` (or ``f |cos θi|``) in Rusinkiewicz half/difference coordinates at
    a fixed ``phi_d`` (degrees; default 90°, Disney BRDF Explorer's slice) and ``phi_h``
    (degrees; matters for anisotropic models only).

    θh (the half vector's angle from the normal) runs across, θd (the angle between ωi and the
    half vector) up, both 0..90°. ``sqrt_theta_h=True`` spaces θh as √θh (as in MERL and BRDF
    Explorer) so that the specular peak near θh = 0 gets room; tick labels stay in degrees.
    Configurations with ωo or ωi below the horizon (none at φd = 90°; θh + θd > 90° at φd = 0°)
    are not reflection and are drawn gray (NaN in the data). Transmission is not part of this view.
    A list of models: the first is the image, every model is drawn as iso-value lines.
    log (default True) and vmax: f of microfacet models grows without bound towards θd = 90°
    (ωo and ωi grazing: the 1/(cos θo cos θi) factor), which would leave the rest of the image
    black. So by default (``vmax=None``) the colour scale tops out at the largest value with both
    ωo and ωi within ``grazing_deg`` of the normal; larger values are drawn in the top colour
    (the colorbar's upper arrow) and the true maximum is in the title.

    Returns the Axes; ``ax.bsdfkit_data`` has ``value`` (list per model, (res, res) or
    (res, res, 3), rows θd, columns θh, NaN where invalid), ``theta_h_deg`` (res,),
    ``theta_d_deg`` (res,), ``wo``/``wi`` ((res, res, 3)), ``valid`` ((res, res) bool),
    ``phi_d``, ``phi_h``, ``sqrt_theta_h``, ``label``, ``model``, ``vmax``, ``cosine``,
    ``channel``, ``log``.
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
    q = _quantity(cosine)
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


# ================================================================ 3D lobe

def lobe3d(model_or_list, theta_o=30.0, phi_o=0.0, log=False, cosine=False, channel="luminance", ax=None,
           n_theta=46, n_phi=91, label=None, *, sphere=None, title=None, legend=True, colorbar=True,
           cmap="viridis", log_decades=3.0, view=(22.0, -70.0), mode=TransportMode.Radiance, n_delta=4096, seed=0,
           alpha=None):
    """3D lobe: the surface ``r(ωi) ωi`` with radius ``r = f(wo, wi)`` (or ``f |cos θi|``;
    on a log scale, decades above ``max · 10^-log_decades``) over the upper hemisphere, or the
    whole sphere (``sphere=True``; default: when some model transmits).

    ``wo = bk.direction(radians(theta_o), radians(phi_o))`` is drawn as a dashed arrow, the
    surface as a gray circle, the normal as a thin line. One model: coloured by value (colorbar;
    ``channel="rgb"``: radius by luminance, colour = hue of f). Several models: one translucent
    colour each, with a legend. Delta lobes are drawn as arrows of length R (or T).

    Returns the 3D Axes; ``ax.bsdfkit_data`` has ``theta_deg`` (n_theta,), ``phi_deg`` (n_phi,),
    ``wi`` ((n_theta, n_phi, 3)), ``value`` (list per model, (n_theta, n_phi) or
    (n_theta, n_phi, 3)), ``radius`` (list per model, (n_theta, n_phi)), ``wo``, ``label``,
    ``model``, ``delta``, ``sphere``, ``cosine``, ``channel``, ``log``, ``log_floor``.
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

    entries = []
    for m, lab in zip(models, labels):
        val = _values(m, wo, wi, cosine, channel, mode)
        delta = []
        if m.flags & BxDFFlags.Specular:
            for lobe in _delta_lobes(m, wo, xdir, n_delta, seed, mode):
                lobe["value"] = _select(lobe["weight"], channel)
                delta.append(lobe)
        entries.append(dict(model=m, label=lab if lab is not None else describe(m), value=val, delta=delta))
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


# ================================================================ sampling quality

def _gauss_legendre(a, b, n_bins, q):
    """Nodes (n_bins * q,) and weights of a q-point Gauss-Legendre rule on each of n_bins equal
    sub-intervals of [a, b], plus the bin index of each node."""
    x, w = np.polynomial.legendre.leggauss(q)
    edges = np.linspace(a, b, n_bins + 1)
    half = 0.5 * np.diff(edges)
    mid = 0.5 * (edges[:-1] + edges[1:])
    nodes = (mid[:, None] + half[:, None] * x[None, :]).ravel()
    weights = (half[:, None] * w[None, :]).ravel()
    return nodes, weights, np.repeat(np.arange(n_bins), q), edges


def _gammaincc(a, x):
    """Regularized upper incomplete gamma function Q(a, x) (series for x < a + 1, else Lentz's
    continued fraction; Numerical Recipes 6.2). Avoids importing scipy (~2 s) for one number."""
    if x <= 0:
        return 1.0
    lead = math.exp(-x + a * math.log(x) - math.lgamma(a))
    if x < a + 1:
        term = total = 1.0 / a
        ap = a
        for _ in range(10_000):
            ap += 1
            term *= x / ap
            total += term
            if abs(term) < abs(total) * 1e-15:
                break
        return max(0.0, 1.0 - total * lead)
    tiny = 1e-300
    b = x + 1 - a
    c, d = 1 / tiny, 1 / b
    h = d
    for i in range(1, 10_000):
        an = -i * (i - a)
        b += 2
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1 / d
        delta = d * c
        h *= delta
        if abs(delta - 1) < 1e-15:
            break
    return min(1.0, lead * h)


def _chi2_sf(x, k):
    """Upper tail P(X > x) of the chi-square distribution with k degrees of freedom."""
    if k <= 0:
        return float("nan")
    return _gammaincc(0.5 * k, 0.5 * x)


def sample_stats(model, theta_o=30.0, phi_o=0.0, n=200_000, seed=0, *, n_theta=90, n_phi=36, quad=12,
                 mode=TransportMode.Radiance, min_expected=5.0):
    """Sampled directions of ``model.sample`` against ``model.pdf``, binned over the sphere.

    Bins: ``n_theta`` equal bins of θi over 0..180° times ``n_phi`` bins of φi over 0..360°.
    ``counts`` are the non-delta valid samples per bin; ``expected = n ∫_bin pdf dω`` by a
    ``quad`` × ``quad`` Gauss-Legendre rule per bin. Pearson's χ² pools the bins with fewer than
    ``min_expected`` expected samples into one cell. Delta-lobe samples (flag Specular) have a
    discrete pdf and are only counted (``n_specular``).

    Returns a dict: ``theta_edges``, ``phi_edges`` (degrees), ``counts``, ``expected``
    ((n_theta, n_phi)), ``solid_angle`` (per bin, sr), ``n``, ``n_valid``, ``n_specular``,
    ``chi2``, ``dof``, ``p_value`` (None when fewer than 2 cells), ``theta_hist``/``theta_pdf``
    (densities of θi in 1/°: samples and ∫ pdf dφ), ``wo``.
    """
    n = _check_int(n, "n", 1)
    wo = _wo_dir(_finite(theta_o, "theta_o"), _finite(phi_o, "phi_o"))
    s = model.sample(wo, n=n, seed=seed, mode=mode)
    spec = s.valid & ((s.flags & int(BxDFFlags.Specular)) != 0)
    ok = s.valid & ~spec
    w = s.wi[ok]
    th = np.degrees(np.arccos(np.clip(w[:, 2], -1.0, 1.0)))
    ph = np.degrees(np.arctan2(w[:, 1], w[:, 0])) % 360.0
    t_nodes, t_w, t_bin, t_edges = _gauss_legendre(0.0, math.pi, n_theta, quad)
    p_nodes, p_w, p_bin, p_edges = _gauss_legendre(0.0, 2 * math.pi, n_phi, quad)
    counts, _, _ = np.histogram2d(th, ph, bins=[np.degrees(t_edges), np.degrees(p_edges)])
    T, P = np.meshgrid(t_nodes, p_nodes, indexing="ij")
    dirs = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    pdf = model.pdf(wo, dirs, mode=mode)
    integrand = pdf * (np.sin(t_nodes) * t_w)[:, None] * p_w[None, :]
    per_bin = np.add.reduceat(np.add.reduceat(integrand, np.arange(0, n_theta * quad, quad), axis=0),
                              np.arange(0, n_phi * quad, quad), axis=1)
    expected = n * per_bin
    solid = np.outer(np.cos(t_edges[:-1]) - np.cos(t_edges[1:]), np.diff(p_edges))
    big = expected >= min_expected
    obs_cells = list(counts[big])
    exp_cells = list(expected[big])
    if np.any(~big) and expected[~big].sum() > 0:
        obs_cells.append(counts[~big].sum())
        exp_cells.append(expected[~big].sum())
    obs_cells, exp_cells = np.asarray(obs_cells), np.asarray(exp_cells)
    if len(exp_cells) >= 2:
        stat = float(np.sum((obs_cells - exp_cells) ** 2 / exp_cells))
        dof = len(exp_cells) - 1
        p_value = _chi2_sf(stat, dof)
    else:
        stat, dof, p_value = float("nan"), 0, None
    dtheta = 180.0 / n_theta
    refl = (s.flags & int(BxDFFlags.Reflection)) != 0
    return dict(theta_edges=np.degrees(t_edges), phi_edges=np.degrees(p_edges), counts=counts, expected=expected,
                solid_angle=solid, n=n, n_valid=int(np.count_nonzero(s.valid)), n_specular=int(np.count_nonzero(spec)),
                n_specular_reflection=int(np.count_nonzero(spec & refl)),
                n_specular_transmission=int(np.count_nonzero(spec & ~refl)),
                chi2=stat, dof=dof, p_value=p_value, theta_hist=counts.sum(axis=1) / (n * dtheta),
                theta_pdf=expected.sum(axis=1) / (n * dtheta), wo=wo)


def samples(model_or_list, theta_o=30.0, phi_o=0.0, n=200_000, seed=0, kind="theta", ax=None, label=None, *,
            n_theta=90, n_phi=36, quad=12, mode=TransportMode.Radiance, title=None, legend=True, log=False,
            cmap="viridis"):
    """Sampling quality: where ``model.sample(wo, n)`` sends directions against what ``model.pdf``
    says (see :func:`sample_stats` for the binning and the χ² test).

    kind="theta" (one Axes; models overlaid): density of θi in 1/° — the samples' histogram
    (steps) and ∫ pdf dφ per bin (line) — against θi (0..90°, or 0..180° when a model transmits),
    with the χ² p-value in the legend.
    kind="image" (first model only; two Axes: ``ax`` may be a pair): sample density and pdf
    (mean over each bin, 1/sr) in θi × φi images on a shared colour scale.

    Returns the Axes (kind "theta") or a tuple of the two Axes (kind "image"); their
    ``bsdfkit_data`` has ``stats`` (list per model of :func:`sample_stats` dicts), ``label``,
    ``model``, ``theta_o``, ``phi_o``, ``kind``.
    """
    models = _as_models(model_or_list)
    labels = _as_labels(label, len(models))
    kind = _check_choice(kind, "kind", ("theta", "image"))
    theta_o, phi_o = _finite(theta_o, "theta_o"), _finite(phi_o, "phi_o")
    stats = [sample_stats(m, theta_o, phi_o, n, seed, n_theta=n_theta, n_phi=n_phi, quad=quad, mode=mode)
             for m in models]
    labs = [lab if lab is not None else describe(m) for m, lab in zip(models, labels)]
    data = dict(kind="samples", stats=stats, label=labs, model=models, theta_o=theta_o, phi_o=phi_o, view=kind)

    def ptxt(st):
        if st["p_value"] is None:
            return "no χ² (no non-delta samples)"
        return f"χ² p = {st['p_value']:.2g}"

    if kind == "theta":
        if ax is None:
            ax = _new_figure((7.0, 4.4)).add_subplot()
        elif getattr(ax, "name", None) != "rectilinear":
            raise ValueError("ax: samples() needs a rectilinear Axes")
        tmax = 180.0 if _transmits(models) else 90.0
        ymax = 0.0
        notes = []
        for k, (st, lab) in enumerate(zip(stats, labs)):
            color = f"C{k % 10}"
            edges = st["theta_edges"]
            centers = 0.5 * (edges[:-1] + edges[1:])
            pre = f"{lab}: " if len(models) > 1 else ""
            if st["n_specular"] < st["n_valid"]:
                ax.stairs(st["theta_hist"], edges, color=color, lw=1.0, fill=True, alpha=0.3,
                          label=f"{pre}samples (histogram)")
                ax.plot(centers, st["theta_pdf"], color=color, lw=1.8, label=f"{pre}pdf ∫ dφ, {ptxt(st)}")
            ymax = max(ymax, float(np.max(st["theta_hist"], initial=0.0)), float(np.max(st["theta_pdf"], initial=0.0)))
            if st["n_specular"]:
                parts = [f"{kind} {cnt / st['n']:.1%}" for kind, cnt in (("R", st["n_specular_reflection"]),
                                                                        ("T", st["n_specular_transmission"]))
                         if cnt]
                notes.append((f"{pre}samples in delta lobes: {', '.join(parts)}\n(not binned: a delta lobe has a "
                              "probability,\nnot a density)", color))
        for k, (txt, color) in enumerate(notes):
            ax.text(0.5, 0.6 - 0.2 * k, txt, transform=ax.transAxes, ha="center", va="center", fontsize="small",
                    color=color, bbox=dict(boxstyle="round", fc="white", ec="none", alpha=0.85))
        ax.axvline(theta_o, color="k", ls="--", lw=1.0, label=f"θo = {theta_o:g}°")
        if tmax > 90:
            ax.axvline(90.0, color="0.3", lw=1.0)
            ax.text(91, 0.5, "transmission →", transform=ax.get_xaxis_transform(), fontsize="x-small", color="0.3")
        ax.set_xlim(0, tmax)
        ax.set_xticks(np.arange(0, tmax + 1, 15 if tmax <= 90 else 30))
        if log:
            ax.set_yscale("log")
            ax.set_ylim(max(ymax, 1e-6) * 1e-4, max(ymax, 1e-6) * 2)
        else:
            ax.set_ylim(0, ymax * 1.1 if ymax > 0 else 1.0)
        ax.set_xlabel("θi, sampled direction from the normal [°]")
        ax.set_ylabel("density of θi [1/°]")
        ax.grid(True, alpha=0.3)
        n_txt = f"{stats[0]['n']:,}".replace(",", " ")
        if title is None:
            title = (f"Sampling vs pdf, θo = {theta_o:g}°, φo = {phi_o:g}° ({n_txt} samples)"
                     + (f"\n{labs[0]}" if len(models) == 1 else ""))
        if title:
            ax.set_title(title, fontsize="medium")
        if legend:
            ax.legend(fontsize="small", loc="best")
        return _set_data(ax, data)

    # kind == "image"
    if ax is None:
        fig = _new_figure((11.0, 4.4))
        axes = fig.subplots(1, 2, sharex=True, sharey=True)
    else:
        axes = list(ax)
        if len(axes) != 2:
            raise ValueError("ax: samples(kind='image') needs two Axes")
    st, lab = stats[0], labs[0]
    tmax = 180.0 if _transmits(models[:1]) else 90.0
    nt = int(round(len(st["theta_edges"]) - 1) * tmax / 180.0)
    hist = st["counts"][:nt] / (st["n"] * st["solid_angle"][:nt])
    pdfm = st["expected"][:nt] / (st["n"] * st["solid_angle"][:nt])
    vmax = _positive_max([hist, pdfm])
    extent = (0.0, 360.0, tmax, 0.0)
    im = None
    for a, img, name in ((axes[0], hist, "sampled density"), (axes[1], pdfm, "pdf (bin mean)")):
        im, _ = _scalar_image(a, img, extent, log=log, log_decades=4.0, vmax=vmax, cmap=cmap, origin="upper",
                              aspect="auto", channel="luminance")
        a.set_title(f"{name} [1/sr]", fontsize="medium")
        a.set_xlabel("φi, azimuth [°]")
        a.set_xticks(np.arange(0, 361, 90))
        if tmax > 90:
            a.axhline(90, color="w", lw=0.8)
    axes[0].set_ylabel("θi from the normal [°]")
    axes[1].figure.colorbar(im, ax=list(axes), shrink=0.85, pad=0.02).set_label("density per solid angle [1/sr]")
    if title is None:
        title = f"{lab}: θo = {theta_o:g}°, φo = {phi_o:g}°, {ptxt(st)}"
    if title:
        axes[0].figure.suptitle(title, fontsize="medium")
    for a in axes:
        _set_data(a, data)
    return tuple(axes)


# ================================================================ all views at once

#: The views of :func:`overview` (and of :func:`explore`), in their default order.
VIEWS = ("polar", "lobe3d", "hemisphere", "halfdiff", "albedo", "samples")
_PROJECTIONS = {"polar": "polar", "lobe3d": "3d"}


def overview(model_or_list, theta_o=30.0, phi_o=0.0, views=VIEWS, *, log=False, cosine=None, channel="luminance",
             fig=None, ncols=3, n_samples=100_000, albedo_samples=32768, albedo_theta=31, res=96, seed=0,
             title=None):
    """Several views of the same model(s) at one ``wo`` in one figure (the CLI ``lobes`` command,
    :func:`explore` and the notebooks use it).

    views: names from :data:`VIEWS`. ``phi_o`` is wo's azimuth (degrees); the polar slice is the
    plane of wo (its ``phi_plane = phi_o + 180``, so the mirror direction is at +θo). log,
    cosine and channel apply to every view that has them (``cosine=None``: f |cos| when a model is
    defined over the whole sphere with f divided by |cos| as Hair is, else f). ``fig``: a Figure
    to draw into (a new pyplot figure otherwise).

    Returns the Figure; ``fig.bsdfkit_axes`` maps each view name to its Axes (each with its
    ``bsdfkit_data``).
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
    axes = {}
    for i, v in enumerate(views):
        ax = fig.add_subplot(nrows, ncols, i + 1, projection=_PROJECTIONS.get(v))
        axes[v] = ax
        if v == "polar":
            polar(models, theta_o=theta_o, phi_plane=phi_o + 180.0, log=log, cosine=cosine, channel=channel, ax=ax,
                  title=f"in-plane slice, {_quantity(cosine)}{' (log)' if log else ''}\nvs θi [°] (plane of ωo)",
                  legend=len(models) > 1)
        elif v == "lobe3d":
            lobe3d(models, theta_o=theta_o, phi_o=phi_o, log=log, cosine=cosine, channel=channel, ax=ax,
                   n_theta=31, n_phi=61, legend=len(models) > 1)
        elif v == "hemisphere":
            hemisphere(models, theta_o=theta_o, phi_o=phi_o, log=log, cosine=cosine, channel=channel, ax=ax,
                       res=res, legend=True,
                       title=f"{_quantity(cosine)} over ωi{' (log)' if log else ''}, disks seen from above")
        elif v == "halfdiff":
            halfdiff(models, log=True, cosine=cosine, channel=channel, ax=ax, res=res,
                     title=f"{_quantity(cosine)} (log), θh × θd at φd = 90°")
        elif v == "albedo":
            albedo(models, n_theta=albedo_theta, n_samples=albedo_samples, channel=channel, ax=ax, seed=seed,
                   title=f"directional albedo ({albedo_samples} samples per θo)\ndashed: white furnace ρ = 1, "
                         f"dotted: θo = {theta_o:g}°", legend=len(models) > 1)
            ax.axvline(min(theta_o, 90.0), color="k", ls=":", lw=1.0)
        elif v == "samples":
            samples(models, theta_o=theta_o, phi_o=phi_o, n=n_samples, seed=seed, ax=ax,
                    title=f"sampling: histogram vs pdf ({n_samples:,} samples)".replace(",", " "))
    if title is None:
        title = (", ".join(describe(m) for m in models) + f"  —  ωo at θo = {theta_o:g}°, φo = {phi_o:g}°"
                 + f"  ({channel}{', log' if log else ''}{', ×cos' if cosine else ''})")
    if title:
        fig.suptitle(title, fontsize="large")
    fig.bsdfkit_axes = axes
    return fig


# ================================================================ gallery of every model

def gallery(models=None, theta_o=40.0, *, fig=None, res=96, albedo_samples=16384, albedo_theta=31, row_height=4.4):
    """One row per model — in-plane polar slice, hemisphere image, directional albedo (RGB and
    luminance) — at ``theta_o`` (degrees).

    models: a list of models, or None for one example of every class in ``bsdfkit.MODELS``
    (``bsdfkit._spec.example_model``: default parameters, or the class's entry of
    ``bsdfkit._spec.EXAMPLES``; a new class with required parameters and no example raises
    LookupError, so the gallery never silently skips a model).

    Returns the Figure (a pyplot figure unless ``fig`` is given); ``fig.bsdfkit_rows`` is a list
    of ``(model, {"polar": ax, "hemisphere": ax, "albedo": ax})``.
    """
    if models is None:
        from . import MODELS
        from ._spec import example_model

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


# ================================================================ interactive exploration

_UNIT_PARAMS = ("alpha", "roughness", "metallic", "reflectance", "transmittance", "color", "clear_coat", "sheen")


def _slider_range(name, default):
    if name == "anisotropy":
        return -1.0, 1.0, 0.01
    if name.startswith("eta") or name == "ior":
        return 0.5, 3.0, 0.01
    if any(t in name for t in _UNIT_PARAMS):
        return 0.0, 1.0, 0.01
    hi = max(1.0, 2.0 * abs(float(default)))
    return (-hi if default < 0 else 0.0), hi, hi / 100.0


def _factory_params(model_factory):
    """(factory, {name: default}) from a model instance, a model class or a callable."""
    import inspect

    if isinstance(model_factory, BxDF):
        base = model_factory
        params = {}
        for k, v in base._params.items():
            if isinstance(v, np.ndarray) and v.shape == (3,) and np.all(v == v[0]):
                v = float(v[0])
            if isinstance(v, (bool, float)):   # integers are knobs (table sizes), not appearance
                params[k] = v

        def factory(**kw):
            p = dict(base._params)
            p.update(kw)
            return type(base)._from_params(p)

        return factory, params
    if isinstance(model_factory, type) and issubclass(model_factory, BxDF):
        from ._spec import example_model

        return _factory_params(example_model(model_factory))
    if not callable(model_factory):
        raise TypeError("model_factory: expected a callable returning a model, a model class or a model")
    params = {}
    for p in inspect.signature(model_factory).parameters.values():
        if p.default is not inspect.Parameter.empty and isinstance(p.default, (bool, int, float, str)):
            params[p.name] = p.default
    return model_factory, params


def _auto_control(name, default, choices):
    """Whether explore() makes a control for a parameter: floats and bools always; integers and
    strings only when ``params=`` gives their range or choices."""
    return isinstance(default, (bool, float)) or name in choices


class Explorer:
    """The widget of :func:`explore`: ``.widget`` (an ipywidgets HBox, shown when the Explorer is
    the last expression of a cell), ``.controls`` (name -> widget), ``.model`` (the current
    model), ``.figure`` (the last drawn Figure), ``.png`` (its PNG bytes, as shown),
    ``.update()`` (rebuild the model and the Figure), ``.error`` (the last model construction
    error, or None)."""

    def __init__(self, factory, params, views, theta_o, phi_o, choices, overview_kw):
        import ipywidgets as W

        self._factory = factory
        self._views = tuple(views)
        self._kw = overview_kw
        self.figure = None
        self.model = None
        self.error = None
        self.png = None
        style = {"description_width": "90px"}
        layout = W.Layout(width="330px")
        c = {}
        c["theta_o"] = W.FloatSlider(value=theta_o, min=0.0, max=89.0, step=0.5, description="θo [°]",
                                     continuous_update=False, style=style, layout=layout)
        c["phi_o"] = W.FloatSlider(value=phi_o, min=0.0, max=360.0, step=1.0, description="φo [°]",
                                   continuous_update=False, style=style, layout=layout)
        self._model_keys = []
        for name, default in params.items():
            if not _auto_control(name, default, choices):
                continue
            is_range = name in choices and isinstance(choices[name], tuple) and len(choices[name]) == 3 and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in choices[name])
            if name in choices and not is_range:
                w = W.Dropdown(options=list(choices[name]), value=default, description=name, style=style,
                               layout=layout)
            elif isinstance(default, bool):
                w = W.Checkbox(value=default, description=name, style=style, layout=layout)
            elif isinstance(default, int) and is_range:
                lo, hi, step = (int(x) for x in choices[name])
                w = W.IntSlider(value=default, min=lo, max=hi, step=step, description=name,
                                continuous_update=False, style=style, layout=layout)
            elif isinstance(default, (int, float)):
                lo, hi, step = choices.get(name, _slider_range(name, default))
                w = W.FloatSlider(value=float(default), min=lo, max=hi, step=step, description=name,
                                  continuous_update=False, style=style, layout=layout, readout_format=".3g")
            else:
                w = W.Text(value=str(default), description=name, continuous_update=False, style=style,
                           layout=layout)
            c[name] = w
            self._model_keys.append(name)
        c["log"] = W.Checkbox(value=False, description="log scale", style=style, layout=layout)
        c["cosine"] = W.Checkbox(value=False, description="× cos θi", style=style, layout=layout)
        c["channel"] = W.Dropdown(options=list(_CHANNELS), value="luminance", description="channel", style=style,
                                  layout=layout)
        self.controls = c
        self._out = W.Output()
        self._msg = W.HTML()
        for w in c.values():
            w.observe(lambda _change: self._redraw(), names="value")
        self.widget = W.HBox([W.VBox(list(c.values()) + [self._msg]), self._out])
        self._redraw()

    def _values(self):
        return {k: w.value for k, w in self.controls.items()}

    def update(self):
        """Build the model from the controls and draw the views; returns the Figure (None if the
        parameters are invalid: then ``.error`` holds the message)."""
        from matplotlib.figure import Figure

        v = self._values()
        kw = {k: v[k] for k in self._model_keys}
        try:
            self.model = self._factory(**kw)
            self.error = None
        except (ValueError, TypeError) as e:
            self.error = str(e)
            return None
        fig = Figure(figsize=self._kw.get("figsize", (15.0, 9.0)))
        overview(self.model, theta_o=v["theta_o"], phi_o=v["phi_o"], views=self._views, log=v["log"],
                 cosine=v["cosine"], channel=v["channel"], fig=fig,
                 **{k: a for k, a in self._kw.items() if k not in ("figsize", "dpi")})
        self.figure = fig
        return fig

    def _redraw(self):
        fig = self.update()
        self._msg.value = "" if self.error is None else f"<span style='color:#b00'>invalid: {self.error}</span>"
        if fig is None:
            return
        # The PNG goes straight into the Output widget's state: no output capture (``with out:``),
        # whose message routing made headless runs (nbclient) stall until the cell timeout, and no
        # dependence on the matplotlib backend (inline or Agg).
        import base64
        import io

        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=self._kw.get("dpi", 80))
        self.png = buf.getvalue()
        self._out.outputs = ({"output_type": "display_data", "metadata": {},
                              "data": {"image/png": base64.b64encode(self.png).decode("ascii"),
                                       "text/plain": f"<bsdfkit views of {describe(self.model)}>"}},)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


def explore(model_factory, theta_o=30.0, phi_o=0.0, views=VIEWS, *, params=None, **overview_kw):
    """Interactive views in Jupyter: sliders for θo, φo and the model's parameters, toggles for
    log scale, × cos θi and the channel; every change redraws :func:`overview`.

    model_factory: a callable whose keyword parameters with number/bool defaults become
    controls (``lambda alpha=0.2, eta=1.5: bk.Dielectric(eta, alpha=alpha)``), a model (its
    real and boolean parameters become controls, RGB ones when gray) or a model class (its
    example model, ``bsdfkit._spec.example_model``). params: ``{name: (min, max, step)}`` (a
    tuple) to set a slider's range (needed for integer parameters), or ``{name: [choices]}``
    (a list) for a dropdown (needed for string parameters). Other keywords go to :func:`overview`
    (plus ``figsize`` in inches and ``dpi`` of the shown PNG, default 80). Invalid parameter values show the model's error message instead of the
    plots.

    Needs ipywidgets (``pip install ipywidgets``); raises ImportError saying so otherwise.
    Returns an :class:`Explorer` (displayed as the widget).
    """
    try:
        import ipywidgets  # noqa: F401
    except ImportError:
        raise ImportError("bsdfkit.plot.explore needs ipywidgets, which is not installed: "
                          "pip install ipywidgets (the static views -- polar, lobe3d, hemisphere, halfdiff, "
                          "albedo, samples, overview -- work without it)") from None
    factory, defaults = _factory_params(model_factory)
    choices = dict(params or {})
    unknown = [k for k in choices if k not in defaults]
    if unknown:
        raise ValueError(f"params: {unknown[0]!r} is not a parameter of the model factory "
                         f"(parameters: {', '.join(defaults) or 'none'})")
    for v in views:
        _check_choice(v, "views", VIEWS)
    return Explorer(factory, defaults, views, _finite(theta_o, "theta_o"), _finite(phi_o, "phi_o"), choices,
                    overview_kw)


# ---------------------------------------------------------------- speed vs accuracy

def pareto(table, ax=None, metric="p99"):
    """Throughput against error of every configuration in a ``bsdfkit.tradeoff`` table, with the
    Pareto front highlighted (see :func:`bsdfkit.tradeoff.pareto`). Returns the Axes."""
    from .tradeoff import pareto as _pareto
    return _pareto(table, ax=ax, metric=metric)
