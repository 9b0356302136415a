"""Preview renderer (bsdfkit.render): white furnace, environment sampling, determinism, meshes,
lights, max_depth semantics, bad input, Ctrl-C and the command line.

Images are small (<= 48 x 48) so the file runs in a few seconds on 2 cores."""
import math
import os
import signal
import threading
import time
import warnings

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import _render
from bsdfkit import render as R
from bsdfkit.io import read_image, write_image

LUM = np.array([0.2126, 0.7152, 0.0722])


# ---------------------------------------------------------------- helpers

FURNACE_CAM = dict(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0), fov=34.0)


def furnace_scene(model, env="white"):
    return R.Scene(environment=env).add_sphere(model, center=(0, 0, 0), radius=1.0).look_at(**FURNACE_CAM)


def pixel_rays(res, origin, target, fov, up=(0.0, 1.0, 0.0)):
    """Pixel-centre ray directions (res, res, 3) of the renderer's camera (same formula)."""
    o, t, u = (np.asarray(x, float) for x in (origin, target, up))
    f = (t - o) / np.linalg.norm(t - o)
    r = np.cross(f, u)
    r /= np.linalg.norm(r)
    up2 = np.cross(r, f)
    th = math.tan(math.radians(fov) / 2)
    c = (np.arange(res) + 0.5) / res
    sx = (2 * c - 1) * th
    sy = (1 - 2 * c) * th
    d = f + sx[None, :, None] * r + sy[:, None, None] * up2
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def sphere_cos(res, margin_deg=0.0):
    """cos(theta_o) at the unit sphere hit of each pixel-centre ray of FURNACE_CAM (nan: miss)."""
    d = pixel_rays(res, **FURNACE_CAM)
    o = np.array(FURNACE_CAM["origin"])
    b = d @ o
    disc = b * b - (o @ o - 1.0)
    t = -b - np.sqrt(np.where(disc > 0, disc, np.nan))
    p = o + t[..., None] * d
    return np.einsum("ijk,ijk->ij", p, -d)


def renders(scene, seeds, **kw):
    kw.setdefault("progress", False)
    return np.stack([R.render(scene, seed=s, **kw) for s in seeds])


# ---------------------------------------------------------------- white furnace

F_ONE = dict(eta=1.0, k=1000.0)   # FrComplex = 1 - O(1e-5): a lossless conductor

# name -> (model, kind): "exact" every path returns exactly 1; "lossless" expectation 1;
# "albedo" expectation = directional albedo at the pixel's theta_o (rough microfacet models lose
# the energy of multiple scattering, and a convex object sees the environment after one bounce).
FURNACE = {
    "diffuse_1": (lambda: bk.Diffuse(1.0), "lossless"),
    "difftrans_lossless": (lambda: bk.DiffuseTransmission(0.5, 0.5), "lossless"),
    "dielectric_smooth": (lambda: bk.Dielectric(1.5), "exact"),
    "dielectric_inverted": (lambda: bk.Dielectric(1 / 1.33), "exact"),
    "thin_dielectric": (lambda: bk.ThinDielectric(1.5), "exact"),
    "conductor_smooth_F1": (lambda: bk.Conductor(**F_ONE), "exact"),
    "conductor_rough_F1": (lambda: bk.Conductor(alpha=0.3, **F_ONE), "albedo"),
    "conductor_rough_F1_separable": (lambda: bk.Conductor(alpha=0.5, masking="separable", **F_ONE), "albedo"),
    "conductor_cu_rough": (lambda: bk.Conductor.from_metal("Cu", alpha=0.3), "albedo"),
    "diffuse_absorbing": (lambda: bk.Diffuse(0.5), "albedo"),
    # stochastic layered model: sample() has pdf_is_proportional, MIS asks pdf() (an approximate
    # density); a white base under a smooth coat with a non-absorbing medium loses nothing
    "coated_diffuse_lossless": (lambda: bk.CoatedDiffuse(1.0, albedo=1.0, thickness=0.1, max_depth=100), "lossless"),
}
FURNACE_RES, FURNACE_SPP, FURNACE_SEEDS = 32, 64, (0, 1, 2, 3)


@pytest.mark.parametrize("name", sorted(FURNACE))
def test_white_furnace(name):
    """Uniform environment of radiance 1, a sphere, max_depth 64: every lossless material
    vanishes (pixels = 1 within the noise of the spp); lossy ones match their albedo."""
    make, kind = FURNACE[name]
    m = make()
    imgs = renders(furnace_scene(m), FURNACE_SEEDS, width=FURNACE_RES, height=FURNACE_RES, spp=FURNACE_SPP,
                   max_depth=64)
    mean = imgs.mean(axis=0)
    cos_o = sphere_cos(FURNACE_RES)
    inside = np.nan_to_num(cos_o) > 0.5          # pixel footprint well inside the silhouette
    assert np.all(np.isfinite(imgs))
    if kind == "exact":
        np.testing.assert_allclose(imgs, 1.0, atol=2e-5)
        return
    if kind == "lossless":
        expected = np.ones_like(mean)
    else:
        ct = np.clip(cos_o[inside], 0.0, 1.0)
        wo = np.stack([np.sqrt(1 - ct * ct), np.zeros_like(ct), ct], -1)
        expected = np.ones_like(mean)
        expected[inside] = m.albedo(wo, n_samples=1 << 15, seed=7)
    # noise bound from the spread of the independent seeds (standard error of the 4-seed mean)
    se = imgs.std(axis=0, ddof=1) / math.sqrt(len(FURNACE_SEEDS))
    err = (mean - expected)[inside]
    se_in = se[inside]
    se_of_mean = math.sqrt(np.sum(se_in ** 2)) / se_in.size
    tol_sys = 2e-3 if kind == "albedo" else 0.0   # MC error of the albedo reference (2^15 samples)
    assert abs(err.mean()) < 5 * se_of_mean + tol_sys, (err.mean(), se_of_mean)
    # per pixel: |error| of order of the pixel noise (mean |N(0, se)| = 0.8 se)
    assert np.mean(np.abs(err)) < 1.6 * np.mean(se_in) + tol_sys, (np.mean(np.abs(err)), np.mean(se_in))
    if name in ("diffuse_absorbing", "conductor_cu_rough"):
        assert mean[inside].mean() < 0.9          # absorbing materials are darker than the furnace


def test_furnace_lossless_images_vanish_into_background():
    """The whole frame of a lossless sphere is the uniform background: mean |pixel - 1| is at
    the noise level (printed for the record) and far below an absorbing sphere's."""
    scene = furnace_scene(bk.Diffuse(1.0))
    img = R.render(scene, width=FURNACE_RES, height=FURNACE_RES, spp=256, max_depth=64, progress=False)
    dark = R.render(furnace_scene(bk.Diffuse(0.8)), width=FURNACE_RES, height=FURNACE_RES, spp=256, max_depth=64,
                    progress=False)
    e1, e2 = np.abs(img - 1).mean(), np.abs(dark - 1).mean()
    print(f"furnace Diffuse(1): mean|p-1| = {e1:.4f}; Diffuse(0.8): {e2:.4f}")
    assert e1 < 0.02 and e2 > 5 * e1


# ---------------------------------------------------------------- environment map sampling

def env_image(h=24, w=48, seed=3):
    rng = np.random.default_rng(seed)
    img = rng.gamma(0.5, 1.0, size=(h, w, 3)).astype(np.float32)
    img[5, 7] = [200, 150, 100]          # a hot spot
    img[:, 30:33] = 0.0                  # a black band: no samples there
    return img


def sampler_weights(img):
    """Cell weights the sampler must follow: luminance of the bilinear interpolant averaged
    over each pixel cell (stencil 1/8, 3/4, 1/8; periodic in u, clamped in v) times sin(theta)."""
    lum = img.astype(np.float64) @ LUM
    w8 = (0.125, 0.75, 0.125)
    h, w = lum.shape
    f = np.zeros_like(lum)
    for dy, wy in zip((-1, 0, 1), w8):
        rows = np.clip(np.arange(h) + dy, 0, h - 1)
        for dx, wx in zip((-1, 0, 1), w8):
            f += wy * wx * np.roll(lum[rows], -dx, axis=1)
    return f * np.sin(np.pi * (np.arange(h) + 0.5) / h)[:, None]


def uv_of(d):
    u = np.arctan2(d[:, 0], -d[:, 2]) / (2 * np.pi)
    u = np.where(u < 0, u + 1, u)
    v = np.arccos(np.clip(d[:, 1], -1, 1)) / np.pi
    return u, v


def test_env_sampling_chi2_matches_luminance_distribution():
    import scipy.stats as scipy_stats
    img = env_image()
    h, w = img.shape[:2]
    s = _render.RenderScene()
    s.set_environment_latlong(img)
    n = 400_000
    rng = np.random.default_rng(11)
    wi, pdf, L = s.env_sample(rng.random((n, 2)))
    assert np.all(np.isfinite(wi)) and np.all(pdf > 0)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-5)
    u, v = uv_of(wi.astype(np.float64))
    cx = np.clip((u * w).astype(int), 0, w - 1)
    cy = np.clip((v * h).astype(int), 0, h - 1)
    counts = np.bincount(cy * w + cx, minlength=h * w).astype(float)
    weights = sampler_weights(img).ravel()
    expected = weights / weights.sum() * n
    assert counts[expected == 0].sum() == 0          # never samples where the map is black
    keep = expected >= 5
    obs, exp = counts[keep], expected[keep]
    # pool the low-expectation cells into one bin
    obs = np.append(obs, counts[~keep].sum())
    exp = np.append(exp, expected[~keep].sum())
    exp *= obs.sum() / exp.sum()
    chi2, p = scipy_stats.chisquare(obs, exp)
    assert p > 1e-3, (chi2, p, len(obs))
    # the returned pdf is the density of that distribution in solid angle
    pmf = weights / weights.sum()
    w64 = wi.astype(np.float64)
    st = np.hypot(w64[:, 0], w64[:, 2])
    pdf_expected = pmf[cy * w + cx] * w * h / (2 * np.pi ** 2 * st)
    close = np.isclose(pdf, pdf_expected, rtol=2e-3)
    assert close.mean() > 0.9999     # a few directions on a cell border round into the neighbour
    # and pdf(wi) of the evaluation path agrees with the sampling path; L = eval(wi)
    pdf2, L2 = s.env_eval_pdf(wi)
    assert np.isclose(pdf2, pdf, rtol=1e-3).mean() > 0.9999
    np.testing.assert_allclose(L2, L, rtol=5e-3, atol=1e-5)   # uv from the direction vs the sampled uv


def test_env_pdf_integrates_to_one_and_bilinear_lookup():
    img = env_image()
    s = _render.RenderScene()
    s.set_environment_latlong(img)
    # integrate pdf over the sphere on a fine (u, v) grid: dw = 2 pi^2 sin(theta) du dv
    nu, nv = 960, 480
    u = (np.arange(nu) + 0.5) / nu
    v = (np.arange(nv) + 0.5) / nv
    phi, th = np.meshgrid(2 * np.pi * u, np.pi * v)
    d = np.stack([np.sin(phi) * np.sin(th), np.cos(th), -np.cos(phi) * np.sin(th)], -1).reshape(-1, 3)
    pdf, L = s.env_eval_pdf(d.astype(np.float32))
    integral = np.sum(pdf * np.sin(th).ravel()) * 2 * np.pi ** 2 / (nu * nv)
    assert abs(integral - 1) < 2e-3, integral
    # radiance at pixel centres is the pixel value (bilinear interpolation between centres)
    h, w = img.shape[:2]
    uu = (np.arange(w) + 0.5) / w
    vv = (np.arange(h) + 0.5) / h
    phi, th = np.meshgrid(2 * np.pi * uu, np.pi * vv)
    d = np.stack([np.sin(phi) * np.sin(th), np.cos(th), -np.cos(phi) * np.sin(th)], -1).reshape(-1, 3)
    _, L = s.env_eval_pdf(d.astype(np.float32))
    np.testing.assert_allclose(L.reshape(h, w, 3), img, rtol=1e-3, atol=1e-4)


def test_env_orientation_convention():
    """Centre of the lat-long image looks along +z, a quarter of the width along +x, row 0 is +y."""
    h, w = 16, 32
    img = np.zeros((h, w, 3), np.float32)
    img[h // 2, w // 2 - 1: w // 2 + 1] = [1, 0, 0]   # u = 0.5 (between these centres) -> +z
    img[h // 2, w // 4 - 1: w // 4 + 1] = [0, 1, 0]   # u = 0.25 -> +x
    img[0, :] = [0, 0, 1]                 # top row -> +y
    s = _render.RenderScene()
    s.set_environment_latlong(img)
    v = (h // 2 + 0.5) / h
    st, ct = math.sin(math.pi * v), math.cos(math.pi * v)
    _, L = s.env_eval_pdf(np.array([[0, ct, st], [st, ct, 0], [0, 1, 0], [0, ct, -st]], np.float32))
    np.testing.assert_allclose(L, [[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]], atol=1e-5)


# ---------------------------------------------------------------- determinism, API

def test_preview_shape_dtype_and_finite():
    img = R.preview(bk.Conductor.from_metal("Au", alpha=0.2), width=24, height=16, spp=2, progress=False)
    assert img.shape == (16, 24, 3) and img.dtype == np.float32
    assert np.all(np.isfinite(img)) and np.all(img >= 0) and img.mean() > 0.05


def test_deterministic_for_any_thread_count_and_pass_split():
    scene = R.default_scene(bk.Dielectric(1.5, alpha=0.2))
    old = bk.get_num_threads()
    try:
        bk.set_num_threads(1)
        a = R.render(scene, width=40, height=24, spp=6, seed=5, progress=False)
        bk.set_num_threads(2)
        b = R.render(scene, width=40, height=24, spp=6, seed=5, progress=False)
    finally:
        bk.set_num_threads(old)
    assert np.array_equal(a, b)
    # the same samples added in two passes (2 + 4) give the same bits as one pass of 6
    core = scene._build()
    o, t, u, fov = scene.camera._checked()
    acc1 = np.zeros((24, 40, 3))
    core.render(o, t, u, fov, 8, 5, 0, 6, acc1)
    acc2 = np.zeros((24, 40, 3))
    core.render(o, t, u, fov, 8, 5, 0, 2, acc2)
    core.render(o, t, u, fov, 8, 5, 2, 6, acc2)
    assert np.array_equal(acc1, acc2)
    assert np.array_equal((acc1 / 6).astype(np.float32), a)
    c = R.render(scene, width=40, height=24, spp=6, seed=6, progress=False)
    assert not np.array_equal(a, c)


def test_directional_light_exact_irradiance():
    """A Diffuse plane under a black sky lit by a directional light: L = rho/pi E cos(theta)."""
    rho, E, th = 0.7, 2.5, math.radians(35)
    sc = R.Scene(environment=0.0)
    sc.add_ground(bk.Diffuse(rho), size=50.0)
    sc.add_directional_light((math.sin(th), math.cos(th), 0.0), E)
    sc.look_at((0, 3, 3), (0, 0, 0), fov=40)
    img = R.render(sc, width=16, height=16, spp=4, progress=False)
    np.testing.assert_allclose(img, rho / math.pi * E * math.cos(th), rtol=1e-5)
    # a sphere casts a shadow: the pixel straight below it is black
    sc.add_sphere(bk.Diffuse(0.5), center=(0, 1.0, 0), radius=0.5)
    sc.lights.clear()
    sc.add_directional_light((0, 1, 0), E)
    sc.look_at((2, 0.3, 0), (0, 0.0, 0), fov=6)
    img = R.render(sc, width=16, height=16, spp=4, max_depth=1, progress=False)   # direct light only
    assert img[7:9, 7:9].max() == 0.0 and img.max() > 0.5


def test_max_depth_semantics():
    """0: only the environment (objects are black); 1: direct lighting, so a Diffuse(1) sphere in
    the furnace is already 1 and a smooth dielectric shows only its first reflection."""
    res = 24
    inside = np.nan_to_num(sphere_cos(res)) > 0.5
    img0 = R.render(furnace_scene(bk.Diffuse(1.0)), width=res, height=res, spp=4, max_depth=0, progress=False)
    assert np.all(img0[inside] == 0) and np.all(img0[[0, 0, -1, -1], [0, -1, 0, -1]] == 1)
    img1 = renders(furnace_scene(bk.Diffuse(1.0)), (0, 1), width=res, height=res, spp=64, max_depth=1).mean(0)
    assert abs(img1[inside].mean() - 1) < 0.01
    imgs = renders(furnace_scene(bk.Dielectric(1.5)), (0, 1, 2, 3), width=res, height=res, spp=256, max_depth=1)
    ct = sphere_cos(res)[inside]
    s2 = (1 - ct ** 2) / 1.5 ** 2
    c_t = np.sqrt(1 - s2)
    fr = ((ct - 1.5 * c_t) / (ct + 1.5 * c_t)) ** 2 / 2 + ((1.5 * ct - c_t) / (1.5 * ct + c_t)) ** 2 / 2
    got = imgs.mean(0)[inside][:, 0]
    se = imgs.std(0, ddof=1)[inside][:, 0] / 2
    assert abs(np.mean(got - fr)) < 5 * math.sqrt(np.sum(se ** 2)) / se.size + 1e-3


# ---------------------------------------------------------------- meshes

def icosphere(subdiv=2):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdiv):
        cache, nf = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                cache[key] = len(v) - 1
            return cache[key]
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return np.array(v), np.array(f)


def test_mesh_outward_normals_and_furnace():
    v, f = icosphere(2)
    # counter-clockwise seen from outside: the geometric normal points away from the centre
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    assert np.all(np.einsum("ij,ij->i", n, v[f].mean(axis=1)) > 0)
    sc = R.Scene(environment="white").add_mesh(bk.Dielectric(1.5), v, f).look_at(**FURNACE_CAM)
    img = R.render(sc, width=24, height=24, spp=8, max_depth=200, progress=False)
    # a closed lossless dielectric polyhedron: every escaping path carries exactly 1
    assert np.mean(np.abs(img - 1) < 1e-4) > 0.98
    sc = R.Scene(environment="white").add_mesh(bk.Diffuse(0.5), v, f).look_at(**FURNACE_CAM)
    img = R.render(sc, width=24, height=24, spp=64, progress=False)
    inside = np.nan_to_num(sphere_cos(24)) > 0.6
    assert abs(img[inside].mean() - 0.5) < 0.01


def write_obj(path, v, f):
    with open(path, "w") as fh:
        fh.write("# icosphere\n")
        for p in v:
            fh.write(f"v {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}\n")
        for t in f + 1:
            fh.write(f"f {t[0]} {t[1]} {t[2]}\n")


def write_ply(path, v, f, binary):
    header = (f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\nelement vertex {len(v)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as fh:
        fh.write(header.encode())
        if binary:
            fh.write(np.asarray(v, "<f4").tobytes())
            rec = np.empty(len(f), dtype=[("n", "u1"), ("i", "<i4", (3,))])
            rec["n"], rec["i"] = 3, f
            fh.write(rec.tobytes())
        else:
            for p in v:
                fh.write(f"{p[0]:.9g} {p[1]:.9g} {p[2]:.9g}\n".encode())
            for t in f:
                fh.write(f"3 {t[0]} {t[1]} {t[2]}\n".encode())


@pytest.mark.parametrize("fmt", ["obj", "ply_ascii", "ply_binary"])
def test_mesh_files_round_trip_and_render_like_arrays(tmp_path, fmt):
    v, f = icosphere(1)
    v = v.astype(np.float32)
    path = tmp_path / f"ico.{fmt.split('_')[0]}"
    if fmt == "obj":
        write_obj(path, v, f)
    else:
        write_ply(path, v, f, binary=fmt == "ply_binary")
    lv, lf = R.load_mesh(path)
    assert lv.dtype == np.float32 and lf.shape == f.shape
    # Assimp may reorder/merge vertices: compare the triangles as sets of corner positions
    tri = lambda vv, ff: sorted(tuple(np.round(vv[t].ravel(), 5)) for t in ff)  # noqa: E731
    assert tri(lv, lf) == tri(v, f)
    a = R.render(R.Scene(environment="sky").add_mesh(bk.Diffuse(0.7), path).look_at(**FURNACE_CAM),
                 width=16, height=16, spp=4, progress=False)
    b = R.render(R.Scene(environment="sky").add_mesh(bk.Diffuse(0.7), lv, lf).look_at(**FURNACE_CAM),
                 width=16, height=16, spp=4, progress=False)
    assert np.array_equal(a, b)


def test_preview_on_a_mesh_shape(tmp_path):
    v, f = icosphere(1)
    img = R.preview(bk.Diffuse(0.6), shape=(v, f), width=20, height=20, spp=2, progress=False)
    assert img.shape == (20, 20, 3) and np.all(np.isfinite(img))


# ---------------------------------------------------------------- bad input

def test_bad_render_arguments_raise_value_error():
    m = bk.Diffuse(0.5)
    for kw in (dict(width=0), dict(height=-1), dict(spp=0), dict(spp=-3), dict(max_depth=-1), dict(seed=-1)):
        with pytest.raises(ValueError):
            R.preview(m, progress=False, **kw)
    # a count of the wrong type: TypeError naming it (bsdfkit._validate.check_int, as everywhere)
    with pytest.raises(TypeError, match="width: expected an integer, got float"):
        R.preview(m, progress=False, width=2.5)
    with pytest.raises(TypeError):
        R.preview("not a model", progress=False)
    with pytest.raises(ValueError):
        R.preview(m, interrupt="ignore", progress=False)


def test_bad_meshes_raise_value_error():
    sc = R.Scene()
    v, f = icosphere(0)
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        sc.add_mesh(bk.Diffuse(0.5), bad, f)
    bad[3, 1] = np.inf
    with pytest.raises(ValueError, match="NaN or Inf"):
        sc.add_mesh(bk.Diffuse(0.5), bad, f)
    with pytest.raises(ValueError, match="indices"):
        sc.add_mesh(bk.Diffuse(0.5), v, f + 1)
    with pytest.raises(ValueError, match="indices"):
        sc.add_mesh(bk.Diffuse(0.5), v, -f)
    with pytest.raises(ValueError):
        sc.add_mesh(bk.Diffuse(0.5), v[:, :2], f)
    with pytest.raises(TypeError):
        sc.add_mesh(bk.Diffuse(0.5), v, f.astype(float))
    with pytest.raises(ValueError):
        sc.add_sphere(bk.Diffuse(0.5), radius=0.0)
    with pytest.raises(ValueError):
        sc.add_sphere(bk.Diffuse(0.5), center=(0, np.nan, 0))
    # the compiled renderer validates too (a misuse of _render raises, never reads out of bounds)
    s = _render.RenderScene()
    mi = s.add_material(bk.Diffuse(0.5))
    with pytest.raises(ValueError):
        s.add_mesh(v.astype(np.float32), np.array([[0, 1, 99]]), mi, mi, 0.0)
    with pytest.raises(ValueError):
        s.add_mesh(np.array([[0, 0, np.nan]] * 3, np.float32), np.array([[0, 1, 2]]), mi, mi, 0.0)
    with pytest.raises(ValueError):
        s.add_sphere([0, 0, 0], 1.0, mi, 7, 0.0)
    with pytest.raises(TypeError):
        s.add_material(object())


def test_bad_cameras_name_the_field():
    """Coordinates the float32 renderer cannot square (|x| > 1e18) name the field, before the
    parallel-up check (eye=(3e38, 0, 0) once failed as "up: must not be parallel")."""
    assert R.CAMERA_MAX_COORD == 1e18
    for field, v in (("origin", (3e38, 0, 0)), ("origin", (1e39, 0, 0)), ("origin", (1e300, 0, 0)),
                     ("target", (0, -2e18, 0)), ("up", (0, 1e39, 0))):
        with pytest.raises(ValueError, match=rf"^camera\.{field}: coordinates must be within \+-1e\+18"):
            R.Camera(**{field: v})._checked()
        with pytest.raises(ValueError, match=rf"^camera\.{field}: coordinates"):   # before the scene is built
            R.render(R.Scene(camera=R.Camera(**{field: v})), width=4, height=4, spp=1, progress=False)
    for field, v in (("origin", (0, np.nan, 0)), ("target", (np.inf, 0, 0)), ("up", (0, 1)), ("up", [[0, 1, 0]])):
        with pytest.raises(ValueError, match=rf"^camera\.{field}: expected 3 finite numbers"):
            R.Camera(**{field: v})._checked()
    with pytest.raises(TypeError, match=r"^camera\.origin: expected a real numeric array"):
        R.Camera(origin="abc")._checked()
    for up in ((0, 0, 0), (0, 1e-30, 0)):
        with pytest.raises(ValueError, match=r"^camera\.up: must not be \(nearly\) zero"):
            R.Camera(up=up)._checked()
    with pytest.raises(ValueError, match=r"^camera\.up: must not be parallel"):
        R.Camera(origin=(0, 5, 0), target=(0, 0, 0), up=(0, 2, 0))._checked()
    # equal in float32 (the renderer's precision), distinct in float64
    with pytest.raises(ValueError, match=r"^camera\.target: must differ from camera\.origin"):
        R.Camera(origin=(1, 0, 0), target=(1 + 1e-9, 0, 0))._checked()
    for fov, err in (("30", TypeError), (np.nan, ValueError), (180, ValueError)):
        with pytest.raises(err, match=r"^camera\.fov: "):
            R.Camera(fov=fov)._checked()
    with pytest.raises(TypeError, match=r"^fov: "):
        R.Scene().look_at((0, 1, 5), (0, 1, 0), fov="30")
    # the largest accepted camera renders a finite image
    sc = R.Scene(environment="sky").add_sphere(bk.Diffuse(0.5), center=(0, 0, 0), radius=1.0)
    sc.camera = R.Camera(origin=(1e18, 1e18, -1e18), target=(-1e18, -1e18, 1e18), up=(0, 1e18, 0), fov=30)
    assert np.all(np.isfinite(R.render(sc, width=8, height=4, spp=4, progress=False)))


def test_scene_geometry_beyond_float32_is_named():
    """Geometry the float32 renderer cannot hold (finite float64 beyond 1e18: 3e38 became inf in
    Embree's buffers) names the argument when it is added, as the camera's fields do."""
    m, tri = bk.Diffuse(0.5), np.array([[0, 1, 2]])
    cases = [(lambda s: s.add_sphere(m, center=(1e300, 0, 0)), r"^center: coordinates"),
             (lambda s: s.add_sphere(m, center=(0, 0, 0), radius=1e30), r"^center \+- radius: coordinates"),
             (lambda s: s.add_mesh(m, np.array([[0, 0, 0], [1, 0, 0], [0, 3e38, 0]]), tri), r"^vertices: coordinates"),
             (lambda s: s.add_mesh(m, np.eye(3), tri, transform=np.diag([1e30, 1, 1, 1])),
              r"^vertices \(transformed\): coordinates"),
             (lambda s: s.add_curves(m, np.array([[[0, 0, 0], [0, 1e19, 0]]])), r"^points \(with radius\): coordinates"),
             (lambda s: s.add_ground(size=1e40), r"^height, size: coordinates")]
    for add, msg in cases:
        with pytest.raises(ValueError, match=msg + r" must be within \+-1e\+18 \(the renderer works in float32\)"):
            add(R.Scene())
    # at the limit: accepted, and a mesh far away still renders a finite image
    sc = R.Scene(environment="sky").add_sphere(m, center=(0, 0, 0), radius=1.0)
    sc.add_mesh(m, np.array([[-1e18, -1e17, -1e18], [1e18, -1e17, -1e18], [0, -1e17, 1e18]]), tri)
    assert np.all(np.isfinite(R.render(sc, width=8, height=4, spp=2, progress=False)))


def test_missing_and_corrupt_env_map(tmp_path):
    missing = tmp_path / "nope.exr"
    with pytest.raises(FileNotFoundError) as ei:
        R.preview(bk.Diffuse(0.5), envmap=str(missing), progress=False, width=4, height=4, spp=1)
    assert str(missing) in str(ei.value)
    corrupt = tmp_path / "corrupt.exr"
    corrupt.write_bytes(b"v/1\x01 this is not an OpenEXR file" * 10)
    with pytest.raises(OSError) as ei:
        R.preview(bk.Diffuse(0.5), envmap=str(corrupt), progress=False, width=4, height=4, spp=1)
    msg = str(ei.value)
    assert str(corrupt) in msg and len(msg) > len(str(corrupt)) + 30   # OpenImageIO's reason follows
    for bad in (np.full((4, 8, 3), np.nan), -np.ones((4, 8, 3)), np.ones((4, 8, 2)), np.ones(5)):
        with pytest.raises(ValueError):
            R.preview(bk.Diffuse(0.5), envmap=bad, progress=False, width=4, height=4, spp=1)


def test_env_map_file_round_trip(tmp_path):
    env = R.default_environment("sky", 64)
    path = tmp_path / "sky.exr"
    write_image(path, env)
    a = R.preview(bk.Conductor.from_metal("Cu", alpha=0.1), envmap=str(path), width=16, height=16, spp=4,
                  progress=False)
    b = R.preview(bk.Conductor.from_metal("Cu", alpha=0.1), envmap=env, width=16, height=16, spp=4,
                  progress=False)
    assert np.array_equal(a, b)


def test_missing_and_corrupt_mesh_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        R.load_mesh(tmp_path / "nope.obj")
    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
    with pytest.raises(ValueError, match="bad.ply"):
        R.load_mesh(bad)


# ---------------------------------------------------------------- Ctrl-C

def _interrupt_after(seconds):
    def fire():
        time.sleep(seconds)
        import _thread
        _thread.interrupt_main()
    th = threading.Thread(target=fire, daemon=True)
    th.start()
    return th


@pytest.fixture
def sigint_default():
    """pytest-xdist workers may ignore SIGINT; interrupt_main() needs Python's handler."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("needs the main thread")
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


def test_ctrl_c_raises_keyboard_interrupt_with_partial_image(sigint_default):
    t0 = time.perf_counter()
    _interrupt_after(0.4)
    with pytest.raises(KeyboardInterrupt) as ei:
        R.preview(bk.Diffuse(0.5), width=128, height=128, spp=100000, progress=False)
    assert time.perf_counter() - t0 < 5.0
    img = ei.value.image
    assert ei.value.spp_done >= 1 and img.shape == (128, 128, 3) and np.all(np.isfinite(img))


def test_ctrl_c_can_return_the_partial_image(sigint_default):
    _interrupt_after(0.4)
    with pytest.warns(RuntimeWarning, match="interrupted"):
        img = R.preview(bk.Diffuse(0.5), width=128, height=128, spp=100000, progress=False, interrupt="return")
    assert img.shape == (128, 128, 3) and np.all(np.isfinite(img)) and img.mean() > 0.05
    # the renderer is still usable afterwards
    assert R.preview(bk.Diffuse(0.5), width=8, height=8, spp=1, progress=False).shape == (8, 8, 3)


# ---------------------------------------------------------------- specs and command line

@pytest.mark.parametrize("spec, cls", [
    ("conductor metal=Cu alpha=0.2", bk.Conductor), ("diffuse 0.8,0.5,0.2", bk.Diffuse),
    ("dielectric eta=1.5 alpha=0.1", bk.Dielectric), ("thindielectric", bk.ThinDielectric),
    ("difftrans 0.5 0.4", bk.DiffuseTransmission), ("Conductor reflectance=0.9 roughness=0.1", bk.Conductor),
    ("glass 1.33", bk.Dielectric)])
def test_parse_spec(spec, cls):
    assert isinstance(R.parse_spec(spec), cls)
    assert R.parse_spec("conductor metal=Cu alpha=0.2") == bk.Conductor.from_metal("Cu", alpha=0.2)


@pytest.mark.parametrize("spec", ["", "velvet 0.5", "diffuse color=red", "conductor metal=Xx", "diffuse 2.0",
                                  "dielectric eta=1.5 0.3"])
def test_parse_spec_errors(spec):
    with pytest.raises(ValueError):
        R.parse_spec(spec)


def test_cli_render(tmp_path, capsys):
    from bsdfkit.__main__ import main
    out = tmp_path / "cu.png"
    assert main(["render", "conductor", "metal=Cu", "alpha=0.2", "-o", str(out), "--width", "32", "--height", "24",
                 "--spp", "2", "-q"]) == 0
    img = read_image(out)
    assert img.shape == (24, 32, 3) and img.std() > 0.01
    exr = tmp_path / "glass.exr"
    assert main(["render", "dielectric eta=1.5", "-o", str(exr), "--width", "16", "--height", "16", "--spp", "2",
                 "--env", "studio", "-q"]) == 0
    assert read_image(exr).shape == (16, 16, 3)
    assert main(["render", "velvet", "-o", str(out), "-q"]) == 2
    assert "unknown model" in capsys.readouterr().err
    assert main(["render", "diffuse", "-o", str(out), "--env", str(tmp_path / "missing.exr"), "-q"]) == 1
    assert "missing.exr" in capsys.readouterr().err
    assert main(["render", "diffuse", "-o", str(out), "--spp", "0", "-q"]) == 1


def test_gallery_files(tmp_path):
    configs = [("Diffuse", bk.Diffuse(0.8)), ("Cu", bk.Conductor.from_metal("Cu", alpha=0.1)),
               ("glass", bk.Dielectric(1.5))]
    paths = R.write_gallery(str(tmp_path), configs, size=(96, 48), spp=4, progress=False, verbose=False)
    assert [os.path.basename(p) for p in paths] == ["gallery.exr", "gallery.png", "gallery_labelled.png"]
    exr, png = read_image(paths[0]), read_image(paths[1])
    assert exr.shape == (48, 96, 3) and png.shape == (48, 96, 3)
    assert np.all(np.isfinite(exr)) and exr.std() > 0.05


def test_project_matches_the_renderer():
    """The gallery labels' projection puts a sphere's centre where the renderer draws it: a black
    sphere under a white environment (no ground), its image centroid against project()."""
    sc = R.Scene(environment=1.0)
    sc.add_sphere(bk.Diffuse(0.0), center=(0.9, 1.3, -0.4), radius=0.3)
    sc.camera = R.Camera(origin=(0.2, 1.6, 4.0), target=(0.0, 0.9, 0.0), fov=40.0)
    w, h = 96, 64
    img = R.render(sc, width=w, height=h, spp=4, progress=False).sum(-1)
    mask = img < 0.5 * img.max()
    ys, xs = np.nonzero(mask)
    px = R.project(sc.camera, [0.9, 1.3, -0.4], (w, h))
    # the centroid of a perspective sphere's disc is within a pixel of its projected centre here
    np.testing.assert_allclose([xs.mean() + 0.5, ys.mean() + 0.5], px, atol=1.0)


def test_project_refuses_bad_input():
    """project() returned NaN for NaN points (and for a point at the camera) without an error."""
    cam = R.Camera(origin=(0.2, 1.6, 4.0), target=(0.0, 0.9, 0.0), fov=40.0)
    good = np.array([[0.9, 1.3, -0.4], [0.0, 0.9, 0.0]])
    px = R.project(cam, good, (96, 64))
    assert px.shape == (2, 2) and np.all(np.isfinite(px))
    np.testing.assert_allclose(px[1], [48, 32], atol=1e-12)   # the target projects to the image centre
    for bad in ([np.nan, 1, 0], [[0, 1, 0], [0, np.inf, 0]]):
        with pytest.raises(ValueError, match=r"^points: 1 point\(s\) contain NaN or Inf"):
            R.project(cam, bad, (96, 64))
    # the camera's own position (0/0 before) and a point behind it have no pixel position
    for bad in ([0.2, 1.6, 4.0], [[0.0, 0.9, 0.0], [0.4, 2.3, 8.0]]):
        with pytest.raises(ValueError, match=r"^points: 1 point\(s\) are not in front of the camera"):
            R.project(cam, bad, (96, 64))
    with pytest.raises(ValueError, match=r"^points: expected an array of points with last axis of length 3"):
        R.project(cam, [0.0, 0.9], (96, 64))
    with pytest.raises(TypeError, match=r"^points: expected a real numeric array"):
        R.project(cam, "x", (96, 64))
    for size, err, match in (((96,), ValueError, r"^size: expected \(width, height\)"),
                             (96, ValueError, r"^size: expected \(width, height\)"),
                             ((0, 64), ValueError, r"^size: width and height must be > 0"),
                             ((96, -1), ValueError, r"^size: width and height must be > 0"),
                             ((np.nan, 64), ValueError, r"^size \(width\): must be finite"),
                             ((96, np.inf), ValueError, r"^size \(height\): must be finite"),
                             (("96", 64), TypeError, r"^size \(width\): expected a real number")):
        with pytest.raises(err, match=match):
            R.project(cam, good, size)
    with pytest.raises(TypeError, match=r"^camera: expected a bsdfkit.render.Camera"):
        R.project((0, 0, 0), good, (96, 64))
