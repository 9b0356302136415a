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

__all__ = ["polar", "albedo", "describe", "luminance", "LUMINANCE_WEIGHTS"]

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
    return repr(model)


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

def polar(model_or_list, theta_o=30.0, phi_plane=0.0, cosine=True, log=False, channel="luminance",
          ax=None, n=721, label=None, *, title=None, legend=True, log_decades=4.0,
          mode=TransportMode.Radiance, n_delta=4096, seed=0, colors=None, linestyle="-",
          annotate_delta=True, magnify_below=0.04):
    """In-plane slice of the lobe(s) over the full circle, in a polar Axes.

    Plots ``f(wo, wi) |cos θi|`` (or ``f`` if ``cosine=False``) for ``wi`` in the plane of
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
