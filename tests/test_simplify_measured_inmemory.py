"""tradeoff / simplify of an in-memory measured model (issue 50, item 5).

``bk.simplify(bk.measured.tabulate(m), tol, families=...)`` raised "path, data: give exactly one
of them": the tuning code rebuilds models from their parameters, and an in-memory Measured's
parameters are (path=None, digest). The in-memory model must behave as the same file loaded from disk.
"""
import numpy as np
import pytest

import bsdfkit as bk


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    mem = bk.measured.tabulate(bk.Conductor.from_metal("Cu", alpha=0.3), resolution=16)
    path = mem.save(tmp_path_factory.mktemp("tab") / "cu.bsdf")
    return mem, bk.Measured(path)


def test_tradeoff_of_an_in_memory_table_equals_the_file(pair):
    mem, disk = pair
    assert mem._params["path"] is None
    a, b = bk.tradeoff(mem, measure=False, n=256), bk.tradeoff(disk, measure=False, n=256)
    assert len(a) == len(b) >= 2
    for col in ("max_err", "p99_err", "albedo_err"):
        np.testing.assert_array_equal(a[col], b[col])
    assert a[0]["p99_err"] == 0.0 and a[1]["p99_err"] > 0      # float64 itself, then float32


def test_simplify_families_of_an_in_memory_table_equals_the_file(pair):
    mem, disk = pair
    fams = (bk.Diffuse, bk.Conductor)
    m1, r1 = bk.simplify(mem, 0.9, families=fams, n=512)
    m2, r2 = bk.simplify(disk, 0.9, families=fams, n=512)
    assert [f.family for f in r1.fits] == [f.family for f in r2.fits] == ["Diffuse", "Conductor"]
    assert [f.error for f in r1.fits] == pytest.approx([f.error for f in r2.fits], rel=1e-9)
    assert m1 == m2 and isinstance(m1, bk.Conductor)


def test_simplify_knobs_of_an_in_memory_table(pair):
    mem, _ = pair
    m, rep = bk.simplify(mem, 1e-3)
    assert rep.within_tol and m == mem      # the table's only knob is precision

