"""The demo's svbrdf.png: a sphere shaded with one per-pixel model equals, pixel by pixel, uniform
models built from the pixel's texel, evaluated in the pixel's frame (rotations computed here); the
figure is written without the renderer extension."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import _demo

SIZE = 48   # a small sphere image: ~1700 pixels


@pytest.fixture(scope="module")
def maps():
    return _demo.svbrdf_maps()


def _pixel(r, c, size=SIZE, margin=_demo.SVBRDF_MARGIN):
    """The sphere point of pixel (r, c) (row 0 at the top), its latitude and longitude."""
    x = ((c + 0.5) / size * 2 - 1) * margin
    y = -((r + 0.5) / size * 2 - 1) * margin
    z = math.sqrt(1 - x * x - y * y)
    return np.array([x, y, z]), math.asin(y), math.atan2(x, z)


def _frame(lat, lon):
    """Columns (east, north, out) of the point at (lat, lon): the frame at (0, 0), i.e. the
    identity (x east, y north, z out of the sphere towards the camera), tilted north by lat
    about x, then turned by lon about y."""
    ca, sa = math.cos(-lat), math.sin(-lat)
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    cb, sb = math.cos(lon), math.sin(lon)
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    return ry @ rx


def _texel(maps, lat, lon):
    h, w = maps["roughness"].shape
    u, v = lon / (2 * math.pi) + 0.5, lat / math.pi + 0.5
    return min(int((1 - v) * h), h - 1), int(u * w) % w


def test_pixels_equal_uniform_models_in_their_frames(maps):
    img, mask = _demo.shade_svbrdf(maps, SIZE, sky=None)
    assert img.shape == (SIZE, SIZE, 3) and np.all(img[~mask] == 0) and np.all(np.isfinite(img))
    wis = np.array([np.array(d) / np.linalg.norm(d) for d, _ in _demo.SVBRDF_LIGHTS])   # (lights, 3)
    irr = np.array([e for _, e in _demo.SVBRDF_LIGHTS])
    seen = {"metal": 0, "dielectric": 0, "tilted": 0, "lit": 0}
    for r in range(1, SIZE, 5):
        for c in range(2, SIZE, 5):
            if not mask[r, c]:
                continue
            p, lat, lon = _pixel(r, c)
            R = _frame(lat, lon)
            np.testing.assert_allclose(R[:, 2], p, atol=1e-12)   # the frame's z is the sphere's normal
            i, j = _texel(maps, lat, lon)
            n_t = maps["normals"][i, j]
            m = bk.NormalMap(bk.FilamentStandard(base_color=tuple(maps["base_color"][i, j]),
                                                 roughness=float(maps["roughness"][i, j]),
                                                 metallic=float(maps["metallic"][i, j])), normals=n_t)
            wo = R.T @ np.array([0.0, 0.0, 1.0])
            f = m.eval(wo, wis @ R)                                  # every light's wi in the local frame
            want = (f * np.maximum(wis @ p, 0.0)[:, None] * irr).sum(axis=0)
            np.testing.assert_allclose(img[r, c], want, rtol=1e-9, atol=1e-12, err_msg=f"pixel {(r, c)}")
            seen["metal" if maps["metallic"][i, j] == 1 else "dielectric"] += 1
            seen["tilted"] += n_t[2] < 0.95
            seen["lit"] += want.max() > 0.05
    assert min(seen.values()) >= 3, seen   # the sample covers both materials and the bevels


def test_sky_term_is_albedo_about_the_shading_normal(maps):
    size = 32
    direct, mask = _demo.shade_svbrdf(maps, size, sky=None)
    sky = np.array([0.2, 0.3, 0.4])
    full, _ = _demo.shade_svbrdf(maps, size, sky=sky, sky_samples=1024)
    picked = {"x": [], "y": [], "flat": []}   # pixels on east/west bevels, north/south bevels, flat texels
    for r, c in zip(*np.nonzero(mask)):
        p, lat, lon = _pixel(r, c, size)
        if p[2] < 0.5:
            continue
        n_t = maps["normals"][_texel(maps, lat, lon)]
        key = "x" if abs(n_t[0]) > 0.3 else "y" if abs(n_t[1]) > 0.3 else "flat" if n_t[2] > 0.999 else None
        if key and len(picked[key]) < 3:
            picked[key].append((r, c))
    assert all(len(v) == 3 for v in picked.values()), picked
    for r, c in sum(picked.values(), []):
        p, lat, lon = _pixel(r, c, size)
        i, j = _texel(maps, lat, lon)
        n_s = _frame(lat, lon) @ maps["normals"][i, j]        # the normal map's normal, world space
        cos = float(n_s[2])                                     # . wo = (0, 0, 1)
        m = bk.FilamentStandard(base_color=tuple(maps["base_color"][i, j]), roughness=float(maps["roughness"][i, j]),
                                metallic=float(maps["metallic"][i, j]))
        rho = m.albedo(np.array([math.sqrt(1 - cos * cos), 0.0, cos]), n_samples=1 << 16, seed=5)   # isotropic
        np.testing.assert_allclose(full[r, c] - direct[r, c], rho * sky, rtol=0.04, err_msg=f"pixel {(r, c)}")


def test_normal_map_convention(maps):
    # x east (+u, columns), y north (towards row 0); a bevel tilts the normal away from the tile
    h, w = maps["roughness"].shape
    n = maps["normals"]
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1, atol=1e-12)
    th, tw = h // 8, w // 16   # one tile; the third of the top row is marble (flat but for its bevel)
    mid_r, mid_c = th // 2, 2 * tw + tw // 2
    east = n[mid_r, 3 * tw - int(0.08 * tw)]     # on the tile's east bevel: the height falls eastwards
    north = n[int(0.08 * th), mid_c]              # north bevel (near the tile's top row)
    assert east[0] > 0.3 and abs(east[1]) < 0.05
    assert north[1] > 0.3 and abs(north[0]) < 0.05
    np.testing.assert_allclose(n[mid_r, mid_c], [0, 0, 1], atol=1e-9)


def test_svbrdf_figure_without_the_renderer(tmp_path):
    # a fresh process in which the renderer extension cannot be imported
    out = tmp_path / "svbrdf.png"
    code = ("import sys; sys.modules['bsdfkit._render'] = None\n"
            "from bsdfkit import _demo\n"
            f"_demo._svbrdf_figure({str(out)!r})\n"
            "assert 'bsdfkit.render' not in sys.modules\n")
    pkg = os.path.dirname(os.path.dirname(os.path.abspath(bk.__file__)))   # the bsdfkit under test
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join([pkg, os.environ.get("PYTHONPATH", "")]))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    import matplotlib.image as mimage
    img = mimage.imread(str(out))
    assert img.shape[0] > 600 and img.shape[1] > 1400
    sphere = img[int(0.3 * img.shape[0]):int(0.7 * img.shape[0]), int(0.05 * img.shape[1]):int(0.3 * img.shape[1]), :3]
    assert sphere.std() > 0.1 and 0.2 < sphere.mean() < 0.8   # shaded, neither blank nor blown out
