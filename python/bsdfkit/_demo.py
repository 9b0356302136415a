"""``python -m bsdfkit demo``: a gallery of every model, written as PNG and markdown files.

Figures are built with ``matplotlib.figure.Figure`` (no pyplot, no GUI backend needed).
"""
from __future__ import annotations

import math
import os
import textwrap
import time

import numpy as np

from . import plot as _plot
from ._enums import TransportMode

#: Incident angles (degrees) of the lobe grid columns and of the albedo table.
THETAS = (0, 30, 60, 80)
#: Samples per θo for the albedo figure and the albedo table.
PLOT_SAMPLES = 8192
TABLE_SAMPLES = 65536
#: Incident angle (degrees) and sample count of views.png.
VIEWS_THETA = 40
VIEWS_SAMPLES = 50_000


def configurations():
    """The demo's model configurations: a list of (spec, model), the first registered example of
    every model class (the gallery's rows), in registry order."""
    from .models import registry
    from .models.spec import example_model, example_spec

    return [(example_spec(cls), example_model(cls)) for cls in registry.classes()]


def _anisotropic(model) -> bool:
    p = model._params
    return "alpha_x" in p and p["alpha_x"] != p["alpha_y"]


def _is_gray(model) -> bool:
    """True when all three channels of the model are equal (its RGB curves would coincide)."""
    return all(np.ptp(np.asarray(v)) == 0 for v in model._params.values() if isinstance(v, np.ndarray))


def _refracts(model) -> bool:
    """True when Radiance-mode transmission is scaled by 1/η² (a real index change)."""
    cls = type(model)
    return cls.transmission and not cls.delta_only and float(model._params.get("eta", 1.0)) != 1.0


def _lobes_figure(configs, path):
    from matplotlib.figure import Figure

    # more than 10 models: two groups side by side (the figure stays under ~6000 px tall), each
    # model one row of len(THETAS) panels, a spacer column for the second group's labels
    nt = len(THETAS)
    groups = 2 if len(configs) > 10 else 1
    nrow = -(-len(configs) // groups)
    # fixed margins: constrained layout would more than double the (polar-heavy) drawing time
    w, h = (3.3 * nt + 1.5) * groups, 3.45 * nrow + 1.7
    fig = Figure(figsize=(w, h))
    ratios = ([1.0] * nt + [0.42]) * (groups - 1) + [1.0] * nt
    gs = fig.add_gridspec(nrow, len(ratios), width_ratios=ratios, left=1.2 / w, right=1 - 0.35 / w,
                          top=1 - 1.45 / h, bottom=0.3 / h, wspace=0.32, hspace=0.42)
    axes = np.empty((len(configs), nt), dtype=object)
    for i in range(len(configs)):
        g, r = divmod(i, nrow)
        for j in range(nt):
            axes[i, j] = fig.add_subplot(gs[r, g * (nt + 1) + j], projection="polar")
    for i, (name, m) in enumerate(configs):
        for j, th in enumerate(THETAS):
            ax = axes[i, j]
            if _anisotropic(m):
                p = m._params
                _plot.polar(m, theta_o=th, phi_plane=0, cosine=True, ax=ax, title="", legend=False,
                            label=f"φ=0° plane (αx={p['alpha_x']:g})", colors=["C4"])
                _plot.polar(m, theta_o=th, phi_plane=90, cosine=True, ax=ax, title="", legend=False,
                            label=f"φ=90° plane (αy={p['alpha_y']:g})", colors=["C1"], linestyle="--")
            else:
                _plot.polar(m, theta_o=th, cosine=True, ax=ax, title="", legend=False, colors=[f"C{i % 10}"])
            ax.set_title(f"θo = {th}°", fontsize="medium", pad=8)
            if j == 0:
                # class name (bold) over its parameters, wrapped to the row's height
                cls, _, rest = _plot.describe(m).partition(" ")
                lines = textwrap.wrap(rest, 34)
                if _anisotropic(m):
                    lines.append("solid: φ = 0° plane, dashed: φ = 90°")
                ax.text(-0.33 if len(lines) > 1 else -0.27, 0.5, f"$\\bf{{{cls}}}$\n" + "\n".join(lines),
                        transform=ax.transAxes, rotation=90, ha="center", va="center", fontsize="medium",
                        linespacing=1.3)
    fig.suptitle("In-plane lobe slices: f·|cos θi| [1/sr] (luminance) vs signed angle θi from the normal [°]\n"
                 "reflection above the surface line, transmission below; dashed: ωo at −θo (mirror at +θo); "
                 "arrows: delta lobes, length = reflectance R / transmittance T [unitless]",
                 fontsize="large", y=1 - 0.2 / h, va="top")
    fig.savefig(path, dpi=90)


def _albedo_figure(configs, path):
    from matplotlib.figure import Figure

    ncol = 4
    nrow = math.ceil(len(configs) / ncol)
    fig = Figure(figsize=(4.6 * ncol, 3.9 * nrow + 0.8), layout="constrained")
    # y not shared: most albedos are <= 1, but a radiance-mode albedo can exceed it (NormalizedFresnel: eta^2)
    axes = fig.subplots(nrow, ncol, squeeze=False, sharex=True)
    for k, (name, m) in enumerate(configs):
        ax = axes.flat[k]
        gray = _is_gray(m)
        if not gray:
            _plot.albedo(m, n_samples=PLOT_SAMPLES, ax=ax, channel="rgb", label="", title="", legend=False)
        _plot.albedo(m, n_samples=PLOT_SAMPLES, ax=ax, channel="luminance",
                     label="luminance (R = G = B)" if gray else "luminance", colors=["k"], title="", legend=False)
        if _refracts(m):
            _plot.albedo(m, n_samples=PLOT_SAMPLES, ax=ax, label="Importance mode (energy, no 1/η²)",
                         mode=TransportMode.Importance, colors=["tab:purple"], linestyle=(0, (1, 1.5)),
                         title="", legend=False)
        ax.set_title(_plot.describe(m), fontsize="medium")
        handles, labels = ax.get_legend_handles_labels()
        keep = [(h, lab.replace(" [", "").replace("]", "") if lab.startswith(" [") else lab)
                for h, lab in zip(handles, labels)]
        top = max([1.0] + [float(np.nanmax(ln.get_ydata())) for ln in ax.lines if len(ln.get_ydata())])
        ax.set_ylim(0, 1.1 * top)
        ax.legend(*zip(*keep), fontsize="small", loc="best", ncol=1 if gray else 2, framealpha=0.85)
        if k % ncol:
            ax.set_ylabel("")
        if k < len(configs) - ncol:
            ax.set_xlabel("")
    for ax in axes.flat[len(configs):]:
        ax.set_visible(False)
    fig.suptitle(f"Directional albedo ρ(θo) = ∫ f |cos θi| dωi, Radiance mode, {PLOT_SAMPLES} samples per θo "
                 "(R, G, B and luminance; dashed: white furnace ρ = 1)", fontsize="large")
    fig.savefig(path, dpi=90)


def _views_figure(configs, path, theta_o=VIEWS_THETA):
    """One row per configuration: 3D lobe, hemisphere image, θh × θd image and sampling check."""
    from matplotlib.figure import Figure

    cols = ("lobe3d", "hemisphere", "halfdiff", "samples")
    nrow = len(configs)
    w, h = 22.0, 4.3 * nrow + 1.5
    fig = Figure(figsize=(w, h))   # fixed margins: constrained layout triples the drawing time here
    fig.subplots_adjust(left=0.5 / w, right=1 - 0.3 / w, top=1 - 1.5 / h, bottom=0.4 / h, wspace=0.45, hspace=0.45)
    for i, (name, m) in enumerate(configs):
        for j, view in enumerate(cols):
            ax = fig.add_subplot(nrow, len(cols), i * len(cols) + j + 1,
                                 projection="3d" if view == "lobe3d" else None)
            if view == "lobe3d":
                _plot.lobe3d(m, theta_o=theta_o, ax=ax, n_theta=25, n_phi=49, legend=False,
                             title=f"{_plot.describe(m)}\n3D lobe, radius = f [1/sr]")
            elif view == "hemisphere":
                _plot.hemisphere(m, theta_o=theta_o, ax=ax, res=90, title="f [1/sr] over ωi (disks seen from above)")
            elif view == "halfdiff":
                _plot.halfdiff(m, ax=ax, res=90, title="f [1/sr] (log), θh × θd at φd = 90°")
            else:
                _plot.samples(m, theta_o=theta_o, n=VIEWS_SAMPLES, ax=ax,
                              title=f"sampling: θi histogram vs pdf ({VIEWS_SAMPLES} samples)")
    fig.suptitle(f"Views of every configuration at θo = {theta_o}° (φo = 0°): 3D lobe, image over directions "
                 "(reflection disk, transmission disk),\nRusinkiewicz θh × θd slice (log), sampled θi vs the pdf "
                 "(χ² p-value)", fontsize="xx-large", y=1 - 0.2 / h, va="top")
    fig.savefig(path, dpi=60)


def _albedo_table(configs, path, n_samples=TABLE_SAMPLES):
    wo = np.stack([np.sin(np.radians(THETAS)), np.zeros(len(THETAS)), np.cos(np.radians(THETAS))], -1)
    lines = ["# bsdfkit directional albedo", "",
             f"ρ(θo) = ∫ f(ωo, ωi) |cos θi| dωi, Monte Carlo with n_samples = {n_samples} importance samples "
             "per θo (seed 0, `BxDF.albedo`), Radiance transport mode. Each cell: luminance "
             "(0.2126 R + 0.7152 G + 0.0722 B), then (R, G, B).", "",
             "| Configuration | " + " | ".join(f"θo = {t}°" for t in THETAS) + " |",
             "|---|" + "---|" * len(THETAS)]
    notes = []
    for name, m in configs:
        rgb = m.albedo(wo, n_samples=n_samples, seed=0)
        lum = _plot.luminance(rgb)
        cells = [f"{y:.4f} ({c[0]:.4f}, {c[1]:.4f}, {c[2]:.4f})" for y, c in zip(lum, rgb)]
        lines.append(f"| `{name}` | " + " | ".join(cells) + " |")
        if _refracts(m):
            imp = _plot.luminance(m.albedo(wo, n_samples=n_samples, seed=0, mode=TransportMode.Importance))
            notes.append(f"- `{name}`: in Radiance mode transmitted radiance is divided by η² = {m.eta ** 2:g}; "
                         "the energy albedo (Importance mode), luminance at θo = "
                         + ", ".join(f"{t}°: {v:.4f}" for t, v in zip(THETAS, imp)) + ".")
    lines += ["", "Notes:", ""] + notes + [
        "- Rough microfacet models (single scattering) lose energy at large α and grazing angles; "
        "values below 1 for a non-absorbing dielectric are expected."]
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines) + "\n")


def run_demo(outdir="bsdfkit-demo", *, verbose=True):
    """Write ``lobes.png``, ``albedo.png``, ``albedo.md``, ``views.png``, ``gallery.exr``,
    ``gallery.png``, ``gallery_labelled.png`` (the render with each sphere numbered and a key
    of the specs), ``hair.exr``, ``hair.png``, ``dispersion.png`` (a dispersive glass sphere
    rendered in RGB and spectral mode, and their difference) and ``dispersion_spectral.exr``
    into ``outdir`` (created if missing); returns the list
    of written paths."""
    t0 = time.perf_counter()
    os.makedirs(outdir, exist_ok=True)
    configs = configurations()
    paths = [os.path.join(outdir, f) for f in ("lobes.png", "albedo.png", "albedo.md", "views.png")]
    _lobes_figure(configs, paths[0])
    _albedo_figure(configs, paths[1])
    _albedo_table(configs, paths[2])
    _views_figure(configs, paths[3])
    from .render import write_gallery  # gallery.exr / gallery.png: one path-traced sphere per configuration
    from .render.scene import is_compiled  # the renderer shades compiled models (not the Python composites)
    paths += write_gallery(outdir, [c for c in configs if is_compiled(c[1])], verbose=verbose, progress=verbose)
    from .render import write_hair  # hair.exr / hair.png: locks of Hair on fibres, labelled
    paths += write_hair(outdir, progress=verbose)
    from .render import write_dispersion  # dispersion.png: a flint-glass sphere, RGB vs spectral render
    paths += write_dispersion(outdir, progress=verbose)
    if verbose:
        for p in paths:
            print(os.path.abspath(p))
        print(f"[bsdfkit demo] {len(configs)} configurations in {time.perf_counter() - t0:.1f} s")
    return paths
