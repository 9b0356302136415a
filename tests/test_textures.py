"""Textures (bsdfkit.textures) and textured models.

References: image lookups against direct numpy indexing / bilinear interpolation written here
from the pixel-centre convention; sRGB decoding against the IEC 61966-2-1 formula; procedural
textures against pbrt-v4's definitions (the checkerboard's filtered form against numerical
integration); textured models against the same models built with per-element parameters."""
import pickle

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import textures as tx

pytest.importorskip("bsdfkit._render", reason="textures need bsdfkit._render (OpenImageIO)")

RNG = np.random.default_rng(7)


def _wrap_index(i, n, mode):
    if mode == "periodic":
        return np.mod(i, n), np.ones_like(i, bool)
    if mode == "clamp":
        return np.clip(i, 0, n - 1), np.ones_like(i, bool)
    if mode == "mirror":
        p = np.mod(i, 2 * n)
        return np.where(p < n, p, 2 * n - 1 - p), np.ones_like(i, bool)
    inside = (i >= 0) & (i < n)            # black
    return np.clip(i, 0, n - 1), inside


def ref_nearest(img, uv, wrap):
    h, w = img.shape[:2]
    x = np.floor(uv[:, 0] * w).astype(int)
    y = np.floor(uv[:, 1] * h).astype(int)
    xi, xin = _wrap_index(x, w, wrap)
    yi, yin = _wrap_index(y, h, wrap)
    return img[yi, xi] * (xin & yin)[:, None]


def ref_bilinear(img, uv, wrap):
    """Bilinear interpolation between pixel centres at ((i + 0.5) / W, (j + 0.5) / H)."""
    h, w = img.shape[:2]
    x = uv[:, 0] * w - 0.5
    y = uv[:, 1] * h - 0.5
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    out = 0
    for dy, wy in ((0, 1 - fy), (1, fy)):
        for dx, wx in ((0, 1 - fx), (1, fx)):
            xi, xin = _wrap_index(x0 + dx, w, wrap)
            yi, yin = _wrap_index(y0 + dy, h, wrap)
            out = out + wx * wy * img[yi, xi] * (xin & yin)[:, None]
    return out


def _uv_off_edges(n, lo, hi, res):
    """uv in [lo, hi) at least 1e-3 texel away from texel edges (nearest lookups have no ties)."""
    uv = RNG.uniform(lo, hi, (n, 2))
    for k, r in enumerate(res):
        f = uv[:, k] * r - np.floor(uv[:, k] * r)
        uv[:, k] += np.where(np.abs(f) < 1e-3, 2e-3 / r, 0) - np.where(np.abs(f - 1) < 1e-3, 2e-3 / r, 0)
    return uv


@pytest.mark.parametrize("wrap", ["periodic", "clamp", "mirror", "black"])
@pytest.mark.parametrize("filt", ["nearest", "bilinear"])
def test_image_lookup_matches_numpy(wrap, filt):
    img = RNG.random((6, 9, 3)).astype(np.float32)
    t = bk.Texture(img, filter=filt, wrap=wrap)
    uv = _uv_off_edges(4000, -1.3, 2.2, (9, 6))
    ref = (ref_nearest if filt == "nearest" else ref_bilinear)(img.astype(np.float64), uv, wrap)
    got = t.lookup(uv)
    assert got.shape == (4000, 3) and got.dtype == np.float64
    np.testing.assert_allclose(got, ref, atol=2e-6, rtol=0)


def test_lookup_shapes_channels_and_transform():
    img = RNG.random((5, 4, 3)).astype(np.float32)
    uv = RNG.random((3, 7, 2))
    t = bk.Texture(img, filter="bilinear")
    assert t.lookup(uv).shape == (3, 7, 3)
    g = bk.Texture(img, filter="bilinear", channel=1)
    assert g.channels == 1 and g.lookup(uv).shape == (3, 7, 1)
    np.testing.assert_array_equal(g.lookup(uv)[..., 0], t.lookup(uv)[..., 1])
    m = np.array([[2.0, 0.0, 0.25], [0.0, -1.0, 1.0]])
    tt = bk.Texture(img, filter="bilinear", transform=m)
    uv2 = np.stack([2 * uv[..., 0] + 0.25, 1 - uv[..., 1]], -1)
    np.testing.assert_array_equal(tt.lookup(uv), t.lookup(uv2))


def test_srgb_decoding_of_8bit_sources(tmp_path):
    px = RNG.integers(0, 256, (4, 4, 3), dtype=np.uint8)
    c = px / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)   # IEC 61966-2-1
    uv = _uv_off_edges(200, 0, 1, (4, 4))
    want = ref_nearest(lin, uv, "periodic")
    np.testing.assert_allclose(bk.Texture(px, filter="nearest").lookup(uv), want, atol=1e-6)
    # an 8-bit PNG: auto is sRGB, encoding="linear" reads the stored values
    from PIL import Image
    Image.fromarray(px).save(tmp_path / "c.png")
    t = bk.Texture(tmp_path / "c.png", filter="nearest")
    np.testing.assert_allclose(t.lookup(uv), want, atol=1e-6)
    np.testing.assert_allclose(bk.Texture(str(tmp_path / "c.png"), filter="nearest", encoding="linear").lookup(uv),
                               ref_nearest(c, uv, "periodic"), atol=1e-6)
    np.testing.assert_allclose(bk.Texture(px, filter="nearest", encoding="gamma 2.2").lookup(uv),
                               ref_nearest(c ** 2.2, uv, "periodic"), atol=1e-6)


def test_float_image_file_is_linear_and_equals_the_array(tmp_path):
    img = RNG.random((8, 6, 3)).astype(np.float32)
    bk.io.write_image(tmp_path / "a.exr", img)
    uv = RNG.uniform(-0.5, 1.5, (500, 2))
    np.testing.assert_array_equal(bk.Texture(tmp_path / "a.exr").lookup(uv), bk.Texture(img).lookup(uv))


def test_scale_and_invert_after_filtering():
    img = RNG.random((4, 4)).astype(np.float32) * 2
    uv = RNG.random((300, 2))
    base = ref_bilinear(img[..., None].astype(np.float64), uv, "periodic")
    np.testing.assert_allclose(bk.Texture(img, scale=0.5).lookup(uv), 0.5 * base, atol=2e-6)
    # pbrt-v4 FloatImageTexture: max(0, 1 - scale * v)
    np.testing.assert_allclose(bk.Texture(img, scale=0.5, invert=True).lookup(uv),
                               np.maximum(0, 1 - 0.5 * base), atol=2e-6)


def test_mipmapped_lookup_with_derivatives_averages():
    """A trilinear lookup whose footprint covers the whole image returns the image mean."""
    img = RNG.random((16, 16, 1)).astype(np.float32)
    t = bk.Texture(img, filter="trilinear")
    uv = np.full((3, 2), 0.5)
    big = np.array([[1.0, 0.0]] * 3), np.array([[0.0, 1.0]] * 3)
    np.testing.assert_allclose(t.lookup(uv, *big)[:, 0], img.mean(), rtol=1e-4)
    np.testing.assert_allclose(t.lookup(uv)[:, 0], ref_bilinear(img.astype(np.float64), uv, "periodic")[:, 0],
                               atol=2e-6)


def test_procedural_textures_follow_pbrt():
    uv = RNG.uniform(-2, 2, (400, 2))
    red = tx.Constant([1.0, 0.0, 0.0])
    c = tx.Checkerboard(red, 0.25, uscale=4, vscale=3, udelta=0.5, vdelta=0.0)
    s, t = 4 * uv[:, 0] + 0.5, 3 * uv[:, 1]
    even = (np.floor(s) + np.floor(t)) % 2 == 0
    want = np.where(even[:, None], [1.0, 0.0, 0.0], 0.25)
    np.testing.assert_array_equal(c.lookup(uv), want)
    img = RNG.random((4, 4)).astype(np.float32)
    im = bk.Texture(img)
    np.testing.assert_allclose(tx.Scale(im, 3.0).lookup(uv), 3 * im.lookup(uv))
    mix = tx.Mix(red, tx.Constant([0.0, 0.0, 2.0]), im)
    a = im.lookup(uv)
    np.testing.assert_allclose(mix.lookup(uv), (1 - a) * [1.0, 0, 0] + a * [0, 0, 2.0])
    assert tx.Constant(0.3).lookup(uv).shape == (400, 1)


def test_checkerboard_filtered_weight_is_the_tent_filtered_checker():
    """pbrt-v4's closed form: the +-1 checker averaged under a tent of half-width 1.5 * |duv|."""
    c = tx.Checkerboard(0.0, 1.0)
    uv = RNG.uniform(0, 4, (50, 2))
    d = RNG.uniform(0.05, 0.8, (50, 2))
    dx, dy = np.stack([d[:, 0], np.zeros(50)], -1), np.stack([np.zeros(50), d[:, 1]], -1)
    w = c.weight(uv, dx, dy)
    t = np.linspace(-1, 1, 20001)
    tent = 1 - np.abs(t)

    def filtered(x, r):
        sq = 1 - 2 * (np.floor(x[:, None] + r[:, None] * t) % 2)
        return np.trapezoid(sq * tent, t, axis=1) / np.trapezoid(tent, t)
    want = 0.5 - filtered(uv[:, 0], 1.5 * d[:, 0]) * filtered(uv[:, 1], 1.5 * d[:, 1]) / 2
    np.testing.assert_allclose(w, want, atol=2e-4)


def test_normals_decode():
    img = RNG.random((4, 4, 3)).astype(np.float32)
    uv = _uv_off_edges(100, 0, 1, (4, 4))
    n = tx.Normals(bk.Texture(img, filter="nearest", encoding="linear")).lookup(uv)
    raw = 2 * ref_nearest(img.astype(np.float64), uv, "periodic") - 1
    np.testing.assert_allclose(n, raw / np.linalg.norm(raw, axis=1, keepdims=True), atol=1e-6)


# ---- textured models
WO = bk.direction(np.radians(np.linspace(5, 80, 24)), np.linspace(0, 6, 24))
WI = bk.direction(np.radians(np.linspace(70, 3, 24)), np.linspace(3, 1, 24))
UV = RNG.random((24, 2))
GREY = RNG.uniform(0.05, 0.6, (5, 7)).astype(np.float32)
RGB = RNG.uniform(0.05, 0.9, (5, 7, 3)).astype(np.float32)


def _cases():
    g, c = bk.Texture(GREY), bk.Texture(RGB)
    return [
        (lambda v: bk.Diffuse(v), c, "reflectance"),
        (lambda v: bk.Conductor.from_metal("Au", alpha=v), g, "alpha"),
        (lambda v: bk.Dielectric(1.5, alpha=v), g, "alpha"),
        (lambda v: bk.Plastic(v, alpha=0.2), c, "reflectance"),
        (lambda v: bk.EON(v, roughness=0.5), c, "reflectance"),
        (lambda v: bk.FilamentStandard(base_color=v, roughness=0.4, metallic=0.5), c, "base_color"),
        (lambda v: bk.FilamentStandard(base_color=[0.5, 0.4, 0.3], roughness=v, metallic=1.0), g, "roughness"),
        (lambda v: bk.CoatedDiffuse(v, alpha=0.1), c, "reflectance"),
    ]


@pytest.mark.parametrize("k", range(len(_cases())))
def test_textured_model_equals_per_element_parameters(k):
    make, tex, name = _cases()[k]
    m = make(tex)
    assert isinstance(m, bk.Textured) and list(m.textures) == [name]
    def per_element(uv):
        return make(tex.lookup(uv)[..., 0] if tex.channels == 1 else tex.lookup(uv))
    per = per_element(UV)
    np.testing.assert_array_equal(m.eval(WO, WI, uv=UV), per.eval(WO, WI))
    np.testing.assert_array_equal(m.pdf(WO, WI, uv=UV), per.pdf(WO, WI))
    a, b = m.sample(WO, n=24, seed=3, uv=UV), per.sample(WO, n=24, seed=3)
    np.testing.assert_array_equal(a.wi, b.wi)
    np.testing.assert_array_equal(a.f, b.f)
    np.testing.assert_array_equal(m.albedo(WO[:4], 256, uv=UV[:4]), per_element(UV[:4]).albedo(WO[:4], 256))
    assert m.at(UV) == per


def test_textured_values_against_scalar_models():
    """Element by element: the model built with the texel's value (nearest: exact float32 values)."""
    t = bk.Texture(GREY, filter="nearest")
    m = bk.Conductor.from_metal("Cu", alpha=t)
    uv = _uv_off_edges(24, 0, 1, (7, 5))
    f = m.eval(WO, WI, uv=uv)
    for i in range(24):
        a = float(GREY[int(uv[i, 1] * 5), int(uv[i, 0] * 7)])
        np.testing.assert_array_equal(f[i], bk.Conductor.from_metal("Cu", alpha=a).eval(WO[i], WI[i]))


def test_textured_composites_and_value_semantics():
    d = bk.Diffuse(bk.Texture(RGB))
    m = bk.Mix(d, bk.Conductor.from_metal("Cu", alpha=bk.Texture(GREY)), weight=bk.Texture(GREY))
    assert isinstance(m, bk.Textured) and set(m.textures) == {"a", "b", "weight"}
    per = m.at(UV)
    np.testing.assert_array_equal(m.eval(WO, WI, uv=UV), per.eval(WO, WI))
    for x in (m, d, bk.Texture(RGB), tx.Checkerboard(tx.Constant([1, 0, 0]), 0.5, uscale=3)):
        y = pickle.loads(pickle.dumps(x))
        assert y == x and hash(y) == hash(x) and repr(y) == repr(x)
    assert bk.Diffuse(bk.Texture(RGB)) != bk.Diffuse(bk.Texture(RGB * 0.5))
    assert "digest" in repr(d) and len(repr(d)) < 200


def test_bad_input_names_the_parameter(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.png"):
        bk.Texture(tmp_path / "nope.png")
    (tmp_path / "bad.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 20)
    with pytest.raises(OSError, match="bad.png"):
        bk.Texture(tmp_path / "bad.png")
    with pytest.raises(ValueError, match="source: pixels must be finite.*\\(1, 2\\)"):
        bk.Texture(np.array([[0.0, 1, 2], [0, 1, np.nan]]))
    with pytest.raises(ValueError, match="filter"):
        bk.Texture(GREY, filter="lanczos")
    with pytest.raises(ValueError, match="wrap"):
        bk.Texture(GREY, wrap="repeat")
    t = bk.Texture(GREY)
    with pytest.raises(ValueError, match=r"uv: entries must be finite.*index \(2,\)"):
        t.lookup([[0, 0], [0.5, 0.5], [np.nan, 0]])
    with pytest.raises(ValueError, match="alpha: a real parameter takes a 1-channel texture"):
        bk.Conductor.from_metal("Cu", alpha=bk.Texture(RGB))
    with pytest.raises(ValueError, match="alpha: entries must be finite and >= 0"):
        bk.Conductor.from_metal("Cu", alpha=bk.Texture(GREY - 1))
    with pytest.raises(TypeError, match="dfg_lut_size"):
        bk.FilamentStandard(base_color=bk.Texture(RGB), dfg_lut_size=bk.Texture(GREY))
    m = bk.Diffuse(bk.Texture(RGB))
    with pytest.raises(ValueError, match="uv: Diffuse has textured parameters"):
        m.eval(WO, WI)
    with pytest.raises(ValueError, match=r"uv: expected shape \(\.\.\., 2\)"):
        m.eval(WO, WI, uv=np.zeros((24, 3)))
    with pytest.raises(NotImplementedError, match="spectral mode"):
        m.eval(WO, WI, uv=UV, wavelengths=np.full((24, 4), 550.0))
    with pytest.raises(NotImplementedError, match=r"tradeoff .*m\.at\(\[u, v\]\)"):
        bk.tradeoff(m)
    with pytest.raises(NotImplementedError, match=r"preview renderer does not look textures up.*at\(\[u, v\]\)"):
        bk.render.preview(m)


@pytest.mark.parametrize("method", ["linear", "stochastic"])
def test_textured_composites_on_an_image_of_uv(method):
    """Composites around textured children, called with (H, W) uv: element by element the
    composite of uniform models built from that element's texel values."""
    rng = np.random.default_rng(11)
    d = bk.Diffuse(bk.Texture(RGB, filter="nearest"))
    c = bk.Conductor.from_metal("Cu", alpha=bk.Texture(GREY, filter="nearest"))
    w = bk.Texture(GREY * 1.5, filter="nearest")
    uv = rng.random((3, 4, 2))
    wo = bk.direction(np.full((3, 4), 0.5), rng.random((3, 4)) * 6)
    wi = bk.direction(np.full((3, 4), 0.4), rng.random((3, 4)) * 6)
    cases = [bk.Mix(d, c, weight=w, method=method), bk.TwoSided(d, c), bk.Mask(c, opacity=w)]
    for m in cases:
        f = m.eval(wo, wi * [1, 1, -1] if isinstance(m, bk.Textured) and m.model_class is bk.TwoSided else wi, uv=uv)
        s = m.sample(wo, n=4, seed=5, uv=uv)
        assert f.shape == (3, 4, 3) and s.wi.shape == (3, 4, 3)
        flat = m.at(uv.reshape(-1, 2))
        s2 = flat.sample(wo.reshape(-1, 3), n=12, seed=5)
        np.testing.assert_array_equal(s.f.reshape(-1, 3), s2.f)
        np.testing.assert_array_equal(s.pdf.reshape(-1), s2.pdf)
    m = cases[0]
    f = m.eval(wo, wi, uv=uv).reshape(-1, 3)
    for i, (x, y) in enumerate(uv.reshape(-1, 2)):
        r, col = int(y * 5), int(x * 7)
        one = bk.Mix(bk.Diffuse(RGB[r, col].astype(np.float64)),
                     bk.Conductor.from_metal("Cu", alpha=float(GREY[r, col])),
                     weight=float(np.float32(GREY[r, col] * 1.5)), method=method)
        np.testing.assert_array_equal(f[i], one.eval(wo.reshape(-1, 3)[i], wi.reshape(-1, 3)[i]))


def test_composites_around_per_element_maps_of_any_shape():
    """Without textures: children with (H, W) parameter maps broadcast with the composite's call;
    element by element the composite of uniform models (nested composites too)."""
    rng = np.random.default_rng(4)
    R, A, W = rng.random((3, 4, 3)), rng.uniform(0.1, 0.5, (3, 4)), rng.random((3, 4))
    wo = bk.direction(0.5, 0.3)
    wi = bk.direction(np.full((3, 4), 0.4), rng.random((3, 4)) * 6)
    inner = bk.Mix(bk.Diffuse(R), bk.Diffuse(0.2), weight=W)
    m = bk.Mix(inner, bk.Conductor.from_metal("Cu", alpha=A), weight=0.3, method="stochastic", key=np.arange(12).reshape(3, 4))
    f, p = m.eval(wo, wi), m.pdf(wo, wi)
    assert m.sample(wo, n=4, seed=1).f.shape == (3, 4, 3)
    for i in range(3):
        for j in range(4):
            one = bk.Mix(bk.Mix(bk.Diffuse(R[i, j]), bk.Diffuse(0.2), weight=float(W[i, j])),
                         bk.Conductor.from_metal("Cu", alpha=float(A[i, j])), weight=0.3, method="stochastic",
                         key=4 * i + j)
            np.testing.assert_array_equal(f[i, j], one.eval(wo, wi[i, j]))
            np.testing.assert_array_equal(p[i, j], one.pdf(wo, wi[i, j]))


def test_png_with_alpha_reads_its_stored_colour(tmp_path):
    """OpenImageIO multiplies a PNG's colour by its alpha by default; a texture (and bk.io) reads
    the stored values: (64, 124, 231, alpha 128) stays (64, 124, 231)."""
    from PIL import Image
    px = np.zeros((2, 2, 4), np.uint8)
    px[...] = (64, 124, 231, 128)
    Image.fromarray(px, "RGBA").save(tmp_path / "a.png")
    np.testing.assert_allclose(bk.io.read_image(tmp_path / "a.png", linear=False)[0, 0] * 255, px[0, 0], atol=1e-3)
    t = bk.Texture(tmp_path / "a.png", filter="nearest", encoding="linear")
    np.testing.assert_allclose(t.lookup([0.25, 0.25]) * 255, px[0, 0], atol=1e-3)
    c = px[0, 0, :3] / 255.0
    srgb = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    rgba = bk.Texture(tmp_path / "a.png", filter="nearest").lookup([0.25, 0.25])
    np.testing.assert_allclose(rgba[:3], srgb, atol=1e-6)
    np.testing.assert_allclose(rgba[3], 128 / 255, atol=1e-6)     # alpha is not sRGB-decoded
