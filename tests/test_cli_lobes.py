"""python -m bsdfkit lobes MODEL-SPEC: the PNG it writes and the errors it reports."""
import os
import subprocess
import sys

import pytest

import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mimage  # noqa: E402

import bsdfkit as bk  # noqa: E402
from bsdfkit.__main__ import main  # noqa: E402


def _run(*args):
    return subprocess.run([sys.executable, "-m", "bsdfkit", *args], capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, MPLBACKEND="Agg"))


def _check_png(path, w, h):
    assert path.is_file() and path.stat().st_size > 10_000
    img = mimage.imread(str(path))
    assert img.shape[:2] == (h, w), img.shape
    assert img[..., :3].std() > 0.05   # not a blank canvas


def test_lobes_subprocess_writes_png_of_the_requested_size(tmp_path):
    out = tmp_path / "lobes.png"
    r = _run("lobes", "conductor", "metal=Cu", "alpha=0.2", "--theta", "30", "-o", str(out), "--size", "1200x800",
             "--samples", "20000")
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == str(out.resolve())
    _check_png(out, 1200, 800)


@pytest.mark.parametrize("args, size", [
    (["dielectric eta=1.5 alpha=0.3", "--log", "--cosine", "--channel", "rgb", "--phi", "45"], (900, 600)),
    (["conductor", "metal=Au", "alpha=0.1", "+", "diffuse", "0.5", "--views", "polar,hemisphere"], (1000, 450)),
    (["thin", "--theta", "60", "--views", "polar,lobe3d,samples"], (800, 300)),
])
def test_lobes_variants(tmp_path, capsys, args, size):
    out = tmp_path / "x.png"
    assert main(["lobes", *args, "-o", str(out), "--size", f"{size[0]}x{size[1]}", "--samples", "5000"]) == 0
    _check_png(out, *size)


def test_lobes_bad_spec_lists_models_and_parameters(tmp_path):
    out = tmp_path / "never.png"
    r = _run("lobes", "plastic", "roughness=0.2", "-o", str(out))
    assert r.returncode != 0
    assert "unknown model 'plastic'" in r.stderr
    for name in ("conductor", "dielectric", "diffuse", "thin_dielectric", "filament_standard"):
        assert f"\n  {name} " in r.stderr
    assert "metal=Cu|Au|Ag|Al|Cr" in r.stderr and "alpha=" in r.stderr
    assert not out.exists()


@pytest.mark.parametrize("args, message", [
    (["conductor", "metl=Cu"], "conductor has no parameter 'metl'"),
    (["conductor", "metal=Cu", "alpha=-1"], "alpha"),
    (["dielectric", "eta=abc"], "eta"),
    (["diffuse", "+"], "empty model spec"),
    (["diffuse", "--size", "big"], "--size"),
    (["diffuse", "--theta", "nan"], "--theta"),
    (["diffuse", "--views", "polar,brdf"], "unknown view 'brdf'"),
])
def test_lobes_errors(tmp_path, capsys, args, message):
    out = tmp_path / "never.png"
    assert main(["lobes", *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("bsdfkit lobes: ") and message in err
    assert not out.exists()


def test_lobes_help_mentions_specs():
    assert main(["lobes", "--help"]) == 0
    r = _run("--help")
    assert r.returncode == 0 and "lobes" in r.stdout


def test_every_model_class_is_reachable_by_spec():
    from bsdfkit.models.spec import example_model, example_spec, parse_spec

    for cls in bk.MODELS:
        assert parse_spec(example_spec(cls)) == example_model(cls)
