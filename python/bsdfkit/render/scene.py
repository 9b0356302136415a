"""The scene description of the preview renderer (:class:`Scene`, :class:`Camera`), its argument
checks, meshes and fibres, and its translation into the compiled renderer's scene (RGB and
spectral mode)."""
from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass, field

import numpy as np

from .. import _render_ext
from .._arrays import _as_real_array, check_real
from ..models import _spectral as _spectral_forms
from .environment import _environment
from .._validate import check_int as _check_int  # noqa: F401  (scenes.py, trace.py)


#: Largest |coordinate| of the camera's origin, target and up, and of the scene's geometry
#: (sphere centres +- radii, mesh vertices, fibre points, the ground): the renderer takes them as
#: float32 and squares target - origin and forward x up there (cpp/bindings/render.cpp
#: render_impl, render/camera.h look_at); within 1e18 those squares (<= 12e36) stay below
#: float32's max 3.4e38, where beyond it they overflowed and the camera failed as "up: must not
#: be parallel to the view direction".
CAMERA_MAX_COORD = 1e18


@dataclass
class Camera:
    """Pinhole camera: position, look-at point, up hint and full horizontal field of view.

    Checked when the camera is used (``render``, ``project``, ``Scene.look_at``): ValueError naming
    the field.

    Parameters
    ----------
    origin, target, up : tuple of 3 float, optional
        3 finite numbers each, within +-``CAMERA_MAX_COORD`` (1e18: the renderer works in
        float32); target must differ from origin (in float32) and up must not be (nearly) zero or
        parallel to the view direction.
    fov : float, optional
        Full horizontal field of view in degrees, in (0, 180).
    """
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


def is_compiled(model) -> bool:
    """True for a model whose code is compiled (the renderer shades those only); False for the
    Python ones (``bk.Mix``, ``bk.TwoSided``, ``bk.Mask``, ``bk.NormalMap``, ``bk.BumpMap``, ``bk.Custom``)."""
    return type(getattr(model, "_core", None)).__module__.startswith("bsdfkit._core")


def _model_check(material, name="material"):
    if hasattr(material, "textures") and hasattr(material, "model_class"):   # bsdfkit.models.textured
        raise NotImplementedError(
            f"{name}: the preview renderer does not look textures up yet ({material.describe()}); render the "
            "material at one texel, material.at([u, v])")
    core = getattr(material, "_core", None)
    if core is None:
        raise TypeError(f"{name}: expected a bsdfkit model (e.g. bk.Diffuse(0.8)), got {type(material).__name__}")
    if not is_compiled(material):
        # a Python-implemented model (bk.Mix, bk.TwoSided, bk.Mask, bk.NormalMap, bk.BumpMap, bk.Custom): the
        # renderer's per-bounce shading runs compiled model code only
        raise TypeError(f"{name}: {type(material).__name__} ({material.describe()}) is implemented in Python and the "
                        "preview renderer takes compiled models only (e.g. bk.Diffuse, bk.Conductor); render one of "
                        "its children, or evaluate it with eval / sample")
    if getattr(material, "varying", ()):
        # per-element parameters follow the call's elements, which a surface has no order of
        raise NotImplementedError(f"{name}: {type(material).__name__} with per-element parameters "
                                  f"({', '.join(material.varying)}) has no one material to render yet (textures "
                                  "on surfaces are to come); render a uniform model")
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


def load_mesh(path):
    """Triangle mesh from a file (OBJ, PLY, STL, glTF, ... via Assimp). Every mesh of the file is
    merged and triangulated.

    Parameters
    ----------
    path : str or os.PathLike
        The mesh file.

    Returns
    -------
    vertices : numpy.ndarray, shape (N, 3)
        float32 positions.
    indices : numpy.ndarray, shape (M, 3)
        int64 triangle vertex indices.

    Raises
    ------
    FileNotFoundError
        A missing file.
    ValueError
        An unreadable file, naming it with Assimp's reason.
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(f"path: no such mesh file: {path}")
    try:
        return _render_ext.load().load_mesh(path)
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


@dataclass
class Scene:
    """Objects, materials, lighting and camera of a render. Build with the ``add_*`` methods (each
    returns the scene, so calls chain) and pass to :func:`render` / :func:`preview`.

    Parameters
    ----------
    environment : str, path, array_like or float, optional
        ``"sky"`` (default), ``"studio"``, ``"white"``, a path to a lat-long EXR/HDR/PNG, an
        (H, W, 3) radiance array, or a constant radiance (number or RGB).
    camera : Camera, optional
        The camera (default: ``Camera()``).
    objects, lights : list, optional
        Usually left empty and filled by the ``add_*`` methods.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> scene = bk.render.Scene(environment="white").add_sphere(bk.Diffuse(0.5))
    >>> img = bk.render.render(scene, width=16, height=16, spp=2, progress=False)
    >>> img.shape, img.dtype.name
    ((16, 16, 3), 'float32')
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
        from ..models import Diffuse
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
        s = _render_ext.load().RenderScene()
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


#: Models the spectral renderer accepts: those with a spectral form, read from ``_core`` (the
#: renderer's spectral material is the variant over every model's form, bxdfs/all.h).
SPECTRAL_MODELS = tuple(c.__name__ for c in _spectral_forms.spectral_classes())


@functools.lru_cache(maxsize=1)
def _spectral_tables():
    """The colour tables of the spectral tracer: D65 of unit luminance on its 5 nm table (as
    ``bk.spectrum_to_rgb(illuminant="D65")``) and XYZ_TO_SRGB @ cmf / integral(y-bar) on the
    1 nm CMF table (``bk.spectrum_to_rgb``'s weights), both linear between nodes."""
    from ..spectral import colorimetry
    w5, _, d, w1, c1 = colorimetry._tables()
    d65_unit = np.ascontiguousarray(d * colorimetry._grid("pbrt")[4], dtype=np.float64)
    match = np.ascontiguousarray(c1 @ colorimetry.XYZ_TO_SRGB.T / colorimetry.cie_y_integral(), dtype=np.float64)
    return d65_unit, float(w5[0]), float(w5[1] - w5[0]), match, float(w1[0]), float(w1[1] - w1[0])


def _uplift_illuminant(rgb, exact):
    """(..., 4) = (c0, c1, c2, scale) of RGB radiance uplifted as pbrt-v4's RGBIlluminantSpectrum
    (the D65 factor is applied by the tracer)."""
    from ..spectral import uplift
    c, scale = uplift.rgb_coefficients(np.asarray(rgb, dtype=np.float64), "illuminant", exact=exact)
    return np.ascontiguousarray(np.concatenate([c, np.asarray(scale)[..., None]], axis=-1), dtype=np.float64)


def _set_spectral(s, materials, env_kind, env_val, lights):
    """Spectral mode of a C++ scene: each material's spectral model (its ``_core.<Model>Spectral``,
    the same kernels as ``model.eval(..., wavelengths=...)``), the colour tables and the lights
    uplifted to illuminant spectra: a constant environment and the directional light with the
    polished fit (``exact=True``, as model parameters), a lat-long image per texel with the
    table lookup (pbrt-v4's ``RGBToSpectrumTable`` as is)."""
    from ..models import _spectral
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
