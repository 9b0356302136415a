"""The Filament DFG table's on-disk cache (issue 11 item 8): a new process reads the table a
previous one computed (keyed by size, samples and the compiled builder's digest) instead of
spending seconds recomputing it, never prints progress when stderr is not a terminal, and
ignores a corrupt cache file. The cached table equals a fresh computation bit for bit."""
import os
import subprocess
import sys
import textwrap

import numpy as np

import bsdfkit as bk
from bsdfkit.models.filament import dfg as filament


def _run(code, cache):
    env = dict(os.environ, BSDFKIT_CACHE_DIR=str(cache))
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True,
                          timeout=600, check=True)


FIRST_EVAL = """
    import time
    t0 = time.perf_counter()
    import numpy as np, bsdfkit as bk
    t1 = time.perf_counter()
    m = bk.FilamentStandard([0.8, 0.5, 0.3])
    f = m.eval(bk.direction(theta=0.5, phi=0.0), bk.direction(theta=0.3, phi=2.0))
    t2 = time.perf_counter()
    from bsdfkit.models.filament import dfg as filament
    print(repr(float(f[0])), t2 - t1, filament._cache_path(128, filament.DFG_LUT_SAMPLES))
"""


def test_second_process_reads_the_cache(tmp_path):
    a = _run(FIRST_EVAL, tmp_path)
    f1, _, path = a.stdout.split()
    assert os.path.dirname(path) == str(tmp_path) and os.path.exists(path)
    assert a.stderr == ""  # no progress lines: stderr is not a terminal
    mtime = os.stat(path).st_mtime_ns
    b = _run(FIRST_EVAL, tmp_path)
    f2, dt2, _ = b.stdout.split()
    assert f1 == f2 and b.stderr == ""
    assert os.stat(path).st_mtime_ns == mtime  # read, not rewritten
    # the cached table is the one this process computes
    cached = np.load(path)
    np.testing.assert_array_equal(cached, filament._build(128, filament.DFG_LUT_SAMPLES, False))


def test_corrupt_cache_is_recomputed(tmp_path):
    a = _run(FIRST_EVAL, tmp_path)
    f1, _, path = a.stdout.split()
    with open(path, "wb") as fh:
        fh.write(b"not a table")
    b = _run(FIRST_EVAL, tmp_path)
    assert b.stdout.split()[0] == f1
    assert np.load(path).shape == (128, 128, 3)


def test_unwritable_cache_dir_still_works(tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("x")  # a file where the directory should be: makedirs fails
    out = _run(FIRST_EVAL.replace("128, ", "16, ").replace("bk.FilamentStandard([0.8, 0.5, 0.3])",
                                                           "bk.FilamentStandard([0.8, 0.5, 0.3], dfg_lut_size=16)"),
               blocked / "sub")
    assert out.stderr == ""


def test_cache_dir_default(monkeypatch, tmp_path):
    monkeypatch.delenv("BSDFKIT_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    if sys.platform.startswith("linux"):
        assert filament.cache_dir() == os.path.join(str(tmp_path), "bsdfkit")
    monkeypatch.setenv("BSDFKIT_CACHE_DIR", str(tmp_path / "x"))
    assert filament.cache_dir() == str(tmp_path / "x")


def test_no_progress_under_quiet(monkeypatch, capsys):
    monkeypatch.setattr(filament, "PROGRESS_DEFAULT", False)
    filament._build(8, 64, None)
    assert capsys.readouterr().err == ""
    filament._build(8, 64, True)  # an explicit request still prints
    assert "Filament DFG" in capsys.readouterr().err
