"""The demo's image files: the labelled gallery, the row of hair locks and the RGB-versus-spectral
dispersion comparison."""
from __future__ import annotations

import math
import os

import numpy as np

from .scene import _model_check, project
from .scenes import (DISPERSION_GLASS, DISPERSION_SIZE, DISPERSION_SPP, GALLERY_SIZE, GALLERY_SPP, HAIR_ROW,
                     HAIR_SIZE, HAIR_SPACING, HAIR_SPP, dispersion_scene, gallery_scene, hair_row_scene)
from .trace import parse_spec, render


def _spec_of(model):
    from ..models.spec import to_spec
    return to_spec(model)


def write_gallery(outdir, configs, *, size=GALLERY_SIZE, spp=GALLERY_SPP, progress=True, verbose=True,
                  labelled=True):
    """Renders one sphere per (name, model) of ``configs`` with :func:`gallery_scene` under the
    default sky and writes ``gallery.exr`` (linear radiance), ``gallery.png`` (sRGB) and, with
    ``labelled``, ``gallery_labelled.png`` (each sphere numbered, with a key of the names).

    Parameters
    ----------
    outdir : str or os.PathLike
        The output folder.
    configs : sequence of (str, BxDF)
        Names and models.
    size : tuple of int, optional
        Image width and height.
    spp : int, optional
        Samples per pixel.
    progress, verbose : bool, optional
        A progress bar; a line per file written.
    labelled : bool, optional
        Also write the numbered image with its key.

    Returns
    -------
    list of str
        The paths written.
    """
    from ..io import write_image
    names = [n for n, _ in configs]
    sc = gallery_scene([m for _, m in configs], aspect=size[0] / size[1])
    img = render(sc, width=size[0], height=size[1], spp=spp, progress=progress)
    paths = [os.path.join(outdir, "gallery.exr"), os.path.join(outdir, "gallery.png")]
    write_image(paths[0], img)
    write_image(paths[1], img)
    if labelled:
        paths.append(os.path.join(outdir, "gallery_labelled.png"))
        _labelled_gallery(paths[2], img, sc, names, size)
    if verbose:
        cols = 4
        rows = [names[i:i + cols] for i in range(0, len(names), cols)]
        print("gallery spheres (back row first, left to right): " +
              " | ".join(", ".join(r) for r in rows))
    return paths


def _labelled_gallery(path, img, sc, names, size):
    """gallery_labelled.png: the render with a number on each sphere and a key of the
    configurations under it (the 640 x 320 render is too small to write the specs on)."""
    import textwrap

    import matplotlib.pyplot as plt

    from ..io import linear_to_srgb
    centers = np.array([o["center"] for o in sc.objects if o["kind"] == "sphere"])
    cols, width = 2, 56                                      # key: 2 columns, long specs wrapped
    entries = [textwrap.wrap(f"{k + 1:>2}  {n}", width, subsequent_indent="      ") for k, n in enumerate(names)]
    per_col = math.ceil(len(entries) / cols)
    key_lines = max(sum(len(e) for e in entries[c * per_col:(c + 1) * per_col]) for c in range(cols))
    w_in, line_in = 10.0, 0.2
    img_h = w_in * size[1] / size[0]
    fig_h = img_h + 0.25 + line_in * key_lines
    fig = plt.figure(figsize=(w_in, fig_h))
    ax = fig.add_axes([0, 1 - img_h / fig_h, 1, img_h / fig_h])
    ax.imshow(linear_to_srgb(np.asarray(img, dtype=np.float64)), interpolation="lanczos")
    ax.set_axis_off()
    if len(centers):
        for k, (x, y) in enumerate(project(sc.camera, centers, size)):
            ax.text(x - 0.5, y - 0.5, str(k + 1), ha="center", va="center", fontsize=11, fontweight="bold",
                    color="white", bbox=dict(boxstyle="circle,pad=0.2", fc="black", ec="white", alpha=0.75, lw=0.8))
    for c in range(cols):
        line = 0
        for e in entries[c * per_col:(c + 1) * per_col]:
            for text in e:
                fig.text(0.01 + 0.5 * c, 1 - (img_h + 0.12 + line * line_in) / fig_h, text, ha="left", va="top",
                         fontsize=9, family="monospace")
                line += 1
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_hair(outdir, rows=HAIR_ROW, *, size=HAIR_SIZE, spp=HAIR_SPP, progress=True, exposure=0.0):
    """Renders :func:`hair_row_scene` of ``rows`` and writes ``hair.exr`` (linear radiance) and
    ``hair.png`` (sRGB, each lock labelled with its name and spec).

    Parameters
    ----------
    outdir : str or os.PathLike
        The output folder.
    rows : sequence of (str, str or Hair), optional
        (label, spec or model) pairs; default :data:`HAIR_ROW`.
    size : tuple of int, optional
        Image width and height.
    spp : int, optional
        Samples per pixel.
    progress : bool, optional
        A progress bar.
    exposure : float, optional
        Stops applied to the PNG.

    Returns
    -------
    list of str
        The two paths.
    """
    from matplotlib.figure import Figure

    from ..io import linear_to_srgb, write_image
    specs = [m if isinstance(m, str) else _spec_of(_model_check(m)) for _, m in rows]
    rows = [(lab, parse_spec(m) if isinstance(m, str) else m) for lab, m in rows]
    w, h = size
    sc = hair_row_scene([m for _, m in rows], aspect=w / h)
    img = render(sc, width=w, height=h, spp=spp, progress=progress)
    paths = [os.path.join(outdir, "hair.exr"), os.path.join(outdir, "hair.png")]
    write_image(paths[0], img)
    # the PNG: the sRGB image with a caption strip under the locks
    dpi, strip = 100, 44
    fig = Figure(figsize=(w / dpi, (h + strip) / dpi), dpi=dpi)
    ax = fig.add_axes((0, strip / (h + strip), 1, h / (h + strip)))
    ax.imshow(np.clip(linear_to_srgb(np.clip(img * 2.0 ** exposure, 0, None)), 0, 1), interpolation="nearest")
    ax.set_axis_off()
    k = len(rows)
    cam = sc.camera
    half_w = math.tan(math.radians(cam.fov / 2)) * cam.origin[2]
    for i, ((lab, _), spec) in enumerate(zip(rows, specs)):
        x = (i - (k - 1) / 2) * HAIR_SPACING
        fx = 0.5 + 0.5 * x / half_w
        words = spec.split()
        fig.text(fx, (strip - 4) / (h + strip), "\n".join([f"{lab}: {words[0]}"] + words[1:]), ha="center",
                 va="top", fontsize=7.5, color="0.1", linespacing=1.25)
    fig.text(0.01, 1 - 0.01, f"Hair (Chiang 2016 / pbrt-v4) on {len(rows)} x 2500 fibres, h from each hit; "
             f"sky + sun, {spp} spp", ha="left", va="top", fontsize=8, color="0.15")
    fig.savefig(paths[1], dpi=dpi, facecolor="white")
    return paths


def write_dispersion(outdir, *, glass=DISPERSION_GLASS, size=DISPERSION_SIZE, spp=DISPERSION_SPP, progress=True):
    """The RGB-versus-spectral comparison of the demo: :func:`dispersion_scene` rendered in RGB (the
    glass at eta(550 nm): no dispersion) and with ``spectral=True`` (hero wavelengths: colour
    fringes along every bright edge seen through the glass), side by side with their difference.
    Writes ``dispersion.png`` and ``dispersion_spectral.exr``.

    Parameters
    ----------
    outdir : str or os.PathLike
        The output folder.
    glass : str, optional
        A named glass spectrum.
    size : tuple of int, optional
        Image width and height.
    spp : int, optional
        Samples per pixel.
    progress : bool, optional
        A progress bar.

    Returns
    -------
    list of str
        The paths written.
    """
    from matplotlib.figure import Figure

    from ..io import linear_to_srgb, write_image
    from ..spectral import Spectrum
    w, h = size
    sc = dispersion_scene(glass, aspect=w / h)
    kw = dict(width=w, height=h, spp=spp, max_depth=12, progress=progress)
    rgb = render(sc, **kw)
    spec = render(sc, spectral=True, **kw)
    paths = [os.path.join(outdir, "dispersion.png"), os.path.join(outdir, "dispersion_spectral.exr")]
    write_image(paths[1], spec)
    tone = lambda x: np.clip(linear_to_srgb(np.clip(x, 0, None)), 0, 1)   # noqa: E731

    def mean3(x):   # 3 x 3 pixel mean: the per-path colour noise of the wavelength sampling drops,
        pad = np.pad(x, ((1, 1), (1, 1), (0, 0)), mode="edge")   # the fringes (systematic) stay
        return sum(pad[i:i + h, j:j + w] for i in range(3) for j in range(3)) / 9.0
    # the difference of the displayed images (sRGB, clipped): what the eye compares
    diff3 = mean3(tone(spec)) - mean3(tone(rgb))
    eta = Spectrum.named(glass)(np.array([450.0, 550.0, 650.0]))
    fig = Figure(figsize=(12.6, 4.1))
    fig.subplots_adjust(left=0.01, right=0.99, top=0.80, bottom=0.03, wspace=0.04)
    axes = fig.subplots(1, 3)
    panels = ((tone(rgb), f"RGB: eta = {eta[1]:.3f} at every colour"),
              (tone(spec), "spectral (4 hero wavelengths per path)"),
              (np.clip(2.0 * np.abs(diff3), 0, 1), "|spectral - RGB| x 2 (displayed sRGB, 3x3 pixel mean)"))
    for ax, (im, title) in zip(axes, panels):
        ax.imshow(im, interpolation="nearest")
        ax.set_title(title, fontsize=10)
        ax.set_axis_off()
    fig.suptitle(f"Dispersion: a {glass} sphere (dense flint, eta {eta[0]:.3f} at 450 nm, {eta[1]:.3f} at 550 nm, "
                 f"{eta[2]:.3f} at 650 nm) under white stripes, {w}x{h}, {spp} spp;\n"
                 "the spectral render splits every bright edge seen through the glass into colour fringes "
                 "(pbrt-v4 hero wavelengths, secondaries terminated at each refraction)", fontsize=10.5)
    fig.savefig(paths[0], dpi=100, facecolor="white")
    return paths
