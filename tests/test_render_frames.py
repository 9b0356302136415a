"""Shading frames of the preview renderer's hits (render/scene.cpp: triangles take a frame computed
per triangle in double when the mesh is added, spheres build theirs from the unnormalized offset
p - c) against float64 frames written here: n the unit geometric normal, s the tangent (triangles:
the edge p1 - p0 made orthogonal to n; spheres: dp/dphi around +y, (-n.z, 0, n.x) normalized),
t = n x s, orthonormal to float rounding; at a sphere's poles any orthonormal frame around n."""
import numpy as np

import bsdfkit as bk
from bsdfkit import render as R
from conftest import fibonacci_sphere

WI = np.array([[0.0, 0.0, 1.0]])


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def check_orthonormal(h, tol=2e-6):
    s, t, n = (np.array(h[k]) for k in "stn")
    for a in (s, t, n):
        assert abs(np.linalg.norm(a) - 1) < tol
    assert abs(s @ t) < tol and abs(s @ n) < tol and abs(t @ n) < tol
    assert np.allclose(np.cross(n, s), t, atol=tol)  # right-handed: t = n x s


def test_triangle_frames_match_float64_gram_schmidt_including_skinny_triangles():
    rng = np.random.default_rng(11)
    tris = []
    for k in range(40):
        p0 = rng.normal(size=3)
        e1 = rng.normal(size=3)
        # every 4th triangle skinny: e2 nearly along e1 (angle ~1e-3 rad)
        e2 = e1 * rng.uniform(0.3, 2.0) + 1e-3 * rng.normal(size=3) if k % 4 == 0 else rng.normal(size=3)
        tris.append((p0, p0 + e1, p0 + e2))
    for p0, p1, p2 in tris:
        verts = np.array([p0, p1, p2], np.float32)
        sc = R.Scene(environment="white").add_mesh(bk.Diffuse(0.5), verts, np.array([[0, 1, 2]]))._build()
        v = verts.astype(float)  # the float32 vertices the renderer stores
        n = unit(np.cross(v[1] - v[0], v[2] - v[0]))
        e1 = v[1] - v[0]
        s = unit(e1 - n * (n @ e1))
        centroid = v.mean(axis=0)
        for side in (1.0, -1.0):  # from either side of the triangle
            o = centroid + side * 3.0 * n + 0.01 * s
            h = sc.debug_hit(o.tolist(), unit(centroid - o).tolist(), WI)
            assert h is not None
            assert np.allclose(h["n"], n, atol=2e-6), (h["n"], n)
            assert np.allclose(h["s"], s, atol=2e-6), (h["s"], s)
            check_orthonormal(h)


def test_sphere_frames_follow_the_parallels_and_stay_orthonormal_at_the_poles():
    c, r = np.array([0.3, 1.2, -0.4]), 0.9
    sc = R.Scene(environment="white").add_sphere(bk.Diffuse(0.5), center=tuple(c), radius=r)._build()
    dirs = list(fibonacci_sphere(64)) + [np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0]),
                                        unit([1e-7, 1.0, 0.0]), unit([0.0, -1.0, 3e-6])]
    for w in dirs:
        o = c + 4.0 * w
        h = sc.debug_hit(o.tolist(), (-w).tolist(), WI)
        assert h is not None
        n = unit(np.array(h["p"]) - c)
        assert np.allclose(h["n"], w, atol=2e-6) and np.allclose(n, w, atol=2e-6)
        check_orthonormal(h)
        q = np.hypot(w[0], w[2])
        if q > 1e-5:  # off the poles: s along the parallel through the hit
            assert np.allclose(h["s"], np.array([-w[2], 0.0, w[0]]) / q, atol=2e-6 / q), (h["s"], w)
