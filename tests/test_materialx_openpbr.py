"""bk.from_materialx: MaterialX ``open_pbr_surface`` and ``standard_surface`` nodes as bk.OpenPBR.

References: the OpenPBR Surface v1.1 specification's parameter table (defaults) as the session's
contract /work/wt/_shared/OPENPBR.md copies it; MaterialX's translation graph
libraries/bxdf/translation/standard_surface_to_open_pbr.mtlx, whose nodes are evaluated here by
hand (each expected value names the graph node it comes from); the OpenPBR repository's example
materials (tests/data/openpbr_examples.json). The documents are this file's own."""
import json
import os
import warnings

import numpy as np
import pytest

import bsdfkit as bk

import MaterialX  # noqa: F401  (a test dependency: pyproject.toml's test extra, scripts/setup.sh; no skip)

HEAD = '<?xml version="1.0"?>\n<materialx version="1.39">\n'

# OpenPBR Surface v1.1 parameter table: the defaults of every input bk.OpenPBR models
SPEC_DEFAULTS = dict(
    base_weight=1.0, base_color=(0.8, 0.8, 0.8), base_metalness=0.0, base_diffuse_roughness=0.0,
    specular_weight=1.0, specular_color=(1.0, 1.0, 1.0), specular_roughness=0.3, specular_roughness_anisotropy=0.0,
    specular_ior=1.5, transmission_weight=0.0, transmission_color=(1.0, 1.0, 1.0), subsurface_weight=0.0,
    subsurface_color=(0.8, 0.8, 0.8), subsurface_scatter_anisotropy=0.0, coat_weight=0.0, coat_color=(1.0, 1.0, 1.0),
    coat_roughness=0.0, coat_roughness_anisotropy=0.0, coat_ior=1.6, coat_darkening=1.0, fuzz_weight=0.0,
    fuzz_color=(1.0, 1.0, 1.0), fuzz_roughness=0.5, thin_film_weight=0.0, thin_film_thickness=0.5, thin_film_ior=1.4,
    geometry_thin_walled=False)

# a non-default value per modelled input, inside the spec's range
OTHER = dict(
    base_weight=0.7, base_color=(0.1, 0.25, 0.6), base_metalness=0.35, base_diffuse_roughness=0.45,
    specular_weight=1.3, specular_color=(0.9, 0.8, 0.7), specular_roughness=0.55, specular_roughness_anisotropy=0.6,
    specular_ior=1.33, transmission_weight=0.4, transmission_color=(0.5, 0.75, 1.0), subsurface_weight=0.25,
    subsurface_color=(0.9, 0.4, 0.3), subsurface_scatter_anisotropy=-0.3, coat_weight=0.8, coat_color=(0.95, 0.9, 0.5),
    coat_roughness=0.15, coat_roughness_anisotropy=0.2, coat_ior=1.45, coat_darkening=0.5, fuzz_weight=0.6,
    fuzz_color=(0.3, 0.6, 0.9), fuzz_roughness=0.8, thin_film_weight=0.9, thin_film_thickness=0.35, thin_film_ior=1.8,
    geometry_thin_walled=True)


def mx_type(v):
    return "boolean" if isinstance(v, bool) else "color3" if isinstance(v, (tuple, list)) else "float"


def mx_value(v):
    return ("true" if v else "false") if isinstance(v, bool) else \
        ", ".join(repr(float(x)) for x in v) if isinstance(v, (tuple, list)) else repr(float(v))


def shader(category, inputs, name="m", extra=""):
    """A MaterialX document with one surface shader node of ``category`` with constant ``inputs``
    ({name: value} or (name, type, attributes) rows) and its surfacematerial ``name``."""
    rows = "".join(f'    <input name="{k}" type="{mx_type(v)}" value="{mx_value(v)}" />\n' for k, v in inputs.items()) \
        if isinstance(inputs, dict) else "".join(f'    <input name="{n}" type="{t}" {a} />\n' for n, t, a in inputs)
    return (HEAD + extra + f'  <{category} name="{name}_sh" type="surfaceshader">\n{rows}  </{category}>\n'
            f'  <surfacematerial name="{name}" type="material">\n'
            f'    <input name="surfaceshader" type="surfaceshader" nodename="{name}_sh" />\n'
            '  </surfacematerial>\n</materialx>\n')


def line_of(text, needle):
    return next(i + 1 for i, s in enumerate(text.splitlines()) if needle in s)


def load(text, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # no warning unless a test asks for one
        return bk.from_materialx(text, **kw)


def assert_params(m, expected, rtol=1e-12):
    assert isinstance(m, bk.OpenPBR)
    for k, v in expected.items():
        got = getattr(m, k)
        if isinstance(v, bool):
            assert bool(got) is v, k
        else:
            np.testing.assert_allclose(np.asarray(got, dtype=np.float64), np.asarray(v, dtype=np.float64),
                                       rtol=rtol, atol=0, err_msg=k)


# ---------------------------------------------------------------- open_pbr_surface

def test_default_open_pbr_surface_is_the_spec_defaults():
    m = load(shader("open_pbr_surface", {}))["m"]
    assert_params(m, SPEC_DEFAULTS)
    assert m == bk.OpenPBR()


def test_openpbr_options_set_the_knobs():
    text = shader("open_pbr_surface", {"coat_weight": 1.0})
    m = load(text, openpbr_options={"compensation": "none", "layering": "reciprocal"})["m"]
    assert m == bk.OpenPBR(coat_weight=1.0, compensation="none", layering="reciprocal")
    assert m.compensation == "none" and m.layering == "reciprocal"
    # the same knobs reach a standard_surface's translation
    ss = load(shader("standard_surface", {}), openpbr_options={"compensation": "none"})["m"]
    assert ss.compensation == "none"
    with pytest.raises(TypeError, match=r"openpbr_options: 'fresnel' is not a bk\.OpenPBR knob"):
        bk.from_materialx(text, openpbr_options={"fresnel": "f82"})
    with pytest.raises(ValueError, match=r"compensation: must be one of"):
        bk.from_materialx(text, openpbr_options={"compensation": "kulla-conty"})


@pytest.mark.parametrize("name", sorted(OTHER))
def test_each_modelled_input_round_trips(name):
    m = load(shader("open_pbr_surface", {name: OTHER[name]}))["m"]
    assert_params(m, {**SPEC_DEFAULTS, name: OTHER[name]})


def test_all_modelled_inputs_at_once():
    m = load(shader("open_pbr_surface", OTHER))["m"]
    assert_params(m, OTHER)
    assert m == bk.OpenPBR(**OTHER)


def test_srgb_constant_colour_is_decoded():
    srgb = [("base_color", "color3", 'value="0.5, 0.04, 1" colorspace="srgb_texture"')]
    m = load(shader("open_pbr_surface", srgb))["m"]
    c = np.array([0.5, 0.04, 1.0])
    np.testing.assert_allclose(m.base_color, np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4),
                               rtol=1e-12)   # IEC 61966-2-1 decoding


@pytest.mark.parametrize("name, value, why", [
    ("transmission_depth", 0.5, "no interior medium"),
    ("transmission_scatter", (0.1, 0.2, 0.3), "no interior medium"),
    ("transmission_scatter_anisotropy", 0.4, "no interior medium"),
    ("transmission_dispersion_scale", 1.0, "no dispersion"),
    ("emission_luminance", 100.0, "emission"),
])
def test_non_modelled_input_refused_then_dropped_with_approximate(name, value, why):
    text = shader("open_pbr_surface", {"base_color": (0.2, 0.4, 0.6), name: value})
    n = line_of(text, f'name="{name}"')
    with pytest.raises(ValueError, match=rf"input '{name}' \(line {n}\) of node 'm_sh' \(open_pbr_surface, line 3\): "
                                         rf"{name} = .* is not modelled by bk\.OpenPBR \({why}.*approximate=True"):
        bk.from_materialx(text)
    with pytest.warns(bk.interop.MaterialXWarning) as rec:
        m = bk.from_materialx(text, approximate=True)["m"]
    assert len(rec) == 1 and rec[0].message.material == "m"
    assert len(rec[0].message.left_out) == 1 and name in rec[0].message.left_out[0]
    assert_params(m, {**SPEC_DEFAULTS, "base_color": (0.2, 0.4, 0.6)})


def test_approximate_lists_every_dropped_input_in_one_warning():
    text = shader("open_pbr_surface", {"emission_luminance": 10.0, "emission_color": (1.0, 0.5, 0.2),
                                       "transmission_weight": 1.0, "transmission_depth": 0.2,
                                       "transmission_dispersion_scale": 0.5,
                                       "transmission_dispersion_abbe_number": 40.0})
    with pytest.warns(bk.interop.MaterialXWarning) as rec:
        m = bk.from_materialx(text, approximate=True)["m"]
    assert len(rec) == 1
    msg = str(rec[0].message)
    for name in ("emission_luminance", "emission_color", "transmission_depth", "transmission_dispersion_scale",
                 "transmission_dispersion_abbe_number"):
        assert name in msg
    assert_params(m, {**SPEC_DEFAULTS, "transmission_weight": 1.0})


def test_approximate_must_be_a_bool():
    with pytest.raises(TypeError, match="approximate: expected True or False, got 'yes'"):
        bk.from_materialx(shader("open_pbr_surface", {}), approximate="yes")


def test_inputs_that_only_act_with_another_are_ignored_at_its_default():
    """emission_color at emission_luminance 0, the Abbe number at dispersion scale 0 (spec): no error, no warning."""
    m = load(shader("open_pbr_surface", {"emission_color": (1.0, 0.0, 0.0),
                                         "transmission_dispersion_abbe_number": 35.0}))["m"]
    assert m == bk.OpenPBR()


def test_geometry_opacity_is_a_mask():
    m = load(shader("open_pbr_surface", {"geometry_opacity": 0.4, "base_metalness": 1.0}))["m"]
    assert isinstance(m, bk.Mask) and m.opacity == 0.4
    assert m.model == bk.OpenPBR(base_metalness=1.0)
    assert isinstance(load(shader("open_pbr_surface", {"geometry_opacity": 1.0}))["m"], bk.OpenPBR)


def test_out_of_range_and_unknown_inputs_name_input_and_line():
    """bk.OpenPBR checks the values; the importer names the input, its node and their lines."""
    for name, value in (("base_weight", 1.5), ("specular_ior", 0.0), ("coat_color", (1.0, -0.2, 1.0)),
                        ("specular_roughness", -0.1)):
        with pytest.raises(ValueError, match=rf"input '{name}' \(line 4\) of node 'm_sh' \(open_pbr_surface, line 3\): "
                                             rf"bk\.OpenPBR: .*{name}"):
            bk.from_materialx(shader("open_pbr_surface", {name: value}))
    with pytest.raises(ValueError, match=r"input 'geometry_opacity' \(line 4\) .*1\.5 is outside \[0, 1\]"):
        bk.from_materialx(shader("open_pbr_surface", {"geometry_opacity": 1.5}))
    with pytest.raises(ValueError, match=r"unknown input 'base_sheen' of a open_pbr_surface node"):
        bk.from_materialx(shader("open_pbr_surface", {"base_sheen": 0.5}))
    with pytest.raises(ValueError, match=r"input 'coat_weight' .*type color3, the open_pbr_surface node definition "
                                         r"says float"):
        bk.from_materialx(shader("open_pbr_surface", [("coat_weight", "color3", 'value="1, 1, 1"')]))


def test_connected_frames_refused_or_dropped():
    tangent = [("geometry_tangent", "vector3", 'value="1, 0, 0"')]
    with pytest.raises(ValueError, match=r"input 'geometry_tangent' \(line 4\) .*not modelled by bk\.OpenPBR "
                                         r"\(the tangent is the shading frame's x axis"):
        bk.from_materialx(shader("open_pbr_surface", tangent))
    with pytest.warns(bk.interop.MaterialXWarning, match="geometry_tangent"):
        assert bk.from_materialx(shader("open_pbr_surface", tangent), approximate=True)["m"] == bk.OpenPBR()


NORMAL_MAP = '''  <image name="nimg" type="vector3">
    <input name="file" type="filename" value="normals.png" />
    <input name="filtertype" type="string" value="closest" />
  </image>
  <normalmap name="nm" type="vector3">
    <input name="in" type="vector3" nodename="nimg" />
    <input name="scale" type="float" value="0.5" />
  </normalmap>
'''


def test_geometry_normal_from_a_normalmap_node(tmp_path):
    from PIL import Image
    px = np.array([[[128, 128, 255], [200, 90, 230]], [[60, 140, 220], [128, 30, 200]]], dtype=np.uint8)
    Image.fromarray(px).save(tmp_path / "normals.png")
    text = shader("open_pbr_surface", [("geometry_normal", "vector3", 'nodename="nm"'),
                                       ("base_metalness", "float", 'value="1"')], extra=NORMAL_MAP)
    (tmp_path / "n.mtlx").write_text(text)
    m = load(tmp_path / "n.mtlx")["m"]
    assert isinstance(m, bk.Textured) and m.model_class is bk.NormalMap
    uv = np.array([[0.25, 0.75], [0.75, 0.75], [0.25, 0.25], [0.75, 0.25]])   # MaterialX uv: v up
    rows = np.floor((1 - uv[:, 1]) * 2).astype(int)
    cols = np.floor(uv[:, 0] * 2).astype(int)
    n = (2 * px[rows, cols].astype(float) / 255.0 - 1) * [0.5, 0.5, 1.0]   # MaterialX normalmap: (2 in - 1) (s, s, 1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    np.testing.assert_allclose(next(iter(m.textures.values())).lookup(uv), n, rtol=1e-6, atol=1e-7)
    assert m.at(uv).model == bk.OpenPBR(base_metalness=1.0)


def test_textured_input(tmp_path):
    """A texture on a modelled input: bk.OpenPBR's per-element parameters when it has them, else a
    clear error naming the input."""
    from PIL import Image
    Image.fromarray(np.full((2, 2, 3), 100, dtype=np.uint8)).save(tmp_path / "c.png")
    img = '  <image name="img" type="color3">\n    <input name="file" type="filename" value="c.png" />\n  </image>\n'
    text = shader("open_pbr_surface", [("base_color", "color3", 'nodename="img"')], extra=img)
    (tmp_path / "t.mtlx").write_text(text)
    if "base_color" in (getattr(bk.OpenPBR, "varying_params", None) or {}):
        m = load(tmp_path / "t.mtlx")["m"]
        assert isinstance(m, bk.Textured) and list(m.textures) == ["base_color"]
        np.testing.assert_allclose(m.at(np.array([[0.5, 0.5]])).base_color, [[100 / 255] * 3], rtol=1e-6)
    else:
        with pytest.raises(ValueError, match=r"input 'base_color' \(line \d+\) of node 'm_sh' \(open_pbr_surface, "
                                             r"line \d+\): a texture for base_color: bk\.OpenPBR takes no textures"):
            bk.from_materialx(tmp_path / "t.mtlx")


def test_unknown_node_and_bad_version_still_clear():
    with pytest.raises(ValueError, match=r"<materialx> \(line 2\): version 1\.40 is newer than the MaterialX package"):
        bk.from_materialx(shader("open_pbr_surface", {}).replace('version="1.39"', 'version="1.40"'))
    with pytest.raises(ValueError, match=r"<materialx> \(line 2\): version 'one' is not a MaterialX version"):
        bk.from_materialx(shader("open_pbr_surface", {}).replace('version="1.39"', 'version="one"'))
    with pytest.raises(ValueError, match=r"node 'm_sh' \(open_pbr_surfaces, line 3\): unknown node "
                                         r"'open_pbr_surfaces'"):
        bk.from_materialx(shader("open_pbr_surfaces", {}))
    text = shader("open_pbr_surface", [("base_weight", "float", 'nodename="w"')],
                  extra='  <wobble name="w" type="float" />\n')
    with pytest.raises(ValueError, match=r"node 'w' \(wobble, line 3\): unknown node 'wobble'"):
        bk.from_materialx(text)


# ---------------------------------------------------------------- standard_surface through MaterialX's translation

# Every expected value below is worked out by hand from libraries/bxdf/translation/
# standard_surface_to_open_pbr.mtlx (MaterialX 1.39), node by node: dot nodes pass their input;
# coatAttenuation = mix(bg 1, fg coat_color, coat); baseColor = base_color * coatAttenuation;
# specWeight = ifgreater(metalness > 0, 1, specular); specColor = ifequal(0 == dot(specular_color, 1),
# white, specular_color); fuzzRoughness = sheen_roughness ^ 0.4; coatWeight = ifgreater(coat *
# metalness > 0, 0, coat); coatDarkening = coat_affect_roughness; thinFilmThickness = thin_film_thickness
# * 0.001 (nm -> um), thinFilmWeight = ifgreater(that > 0, 1, 0); geometryOpacity = opacity[0];
# subsurfaceRadius = subsurface_scale, subsurfaceRadiusScale = subsurface_radius. Unset inputs take
# standard_surface's own defaults (base 1, base_color 0.8, specular_roughness 0.2, coat_roughness 0.1,
# coat_IOR 1.5, sheen_roughness 0.3, subsurface_color 1, thin_film_IOR 1.5; stdlib standard_surface
# node definition).
SS_COMMON = dict(base_weight=1.0, base_color=(0.8, 0.8, 0.8), base_metalness=0.0, base_diffuse_roughness=0.0,
                 specular_weight=1.0, specular_color=(1.0, 1.0, 1.0), specular_roughness=0.2,
                 specular_roughness_anisotropy=0.0, specular_ior=1.5, transmission_weight=0.0,
                 transmission_color=(1.0, 1.0, 1.0), subsurface_weight=0.0, subsurface_color=(1.0, 1.0, 1.0),
                 subsurface_scatter_anisotropy=0.0, coat_weight=0.0, coat_color=(1.0, 1.0, 1.0), coat_roughness=0.1,
                 coat_roughness_anisotropy=0.0, coat_ior=1.5, coat_darkening=0.0, fuzz_weight=0.0,
                 fuzz_color=(1.0, 1.0, 1.0), fuzz_roughness=0.3 ** 0.4, thin_film_weight=0.0, thin_film_thickness=0.0,
                 thin_film_ior=1.5, geometry_thin_walled=False)

SS_METAL = dict(metalness=1.0, base_color=(0.95, 0.64, 0.54), specular=0.6, specular_color=(1.0, 0.9, 0.8),
                specular_roughness=0.25, specular_anisotropy=0.4, coat=0.5, coat_color=(0.9, 0.8, 0.7),
                coat_roughness=0.2)
OPBR_METAL = {**SS_COMMON,
              "base_metalness": 1.0,
              "base_color": (0.95 * 0.95, 0.64 * 0.9, 0.54 * 0.85),   # baseColor: base_color (0.5 + 0.5 coat_color)
              "specular_weight": 1.0,                                 # specWeight: metalness 1 > 0
              "specular_color": (1.0, 0.9, 0.8),                      # specColor: dot 2.7 != 0
              "specular_roughness": 0.25, "specular_roughness_anisotropy": 0.4,
              "coat_weight": 0.0,                                     # coatWeight: coat metalness 0.5 > 0
              "coat_color": (0.9, 0.8, 0.7), "coat_roughness": 0.2}

SS_GLASS = dict(base=0.0, transmission=1.0, transmission_color=(0.9, 0.95, 1.0), specular=0.8,
                specular_color=(0.0, 0.0, 0.0), specular_IOR=1.45, specular_roughness=0.05,
                thin_film_thickness=400.0, thin_film_IOR=1.33, thin_walled=True)
OPBR_GLASS = {**SS_COMMON,
              "base_weight": 0.0,
              "specular_weight": 0.8,                                 # specWeight: metalness 0 -> specular
              "specular_color": (1.0, 1.0, 1.0),                      # specColor: dot(black, 1) == 0 -> white
              "specular_ior": 1.45, "specular_roughness": 0.05,
              "transmission_weight": 1.0, "transmission_color": (0.9, 0.95, 1.0),
              "thin_film_weight": 1.0, "thin_film_thickness": 0.4,    # 400 nm * 0.001
              "thin_film_ior": 1.33, "geometry_thin_walled": True}

SS_COATED = dict(base_color=(0.2, 0.3, 0.6), diffuse_roughness=0.3, coat=0.8, coat_color=(0.9, 0.95, 1.0),
                 coat_roughness=0.05, coat_anisotropy=0.3, coat_IOR=1.6, coat_affect_roughness=0.5, sheen=0.4,
                 sheen_color=(0.7, 0.6, 0.5), sheen_roughness=0.5, subsurface=0.2, subsurface_color=(0.9, 0.5, 0.4),
                 subsurface_radius=(1.0, 0.4, 0.2), subsurface_scale=0.1, subsurface_anisotropy=0.25,
                 opacity=(0.7, 0.7, 0.7))
OPBR_COATED = {**SS_COMMON,
               "base_color": (0.2 * 0.92, 0.3 * 0.96, 0.6 * 1.0),    # baseColor: base_color (0.2 + 0.8 coat_color)
               "base_diffuse_roughness": 0.3,
               "coat_weight": 0.8,                                    # coatWeight: coat metalness 0 -> coat
               "coat_color": (0.9, 0.95, 1.0), "coat_roughness": 0.05, "coat_roughness_anisotropy": 0.3,
               "coat_ior": 1.6, "coat_darkening": 0.5,                # coatDarkening: coat_affect_roughness
               "fuzz_weight": 0.4, "fuzz_color": (0.7, 0.6, 0.5), "fuzz_roughness": 0.5 ** 0.4,
               "subsurface_weight": 0.2, "subsurface_color": (0.9, 0.5, 0.4), "subsurface_scatter_anisotropy": 0.25}


@pytest.mark.parametrize("ss, expected, opacity", [(SS_METAL, OPBR_METAL, None), (SS_GLASS, OPBR_GLASS, None),
                                                   (SS_COATED, OPBR_COATED, 0.7)], ids=["metal", "glass", "coated"])
def test_standard_surface_through_materialx_translation(ss, expected, opacity):
    m = load(shader("standard_surface", ss))["m"]
    if opacity is not None:   # geometryOpacity = opacity[0] -> bk.Mask
        assert isinstance(m, bk.Mask) and m.opacity == pytest.approx(opacity, rel=1e-15)
        m = m.model
    assert_params(m, expected)


def test_default_standard_surface():
    assert_params(load(shader("standard_surface", {}))["m"], SS_COMMON)


def test_standard_surface_inputs_the_translation_leaves_out():
    text = shader("standard_surface", {"specular_rotation": 0.25, "metalness": 1.0})
    with pytest.raises(ValueError, match=r"input 'specular_rotation' \(line 4\) of node 'm_sh' \(standard_surface, "
                                         r"line 3\): specular_rotation is not carried to OpenPBR by MaterialX's "
                                         r"libraries/bxdf/translation/standard_surface_to_open_pbr\.mtlx"):
        bk.from_materialx(text)
    with pytest.warns(bk.interop.MaterialXWarning, match="specular_rotation") as rec:
        m = bk.from_materialx(text, approximate=True)["m"]
    assert len(rec) == 1
    assert_params(m, {**SS_COMMON, "base_metalness": 1.0})


def test_standard_surface_non_modelled_output_names_its_inputs():
    """transmission_depth reaches OpenPBR's transmission_depth through a dot node: refused naming
    the standard_surface input, dropped with approximate=True."""
    text = shader("standard_surface", {"transmission": 1.0, "transmission_depth": 2.0})
    n = line_of(text, 'name="transmission_depth"')
    with pytest.raises(ValueError, match=rf"node 'm_sh' \(standard_surface, line 3\): input\(s\) 'transmission_depth' "
                                         rf"\(line {n}\) -> OpenPBR transmission_depth .*: transmission_depth = 2 is "
                                         r"not modelled by bk\.OpenPBR"):
        bk.from_materialx(text)
    with pytest.warns(bk.interop.MaterialXWarning, match="transmission_depth"):
        m = bk.from_materialx(text, approximate=True)["m"]
    assert_params(m, {**SS_COMMON, "transmission_weight": 1.0})


def test_standard_surface_texture_through_an_arithmetic_node(tmp_path):
    from PIL import Image
    Image.fromarray(np.full((2, 2), 100, dtype=np.uint8)).save(tmp_path / "r.png")
    img = '  <image name="img" type="float">\n    <input name="file" type="filename" value="r.png" />\n  </image>\n'
    text = shader("standard_surface", [("sheen_roughness", "float", 'nodename="img"')], extra=img)
    (tmp_path / "t.mtlx").write_text(text)
    with pytest.raises(ValueError, match=r"node 'm_sh' \(standard_surface, line \d+\): input\(s\) 'sheen_roughness' "
                                         r"\(line \d+\) -> OpenPBR fuzz_roughness .*a texture reaches the power node "
                                         r"'fuzzRoughness'"):
        bk.from_materialx(tmp_path / "t.mtlx")


# ---------------------------------------------------------------- the OpenPBR repository's examples

EXAMPLES = os.path.join(os.path.dirname(__file__), "data", "openpbr_examples.json")
NOT_MODELLED = {"transmission_depth": 0.0, "transmission_scatter": 0.0, "transmission_scatter_anisotropy": 0.0,
                "transmission_dispersion_scale": 0.0, "emission_luminance": 0.0}   # the contract's list (defaults)


def _examples():
    with open(EXAMPLES) as f:
        return json.load(f)


@pytest.mark.parametrize("name", sorted(_examples()))
def test_openpbr_examples(name):
    """Each example's open_pbr_surface, written as MaterialX: the modelled inputs equal the example's
    values; inputs bk.OpenPBR does not model are refused, or dropped (named) with approximate=True."""
    ex = _examples()[name]
    text = shader("open_pbr_surface", {k: tuple(v) if isinstance(v, list) else v for k, v in ex.items()})
    dropped = sorted(k for k, d in NOT_MODELLED.items() if k in ex and np.any(np.asarray(ex[k]) != d))
    if dropped:
        with pytest.raises(ValueError, match=rf"input '({'|'.join(dropped)})' .*is not modelled by bk\.OpenPBR"):
            bk.from_materialx(text)
        with pytest.warns(bk.interop.MaterialXWarning) as rec:
            m = bk.from_materialx(text, approximate=True)["m"]
        assert len(rec) == 1 and all(k in str(rec[0].message) for k in dropped)
    else:
        m = load(text)["m"]
    if "geometry_opacity" in ex and ex["geometry_opacity"] < 1:
        assert isinstance(m, bk.Mask) and m.opacity == ex["geometry_opacity"]
        m = m.model
    modelled = {k: v for k, v in ex.items() if k in SPEC_DEFAULTS}
    assert_params(m, {**SPEC_DEFAULTS, **modelled})
    assert m == bk.OpenPBR(**modelled)


def test_standard_surface_textured_opacity_is_a_mask_of_channel_0(tmp_path):
    """opacity (color3) from an image: the translation's geometryOpacity = extract(opacity, 0) is the
    image's first channel, read as bk.Mask's opacity per texel."""
    from PIL import Image
    px = np.random.default_rng(5).integers(0, 256, (2, 2, 3), dtype=np.uint8)
    Image.fromarray(px).save(tmp_path / "o.png")
    img = ('  <image name="img" type="color3">\n    <input name="file" type="filename" value="o.png" />\n'
           '    <input name="filtertype" type="string" value="closest" />\n  </image>\n')
    text = shader("standard_surface", [("opacity", "color3", 'nodename="img"'), ("metalness", "float", 'value="1"')],
                  extra=img)
    (tmp_path / "o.mtlx").write_text(text)
    m = load(tmp_path / "o.mtlx")["m"]
    assert isinstance(m, bk.Textured) and m.model_class is bk.Mask
    uv = np.array([[0.25, 0.75], [0.75, 0.75], [0.25, 0.25], [0.75, 0.25]])   # MaterialX uv: v up
    rows, cols = np.floor((1 - uv[:, 1]) * 2).astype(int), np.floor(uv[:, 0] * 2).astype(int)
    at = m.at(uv)
    np.testing.assert_allclose(at.opacity, px[rows, cols, 0] / 255.0, rtol=1e-6, atol=1e-7)   # no colorspace: linear
    assert_params(at.model, {**SS_COMMON, "base_metalness": 1.0})
