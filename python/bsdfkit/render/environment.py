"""Environments of the preview renderer: the procedural lat-long maps (sky, studio, stripes) and
the normalisation of an ``envmap`` argument (a name, a file, an array or a constant)."""
from __future__ import annotations

import os

import numpy as np

from .. import _render_ext


#: Named environments: procedural ``"sky"`` (the default: sky gradient, ground and a sun-like
#: hot spot), ``"studio"`` (dark room with three soft boxes) and ``"white"`` (uniform radiance 1,
#: the white furnace).
ENVIRONMENTS = ("sky", "studio", "white")


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
    """Radiance of a procedural environment toward world directions. See :func:`default_environment`.

    Parameters
    ----------
    kind : {"sky", "studio"}
        The environment.
    directions : array_like, shape (..., 3)
        Unit directions in world space (y up).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        float64 radiance.
    """
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

    Parameters
    ----------
    kind : {"sky", "studio"}, optional
        ``"sky"``: blue zenith fading to a bright horizon, a dim brownish ground below the
        horizon and a sun-like hot spot (angular radius 2.5 degrees, radiance ~600, direction
        :data:`SUN_DIRECTION`) with a soft glow. ``"studio"``: a dark grey room lit by a large key
        soft box (front left, above), a fill (right) and a rim light (behind).
    width : int, optional
        Image width in pixels.

    Returns
    -------
    numpy.ndarray, shape (width // 2, width, 3)
        float32 linear radiance.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.render.default_environment("studio", width=64).shape
    (32, 64, 3)
    """
    if kind not in ("sky", "studio"):
        raise ValueError(f"kind: must be 'sky' or 'studio', got {kind!r}")
    width = int(width)
    if width < 8:
        raise ValueError("width: must be >= 8")
    env = procedural_environment(kind, _latlong_dirs(width, width // 2))
    return np.ascontiguousarray(env, dtype=np.float32)


def stripes_environment(width: int = 512) -> np.ndarray:
    """A dark lat-long environment with bright white stripes (12 vertical bars around the azimuth
    and two horizontal bands): sharp white edges for a glass to disperse into colour fringes.

    Parameters
    ----------
    width : int, optional
        Image width in pixels.

    Returns
    -------
    numpy.ndarray, shape (width // 2, width, 3)
        float32 linear radiance.
    """
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


def _read_env_file(path: str) -> np.ndarray:
    """Lat-long image from a file via OpenImageIO; errors name the file and give OIIO's reason."""
    try:
        img = _render_ext.load().read_image(path)
    except RuntimeError as e:
        if not os.path.exists(path):
            raise FileNotFoundError(f"envmap: cannot read environment map {e}") from None
        raise OSError(f"envmap: cannot read environment map {e}") from None
    if path.lower().endswith((".png", ".jpg", ".jpeg", ".bmp")):
        from ..io import srgb_to_linear
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
