"""The preview renderer against Mitsuba 3's `path` integrator (llvm_ad_rgb): the same sphere,
environment map, camera and material, both unbiased, so the images differ by noise only.

Conventions matched (see bsdfkit.testing.mitsuba_scene): perspective sensor with fov on x and
look_at, box reconstruction filter, Mitsuba max_depth = ours + 1, the envmap's lat-long
orientation (checked first, on an environment-only view of a map with distinctive features),
and Mitsuba's envmap texel positions (rows at y / (H - 1), ours at (y + 0.5) / H): the test
environment is an analytic function sampled on each renderer's own grid. Microfacet models use
masking="separable", Mitsuba's only form.

Statistics: each renderer makes K independent renders (seeds); per pixel, the standard error of
the K-mean is pooled over 3 x 3 neighbourhoods (so its estimate has ~60 degrees of freedom) and
z = (ours - mitsuba) / sqrt(se_ours^2 + se_mi^2). Unbiased agreement gives mean(z^2) ~ 1 and
a Gaussian tail; the relative error of the image mean is compared with its own standard error.
"""
import math

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import render as R

import bsdfkit.testing.mitsuba as mitsuba_ref
import mitsuba  # noqa: F401,E402

RES = 48
K = 8
SPP = 128          # per seed; K * SPP = 1024 spp per renderer
ENV_W, ENV_H = 256, 128
CAMERA = dict(origin=(0.0, 0.6, 3.6), target=(0.0, 0.0, 0.0), fov=38.0)
# float32 rounding, the two envmap grids sampling the analytic map at different places (<= 0.1 %
# locally, on the bump; see test_environment_orientation) and the 1e-4 ray offsets: a systematic
# allowance on the mean, well below anything a wrong convention or model would produce (>= 1 %).
SYS_REL = 1e-3


def env_function(d):
    """Smooth analytic environment with asymmetric features (so a flipped or rotated mapping
    shows): a warm bump toward (0.6, 0.3, 0.74), a blue lobe up-left, gradients in x, y and z."""
    d0 = np.array([0.6, 0.3, 0.74])
    d0 /= np.linalg.norm(d0)
    d1 = np.array([-0.3, 0.9, 0.3])
    d1 /= np.linalg.norm(d1)
    bump = np.exp((d @ d0 - 1) / 0.02)
    lobe = np.exp((d @ d1 - 1) / 0.05)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    r = 0.5 + 0.3 * x + 0.2 * y + 6 * bump
    g = 0.5 - 0.2 * z + 0.1 * y * y + 3 * bump
    b = 0.6 + 0.3 * y + 1.5 * lobe
    return np.stack([r, g, b], -1)


def latlong(u, v):
    phi, th = np.meshgrid(2 * np.pi * u, np.pi * v)
    st = np.sin(th)
    return np.stack([np.sin(phi) * st, np.cos(th), -np.cos(phi) * st], -1)


ENV_OURS = env_function(latlong((np.arange(ENV_W) + 0.5) / ENV_W, (np.arange(ENV_H) + 0.5) / ENV_H)).astype(np.float32)
ENV_MI = env_function(latlong((np.arange(ENV_W) + 0.5) / ENV_W, np.arange(ENV_H) / (ENV_H - 1))).astype(np.float32)


def render_mitsuba(scene, seeds, spp, max_depth):
    mitsuba_ref.variant()
    import mitsuba as mi
    from bsdfkit.testing.mitsuba_scene import to_mitsuba_scene
    d = to_mitsuba_scene(scene, width=RES, height=RES, spp=spp, max_depth=max_depth)
    d["environment"] = {"type": "envmap", "bitmap": mi.Bitmap(ENV_MI)}
    msc = mi.load_dict(d)
    return np.stack([np.array(mi.render(msc, seed=s, spp=spp), dtype=np.float64) for s in seeds])


def render_ours(scene, seeds, spp, max_depth):
    return np.stack([R.render(scene, width=RES, height=RES, spp=spp, max_depth=max_depth, seed=s, progress=False)
                     for s in seeds]).astype(np.float64)


def pooled_se(imgs):
    """Standard error of the mean over the first axis, variance pooled over 3 x 3 pixels."""
    var = imgs.var(axis=0, ddof=1)
    p = np.pad(var, ((1, 1), (1, 1), (0, 0)), mode="edge")
    pooled = sum(p[dy:dy + var.shape[0], dx:dx + var.shape[1]] for dy in range(3) for dx in range(3)) / 9
    return np.sqrt(pooled / imgs.shape[0])


def compare(ours, theirs):
    a, b = ours.mean(0), theirs.mean(0)
    se = np.sqrt(pooled_se(ours) ** 2 + pooled_se(theirs) ** 2)
    ok = se > 0
    z = np.where(ok, (a - b) / np.where(ok, se, 1), 0.0)
    exact = ~ok
    rel = (a.mean() - b.mean()) / b.mean()
    se_rel = math.sqrt(np.sum(se ** 2)) / se.size / b.mean()
    return dict(rel_mean_error=float(rel), se_rel=float(se_rel), mean_z2=float(np.mean(z[ok] ** 2)),
                frac_z_gt_4=float(np.mean(np.abs(z[ok]) > 4)), max_abs_exact=float(np.abs(a - b)[exact].max(initial=0)),
                rel_abs_pixel=float(np.mean(np.abs(a - b)) / b.mean()))


def test_environment_orientation():
    """Environment only, three view directions including the bump: a mirrored, rotated or
    shifted lat-long mapping would miss by the bump's full contrast; the identical Mitsuba
    convention agrees to the interpolation difference of the two texel grids."""
    for target in ((0.6, 0.3, 0.74), (1.0, 0.2, 0.0), (-0.3, 0.9, 0.3), (0.0, -0.5, -1.0)):
        sc = R.Scene(environment=ENV_OURS).look_at((0, 0, 0), target, fov=50)
        ours = render_ours(sc, (0,), 64, 0)[0]
        theirs = render_mitsuba(sc, (0,), 64, 0)[0]
        rel = np.abs(ours - theirs).mean() / theirs.mean()
        assert rel < 3e-3, (target, rel)
        # the same bitmap given to Mitsuba unchanged would be shifted by half a row: visible on the bump
    sc = R.Scene(environment=ENV_OURS).look_at((0, 0, 0), (0.6, 0.3, 0.74), fov=50)
    mitsuba_ref.variant()
    import mitsuba as mi
    from bsdfkit.testing.mitsuba_scene import to_mitsuba_scene
    d = to_mitsuba_scene(sc, width=RES, height=RES, spp=64, max_depth=0)
    d["environment"] = {"type": "envmap", "bitmap": mi.Bitmap(np.fliplr(ENV_MI).copy())}
    mirrored = np.array(mi.render(mi.load_dict(d), seed=0, spp=64))
    ours = render_ours(sc, (0,), 64, 0)[0]
    assert np.abs(ours - mirrored).mean() / mirrored.mean() > 0.05


MATERIALS = {
    "diffuse": lambda: bk.Diffuse([0.8, 0.5, 0.3]),
    "conductor_rough": lambda: bk.Conductor.from_metal("Cu", alpha=0.3, masking="separable"),
    "conductor_aniso": lambda: bk.Conductor.from_metal("Au", alpha_x=0.4, alpha_y=0.1, masking="separable"),
    "conductor_smooth": lambda: bk.Conductor.from_metal("Ag"),
    "dielectric_rough": lambda: bk.Dielectric(1.5, alpha=0.3, masking="separable"),
    "dielectric_smooth": lambda: bk.Dielectric(1.5),
    "thin_dielectric": lambda: bk.ThinDielectric(1.5),
}


@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_sphere_matches_mitsuba(name):
    m = MATERIALS[name]()
    sc = R.Scene(environment=ENV_OURS).add_sphere(m, center=(0, 0, 0), radius=1.0).look_at(**CAMERA)
    max_depth = 8
    ours = render_ours(sc, range(K), SPP, max_depth)
    theirs = render_mitsuba(sc, range(100, 100 + K), SPP, max_depth)
    s = compare(ours, theirs)
    print(name, {k: round(v, 5) for k, v in s.items()})
    assert abs(s["rel_mean_error"]) < 4 * s["se_rel"] + SYS_REL, s
    assert s["mean_z2"] < 1.35, s
    assert s["frac_z_gt_4"] < 0.005, s
    assert s["max_abs_exact"] < 1e-3 * max(1.0, float(ours.mean())), s
