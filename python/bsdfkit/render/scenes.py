"""Ready-made scenes: the preview (a model on a sphere or a mesh), the gallery of spheres, locks of
hair on fibres and the dispersion demo's glass sphere."""
from __future__ import annotations

import math
import os

import numpy as np

from .environment import stripes_environment
from .scene import Camera, Scene, _check_int


def default_scene(model, *, shape=None, envmap=None) -> Scene:
    """The preview scene: ``model`` on a unit sphere (or ``shape``) standing on a grey checkerboard
    ground, seen from the front.

    Parameters
    ----------
    model : BxDF
        The material.
    shape : str or tuple, optional
        A mesh file path or a ``(vertices, indices)`` pair, fitted to the sphere's place;
        ``"hair"``: the fibres of :func:`hair_scene` instead.
    envmap : optional
        The environment (default: the procedural sky).

    Returns
    -------
    Scene
        The scene.
    """
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
    """One unit sphere per model on the checkerboard ground, in rows of ``columns`` from the back
    row to the front, left to right (rows staggered by half a spacing), seen from above (about
    24 degrees down) so that no sphere hides another (camera fov 40 degrees).

    Parameters
    ----------
    models : sequence of BxDF
        The materials.
    columns : int, optional
        Spheres per row.
    envmap : optional
        The environment (default: the procedural sky).
    spacing : float, optional
        Distance between sphere centres.
    aspect : float, optional
        Width / height of the image the camera is framed for.

    Returns
    -------
    Scene
        The scene.
    """
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


def hair_swatch(n_fibres=1500, length=2.0, radius=0.004, curl=0.3, seed=0, *, width=0.9, thickness=0.18,
                wave=0.12, points_per_fibre=24, top=2.15):
    """A procedural lock of hair: ``n_fibres`` fibres hanging from a short bar, for
    :meth:`Scene.add_curves`.

    The roots lie on a ``width`` x ``thickness`` rectangle (x, z) at height ``top`` (world y-up);
    each fibre falls about ``length`` toward -y, following the lock's common S-shaped ``wave``
    and its own helical ``curl`` with a random phase, and the lock narrows toward the tips.
    Fibres taper to 40 % of the root radius over the last fifth.

    Parameters
    ----------
    n_fibres : int, optional
        Number of fibres.
    length : float, optional
        Fibre length (world units).
    radius : float, optional
        Fibre radius at the root.
    curl : float, optional
        0: straight fibres, 1: curls of radius ~0.05 length, a few turns per fibre.
    seed : int, optional
        Makes it reproducible.
    width, thickness : float, optional
        The root rectangle.
    wave : float, optional
        Amplitude of the common S-shape (world units, in z and a little in x).
    points_per_fibre : int, optional
        Control points per fibre.
    top : float, optional
        Height of the roots.

    Returns
    -------
    points : numpy.ndarray, shape (F, P, 3)
        float64 control points.
    radius : numpy.ndarray, shape (F, P)
        float64 radii.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> pts, r = bk.render.hair_swatch(n_fibres=10, points_per_fibre=8)
    >>> pts.shape, r.shape
    ((10, 8, 3), (10, 8))
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
    """A lock of hair (:func:`hair_swatch`) of ``model`` against the environment, seen from the front
    at eye level with a 30 degree field of view; no ground.

    Parameters
    ----------
    model : Hair
        The fibre material.
    n_fibres : int, optional
        Fibres in the lock.
    curl : float, optional
        As :func:`hair_swatch`'s.
    seed : int, optional
        Seed of the lock.
    envmap : optional
        The environment (default: the ``"studio"`` soft boxes, which give hair its highlights).
    aspect : float, optional
        Width / height of the image the camera is framed for.

    Returns
    -------
    Scene
        The scene.
    """
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
    a different seed each) per model, side by side along x, left to right.

    Parameters
    ----------
    models : sequence of Hair
        The fibre materials.
    n_fibres : int, optional
        Fibres per lock.
    spacing : float, optional
        Distance between locks.
    envmap : optional
        The environment (default: the ``"sky"``, whose sun gives the highlights).
    aspect : float, optional
        Width / height of the image the camera is framed for.
    seed : int, optional
        Seed of the first lock.

    Returns
    -------
    Scene
        The scene.
    """
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


#: The demo's dispersive glass (a dense flint: n = 1.819 at 450 nm, 1.777 at 650 nm; pbrt-v4's data).
DISPERSION_GLASS = "glass-F11"


DISPERSION_SIZE = (240, 180)


DISPERSION_SPP = 128


def dispersion_scene(glass=DISPERSION_GLASS, *, envmap=None, aspect=4 / 3) -> Scene:
    """A glass sphere with eta = ``bk.Spectrum.named(glass)`` (dispersive) floating in
    :func:`stripes_environment`, framed close.

    Parameters
    ----------
    glass : str, optional
        A named glass spectrum (``bk.Spectrum.names()``).
    envmap : optional
        The environment (default: the stripes).
    aspect : float, optional
        Width / height of the image the camera is framed for.

    Returns
    -------
    Scene
        The scene.
    """
    from ..models import Dielectric
    from ..spectral import Spectrum
    sc = Scene(environment=stripes_environment() if envmap is None else envmap)
    sc.add_sphere(Dielectric(eta=Spectrum.named(glass)), center=(0.0, 1.0, 0.0), radius=1.0)
    sc.look_at((0.0, 1.25, 3.6), (0.0, 0.95, 0.0), fov=38.0 * max(1.0, aspect / (4 / 3)))
    return sc
