"""The DFG table bsdfkit computes for Filament's models (bk.filament.dfg_lut): layout, caching,
determinism, the alpha -> 0 limits, and its values against an independent Gauss-Legendre
quadrature (bsdfkit.testing.drjit_filament.dfg_quadrature: NDF-CDF coordinates with the
horizon cut resolved exactly; the library integrates by quasi-Monte Carlo visible-normal and
mixture sampling).

Tolerance: 1e-3 absolute, relative where the value exceeds 1 (z, the sheen albedo, reaches ~50
at grazing NoV and roughness < 0.05, which no model reads: roughness is clamped to >= 0.045).
Measured at size 128, 1024 samples: x, y <= 1.2e-4; z <= 2.5e-4."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models.filament import dfg as _dfg
from bsdfkit import _core
from bsdfkit.testing import mitsuba as ref

ref.variant()
from bsdfkit.testing import drjit_filament as dj  # noqa: E402

SIZE = 128
ROWS = [1, 2, 3, 6, 8, 12, 16, 32, 64, 96, 127]
COLS = [0, 1, 2, 3, 5, 8, 12, 16, 32, 64, 96, 127]


def test_layout_and_cache():
    lut = bk.filament.dfg_lut()
    assert lut.shape == (SIZE, SIZE, 3) and lut.dtype == np.float64 and not lut.flags.writeable
    assert bk.filament._table(SIZE) is bk.filament._table(SIZE)
    np.testing.assert_array_equal(lut, bk.filament.dfg_lut(SIZE))
    assert np.all(np.isfinite(lut)) and np.all(lut >= 0)
    assert np.all(lut[..., 0] <= lut[..., 1] + 1e-12)  # Fc <= 1
    assert np.all(lut[..., 1] <= 1 + 1e-3)              # GGX albedo with F = 1


def test_models_share_the_table():
    a, b = bk.FilamentStandard(roughness=0.3), bk.FilamentCloth(roughness=0.7)
    assert a._core is not b._core and bk.filament._table(128).size == 128
    c = bk.FilamentStandard(roughness=0.3, dfg_lut_size=32)
    wo, wi = bk.direction(0.4, 0.0), bk.direction(0.6, 3.0)
    assert not np.array_equal(a.eval(wo, wi), c.eval(wo, wi))   # another table, another interpolation
    np.testing.assert_allclose(a.eval(wo, wi), c.eval(wo, wi), rtol=2e-3)


def test_deterministic_for_any_thread_count():
    n0 = bk.get_num_threads()
    try:
        bk.set_num_threads(1)
        a = _core.filament_dfg_rows(12, 128, 0, 12)
        bk.set_num_threads(2)
        b = _core.filament_dfg_rows(12, 128, 0, 12)
        c = np.concatenate([_core.filament_dfg_rows(12, 128, 0, 5), _core.filament_dfg_rows(12, 128, 5, 12)])
    finally:
        bk.set_num_threads(n0)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)


def test_alpha_to_zero_limits():
    """Row 0 holds the alpha -> 0 limits; the computed rows approach them: y -> 1 (a smooth
    mirror with F = 1 reflects everything) and x -> (1 - NoV)^5 at every NoV."""
    lut = bk.filament.dfg_lut()
    nov = np.r_[1e-4, np.arange(1, SIZE) / (SIZE - 1)]
    np.testing.assert_array_equal(lut[0, :, 1], 1.0)
    np.testing.assert_allclose(lut[0, :, 0], (1 - nov) ** 5, rtol=1e-15)
    np.testing.assert_array_equal(lut[0, :, 2], 0.0)
    prev = None
    for size in (128, 1024, 4096):
        row = _core.filament_dfg_rows(size, 256, 1, 2)[0]
        nv = np.r_[1e-4, np.arange(1, size) / (size - 1)]
        dev = np.abs(row[:, 1] - 1)
        if prev is not None:
            assert dev.max() < prev
        prev = dev.max()
        # y - 1 and x - Fc shrink like alpha tan(theta_v) (the masking of a nearly flat surface)
        at = (1 / (size - 1)) ** 2 * np.sqrt(1 - nv ** 2) / nv
        assert np.all(dev <= 2 * at + 1e-4), (size, dev.max())
        assert np.all(np.abs(row[:, 0] - (1 - nv) ** 5) <= 2 * at + 1e-4)
    assert prev < 2e-3


@pytest.mark.parametrize("row", ROWS)
def test_against_quadrature(row):
    lut = bk.filament.dfg_lut(SIZE)
    r = row / (SIZE - 1)
    nov = np.array([1e-4 if i == 0 else i / (SIZE - 1) for i in COLS])
    q = dj.dfg_quadrature(nov, np.full(len(COLS), r), n=160)
    got = lut[row, COLS]
    err = np.abs(got - q) / np.maximum(1.0, np.abs(q))
    print(f"r={r:.4f}: max err x {err[:, 0].max():.1e} y {err[:, 1].max():.1e} z {err[:, 2].max():.1e}")
    assert err.max() < 1e-3


def test_progress_and_validation(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("BSDFKIT_CACHE_DIR", str(tmp_path))  # an empty disk cache: computed here
    _dfg._CACHE.pop((9, 64), None)
    _dfg._CACHE.pop((10, 64), None)
    bk.filament.dfg_lut(9, 64, progress=True)
    assert "computing the Filament DFG table (9x9, 64 samples" in capsys.readouterr().err
    bk.filament.dfg_lut(10, 64, progress=False)
    assert capsys.readouterr().err == ""
    bk.filament.dfg_lut(9, 64, progress=True)  # cached: nothing to report
    assert capsys.readouterr().err == ""
    for bad in (1, 0, 5000, 2.5, True):
        with pytest.raises(ValueError, match="size"):
            bk.filament.dfg_lut(bad)
    with pytest.raises(ValueError, match="samples"):
        bk.filament.dfg_lut(16, 1)
    with pytest.raises(ValueError, match="name"):
        bk.filament.term("D_Beckmann", 0.5, 0.5)
    with pytest.raises(ValueError, match="expects"):
        bk.filament.term("V_Kelemen", 0.5, 0.5)
