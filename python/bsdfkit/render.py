"""Preview renderer: any bsdfkit material on an object under an environment.

A path tracer in the C++ core (Embree 3 for rays, OpenImageIO for environment maps) that calls
the very same per-element model code as ``eval``/``sample``/``pdf``. It estimates the light
transport equation with BSDF sampling and environment importance sampling combined by multiple
importance sampling (power heuristic), Russian roulette and a maximum depth, as pbrt-v4's
``PathIntegrator`` does.

>>> import bsdfkit as bk
>>> img = bk.render.preview(bk.Conductor.from_metal("Au", alpha=0.2), spp=16)   # (256, 256, 3)
>>> bk.io.write_image("gold.png", img)

Conventions
-----------
* World space is y-up. A lat-long environment image maps row 0 to the zenith (+y) and column u
  (in [0, 1) across the width) to the azimuth phi = 2 pi u, with the direction
  ``(sin phi sin theta, cos theta, -cos phi sin theta)``, theta = pi v: the image centre looks
  along +z, the left/right edges along -z, a quarter of the width along +x. This is the mapping
  of Mitsuba 3's ``envmap`` plugin (with the identity ``to_world``). Radiance is bilinearly
  interpolated between pixel centres.
* Values are linear radiance in RGB; images come back as float32 (H, W, 3), row 0 at the top.
  ``spectral=True`` traces 4 wavelengths per path instead (pbrt-v4's hero-wavelength scheme) and
  returns linear sRGB the same way; see :func:`preview`.
* The camera is a pinhole: ``fov`` is the full horizontal field of view in degrees; image x
  grows along ``forward x up``; its origin, target and up coordinates, like the scene's geometry,
  lie within +-1e18 (the renderer works in float32, :class:`Camera`). Pixels are box-filtered
  (uniform jitter inside the pixel).
* ``max_depth`` counts scattering events (pbrt-v4): 0 shows the environment only, 1 is direct
  lighting. Mitsuba's ``max_depth`` counts path vertices: Mitsuba's value is ours + 1.
* Objects: spheres, triangle meshes (numpy arrays, or OBJ/PLY/... files through Assimp), fibres
  (round Embree curves through given points, e.g. a :func:`hair_swatch`) and a ground plane, one
  bsdfkit model per object (the ground may alternate two in a checkerboard).
  The shading frame is the geometric normal (outward: triangles wind counter-clockwise seen
  from outside) and a tangent (a sphere's parallels around +y; a triangle's first edge), so an
  anisotropic ``alpha_x`` runs along that tangent. Dielectric ``eta`` is inside over outside.
* Fibres (:meth:`Scene.add_curves`): at a hit the frame's x is the fibre tangent. For a hair model
  (``Hair``, ``Hair(h=None)``) z is the part of wo normal to the fibre (the ribbon facing the ray,
  as pbrt-v4) and the offset across the fibre is taken from the hit: h = ((p - c) . y) / r, the
  signed distance between the ray and the fibre axis (c, radius r at the hit) along y = z x x, in
  [-1, 1] (the Hair model's own ``h`` is ignored there). With this sign the R lobe
  (phi_i - phi_o = -2 asin h, pbrt-v4) is the mirror reflection off the cylinder at the hit. For
  other models z is the tube's outward normal and rays leave the fibre from its surface, as from
  any surface (and as in Mitsuba). Rays leave a hair fibre from its axis, past its own cylinder:
  the hair model is a far-field description of the whole fibre (its TT and TRT lobes exit on the
  far side), so a hair does not shadow itself at the scattering point.
* Determinism: a sample's random numbers depend only on (seed, pixel, sample index), so an image
  is bit-identical for any thread count (``bk.set_num_threads``) and any split into passes.
* Ctrl-C: the render stops within a fraction of a second and, by default
  (``interrupt="raise"``), a ``KeyboardInterrupt`` propagates whose ``image`` attribute holds
  the average of the passes completed so far (``None`` if none) and ``spp_done`` their sample
  count. ``interrupt="return"`` returns that partial image instead (with a warning).
"""
from __future__ import annotations

import functools
import math
import os
import sys
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from . import _core
from ._arrays import _as_real_array, check_real

__all__ = ["Camera", "Scene", "preview", "render", "default_environment", "procedural_environment", "default_scene",
           "gallery_scene", "hair_swatch", "hair_scene", "hair_row_scene", "load_mesh", "parse_spec", "write_gallery",
           "write_hair", "ENVIRONMENTS", "HAIR_ROW", "SPECTRAL_MODELS", "stripes_environment",
           "dispersion_scene", "write_dispersion"]

#: Named environments: procedural ``"sky"`` (the default: sky gradient, ground and a sun-like
#: hot spot), ``"studio"`` (dark room with three soft boxes) and ``"white"`` (uniform radiance 1,
#: the white furnace).
ENVIRONMENTS = ("sky", "studio", "white")

_LUM = np.array([0.2126, 0.7152, 0.0722])


# ---------------------------------------------------------------- environments

def _latlong_dirs(width: int, height: int) -> np.ndarray:
    """World directions of the pixel centres of a lat-long image, (H, W, 3) float64."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    phi, theta = np.meshgrid(2 * np.pi * u, np.pi * v)
    st = np.sin(theta)
    return np.stack([np.sin(phi) * st, np.cos(theta), -np.cos(phi) * st], axis=-1)


#: Direction toward the sun of the "sky" environment: behind the default camera's left shoulder.
SUN_DIRECTION = np.array([-0.5, 0.62, 0.6]) / np.linalg.norm([-0.5, 0.62, 0.6])


def _soft_disk(cos_angle, radius_deg, edge_deg):
    ang = np.degrees(np.arccos(np.clip(cos_angle, -1, 1)))
    t = np.clip((radius_deg + edge_deg - ang) / (2 * edge_deg), 0, 1)
    return t * t * (3 - 2 * t)


def procedural_environment(kind: str, directions) -> np.ndarray:
    """Radiance of a procedural environment (``"sky"`` or ``"studio"``) toward world
    ``directions`` (..., 3) (unit, y-up), float64 (..., 3). See :func:`default_environment`."""
    if kind not in ("sky", "studio"):
        raise ValueError(f"kind: must be 'sky' or 'studio', got {kind!r}")
    d = np.asarray(directions, dtype=np.float64)
    y = d[..., 1:2]
    if kind == "sky":
        up = np.clip(y, 0, 1)
        zenith, horizon = np.array([0.18, 0.34, 0.85]), np.array([0.95, 1.0, 1.08])
        sky = horizon + (zenith - horizon) * (1 - (1 - up) ** 3)
        ground = np.array([0.32, 0.27, 0.22]) * (0.55 + 0.45 * np.clip(1 + 4 * y, 0, 1))
        blend = np.clip(y * 40 + 0.5, 0, 1)               # ~1.4 degree soft horizon
        env = ground + (sky - ground) * blend
        c = d @ SUN_DIRECTION
        ang = np.arccos(np.clip(c, -1, 1))
        env = env + np.array([1.0, 0.8, 0.55]) * (4.0 * np.exp(-ang / 0.12))[..., None] * (y > -0.05)
        env = env + np.array([1.0, 0.95, 0.85]) * 600.0 * _soft_disk(c, 2.5, 0.6)[..., None]
    else:
        env = np.full(d.shape, 0.03) + 0.04 * np.clip(y, 0, 1)
        for direction, size, level in (((-0.6, 0.55, 0.6), 22.0, 9.0),      # key, front left above
                                       ((0.85, 0.25, 0.45), 18.0, 3.0),      # fill, right
                                       ((0.2, 0.5, -0.85), 12.0, 6.0)):      # rim, behind
            v = np.asarray(direction) / np.linalg.norm(direction)
            env = env + level * _soft_disk(d @ v, size, 2.0)[..., None]
    return env


#: Width of the procedural environments' lat-long images (height = width / 2): 1.4 degrees per
#: texel keeps the sun a few texels wide while the map and its sampling table (0.9 MB) stay in
#: a core's L2 cache; environment lookups are the renderer's main memory traffic.
DEFAULT_ENV_WIDTH = 256


def default_environment(kind: str = "sky", width: int = DEFAULT_ENV_WIDTH) -> np.ndarray:
    """Procedural lat-long environment, float32 (width // 2, width, 3) linear radiance.

    ``"sky"``: blue zenith fading to a bright horizon, a dim brownish ground below the horizon
    and a sun-like hot spot (angular radius 2.5 degrees, radiance ~600, direction
    :data:`SUN_DIRECTION`) with a soft glow. ``"studio"``: a dark grey room lit by a large key
    soft box (front left, above), a fill (right) and a rim light (behind).
    """
    if kind not in ("sky", "studio"):
        raise ValueError(f"kind: must be 'sky' or 'studio', got {kind!r}")
    width = int(width)
    if width < 8:
        raise ValueError("width: must be >= 8")
    env = procedural_environment(kind, _latlong_dirs(width, width // 2))
    return np.ascontiguousarray(env, dtype=np.float32)


def _read_env_file(path: str) -> np.ndarray:
    """Lat-long image from a file via OpenImageIO; errors name the file and give OIIO's reason."""
    try:
        img = _core.read_image(path)
    except RuntimeError as e:
        if not os.path.exists(path):
            raise FileNotFoundError(f"envmap: cannot read environment map {e}") from None
        raise OSError(f"envmap: cannot read environment map {e}") from None
    if path.lower().endswith((".png", ".jpg", ".jpeg", ".bmp")):
        from .io import srgb_to_linear
        img = srgb_to_linear(img).astype(np.float32)
    return img


def _environment(env):
    """Normalises an environment spec to ('constant', rgb) or ('latlong', float32 (H, W, 3))."""
    if env is None:
        env = "sky"
    if isinstance(env, os.PathLike):
        env = os.fspath(env)
    if isinstance(env, str):
        key = env.lower()
        if key in ("sky", "default"):
            return ("latlong", default_environment("sky"))
        if key == "studio":
            return ("latlong", default_environment("studio"))
        if key in ("white", "uniform", "furnace"):
            return ("constant", (1.0, 1.0, 1.0))
        return ("latlong", _checked_latlong(_read_env_file(env), f"envmap ({env})"))
    if isinstance(env, (bool, np.bool_)):
        raise TypeError("envmap: expected a name, a path, a radiance value or an image array, got a bool")
    if isinstance(env, (int, float, np.integer, np.floating)):
        env = (float(env),) * 3
    a = np.asarray(env)
    if a.dtype.kind not in "fiu":
        raise TypeError(f"envmap: expected a name, a path, a radiance value or an image array, got {type(env).__name__}")
    if a.shape == (3,):
        rgb = a.astype(np.float64)
        if not np.all(np.isfinite(rgb)) or np.any(rgb < 0):
            raise ValueError("envmap: constant radiance must be finite and >= 0")
        return ("constant", tuple(float(x) for x in rgb))
    return ("latlong", _checked_latlong(a, "envmap"))


def _checked_latlong(a, name) -> np.ndarray:
    a = np.asarray(a)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or a.shape[2] not in (1, 3, 4) or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"{name}: expected a lat-long image of shape (H, W), (H, W, 1), (H, W, 3) or (H, W, 4); "
                         f"got {a.shape}")
    a = a[..., :3] if a.shape[2] != 1 else np.repeat(a, 3, axis=2)
    a = a.astype(np.float32)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or Inf")
    if np.any(a < 0):
        raise ValueError(f"{name}: radiance must be >= 0")
    return np.ascontiguousarray(a)


# ---------------------------------------------------------------- meshes

def load_mesh(path):
    """Triangle mesh from a file (OBJ, PLY, STL, glTF, ... via Assimp): (vertices float32 (N, 3),
    indices int64 (M, 3)). Every mesh of the file is merged and triangulated. Raises
    FileNotFoundError for a missing file and ValueError naming the file with Assimp's reason
    for an unreadable one."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(f"path: no such mesh file: {path}")
    try:
        return _core.load_mesh(path)
    except RuntimeError as e:
        raise ValueError(f"cannot read mesh {e}") from None


def _mesh_arrays(vertices, indices):
    v = np.asarray(vertices)
    if v.dtype.kind not in "fiu":
        raise TypeError(f"vertices: expected a real array, got dtype {v.dtype}")
    v = v.astype(np.float64)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) == 0:
        raise ValueError(f"vertices: expected shape (N, 3) with N >= 1, got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError("vertices: contains NaN or Inf")
    i = np.asarray(indices)
    if i.dtype.kind not in "iu":
        raise TypeError(f"indices: expected an integer array, got dtype {i.dtype}")
    if i.ndim != 2 or i.shape[1] != 3 or len(i) == 0:
        raise ValueError(f"indices: expected shape (M, 3) with M >= 1, got {i.shape}")
    if i.min() < 0 or i.max() >= len(v):
        raise ValueError(f"indices: values must be in [0, {len(v)}), got range [{i.min()}, {i.max()}]")
    return v, i.astype(np.int64)


def _apply_transform(v, transform):
    if transform is None:
        return v
    t = np.asarray(transform, dtype=np.float64)
    if t.shape != (4, 4) or not np.all(np.isfinite(t)):
        raise ValueError("transform: expected a finite 4x4 matrix")
    h = v @ t[:3, :3].T + t[:3, 3]
    if not np.all(np.isfinite(h)):
        raise ValueError("transform: produces NaN or Inf vertices")
    return h


def _fit_on_ground(v, radius=1.0, height=0.0):
    """Scales and moves vertices so that the bounding box fits a sphere of ``radius`` and sits
    on the plane y = height, centred on the y axis."""
    lo, hi = v.min(axis=0), v.max(axis=0)
    half = 0.5 * np.linalg.norm(hi - lo)
    s = radius / half if half > 0 else 1.0
    c = 0.5 * (lo + hi)
    out = (v - c) * s
    out[:, 1] += height - out[:, 1].min()
    return out


# ---------------------------------------------------------------- fibres

def _fibre_list(points, name):
    if isinstance(points, np.ndarray) and points.ndim == 3:
        fibres = list(points)
    elif isinstance(points, (list, tuple)):
        fibres = list(points)
    else:
        a = np.asarray(points)
        raise ValueError(f"{name}: expected an (F, P, 3) array or a list of (P, 3) arrays, got shape {a.shape}")
    if not fibres:
        raise ValueError(f"{name}: need at least one fibre")
    out = []
    for k, q in enumerate(fibres):
        q = np.asarray(q)
        if q.dtype.kind not in "fiu":
            raise TypeError(f"{name}: fibre {k}: expected real numbers, got dtype {q.dtype}")
        q = q.astype(np.float64)
        if q.ndim != 2 or q.shape[1] != 3 or len(q) < 2:
            raise ValueError(f"{name}: fibre {k}: expected shape (P, 3) with P >= 2, got {q.shape}")
        if not np.all(np.isfinite(q)):
            raise ValueError(f"{name}: fibre {k}: contains NaN or Inf")
        out.append(q)
    return out


def _radius_list(radius, fibres):
    if isinstance(radius, (bool, np.bool_)):
        raise TypeError("radius: expected a number or per-point radii, got a bool")
    if np.ndim(radius) == 0:
        r = float(radius)
        if not (math.isfinite(r) and r > 0):
            raise ValueError(f"radius: must be finite and > 0, got {radius!r}")
        return [np.full(len(q), r) for q in fibres]
    rs = list(radius) if not (isinstance(radius, np.ndarray) and radius.ndim == 2) else list(radius)
    if len(rs) != len(fibres):
        raise ValueError(f"radius: expected one array per fibre ({len(fibres)}), got {len(rs)}")
    out = []
    for k, (r, q) in enumerate(zip(rs, fibres)):
        r = np.asarray(r, dtype=np.float64)
        if r.shape != (len(q),):
            raise ValueError(f"radius: fibre {k}: expected shape ({len(q)},), got {r.shape}")
        if not np.all(np.isfinite(r)) or np.any(r <= 0):
            raise ValueError(f"radius: fibre {k}: must be finite and > 0")
        out.append(r)
    return out


def hair_swatch(n_fibres=1500, length=2.0, radius=0.004, curl=0.3, seed=0, *, width=0.9, thickness=0.18,
                wave=0.12, points_per_fibre=24, top=2.15):
    """A procedural lock of hair: ``n_fibres`` fibres hanging from a short bar, for
    :meth:`Scene.add_curves`. Returns ``(points, radius)``: float64 arrays (F, P, 3) and (F, P).

    The roots lie on a ``width`` x ``thickness`` rectangle (x, z) at height ``top`` (world y-up);
    each fibre falls about ``length`` toward -y, following the lock's common S-shaped ``wave``
    (amplitude in world units, in z and a little in x) and its own helical ``curl`` (0: straight
    fibres, 1: curls of radius ~0.05 length, a few turns per fibre) with a random phase, and the
    lock narrows toward the tips. ``radius`` is the fibre radius at the root; fibres taper to 40 %
    of it over the last fifth. ``seed`` makes it reproducible.
    """
    n = _check_int(n_fibres, "n_fibres", 1)
    p = _check_int(points_per_fibre, "points_per_fibre", 2)
    for name, v, lo in (("length", length, 0.0), ("radius", radius, 0.0), ("width", width, -1.0),
                        ("thickness", thickness, -1.0)):
        if not (isinstance(v, (int, float, np.integer, np.floating)) and math.isfinite(v) and v > lo):
            raise ValueError(f"{name}: must be a finite number > {max(lo, 0):g}, got {v!r}")
    for name, v in (("curl", curl), ("wave", wave), ("top", top)):
        if not (isinstance(v, (int, float, np.integer, np.floating)) and math.isfinite(v)):
            raise ValueError(f"{name}: must be a finite number, got {v!r}")
    if curl < 0:
        raise ValueError(f"curl: must be >= 0, got {curl!r}")
    rng = np.random.default_rng(_check_int(seed, "seed", 0))
    s = np.linspace(0.0, 1.0, p)                                  # arc parameter, root -> tip
    x0 = (rng.random(n) - 0.5) * width
    z0 = (rng.random(n) - 0.5) * thickness
    ln = length * (0.85 + 0.15 * rng.random(n))                   # uneven tips
    narrow = 1.0 - 0.45 * s ** 1.5                                # the lock gathers toward the tips
    y = top - ln[:, None] * s[None, :]
    x = x0[:, None] * narrow[None, :] + 0.25 * wave * np.sin(np.pi * s)[None, :]
    z = z0[:, None] * narrow[None, :] + wave * np.sin(2 * np.pi * s)[None, :]
    # per fibre helical curl and a little stray direction
    turns = 2.5 + 1.5 * rng.random(n)
    phase = 2 * np.pi * rng.random(n)
    amp = curl * 0.05 * length * (0.6 + 0.8 * rng.random(n))
    ang = phase[:, None] + 2 * np.pi * turns[:, None] * s[None, :]
    ramp = np.minimum(1.0, 4 * s)[None, :]                        # straight at the root
    x = x + amp[:, None] * ramp * np.cos(ang)
    z = z + amp[:, None] * ramp * np.sin(ang)
    stray = 0.02 * length * rng.standard_normal((n, 2))
    x = x + stray[:, :1] * s[None, :] ** 2
    z = z + stray[:, 1:] * s[None, :] ** 2
    pts = np.stack([x, y, z], axis=-1)
    r = radius * np.where(s > 0.8, 1.0 - 0.6 * (s - 0.8) / 0.2, 1.0)
    return pts, np.broadcast_to(r, (n, p)).copy()


def hair_scene(model, *, n_fibres=1500, curl=0.3, seed=0, envmap=None, aspect=1.0) -> Scene:
    """A lock of hair (:func:`hair_swatch`) of ``model`` against the environment (default: the
    ``"studio"`` soft boxes, which give hair its highlights), seen from the front at eye level
    with a 30 degree field of view, framed for width / height = ``aspect``; no ground."""
    pts, r = hair_swatch(n_fibres=n_fibres, curl=curl, seed=seed)
    sc = Scene(environment="studio" if envmap is None else envmap)
    sc.add_curves(model, pts, r)
    fov = 30.0
    half_h = 1.2                                                  # the lock spans y ~ 0 .. 2.2
    half_w = max(0.75, half_h * aspect)
    dist = half_w / math.tan(math.radians(fov / 2))
    sc.camera = Camera(origin=(0.0, 1.15, dist), target=(0.0, 1.1, 0.0), up=(0.0, 1.0, 0.0), fov=fov)
    return sc


#: The demo's row of hair locks: (label, model spec), pbrt-v4's melanin concentrations
#: (``Hair.from_concentration``; eumelanin 0.3 is blonde, 1.3 brown, 8 black).
HAIR_ROW = (("blonde", "hair concentration=0.3"),
            ("red", "hair concentration=0.15 pheomelanin=1.2"),
            ("brown", "hair concentration=1.3"),
            ("black", "hair concentration=8"))
#: Size and quality of the demo's ``hair.png``.
HAIR_SIZE = (512, 288)
HAIR_SPP = 32
#: Spacing of the locks of :func:`hair_row_scene` (world units; a lock is ~0.6 wide).
HAIR_SPACING = 1.0


def hair_row_scene(models, *, n_fibres=2500, spacing=HAIR_SPACING, envmap=None,
                   aspect=HAIR_SIZE[0] / HAIR_SIZE[1], seed=0) -> Scene:
    """One lock of hair (:func:`hair_swatch` with width 0.55, thickness 0.12, wave 0.18, curl 0.12,
    a different seed each) per model, side by side along x, left to right, under ``envmap``
    (default: the ``"sky"``, whose sun gives the highlights), framed for width / height = ``aspect``."""
    models = list(models)
    if not models:
        raise ValueError("models: need at least one model")
    sc = Scene(environment="sky" if envmap is None else envmap)
    k = len(models)
    for i, m in enumerate(models):
        pts, r = hair_swatch(n_fibres=n_fibres, seed=seed + i, width=0.55, thickness=0.12, wave=0.18, curl=0.12)
        pts[..., 0] += (i - (k - 1) / 2) * spacing
        sc.add_curves(m, pts, r)
    fov = 30.0
    half_w = max((k - 1) / 2 * spacing + 0.6, 1.2 * aspect)
    dist = half_w / math.tan(math.radians(fov / 2))
    sc.camera = Camera(origin=(0.0, 1.15, dist), target=(0.0, 1.1, 0.0), up=(0.0, 1.0, 0.0), fov=fov)
    return sc


def write_hair(outdir, rows=HAIR_ROW, *, size=HAIR_SIZE, spp=HAIR_SPP, progress=True, exposure=0.0):
    """Renders :func:`hair_row_scene` of ``rows`` ((label, spec or model) pairs; default
    :data:`HAIR_ROW`) and writes ``hair.exr`` (linear radiance) and ``hair.png`` (sRGB, each lock
    labelled with its name and spec); returns the two paths."""
    from matplotlib.figure import Figure

    from .io import linear_to_srgb, write_image
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


def _spec_of(model):
    from .models.spec import to_spec
    return to_spec(model)


# ---------------------------------------------------------------- scene

#: Largest |coordinate| of the camera's origin, target and up, and of the scene's geometry
#: (sphere centres +- radii, mesh vertices, fibre points, the ground): the renderer takes them as
#: float32 and squares target - origin and forward x up there (cpp/bindings/render.cpp
#: render_impl, render/camera.h look_at); within 1e18 those squares (<= 12e36) stay below
#: float32's max 3.4e38, where beyond it they overflowed and the camera failed as "up: must not
#: be parallel to the view direction".
CAMERA_MAX_COORD = 1e18


@dataclass
class Camera:
    """Pinhole camera: position, look-at point, up hint and full horizontal field of view (degrees).

    origin, target, up: 3 finite numbers each, within +-``CAMERA_MAX_COORD`` (1e18: the renderer
    works in float32); target must differ from origin (in float32) and up must not be (nearly)
    zero or parallel to the view direction; fov in (0, 180). Checked when the camera is used
    (``render``, ``project``, ``Scene.look_at``): ValueError naming the field."""
    origin: tuple = (0.0, 1.45, 5.6)
    target: tuple = (0.0, 0.9, 0.0)
    up: tuple = (0.0, 1.0, 0.0)
    fov: float = 32.0

    def _checked(self):
        names = ("origin", "target", "up")
        o, t, u = (_vec3(getattr(self, n), f"camera.{n}") for n in names)
        for n, x in zip(names, (o, t, u)):
            _check_extent(x, f"camera.{n}")
        f = t - o
        f32 = t.astype(np.float32) - o.astype(np.float32)
        if not (np.linalg.norm(f) > 0 and np.dot(f32, f32) > 0):   # the renderer's test is in float32
            raise ValueError("camera.target: must differ from camera.origin (in float32, the renderer's precision)")
        if not np.linalg.norm(u) >= 1e-6:
            raise ValueError(f"camera.up: must not be (nearly) zero, got {u.tolist()}")
        if np.linalg.norm(np.cross(f / np.linalg.norm(f), u)) < 1e-6:
            raise ValueError("camera.up: must not be parallel to the view direction")
        fov = check_real(self.fov, "camera.fov")
        if not 0 < fov < 180:
            raise ValueError("camera.fov: must be in (0, 180) degrees")
        return o.tolist(), t.tolist(), u.tolist(), fov


def _model_check(material, name="material"):
    core = getattr(material, "_core", None)
    if core is None:
        raise TypeError(f"{name}: expected a bsdfkit model (e.g. bk.Diffuse(0.8)), got {type(material).__name__}")
    return material


def _check_extent(a, name):
    """World coordinates (the camera's, the scene geometry's) within +-CAMERA_MAX_COORD: Embree
    and the renderer hold them in float32 and square differences of them (finite float64 values
    up to 1.8e308 passed the finiteness check and became inf or overflowed there)."""
    m = float(np.max(np.abs(a))) if np.size(a) else 0.0
    if m > CAMERA_MAX_COORD:
        raise ValueError(f"{name}: coordinates must be within +-{CAMERA_MAX_COORD:g} (the renderer works in "
                         f"float32), got a magnitude of {m:g}")


def _vec3(x, name):
    a = _as_real_array(x, name).astype(np.float64)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected 3 finite numbers")
    return a


@dataclass
class Scene:
    """Objects, materials, lighting and camera of a render. Build with the ``add_*`` methods
    (each returns the scene, so calls chain) and pass to :func:`render` / :func:`preview`.

    ``environment``: ``"sky"`` (default), ``"studio"``, ``"white"``, a path to a lat-long
    EXR/HDR/PNG, an (H, W, 3) radiance array, or a constant radiance (number or RGB).
    """
    environment: object = "sky"
    camera: Camera = field(default_factory=Camera)
    objects: list = field(default_factory=list)
    lights: list = field(default_factory=list)

    def add_sphere(self, material, center=(0.0, 1.0, 0.0), radius=1.0) -> "Scene":
        """A sphere (outward normal) of one material."""
        c = _vec3(center, "center")
        r = float(radius)
        if not (math.isfinite(r) and r > 0):
            raise ValueError("radius: must be finite and > 0")
        _check_extent(c, "center")
        _check_extent(np.abs(c) + r, "center +- radius")
        self.objects.append(dict(kind="sphere", material=_model_check(material), center=c, radius=r))
        return self

    def add_mesh(self, material, vertices, indices=None, *, transform=None, fit=False) -> "Scene":
        """A triangle mesh of one material.

        ``vertices`` (N, 3) and ``indices`` (M, 3) arrays (counter-clockwise seen from outside),
        or ``vertices`` a path to a mesh file (OBJ/PLY/... read by :func:`load_mesh`).
        ``transform``: optional 4x4 object-to-world matrix. ``fit=True`` then scales and moves
        the mesh to fit a unit sphere standing on the ground plane y = 0 (like the preview sphere).
        """
        if isinstance(vertices, (str, os.PathLike)):
            if indices is not None:
                raise ValueError("indices: not accepted with a mesh file path")
            vertices, indices = load_mesh(vertices)
        elif indices is None:
            raise ValueError("indices: required with a vertex array")
        v, i = _mesh_arrays(vertices, indices)
        v = _apply_transform(v, transform)
        if fit:
            v = _fit_on_ground(v)
        _check_extent(v, "vertices" if transform is None else "vertices (transformed)")
        self.objects.append(dict(kind="mesh", material=_model_check(material), vertices=v, indices=i))
        return self

    def add_curves(self, material, points, radius=0.01) -> "Scene":
        """Fibres of one material: smooth round curves (Embree round Catmull-Rom curves) through
        the given points, e.g. the output of :func:`hair_swatch`.

        ``points``: an (F, P, 3) array (F fibres of P >= 2 points each) or a list of (P_i, 3)
        arrays. ``radius``: the fibre radius (world units, > 0), a number or one value per point
        (an (F, P) array or a list of (P_i,) arrays), interpolated along the fibre. Each fibre
        passes through its points (end tangents continue the first and last segment). See the
        module notes for the shading frame and the offset h of hair models.
        """
        fibres = _fibre_list(points, "points")
        radii = _radius_list(radius, fibres)
        ctrl, segs, start = [], [], 0
        for q, r in zip(fibres, radii):
            # phantom end points: the Catmull-Rom segment i spans control points i+1 .. i+2
            qe = np.concatenate([2 * q[:1] - q[1:2], q, 2 * q[-1:] - q[-2:-1]])
            re = np.concatenate([r[:1], r, r[-1:]])
            ctrl.append(np.concatenate([qe, re[:, None]], axis=1))
            segs.append(start + np.arange(len(q) - 1))
            start += len(qe)
        ctrl = np.concatenate(ctrl)
        _check_extent(np.abs(ctrl[:, :3]) + ctrl[:, 3:], "points (with radius)")
        self.objects.append(dict(kind="curves", material=_model_check(material),
                                 points=ctrl, segments=np.concatenate(segs).astype(np.int64)))
        return self

    def add_ground(self, material=None, *, height=0.0, size=200.0, checker=None, checker_size=0.5) -> "Scene":
        """A horizontal square (normal +y) of side ``size`` at y = ``height``. With ``checker`` (a
        second model) the two materials alternate on squares of side ``checker_size``.
        Defaults: a grey checkerboard of Diffuse(0.45) and Diffuse(0.15)."""
        from .models import Diffuse
        if material is None:
            material = Diffuse(0.45)
            if checker is None:
                checker = Diffuse(0.15)
        h, s, cs = float(height), float(size), float(checker_size)
        if not (math.isfinite(h) and math.isfinite(s) and s > 0):
            raise ValueError("height, size: must be finite, size > 0")
        if checker is not None and not (math.isfinite(cs) and cs > 0):
            raise ValueError("checker_size: must be finite and > 0")
        _check_extent(np.array([h, s / 2]), "height, size")
        a = s / 2
        v = np.array([[-a, h, -a], [a, h, -a], [a, h, a], [-a, h, a]])
        i = np.array([[0, 2, 1], [0, 3, 2]])   # counter-clockwise seen from above: normal +y
        self.objects.append(dict(kind="mesh", material=_model_check(material), vertices=v, indices=i,
                                 checker=None if checker is None else _model_check(checker, "checker"),
                                 checker_size=cs))
        return self

    def add_directional_light(self, direction, irradiance=(3.0, 3.0, 3.0)) -> "Scene":
        """A light at infinity: ``irradiance`` (RGB, or a number) on a surface facing it, arriving
        from ``direction`` (pointing toward the light). At most one."""
        d = _vec3(direction, "direction")
        if not np.linalg.norm(d) > 0:
            raise ValueError("direction: must be non-zero")
        e = np.broadcast_to(np.asarray(irradiance, dtype=np.float64), (3,))
        if not np.all(np.isfinite(e)) or np.any(e < 0):
            raise ValueError("irradiance: must be finite and >= 0")
        if self.lights:
            raise ValueError("lights: only one directional light is supported")
        self.lights.append(dict(direction=d / np.linalg.norm(d), irradiance=e.copy()))
        return self

    def look_at(self, origin, target, up=(0.0, 1.0, 0.0), fov=None) -> "Scene":
        """Sets the camera (``fov`` in degrees, full horizontal; kept if None)."""
        self.camera = Camera(tuple(_vec3(origin, "origin")), tuple(_vec3(target, "target")),
                             tuple(_vec3(up, "up")), self.camera.fov if fov is None else check_real(fov, "fov"))
        self.camera._checked()
        return self

    def _build(self, envmap=None, spectral=False):
        """The C++ scene: materials, Embree geometry, lighting (committed); with ``spectral``
        also the spectral models, colour tables and uplifted lights (:func:`_set_spectral`)."""
        s = _core.RenderScene()
        mats = {}

        def mat(m):
            key = id(m)
            if key not in mats:
                mats[key] = (s.add_material(m), m)
            return mats[key][0]

        for ob in self.objects:
            a = mat(ob["material"])
            b = mat(ob["checker"]) if ob.get("checker") is not None else a
            cs = ob.get("checker_size", 0.0) if ob.get("checker") is not None else 0.0
            if ob["kind"] == "sphere":
                s.add_sphere(ob["center"].tolist(), ob["radius"], a, b, cs)
            elif ob["kind"] == "curves":
                s.add_curves(np.ascontiguousarray(ob["points"], dtype=np.float32), ob["segments"], a)
            else:
                s.add_mesh(np.ascontiguousarray(ob["vertices"], dtype=np.float32),
                           np.ascontiguousarray(ob["indices"], dtype=np.int64), a, b, cs)
        kind, val = _environment(self.environment if envmap is None else envmap)
        if kind == "constant":
            s.set_environment_constant(list(val))
        else:
            s.set_environment_latlong(val)
        for light in self.lights:
            s.set_directional(light["direction"].tolist(), light["irradiance"].tolist())
        if spectral:
            _set_spectral(s, list(mats.values()), kind, val, self.lights)
        s.commit()
        return s


# ---------------------------------------------------------------- spectral mode

#: Models the spectral renderer accepts (those with a spectral kernel, batch_spectral.h).
SPECTRAL_MODELS = ("Diffuse", "DiffuseTransmission", "Conductor", "Dielectric", "ThinDielectric", "Plastic",
                   "FilamentStandard", "NormalizedFresnel", "CoatedDiffuse", "CoatedConductor",
                   "Measured (spectral tensor files)", "MERL", "Hair (a single h; not the far field h=None)")


@functools.lru_cache(maxsize=1)
def _spectral_tables():
    """The colour tables of the spectral tracer: D65 of unit luminance on its 5 nm table (as
    ``bk.spectrum_to_rgb(illuminant="D65")``) and XYZ_TO_SRGB @ cmf / integral(y-bar) on the
    1 nm CMF table (``bk.spectrum_to_rgb``'s weights), both linear between nodes."""
    from .spectral import colorimetry
    w5, _, d, w1, c1 = colorimetry._tables()
    d65_unit = np.ascontiguousarray(d * colorimetry._grid("pbrt")[4], dtype=np.float64)
    match = np.ascontiguousarray(c1 @ colorimetry.XYZ_TO_SRGB.T / colorimetry.cie_y_integral(), dtype=np.float64)
    return d65_unit, float(w5[0]), float(w5[1] - w5[0]), match, float(w1[0]), float(w1[1] - w1[0])


def _uplift_illuminant(rgb, exact):
    """(..., 4) = (c0, c1, c2, scale) of RGB radiance uplifted as pbrt-v4's RGBIlluminantSpectrum
    (the D65 factor is applied by the tracer)."""
    from .spectral import uplift
    c, scale = uplift.rgb_coefficients(np.asarray(rgb, dtype=np.float64), "illuminant", exact=exact)
    return np.ascontiguousarray(np.concatenate([c, np.asarray(scale)[..., None]], axis=-1), dtype=np.float64)


def _set_spectral(s, materials, env_kind, env_val, lights):
    """Spectral mode of a C++ scene: each material's spectral model (its ``_core.<Model>Spectral``,
    the same kernels as ``model.eval(..., wavelengths=...)``), the colour tables and the lights
    uplifted to illuminant spectra: a constant environment and the directional light with the
    polished fit (``exact=True``, as model parameters), a lat-long image per texel with the
    table lookup (pbrt-v4's ``RGBToSpectrumTable`` as is)."""
    from .models import _spectral
    for index, model in materials:
        try:
            core = _spectral._spectral_core(model)
        except NotImplementedError:
            raise NotImplementedError(
                f"spectral: {type(model).__name__} has no spectral kernel yet; spectral=True renders "
                f"{', '.join(SPECTRAL_MODELS)} (render this scene with spectral=False)") from None
        try:
            s.set_spectral_material(index, core)
        except TypeError:   # a spectral kernel the renderer does not know yet
            raise NotImplementedError(
                f"spectral: the renderer has no spectral path for {type(model).__name__} yet; spectral=True "
                f"renders {', '.join(SPECTRAL_MODELS)} (render this scene with spectral=False)") from None
    s.set_spectral_tables(*_spectral_tables())
    zero = np.array([0.0, 0.0, -np.inf, 0.0])
    if env_kind == "constant":
        constant, texels = _uplift_illuminant(env_val, True), None
    else:
        constant, texels = zero, _uplift_illuminant(env_val.astype(np.float64), False)
    sun = _uplift_illuminant(lights[0]["irradiance"], True) if lights else zero
    s.set_spectral_lights(constant, sun, texels)


def default_scene(model, *, shape=None, envmap=None) -> Scene:
    """The preview scene: ``model`` on a unit sphere (or ``shape``: a mesh file path or a
    ``(vertices, indices)`` pair, fitted to the same place) standing on a grey checkerboard
    ground, seen from the front, under ``envmap`` (default: the procedural sky).
    ``shape="hair"``: the fibres of :func:`hair_scene` instead."""
    if isinstance(shape, str) and shape == "hair":
        return hair_scene(model, envmap=envmap)
    sc = Scene(environment="sky" if envmap is None else envmap)
    if shape is None or (isinstance(shape, str) and shape == "sphere"):
        sc.add_sphere(model, center=(0.0, 1.0, 0.0), radius=1.0)
    elif isinstance(shape, (str, os.PathLike)):
        sc.add_mesh(model, shape, fit=True)
    else:
        v, i = shape
        sc.add_mesh(model, v, i, fit=True)
    sc.add_ground()
    return sc


def gallery_scene(models, *, columns=5, envmap=None, spacing=2.5, aspect=2.0) -> Scene:
    """One unit sphere per model on the checkerboard ground, in rows of ``columns`` from the
    back row to the front, left to right (rows staggered by half a spacing), seen from above
    (about 24 degrees down) so that no sphere hides another, framed for an image of width /
    height = ``aspect`` (camera fov 40 degrees)."""
    models = list(models)
    if not models:
        raise ValueError("models: need at least one model")
    columns = max(1, min(int(columns), len(models)))
    rows = math.ceil(len(models) / columns)
    sc = Scene(environment="sky" if envmap is None else envmap)
    row_gap = 1.1 * spacing
    for k, m in enumerate(models):
        r, c = divmod(k, columns)
        x = (c - (columns - 1) / 2 + (0.25 if r % 2 == 0 else -0.25) * (rows > 1)) * spacing
        z = (r - (rows - 1) / 2) * row_gap
        sc.add_sphere(m, center=(x, 1.0, z), radius=1.0)
    fov = 40.0
    t = math.tan(math.radians(fov / 2))
    half_w = ((columns - 1) / 2 + 0.25 * (rows > 1)) * spacing + 1.35
    depth = (rows - 1) * row_gap
    tilt = math.radians(24.0)
    # far enough for the width, and for the rows' vertical extent (depth seen at the tilt, plus a
    # sphere's height) within the frame's vertical half-angle
    half_h = 0.5 * (depth * math.sin(tilt) + 2.0 * math.cos(tilt)) + 0.6
    dist = max(half_w / t, half_h * aspect / t) + depth / 2 * math.cos(tilt)
    target = (0.0, 1.0, 0.0)
    sc.camera = Camera(origin=(0.0, 1.0 + dist * math.sin(tilt), dist * math.cos(tilt)), target=target,
                       up=(0.0, 1.0, 0.0), fov=fov)
    sc.add_ground()
    return sc


#: Gallery output size and quality of ``python -m bsdfkit demo``.
GALLERY_SIZE = (640, 320)
GALLERY_SPP = 48


def project(camera: Camera, points, size) -> np.ndarray:
    """Pixel coordinates (x right, y down, pixel centres at +0.5) of world ``points`` (..., 3) in
    an image of ``size`` = (width, height) seen by the pinhole ``camera`` (the renderer's
    convention: full horizontal fov, image x along forward x up).

    Raises ValueError naming ``points`` for NaN / infinite points, points not in front of the
    camera (on or behind the plane through its origin facing the view direction: they have no
    pixel position) and positions beyond float64's range; ``size`` must be two finite numbers > 0."""
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a bsdfkit.render.Camera, got {type(camera).__name__}")
    o, t, u, fov = (np.asarray(v, dtype=np.float64) for v in camera._checked())
    p = _as_real_array(points, "points")
    if p.ndim == 0 or p.shape[-1] != 3:
        raise ValueError(f"points: expected an array of points with last axis of length 3, got shape {p.shape}")
    p = p.astype(np.float64)
    if not np.all(np.isfinite(p)):
        raise ValueError(f"points: {np.count_nonzero(~np.all(np.isfinite(p), axis=-1))} point(s) contain NaN or Inf")
    try:
        w, h = size
    except (TypeError, ValueError):
        raise ValueError(f"size: expected (width, height), got {size!r}") from None
    w, h = check_real(w, "size (width)"), check_real(h, "size (height)")
    if not (w > 0 and h > 0):
        raise ValueError(f"size: width and height must be > 0, got {size!r}")
    f = (t - o) / np.linalg.norm(t - o)
    r = np.cross(f, u)
    r /= np.linalg.norm(r)
    up = np.cross(r, f)
    th = math.tan(math.radians(float(fov)) / 2)
    with np.errstate(all="ignore"):
        d = p - o
        z = d @ f
        x = (1 + (d @ r) / (z * th)) * w / 2
        y = (1 - (d @ up) / (z * th * h / w)) * h / 2
    behind = np.count_nonzero(~(z > 0))
    if behind:
        raise ValueError(f"points: {behind} point(s) are not in front of the camera (on or behind the plane through "
                         "its origin facing the view direction); they have no pixel position")
    xy = np.stack([x, y], axis=-1)
    if not np.all(np.isfinite(xy)):
        raise ValueError(f"points: {np.count_nonzero(~np.all(np.isfinite(xy), axis=-1))} point(s) project beyond "
                         "float64's range (too close to the camera's plane for their offset, or too large)")
    return xy


def _labelled_gallery(path, img, sc, names, size):
    """gallery_labelled.png: the render with a number on each sphere and a key of the
    configurations under it (the 640 x 320 render is too small to write the specs on)."""
    import textwrap

    import matplotlib.pyplot as plt

    from .io import linear_to_srgb
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


def write_gallery(outdir, configs, *, size=GALLERY_SIZE, spp=GALLERY_SPP, progress=True, verbose=True,
                  labelled=True):
    """Renders one sphere per (name, model) of ``configs`` with :func:`gallery_scene` under the
    default sky and writes ``gallery.exr`` (linear radiance), ``gallery.png`` (sRGB) and, with
    ``labelled``, ``gallery_labelled.png`` (each sphere numbered, with a key of the names);
    returns the paths."""
    from .io import write_image
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


# ---------------------------------------------------------------- dispersion demo

#: The demo's dispersive glass (a dense flint: n = 1.819 at 450 nm, 1.777 at 650 nm; pbrt-v4's data).
DISPERSION_GLASS = "glass-F11"
DISPERSION_SIZE = (240, 180)
DISPERSION_SPP = 128


def stripes_environment(width: int = 512) -> np.ndarray:
    """A dark lat-long environment with bright white stripes (12 vertical bars around the azimuth
    and two horizontal bands), float32 (width // 2, width, 3): sharp white edges for a glass to
    disperse into colour fringes."""
    width = int(width)
    if width < 16:
        raise ValueError("width: must be >= 16")
    d = _latlong_dirs(width, width // 2)
    phi = np.arctan2(d[..., 0], -d[..., 2])
    elev = np.degrees(np.arcsin(np.clip(d[..., 1], -1, 1)))
    bars = (np.mod(np.degrees(phi), 30.0) < 6.0) & (elev > -10) & (elev < 55)
    bands = (np.abs(elev - 22.0) < 2.5) | (np.abs(elev + 4.0) < 1.5)
    env = np.where((bars | bands)[..., None], 6.0, 0.02) + 0.02 * np.clip(d[..., 1:2], 0, 1)
    return np.ascontiguousarray(np.broadcast_to(env, d.shape), dtype=np.float32)


def dispersion_scene(glass=DISPERSION_GLASS, *, envmap=None, aspect=4 / 3) -> Scene:
    """A glass sphere with eta = ``bk.Spectrum.named(glass)`` (dispersive) floating in
    :func:`stripes_environment`, framed close."""
    from .models import Dielectric
    from .spectral import Spectrum
    sc = Scene(environment=stripes_environment() if envmap is None else envmap)
    sc.add_sphere(Dielectric(eta=Spectrum.named(glass)), center=(0.0, 1.0, 0.0), radius=1.0)
    sc.look_at((0.0, 1.25, 3.6), (0.0, 0.95, 0.0), fov=38.0 * max(1.0, aspect / (4 / 3)))
    return sc


def write_dispersion(outdir, *, glass=DISPERSION_GLASS, size=DISPERSION_SIZE, spp=DISPERSION_SPP, progress=True):
    """The RGB-versus-spectral comparison of the demo: :func:`dispersion_scene` rendered in RGB
    (the glass at eta(550 nm): no dispersion) and with ``spectral=True`` (hero wavelengths:
    colour fringes along every bright edge seen through the glass), side by side with their
    difference. Writes ``dispersion.png`` and ``dispersion_spectral.exr``; returns the paths."""
    from matplotlib.figure import Figure

    from .io import linear_to_srgb, write_image
    from .spectral import Spectrum
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


# ---------------------------------------------------------------- rendering

def _check_int(v, name, lo):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
        raise ValueError(f"{name}: expected an integer, got {v!r}")
    if v < lo:
        raise ValueError(f"{name}: must be >= {lo}, got {v}")
    return int(v)


class _Progress:
    """A one-line text progress bar on stderr, shown only for renders expected to last > 1 s."""

    def __init__(self, enabled, total, label):
        self.enabled, self.total, self.label = enabled, total, label
        self.t0 = time.perf_counter()
        self.shown = False

    def update(self, done):
        if not self.enabled:
            return
        el = time.perf_counter() - self.t0
        eta = el / done * (self.total - done) if done else float("inf")
        if not self.shown and el + eta < 1.0:
            return
        self.shown = True
        n = 30
        k = int(n * done / self.total)
        sys.stderr.write(f"\r{self.label} [{'#' * k}{'.' * (n - k)}] {done}/{self.total} spp "
                         f"{el:5.1f} s, ~{eta:4.1f} s left ")
        sys.stderr.flush()

    def close(self, note=""):
        if self.shown:
            sys.stderr.write(f"{note}\n")
            sys.stderr.flush()


_WAVE_SAMPLES = 4  # sample indices per wave of the C++ tracer (render/wavefront.h kWaveSamples)


def render(scene: Scene, *, envmap=None, width=256, height=256, spp=64, max_depth=8, seed=0, progress=True,
           interrupt="raise", return_stats=False, spectral=False):
    """Renders a :class:`Scene`; see :func:`preview` for the arguments.

    With ``return_stats=True`` returns ``(image, stats)``, stats a dict with ``seconds``
    (wall time of the path tracing), ``build_seconds`` (scene and BVH), ``rays`` (camera,
    bounce and shadow rays traced), ``spp`` and ``nonfinite`` (discarded NaN/Inf path samples).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a bsdfkit.render.Scene, got {type(scene).__name__}")
    width = _check_int(width, "width", 1)
    height = _check_int(height, "height", 1)
    spp = _check_int(spp, "spp", 1)
    max_depth = _check_int(max_depth, "max_depth", 0)
    seed = _check_int(seed, "seed", 0) & 0xFFFFFFFFFFFFFFFF
    if width * height > 1 << 26:
        raise ValueError("width * height: at most 2**26 pixels")
    if interrupt not in ("raise", "return"):
        raise ValueError(f"interrupt: must be 'raise' or 'return', got {interrupt!r}")
    if not isinstance(spectral, (bool, np.bool_)):
        raise TypeError(f"spectral: expected True or False, got {spectral!r}")
    o, t, u, fov = scene.camera._checked()

    t0 = time.perf_counter()
    core = scene._build(envmap, spectral=bool(spectral))
    trace = core.render_spectral if spectral else core.render
    t1 = time.perf_counter()
    acc = np.zeros((height, width, 3), np.float64)
    scratch = np.empty_like(acc)
    done, rays, nonfinite = 0, 0, 0
    bar = _Progress(progress, spp, f"render {width}x{height}{' spectral' if spectral else ''}")
    try:
        # passes of whole waves: the tracer traces 4 sample indices of a tile together
        # (render/wavefront.h kWaveSamples); a pass of fewer leaves its packets part-empty
        k = _WAVE_SAMPLES
        while done < spp:
            k = min(k, spp - done)
            np.copyto(scratch, acc)
            ts = time.perf_counter()
            _, r, nf = trace(o, t, u, fov, max_depth, seed, done, done + k, scratch)
            dt = time.perf_counter() - ts
            acc, scratch = scratch, acc
            done += k
            rays += r
            nonfinite += nf
            bar.update(done)
            # passes of ~0.25 s: responsive progress; the result does not depend on the split
            k = min(4 * k, int(k * 0.25 / max(dt, 1e-6)))
            k = max(_WAVE_SAMPLES, k - k % _WAVE_SAMPLES)
    except KeyboardInterrupt as e:
        bar.close(" interrupted")
        partial = (acc / done).astype(np.float32) if done else None
        if interrupt == "return" and partial is not None:
            warnings.warn(f"render interrupted: returning the image after {done} of {spp} spp", RuntimeWarning,
                          stacklevel=2)
            return (partial, dict(seconds=time.perf_counter() - t1, build_seconds=t1 - t0, rays=rays, spp=done,
                                  nonfinite=nonfinite)) if return_stats else partial
        e.image = partial
        e.spp_done = done
        raise
    bar.close()
    img = (acc / spp).astype(np.float32)
    if return_stats:
        return img, dict(seconds=time.perf_counter() - t1, build_seconds=t1 - t0, rays=rays, spp=spp,
                         nonfinite=nonfinite)
    return img


def preview(model_or_scene, envmap=None, width=256, height=256, spp=64, max_depth=8, seed=0, progress=True, *,
            shape=None, interrupt="raise", return_stats=False, spectral=False):
    """Path-traced image of a material, float32 (height, width, 3) linear radiance.

    model_or_scene: a bsdfkit model (shown on a unit sphere, or on ``shape``, standing on a
        checkerboard ground; see :func:`default_scene`) or a :class:`Scene`.
    envmap: environment, overriding the scene's: ``"sky"`` (procedural default), ``"studio"``,
        ``"white"`` (uniform radiance 1), a lat-long EXR/HDR/PNG path, an (H, W, 3) array, or a
        constant radiance. A missing or unreadable file raises FileNotFoundError / OSError naming
        the file with OpenImageIO's reason.
    width, height, spp: image size and samples per pixel (>= 1). max_depth: scattering events
        per path (>= 0; Mitsuba's max_depth is ours + 1). seed: the image is a deterministic
        function of the seed, independent of the thread count.
    progress: a text progress bar on stderr for renders longer than about a second.
    interrupt: on Ctrl-C, ``"raise"`` (default) re-raises KeyboardInterrupt carrying
        ``.image`` (the completed passes' average, or None) and ``.spp_done``; ``"return"``
        returns that partial image with a RuntimeWarning.
    spectral: trace hero-wavelength paths (pbrt-v4's spectral PathIntegrator) instead of RGB:
        4 wavelengths per path from pbrt-v4's visible-wavelength importance sampling
        (``bk.sample_wavelengths``), the materials through their spectral kernels (the same as
        ``model.eval(..., wavelengths=...)``: spectra as parameters, RGB parameters uplifted,
        a dielectric with ``eta=bk.Spectrum(...)`` disperses), the environment and light RGB
        uplifted to illuminant spectra (pbrt-v4 ``RGBIlluminantSpectrum``: Jakob & Hanika
        sigmoid times D65; a lat-long image per texel, bilinear between texel spectra), a
        refraction through a dispersive dielectric terminating the secondary wavelengths
        (pbrt-v4 ``TerminateSecondary``), each path converted to linear sRGB as
        ``bk.spectrum_to_rgb``. Models without a spectral kernel (see ``SPECTRAL_MODELS``)
        raise NotImplementedError naming the model: their RGB f is not a spectrum, and
        uplifting it per evaluation would pass an RGB render off as a spectral one.

    Write the result with ``bk.io.write_image("x.png", img, exposure=0)`` (sRGB PNG) or ".exr".
    """
    if isinstance(model_or_scene, Scene):
        if shape is not None:
            raise ValueError("shape: only accepted with a model, not a Scene")
        scene = model_or_scene
    else:
        scene = default_scene(_model_check(model_or_scene, "model_or_scene"), shape=shape)
    return render(scene, envmap=envmap, width=width, height=height, spp=spp, max_depth=max_depth, seed=seed,
                  progress=progress, interrupt=interrupt, return_stats=return_stats, spectral=spectral)


# ---------------------------------------------------------------- model specs (CLI)

def parse_spec(spec):
    """A model from a readable spec: ``"conductor metal=Cu alpha=0.2"``, ``"diffuse 0.8,0.5,0.2"``,
    ``"dielectric eta=1.5 alpha=0.1"``, ``"thin_dielectric"``, ``"difftrans 0.5 0.4"``.

    The same parser as ``python -m bsdfkit lobes`` (``bsdfkit._spec.parse_spec``): a model name
    (or alias), then positional values and ``key=value`` constructor parameters (RGB as
    ``r,g,b``); ``metal=`` / ``reflectance=`` select ``Conductor.from_metal`` /
    ``from_reflectance``. Raises ValueError listing the valid models or parameters."""
    from .models.spec import parse_spec as shared
    return shared(spec)
