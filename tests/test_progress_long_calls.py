"""Progress and Ctrl-C on the long calls of scenes and textures (issue 48 item 7): scene import
(pbrt, Mitsuba, glTF, MaterialX), simplify of a textured material, building an image texture.

From the user's side: the ``progress=`` callable each call takes (one bar per call: one stage
sequence, steps counted up to the total), the text line ``progress=True`` writes on stderr, the
auto mode's silence where nobody watches, and a KeyboardInterrupt raised inside the loop (what
Ctrl-C raises there) propagating as itself, with nothing run after it."""
import _thread
import json
import threading

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import _progress

pytest.importorskip("bsdfkit._render", reason="textures need bsdfkit._render (OpenImageIO)")

# a scene long enough that the reader reports while it reads (every 64 statements)
PBRT = "\n".join(['MakeNamedMaterial "gold" "string type" "conductor" "spectrum eta" "metal-Au-eta"'
                  ' "spectrum k" "metal-Au-k" "float roughness" 0.1',
                  'MakeNamedMaterial "wall" "string type" "diffuse" "rgb reflectance" [0.8 0.7 0.6]',
                  'Material "dielectric" "float eta" 1.5']
                 + ['AttributeBegin NamedMaterial "wall" Shape "sphere" "float radius" 1 AttributeEnd'] * 200)


class Recorder:
    """A progress callable that records its calls and raises KeyboardInterrupt at one of them."""

    def __init__(self, stop_at=None):
        self.calls, self.stop_at = [], stop_at

    def __call__(self, done, total, stage):
        self.calls.append((done, total, stage))
        if self.stop_at is not None and len(self.calls) == self.stop_at:
            raise KeyboardInterrupt

    def stages(self):
        out = []
        for _, _, s in self.calls:
            if not out or out[-1] != s:
                out.append(s)
        return out


def _counts_up(calls, total=None):
    done = [d for d, _, _ in calls]
    totals = {t for _, t, _ in calls}
    assert done == sorted(done) and len(totals) == 1, calls
    if total is not None:
        assert totals == {total} and done[-1] == total, calls


# ---------------------------------------------------------------------------- scene import

def test_from_pbrt_reports_reading_then_materials():
    rec = Recorder()
    mats = bk.from_pbrt(PBRT, progress=rec)
    assert list(mats) == ["gold", "wall", "material#1 (line 3)"]
    assert rec.stages() == ["reading the scene (characters)", "materials"]
    reading = [c for c in rec.calls if c[2].startswith("reading")]
    assert len(reading) > 1                                   # reported while reading
    _counts_up(reading, len(PBRT))
    _counts_up([c for c in rec.calls if c[2] == "materials"], 3)


def test_from_pbrt_counts_included_files(tmp_path):
    (tmp_path / "inc.pbrt").write_text(PBRT)
    main = 'Include "inc.pbrt"\nMakeNamedMaterial "red" "string type" "diffuse" "rgb reflectance" [0.8 0.1 0.1]\n'
    (tmp_path / "scene.pbrt").write_text(main)
    rec = Recorder()
    assert list(bk.from_pbrt(tmp_path / "scene.pbrt", progress=rec))[-1] == "red"
    reading = [c for c in rec.calls if c[2].startswith("reading")]
    assert reading[-1][:2] == (len(main) + len(PBRT), len(main) + len(PBRT))   # the include's text counted


def test_from_pbrt_ctrl_c_while_reading():
    rec = Recorder(2)
    with pytest.raises(KeyboardInterrupt):
        bk.from_pbrt(PBRT, progress=rec)
    assert len(rec.calls) == 2 and rec.calls[-1][2].startswith("reading")   # nothing after the interrupt


def test_from_pbrt_ctrl_c_while_converting():
    n_reading = sum(1 for c in _record(lambda r: bk.from_pbrt(PBRT, progress=r)) if c[2].startswith("reading"))
    rec = Recorder(n_reading + 1)                             # the first material's step
    with pytest.raises(KeyboardInterrupt):
        bk.from_pbrt(PBRT, progress=rec)
    assert rec.calls[-1][:3] == (1, 3, "materials")


def _record(fn):
    rec = Recorder()
    fn(rec)
    return rec.calls


def test_progress_true_writes_one_line_on_stderr(capsys):
    bk.from_pbrt(PBRT, progress=True)
    err = capsys.readouterr().err
    assert err.endswith("\n") and err.count("\n") == 1        # one line, rewritten in place, ended
    assert err.rstrip().rsplit("\r", 1)[-1].strip() == "from_pbrt: materials 3/3"


def test_auto_progress_is_silent_where_nobody_watches(capsys):
    bk.from_pbrt(PBRT)                                        # stderr is captured: not a terminal
    bk.Texture(np.full((64, 64, 3), 128, np.uint8))
    assert capsys.readouterr().err == ""


def test_from_mitsuba_file_reports_each_bsdf(tmp_path):
    xml = tmp_path / "scene.xml"
    xml.write_text('<scene version="3.0.0">'
                   '<bsdf type="diffuse" id="a"><rgb name="reflectance" value="0.5"/></bsdf>'
                   '<bsdf type="roughconductor" id="b"><string name="material" value="Au"/>'
                   '<string name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf>'
                   '<bsdf type="dielectric" id="c"/></scene>')
    rec = Recorder()
    assert list(bk.from_mitsuba(str(xml), progress=rec)) == ["a", "b", "c"]
    assert rec.stages() == ["BSDFs"]
    _counts_up(rec.calls, 3)
    with pytest.raises(KeyboardInterrupt):
        bk.from_mitsuba(str(xml), progress=Recorder(1))


def test_from_gltf_reports_each_material(tmp_path):
    path = tmp_path / "m.gltf"
    path.write_text(json.dumps({"asset": {"version": "2.0"}, "materials": [
        {"name": n, "pbrMetallicRoughness": {"roughnessFactor": r}} for n, r in (("a", 0.3), ("b", 0.5))]}))
    rec = Recorder()
    assert list(bk.from_gltf(path, progress=rec)) == ["a", "b"]
    assert rec.stages() == ["materials"]
    _counts_up(rec.calls, 2)
    with pytest.raises(KeyboardInterrupt):
        bk.from_gltf(path, progress=Recorder(1))


def test_from_materialx_reports_each_material():
    pytest.importorskip("MaterialX")
    doc = '<?xml version="1.0"?>\n<materialx version="1.39">' + "".join(
        f'<UsdPreviewSurface name="{n}_sh" type="surfaceshader"><input name="roughness" type="float" value="0.4"/>'
        f'</UsdPreviewSurface><surfacematerial name="{n}" type="material">'
        f'<input name="surfaceshader" type="surfaceshader" nodename="{n}_sh"/></surfacematerial>' for n in "ab") \
        + "</materialx>"
    rec = Recorder()
    assert list(bk.from_materialx(doc, progress=rec)) == ["a", "b"]
    _counts_up(rec.calls, 2)
    with pytest.raises(KeyboardInterrupt):
        bk.from_materialx(doc, progress=Recorder(1))


@pytest.mark.parametrize("fn", [lambda: bk.from_pbrt(PBRT, progress="yes"),
                                lambda: bk.Texture(np.zeros((2, 2)), progress=1)])
def test_progress_argument_is_checked(fn):
    with pytest.raises(TypeError, match="progress"):
        fn()


# ---------------------------------------------------------------------------- textures

def test_texture_build_reports_its_three_steps():
    rec = Recorder()
    rng = np.random.default_rng(1)
    t = bk.Texture(rng.integers(0, 256, (64, 64, 3), dtype=np.uint8), progress=rec)
    assert [c[0] for c in rec.calls] == [1, 2, 3] and {c[1] for c in rec.calls} == {3}
    assert [c[2] for c in rec.calls][:2] == ["decoding", "writing the MIP-mapped texture"]
    assert t.lookup([[0.5, 0.5]]).shape == (1, 3)


def test_texture_ctrl_c_leaves_no_partial_texture():
    img = np.random.default_rng(2).integers(0, 256, (32, 32, 3), dtype=np.uint8)
    with pytest.raises(KeyboardInterrupt):
        bk.Texture(img, progress=Recorder(2))                 # before the MIP-mapped file is written
    t = bk.Texture(img, filter="nearest")                     # the same pixels build whole afterwards
    want = ((img[5, 7] / 255.0 + 0.055) / 1.055) ** 2.4       # sRGB decoding, independent of bsdfkit
    np.testing.assert_allclose(t.lookup([[(7 + 0.5) / 32, (5 + 0.5) / 32]])[0], want, rtol=1e-5)


def test_ctrl_c_during_a_compiled_step_raises_keyboard_interrupt_at_once():
    """run_polled: the compiled call (a texture's read or write) runs on a worker thread; Ctrl-C
    (here: interrupt_main while the worker is still busy) is a KeyboardInterrupt in the caller
    without waiting for the worker, not a SystemError."""
    release, started = threading.Event(), threading.Event()

    def busy():
        started.set()
        _thread.interrupt_main()                              # what Ctrl-C does to the main thread
        release.wait(60)
        return "done"
    prog = _progress.Progress(False, 1, "busy")
    try:
        with pytest.raises(KeyboardInterrupt):
            _progress.run_polled(prog, busy)
        assert started.is_set() and not release.is_set()     # the worker was still in its call
    finally:
        release.set()


def test_run_polled_returns_and_raises_as_the_call():
    prog = _progress.Progress(False, 1, "x")
    assert _progress.run_polled(prog, lambda a, b: a + b, 2, 3) == 5
    with pytest.raises(OSError, match="bad"):
        _progress.run_polled(prog, lambda: (_ for _ in ()).throw(OSError("bad")))


# ---------------------------------------------------------------------------- textured simplify

def _textured():
    rng = np.random.default_rng(3)
    return bk.FilamentStandard(base_color=bk.Texture(rng.uniform(0.1, 0.9, (8, 8, 3))),
                               roughness=bk.Texture(rng.uniform(0.3, 0.7, (8, 8))), metallic=0.0)


def test_textured_simplify_shows_one_bar_over_all_texels():
    rec = Recorder()
    bk.simplify(_textured(), 0.05, n=256, n_albedo=32, n_texels=4, progress=rec)
    assert len(rec.stages()) == 1 and "4 texels" in rec.stages()[0]
    total = rec.calls[0][1]
    assert [c[0] for c in rec.calls] == list(range(1, total + 1))   # one count over every texel's configurations
    assert total > 4


def test_textured_simplify_ctrl_c_stops_between_configurations():
    rec = Recorder(3)
    with pytest.raises(KeyboardInterrupt):
        bk.simplify(_textured(), 0.05, n=256, n_albedo=32, n_texels=4, progress=rec)
    assert [c[0] for c in rec.calls] == [1, 2, 3]


# ---------------------------------------------------------------------------- the helper's rules

def test_auto_bar_waits_its_delay_and_nested_auto_bars_stay_silent(monkeypatch, capsys):
    monkeypatch.setattr(_progress, "_interactive", lambda: True)   # as if stderr were a terminal
    with _progress.Progress(None, 2, "outer", "call", delay=1e9) as quiet:   # a short call: never shown
        quiet.advance()
        quiet.advance()
    assert capsys.readouterr().err == ""
    with _progress.Progress(None, 2, "outer", "call", delay=0) as outer:
        with _progress.Progress(None, 5, "inner", "nested", delay=0) as inner:
            inner.advance()
        outer.advance()
        outer.advance()
    err = capsys.readouterr().err
    assert "nested" not in err and err.rstrip().rsplit("\r", 1)[-1].strip() == "call: outer 2/2"
    with _progress.Progress(None, 1, "again", "later", delay=0) as after:   # closed bars release the rule
        after.advance()
    assert "later: again 1/1" in capsys.readouterr().err
