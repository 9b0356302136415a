"""Spectrum -> linear sRGB the way Mitsuba 3's RGB variants project it (CIE 1931 observer, D65)."""
from __future__ import annotations

import numpy as np

__all__ = ["spectrum_to_rgb"]


# CIE 1931 2-degree standard observer colour-matching functions x̄, ȳ, z̄ at 5 nm steps from 360 to
# 830 nm (CIE 015:2004 Table T.4; public data, as distributed by CVRL, cvrl.org "ciexyz31"). These
# are the values of Mitsuba 3's ``cie1931_tbl`` (src/core/spectrum.cpp).
_CIE_X = (
    0.0001299, 0.0002321, 0.0004149, 0.0007416, 0.001368, 0.002236, 0.004243, 0.00765,
    0.01431, 0.02319, 0.04351, 0.07763, 0.13438, 0.21477, 0.2839, 0.3285,
    0.34828, 0.34806, 0.3362, 0.3187, 0.2908, 0.2511, 0.19536, 0.1421,
    0.09564, 0.05795001, 0.03201, 0.0147, 0.0049, 0.0024, 0.0093, 0.0291,
    0.06327, 0.1096, 0.1655, 0.2257499, 0.2904, 0.3597, 0.4334499, 0.5120501,
    0.5945, 0.6784, 0.7621, 0.8425, 0.9163, 0.9786, 1.0263, 1.0567,
    1.0622, 1.0456, 1.0026, 0.9384, 0.8544499, 0.7514, 0.6424, 0.5419,
    0.4479, 0.3608, 0.2835, 0.2187, 0.1649, 0.1212, 0.0874, 0.0636,
    0.04677, 0.0329, 0.0227, 0.01584, 0.01135916, 0.008110916, 0.005790346, 0.004109457,
    0.002899327, 0.00204919, 0.001439971, 0.0009999493, 0.0006900786, 0.0004760213, 0.0003323011,
    0.0002348261, 0.0001661505, 0.000117413, 8.307527e-05, 5.870652e-05, 4.150994e-05, 2.935326e-05,
    2.067383e-05, 1.455977e-05, 1.025398e-05, 7.221456e-06, 5.085868e-06, 3.581652e-06, 2.522525e-06,
    1.776509e-06, 1.251141e-06,
)


_CIE_Y = (
    3.917e-06, 6.965e-06, 1.239e-05, 2.202e-05, 3.9e-05, 6.4e-05, 0.00012, 0.000217,
    0.000396, 0.00064, 0.00121, 0.00218, 0.004, 0.0073, 0.0116, 0.01684,
    0.023, 0.0298, 0.038, 0.048, 0.06, 0.0739, 0.09098, 0.1126,
    0.13902, 0.1693, 0.20802, 0.2586, 0.323, 0.4073, 0.503, 0.6082,
    0.71, 0.7932, 0.862, 0.9148501, 0.954, 0.9803, 0.9949501, 1.0,
    0.995, 0.9786, 0.952, 0.9154, 0.87, 0.8163, 0.757, 0.6949,
    0.631, 0.5668, 0.503, 0.4412, 0.381, 0.321, 0.265, 0.217,
    0.175, 0.1382, 0.107, 0.0816, 0.061, 0.04458, 0.032, 0.0232,
    0.017, 0.01192, 0.00821, 0.005723, 0.004102, 0.002929, 0.002091, 0.001484,
    0.001047, 0.00074, 0.00052, 0.0003611, 0.0002492, 0.0001719, 0.00012, 8.48e-05,
    6e-05, 4.24e-05, 3e-05, 2.12e-05, 1.499e-05, 1.06e-05, 7.4657e-06, 5.2578e-06,
    3.7029e-06, 2.6078e-06, 1.8366e-06, 1.2934e-06, 9.1093e-07, 6.4153e-07, 4.5181e-07,
)


_CIE_Z = (
    0.0006061, 0.001086, 0.001946, 0.003486, 0.006450001, 0.01054999, 0.02005001, 0.03621,
    0.06785001, 0.1102, 0.2074, 0.3713, 0.6456, 1.0390501, 1.3856, 1.62296,
    1.74706, 1.7826, 1.77211, 1.7441, 1.6692, 1.5281, 1.28764, 1.0419,
    0.8129501, 0.6162, 0.46518, 0.3533, 0.272, 0.2123, 0.1582, 0.1117,
    0.07824999, 0.05725001, 0.04216, 0.02984, 0.0203, 0.0134, 0.008749999, 0.005749999,
    0.0039, 0.002749999, 0.0021, 0.0018, 0.001650001, 0.0014, 0.0011, 0.001,
    0.0008, 0.0006, 0.00034, 0.00024, 0.00019, 0.0001, 4.999999e-05, 3e-05,
    2e-05, 1e-05) + (0.0,) * 37


# CIE standard illuminant D65, relative spectral power (100 at 560 nm), 5 nm steps from 360 to
# 830 nm (CIE S 014-2 / ISO 11664-2; public data). Mitsuba 3's ``d65_table`` (core/spectrum.h).
_D65 = (
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204,
    91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41,
    117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
    107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026,
    89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207,
    80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979,
    74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054,
    46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054,
    51.959, 54.6998, 57.4406, 58.8765, 60.3125,
)


_CIE_MIN, _CIE_MAX, _CIE_SAMPLES = 360.0, 830.0, 95


#: Mitsuba's MI_CIE_Y_NORMALIZATION (1 / integral of ȳ) and MI_CIE_D65_NORMALIZATION.
_CIE_Y_NORMALIZATION = 1.0 / 106.7502593994140625


_CIE_D65_NORMALIZATION = 1.0 / 98.99741751876255


#: XYZ -> linear sRGB (ITU-R BT.709 primaries, D65 white), Mitsuba's ``xyz_to_srgb``.
_XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                         [-0.969256, 1.875991, 0.041556],
                         [0.055648, -0.204043, 1.057311]])


def _table_lookup(table, w):
    """Mitsuba's ``cie1931_xyz``/``cie_d65`` lookup: linear interpolation in a 95-entry table,
    0 outside [360, 830] nm."""
    t = (w - _CIE_MIN) * ((_CIE_SAMPLES - 1) / (_CIE_MAX - _CIE_MIN))
    i0 = np.clip(t.astype(np.int64), 0, _CIE_SAMPLES - 2)
    w1 = t - i0
    tab = np.asarray(table, dtype=np.float64)
    v = (1.0 - w1) * tab[..., i0] + w1 * tab[..., i0 + 1]
    inside = (w >= _CIE_MIN) & (w <= _CIE_MAX)
    return np.where(inside, v, 0.0)


def spectrum_to_rgb(wavelengths, values, *, d65: bool = True, bounded: bool = False) -> np.ndarray:
    """Linear sRGB (BT.709 primaries) of a piecewise-linear spectrum, as Mitsuba 3's RGB variants
    compute it (``mitsuba::spectrum_list_to_srgb``).

    wavelengths: increasing, in nm; values: the spectrum at those wavelengths (linear in between,
    0 outside). The product with the CIE 1931 2-degree colour-matching functions (5 nm table,
    linearly interpolated) is summed at Mitsuba's 1000 equally spaced points over [360, 830] nm,
    normalised so that a constant 1 has luminance Y = 1 (Mitsuba's ``MI_CIE_Y_NORMALIZATION``),
    and converted XYZ -> linear sRGB.

    d65: weight by the CIE D65 illuminant (normalised to unit luminance). Mitsuba does so for every
    non-emitter spectrum given in a scene dictionary (``{"type": "spectrum", "value": [(λ, v),
    ...]}``): a constant spectrum then maps to grey. Mitsuba's IOR presets (``material="Cu"``,
    ``bsdfkit.METALS``) are projected without it (``d65=False``).
    bounded: clip to [0, 1] (reflectances); otherwise only negative values are clamped to 0
    (eta, k), as Mitsuba does. Returns float64 (3,).
    """
    lam = np.asarray(wavelengths, dtype=np.float64).reshape(-1)
    val = np.asarray(values, dtype=np.float64).reshape(-1)
    if lam.size == 0 or lam.size != val.size:
        raise ValueError(f"wavelengths, values: need the same non-zero length, got {lam.size} and {val.size}")
    if not (np.all(np.isfinite(lam)) and np.all(np.isfinite(val))):
        raise ValueError("wavelengths, values: must be finite")
    if np.any(np.diff(lam) <= 0):
        raise ValueError(f"wavelengths: must be strictly increasing, got {lam.tolist()}")
    w = _CIE_MIN + np.arange(1000) / 999.0 * (_CIE_MAX - _CIE_MIN)
    w = w[(w >= lam[0]) & (w <= lam[-1])]
    if lam.size == 1:
        v = np.full(w.shape, val[0])
    else:
        idx = np.clip(np.searchsorted(lam, w, side="right") - 1, 0, lam.size - 2)
        w0, w1, v0, v1 = lam[idx], lam[idx + 1], val[idx], val[idx + 1]
        v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
    weight = v * (_table_lookup(_D65, w) * _CIE_D65_NORMALIZATION if d65 else 1.0)
    xyz = _table_lookup((_CIE_X, _CIE_Y, _CIE_Z), w) @ weight
    xyz *= (_CIE_MAX - _CIE_MIN) * _CIE_Y_NORMALIZATION / 1000.0
    rgb = _XYZ_TO_SRGB @ xyz
    return np.clip(rgb, 0.0, 1.0) if bounded else np.maximum(rgb, 0.0)
