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
    # at most 22 rows per group of columns (the image stays under 6000 px tall), groups side by side
    groups = -(-len(configs) // 22)
    nrow = -(-len(configs) // groups)
    w, h = 22.0 * groups, 4.3 * nrow + 1.5
    fig = Figure(figsize=(w, h))   # fixed margins: constrained layout triples the drawing time here
    fig.subplots_adjust(left=0.5 / w, right=1 - 0.3 / w, top=1 - 1.5 / h, bottom=0.4 / h, wspace=0.45, hspace=0.45)
    for i, (name, m) in enumerate(configs):
        g, r = divmod(i, nrow)
        for j, view in enumerate(cols):
            ax = fig.add_subplot(nrow, len(cols) * groups, r * len(cols) * groups + g * len(cols) + j + 1,
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


# ---------------------------------------------------------------- svbrdf.png: a spatially varying material

#: Texels (rows, columns) of the demo's procedural maps: lat-long, u (columns) over 360° of
#: longitude, v (rows) over 180° of latitude, so a texel is square at the equator.
SVBRDF_MAP_SHAPE = (256, 512)
#: Pixels (width = height) of svbrdf.png's sphere image (about its size in the figure).
SVBRDF_SIZE = 600
#: Half-width of the sphere image in sphere radii.
SVBRDF_MARGIN = 1.05
#: Directional lights of the sphere: (direction towards the light, world space; RGB irradiance).
#: World: x right, y up, z towards the (orthographic) camera.
SVBRDF_LIGHTS = (((-0.55, 0.6, 0.58), (2.6, 2.45, 2.2)),     # key, upper left, warm
                 ((0.85, -0.05, 0.52), (0.35, 0.42, 0.55)),  # fill, right, cool
                 ((0.35, 0.55, -0.76), (1.6, 1.6, 1.7)))     # rim, behind upper right
#: Radiance of the uniform sky of the ambient term (times each pixel's albedo).
SVBRDF_SKY = (0.16, 0.18, 0.22)
#: Importance samples per pixel of the ambient albedo.
SVBRDF_SKY_SAMPLES = 16


def _noise(shape, cells, seed):
    """Smooth value noise in [0, 1) on a (rows, cols) grid, periodic across the columns (the
    longitude wraps): random values on a (cells, 2 cells) lattice, bicubic-smoothed bilinear
    interpolation."""
    h, w = shape
    rng = np.random.default_rng(seed)
    ch, cw = cells, 2 * cells
    g = rng.random((ch + 1, cw))
    y = (np.arange(h) + 0.5) / h * ch
    x = (np.arange(w) + 0.5) / w * cw
    y0, x0 = np.minimum(y.astype(int), ch - 1), x.astype(int) % cw
    fy, fx = y - y0, x - np.floor(x)
    fy, fx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)   # smoothstep weights
    x1 = (x0 + 1) % cw
    a = g[y0][:, x0] * (1 - fx) + g[y0][:, x1] * fx
    b = g[y0 + 1][:, x0] * (1 - fx) + g[y0 + 1][:, x1] * fx
    return a * (1 - fy)[:, None] + b * fy[:, None]


def _fbm(shape, cells, seed, octaves=4):
    """Sum of octaves of :func:`_noise` (each twice the cells, half the amplitude), in [0, 1)."""
    out, amp, tot = np.zeros(shape), 1.0, 0.0
    for o in range(octaves):
        out += amp * _noise(shape, cells * 2 ** o, seed + o)
        tot += amp
        amp /= 2
    return out / tot


def svbrdf_maps(shape=SVBRDF_MAP_SHAPE, seed=3):
    """The demo material's procedural maps, tiles of three kinds in a lat-long layout.

    16 x 8 square tiles (22.5° each) with grout between them: white marble with grey veins
    (glossy, dielectric), blue glazed ceramic (dielectric, roughness with a noisy pattern) and
    hammered gold (metallic, dimpled), on a fixed pattern. Returns a dict of float64 arrays:
    ``base_color`` (rows, cols, 3, linear RGB), ``roughness`` and ``metallic`` (rows, cols, in
    [0, 1]), ``height`` (rows, cols, texel units) and ``normals`` (rows, cols, 3, unit tangent-space
    normals, OpenGL convention: x along +u (east), y along +v (north, towards row 0))."""
    from .io import srgb_to_linear

    h, w = shape
    ty, tx = 8, 16
    row, col = np.mgrid[0:h, 0:w]
    fy, fx = (row + 0.5) * ty / h, (col + 0.5) * tx / w
    iy, ix = fy.astype(int), fx.astype(int)
    dy, dx = fy - iy, fx - ix
    edge = np.minimum(np.minimum(dx, 1 - dx), np.minimum(dy, 1 - dy))   # tile units to the tile's edge
    grout_w, bevel = 0.045, 0.06
    grout = edge < grout_w
    # kind per tile: 0 marble, 1 glazed, 2 gold; gold on a sparse diagonal pattern
    kind = np.where((ix + 2 * iy) % 5 == 0, 2, np.where((ix + iy) % 2 == 0, 0, 1))

    n1, n2 = _fbm(shape, 4, seed), _fbm(shape, 8, seed + 10)
    # marble: veins along a warped diagonal (a classic turbulence marble)
    veins = np.abs(np.sin(2 * np.pi * (fx * 0.35 + fy * 0.6) + 9.0 * n1))
    vein = (1 - veins) ** 6
    marble = (1 - 0.55 * vein)[..., None] * [0.93, 0.92, 0.88] + (0.55 * vein)[..., None] * [0.30, 0.31, 0.34]
    glaze = np.array([0.10, 0.32, 0.62]) * (0.75 + 0.5 * n2)[..., None]
    gold = np.array([1.0, 0.78, 0.34]) * (0.92 + 0.16 * n2)[..., None]
    grout_c = np.array([0.36, 0.34, 0.31])
    srgb = np.select([grout[..., None], (kind == 0)[..., None], (kind == 1)[..., None]], [grout_c, marble, glaze], gold)
    base_color = srgb_to_linear(srgb)

    roughness = np.select([grout, kind == 0, kind == 1],
                          [0.9, 0.18 + 0.25 * vein, 0.12 + 0.6 * n2], 0.3 + 0.25 * n1)
    metallic = np.where(grout, 0.0, np.where(kind == 2, 1.0, 0.0))

    # height: tiles 1, bevelled down to the grout at 0; gold dimpled, glaze rippled, marble flat
    plateau = np.clip((edge - grout_w) / bevel, 0, 1)
    plateau = plateau * plateau * (3 - 2 * plateau)
    sub_y, sub_x = (fy * 3) % 1 - 0.5, (fx * 3) % 1 - 0.5      # 3 x 3 dimples per gold tile
    dimple = np.exp(-(sub_x ** 2 + sub_y ** 2) / 0.035)
    detail = np.select([kind == 2, kind == 1], [-0.6 * dimple, 0.15 * n2], 0.0)
    height = (1.2 * plateau + plateau * detail) * (h / ty) * 0.06   # in texel units: bevels at ~50°
    # tangent-space normal of the height field: (-dh/dx, -dh/dy, 1), y north (row 0 is north)
    dhdx = (np.roll(height, -1, 1) - np.roll(height, 1, 1)) / 2          # wraps in longitude
    dhdy = -np.gradient(height, axis=0)                                  # d/d(north) = -d/d(row)
    normals = np.stack([-dhdx, -dhdy, np.ones_like(height)], -1)
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    return {"base_color": base_color, "roughness": roughness, "metallic": metallic, "height": height,
            "normals": normals}


def sphere_frames(size=SVBRDF_SIZE, margin=SVBRDF_MARGIN):
    """Geometry of a unit sphere seen by an orthographic camera looking down -z, one sample per
    pixel centre of a size x size image (row 0 at the top, y up) spanning [-margin, margin] in x
    and y.

    Returns ``(mask, normal, tangent, uv)``: the (size, size) mask of pixels on the sphere, and for
    those pixels (in row-major order) the world normal (N, 3), the tangent (N, 3), the unit vector
    along increasing longitude (cos φ, 0, -sin φ) with φ = atan2(x, z), and uv (N, 2): u = φ / 2π
    + 1/2 in [0, 1), v = latitude / π + 1/2 in [0, 1] (0 at the south pole)."""
    c = ((np.arange(size) + 0.5) / size * 2 - 1) * margin
    px, py = np.meshgrid(c, -c)
    r2 = px * px + py * py
    mask = r2 < 1
    x, y = px[mask], py[mask]
    z = np.sqrt(1 - r2[mask])
    normal = np.stack([x, y, z], -1)
    phi = np.arctan2(x, z)
    tangent = np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], -1)
    uv = np.stack([(phi / (2 * np.pi) + 0.5) % 1.0, np.arcsin(np.clip(y, -1, 1)) / np.pi + 0.5], -1)
    return mask, normal, tangent, uv


def texel_lookup(maps, uv):
    """Nearest-texel lookup of every map at uv (N, 2): a dict of per-element arrays. Column
    floor(u W) mod W, row floor((1 - v) H) clipped (row 0 is v = 1, the north pole)."""
    h, w = next(iter(maps.values())).shape[:2]
    col = np.floor(uv[:, 0] * w).astype(int) % w
    row = np.clip(np.floor((1 - uv[:, 1]) * h).astype(int), 0, h - 1)
    return {k: v[row, col] for k, v in maps.items()}


def svbrdf_model(params):
    """The demo's material for per-element parameters (from :func:`texel_lookup`, or one texel's):
    ``NormalMap(FilamentStandard(base_color, roughness, metallic), normals)``."""
    import bsdfkit as bk

    return bk.NormalMap(bk.FilamentStandard(base_color=params["base_color"], roughness=params["roughness"],
                                            metallic=params["metallic"]), normals=params["normals"])


def shade_svbrdf(maps, size=SVBRDF_SIZE, lights=SVBRDF_LIGHTS, sky=SVBRDF_SKY, sky_samples=SVBRDF_SKY_SAMPLES):
    """A sphere with the material of ``maps`` (see :func:`svbrdf_maps`), shaded with the library's
    per-element evaluation (no renderer): returns (radiance, mask), the linear RGB radiance
    (size, size, 3), 0 off the sphere, and :func:`sphere_frames`' mask.

    One model for all sphere pixels (:func:`svbrdf_model` of each pixel's nearest texel), called
    in world space with each pixel's ``normal=`` and ``tangent=``, the orthographic view direction
    wo = (0, 0, 1). Per pixel: the sum over ``lights`` of f(wo, wi) max(n . wi, 0) E (n the
    geometric normal), plus ``sky`` times the directional albedo (radiance under a uniform sky),
    ``sky_samples`` importance samples per pixel."""
    mask, normal, tangent, uv = sphere_frames(size)
    px = texel_lookup(maps, uv)
    m = svbrdf_model(px)
    wo = np.broadcast_to(np.array([0.0, 0.0, 1.0]), normal.shape)
    rad = np.zeros(normal.shape)
    for d, e in lights:
        wi = np.asarray(d, dtype=np.float64) / np.linalg.norm(d)
        cos = np.maximum(normal @ wi, 0.0)
        f = m.eval(wo, np.broadcast_to(wi, normal.shape), normal=normal, tangent=tangent)
        rad += f * cos[:, None] * np.asarray(e)
    if sky is not None and np.any(np.asarray(sky) > 0):
        # the albedo of the FilamentStandard about the normal map's world-space normal, without the
        # NormalMap's geometric-side terms: NormalMap.albedo with per-element parameters in its
        # child raises for now (the composite's albedo repeats wo per sample, not the child's arrays)
        n = px["normals"]
        shading = n[:, :1] * tangent + n[:, 1:2] * np.cross(normal, tangent) + n[:, 2:] * normal
        shading /= np.linalg.norm(shading, axis=1, keepdims=True)
        rad += m.model.albedo(wo, n_samples=sky_samples, seed=0, normal=shading) * np.asarray(sky)
    img = np.zeros((size, size, 3))
    img[mask] = rad
    return img, mask


def tonemap(rgb, exposure=1.0):
    """Display sRGB in [0, 1] of linear radiance: exposure, Reinhard's x / (1 + x) per channel, the
    sRGB curve."""
    from .io import linear_to_srgb

    x = np.maximum(rgb * exposure, 0.0)
    return linear_to_srgb(x / (1 + x))


def _svbrdf_figure(path, size=SVBRDF_SIZE):
    from matplotlib.figure import Figure
    from .io import linear_to_srgb

    t0 = time.perf_counter()
    maps = svbrdf_maps()
    rad, mask = shade_svbrdf(maps, size)
    secs = time.perf_counter() - t0
    bg = np.linspace(0.22, 0.12, size)[:, None, None] * np.ones((1, size, 3))
    img = np.where(mask[..., None], tonemap(rad, 1.6), bg)

    fig = Figure(figsize=(14.5, 6.6))
    gs = fig.add_gridspec(2, 3, width_ratios=[1.4, 1, 1], left=0.015, right=0.985, top=0.86, bottom=0.05,
                          wspace=0.22, hspace=0.3)
    ax = fig.add_subplot(gs[:, 0])
    ax.imshow(img, interpolation="antialiased")
    ax.set_title(f"Sphere: m.eval(wo, wi, normal=, tangent=), {size}×{size} px\n"
                 f"{len(SVBRDF_LIGHTS)} directional lights + sky × albedo, {secs:.1f} s, no renderer",
                 fontsize="medium")
    ax.set_axis_off()
    extent = (0, 360, -90, 90)
    panels = ((gs[0, 1], "base_color (sRGB)", linear_to_srgb(maps["base_color"]), {}),
              (gs[0, 2], "roughness (perceptual)", maps["roughness"], {"cmap": "magma", "vmin": 0, "vmax": 1}),
              (gs[1, 1], "metallic", maps["metallic"], {"cmap": "gray", "vmin": 0, "vmax": 1}),
              (gs[1, 2], "normal map: (n + 1) / 2 as RGB\n(tangent space, from a height field)",
               (maps["normals"] + 1) / 2, {}))
    for g, title, data, kw in panels:
        a = fig.add_subplot(g)
        im = a.imshow(data, extent=extent, interpolation="nearest", aspect="equal", **kw)
        a.set_title(title, fontsize="medium")
        a.set_xticks([0, 90, 180, 270, 360])
        a.set_yticks([-90, 0, 90])
        a.tick_params(labelsize="small")
        a.set_xlabel("longitude u [°]", fontsize="small")
        a.set_ylabel("latitude v [°]", fontsize="small")
        if data.ndim == 2:
            fig.colorbar(im, ax=a, shrink=0.8, pad=0.05)
    fig.suptitle("SVBRDF: one NormalMap(FilamentStandard(base_color, roughness, metallic), normals) with "
                 f"per-pixel arrays, maps {maps['roughness'].shape[1]}×{maps['roughness'].shape[0]} "
                 "texels (lat-long, nearest texel)", fontsize="large")
    fig.savefig(path, dpi=120)


def run_demo(outdir="bsdfkit-demo", *, verbose=True):
    """Write ``lobes.png``, ``albedo.png``, ``albedo.md``, ``views.png``, ``svbrdf.png`` (a
    material with per-pixel parameter maps and a normal map on a sphere shaded with ``eval``, no
    renderer, beside its maps), ``gallery.exr``, ``gallery.png``, ``gallery_labelled.png`` (the
    render with each sphere numbered and a key of the specs), ``hair.exr``, ``hair.png``,
    ``dispersion.png`` (a dispersive glass sphere rendered in RGB and spectral mode, and their
    difference) and ``dispersion_spectral.exr`` into ``outdir`` (created if missing); returns the
    list of written paths."""
    t0 = time.perf_counter()
    os.makedirs(outdir, exist_ok=True)
    configs = configurations()
    paths = [os.path.join(outdir, f) for f in ("lobes.png", "albedo.png", "albedo.md", "views.png")]
    _lobes_figure(configs, paths[0])
    _albedo_figure(configs, paths[1])
    _albedo_table(configs, paths[2])
    _views_figure(configs, paths[3])
    paths.append(os.path.join(outdir, "svbrdf.png"))
    _svbrdf_figure(paths[-1])
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
