"""Scene sources and skipped materials (issue 11 items 2, 3, 11): from_pbrt takes a path as well
as text, refuses a word that is not a pbrt directive (``bk.from_pbrt("scene.pbrt")`` returned {}),
follows Include/Import relative to the including file, and names every material that
``skip_unsupported`` leaves out; from_mitsuba takes a loaded mi.BSDF as well as a dict."""
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.interop.pbrt import PbrtSkipWarning

SCENE = '''MakeNamedMaterial "gold" "string type" "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
    "float roughness" 0.04
Include "parts/glass.pbrt"
Material "interface"
Material "diffuse" "rgb reflectance" [0.2 0.3 0.4]
'''
GLASS = '''# included
MakeNamedMaterial "glass" "string type" "dielectric" "float eta" 1.33
Import "../more/skin.pbrt"
'''
SKIN = '''
MakeNamedMaterial "skin" "string type" "subsurface"
'''


@pytest.fixture
def scene_dir(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "more").mkdir()
    (tmp_path / "scene.pbrt").write_text(SCENE)
    (tmp_path / "parts" / "glass.pbrt").write_text(GLASS)
    (tmp_path / "more" / "skin.pbrt").write_text(SKIN)
    return tmp_path


@pytest.mark.filterwarnings("ignore::bsdfkit.interop.pbrt.PbrtSkipWarning")
def test_path_and_pathlike_and_text(scene_dir, monkeypatch):
    by_path = bk.from_pbrt(scene_dir / "scene.pbrt", skip_unsupported=True)
    assert list(by_path) == ["gold", "glass", "material#2 (line 5)"]
    assert by_path["glass"] == bk.Dielectric(1.33, alpha=0.0, masking="correlated")
    gold = bk.Conductor(bk.Spectrum.named("metal-Au-eta"), bk.Spectrum.named("metal-Au-k"), alpha=0.2)
    assert by_path["gold"] == bk.Conductor(*(g.to_rgb("unbounded", illuminant=None) for g in (gold.eta, gold.k)),
                                           alpha=0.2)
    assert bk.from_pbrt(str(scene_dir / "scene.pbrt"), skip_unsupported=True) == by_path
    # text: includes relative to the working directory
    monkeypatch.chdir(scene_dir)
    assert bk.from_pbrt(SCENE, skip_unsupported=True) == by_path


def test_bare_word_is_an_error_naming_the_line(tmp_path):
    with pytest.raises(FileNotFoundError, match="scene.pbrt"):
        bk.from_pbrt("scene.pbrt")  # returned {} before
    with pytest.raises(ValueError, match=r"line 2: unknown directive 'Materail'"):
        bk.from_pbrt('Material "diffuse"\nMaterail "diffuse"')
    with pytest.raises(ValueError, match="line 1: unknown directive 'my_scene.txt'.*file name"):
        bk.from_pbrt("my_scene.txt")


def test_include_errors(tmp_path):
    (tmp_path / "a.pbrt").write_text('Material "diffuse"\nInclude "missing.pbrt"\n')
    with pytest.raises(OSError, match=r"line 2: Include 'missing.pbrt'.*missing.pbrt"):
        bk.from_pbrt(tmp_path / "a.pbrt")
    (tmp_path / "loop.pbrt").write_text('Include "loop.pbrt"\n')
    with pytest.raises(ValueError, match="nested deeper than 32"):
        bk.from_pbrt(tmp_path / "loop.pbrt")
    (tmp_path / "bad.pbrt").write_text('Material "diffuse"\n\nShape ]\n')
    (tmp_path / "top.pbrt").write_text('Include "bad.pbrt"\n')
    with pytest.raises(ValueError, match=r"bad.pbrt: line 3: unexpected ']'"):
        bk.from_pbrt(tmp_path / "top.pbrt")


def test_skip_unsupported_warns_per_material(scene_dir):
    with pytest.warns(PbrtSkipWarning) as rec:
        bk.from_pbrt(scene_dir / "scene.pbrt", skip_unsupported=True)
    ws = [w.message for w in rec if isinstance(w.message, PbrtSkipWarning)]
    assert [(w.material, w.line) for w in ws] == [("skin", 2), ("material#1 (line 4)", 4)]
    assert ws[0].file.endswith(os.path.join("more", "skin.pbrt"))
    assert "subsurface" in ws[0].reason and "interface" in ws[1].reason
    assert "'skin' (subsurface, line 2)" in str(ws[0]) and "skin.pbrt" in str(ws[0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="skin"):
            bk.from_pbrt(scene_dir / "scene.pbrt")  # no skipping: the first failure raises


def test_cli_lists_skipped_materials(scene_dir):
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", str(scene_dir / "scene.pbrt"), "--skip-unsupported",
                        "-n", "64"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "skipped 2 unsupported material(s)" in r.stdout
    assert "'skin' (" in r.stdout and "skin.pbrt: line 2" in r.stdout
    assert "'material#1 (line 4)' (line 4)" in r.stdout and "interface" in r.stdout


# ------------------------------------------------------------------ from_mitsuba: loaded BSDFs

@pytest.mark.parametrize("d", [
    {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.1, 0.2, 0.3]}},
    {"type": "conductor", "material": "Au"},
    {"type": "conductor"},
    {"type": "roughconductor", "material": "Cu", "alpha": 0.3, "distribution": "ggx"},
    {"type": "roughconductor", "alpha_u": 0.3, "alpha_v": 0.05, "distribution": "ggx", "eta": 1.5, "k": 2.0},
    {"type": "dielectric", "int_ior": 1.33},
    {"type": "roughdielectric", "int_ior": 1.5, "alpha": 0.2, "distribution": "ggx"},
    {"type": "thindielectric", "int_ior": 1.5},
    {"type": "twosided", "bsdf": {"type": "roughconductor", "alpha": 0.2, "distribution": "ggx", "material": "Al"}},
], ids=lambda d: d["type"] + ("/" + d["bsdf"]["type"] if "bsdf" in d else ""))
def test_from_mitsuba_loaded_bsdf(d):
    from bsdfkit.testing import mitsuba as ref
    mi = ref._mi()[0]
    want = bk.from_mitsuba(d)
    got = bk.from_mitsuba(mi.load_dict(d))
    assert type(got) is type(want)
    for k, v in want._params.items():  # equal to float32 precision (Mitsuba stores float32)
        g = got._params[k]
        if isinstance(v, (str, bool)) or v is None:
            assert g == v, k
        else:
            np.testing.assert_allclose(g, v, rtol=1e-5, atol=1e-7, err_msg=k)  # METALS: 6 digits


def test_from_mitsuba_loaded_beckmann():
    """A loaded plugin's distribution and sample_visible come from its to_string."""
    from bsdfkit.testing import mitsuba as ref
    mi = ref._mi()[0]
    m = bk.from_mitsuba(mi.load_dict({"type": "roughconductor", "alpha": 0.2, "sample_visible": False}))
    assert (m.distribution, m.sample_visible, m.masking) == ("beckmann", False, "separable")
    with pytest.raises(ValueError, match="RoughPlastic"):  # no loaded plastics (their tables are Mitsuba's)
        bk.from_mitsuba(mi.load_dict({"type": "roughplastic", "alpha": 0.2}))
