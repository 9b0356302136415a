"""Hair on fibres in the preview renderer: the offset h and the frame taken from a curve hit, the
R lobe against the geometric mirror reflection off the cylinder, the white furnace of a lock of
sigma_a = 0 hair, a lock under the studio environment, and bad input.

Expected values come from the ray-cylinder geometry written here and from the model's own
``eval`` (the Hair model is checked against Mitsuba and a float64 reference in tests/models)."""
import math

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import render as R
from conftest import fibonacci_sphere

LUM = np.array([0.2126, 0.7152, 0.0722])
X = np.array([1.0, 0.0, 0.0])


def fibre_scene(model, radius=0.1, env="white"):
    """One straight fibre along world x through the origin (radius ``radius``)."""
    pts = np.array([[-3.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    return R.Scene(environment=env).add_curves(model, pts[None], radius)


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


# (ray origin, direction): rays passing the x axis at signed distance b along X x d
RAYS = [((0.3, 0.05, 5.0), (-0.4, 0.0, -1.0)),        # h = +0.5, theta_o ~ 22 degrees
        ((0.0, -0.07, 4.0), (0.0, 0.0, -1.0)),        # h = -0.7, perpendicular to the fibre
        ((1.0, 1.78, 3.0), (-0.5, -0.58, -1.0)),      # oblique in every axis
        ((-0.5, 3.0, -0.033), (0.3, -1.0, -0.02))]    # from above, h = 0.93


@pytest.mark.parametrize("origin, direction", RAYS)
def test_h_and_frame_from_the_hit_reproduce_hair_eval(origin, direction):
    r = 0.1
    m = bk.Hair.from_concentration(0.8, 0.2, beta_m=0.25, beta_n=0.35, alpha=3.0)
    sc = fibre_scene(m, radius=r)
    o, d = np.asarray(origin, float), unit(direction)
    wi = fibonacci_sphere(400)
    hit = sc._build().debug_hit(o.tolist(), d.tolist(), wi)
    # the signed distance between the ray and the axis along X x d, in radii (module docstring)
    y = unit(np.cross(X, d))
    h = float(o @ y) / r
    assert abs(h) < 1
    assert hit is not None and hit["fibre"]
    assert hit["h"] == pytest.approx(h, abs=2e-4)
    # frame: x the fibre, z the part of wo normal to it, y = z x x
    wo = -d
    z = unit(wo - (wo @ X) * X)
    np.testing.assert_allclose(hit["s"], X, atol=1e-5)
    np.testing.assert_allclose(hit["n"], z, atol=1e-5)
    np.testing.assert_allclose(hit["t"], np.cross(z, X), atol=1e-5)
    frame = np.stack([X, np.cross(z, X), z])
    wo_l, wi_l = frame @ wo, wi @ frame.T
    np.testing.assert_allclose(hit["wo"], wo_l, atol=1e-5)
    # the renderer's f |cos| at the hit equals the model's eval at that h (float32 renderer)
    ref = bk.Hair(sigma_a=m.sigma_a, beta_m=0.25, beta_n=0.35, alpha=3.0, h=h).eval(wo_l, wi_l)
    ref = ref * np.abs(wi_l[:, 2:3])
    got = hit["f_cos"]
    assert ref.max() > 0.1
    np.testing.assert_allclose(got, ref, rtol=2e-3, atol=2e-4 * ref.max())


def ray_cylinder_hit(o, d, r):
    """First hit of o + t d with the infinite cylinder y^2 + z^2 = r^2 around x."""
    a = d[1] ** 2 + d[2] ** 2
    b = 2 * (o[1] * d[1] + o[2] * d[2])
    c = o[1] ** 2 + o[2] ** 2 - r * r
    t = (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
    return o + t * d


@pytest.mark.parametrize("origin, direction", RAYS[:3])
def test_r_lobe_peaks_at_the_mirror_reflection_off_the_cylinder(origin, direction):
    # dark, smooth, untilted: f is the R lobe, peaked on the mirror direction of the real cylinder
    r = 0.1
    m = bk.Hair(sigma_a=50.0, beta_m=0.06, beta_n=0.06, alpha=0.0)
    o, d = np.asarray(origin, float), unit(direction)
    p = ray_cylinder_hit(o, d, r)
    n = unit(np.array([0.0, p[1], p[2]]))
    mirror = d - 2 * (d @ n) * n
    # the mirror image of that direction across the plane of the ray and the fibre (h -> -h)
    y = unit(np.cross(X, d))
    wrong = mirror - 2 * (mirror @ y) * y
    dirs = np.concatenate([fibonacci_sphere(40000), [mirror, wrong]])
    hit = fibre_scene(m, radius=r)._build().debug_hit(o.tolist(), d.tolist(), dirs)
    v = hit["f_cos"] @ LUM
    peak = dirs[np.argmax(v[:-2])]
    assert math.degrees(math.acos(min(1.0, peak @ mirror))) < 4.0
    assert v[-2] > 50 * v[-1]
    assert v[-2] >= 0.9 * v[:-2].max()


def test_white_furnace_lock_of_lossless_hair():
    # sigma_a = 0: every fibre scatters all it receives, so under uniform radiance 1 the lock
    # vanishes into the background at any depth of interreflection (max_depth large)
    pts, rad = R.hair_swatch(n_fibres=250, length=1.0, radius=0.02, curl=0.4, seed=3, width=0.5, thickness=0.15,
                             top=0.5)
    m = bk.Hair(sigma_a=0.0, beta_m=0.3, beta_n=0.3, alpha=2.0)
    sc = R.Scene(environment="white").add_curves(m, pts, rad).look_at((0, 0, 2.6), (0, 0, 0), fov=34)
    coverage = R.render(sc, width=32, height=32, spp=1, max_depth=0, progress=False)
    hair = coverage[..., 1] < 0.5        # max_depth 0: the camera sees black fibres
    assert hair.mean() > 0.15
    img, st = R.render(sc, width=32, height=32, spp=24, max_depth=100, progress=False, return_stats=True)
    assert st["nonfinite"] == 0
    y = img @ LUM
    assert abs(y[hair].mean() - 1) < 0.01          # measured 1.0015 (seed 0)
    assert np.median(np.abs(y[hair] - 1)) < 0.05    # per-pixel Monte Carlo noise at 24 spp
    assert abs(y[~hair].mean() - 1) < 0.01
    # the same lock of brown hair absorbs
    sc2 = R.Scene(environment="white").add_curves(bk.Hair(), pts, rad).look_at((0, 0, 2.6), (0, 0, 0), fov=34)
    y2 = R.render(sc2, width=32, height=32, spp=4, max_depth=100, progress=False) @ LUM
    assert y2[hair].mean() < 0.6


def test_white_furnace_far_field_fibre():
    pts, rad = R.hair_swatch(n_fibres=60, length=1.0, radius=0.02, curl=0.2, seed=1, width=0.5, thickness=0.1,
                             top=0.5)
    sc = R.Scene(environment="white").add_curves(bk.Hair(sigma_a=0.0, h=None), pts, rad)
    sc.look_at((0, 0, 2.6), (0, 0, 0), fov=34)
    hair = R.render(sc, width=24, height=24, spp=1, max_depth=0, progress=False)[..., 1] < 0.5
    y = R.render(sc, width=24, height=24, spp=64, max_depth=100, progress=False) @ LUM
    assert hair.mean() > 0.05
    # the lock's mean against 1 within 4 standard errors of its pixels' Monte Carlo noise (a fixed
    # 0.015 was about one standard error at 8 spp: any change of the random streams could fail it;
    # at 64 spp the standard error is ~0.0045, so 4 of them hold the mean to ~2 %)
    se = y[hair].std(ddof=1) / np.sqrt(hair.sum())
    assert se < 0.006
    assert abs(y[hair].mean() - 1) < 4 * se


def test_lock_under_the_studio_environment_is_finite_and_lit():
    m = bk.Hair.from_concentration(0.6, 0.3)
    sc = R.hair_scene(m, n_fibres=400, aspect=0.75)
    img, st = R.render(sc, width=36, height=48, spp=4, progress=False, return_stats=True)
    assert img.shape == (48, 36, 3) and img.dtype == np.float32
    assert np.all(np.isfinite(img)) and st["nonfinite"] == 0
    # the same framing under a constant environment of 1 and max_depth 0 shows where the lock is
    mask = R.render(sc, envmap=1.0, width=36, height=48, spp=1, max_depth=0, progress=False)[..., 1] < 0.5
    assert 0.15 < mask.mean() < 0.8
    y = img @ LUM
    assert y[mask].mean() > 0.02           # lit, not black
    # hair is brown: red above blue where it is lit
    lit = mask & (y > np.percentile(y[mask], 50))
    assert img[lit, 0].mean() > 1.3 * img[lit, 2].mean()


def test_preview_shape_hair_uses_the_lock():
    img = R.preview(bk.Hair(), shape="hair", width=16, height=24, spp=1, progress=False)
    assert img.shape == (24, 16, 3) and np.all(np.isfinite(img))


def test_non_hair_material_on_fibres_uses_the_tube_normal():
    sc = fibre_scene(bk.Diffuse(0.5))
    hit = sc._build().debug_hit([0.0, 0.05, 5.0], [0.0, 0.0, -1.0], np.array([[0.0, 0.0, 1.0]]))
    # outward normal of the cylinder where the ray enters it: (0, 0.05, sqrt(0.1^2 - 0.05^2)) / 0.1
    np.testing.assert_allclose(hit["n"], [0.0, 0.5, math.sqrt(0.75)], atol=1e-4)
    np.testing.assert_allclose(hit["f_cos"][0], 0.5 / math.pi * math.sqrt(0.75), rtol=1e-4)


def test_hair_swatch_shape_and_determinism():
    p, r = R.hair_swatch(n_fibres=10, points_per_fibre=7, radius=0.01, seed=5)
    assert p.shape == (10, 7, 3) and r.shape == (10, 7)
    assert np.all(r > 0) and r.max() == 0.01
    p2, _ = R.hair_swatch(n_fibres=10, points_per_fibre=7, radius=0.01, seed=5)
    np.testing.assert_array_equal(p, p2)
    # fibres hang down from the roots
    assert np.all(p[:, 0, 1] > p[:, -1, 1])


@pytest.mark.parametrize("points, radius, match", [
    (np.zeros((2, 1, 3)), 0.1, "points: fibre 0"),
    (np.zeros((2, 4, 2)), 0.1, "points: fibre 0"),
    (np.full((1, 3, 3), np.nan), 0.1, "points: fibre 0: contains NaN"),
    (np.zeros((0, 3, 3)), 0.1, "points: need at least one fibre"),
    (np.zeros((1, 3, 3)), 0.0, "radius"),
    (np.zeros((1, 3, 3)), -1.0, "radius"),
    (np.zeros((1, 3, 3)), np.array([[0.1, 0.1]]), "radius: fibre 0"),
    (np.zeros((1, 3, 3)), np.array([[0.1, np.nan, 0.1]]), "radius: fibre 0"),
    (np.zeros(9), 0.1, "points"),
])
def test_bad_curves_raise_value_error(points, radius, match):
    with pytest.raises(ValueError, match=match):
        R.Scene().add_curves(bk.Hair(), points, radius)


def test_bad_curve_arguments():
    with pytest.raises(TypeError, match="material"):
        R.Scene().add_curves("hair", np.zeros((1, 3, 3)), 0.1)
    with pytest.raises(TypeError, match="points"):
        R.Scene().add_curves(bk.Hair(), [np.array([["a", "b", "c"]] * 3)], 0.1)
    for kw, match in ((dict(n_fibres=0), "n_fibres"), (dict(length=-1.0), "length"), (dict(radius=0.0), "radius"),
                      (dict(curl=-0.1), "curl"), (dict(curl=float("nan")), "curl"), (dict(seed=-1), "seed"),
                      (dict(points_per_fibre=1), "points_per_fibre")):
        with pytest.raises(ValueError, match=match):
            R.hair_swatch(**kw)
    from bsdfkit import _render
    s = _render.RenderScene()
    m = s.add_material(bk.Hair())
    pts = np.zeros((5, 4), np.float32)
    pts[:, 3] = 0.1
    with pytest.raises(ValueError, match="segments"):
        s.add_curves(pts, np.array([2]), m)
    pts[1, 3] = 0.0
    with pytest.raises(ValueError, match="radius"):
        s.add_curves(pts, np.array([0]), m)
