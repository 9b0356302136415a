"""bk.from_materialx: MaterialX documents (gltf_pbr, UsdPreviewSurface, image / tiledimage /
normalmap nodes) as FilamentStandard models (open_pbr_surface / standard_surface:
test_materialx_openpbr.py). References: the UsdPreviewSurface spec's and the
glTF 2.0 spec's formulas written here (F0 from ior, alpha = roughness^2, GGX with
height-correlated Smith masking, Schlick Fresnel), Lambert, and texel values decoded here from the
8-bit PNGs the tests write; the documents are this file's own."""
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import bsdfkit as bk

import MaterialX  # noqa: F401,E402  (a test dependency: pyproject.toml's test extra, scripts/setup.sh; no skip)

HEAD = '<?xml version="1.0"?>\n<materialx version="1.39">\n'


def mtlx(body, head=HEAD):
    return head + body + "</materialx>\n"


def usd(name, inputs, shader="UsdPreviewSurface"):
    """A surface shader node with constant / connected inputs and its surfacematerial."""
    rows = "".join(f'    <input name="{n}" type="{t}" {v} />\n' for n, t, v in inputs)
    return (f'  <{shader} name="{name}_sh" type="surfaceshader">\n{rows}  </{shader}>\n'
            f'  <surfacematerial name="{name}" type="material">\n'
            f'    <input name="surfaceshader" type="surfaceshader" nodename="{name}_sh" />\n  </surfacematerial>\n')


def line_of(text, needle):
    return next(i + 1 for i, s in enumerate(text.splitlines()) if needle in s)


def load(text, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bk.interop.MaterialXWarning)
        return bk.from_materialx(text, **kw)


def directions(n=64, seed=3):
    rng = np.random.default_rng(seed)
    th = rng.uniform(0.05, 1.45, (2, n))
    ph = rng.uniform(0, 2 * np.pi, (2, n))
    return bk.direction(th[0], ph[0]), bk.direction(th[1], ph[1])


# ---------------------------------------------------------------- spec formulas (independent of bsdfkit)

def f0_from_ior(ior):
    return ((1 - ior) / (1 + ior)) ** 2          # UsdPreviewSurface spec ("metallic"), glTF KHR_materials_ior


def ggx_d(cos_h, alpha):
    a2 = alpha * alpha
    return a2 / (np.pi * (cos_h ** 2 * (a2 - 1) + 1) ** 2)


def smith_lambda(cos_t, alpha):
    tan2 = (1 - cos_t ** 2) / cos_t ** 2
    return (-1 + np.sqrt(1 + alpha ** 2 * tan2)) / 2


def ggx_schlick(wo, wi, alpha, f0, f90=1.0):
    """GGX with height-correlated Smith masking and Schlick Fresnel (glTF 2.0 spec, Appendix B)."""
    h = wo + wi
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    no, ni, nh, vh = wo[..., 2], wi[..., 2], h[..., 2], np.sum(wo * h, axis=-1)
    g2 = 1 / (1 + smith_lambda(no, alpha) + smith_lambda(ni, alpha))
    f = np.asarray(f0)[None, :] + (f90 - np.asarray(f0)[None, :]) * ((1 - vh) ** 5)[:, None]
    return (ggx_d(nh, alpha) * g2 / (4 * no * ni))[:, None] * f


def srgb_decode(c8):
    c = c8 / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


# ---------------------------------------------------------------- UsdPreviewSurface

@pytest.mark.parametrize("ior", [1.2, 1.5, 2.0])
def test_usd_reflectance_is_the_spec_f0_from_ior(ior):
    m = load(mtlx(usd("m", [("ior", "float", f'value="{ior}"'), ("roughness", "float", 'value="0.3"'),
                             ("diffuseColor", "color3", 'value="0.2, 0.4, 0.6"')])))["m"]
    assert isinstance(m, bk.FilamentStandard)
    assert 0.16 * m.reflectance ** 2 == pytest.approx(f0_from_ior(ior), rel=1e-12)
    assert m.roughness == 0.3 and m.metallic == 0.0 and list(m.base_color) == [0.2, 0.4, 0.6]


def test_usd_defaults_are_the_spec_fallbacks():
    m = load(mtlx(usd("m", [])))["m"]
    # spec fallbacks: diffuseColor 0.18, metallic 0, roughness 0.5, ior 1.5 (F0 0.04), clearcoat 0
    assert list(m.base_color) == [0.18] * 3 and m.metallic == 0 and m.roughness == 0.5
    assert m.reflectance == pytest.approx(0.5, abs=1e-15) and m.clear_coat == 0


def test_usd_diffuse_only_is_lambert():
    """ior 1: F0 = 0, metallic 0: the diffuse lobe alone (FilamentStandard's f90 rule gives F90 = 0 at F0 = 0)."""
    c = np.array([0.7, 0.3, 0.1])
    m = load(mtlx(usd("m", [("ior", "float", 'value="1.0"'), ("diffuseColor", "color3", 'value="0.7, 0.3, 0.1"')])))["m"]
    wo, wi = directions()
    np.testing.assert_allclose(m.eval(wo, wi), np.broadcast_to(c / np.pi, (len(wo), 3)), rtol=1e-12, atol=0)


@pytest.mark.parametrize("metallic", [1.0, 0.4])
def test_usd_metal_at_retroreflection_is_the_spec(metallic):
    """Metalness workflow: F0 = mix(F0(ior), diffuseColor, metallic) ("in between, we interpolate"),
    diffuse diffuseColor (1 - metallic) (MaterialX's graph weights the diffuse so). At wi = wo
    (v.h = 1) Schlick is F0 whatever F90, so FilamentStandard (single scattering) is the spec there."""
    c, r, ior = np.array([0.95, 0.64, 0.54]), 0.4, 1.6
    m = load(mtlx(usd("m", [("metallic", "float", f'value="{metallic}"'), ("roughness", "float", f'value="{r}"'),
                             ("ior", "float", f'value="{ior}"'),
                             ("diffuseColor", "color3", 'value="0.95, 0.64, 0.54"')])),
             options={"energy_compensation": False})["m"]
    wo, _ = directions()
    f0 = (1 - metallic) * f0_from_ior(ior) + metallic * c
    ref = ggx_schlick(wo, wo.copy(), r * r, f0, f90=f0) + (1 - metallic) * c / np.pi   # spec: alpha = roughness^2
    np.testing.assert_allclose(m.eval(wo, wo), ref, rtol=1e-9)


def test_usd_dielectric_specular_is_ggx_schlick():
    """Black diffuse, metallic 0, ior 1.5: the spec's specular lobe F0 0.04 -> white F90, everywhere."""
    r = 0.5
    m = load(mtlx(usd("m", [("diffuseColor", "color3", 'value="0, 0, 0"'), ("roughness", "float", f'value="{r}"')])),
             options={"energy_compensation": False, "f90": "one"})["m"]
    wo, wi = directions()
    np.testing.assert_allclose(m.eval(wo, wi), ggx_schlick(wo, wi, r * r, [0.04] * 3), rtol=1e-9)


def test_usd_specular_workflow():
    grey = load(mtlx(usd("m", [("useSpecularWorkflow", "integer", 'value="1"'),
                                ("specularColor", "color3", 'value="0.09, 0.09, 0.09"'),
                                ("diffuseColor", "color3", 'value="0.5, 0.2, 0.2"')])))["m"]
    assert 0.16 * grey.reflectance ** 2 == pytest.approx(0.09, rel=1e-12) and grey.metallic == 0
    # a black diffuse and a tinted specular: F0 = specularColor, white F90: FilamentStandard's metal
    metal = load(mtlx(usd("m", [("useSpecularWorkflow", "integer", 'value="1"'),
                                 ("specularColor", "color3", 'value="0.9, 0.6, 0.3"'),
                                 ("diffuseColor", "color3", 'value="0, 0, 0"'), ("roughness", "float", 'value="0.3"')])),
                  options={"energy_compensation": False, "f90": "one"})["m"]
    wo, wi = directions()
    np.testing.assert_allclose(metal.eval(wo, wi), ggx_schlick(wo, wi, 0.09, [0.9, 0.6, 0.3]), rtol=1e-9)


def test_usd_clearcoat_and_masks():
    m = load(mtlx(usd("m", [("clearcoat", "float", 'value="0.7"'), ("clearcoatRoughness", "float", 'value="0.2"')])))["m"]
    assert m.clear_coat == 0.7 and m.clear_coat_roughness == 0.2
    cut = load(mtlx(usd("m", [("opacity", "float", 'value="0.3"'), ("opacityThreshold", "float", 'value="0.5"')])))["m"]
    assert isinstance(cut, bk.Mask) and cut.opacity == 0.0
    kept = load(mtlx(usd("m", [("opacity", "float", 'value="0.6"'), ("opacityThreshold", "float", 'value="0.5"')])))["m"]
    assert isinstance(kept, bk.FilamentStandard)
    presence = load(mtlx(usd("m", [("opacity", "float", 'value="0.25"'), ("opacityMode", "integer", 'value="1"')])))["m"]
    assert isinstance(presence, bk.Mask) and presence.opacity == 0.25


def test_notes_warn_once_per_material():
    text = mtlx(usd("m", [("emissiveColor", "color3", 'value="1, 0, 0"'), ("metallic", "float", 'value="1"'),
                          ("diffuseColor", "color3", 'value="0.9, 0.5, 0.2"')]))
    with pytest.warns(bk.interop.MaterialXWarning) as rec:
        bk.from_materialx(text)
    assert len(rec) == 1 and rec[0].message.material == "m"
    assert [s.split(" ")[0] for s in rec[0].message.left_out] == ["metallic:", "emissiveColor"]


def test_srgb_constant_colour_is_decoded():
    m = load(mtlx(usd("m", [("diffuseColor", "color3", 'value="0.5, 0.04, 1" colorspace="srgb_texture"')])))["m"]
    np.testing.assert_allclose(m.base_color, srgb_decode(np.array([0.5, 0.04, 1.0]) * 255), rtol=1e-12)


# ---------------------------------------------------------------- gltf_pbr

GLTF_INPUTS = [("base_color", "color3", 'value="0.9, 0.5, 0.2"'), ("metallic", "float", 'value="0.3"'),
               ("roughness", "float", 'value="0.45"'), ("ior", "float", 'value="1.4"'),
               ("clearcoat", "float", 'value="0.5"'), ("clearcoat_roughness", "float", 'value="0.25"'),
               ("sheen_color", "color3", 'value="0.2, 0.3, 0.4"'), ("sheen_roughness", "float", 'value="0.6"')]


def test_gltf_pbr_parameters_follow_the_gltf_spec():
    m = load(mtlx(usd("g", GLTF_INPUTS, shader="gltf_pbr")))["g"]
    assert list(m.base_color) == [0.9, 0.5, 0.2] and m.metallic == 0.3 and m.roughness == 0.45
    assert 0.16 * m.reflectance ** 2 == pytest.approx(f0_from_ior(1.4), rel=1e-12)   # KHR_materials_ior
    assert (m.clear_coat, m.clear_coat_roughness) == (0.5, 0.25)
    assert list(m.sheen_color) == [0.2, 0.3, 0.4] and m.sheen_roughness == 0.6


def test_gltf_pbr_is_from_gltf_s_mapping(tmp_path):
    import json
    doc = {"asset": {"version": "2.0"}, "materials": [{"name": "g", "pbrMetallicRoughness": {
        "baseColorFactor": [0.9, 0.5, 0.2, 1], "metallicFactor": 0.3, "roughnessFactor": 0.45},
        "extensions": {"KHR_materials_ior": {"ior": 1.4},
                       "KHR_materials_clearcoat": {"clearcoatFactor": 0.5, "clearcoatRoughnessFactor": 0.25},
                       "KHR_materials_sheen": {"sheenColorFactor": [0.2, 0.3, 0.4], "sheenRoughnessFactor": 0.6}}}]}
    (tmp_path / "g.gltf").write_text(json.dumps(doc))
    assert load(mtlx(usd("g", GLTF_INPUTS, shader="gltf_pbr")))["g"] == bk.from_gltf(tmp_path / "g.gltf")["g"]


def test_gltf_pbr_metal_is_ggx_schlick():
    """glTF 2.0 Appendix B: metal = F_schlick(base_color, 1) D V; FilamentStandard with f90 one, single scattering."""
    m = load(mtlx(usd("g", [("base_color", "color3", 'value="1.0, 0.77, 0.34"'), ("roughness", "float", 'value="0.6"')],
                      shader="gltf_pbr")), options={"f90": "one", "energy_compensation": False})["g"]
    wo, wi = directions()
    np.testing.assert_allclose(m.eval(wo, wi), ggx_schlick(wo, wi, 0.36, [1.0, 0.77, 0.34]), rtol=1e-9)


# ---------------------------------------------------------------- textures

@pytest.fixture
def images(tmp_path):
    """8-bit PNGs with known texels: colour (4 x 4 RGB), data (4 x 4 RGB), normals (2 x 2 RGB)."""
    from PIL import Image
    rng = np.random.default_rng(7)
    px = {"colour": rng.integers(0, 256, (4, 4, 3), dtype=np.uint8),
          "data": rng.integers(0, 256, (4, 4, 3), dtype=np.uint8),
          "normals": np.array([[[128, 128, 255], [200, 90, 230]], [[60, 140, 220], [128, 30, 200]]], dtype=np.uint8)}
    os.makedirs(tmp_path / "tex")
    for k, a in px.items():
        Image.fromarray(a).save(tmp_path / "tex" / f"{k}.png")
    return tmp_path, px


def texel(a, uv):
    """The nearest texel of image array ``a`` at MaterialX uv ((0, 0) the lower-left corner)."""
    h, w = a.shape[:2]
    i = np.floor((1 - uv[:, 1]) * h).astype(int)
    j = np.floor(uv[:, 0] * w).astype(int)
    return a[i, j]


TEX_DOC = '''  <nodegraph name="NG">
    <image name="col" type="color3">
      <input name="file" type="filename" value="colour.png" colorspace="srgb_texture" />
      <input name="filtertype" type="string" value="closest" />
    </image>
    <tiledimage name="rough" type="float">
      <input name="file" type="filename" value="data.png" colorspace="srgb_texture" />
      <input name="uvtiling" type="vector2" value="2, 3" />
      <input name="filtertype" type="string" value="closest" />
    </tiledimage>
    <output name="col_out" type="color3" nodename="col" />
    <output name="rough_out" type="float" nodename="rough" />
  </nodegraph>
'''


def test_textured_usd_matches_texels_and_at(images):
    d, px = images
    text = mtlx(TEX_DOC + usd("m", [("diffuseColor", "color3", 'nodegraph="NG" output="col_out"'),
                                    ("roughness", "float", 'nodegraph="NG" output="rough_out"')]),
                head='<?xml version="1.0"?>\n<materialx version="1.39" fileprefix="tex/">\n')
    (d / "m.mtlx").write_text(text)
    m = load(d / "m.mtlx")["m"]
    assert isinstance(m, bk.Textured) and sorted(m.textures) == ["base_color", "roughness"]
    rng = np.random.default_rng(1)
    uv = (rng.integers(0, 24, (40, 2)) + 0.5) / 24   # away from texel edges
    at = m.at(uv)
    # colour image: srgb_texture -> sRGB decoding; nearest texel with v up
    np.testing.assert_allclose(at.base_color, srgb_decode(texel(px["colour"], uv).astype(float)), rtol=1e-6, atol=1e-7)
    # a float image is data: no colour conversion (MaterialX converts colour3/4 images only), channel 0,
    # tiledimage st = uv * uvtiling, periodic
    st = np.mod(uv * [2.0, 3.0], 1.0)
    np.testing.assert_allclose(at.roughness, texel(px["data"], st)[:, 0] / 255.0, rtol=1e-6, atol=1e-7)
    wo, wi = directions(len(uv))
    np.testing.assert_array_equal(m.eval(wo, wi, uv=uv), at.eval(wo, wi))
    per_element = bk.FilamentStandard(base_color=at.base_color, roughness=at.roughness, reflectance=m.reflectance)
    np.testing.assert_array_equal(m.eval(wo, wi, uv=uv), per_element.eval(wo, wi))


def test_gltf_pbr_normalmap(images):
    d, px = images
    text = mtlx('''  <image name="nimg" type="vector3">
    <input name="file" type="filename" value="tex/normals.png" />
    <input name="filtertype" type="string" value="closest" />
  </image>
  <normalmap name="nm" type="vector3">
    <input name="in" type="vector3" nodename="nimg" />
    <input name="scale" type="float" value="0.5" />
  </normalmap>
''' + usd("g", [("normal", "vector3", 'nodename="nm"'), ("base_color", "color3", 'value="0.5, 0.5, 0.5"')],
          shader="gltf_pbr"))
    (d / "n.mtlx").write_text(text)
    m = load(d / "n.mtlx")["g"]
    assert isinstance(m, bk.Textured) and m.model_class is bk.NormalMap
    uv = np.array([[0.25, 0.75], [0.75, 0.75], [0.25, 0.25], [0.75, 0.25]])
    n = (2 * texel(px["normals"], uv).astype(float) / 255.0 - 1) * [0.5, 0.5, 1.0]   # MaterialX normalmap: (2 in - 1) (s, s, 1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    got = next(iter(m.textures.values())).lookup(uv)
    np.testing.assert_allclose(got, n, rtol=1e-6, atol=1e-7)


# ---------------------------------------------------------------- refused and malformed input

def test_truncated_document_names_the_line(tmp_path):
    text = mtlx(usd("m", [("roughness", "float", 'value="0.3"')]))
    p = tmp_path / "t.mtlx"
    p.write_text(text[:text.index("</UsdPreviewSurface>")])
    with pytest.raises(ValueError, match=r"t\.mtlx: not a well-formed MaterialX document: .* at line \d+, column"):
        bk.from_materialx(p)


def test_unknown_node_names_node_and_line():
    text = mtlx('  <multiply name="mul" type="float">\n    <input name="in1" type="float" value="0.5" />\n'
                '  </multiply>\n' + usd("m", [("roughness", "float", 'nodename="mul"')]))
    n = line_of(text, 'name="mul"')
    with pytest.raises(ValueError, match=rf"node 'mul' \(multiply, line {n}\): 'multiply' nodes are not read"):
        bk.from_materialx(text)
    text = mtlx('  <wobble name="w" type="float" />\n' + usd("m", [("roughness", "float", 'nodename="w"')]))
    with pytest.raises(ValueError, match=r"node 'w' \(wobble, line 3\): unknown node 'wobble'"):
        bk.from_materialx(text)
    text = mtlx(usd("m", [], shader="fancy_surface"))
    with pytest.raises(ValueError, match=r"node 'm_sh' \(fancy_surface, line 3\): unknown node"):
        bk.from_materialx(text)


def test_missing_texture_names_path_and_line(tmp_path):
    text = mtlx('  <image name="img" type="color3">\n    <input name="file" type="filename" value="nope.png" />\n'
                '  </image>\n' + usd("m", [("diffuseColor", "color3", 'nodename="img"')]))
    (tmp_path / "m.mtlx").write_text(text)
    with pytest.raises(FileNotFoundError, match=r"input 'file' \(line 4\) of node 'img' \(image, line 3\): "
                                                r"image file not found: .*nope\.png"):
        bk.from_materialx(tmp_path / "m.mtlx")


def test_wrong_type_and_values():
    text = mtlx(usd("m", [("roughness", "color3", 'value="0.1, 0.2, 0.3"')]))
    with pytest.raises(ValueError, match=r"input 'roughness' \(line 4\) of node 'm_sh' \(UsdPreviewSurface, line 3\): "
                                         r"type color3, the UsdPreviewSurface node definition says float"):
        bk.from_materialx(text)
    with pytest.raises(ValueError, match=r"input 'roughness' .*cannot read 'rough' as a float value"):
        bk.from_materialx(mtlx(usd("m", [("roughness", "float", 'value="rough"')])))
    with pytest.raises(ValueError, match=r"input 'metallic' .*1\.5 is outside \[0\.0, 1\.0\]"):
        bk.from_materialx(mtlx(usd("m", [("metallic", "float", 'value="1.5"')])))
    with pytest.raises(ValueError, match=r"unknown input 'shininess'"):
        bk.from_materialx(mtlx(usd("m", [("shininess", "float", 'value="1"')])))


def test_unrepresentable_usd_inputs_refused():
    with pytest.raises(ValueError, match=r"input 'opacity' .*translucent .*no transmission"):
        bk.from_materialx(mtlx(usd("m", [("opacity", "float", 'value="0.5"')])))
    with pytest.raises(ValueError, match=r"input 'specularColor' .*tinted"):
        bk.from_materialx(mtlx(usd("m", [("useSpecularWorkflow", "integer", 'value="1"'),
                                         ("specularColor", "color3", 'value="0.1, 0.05, 0.02"')])))
    with pytest.raises(ValueError, match=r"input 'ior' .*clearcoat > 0 with ior 2: .*IOR 1\.5"):
        bk.from_materialx(mtlx(usd("m", [("clearcoat", "float", 'value="1"'), ("ior", "float", 'value="2"')])))
    with pytest.raises(ValueError, match=r"input 'ior' .*F0 .* above FilamentStandard's 0\.16"):
        bk.from_materialx(mtlx(usd("m", [("ior", "float", 'value="3"')])))
    with pytest.raises(ValueError, match=r"input 'normal' .*other than the constant \(0, 0, 1\)"):
        bk.from_materialx(mtlx(usd("m", [("normal", "vector3", 'value="0.1, 0, 1"')])))


def test_versions_roots_and_arguments(tmp_path, monkeypatch):
    with pytest.raises(ValueError, match=r"<materialx> \(line 2\): version 1\.40 is newer than the MaterialX package"):
        bk.from_materialx(mtlx(usd("m", []), head='<?xml version="1.0"?>\n<materialx version="1.40">\n'))
    with pytest.raises(ValueError, match=r"root element is <scene> \(line 1\), expected <materialx>"):
        bk.from_materialx("<scene />")
    with pytest.raises(FileNotFoundError, match="MaterialX file not found"):
        bk.from_materialx(tmp_path / "none.mtlx")
    with pytest.raises(TypeError, match="got bytes"):
        bk.from_materialx(b"<materialx/>")
    with pytest.raises(TypeError, match="'f99' is not a FilamentStandard option"):
        bk.from_materialx(mtlx(usd("m", [])), options={"f99": 1})
    monkeypatch.setitem(sys.modules, "MaterialX", None)
    with pytest.raises(ImportError, match="pip install materialx"):
        bk.from_materialx(mtlx(usd("m", [])))


def test_cli_simplify_reads_mtlx(tmp_path):
    (tmp_path / "s.mtlx").write_text(mtlx(usd("red", [("diffuseColor", "color3", 'value="0.8, 0.1, 0.1"')])))
    env = dict(os.environ, MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", str(tmp_path / "s.mtlx"), "--tol", "1e-2",
                        "-n", "256"], capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "1 material(s)" in r.stdout and "red" in r.stdout


def test_image_node_options_and_refusals(images):
    d, px = images

    def doc(extra, image_type="color3", target=("diffuseColor", "color3")):
        return mtlx(f'  <image name="img" type="{image_type}">\n'
                    '    <input name="file" type="filename" value="tex/colour.png" />\n' + extra + '  </image>\n'
                    + usd("m", [(target[0], target[1], 'nodename="img"')]))

    def write(text):
        (d / "i.mtlx").write_text(text)
        return d / "i.mtlx"

    t = load(write(doc('    <input name="uaddressmode" type="string" value="clamp" />\n'
                       '    <input name="vaddressmode" type="string" value="mirror" />\n'
                       '    <input name="filtertype" type="string" value="cubic" />\n')))["m"].textures["base_color"]
    assert (t.wrap, t.filter, t.encoding) == (("clamp", "mirror"), "bicubic", "linear")   # no colorspace: linear
    t = load(write(doc('    <input name="uaddressmode" type="string" value="constant" />\n')))["m"].textures["base_color"]
    assert t.wrap == ("black", "periodic")
    with pytest.raises(ValueError, match=r"node 'img' \(image, line 3\): uaddressmode constant with a non-zero default"):
        bk.from_materialx(write(doc('    <input name="uaddressmode" type="string" value="constant" />\n'
                                    '    <input name="default" type="color3" value="1, 0, 0" />\n')))
    tc = mtlx('  <texcoord name="tc" type="vector2">\n    <input name="index" type="integer" value="1" />\n'
              '  </texcoord>\n  <image name="img" type="color3">\n'
              '    <input name="file" type="filename" value="tex/colour.png" />\n'
              '    <input name="texcoord" type="vector2" nodename="tc" />\n  </image>\n'
              + usd("m", [("diffuseColor", "color3", 'nodename="img"')]))
    with pytest.raises(ValueError, match=r"node 'img' \(image, line 6\): texcoord: only the default uv set"):
        bk.from_materialx(write(tc))
    assert load(write(tc.replace('value="1"', 'value="0"')))["m"].textures["base_color"].filter == "bilinear"
    with pytest.raises(ValueError, match=r"node 'img' \(image, line 3\): colorspace 'acescg' of its file"):
        bk.from_materialx(write(doc("").replace('value="tex/colour.png"', 'value="tex/colour.png" colorspace="acescg"')))
    with pytest.raises(ValueError, match=r"input 'diffuseColor' .*connected to node 'img' \(image, line 3\) of type "
                                         r"float, the input is color3"):
        bk.from_materialx(write(doc("", image_type="float")))


def test_nodegraph_interface_and_constant_nodes(images):
    d, px = images
    text = mtlx('''  <nodegraph name="NG">
    <input name="tint" type="color3" value="0.25, 0.5, 0.75" />
    <constant name="c" type="color3">
      <input name="value" type="color3" interfacename="tint" />
    </constant>
    <output name="out" type="color3" nodename="c" />
  </nodegraph>
''' + usd("m", [("diffuseColor", "color3", 'nodegraph="NG" output="out"')]))
    assert list(load(text)["m"].base_color) == [0.25, 0.5, 0.75]


def test_gltf_pbr_textured_metallic_roughness(images):
    """gltf_pbr's metallic and roughness from two float images: each its own texture, channel 0."""
    d, px = images
    text = mtlx('''  <image name="met" type="float">
    <input name="file" type="filename" value="tex/data.png" />
    <input name="filtertype" type="string" value="closest" />
  </image>
  <image name="rgh" type="float">
    <input name="file" type="filename" value="tex/colour.png" />
    <input name="filtertype" type="string" value="closest" />
  </image>
''' + usd("g", [("metallic", "float", 'nodename="met"'), ("roughness", "float", 'nodename="rgh"'),
                ("base_color", "color3", 'value="0.8, 0.7, 0.6"')], shader="gltf_pbr"))
    (d / "g.mtlx").write_text(text)
    m = load(d / "g.mtlx")["g"]
    uv = (np.random.default_rng(2).integers(0, 8, (16, 2)) + 0.5) / 8
    at = m.at(uv)
    np.testing.assert_allclose(at.metallic, texel(px["data"], uv)[:, 0] / 255.0, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(at.roughness, texel(px["colour"], uv)[:, 0] / 255.0, rtol=1e-6, atol=1e-7)
    wo, wi = directions(len(uv))
    np.testing.assert_array_equal(m.eval(wo, wi, uv=uv), at.eval(wo, wi))


def test_dot_cycle_is_refused():
    text = mtlx('  <dot name="a" type="float">\n    <input name="in" type="float" nodename="b" />\n  </dot>\n'
                '  <dot name="b" type="float">\n    <input name="in" type="float" nodename="a" />\n  </dot>\n'
                + usd("m", [("roughness", "float", 'nodename="a"')]))
    with pytest.raises(ValueError, match=r"node '[ab]' \(dot, line [36]\): a chain of more than 64 dot / constant "
                                         r"nodes \(or a cycle\)"):
        bk.from_materialx(text)


def test_every_truncation_is_a_value_error():
    text = mtlx(TEX_DOC + usd("m", [("diffuseColor", "color3", 'nodegraph="NG" output="col_out"')]))
    for n in range(0, len(text) - 1, 37):
        with pytest.raises(ValueError, match=r"not a well-formed MaterialX document|not a MaterialX document"):
            bk.from_materialx(text[:n] + "<")
