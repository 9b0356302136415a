"""tools/perf/bits.py: the fingerprints repeat exactly on the same build, follow the outputs, and
--compare names what differs."""

import json

import pytest
from perf_support import load_tool


@pytest.fixture(scope="module")
def bits():
    return load_tool("bits.py")


def test_fingerprints_repeat_and_compare(bits, tmp_path, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert bits.main([str(a), "--n", "700", "--no-render", "--no-spectral"]) == 0
    fp = json.loads(a.read_text())
    assert any(k.startswith("Dielectric-") for k in fp) and all(len(v) == 16 for v in fp.values())
    # the same build, the same inputs: every fingerprint again (a subset recomputed: the rest not compared)
    assert bits.main([str(b), "--n", "700", "--no-render", "--no-spectral", "--only", "Dielectric,Plastic",
                      "--compare", str(a)]) == 0
    assert "differ: none" in capsys.readouterr().out
    key = sorted(json.loads(b.read_text()))[0]
    fp[key] = "0" * 16
    a.write_text(json.dumps(fp))
    assert bits.main([str(b), "--n", "700", "--no-render", "--no-spectral", "--only", "Dielectric,Plastic",
                      "--compare", str(a)]) == 1
    assert f"differ: {key}" in capsys.readouterr().out
    assert bits.differing({"x": "1", "y": "2"}, {"x": "1", "z": "3"}) == ["y", "z"]


def test_fingerprint_follows_the_outputs(bits):
    # other inputs (one more pair) give other fingerprints, model by model
    one, two = (bits.fingerprints(n, render=False, only="Conductor,Diffuse", spectral=False) for n in (700, 701))
    assert len(one) >= 4 and one.keys() == two.keys() and all(one[k] != two[k] for k in one)
