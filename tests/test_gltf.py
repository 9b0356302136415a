"""glTF 2.0 materials -> FilamentStandard (bk.from_gltf, issue 48 item 4).

The assets are written here (JSON, tiny PNGs, a GLB packed by hand from the spec's layout); every
expected parameter follows from the glTF 2.0 specification and its KHR extensions by hand
(factor x texel, sRGB decoding of colour textures, f0 = ((ior - 1) / (ior + 1))^2, ...), and the
imported model is compared with a FilamentStandard built from those numbers -- never with the
importer's own output.
"""
import base64
import json
import math
import struct
import warnings

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.interop.gltf import GltfWarning

WO = bk.direction(np.radians([10.0, 35.0, 60.0, 80.0]), np.radians([0.0, 40.0, 200.0, 300.0]))
WI = bk.direction(np.radians([20.0, 45.0, 70.0, 30.0]), np.radians([180.0, 120.0, 10.0, 90.0]))


def _asset(materials, **extra):
    return dict({"asset": {"version": "2.0"}, "materials": materials}, **extra)


def _write(tmp_path, doc, name="m.gltf"):
    p = tmp_path / name
    p.write_text(json.dumps(doc))
    return p


def _load(path, **kw):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        out = bk.from_gltf(path, **kw)
    return out, [x.message for x in w if isinstance(x.message, GltfWarning)]


def _same(m, ref, **kw):
    a, b = m.eval(WO, WI, **kw), ref.eval(WO, WI, **kw)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=0)


def _srgb(c8):
    """IEC 61966-2-1 decoding of 8-bit values (written out here, not bsdfkit's)."""
    c = np.asarray(c8, dtype=np.float64) / 255
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


# ---------------------------------------------------------------- factors only

def test_defaults_and_factors(tmp_path):
    p = _write(tmp_path, _asset([
        {},                                                        # every default
        {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1, 0.766, 0.336, 1], "metallicFactor": 1,
                                                  "roughnessFactor": 0.3}},
        {"name": "gold"},                                          # a repeated name
    ]))
    mats, warned = _load(p)
    assert list(mats) == ["material#0", "gold", "gold (material#2)"] and not warned
    # glTF defaults: baseColor 1, metallic 1, roughness 1; dielectric f0 0.04 -> reflectance 0.5
    _same(mats["material#0"], bk.FilamentStandard(base_color=1.0, metallic=1.0, roughness=1.0, reflectance=0.5))
    _same(mats["gold"], bk.FilamentStandard(base_color=[1, 0.766, 0.336], metallic=1.0, roughness=0.3,
                                            reflectance=0.5))


def test_roughness_is_perceptual(tmp_path):
    """glTF alpha = roughness^2 (spec Appendix B): with a dielectric, no diffuse and no energy
    compensation, FilamentStandard's lobe at the mirror direction must be GGX with alpha = r^2."""
    r = 0.4
    p = _write(tmp_path, _asset([{"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0,
                                                           "roughnessFactor": r}}]))
    m = _load(p, options={"energy_compensation": False, "f90": "one"})[0]["material#0"]
    wo = bk.direction(0.0, 0.0)
    a = r * r
    d = 1 / (math.pi * a * a)                     # GGX D at h = n
    g = 1.0                                       # Smith at normal incidence
    f0 = 0.04
    expected = f0 * d * g / 4                     # f = F D G / (4 cos_o cos_i), cos = 1
    np.testing.assert_allclose(m.eval(wo, wo), expected, rtol=1e-9)


def test_extensions_factors(tmp_path):
    ior = 1.33
    doc = _asset([{
        "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1], "metallicFactor": 0.25, "roughnessFactor": 0.6},
        "extensions": {
            "KHR_materials_ior": {"ior": ior},
            "KHR_materials_specular": {"specularFactor": 0.8},
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.7, "clearcoatRoughnessFactor": 0.15,
                                        "clearcoatNormalTexture": {"index": 0}},
            "KHR_materials_sheen": {"sheenColorFactor": [0.3, 0.2, 0.1], "sheenRoughnessFactor": 0.45},
            "KHR_materials_emissive_strength": {"emissiveStrength": 5},
            "KHR_materials_iridescence": {"iridescenceFactor": 1},
        },
        "emissiveFactor": [1, 1, 1],
        "occlusionTexture": {"index": 0},
    }])
    mats, warned = _load(_write(tmp_path, doc))
    f0 = ((ior - 1) / (ior + 1)) ** 2 * 0.8       # KHR_materials_ior x KHR_materials_specular
    ref = bk.FilamentStandard(base_color=[0.2, 0.4, 0.6], metallic=0.25, roughness=0.6, reflectance=math.sqrt(f0 / 0.16),
                              clear_coat=0.7, clear_coat_roughness=0.15, sheen_color=[0.3, 0.2, 0.1],
                              sheen_roughness=0.45)
    _same(mats["material#0"], ref)
    (w,) = warned
    text = str(w)
    for item in ("occlusionTexture", "emissive", "KHR_materials_emissive_strength", "KHR_materials_iridescence",
                 "clearcoatNormalTexture", "f90"):
        assert item in text, item
    assert w.material == 0 and w.name == "material#0" and len(w.left_out) == 5


def test_ior_clamped_and_zero(tmp_path):
    doc = _asset([{"extensions": {"KHR_materials_ior": {"ior": 2.6}}}, {"extensions": {"KHR_materials_ior": {"ior": 0}}},
                  {"extensions": {"KHR_materials_ior": {"ior": 1.0}}}])
    mats, warned = _load(_write(tmp_path, doc))
    assert [m.reflectance for m in mats.values()] == [1.0, 1.0, 0.0]
    assert len(warned) == 2 and all("clamped" in str(w) for w in warned)


def test_anisotropy(tmp_path):
    r, s = 0.5, 0.6
    doc = _asset([{"pbrMetallicRoughness": {"roughnessFactor": r},
                   "extensions": {"KHR_materials_anisotropy": {"anisotropyStrength": s, "anisotropyRotation": rot}}}
                  for rot in (0.0, math.pi / 2, math.pi, 0.3)])
    mats, warned = _load(_write(tmp_path, doc))
    a = r * r
    at, ab = a + (1 - a) * s * s, a               # KHR_materials_anisotropy: mix(alpha, 1, strength^2), alpha
    m0, m90, m180, m03 = mats.values()
    # FilamentStandard: alpha_t = roughness^2 (1 + k), alpha_b = roughness^2 (1 - k)
    np.testing.assert_allclose([m0.roughness ** 2 * (1 + m0.anisotropy), m0.roughness ** 2 * (1 - m0.anisotropy)],
                               [at, ab], rtol=1e-14)
    np.testing.assert_allclose([m90.roughness ** 2 * (1 + m90.anisotropy), m90.roughness ** 2 * (1 - m90.anisotropy)],
                               [ab, at], rtol=1e-14)
    assert m180.anisotropy == pytest.approx(m0.anisotropy)
    assert m03.anisotropy == 0 and m03.roughness == r
    assert len(warned) == 1 and "anisotropyRotation" in str(warned[0])


def test_alpha_and_double_sided(tmp_path):
    doc = _asset([
        {"alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 0.3]}},
        {"alphaMode": "MASK", "alphaCutoff": 0.4, "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 0.3]}},
        {"alphaMode": "MASK", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 0.6]}},
        {"doubleSided": True, "alphaMode": "OPAQUE", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 0.2]}},
    ])
    a, b, c, d = _load(_write(tmp_path, doc))[0].values()
    base = bk.FilamentStandard(base_color=0.5, metallic=1.0, roughness=1.0)
    assert isinstance(a, bk.Mask) and a.opacity == 0.3
    _same(a, bk.Mask(base, 0.3))
    assert isinstance(b, bk.Mask) and b.opacity == 0.0          # 0.3 < cutoff 0.4: transparent
    assert isinstance(c, bk.FilamentStandard)                   # 0.6 >= default cutoff 0.5: opaque
    assert isinstance(d, bk.TwoSided)
    _same(d, bk.TwoSided(base))
    wo_below = WO * np.array([1, 1, -1])
    np.testing.assert_allclose(d.eval(wo_below, WI * np.array([1, 1, -1])), base.eval(WO, WI), rtol=1e-12)


def test_options(tmp_path):
    p = _write(tmp_path, _asset([{"pbrMetallicRoughness": {"roughnessFactor": 0.5}}]))
    m = bk.from_gltf(p, options={"diffuse": "burley", "f90": "one"})["material#0"]
    _same(m, bk.FilamentStandard(base_color=1.0, metallic=1.0, roughness=0.5, diffuse="burley", f90="one"))
    with pytest.raises(TypeError, match="not a FilamentStandard option"):
        bk.from_gltf(p, options={"anisotropy": 0.5})


# ---------------------------------------------------------------- bad input

def _glb(doc, binary=None):
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    out = struct.pack("<II", len(js), 0x4E4F534A) + js
    if binary is not None:
        binary += b"\0" * (-len(binary) % 4)
        out += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(out)) + out


@pytest.mark.parametrize("content, match", [
    (b"{not json", r"not valid glTF JSON: .* line 1 column 2"),
    (b"[1, 2]", "a glTF document is a JSON object"),
    (b'{"asset": {"version": "1.0"}, "materials": []}', "glTF 1.0 materials"),
    (b'{"materials": []}', "asset.version"),
    (b"\xff\xfe{}", "not UTF-8"),
    (b'{"asset": {"version": "2.0"}, "materials": {}}', "materials must be a JSON array"),
    (b'{"asset": {"version": "2.0"}, "materials": [{"pbrMetallicRoughness": {"roughnessFactor": 2}}]}',
     r"materials\[0\].*roughnessFactor: expected a number in \[0.0, 1.0\]"),
    (b'{"asset": {"version": "2.0"}, "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 1]}}]}',
     r"materials\[0\].*baseColorFactor: expected 4 numbers"),
    (b'{"asset": {"version": "2.0"}, "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 3}}}]}',
     r"materials\[0\].*baseColorTexture: textures\[3\] does not exist"),
    (b'{"asset": {"version": "2.0"}, "materials": [{"alphaMode": "CLIP"}]}', r"alphaMode"),
    (b'{"asset": {"version": "2.0"}, "materials": [{"extensions": {"KHR_materials_ior": {"ior": 0.5}}}]}',
     r"ior: must be 0 or >= 1"),
    (b"glTF", "truncated GLB header"),
    (struct.pack("<III", 0x46546C67, 1, 12), "version 1"),
    (struct.pack("<III", 0x46546C67, 2, 100), "truncated GLB: the header gives 100 bytes"),
    (struct.pack("<III", 0x46546C67, 2, 20) + struct.pack("<II", 50, 0x4E4F534A), "runs past the end"),
    (struct.pack("<III", 0x46546C67, 2, 12), "has no chunk"),
    (struct.pack("<III", 0x46546C67, 2, 20) + struct.pack("<II", 0, 0x004E4942), "must be JSON"),
])
def test_corrupt(tmp_path, content, match):
    name = "x.glb" if content[:4] == b"glTF" else "x.gltf"
    p = tmp_path / name
    p.write_bytes(content)
    with pytest.raises(ValueError, match=match) as e:
        bk.from_gltf(p)
    assert str(p) in str(e.value)


def test_not_glb_magic(tmp_path):
    p = tmp_path / "x.glb"
    p.write_bytes(b"GLTF" + bytes(20))
    with pytest.raises(ValueError, match="not a GLB file"):
        bk.from_gltf(p)


def test_missing_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.gltf"):
        bk.from_gltf(tmp_path / "nope.gltf")
    doc = _asset([{}, {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
                 textures=[{"source": 0}], images=[{"uri": "missing%20albedo.png"}])
    with pytest.raises(FileNotFoundError, match=r"materials\[1\].*textures\[0\] -> images\[0\]: image file not "
                                                r"found: .*missing albedo.png"):
        bk.from_gltf(_write(tmp_path, doc))
    doc = _asset([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}], textures=[{"source": 0}],
                 images=[{"bufferView": 0, "mimeType": "image/png"}], bufferViews=[{"buffer": 0, "byteLength": 10}],
                 buffers=[{"uri": "lost.bin", "byteLength": 10}])
    with pytest.raises(FileNotFoundError, match=r"materials\[0\].*images\[0\] -> bufferViews\[0\] -> buffers\[0\]: "
                                                r"buffer file not found: .*lost.bin"):
        bk.from_gltf(_write(tmp_path, doc))
    # a missing buffer that no material needs (geometry) is not opened
    doc = _asset([{}], buffers=[{"uri": "geometry.bin", "byteLength": 10}])
    assert list(bk.from_gltf(_write(tmp_path, doc))) == ["material#0"]


def test_bad_buffers(tmp_path):
    base = dict(textures=[{"source": 0}], images=[{"bufferView": 0, "mimeType": "image/png"}])
    mats = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    cases = [
        (dict(bufferViews=[{"buffer": 0, "byteLength": 10}], buffers=[{"uri": "data:application/octet-stream;base64,"
                                                                              "AAAA", "byteLength": 3}]),
         r"bufferViews\[0\] \(bytes 0 to 10\) runs past the end of buffers\[0\] \(3 bytes\)"),
        (dict(bufferViews=[{"buffer": 0, "byteLength": 3}], buffers=[{"uri": "data:application/octet-stream;base64,"
                                                                              "!!!!", "byteLength": 3}]),
         "bad base64"),
        (dict(bufferViews=[{"buffer": 0, "byteLength": 3}], buffers=[{"byteLength": 3}]),
         r"buffers\[0\] has no uri and the GLB file has no BIN chunk"),
        (dict(bufferViews=[{"buffer": 0, "byteLength": 3}], buffers=[{"uri": "data:application/octet-stream;base64,"
                                                                              "AAAA", "byteLength": 3}]),
         "neither PNG nor JPEG"),
    ]
    for extra, match in cases:
        with pytest.raises(ValueError, match=match):
            bk.from_gltf(_write(tmp_path, _asset(mats, **base, **extra)))


def test_glb_factors(tmp_path):
    p = tmp_path / "m.glb"
    p.write_bytes(_glb(_asset([{"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1],
                                                                         "metallicFactor": 0}}]), b"\x01\x02\x03"))
    _same(bk.from_gltf(p)["red"], bk.FilamentStandard(base_color=[0.8, 0.1, 0.1], metallic=0.0, roughness=1.0))


# ---------------------------------------------------------------- textures
#
# 2 x 2 images written with exact 8-bit values (PIL); texel (row i, column j) has its centre at
# uv = ((j + 0.5) / 2, (i + 0.5) / 2): glTF's uv origin is the image's top-left corner.

BASE = np.array([[[255, 128, 0, 255], [64, 124, 231, 128]],
                 [[10, 200, 30, 0], [250, 250, 250, 77]]], dtype=np.uint8)          # RGBA, sRGB colour
MR = np.array([[[0, 51, 255], [9, 204, 0]], [[0, 255, 128], [99, 10, 77]]], dtype=np.uint8)   # G rough, B metal
NORMAL = np.array([[[128, 128, 255], [200, 90, 230]], [[30, 160, 200], [128, 255, 180]]], dtype=np.uint8)
CENTRES = np.array([[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]])   # texels (0,0) (0,1) (1,0) (1,1)
TEXEL = [(0, 0), (0, 1), (1, 0), (1, 1)]
NEAREST = {"magFilter": 9728, "minFilter": 9728}


def _png(path, a):
    from PIL import Image
    Image.fromarray(a).save(path)
    return path


def _texel(img, uv):
    """The texel (row, column) nearest to uv in [0, 1)^2 of a 2 x 2 image."""
    return img[int(uv[1] * 2), int(uv[0] * 2)]


def _textured_doc(tmp_path, images=None, sampler=NEAREST, mat_extra=None, pbr_extra=None, **info_extra):
    _png(tmp_path / "base.png", BASE)
    _png(tmp_path / "mr.png", MR)
    pbr = {"baseColorFactor": [0.9, 0.8, 0.7, 1.0], "baseColorTexture": dict({"index": 0}, **info_extra),
           "metallicFactor": 0.6, "roughnessFactor": 0.8, "metallicRoughnessTexture": dict({"index": 1}, **info_extra)}
    pbr.update(pbr_extra or {})
    mat = dict({"name": "tex", "pbrMetallicRoughness": pbr}, **(mat_extra or {}))
    return _asset([mat], textures=[{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
                  images=images or [{"uri": "base.png"}, {"uri": "mr.png"}], samplers=[sampler])


def _expected(uvs, base_factor=(0.9, 0.8, 0.7), metal=0.6, rough=0.8):
    """FilamentStandard with the per-element parameters the glTF spec gives at the texels of uvs."""
    bc = np.array([np.asarray(base_factor) * _srgb(_texel(BASE, uv)[:3]) for uv in uvs])
    m = np.array([metal * _texel(MR, uv)[2] / 255 for uv in uvs])
    r = np.array([rough * _texel(MR, uv)[1] / 255 for uv in uvs])
    return bk.FilamentStandard(base_color=bc, metallic=m, roughness=r, reflectance=0.5)


def test_textured_base_color_metallic_roughness(tmp_path):
    mats, warned = _load(_write(tmp_path, _textured_doc(tmp_path)))
    m = mats["tex"]
    assert not warned
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), _expected(CENTRES).eval(WO, WI), rtol=1e-6)
    # the spec's own worked example: [64, 124, 231] x [0.2, 1.0, 0.7] -> [0.0102, 0.202, 0.5593]
    np.testing.assert_allclose(_srgb([64, 124, 231]) * [0.2, 1.0, 0.7], [0.0102, 0.202, 0.5593], atol=6e-4)


@pytest.mark.parametrize("wrap, texels", [
    (10497, [(0, 0), (0, 1)]),     # repeat: u 1.25 -> 0.25, u -0.25 -> 0.75
    (33648, [(0, 1), (0, 0)]),     # mirrored repeat: 1.25 -> 0.75, -0.25 -> 0.25
    (33071, [(0, 1), (0, 0)]),     # clamp to edge: the last / first column
])
def test_wrap_modes(tmp_path, wrap, texels):
    doc = _textured_doc(tmp_path, sampler=dict(NEAREST, wrapS=wrap, wrapT=10497))
    m = bk.from_gltf(_write(tmp_path, doc))["tex"]
    uv = np.array([[1.25, 0.25], [-0.25, 0.25]])
    ref_uv = np.array([[(j + 0.5) / 2, (i + 0.5) / 2] for i, j in texels])
    np.testing.assert_allclose(m.eval(WO[:2], WI[:2], uv=uv), _expected(ref_uv).eval(WO[:2], WI[:2]), rtol=1e-6)


def test_bilinear_roughness(tmp_path):
    """magFilter LINEAR: the roughness between two texel centres is the linear blend of G/255."""
    doc = _textured_doc(tmp_path, sampler={"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071})
    doc["materials"][0]["pbrMetallicRoughness"].pop("baseColorTexture")
    m = bk.from_gltf(_write(tmp_path, doc))["tex"]
    uv = np.array([[0.25 + 0.5 * 0.3, 0.25]])      # 30 % of the way from texel (0,0) to (0,1)
    g = (0.7 * MR[0, 0, 1] + 0.3 * MR[0, 1, 1]) / 255
    b = (0.7 * MR[0, 0, 2] + 0.3 * MR[0, 1, 2]) / 255
    ref = bk.FilamentStandard(base_color=[0.9, 0.8, 0.7], metallic=0.6 * b, roughness=0.8 * g)
    np.testing.assert_allclose(m.eval(WO[:1], WI[:1], uv=uv), ref.eval(WO[:1], WI[:1]), rtol=1e-5)


def test_texture_transform(tmp_path):
    off, rot, sc = [0.5, 0.0], math.pi / 2, [0.5, 0.5]
    doc = _textured_doc(tmp_path, sampler=dict(NEAREST), extensions={"KHR_texture_transform": {
        "offset": off, "rotation": rot, "scale": sc}})
    m = bk.from_gltf(_write(tmp_path, doc))["tex"]
    uv = np.array([[0.2, 0.3], [0.9, 0.6], [0.4, 0.95], [0.6, 0.1]])
    # KHR_texture_transform: u' = sx cos u + sy sin v + ox, v' = -sx sin u + sy cos v + oy (its README's
    # example: offset [0, 1], rotation 90 degrees, scale 0.5 maps the unit square onto the lower-left quadrant)
    c, s = math.cos(rot), math.sin(rot)
    ref_uv = np.stack([sc[0] * c * uv[:, 0] + sc[1] * s * uv[:, 1] + off[0],
                       -sc[0] * s * uv[:, 0] + sc[1] * c * uv[:, 1] + off[1]], axis=-1) % 1.0
    np.testing.assert_allclose(m.eval(WO, WI, uv=uv), _expected(ref_uv).eval(WO, WI), rtol=1e-6)


def test_embedded_images_data_uri_and_glb(tmp_path):
    b64 = [base64.b64encode(_png(tmp_path / n, a).read_bytes()).decode() for n, a in (("b.png", BASE), ("m.png", MR))]
    doc = _textured_doc(tmp_path, images=[{"uri": "data:image/png;base64," + x} for x in b64])
    m = bk.from_gltf(_write(tmp_path, doc))["tex"]
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), _expected(CENTRES).eval(WO, WI), rtol=1e-6)
    # GLB: both PNGs in buffer views of the BIN chunk (the second at a 4-aligned offset)
    pngs = [base64.b64decode(x) for x in b64]
    off = len(pngs[0]) + (-len(pngs[0]) % 4)
    binary = pngs[0] + b"\0" * (off - len(pngs[0])) + pngs[1]
    doc = _textured_doc(tmp_path, images=[{"bufferView": 0, "mimeType": "image/png"},
                                          {"bufferView": 1, "mimeType": "image/png"}])
    doc.update(bufferViews=[{"buffer": 0, "byteLength": len(pngs[0])},
                            {"buffer": 0, "byteOffset": off, "byteLength": len(pngs[1])}],
               buffers=[{"byteLength": len(binary)}])
    p = tmp_path / "tex.glb"
    p.write_bytes(_glb(doc, binary))
    m = bk.from_gltf(p)["tex"]
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), _expected(CENTRES).eval(WO, WI), rtol=1e-6)
    # .gltf with the same buffer as an external .bin file (percent-encoded name)
    (tmp_path / "tex data.bin").write_bytes(binary)
    doc["buffers"] = [{"uri": "tex%20data.bin", "byteLength": len(binary)}]
    m = bk.from_gltf(_write(tmp_path, doc))["tex"]
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), _expected(CENTRES).eval(WO, WI), rtol=1e-6)
    del doc["buffers"][0]["uri"]
    # a corrupt embedded PNG: a clear error naming the image
    bad = bytearray(binary)
    bad[20:60] = bytes(40)
    p.write_bytes(_glb(doc, bytes(bad)))
    with pytest.raises(ValueError, match=r"images\[0\]"):
        bk.from_gltf(p)


def test_normal_map(tmp_path):
    _png(tmp_path / "n.png", NORMAL)
    scale = 0.5
    doc = _asset([{"name": "n", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0.0,
                                                         "roughnessFactor": 0.4},
                   "normalTexture": {"index": 0, "scale": scale}}],
                 textures=[{"source": 0, "sampler": 0}], images=[{"uri": "n.png"}], samplers=[NEAREST])
    m = bk.from_gltf(_write(tmp_path, doc))["n"]
    assert m.model_class is bk.NormalMap
    n = np.array([(_texel(NORMAL, uv) / 255 * 2 - 1) * [scale, scale, 1] for uv in CENTRES])
    n /= np.linalg.norm(n, axis=-1, keepdims=True)    # glTF: normalise after scaling
    ref = bk.NormalMap(bk.FilamentStandard(base_color=0.5, metallic=0.0, roughness=0.4), n)
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), ref.eval(WO, WI), rtol=1e-6, atol=1e-12)


def test_alpha_texture_and_extension_textures(tmp_path):
    _png(tmp_path / "base.png", BASE)
    _png(tmp_path / "mr.png", MR)
    doc = _asset([{"name": "x", "alphaMode": "BLEND",
                   "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5], "baseColorTexture": {"index": 0},
                                            "metallicFactor": 0.0, "roughnessFactor": 0.5},
                   "extensions": {
                       "KHR_materials_clearcoat": {"clearcoatFactor": 0.9, "clearcoatTexture": {"index": 1},
                                                   "clearcoatRoughnessFactor": 0.5,
                                                   "clearcoatRoughnessTexture": {"index": 1}},
                       "KHR_materials_sheen": {"sheenColorFactor": [1, 0.5, 0.25], "sheenColorTexture": {"index": 0},
                                               "sheenRoughnessFactor": 0.8, "sheenRoughnessTexture": {"index": 0}}}}],
                 textures=[{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
                 images=[{"uri": "base.png"}, {"uri": "mr.png"}], samplers=[NEAREST])
    m = bk.from_gltf(_write(tmp_path, doc))["x"]
    assert m.model_class is bk.Mask
    px = np.array([_texel(BASE, uv) for uv in CENTRES])
    mr = np.array([_texel(MR, uv) for uv in CENTRES])
    inner = bk.FilamentStandard(
        base_color=_srgb(px[:, :3]), metallic=0.0, roughness=0.5,
        clear_coat=0.9 * mr[:, 0] / 255, clear_coat_roughness=0.5 * mr[:, 1] / 255,     # R and G, linear
        sheen_color=[1, 0.5, 0.25] * _srgb(px[:, :3]), sheen_roughness=0.8 * px[:, 3] / 255)  # sRGB RGB, linear A
    ref = bk.Mask(inner, 0.5 * px[:, 3] / 255)                                          # alpha: linear
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), ref.eval(WO, WI), rtol=1e-6, atol=1e-15)


def test_second_uv_set_left_out(tmp_path):
    doc = _textured_doc(tmp_path, texCoord=1)
    mats, warned = _load(_write(tmp_path, doc))
    assert len(warned) == 1 and "TEXCOORD_1" in str(warned[0]) and "baseColorTexture" in str(warned[0])
    _same(mats["tex"], bk.FilamentStandard(base_color=[0.9, 0.8, 0.7], metallic=0.6, roughness=0.8))


def test_textured_specular_anisotropy_and_mask(tmp_path):
    """KHR_materials_specular's A-channel strength, KHR_materials_anisotropy over a roughness map
    and alphaMode MASK over a texture alpha: nonlinear functions of texels, by hand per texel."""
    doc = _textured_doc(tmp_path, mat_extra={
        "alphaMode": "MASK", "alphaCutoff": 0.4,
        "extensions": {"KHR_materials_ior": {"ior": 1.7},
                       "KHR_materials_specular": {"specularFactor": 0.9, "specularTexture": {"index": 0}},
                       "KHR_materials_anisotropy": {"anisotropyStrength": 0.7}}})
    mats, warned = _load(_write(tmp_path, doc))
    m = mats["tex"]
    assert m.model_class is bk.Mask and len(warned) == 1 and "f90 = specularFactor" in str(warned[0])
    px = np.array([_texel(BASE, uv) for uv in CENTRES])
    mr = np.array([_texel(MR, uv) for uv in CENTRES])
    f0 = ((1.7 - 1) / 2.7) ** 2 * 0.9 * px[:, 3] / 255          # KHR_materials_ior x specularFactor x A
    a = (0.8 * mr[:, 1] / 255) ** 2                            # alpha = roughness^2
    at, ab = a + (1 - a) * 0.49, a                             # KHR_materials_anisotropy
    inner = bk.FilamentStandard(base_color=[0.9, 0.8, 0.7] * _srgb(px[:, :3]), metallic=0.6 * mr[:, 2] / 255,
                                roughness=np.sqrt((at + ab) / 2), anisotropy=(at - ab) / (at + ab),
                                reflectance=np.sqrt(np.minimum(f0, 0.16) / 0.16))
    ref = bk.Mask(inner, (px[:, 3] / 255 >= 0.4).astype(float))
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), ref.eval(WO, WI), rtol=1e-6, atol=1e-15)


def test_textured_models_are_values(tmp_path):
    import pickle
    p = _write(tmp_path, _textured_doc(tmp_path, mat_extra={"normalTexture": {"index": 1, "scale": 2.0}}))
    a, b = bk.from_gltf(p)["tex"], bk.from_gltf(p)["tex"]
    assert a == b and hash(a) == hash(b)
    c = pickle.loads(pickle.dumps(a))
    np.testing.assert_array_equal(c.eval(WO, WI, uv=CENTRES), a.eval(WO, WI, uv=CENTRES))
    np.testing.assert_array_equal(a.at(CENTRES).eval(WO, WI), a.eval(WO, WI, uv=CENTRES))


def test_filters_from_sampler(tmp_path):
    cases = [({}, "bilinear"), ({"magFilter": 9728}, "nearest"), ({"magFilter": 9728, "minFilter": 9984}, "nearest"),
             ({"magFilter": 9729, "minFilter": 9987}, "trilinear"), ({"minFilter": 9986}, "trilinear"),
             ({"magFilter": 9729, "minFilter": 9985}, "bilinear")]
    for sampler, filt in cases:
        doc = _textured_doc(tmp_path, sampler=dict(sampler, wrapS=33071, wrapT=33648))
        t = bk.from_gltf(_write(tmp_path, doc))["tex"].textures["base_color"]
        t = t.a if isinstance(t, bk.interop.gltf.GltfValue) else t
        assert (t.filter, t.wrap) == (filt, ("clamp", "mirror")), sampler


def test_grey_images(tmp_path):
    """A grey image's R, G and B are its grey value; a grey + alpha image's alpha is its second
    channel (PNG colour types 0 and 4)."""
    grey = np.array([[40, 200], [120, 255]], dtype=np.uint8)
    ga = np.stack([grey, 255 - grey], -1)
    _png(tmp_path / "g.png", grey)
    _png(tmp_path / "ga.png", ga)
    doc = _asset([{"name": "g", "alphaMode": "BLEND",
                   "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}, "metallicRoughnessTexture": {"index": 0}}}],
                 textures=[{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
                 images=[{"uri": "g.png"}, {"uri": "ga.png"}], samplers=[NEAREST])
    m = bk.from_gltf(_write(tmp_path, doc))["g"]
    g = np.array([_texel(grey[..., None], uv)[0] for uv in CENTRES])
    ref = bk.Mask(bk.FilamentStandard(base_color=np.repeat(_srgb(g)[:, None], 3, 1), metallic=g / 255,
                                      roughness=g / 255), (255 - g) / 255)
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), ref.eval(WO, WI), rtol=1e-6, atol=1e-15)


def test_textured_lambert_closed_form(tmp_path):
    """With ior 1 (f0 = 0: no specular, f90 = saturate(16.5 sum f0) = 0) and metallic 0, Filament's
    standard model is Lambert: f = baseColor / pi, baseColor = factor x srgb_decode(texel / 255) --
    a closed form, independent of FilamentStandard's parameters."""
    doc = _textured_doc(tmp_path, pbr_extra={"metallicFactor": 0.0, "baseColorFactor": [0.5, 0.25, 1.0, 1.0]},
                        mat_extra={"extensions": {"KHR_materials_ior": {"ior": 1.0}}})
    m = bk.from_gltf(_write(tmp_path, doc))["tex"]
    expected = np.array([[0.5, 0.25, 1.0] * _srgb(_texel(BASE, uv)[:3]) / np.pi for uv in CENTRES])
    np.testing.assert_allclose(m.eval(WO, WI, uv=CENTRES), expected, rtol=1e-6)
