"""A :class:`bsdfkit.render.Scene` as a Mitsuba 3 scene, for cross-checking and benchmarking
the preview renderer against Mitsuba's ``path`` integrator (``llvm_ad_rgb``).

What maps to what
-----------------
* Camera: ``perspective`` sensor, ``fov`` on the x axis (Mitsuba's default ``fov_axis``),
  ``to_world = look_at(origin, target, up)``; ``hdrfilm`` with a **box** reconstruction filter
  (Mitsuba's default is Gaussian; ours is a box) and the ``independent`` sampler.
* ``max_depth``: Mitsuba counts path vertices, we count scattering events, so Mitsuba's value
  is ours + 1 (ours 0 -> 1: only emitters seen directly; ours 1 -> 2: direct lighting).
* Environment: ``envmap`` with the identity ``to_world``: Mitsuba's lat-long mapping is the one
  the renderer uses (``d = (sin phi sin theta, cos theta, -cos phi sin theta)``). Mitsuba 3.9.1
  places the pixel values at u = (x + 0.5) / W like us, but at v = y / (H - 1) (rows on the
  poles) where we use (y + 0.5) / H; so the Mitsuba bitmap is resampled at Mitsuba's rows:
  procedural environments are re-evaluated exactly there, images are linearly interpolated
  between our rows. A constant environment becomes the ``constant`` emitter.
* Directional light -> ``directional`` (Mitsuba's ``direction`` is the propagation direction,
  the opposite of ours).
* Fibres (``Scene.add_curves``: Embree round Catmull-Rom curves) -> ``bsplinecurve``: each
  Catmull-Rom segment is rewritten exactly as a 4-point cubic B-spline (same position and radius
  polynomials), one curve per segment. Our rays leave a fibre from its axis, Mitsuba's from the
  surface, so shadows differ at the scale of the fibre radius. Hair models map through
  ``Hair.to_mitsuba`` (Mitsuba derives h from wo and the tube normal: the same h as ours).
* Spheres -> ``sphere`` with its pole on +y (its tangent then runs along our parallels, so
  anisotropic materials line up); meshes -> a temporary PLY file loaded by the ``ply`` plugin.
* Materials -> :func:`bsdfkit.testing.mitsuba.to_mitsuba` (or ``bsdf_fn``). A checkerboard
  ground of two ``Diffuse`` models -> ``diffuse`` with a ``checkerboard`` texture on the
  rectangle's uv (same squares, possibly swapped colours: for benchmarks, not for pixel tests).
"""
from __future__ import annotations

import os
import tempfile

import numpy as np

from . import mitsuba as _ref

__all__ = ["mitsuba_envmap_image", "to_mitsuba_scene"]


def mitsuba_envmap_image(env, height=None, width=None) -> np.ndarray:
    """The float32 (H, W, 3) bitmap that makes Mitsuba's ``envmap`` show the environment the
    renderer shows for the spec ``env`` (a name, path, array; see ``bsdfkit.render``).
    Procedural environments are evaluated at Mitsuba's sample positions ((x + 0.5) / W, y / (H - 1));
    images are resampled there with the renderer's own bilinear rule. Returns None for a
    constant environment."""
    from .. import render as R

    if isinstance(env, str) and env.lower() in ("sky", "default", "studio"):
        kind = "studio" if env.lower() == "studio" else "sky"
        w = width or R.DEFAULT_ENV_WIDTH
        h = height or w // 2
        u = (np.arange(w) + 0.5) / w
        v = np.arange(h) / (h - 1)
        phi, theta = np.meshgrid(2 * np.pi * u, np.pi * v)
        st = np.sin(theta)
        d = np.stack([np.sin(phi) * st, np.cos(theta), -np.cos(phi) * st], axis=-1)
        return np.ascontiguousarray(R.procedural_environment(kind, d), dtype=np.float32)
    kind, val = R._environment(env)
    if kind == "constant":
        return None
    img = np.asarray(val, dtype=np.float64)
    h, w = img.shape[:2]
    # our rows sit at (y + 0.5) / h; Mitsuba's at y / (h - 1): interpolate ours there
    py = np.arange(h) / (h - 1) * h - 0.5 if h > 1 else np.zeros(1)
    y0 = np.floor(py).astype(int)
    t = (py - y0)[:, None, None]
    a = img[np.clip(y0, 0, h - 1)]
    b = img[np.clip(y0 + 1, 0, h - 1)]
    return np.ascontiguousarray((1 - t) * a + t * b, dtype=np.float32)


def _write_ply(path, v, i):
    v = np.ascontiguousarray(v, dtype="<f4")
    i = np.ascontiguousarray(i, dtype="<i4")
    with open(path, "wb") as fh:
        fh.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\n"
                  "property float x\nproperty float y\nproperty float z\n"
                  f"element face {len(i)}\nproperty list uchar int vertex_indices\nend_header\n").encode())
        rec = np.empty(len(i), dtype=[("n", "u1"), ("i", "<i4", (3,))])
        rec["n"] = 3
        rec["i"] = i
        fh.write(v.tobytes())
        fh.write(rec.tobytes())


# Uniform Catmull-Rom and uniform cubic B-spline segments in the power basis [1, t, t^2, t^3]
# (Catmull & Rom 1974; de Boor): C(t) = T M P for 4 control points P.
_M_CATMULL_ROM = 0.5 * np.array([[0, 2, 0, 0], [-1, 0, 1, 0], [2, -5, 4, -1], [-1, 3, -3, 1]], dtype=np.float64)
_M_BSPLINE = np.array([[1, 4, 1, 0], [-3, 0, 3, 0], [3, -6, 3, 0], [-1, 3, -3, 1]], dtype=np.float64) / 6
# B = M_bspline^-1 M_catmull_rom: the B-spline control points of the same cubic (position and radius)
_CATMULL_ROM_TO_BSPLINE = np.linalg.solve(_M_BSPLINE, _M_CATMULL_ROM)


def _write_bspline_curves(path, points, segments):
    """Mitsuba's ``bsplinecurve`` text file ("x y z radius" per control point, a blank line between
    curves) holding the renderer's Catmull-Rom segments exactly: each segment (control points
    i .. i+3 of ``points``, an (N, 4) array of x, y, z, r) becomes one 4-point B-spline curve with
    the same cubic position and radius, so both renderers trace the same swept surface."""
    idx = segments[:, None] + np.arange(4)
    b = np.einsum("ij,sjk->sik", _CATMULL_ROM_TO_BSPLINE, points[idx])   # (S, 4, 4)
    with open(path, "w") as fh:
        for seg in b:
            fh.write("\n".join(" ".join(repr(float(x)) for x in row) for row in seg))
            fh.write("\n\n")


def _rgb(v):
    a = np.broadcast_to(np.asarray(v, dtype=np.float64), (3,))
    return {"type": "rgb", "value": [float(x) for x in a]}


def to_mitsuba_scene(scene, *, width=256, height=256, spp=64, max_depth=8, envmap=None, rr_depth=None,
                     bsdf_fn=None, tmpdir=None) -> dict:
    """Mitsuba scene dictionary equivalent to ``bsdfkit.render.render(scene, width=..., ...)``.

    ``rr_depth``: Mitsuba's Russian-roulette start (default: Mitsuba's own, 5). ``bsdf_fn``:
    model -> Mitsuba BSDF dict (default :func:`bsdfkit.testing.mitsuba.to_mitsuba`, which
    raises for DiffuseTransmission). Meshes are written as PLY files into ``tmpdir`` (default: a
    new temporary directory, kept for the lifetime of the dict's use)."""
    _ref.variant()
    import mitsuba as mi

    bsdf_fn = bsdf_fn or _ref.to_mitsuba
    o, t, u, fov = scene.camera._checked()
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(max_depth) + 1},
        "sensor": {"type": "perspective", "fov": float(fov), "fov_axis": "x",
                   "to_world": mi.ScalarTransform4f().look_at(origin=o, target=t, up=u),
                   "film": {"type": "hdrfilm", "width": int(width), "height": int(height),
                            "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": int(spp)}},
    }
    if rr_depth is not None:
        d["integrator"]["rr_depth"] = int(rr_depth)
    env = scene.environment if envmap is None else envmap
    bmp = mitsuba_envmap_image(env)
    if bmp is None:
        from .. import render as R
        d["environment"] = {"type": "constant", "radiance": _rgb(R._environment(env)[1])}
    else:
        d["environment"] = {"type": "envmap", "bitmap": mi.Bitmap(bmp)}
    for k, light in enumerate(scene.lights):
        d[f"sun{k}"] = {"type": "directional", "direction": (-light["direction"]).tolist(),
                        "irradiance": _rgb(light["irradiance"])}
    tmp = None
    for k, ob in enumerate(scene.objects):
        if ob.get("checker") is not None:
            a, b = ob["material"], ob["checker"]
            if type(a).__name__ != "Diffuse" or type(b).__name__ != "Diffuse":
                raise NotImplementedError("a checkerboard of non-Diffuse models has no Mitsuba counterpart here")
            v = ob["vertices"]
            lo, hi = v.min(axis=0), v.max(axis=0)
            size = float(hi[0] - lo[0])
            reps = size / ob["checker_size"] / 2   # Mitsuba's checkerboard: 2 x 2 squares per unit uv
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
                "type": "checkerboard", "color0": _rgb(a.reflectance), "color1": _rgb(b.reflectance),
                "to_uv": mi.ScalarTransform4f().scale([reps, reps, 1])}}}
            # rectangle: [-1, 1]^2 in its xy plane, normal +z; rotate to normal +y, scale, lift
            d[f"obj{k}"] = {"type": "rectangle", "bsdf": bsdf,
                            "to_world": mi.ScalarTransform4f().translate([float((lo[0] + hi[0]) / 2), float(lo[1]),
                                                                          float((lo[2] + hi[2]) / 2)])
                            @ mi.ScalarTransform4f().rotate([1, 0, 0], -90)
                            @ mi.ScalarTransform4f().scale([size / 2, size / 2, 1])}
            continue
        bsdf = bsdf_fn(ob["material"])
        if ob["kind"] == "curves":
            if tmp is None:
                tmp = tmpdir or tempfile.mkdtemp(prefix="bsdfkit-mi-")
            path = os.path.join(tmp, f"curves{k}.txt")
            _write_bspline_curves(path, ob["points"], ob["segments"])
            d[f"obj{k}"] = {"type": "bsplinecurve", "filename": path, "bsdf": bsdf}
            continue
        if ob["kind"] == "sphere":
            # pole on +y so that Mitsuba's dp/du (along the parallels) is our tangent (negated,
            # which rotates the frame by 180 degrees about n: same anisotropic GGX)
            c, r = ob["center"].tolist(), float(ob["radius"])
            d[f"obj{k}"] = {"type": "sphere", "bsdf": bsdf,
                            "to_world": mi.ScalarTransform4f().translate(c) @ mi.ScalarTransform4f().rotate([1, 0, 0], -90)
                            @ mi.ScalarTransform4f().scale(r)}
        else:
            if tmp is None:
                tmp = tmpdir or tempfile.mkdtemp(prefix="bsdfkit-mi-")
            path = os.path.join(tmp, f"mesh{k}.ply")
            _write_ply(path, ob["vertices"], ob["indices"])
            d[f"obj{k}"] = {"type": "ply", "filename": path, "face_normals": True, "bsdf": bsdf}
    return d
