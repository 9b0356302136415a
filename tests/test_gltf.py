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
