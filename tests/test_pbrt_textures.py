"""pbrt-v4 import as scene files write it (issue 48, item 2): ``Texture`` statements (imagemap, scale,
mix, checkerboard, constant), texture-valued material parameters, ``mix`` with a texture amount,
``interface``, ``measured``, ``normalmap`` and ``displacement``.

Expected values are written from pbrt-v4's ``src/pbrt/textures.cpp`` / ``materials.cpp`` /
``materials.h`` semantics with numpy on the pixels the tests write (an independent bilinear
lookup and sRGB decode), never from the importer's output.
"""
import os
import warnings

import numpy as np
import pytest

import bsdfkit as bk

PIL = pytest.importorskip("PIL.Image")
pytest.importorskip("bsdfkit._render")

RNG = np.random.default_rng(48)
# 4 x 3 RGB image: pixel values 0..255, rows top to bottom as stored
PX = RNG.integers(0, 256, size=(3, 4, 3)).astype(np.uint8)
# uv points (pbrt's convention: v = 0 at the bottom of the image), away from texel boundaries
UV = np.array([[0.1, 0.2], [0.37, 0.81], [0.62, 0.45], [0.93, 0.07], [1.3, -0.4]])


def srgb_decode(c):
    """IEC 61966-2-1 sRGB to linear (pbrt-v4 SRGBColorEncoding)."""
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def bilerp(img, s, t):
    """pbrt-v4 Image::Bilerp with repeat wrap: texel (x, y) centred at ((x + 0.5) / W, (y + 0.5) / H),
    (s, t) in the image's coordinates (t = 0 at the first row)."""
    h, w = img.shape[:2]
    x, y = s * w - 0.5, t * h - 0.5
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    dx, dy = (x - x0)[..., None], (y - y0)[..., None]

    def px(i, j):
        return img[np.mod(j, h), np.mod(i, w)]
    return ((1 - dx) * (1 - dy) * px(x0, y0) + dx * (1 - dy) * px(x0 + 1, y0) + (1 - dx) * dy * px(x0, y0 + 1)
            + dx * dy * px(x0 + 1, y0 + 1))


def pbrt_image(img_linear, uv, su=1.0, sv=1.0, du=0.0, dv=0.0):
    """pbrt-v4 ImageTexture: st = (su u + du, sv v + dv), then t flipped (st[1] = 1 - st[1])."""
    s = su * uv[:, 0] + du
    t = 1 - (sv * uv[:, 1] + dv)
    return bilerp(img_linear, s, t)


@pytest.fixture
def scene(tmp_path):
    """Writes ``c.png`` (PX) into a scene directory; returns a function writing and importing a scene."""
    PIL.fromarray(PX).save(tmp_path / "c.png")

    def load(text, name="scene.pbrt", **kw):
        path = tmp_path / name
        path.write_text(text)
        return bk.from_pbrt(path, **kw)
    load.dir = tmp_path
    return load


def _at(m, uv=UV):
    return m.at(uv)


def test_imagemap_reflectance_bilinear_srgb(scene):
    """A spectrum imagemap of an 8-bit PNG: sRGB-decoded (pbrt-v4's default for .png), bilinear,
    repeat wrap, v flipped, with the uv mapping's scale and offset; diffuse clamps to [0, 1]."""
    ms = scene('Texture "img" "spectrum" "imagemap" "string filename" "c.png"\n'
               'Texture "img2" "spectrum" "imagemap" "string filename" "c.png" "float uscale" 2 "float vscale" 3\n'
               '  "float udelta" 0.25 "float vdelta" -0.1\n'
               'MakeNamedMaterial "a" "string type" "diffuse" "texture reflectance" "img"\n'
               'MakeNamedMaterial "b" "string type" "diffuse" "texture reflectance" "img2"\n')
    lin = srgb_decode(PX / 255.0)
    np.testing.assert_allclose(_at(ms["a"]).reflectance, pbrt_image(lin, UV), rtol=0, atol=2e-6)
    np.testing.assert_allclose(_at(ms["b"]).reflectance, pbrt_image(lin, UV, 2, 3, 0.25, -0.1), rtol=0, atol=2e-6)
    # eval at uv = the Diffuse of the hand-computed reflectance at each point
    wo, wi = bk.direction(0.4, 0.1), bk.direction(0.7, 2.0)
    f = ms["a"].eval(np.broadcast_to(wo, UV.shape[:1] + (3,)), np.broadcast_to(wi, UV.shape[:1] + (3,)), uv=UV)
    np.testing.assert_allclose(f, pbrt_image(lin, UV) / np.pi, rtol=0, atol=1e-6)


def test_imagemap_options(scene):
    """encoding, scale, invert (max(0, 1 - scale v), pbrt-v4 FloatImageTexture), filter point, wrap
    clamp, and a float texture of an RGB image reading channel 0 (pbrt-v4 MIPMap texel<Float>)."""
    ms = scene('Texture "lin" "float" "imagemap" "string filename" "c.png" "string encoding" "linear"\n'
               'Texture "inv" "float" "imagemap" "string filename" "c.png" "string encoding" "linear"\n'
               '   "float scale" 0.5 "bool invert" true\n'
               'Texture "pt" "spectrum" "imagemap" "string filename" "c.png" "string filter" "point"\n'
               '   "string wrap" "clamp" "string encoding" "gamma 2.2"\n'
               'MakeNamedMaterial "lin" "string type" "dielectric" "texture roughness" "lin"\n'
               '   "bool remaproughness" false\n'
               'MakeNamedMaterial "inv" "string type" "dielectric" "texture roughness" "inv"\n'
               '   "bool remaproughness" false\n'
               'MakeNamedMaterial "pt" "string type" "diffuse" "texture reflectance" "pt"\n')
    raw = PX / 255.0
    r = pbrt_image(raw[..., :1], UV)[:, 0]
    np.testing.assert_allclose(_at(ms["lin"]).alpha_x, r, atol=2e-6)
    np.testing.assert_allclose(_at(ms["lin"]).alpha_y, r, atol=2e-6)
    np.testing.assert_allclose(_at(ms["inv"]).alpha_x, np.maximum(0, 1 - 0.5 * r), atol=2e-6)
    # point filter, clamp wrap: the texel containing (s, t) of the clamped coordinates
    s, t = UV[:, 0], 1 - UV[:, 1]
    i = np.clip(np.floor(s * 4).astype(int), 0, 3)
    j = np.clip(np.floor(t * 3).astype(int), 0, 2)
    np.testing.assert_allclose(_at(ms["pt"]).reflectance, raw[j, i] ** 2.2, atol=2e-6)


def test_roughness_textures_remapped(scene):
    """roughness / uroughness / vroughness textures: alpha = sqrt(value) per lookup with
    remaproughness true (pbrt-v4 TrowbridgeReitzDistribution::RoughnessToAlpha), as given without."""
    common = 'Texture "r" "float" "imagemap" "string filename" "c.png" "string encoding" "linear"\n'
    ms = scene(common + 'MakeNamedMaterial "c" "string type" "conductor" "texture uroughness" "r"\n'
               '   "float vroughness" 0.25\n'
               'MakeNamedMaterial "d" "string type" "coateddiffuse" "texture roughness" "r"\n'
               '   "bool remaproughness" false\n'
               'MakeNamedMaterial "cc" "string type" "coatedconductor" "texture conductor.roughness" "r"\n'
               '   "float interface.roughness" 0.04\n')
    r = pbrt_image(PX[..., :1] / 255.0, UV)[:, 0]
    c = _at(ms["c"])
    np.testing.assert_allclose(c.alpha_x, np.sqrt(r), atol=2e-6)
    assert np.all(c.alpha_y == 0.5)
    d = _at(ms["d"])
    np.testing.assert_allclose(d.alpha_x, r, atol=2e-6)
    cc = _at(ms["cc"])
    np.testing.assert_allclose(cc.conductor_alpha_x, np.sqrt(r), atol=2e-6)
    np.testing.assert_allclose(cc.conductor_alpha_y, np.sqrt(r), atol=2e-6)
    assert np.all(cc.interface_alpha_x == 0.2)


def test_checkerboard_constant_scale_mix(scene):
    """checkerboard (tex1 where floor(s) + floor(t) is even), constant, scale (tex * scale) and mix
    ((1 - amount) tex1 + amount tex2), nested through named textures, in pbrt-v4's uv (no flip)."""
    ms = scene('Texture "k" "spectrum" "checkerboard" "float uscale" 2 "float vscale" 2 "rgb tex1" [0.9 0.1 0.1]\n'
               '   "texture tex2" "half"\n'
               'Texture "grey" "spectrum" "constant" "rgb value" [0.8 0.6 0.4]\n'
               'Texture "half" "spectrum" "scale" "texture tex" "grey" "float scale" 0.5\n'
               'Texture "amt" "float" "checkerboard" "float uscale" 2 "float vscale" 2 "float tex1" 0.25\n'
               '   "float tex2" 0.75\n'
               'Texture "m" "spectrum" "mix" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1] "texture amount" "amt"\n'
               'MakeNamedMaterial "k" "string type" "diffuse" "texture reflectance" "k"\n'
               'MakeNamedMaterial "m" "string type" "diffuse" "texture reflectance" "m"\n')
    uv = np.array([[0.1, 0.1], [0.6, 0.1], [0.1, 0.6], [0.6, 0.6], [1.2, 0.3]])
    even = np.array([True, False, False, True, True])   # floor(2u) + floor(2v) even
    want = np.where(even[:, None], [0.9, 0.1, 0.1], [0.4, 0.3, 0.2])
    np.testing.assert_allclose(ms["k"].at(uv).reflectance, want, rtol=1e-15)
    a = np.where(even, 0.25, 0.75)[:, None]
    np.testing.assert_allclose(ms["m"].at(uv).reflectance, (1 - a) * [1, 0, 0] + a * [0, 0, 1], rtol=1e-15)


def test_mix_material_texture_amount(scene):
    """pbrt-v4 mix with a float texture amount: bk.Mix(..., method="stochastic") whose weight is
    the amount per lookup, clamped to [0, 1] (MixMaterial: <= 0 the first, >= 1 the second)."""
    ms = scene('Texture "a" "float" "imagemap" "string filename" "c.png" "string encoding" "linear" "float scale" 2\n'
               'Texture "s" "float" "scale" "texture tex" "a" "float scale" -1\n'
               'MakeNamedMaterial "red" "string type" "diffuse" "rgb reflectance" [0.8 0.1 0.1]\n'
               'MakeNamedMaterial "gold" "string type" "conductor" "spectrum eta" "metal-Au-eta"\n'
               '   "spectrum k" "metal-Au-k"\n'
               'MakeNamedMaterial "m" "string type" "mix" "string materials" ["red" "gold"] "texture amount" "a"\n'
               'MakeNamedMaterial "neg" "string type" "mix" "string materials" ["red" "gold"] "texture amount" "s"\n')
    m = ms["m"].at(UV)
    assert m.method == "stochastic" and m.a == ms["red"] and m.b == ms["gold"]
    v = 2 * pbrt_image(PX[..., :1] / 255.0, UV)[:, 0]
    np.testing.assert_allclose(m.weight, np.clip(v, 0, 1), atol=4e-6)
    assert np.all(ms["neg"].at(UV).weight == 0)


def test_conductor_reflectance_texture(scene):
    """pbrt-v4 ConductorMaterial with a reflectance texture: eta = 1, k = 2 sqrt(r) / sqrt(1 - r),
    r clamped to [0, 0.9999] per lookup; coatedconductor likewise, eta / k textures as given."""
    ms = scene('Texture "img" "spectrum" "imagemap" "string filename" "c.png"\n'
               'Texture "k" "spectrum" "scale" "texture tex" "img" "float scale" 3\n'
               'MakeNamedMaterial "c" "string type" "conductor" "texture reflectance" "img"\n'
               'MakeNamedMaterial "cc" "string type" "coatedconductor" "texture reflectance" "img"\n'
               'MakeNamedMaterial "ek" "string type" "conductor" "rgb eta" [0.2 0.3 0.4] "texture k" "k"\n')
    r = np.clip(pbrt_image(srgb_decode(PX / 255.0), UV), 0, 0.9999)
    k = 2 * np.sqrt(r) / np.sqrt(1 - r)
    c = _at(ms["c"])
    assert np.all(c.eta == 1)
    np.testing.assert_allclose(c.k, k, rtol=2e-5, atol=1e-6)
    cc = _at(ms["cc"])
    np.testing.assert_allclose(cc.conductor_k, k, rtol=2e-5, atol=1e-6)
    ek = _at(ms["ek"])
    np.testing.assert_allclose(ek.k, 3 * pbrt_image(srgb_decode(PX / 255.0), UV), atol=6e-6)


def test_layered_textures(scene):
    """coateddiffuse: reflectance and albedo (``_params``: ``.albedo`` is the method) clamped to
    [0, 1], g to [-1, 1], thickness as given
    (pbrt-v4 CoatedDiffuseMaterial::GetBxDF)."""
    ms = scene('Texture "t" "float" "imagemap" "string filename" "c.png" "string encoding" "linear"\n'
               'Texture "g" "float" "scale" "texture tex" "t" "float scale" 4\n'
               'Texture "alb" "spectrum" "scale" "rgb tex" [0.5 1 2] "texture scale" "t"\n'
               'MakeNamedMaterial "cd" "string type" "coateddiffuse" "texture thickness" "t" "texture g" "g"\n'
               '   "texture albedo" "alb"\n')
    t = pbrt_image(PX[..., :1] / 255.0, UV)[:, 0]
    cd = _at(ms["cd"])
    np.testing.assert_allclose(cd.thickness, t, atol=2e-6)
    np.testing.assert_allclose(cd.g, np.clip(4 * t, -1, 1), atol=8e-6)
    np.testing.assert_allclose(cd._params["albedo"], np.clip(t[:, None] * [0.5, 1, 2], 0, 1), atol=4e-6)


def test_normalmap(scene, tmp_path):
    """"string normalmap": the image read linearly, bilinear with repeat wrap at (u, 1 - v), decoded as
    normalize(2 rgb - 1) (pbrt-v4 NormalMap()), -> bk.NormalMap with pbrt's rules (no flip of invalid
    normals, no shadow terminator)."""
    n = RNG.normal(size=(3, 4, 3)) * [0.4, 0.4, 1]
    n[..., 2] = np.abs(n[..., 2]) + 0.3
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    px = np.round((n + 1) / 2 * 255).astype(np.uint8)
    PIL.fromarray(px).save(tmp_path / "n.png")
    ms = scene('MakeNamedMaterial "nm" "string type" "diffuse" "rgb reflectance" [0.5 0.5 0.5]\n'
               '   "string normalmap" "n.png"\n')
    m = _at(ms["nm"])
    assert isinstance(m, bk.NormalMap) and m.model == bk.Diffuse(0.5)
    assert m.flip_invalid_normals is False and m.shadowing is False
    want = 2 * pbrt_image(px / 255.0, UV) - 1
    want /= np.linalg.norm(want, axis=-1, keepdims=True)
    np.testing.assert_allclose(m.normals, want, atol=5e-6)


def test_displacement_bump(scene):
    """"texture displacement" -> bk.BumpMap with pbrt-v4 BumpMap()'s forward differences: du = dv =
    0.0005 without uv derivatives, (d(u + du, v) - d(u, v)) / du."""
    ms = scene('Texture "h" "float" "imagemap" "string filename" "c.png" "string encoding" "linear"\n'
               'MakeNamedMaterial "b" "string type" "diffuse" "texture displacement" "h"\n')
    m = _at(ms["b"])
    assert isinstance(m, bk.BumpMap) and m.model == bk.Diffuse(0.5)
    h = PX[..., :1] / 255.0
    d = 0.0005
    h0 = pbrt_image(h, UV)[:, 0]
    np.testing.assert_allclose(m.dh_du, (pbrt_image(h, UV + [d, 0])[:, 0] - h0) / d, rtol=0, atol=1e-3)
    np.testing.assert_allclose(m.dh_dv, (pbrt_image(h, UV + [0, d])[:, 0] - h0) / d, rtol=0, atol=1e-3)


def test_measured(tmp_path):
    """measured "string filename" (relative to the scene file) -> bk.Measured of that file."""
    bk.measured.tabulate(bk.Diffuse(0.5), resolution=8).save(tmp_path / "d.bsdf")
    path = tmp_path / "s.pbrt"
    path.write_text('MakeNamedMaterial "m" "string type" "measured" "string filename" "d.bsdf"\n'
                    'MakeNamedMaterial "gone" "string type" "measured" "string filename" "nope.bsdf"\n')
    with pytest.warns(bk.interop.PbrtSkipWarning, match=r"'gone' \(measured, line 2\): parameter 'filename': no "
                                                        r"measured BSDF file '.*nope\.bsdf'"):
        ms = bk.from_pbrt(path, skip_unsupported=True)
    assert ms == {"m": bk.Measured(str(tmp_path / "d.bsdf"))}


def test_interface_skip():
    """interface (and none): no BSDF; skipped with their own reason, an error otherwise."""
    text = 'MakeNamedMaterial "water-air" "string type" "interface"\nMaterial "diffuse"'
    with pytest.raises(ValueError, match=r"'water-air' \(interface, line 1\): 'interface' material: no BSDF"):
        bk.from_pbrt(text)
    with pytest.warns(bk.interop.PbrtSkipWarning, match="no BSDF"):
        assert list(bk.from_pbrt(text, skip_unsupported=True)) == ["material#1 (line 2)"]


@pytest.mark.parametrize("text, words", [
    ('Texture "t" "spectrum" "imagemap" "string filename" "missing.png"\nMaterial "diffuse" "texture reflectance" "t"',
     ["line 2", "'reflectance'", "texture 't'", "imagemap, line 1", "no image file", "missing.png"]),
    ('Texture "t" "spectrum" "marble"\n\nMaterial "diffuse" "texture reflectance" "t"',
     ["line 3", "'marble'", "line 1", "unsupported texture class"]),
    ('Texture "t" "float" "fbm"\nMaterial "conductor" "texture roughness" "t"', ["'fbm'", "line 1", "line 2"]),
    ('Texture "t" "float" "ptex" "string filename" "x.ptx"\nMaterial "conductor" "texture roughness" "t"', ["'ptex'"]),
    ('Material "diffuse" "texture reflectance" "nope"', ["no spectrum texture named 'nope'"]),
    ('Texture "r" "float" "constant" "float value" 0.5\nMaterial "diffuse" "texture reflectance" "r"',
     ["no spectrum texture named 'r'", "there is a float texture 'r'"]),
    ('Texture "a" "float" "scale" "texture tex" "b"\nTexture "b" "float" "mix" "texture amount" "a"\n'
     'Material "conductor" "texture roughness" "a"', ["cycle", "a -> b -> a"]),
    ('Texture "k" "float" "checkerboard" "integer dimension" 3\nMaterial "conductor" "texture roughness" "k"',
     ["3-D checkerboard"]),
    ('Texture "k" "float" "checkerboard" "string mapping" "spherical"\nMaterial "conductor" "texture roughness" "k"',
     ["'spherical' mapping"]),
    ('Texture "k" "float" "constant" "float valu" 1\nMaterial "conductor" "texture roughness" "k"', ["'valu'"]),
    ('Texture "t" "float" "constant"\nMaterial "dielectric" "texture eta" "t"', ["'eta'", "only a constant"]),
    ('Material "subsurface" "float scale" 1', ["unsupported material type 'subsurface'"]),
])
def test_texture_errors(text, words):
    with pytest.raises(ValueError) as e:
        bk.from_pbrt(text)
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_texture_parse_errors():
    for text, words in [('Texture "t" "float" "constant"\nTexture "t" "float" "constant"', ["line 2", "redefined",
                                                                                          "line 1"]),
                        ('Texture "t" "colour" "constant"', ["line 1", "'colour'"]),
                        ('Texture "t" "float"', ["line 1", "end of input"])]:
        with pytest.raises(ValueError) as e:
            bk.parse_pbrt_materials(text)
        for w in words:
            assert w in str(e.value), (w, str(e.value))
    # float and spectrum textures have separate names (pbrt-v4); pbrt-v3's "color" is a spectrum
    recs = bk.parse_pbrt_materials('Texture "t" "float" "constant"\nTexture "t" "color" "constant"\nMaterial "diffuse"')
    assert sorted(recs[0].textures) == [("float", "t"), ("spectrum", "t")]
    assert recs[0].textures[("spectrum", "t")].line == 2


def test_skip_names_texture_and_shares_it(scene):
    """With skip_unsupported, a material whose texture cannot be converted is skipped naming it;
    others using supported textures import; an image texture used twice is converted once."""
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        ms = scene('Texture "w" "spectrum" "wrinkled"\nTexture "img" "spectrum" "imagemap" "string filename" "c.png"\n'
                   'MakeNamedMaterial "a" "string type" "diffuse" "texture reflectance" "w"\n'
                   'MakeNamedMaterial "b" "string type" "diffuse" "texture reflectance" "img"\n'
                   'MakeNamedMaterial "c" "string type" "coateddiffuse" "texture reflectance" "img"\n',
                   skip_unsupported=True)
    msgs = [str(x.message) for x in w if issubclass(x.category, bk.interop.PbrtSkipWarning)]
    assert len(msgs) == 1 and "'a'" in msgs[0] and "'wrinkled'" in msgs[0]
    assert list(ms) == ["b", "c"]
    assert ms["b"].textures["reflectance"].tex is ms["c"].textures["reflectance"].tex


def test_image_relative_to_main_scene(scene, tmp_path):
    """Image files are relative to the scene file's directory (pbrt-v4's search directory), also for a
    Texture statement in an included file of another directory."""
    os.mkdir(tmp_path / "sub")
    (tmp_path / "sub" / "tex.pbrt").write_text('Texture "img" "spectrum" "imagemap" "string filename" "c.png"\n')
    ms = scene('Include "sub/tex.pbrt"\nMakeNamedMaterial "a" "string type" "diffuse" "texture reflectance" "img"\n')
    np.testing.assert_allclose(_at(ms["a"]).reflectance, pbrt_image(srgb_decode(PX / 255.0), UV), atol=2e-6)


TEXTURED = '''Texture "img" "spectrum" "imagemap" "string filename" "c.png" "float uscale" 2 "string wrap" "clamp"
Texture "r" "float" "imagemap" "string filename" "c.png" "string encoding" "linear" "float scale" 0.5 "bool invert" true
Texture "k" "spectrum" "checkerboard" "float uscale" 4 "rgb tex1" [0.9 0.1 0.1] "texture tex2" "img"
Texture "s" "float" "scale" "texture tex" "r" "float scale" 2
Texture "m" "float" "mix" "float tex1" 0.1 "texture tex2" "s" "texture amount" "r"
MakeNamedMaterial "a" "string type" "diffuse" "texture reflectance" "k" "texture displacement" "r"
MakeNamedMaterial "b" "string type" "conductor" "texture reflectance" "img" "texture uroughness" "m"
MakeNamedMaterial "c" "string type" "coateddiffuse" "texture reflectance" "img" "texture g" "s"
    "string normalmap" "c.png"
MakeNamedMaterial "d" "string type" "mix" "string materials" ["a" "b"] "texture amount" "m"
'''
TOKENS = ['"', "[", "]", "0", "-1", "1e308", "nan", "inf", '"float', '"texture', '"spectrum', '"imagemap"', '"mix"',
          '"checkerboard"', '"scale"', '"constant"', '"marble"', "Texture", '"c.png"', '"nope.png"', '"r"', '"k"', "\n"]


@pytest.mark.parametrize("seed", range(2))
def test_mutated_textured_scene(scene, seed):
    """Mutated textured scenes (the interop fuzz's mutations, texture tokens): each imports into
    models that evaluate finite at uv, or raises ValueError / OSError naming a line."""
    import random
    rng = random.Random(seed)
    wo, wi = np.broadcast_to(bk.direction(0.4, 0.1), (5, 3)), np.broadcast_to(bk.direction(0.7, 2.0), (5, 3))
    for k in range(60):
        s = list(TEXTURED)
        for _ in range(rng.randint(1, 3)):
            i = rng.randrange(len(s) + 1)
            op = rng.random()
            if op < 0.3 and s:
                del s[min(i, len(s) - 1)]
            elif op < 0.7:
                s.insert(i, rng.choice(TOKENS))
            else:
                s[i:i] = s[i:min(len(s), i + rng.randint(1, 40))]
        text = "".join(s)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ms = scene(text, skip_unsupported=k % 4 != 0)
        except (ValueError, OSError) as e:
            assert "line" in str(e), (str(e), text)
            continue
        for m in ms.values():
            f = m.eval(wo, wi, uv=UV)
            assert np.all(np.isfinite(f)) and np.all(f >= 0), (m, text)


def test_cli_simplify_textured_scene(scene):
    """python -m bsdfkit simplify on a textured scene: the textured material (now imported) is
    simplified with the uniform one, or listed as not simplified where simplify raises
    NotImplementedError; never a failed command."""
    import subprocess
    import sys
    scene('Texture "img" "spectrum" "imagemap" "string filename" "c.png"\n'
          'MakeNamedMaterial "plain" "string type" "diffuse" "rgb reflectance" [0.5 0.4 0.3]\n'
          'MakeNamedMaterial "tex" "string type" "diffuse" "texture reflectance" "img"\n')
    pkg = os.path.dirname(os.path.dirname(bk.__file__))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([pkg, os.environ.get("PYTHONPATH", "")]))
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", str(scene.dir / "scene.pbrt"), "--tol", "1e-2",
                        "-n", "2000"], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "2 material(s)" in r.stdout and "\ntex " in r.stdout
    assert "all 2 material(s) meet tol 0.01" in r.stdout or "1 material(s) not simplified: tex" in r.stdout


def test_float_image_ignores_encoding(scene, tmp_path):
    """An EXR is a float image: pbrt-v4 applies "encoding" to 8-bit images only, so an sRGB encoding
    given for an EXR leaves its values as stored."""
    img = RNG.uniform(0.0, 2.0, size=(3, 4, 3))
    bk.io.write_image(tmp_path / "f.exr", img)
    ms = scene('Texture "f" "spectrum" "imagemap" "string filename" "f.exr" "string encoding" "sRGB"\n'
               'MakeNamedMaterial "c" "string type" "conductor" "texture eta" "f" "rgb k" [1 1 1]\n')
    np.testing.assert_allclose(_at(ms["c"]).eta, pbrt_image(img.astype(np.float32), UV), rtol=1e-6, atol=1e-6)


def test_scene_idioms(scene):
    """Constructs of the public pbrt-v4 scenes, written here: a Texture inside TransformBegin /
    TransformEnd, vscale -1, an imagemap-driven mix scaled for reflectance and for a displacement,
    and a 3-D (wrinkled) displacement, which skips its material naming the texture."""
    want = (r"'couch'.*'displacement': pbrt texture 'swr' \(float scale, line 4\): parameter 'tex': "
            r"pbrt texture 'wr' \(float wrinkled, line 3\): unsupported texture class 'wrinkled'")
    with pytest.warns(bk.interop.PbrtSkipWarning, match=want):
        ms = scene('TransformBegin\n  Scale 3 3 3\n  Texture "wr" "float" "wrinkled"\n'
                   '  Texture "swr" "float" "scale" "texture tex" "wr" "float scale" 0.005\nTransformEnd\n'
                   'MakeNamedMaterial "couch" "string type" "coateddiffuse" "texture displacement" "swr"\n'
                   'Texture "amt" "float" "imagemap" "string filename" "c.png" "float uscale" 2 "float vscale" -2\n'
                   '   "float udelta" -0.5 "float vdelta" 0.5\n'
                   'Texture "kd" "spectrum" "mix" "rgb tex1" [0.01 0.009 0.006] "rgb tex2" [0.036 0.027 0.019]\n'
                   '   "texture amount" "amt"\n'
                   'Texture "kds" "spectrum" "scale" "float scale" 0.8 "texture tex" "kd"\n'
                   'Texture "bump" "float" "mix" "texture amount" "amt" "float tex1" 0 "float tex2" 0.01\n'
                   'MakeNamedMaterial "bark" "string type" "diffuse" "texture reflectance" "kds"\n'
                   '   "texture displacement" "bump"\n', skip_unsupported=True)
    assert list(ms) == ["bark"]
    m = _at(ms["bark"])
    assert isinstance(m, bk.BumpMap)
    a = pbrt_image(srgb_decode(PX[..., :1] / 255.0), UV, 2, -2, -0.5, 0.5)   # png: sRGB by default
    want = 0.8 * ((1 - a) * [0.01, 0.009, 0.006] + a * [0.036, 0.027, 0.019])
    np.testing.assert_allclose(m.model.reflectance, want, rtol=1e-5, atol=1e-8)
