"""from_pbrt reads every directive of pbrt-v4's scene format (issue 50, items 6, 9 and 14).

``ActiveTransform StartTime`` was read as a directive named "StartTime", so pbrt-v4's
killeroo-moving.pbrt could not be imported even with skip_unsupported=True; a missing Include
(most public scenes include geometry a material user does not have) was always fatal; a
ColorSpace other than sRGB was ignored silently. The syntax below is pbrt-v4's file format
(pbrt.org/fileformat-v4, src/pbrt/parser.cpp): one statement per directive.
"""
import subprocess
import sys
import warnings

import pytest

import bsdfkit as bk
from bsdfkit.interop import PbrtColorSpaceWarning, PbrtMissingIncludeWarning

EVERY_DIRECTIVE = """
Option "bool disablepixeljitter" true
Option "string rendercoordsys" "world"
ColorSpace "srgb"
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [45]
Sampler "zsobol" "integer pixelsamples" 16
Integrator "volpath" "integer maxdepth" [5]
PixelFilter "gaussian" "float sigma" 0.5
Film "rgb" "string filename" "out.exr" "integer xresolution" [64] "integer yresolution" [64]
Accelerator "bvh" "integer maxnodeprims" 4
TransformTimes 0 1
ActiveTransform StartTime
Translate 0 0 0
ActiveTransform EndTime
Translate 0 0 1
ActiveTransform All
Identity
CoordinateSystem "mycamera"
CoordSysTransform "camera"
MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_a" [0.1 0.1 0.1]
MediumInterface "" "fog"
WorldBegin
MediumInterface "fog"
Attribute "shape" "float radius" 0.5
LightSource "infinite" "rgb L" [1 1 1]
AttributeBegin
  AreaLightSource "diffuse" "blackbody L" [6500]
  Shape "sphere"
AttributeEnd
Texture "checks" "spectrum" "checkerboard" "float uscale" [4] "float vscale" [4]
MakeNamedMaterial "gold" "string type" "conductor" "float roughness" 0.01
Material "diffuse" "rgb reflectance" [0.5 0.4 0.3]
TransformBegin
  NamedMaterial "gold"
  Rotate 30 0 1 0
  Scale 2 2 2
  Shape "sphere"
TransformEnd
Shape "disk"
ObjectBegin "thing"
  NamedMaterial "gold"
  Shape "sphere"
ObjectEnd
ObjectInstance "thing"
ReverseOrientation
ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1]
Transform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1]
Shape "trianglemesh" "integer indices" [0 1 2] "point3 P" [0 0 0 1 0 0 0 1 0]
"""


def test_every_pbrt_v4_directive_parses():
    with warnings.catch_warnings():
        warnings.simplefilter("error")      # nothing here deserves a warning
        recs = bk.parse_pbrt_materials(EVERY_DIRECTIVE)
        models = bk.from_pbrt(EVERY_DIRECTIVE)
    assert [r.name for r in recs] == ["gold", "material#1 (line 33)"]
    assert isinstance(models["gold"], bk.Conductor) and models["gold"].alpha_x == pytest.approx(0.1)
    assert models["material#1 (line 33)"] == bk.Diffuse([0.5, 0.4, 0.3])
    # TransformBegin/End and ObjectBegin/End scope the material as AttributeBegin/End do in
    # pbrt-v4: the disk and the triangle mesh after them are diffuse, the two spheres gold
    shapes = {r.name: r.shapes for r in recs}
    assert shapes == {"gold": 2, "material#1 (line 33)": 2}


@pytest.mark.parametrize("arg", ["Sometimes", '"StartTime"', "1", ""])
def test_active_transform_rejects_other_arguments(arg):
    with pytest.raises(ValueError, match=r"line 2: ActiveTransform: expected All, StartTime, EndTime"):
        bk.from_pbrt(f'Material "diffuse"\nActiveTransform {arg}\n')


# the shape of pbrt-v4's killeroo-moving.pbrt: motion blur through ActiveTransform, and the
# geometry in an Include the user does not have
MOVING = """WorldBegin
AttributeBegin
    Material "coateddiffuse" "float roughness" [ 0.025 ] "rgb reflectance" [ 0.4 0.2 0.2 ]
    ActiveTransform StartTime
    Translate 35 35 35
    AttributeBegin
        Include "geometry/model.pbrt"
    AttributeEnd
    Material "coateddiffuse" "float roughness" [ 0.15 ] "rgb reflectance" [ 0.4 0.5 0.4 ]
    AttributeBegin
        ActiveTransform StartTime
        Translate 30 0 0
        ActiveTransform All
        Include "geometry/model.pbrt"
    AttributeEnd
AttributeEnd
"""


def test_missing_includes_are_fatal_unless_skipped_one_warning_each(tmp_path):
    scene = tmp_path / "moving.pbrt"
    scene.write_text(MOVING)
    with pytest.raises(OSError, match=r"line 7: Include 'geometry/model.pbrt'.*skip_missing_includes=True"):
        bk.from_pbrt(scene)
    with pytest.warns(PbrtMissingIncludeWarning) as rec:
        models = bk.from_pbrt(scene, skip_missing_includes=True)
    assert [(w.message.line, w.message.include) for w in rec] == [(7, "geometry/model.pbrt"),
                                                                 (14, "geometry/model.pbrt")]
    assert rec[0].message.file == str(scene) and rec[0].message.path == str(tmp_path / "geometry" / "model.pbrt")
    assert [type(m).__name__ for m in models.values()] == ["CoatedDiffuse", "CoatedDiffuse"]
    # an include that exists is still read
    (tmp_path / "geometry").mkdir()
    (tmp_path / "geometry" / "model.pbrt").write_text('Material "diffuse"\nShape "sphere"\n')
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        models = bk.from_pbrt(scene, skip_missing_includes=True)
    assert len(models) == 4
    with pytest.raises(TypeError, match="skip_missing_includes"):
        bk.from_pbrt(MOVING, skip_missing_includes="yes")


def test_cli_skips_missing_includes_when_asked(tmp_path):
    scene = tmp_path / "moving.pbrt"
    scene.write_text(MOVING.replace("coateddiffuse", "diffuse").replace('"float roughness" [ 0.025 ]', "")
                     .replace('"float roughness" [ 0.15 ]', ""))
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", str(scene), "-n", "64"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "--skip-missing-includes" in r.stderr
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", str(scene), "-n", "64",
                        "--skip-missing-includes"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "skipped 2 missing include(s)" in r.stdout and "'geometry/model.pbrt' (" in r.stdout


def test_non_srgb_colorspace_warns_once_per_file():
    text = 'ColorSpace "rec2020"\nMaterial "diffuse" "rgb reflectance" [0.5 0.2 0.1]\nColorSpace "aces2065-1"\n'
    with pytest.warns(PbrtColorSpaceWarning, match="'rec2020' is not honoured") as rec:
        bk.from_pbrt(text)
    assert len([w for w in rec if w.category is PbrtColorSpaceWarning]) == 1 and rec[0].message.line == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bk.from_pbrt('ColorSpace "srgb"\nMaterial "diffuse"\n')
