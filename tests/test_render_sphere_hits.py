"""Ray-sphere hits of the preview renderer (spheres are Embree user geometry with bsdfkit's own
intersection, render/scene.cpp) against the float64 ray-sphere geometry written here: the first
hit point and its normal for rays from far away, from just off the surface (the renderer's spawned
rays, both sides), from inside, and for near-tangent rays on both sides of the silhouette."""
import math

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import render as R
from conftest import fibonacci_sphere

C = np.array([0.3, 1.2, -0.4])
RADIUS = 0.9
WI = np.array([[0.0, 0.0, 1.0]])


def scene():
    # no ground: only the sphere can be hit
    return R.Scene(environment="white").add_sphere(bk.Diffuse(0.5), center=tuple(C), radius=RADIUS)._build()


def first_root(o, d):
    """Smallest t > 0 of |o + t d - C| = RADIUS in float64 (d unit), or None."""
    p = o - C
    b = p @ d
    c = p @ p - RADIUS * RADIUS
    disc = b * b - c
    if disc < 0:
        return None
    s = math.sqrt(disc)
    for t in sorted([-b - s, -b + s]):
        if t > 0:
            return t
    return None


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def check_hit(sc, o, d, tol=2e-5):
    hit = sc.debug_hit(o.tolist(), d.tolist(), WI)
    t = first_root(o, d)
    assert (hit is None) == (t is None), (o, d, t)
    if t is None:
        return
    p = o + t * d
    n = (p - C) / RADIUS
    assert np.allclose(hit["p"], p, atol=tol * max(1.0, np.abs(p).max())), (hit["p"], p)
    assert np.allclose(hit["n"], n, atol=tol), (hit["n"], n)


def test_rays_from_far_away_hit_where_the_geometry_says():
    sc = scene()
    rng = np.random.default_rng(3)
    for dist in (3.0, 50.0, 1e3):
        for w in fibonacci_sphere(24):
            o = C + dist * w
            # aim at a random point of the sphere's disc seen from o (some miss: |offset| up to 1.2 r)
            target = C + 1.2 * RADIUS * (rng.random(3) - 0.5)
            check_hit(sc, o, unit(target - o), tol=2e-5 if dist < 100 else 2e-4)


def test_rays_leaving_the_surface_do_not_hit_it_again_and_rays_entering_hit_the_far_side():
    sc = scene()
    rng = np.random.default_rng(4)
    for n in fibonacci_sphere(40):
        p = C + RADIUS * n
        eps = 1e-4 * max(np.abs(p).max(), 1.0)   # the renderer's spawn offset (scene.h)
        # outward ray from just outside: leaves the sphere, no hit
        d_out = unit(n + 0.9 * (rng.random(3) - 0.5))
        if d_out @ n <= 0.05:
            continue
        assert sc.debug_hit((p + eps * n).tolist(), d_out.tolist(), WI) is None
        # inward ray from just inside: the far side
        d_in = unit(-n + 0.9 * (rng.random(3) - 0.5))
        o = p - eps * n
        check_hit(sc, o, d_in)
        t = first_root(o, d_in)
        assert t > 0.05 * RADIUS     # not the surface it started on


def test_rays_from_the_centre_hit_at_one_radius():
    sc = scene()
    for d in fibonacci_sphere(30):
        hit = sc.debug_hit(C.tolist(), d.tolist(), WI)
        assert hit is not None
        assert np.allclose(hit["p"], C + RADIUS * d, atol=2e-6)


@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_near_tangent_rays_on_both_sides_of_the_silhouette(side):
    sc = scene()
    # rays along -z passing the centre at distance RADIUS (1 + side * 1e-4): inside the
    # silhouette they hit near the rim, outside they miss
    for phi in np.linspace(0, 2 * math.pi, 13)[:-1]:
        off = RADIUS * (1 + side * 1e-4) * np.array([math.cos(phi), math.sin(phi), 0.0])
        o = C + off + np.array([0.0, 0.0, 10.0])
        d = np.array([0.0, 0.0, -1.0])
        hit = sc.debug_hit(o.tolist(), d.tolist(), WI)
        if side > 0:
            assert hit is None
        else:
            t = first_root(o, d)
            assert hit is not None and t is not None
            # near the rim the hit's depth along the ray is ill-conditioned in float32 ray
            # coordinates: compare the re-projected point with a tolerance of the rim's scale
            p = o + t * d
            assert np.allclose(hit["p"], p, atol=3e-3)
