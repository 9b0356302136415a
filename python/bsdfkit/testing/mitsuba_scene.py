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
  polynomials), one curve per segment. Rays leave a fibre of a surface material from its surface
  in both renderers; for hair models ours leave from the axis (the far-field hair model, see
  render/scene.h), Mitsuba's from the surface. Hair models map through
  ``Hair.to_mitsuba`` (Mitsuba derives h from wo and the tube normal: the same h as ours).
* Spheres -> ``sphere`` with its pole on +y (its tangent then runs along our parallels, so
  anisotropic materials line up); meshes -> a temporary PLY file loaded by the ``ply`` plugin.
* Spectral (``spectral=True``, for ``render(..., spectral=True)``; the process must already run
  a spectral variant, see :func:`render_spectral`, which renders in a child process so that the
  caller keeps the suite's one ``llvm_ad_rgb`` variant): each model's ``bk.Spectrum`` parameters
  (reflectances, eta, k) become Mitsuba ``spectrum`` dicts of the same nodes (piecewise linear in
  both; the end values are repeated at 360 and 830 nm, where bk.Spectrum clamps and Mitsuba's
  irregular spectrum would drop to 0); RGB parameters stay ``rgb`` (then Mitsuba uplifts them with
  its own table, pbrt-v4's table differs slightly). A dispersive dielectric has no Mitsuba
  counterpart (its ``int_ior`` is a scalar): NotImplementedError. The environment and the sun
  stay RGB: Mitsuba's spectral ``envmap`` and ``directional`` uplift them as illuminants (times
  D65), as the renderer does (an achromatic map uplifts to a constant spectrum in both).
* Materials -> :func:`bsdfkit.testing.mitsuba.to_mitsuba` (or ``bsdf_fn``). A checkerboard
  ground of two ``Diffuse`` models -> ``diffuse`` with a ``checkerboard`` texture on the
  rectangle's uv (same squares, possibly swapped colours: for benchmarks, not for pixel tests).
"""
from __future__ import annotations

import io
import os
import pickle
import subprocess
import sys
import tempfile

import numpy as np

from . import mitsuba as _ref

__all__ = ["mitsuba_envmap_image", "to_mitsuba_scene", "spectral_bsdf", "render_spectral", "SPECTRAL_VARIANT"]

#: The Mitsuba variant of :func:`render_spectral`.
SPECTRAL_VARIANT = "llvm_ad_spectral"


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


def _spectrum_param(spec):
    """A ``bk.Spectrum`` as a Mitsuba spectrum parameter: a float for a constant, else the
    irregular ``spectrum`` of its nodes with the end values repeated at 360 and 830 nm."""
    if spec.is_constant:
        return float(spec.values[0]) if spec.values is not None else float(spec(550.0))
    if spec.wavelengths is None:    # an analytic spectrum (uplifted RGB, blackbody): its 1 nm samples
        lam = np.arange(360.0, 831.0)
        val = np.asarray(spec(lam), dtype=np.float64)
    else:
        lam, val = np.asarray(spec.wavelengths, np.float64), np.asarray(spec.values, np.float64)
        if lam[0] > 360.0:
            lam, val = np.concatenate([[360.0], lam]), np.concatenate([[val[0]], val])
        if lam[-1] < 830.0:
            lam, val = np.concatenate([lam, [830.0]]), np.concatenate([val, [val[-1]]])
    return {"type": "spectrum", "value": [(float(a), float(b)) for a, b in zip(lam, val)]}


# Mitsuba parameter name -> bsdfkit attribute holding the same quantity.
_SPECTRAL_KEYS = {"reflectance": "reflectance", "eta": "eta", "k": "k", "diffuse_reflectance": "reflectance",
                  "specular_reflectance": "specular_reflectance", "transmittance": "transmittance"}


def spectral_bsdf(model) -> dict:
    """The Mitsuba BSDF dict of ``model`` for a spectral variant: :func:`bsdfkit.testing.mitsuba.to_mitsuba`'s
    dict with every parameter the model holds as a ``bk.Spectrum`` given as that spectrum (see the
    module docstring). Raises NotImplementedError for a dispersive dielectric."""
    from ..spectral.spectrum import Spectrum

    d = _ref.to_mitsuba(model)
    if isinstance(model, dict):
        return d
    eta = getattr(model, "eta", None)
    if isinstance(eta, Spectrum) and not eta.is_constant and _has_key(d, "int_ior"):
        raise NotImplementedError(f"{type(model).__name__}: a dispersive eta has no Mitsuba counterpart "
                                  "(its dielectrics take a scalar int_ior)")

    def walk(node):
        if isinstance(node, dict):
            out = {}
            for k, v in node.items():
                attr = _SPECTRAL_KEYS.get(k)
                val = getattr(model, attr, None) if attr else None
                out[k] = _spectrum_param(val) if isinstance(val, Spectrum) else walk(v)
            return out
        return node
    return walk(d)


def _has_key(node, key):
    return isinstance(node, dict) and (key in node or any(_has_key(v, key) for v in node.values()))


def render_spectral(scenes, *, seeds, width, height, spp, max_depth, envmap_bitmap=None, timeout=900.0):
    """Mitsuba's ``path`` integrator in ``llvm_ad_spectral`` on each of ``scenes`` (bsdfkit.render
    Scenes, exported by :func:`to_mitsuba_scene` with ``spectral=True``), one render per seed:
    a list of (len(seeds), height, width, 3) float64 linear sRGB arrays. ``envmap_bitmap``: an
    (H, W, 3) array given to Mitsuba's ``envmap`` instead of the scenes' environment (for images
    sampled on Mitsuba's own texel grid). All scenes render in ONE child process (``python -m
    bsdfkit.testing.mitsuba_scene``) that selects the spectral variant, so the caller's process
    keeps its variant; raises RuntimeError with the child's stderr if it fails."""
    payload = {"scenes": list(scenes), "seeds": [int(s) for s in seeds], "width": int(width), "height": int(height),
               "spp": int(spp), "max_depth": int(max_depth),
               "envmap": None if envmap_bitmap is None else np.ascontiguousarray(envmap_bitmap, np.float32)}
    from .llvm import configure_llvm_env
    env = dict(os.environ)
    path = configure_llvm_env()
    if path:
        env["DRJIT_LIBLLVM_PATH"] = path
    proc = subprocess.run([sys.executable, "-m", "bsdfkit.testing.mitsuba_scene"], input=pickle.dumps(payload),
                          capture_output=True, env=env, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"Mitsuba {SPECTRAL_VARIANT} child failed ({proc.returncode}):\n"
                           f"{proc.stderr.decode(errors='replace')[-4000:]}")
    data = np.load(io.BytesIO(proc.stdout))
    return [data[f"img{i}"] for i in range(len(payload["scenes"]))]


def _child():  # pragma: no cover - runs in the child process of render_spectral
    payload = pickle.loads(sys.stdin.buffer.read())
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(SPECTRAL_VARIANT)
    dr.set_flag(dr.JitFlag.FastMath, False)
    out = {}
    for i, sc in enumerate(payload["scenes"]):
        d = to_mitsuba_scene(sc, width=payload["width"], height=payload["height"], spp=payload["spp"],
                             max_depth=payload["max_depth"], spectral=True)
        if payload["envmap"] is not None:
            d["environment"] = {"type": "envmap", "bitmap": mi.Bitmap(payload["envmap"])}
        msc = mi.load_dict(d)
        out[f"img{i}"] = np.stack([np.array(mi.render(msc, seed=s, spp=payload["spp"]), dtype=np.float64)
                                   for s in payload["seeds"]])
    buf = io.BytesIO()
    np.savez(buf, **out)
    sys.stdout.buffer.write(buf.getvalue())
    sys.stdout.buffer.flush()


def to_mitsuba_scene(scene, *, width=256, height=256, spp=64, max_depth=8, envmap=None, rr_depth=None,
                     bsdf_fn=None, tmpdir=None, spectral=False) -> dict:
    """Mitsuba scene dictionary equivalent to ``bsdfkit.render.render(scene, width=..., ...)``.

    ``rr_depth``: Mitsuba's Russian-roulette start (default: Mitsuba's own, 5). ``bsdf_fn``:
    model -> Mitsuba BSDF dict (default :func:`bsdfkit.testing.mitsuba.to_mitsuba`, which
    raises for DiffuseTransmission; with ``spectral=True`` :func:`spectral_bsdf`). Meshes are
    written as PLY files into ``tmpdir`` (default: a new temporary directory, kept for the
    lifetime of the dict's use). ``spectral=True``: the dict of ``render(..., spectral=True)``
    for the spectral variant the process runs already (this function then selects none; see
    :func:`render_spectral`)."""
    if spectral:
        import mitsuba as mi
        if not mi.variant() or "spectral" not in mi.variant():
            raise RuntimeError(f"to_mitsuba_scene(spectral=True): the process runs Mitsuba variant "
                               f"{mi.variant()!r}; select a spectral one first (or use render_spectral)")
        bsdf_fn = bsdf_fn or spectral_bsdf
    else:
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


if __name__ == "__main__":  # pragma: no cover
    _child()
