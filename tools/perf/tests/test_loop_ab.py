"""tools/perf/loop_ab.py: the harness over batch.h's loops builds, runs and reads its own output, and an
A/B against a revision's headers runs both binaries (the figures themselves are timings: not
asserted)."""
import shutil
import sys
import subprocess
from pathlib import Path

import pytest
from perf_support import load_tool

_ROOT = Path(__file__).resolve().parents[3]
_PATH = _ROOT / "tools" / "perf" / "loop_ab.py"


@pytest.fixture(scope="module")
def loop_ab():
    return load_tool("loop_ab.py")


def test_parse_reads_model_op_pairs(loop_ab):
    text = "# header\ndiffuse eval 26.61 pdf 18.40 sample 92.30\ncond_r pdf 33.5\nnoise line\n"
    assert loop_ab.parse(text) == {("diffuse", "eval"): 26.61, ("diffuse", "pdf"): 18.40,
                                   ("diffuse", "sample"): 92.30, ("cond_r", "pdf"): 33.5}


def test_source_holds_only_the_requested_models_and_ops(loop_ab):
    src = loop_ab.source(["diffuse"], ["pdf"])
    assert 'run("diffuse"' in src and 'run("cond_r"' not in src
    assert 'std::string ops = "pdf";' in src
    assert "using Vec = std::vector<T, std::allocator<T>>" in src
    assert "using Vec = std::vector<T, A64<T>>" in loop_ab.source(["diffuse"], ["pdf"], aligned=True)
    assert "using F = float;" in src and "DiffuseBxDF<float>::make" in src


def test_source_float64_instantiates_double_models(loop_ab):
    src = loop_ab.source(["plastic_r", "nfresnel"], ["eval"], dtype="float64")
    assert "using F = double;" in src and "<float>" not in src
    assert "PlasticBxDF<double>::make(p)" in src and "NormalizedFresnelBxDF<double>::make({})" in src


@pytest.mark.parametrize("bad", [["--models", "nope"], ["--ops", "albedo"], ["--n", "3"], ["--dtype", "float16"]])
def test_bad_arguments_are_named(loop_ab, bad, capsys):
    with pytest.raises(SystemExit) as e:
        loop_ab.main(bad)
    assert e.value.code == 2
    assert bad[0] in capsys.readouterr().err


@pytest.mark.skipif(shutil.which("g++") is None, reason="needs g++ (the library's compiler)")
def test_builds_and_runs_one_kernel(loop_ab, tmp_path):
    out = subprocess.run([sys.executable, str(_PATH), "--models", "diffuse", "--ops", "pdf", "--n", "4096",
                          "--reps", "3", "--aligned", "--keep", str(tmp_path)], check=True, capture_output=True,
                         text=True).stdout
    rows = [l.split() for l in out.splitlines() if l.startswith("diffuse")]
    assert len(rows) == 1 and rows[0][1] == "pdf" and float(rows[0][2]) > 0
    assert "unexpected bad inputs" not in out


@pytest.mark.skipif(shutil.which("g++") is None or not (_ROOT / ".git").exists(), reason="needs g++ and the git checkout")
def test_ab_against_head_runs_both_sides(loop_ab, tmp_path):
    out = subprocess.run([sys.executable, str(_PATH), "--models", "diffuse", "--ops", "eval", "--n", "4096", "--reps", "3",
                          "--base", "HEAD", "--rounds", "1", "--keep", str(tmp_path)],
                         check=True, capture_output=True, text=True).stdout
    row = [l.split() for l in out.splitlines() if l.startswith("diffuse")][0]
    assert row[1] == "eval" and float(row[2]) > 0 and float(row[3]) > 0 and row[4].endswith("x")
    assert (tmp_path / "loops_a").exists() and (tmp_path / "loops_b").exists()


@pytest.mark.skipif(shutil.which("g++") is None, reason="needs g++ (the library's compiler)")
def test_bad_march_is_named(tmp_path):
    r = subprocess.run([sys.executable, str(_PATH), "--models", "diffuse", "--ops", "pdf", "--n", "4096",
                        "--march", "no-such-cpu", "--keep", str(tmp_path)], capture_output=True, text=True)
    assert r.returncode != 0 and "Traceback" not in r.stderr
    assert "-march=no-such-cpu" in r.stderr and "could not build" in r.stderr


def test_contract_source_only_with_the_flag(loop_ab):
    plain = loop_ab.source(["diffuse"], ["eval", "pdf"])
    assert "contract_loop" not in plain and "g_differ" not in plain
    src = loop_ab.source(["diffuse"], ["eval", "pdf"], contract=True)
    for variant in ("eval:rows-nocheck", "eval:planes", "eval:planes-nocheck", "pdf:rows-nocheck", "pdf:planes",
                    "pdf:planes-nocheck"):
        assert f'" {variant} %.2f"' in src
    assert "contract_loop<true, true, true>" in src and "contract variants differ" in src


def test_contract_with_base_is_refused(loop_ab, capsys):
    with pytest.raises(SystemExit) as e:
        loop_ab.main(["--contract", "--base", "HEAD"])
    assert e.value.code == 2 and "--contract" in capsys.readouterr().err


@pytest.mark.skipif(shutil.which("g++") is None, reason="needs g++ (the library's compiler)")
def test_contract_variants_run_and_match_the_library(tmp_path):
    # N = 4099: whole packets and a padded tail; the program compares every variant's values with
    # the library kernel's, bit for bit, and says so when they differ
    out = subprocess.run([sys.executable, str(_PATH), "--contract", "--models", "cond_r", "--ops", "eval,pdf",
                          "--n", "4099", "--reps", "2", "--keep", str(tmp_path)], check=True, capture_output=True,
                         text=True).stdout
    assert "differ" not in out and "unexpected bad inputs" not in out
    ops = {l.split()[1]: float(l.split()[2]) for l in out.splitlines() if l.startswith("cond_r")}
    assert set(ops) == {"eval", "pdf", "eval:rows-nocheck", "eval:planes", "eval:planes-nocheck", "pdf:rows-nocheck",
                        "pdf:planes", "pdf:planes-nocheck"}
    assert all(v > 0 for v in ops.values())


@pytest.mark.skipif(shutil.which("g++") is None, reason="needs g++")
def test_null_model_runs_every_op_and_checks_its_outputs(tmp_path):
    # the contract bound's model: the program checks that the library kernels wrote what the null
    # model defines (f = 1, pdf = 1, the mirror sample) and says so otherwise; N = 4099 has a
    # padded tail
    out = subprocess.run([sys.executable, str(_PATH), "--models", "null", "--ops", "eval,pdf,sample", "--n", "4099",
                          "--reps", "2", "--keep", str(tmp_path)], check=True, capture_output=True, text=True).stdout
    assert "wrong outputs" not in out and "unexpected bad inputs" not in out
    ops = {l.split()[1]: float(l.split()[2]) for l in out.splitlines() if l.startswith("null")}
    assert set(ops) == {"eval", "pdf", "sample"} and all(v > 0 for v in ops.values())
    # the built program also takes seconds per call and a subset of its ops (throughput.py's use)
    secs = subprocess.run([str(tmp_path / "loops_b"), "4099", "2", "3", "s", "sample"], check=True,
                          capture_output=True, text=True).stdout
    (line,) = [l.split() for l in secs.splitlines() if l.startswith("null")]
    assert line[1] == "sample" and len(line) == 3 and 0 < float(line[2]) < 1
