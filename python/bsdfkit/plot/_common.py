"""Helpers shared by the plot views: channels, argument checks, figure and colour-map plumbing, direction grids."""
from __future__ import annotations

import math

import numpy as np

from .._enums import BxDFFlags
from ..models.describe import _fmt
from ..models import BxDF
from .._validate import check_int as _check_int  # noqa: F401  (the plot modules)

__all__ = ["LUMINANCE_WEIGHTS", "luminance"]


#: Rec. 709 / sRGB luminance weights of linear R, G, B.
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])


_CHANNELS = ("luminance", "r", "g", "b", "rgb")


_RGB_COLORS = ("tab:red", "tab:green", "tab:blue")


_RGB_STYLES = ("-", "--", ":", "-.")


def luminance(rgb) -> np.ndarray:
    """Luminance 0.2126 R + 0.7152 G + 0.0722 B of (..., 3) linear RGB values.

    Parameters
    ----------
    rgb : array_like, shape (..., 3)
        Linear RGB.

    Returns
    -------
    numpy.ndarray, shape (...)
        The luminance.

    Examples
    --------
    >>> from bsdfkit import plot as bkplot
    >>> float(bkplot.luminance([1.0, 1.0, 1.0]))
    1.0
    """
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


def _new_axes(polar_axes: bool):
    import matplotlib.pyplot as plt  # lazy: only when the caller did not give an Axes

    fig = plt.figure(figsize=(6.4, 6.4) if polar_axes else (7.0, 4.6), layout="constrained")
    return fig.add_subplot(projection="polar" if polar_axes else None)


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


def _check_choice(v, name, allowed):
    if v not in allowed:
        raise ValueError(f"{name}: must be one of {', '.join(map(repr, allowed))}, got {v!r}")
    return v


def _transmits(models) -> bool:
    """Whether a plot must show the whole sphere: a transmitting model, or one defined over the
    whole sphere (the ``full_sphere`` capability, e.g. Hair)."""
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
