"""Colorimetry: CIE 1931 colour-matching functions, the D65 illuminant and the projection of a
spectrum to linear sRGB, all from colour-science's tables (the few used here are kept in the
package, ``data/cie1931_d65.npz``, written from colour-science by :func:`write_table_file`: importing
colour-science takes seconds, reading the file a millisecond; the tests check the file against it).

Two discretisations of the projection (the spectrum times the CMFs, times D65 for reflectances,
summed over wavelength, then Mitsuba's / pbrt's XYZ -> linear sRGB matrix):

* ``"mitsuba"``: Mitsuba 3's RGB variants (``mitsuba::spectrum_list_to_srgb``) to ~1e-7: 1000
  equally spaced wavelengths in [360, 830] nm, the CMFs and D65 linearly interpolated in their
  5 nm tables, Mitsuba's normalisation constants. A constant 1 projects to (0.99899, 0.99887,
  0.99880), not white: Mitsuba's D65 constant is 0.11 % off the sum on its own grid.
* ``"pbrt"``: pbrt-v4's ``SpectrumToXYZ``: every nm from 360 to 830 with the 1 nm CMF table,
  divided by the sum of y-bar, D65 scaled to luminance 1 on the same grid; a constant c
  projects to grey c within 1e-4 (the rounding of the matrix). The RGB -> spectrum uplift is
  fitted for this one, so its round trip is exact up to table interpolation.
"""
from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

__all__ = ["LAMBDA_MIN", "LAMBDA_MAX", "XYZ_TO_SRGB", "SRGB_TO_XYZ", "cmfs", "d65", "project", "xyz_to_srgb",
           "CIE_Y_INTEGRAL"]

#: Visible range of the spectral path (pbrt-v4 ``Lambda_min`` / ``Lambda_max``), nm.
LAMBDA_MIN, LAMBDA_MAX = 360.0, 830.0
#: Integral of CIE 1931 y-bar over [360, 830] nm on its 1 nm table (pbrt-v4 ``CIE_Y_integral``;
#: recomputed from colour-science's table in :func:`cie_y_integral`, equal to 1e-6).
CIE_Y_INTEGRAL = 106.856895
#: XYZ -> linear sRGB (BT.709 primaries, D65 white) as Mitsuba 3 (``xyz_to_srgb``) and pbrt-v4's
#: rgb2spec optimizer write it (Poynton's rounding). colour-science's matrix computed from the
#: sRGB primaries differs by up to 4.9e-4 per entry; this one is kept so that the projection
#: reproduces Mitsuba's.
XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                        [-0.969256, 1.875991, 0.041556],
                        [0.055648, -0.204043, 1.057311]])
XYZ_TO_SRGB.setflags(write=False)
SRGB_TO_XYZ = np.linalg.inv(XYZ_TO_SRGB)
SRGB_TO_XYZ.setflags(write=False)

# Mitsuba 3's normalisation constants (include/mitsuba/core/spectrum.h): MI_CIE_Y_NORMALIZATION
# (1 / its float32 sum of y-bar over its 1000-point grid) and MI_CIE_D65_NORMALIZATION.
_MI_Y_NORMALIZATION = 1.0 / 106.7502593994140625
_MI_D65_NORMALIZATION = 1.0 / 98.99741751876255
_N_GRID = 1000   # Mitsuba's integration points over [360, 830] nm


#: The package's copy of the colour-science tables :func:`_tables` returns.
TABLE_FILE = Path(__file__).resolve().parent.parent / "data" / "cie1931_d65.npz"
_TABLE_KEYS = ("w5", "cmf5", "d65_5", "w1", "cmf1")


@functools.lru_cache(maxsize=None)
def _tables():
    """(5 nm wavelengths (95,), CMFs (95, 3), D65 (95,), 1 nm wavelengths (471,), CMFs (471, 3)),
    read-only float64: colour-science's tables (:func:`tables_from_colour`) as kept in
    :data:`TABLE_FILE`; from colour-science itself if the file is missing."""
    try:
        with np.load(TABLE_FILE) as z:
            out = tuple(np.array(z[k], dtype=np.float64) for k in _TABLE_KEYS)
    except FileNotFoundError:
        out = tables_from_colour()
    for a in out:
        a.setflags(write=False)
    return out


def tables_from_colour():
    """The tables of :func:`_tables` computed from colour-science (imports it: seconds).

    D65: colour-science tabulates CIE D65 from 300 to 780 nm; 785-830 nm come from its CIE
    daylight series at 6504 K (M1, M2 rounded as CIE 015 does), which reproduces the CIE table
    there to 5e-5 (of ~60)."""
    import colour

    w5 = np.arange(360.0, 830.5, 5.0)
    w1 = np.arange(360.0, 830.5, 1.0)
    cmf = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    c5 = np.asarray(cmf[w5], dtype=np.float64)
    c1 = np.asarray(cmf[w1], dtype=np.float64)
    tab = colour.SDS_ILLUMINANTS["D65"]
    inside = w5 <= tab.wavelengths[-1]
    series = colour.sd_CIE_illuminant_D_series(colour.temperature.CCT_to_xy_CIE_D(6500.0 * 1.4388 / 1.4380))
    d = np.where(inside, np.asarray(tab[np.where(inside, w5, 360.0)]), np.asarray(series[w5]) * 100.0 / series[560])
    return (w5, c5, np.asarray(d, dtype=np.float64), w1, c1)


def write_table_file(path=None):
    """Writes :func:`tables_from_colour` to ``path`` (default :data:`TABLE_FILE`); run it when
    colour-science's tables change (tests/test_spectral_tables.py fails then)."""
    np.savez(TABLE_FILE if path is None else path, **dict(zip(_TABLE_KEYS, tables_from_colour())))


def _lerp_table(w, table, lam):
    """Linear interpolation in a uniform table (rows = wavelengths), 0 outside it (Mitsuba's
    ``cie1931_xyz`` / ``cie_d65`` lookups)."""
    t = (lam - w[0]) * ((len(w) - 1) / (w[-1] - w[0]))
    i0 = np.clip(t.astype(np.int64), 0, len(w) - 2)
    a = (t - i0)[..., None] if table.ndim == 2 else t - i0
    v = (1.0 - a) * table[i0] + a * table[i0 + 1]
    inside = (lam >= w[0]) & (lam <= w[-1])
    return np.where(inside[..., None] if table.ndim == 2 else inside, v, 0.0)


def cmfs(wavelengths, *, table: str = "1nm") -> np.ndarray:
    """CIE 1931 2-degree colour-matching functions x-bar, y-bar, z-bar at ``wavelengths`` (nm),
    linearly interpolated in colour-science's 1 nm table (``table="1nm"``, pbrt-v4's) or its
    5 nm subsampling (``"5nm"``, Mitsuba's), 0 outside [360, 830]. Returns (..., 3) float64."""
    w5, c5, _, w1, c1 = _tables()
    lam = np.asarray(wavelengths, dtype=np.float64)
    if table == "1nm":
        return _lerp_table(w1, c1, lam)
    if table == "5nm":
        return _lerp_table(w5, c5, lam)
    raise ValueError(f"table: expected '1nm' or '5nm', got {table!r}")


def d65(wavelengths) -> np.ndarray:
    """CIE standard illuminant D65 (relative, 100 at 560 nm) at ``wavelengths`` (nm): linear in
    its 5 nm table, 0 outside [360, 830]."""
    w5, _, d, _, _ = _tables()
    return _lerp_table(w5, d, np.asarray(wavelengths, dtype=np.float64))


@functools.lru_cache(maxsize=None)
def _grid(normalization):
    """(wavelengths, CMFs (n, 3), D65 (n,), scale, D65 scale) of a projection: XYZ =
    sum(values * cmf * [D65 * D65 scale]) * scale."""
    if normalization == "mitsuba":
        w = LAMBDA_MIN + np.arange(_N_GRID) / (_N_GRID - 1.0) * (LAMBDA_MAX - LAMBDA_MIN)
        c = cmfs(w, table="5nm")
        return w, c, d65(w), (LAMBDA_MAX - LAMBDA_MIN) / _N_GRID * _MI_Y_NORMALIZATION, _MI_D65_NORMALIZATION
    if normalization == "pbrt":
        w = np.arange(LAMBDA_MIN, LAMBDA_MAX + 0.5, 1.0)
        c = cmfs(w, table="1nm")
        d = d65(w)
        return w, c, d, 1.0 / c[:, 1].sum(), c[:, 1].sum() / (d * c[:, 1]).sum()
    raise ValueError(f"normalization: expected 'mitsuba' or 'pbrt', got {normalization!r}")


def grid_weights(*, illuminant: str | None = "D65", normalization: str = "mitsuba"):
    """A projection as weights: (w (n,), W (n, 3)) with XYZ = values(w) @ W.

    normalization: "mitsuba" (1000 points, 5 nm CMFs, Mitsuba's constants) or "pbrt" (pbrt-v4's
    ``SpectrumToXYZ``: every nm from 360 to 830, 1 nm CMFs, divided by the sum of y-bar; the
    illuminant scaled to luminance 1 on the same grid). illuminant: "D65" or None."""
    if illuminant not in ("D65", None):
        raise ValueError(f"illuminant: expected 'D65' or None, got {illuminant!r}")
    w, c, d, scale, dscale = _grid(normalization)
    weight = d * dscale if illuminant == "D65" else np.ones_like(w)
    return w, c * (weight * scale)[:, None]


def xyz_to_srgb(xyz) -> np.ndarray:
    """Linear sRGB of CIE XYZ (..., 3) with Mitsuba's/pbrt's matrix."""
    return np.asarray(xyz, dtype=np.float64) @ XYZ_TO_SRGB.T


def project(wavelengths, values, *, d65: bool = True, bounded: bool = False,
            normalization: str = "mitsuba") -> np.ndarray:
    """Linear sRGB of a piecewise-linear spectrum given by (wavelengths, values), as Mitsuba 3's
    RGB variants compute it (``mitsuba::spectrum_list_to_srgb``): the spectrum is 0 outside
    [wavelengths[0], wavelengths[-1]]. ``d65``: weight by D65 (reflectances and other
    non-emitter spectra in Mitsuba scene dicts); ``bounded``: clip to [0, 1], otherwise clamp
    at 0. Returns float64 (3,)."""
    lam = np.asarray(wavelengths, dtype=np.float64).reshape(-1)
    val = np.asarray(values, dtype=np.float64).reshape(-1)
    if lam.size == 0 or lam.size != val.size:
        raise ValueError(f"wavelengths, values: need the same non-zero length, got {lam.size} and {val.size}")
    if not (np.all(np.isfinite(lam)) and np.all(np.isfinite(val))):
        raise ValueError("wavelengths, values: must be finite")
    if np.any(np.diff(lam) <= 0):
        raise ValueError(f"wavelengths: must be strictly increasing, got {lam.tolist()}")
    w, W = grid_weights(illuminant="D65" if d65 else None, normalization=normalization)
    keep = (w >= lam[0]) & (w <= lam[-1])
    if lam.size == 1:
        v = np.full(int(keep.sum()), val[0])
    else:
        v = np.interp(w[keep], lam, val)
    with np.errstate(over="ignore", invalid="ignore"):
        rgb = xyz_to_srgb(v @ W[keep])
    if not np.all(np.isfinite(rgb)):   # finite values near float64's max overflow in the sums
        raise ValueError(f"values: the spectrum's projection to RGB overflows (values up to "
                         f"{float(np.max(np.abs(val))):.3g})")
    return np.clip(rgb, 0.0, 1.0) if bounded else np.maximum(rgb, 0.0)


def cie_y_integral() -> float:
    """Integral of y-bar over [360, 830] nm, a 1 nm sum over colour-science's table (pbrt-v4's
    ``CIE_Y_integral`` = 106.856895)."""
    return float(_tables()[4][:, 1].sum())
