"""The colour-science tables bsdfkit keeps in the package (spectral/colorimetry.py TABLE_FILE: CIE
1931 CMFs on 5 nm and 1 nm grids, D65 on 5 nm) are exactly what colour-science gives, so the first
spectral call does not need to import colour-science (seconds) and still uses its data."""
import numpy as np

from bsdfkit.spectral import colorimetry


def test_table_file_equals_colour_science():
    kept = colorimetry._tables()
    fresh = colorimetry.tables_from_colour()
    assert len(kept) == len(fresh) == 5
    for name, a, b in zip(("w5", "cmf5", "d65_5", "w1", "cmf1"), kept, fresh):
        assert a.shape == b.shape and np.array_equal(a, b), name


def test_tables_against_cie_values():
    # independent spot values of the CIE 1931 2-degree observer (CIE 015:2018 table) and D65
    w5, c5, d, w1, c1 = colorimetry._tables()
    assert np.allclose(c1[w1 == 555.0][0], [0.5120501, 1.0000000, 0.0057499], atol=1e-6)
    assert np.allclose(c5[w5 == 600.0][0], [1.0622000, 0.6310000, 0.0008000], atol=1e-6)
    assert d[w5 == 560.0][0] == 100.0
    assert abs(d[w5 == 500.0][0] - 109.354) < 1e-3
    assert abs(colorimetry.cie_y_integral() / colorimetry.CIE_Y_INTEGRAL - 1) < 1e-6   # pbrt-v4 CIE_Y_integral
