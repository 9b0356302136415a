"""Fibres (``Scene.add_curves``) in the preview renderer against Mitsuba 3's `path` integrator
(llvm_ad_rgb) with its ``bsplinecurve`` shape: the Catmull-Rom segments are handed to Mitsuba
rewritten exactly as cubic B-splines (bsdfkit.testing.mitsuba_scene), so both trace the same swept
surface; the statistics are those of test_render_mitsuba.py (pooled per-pixel z, image mean).

Rays leave a fibre of a surface material (Diffuse, Conductor) from its surface in both renderers,
so the hard shadows a sun casts from one fibre onto another fall on the same pixels: the diffuse
fibres are compared under the sun too (when our rays left from the axis, that case gave mean z^2
1.8). Hair fibres keep their axis convention (render/scene.h: the far-field hair model describes
the whole fibre), and still agree with Mitsuba's hair under the sun."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import render as R
from bsdfkit.testing.mitsuba_scene import _CATMULL_ROM_TO_BSPLINE, _M_BSPLINE, _M_CATMULL_ROM

from test_render_mitsuba import ENV_OURS, K, SPP, SYS_REL, compare, render_mitsuba, render_ours

CAMERA = dict(origin=(0.0, 0.4, 3.2), target=(0.0, 0.0, 0.0), fov=34.0)


def fibres():
    """Five gently curved fibres across the view, radius 0.03, over nothing but the environment
    (every path sees the analytic map), two of them crossing in front of the others."""
    t = np.linspace(-1.0, 1.0, 9)
    pts = []
    for k, (y, z, bend) in enumerate(((-0.5, 0.0, 0.2), (-0.2, 0.15, -0.15), (0.1, -0.1, 0.25), (0.4, 0.2, -0.1),
                                      (0.7, 0.0, 0.15))):
        x = t * 1.1
        pts.append(np.stack([x, y + bend * (1 - t ** 2) + 0.1 * np.sin(3 * t + k), z + 0.2 * np.cos(2 * t + k)], -1))
    cross = np.stack([0.2 * np.sin(2 * t), t * 0.9, np.full_like(t, 0.5)], -1)
    pts.append(cross)
    return pts


def scene(material, sun):
    """The analytic environment, with ``sun`` plus a directional light: its sharp highlights make
    the hair images depend on the lobe widths and shifts (beta_m 0.3 -> 0.15 gives mean z^2 ~ 4,
    eta 1.55 -> 1.45 a 25-sigma mean shift), which the smooth environment alone blurs away, and the
    hard shadows of one fibre on another show where rays leave a fibre (its surface, as Mitsuba,
    for the surface models)."""
    sc = R.Scene(environment=ENV_OURS)
    if sun:
        sc.add_directional_light((0.3, 0.8, 0.9), (6.0, 6.0, 6.0))
    return sc.add_curves(material, fibres(), radius=0.03).look_at(**CAMERA)


def test_catmull_rom_to_bspline_is_the_same_cubic():
    """The conversion matrix turns 4 Catmull-Rom control points into the B-spline control points of
    the identical cubic (position and radius), at every t: a wrong basis would miss by O(1)."""
    rng = np.random.default_rng(3)
    p = rng.normal(size=(4, 4))
    t = np.linspace(0, 1, 33)
    tb = np.stack([t ** 0, t, t ** 2, t ** 3], 1)
    # the Catmull-Rom segment interpolates its middle control points (independent of the matrices' algebra)
    cr = tb @ _M_CATMULL_ROM @ p
    np.testing.assert_allclose(cr[0], p[1], atol=1e-14)
    np.testing.assert_allclose(cr[-1], p[2], atol=1e-14)
    np.testing.assert_allclose(tb @ _M_BSPLINE @ (_CATMULL_ROM_TO_BSPLINE @ p), cr, atol=1e-13)


@pytest.mark.parametrize("name, material, sun", [
    ("diffuse", lambda: bk.Diffuse([0.8, 0.5, 0.3]), False),
    ("diffuse_sun", lambda: bk.Diffuse([0.8, 0.5, 0.3]), True),
    ("conductor_rough", lambda: bk.Conductor.from_metal("Au", alpha=0.3, masking="separable"), False),
    ("hair", lambda: bk.Hair(sigma_a=[0.3, 0.6, 1.2], beta_m=0.3, beta_n=0.3), False),
    ("hair_sun", lambda: bk.Hair(sigma_a=[0.3, 0.6, 1.2], beta_m=0.3, beta_n=0.3), True),
])
def test_fibres_match_mitsuba(name, material, sun):
    sc = scene(material(), sun)
    max_depth = 8
    ours = render_ours(sc, range(K), SPP, max_depth)
    theirs = render_mitsuba(sc, range(100, 100 + K), SPP, max_depth)
    s = compare(ours, theirs)
    print(name, {k: round(v, 5) for k, v in s.items()})
    # the fibres cover a good part of the image (not an environment-only comparison)
    assert np.mean(np.abs(ours.mean(0) - render_ours(R.Scene(environment=ENV_OURS).look_at(**CAMERA), (0,), 4, 0)[0])
                   > 0.05) > 0.15
    assert abs(s["rel_mean_error"]) < 4 * s["se_rel"] + SYS_REL, s
    assert s["mean_z2"] < 1.35, s
    assert s["frac_z_gt_4"] < 0.005, s
