"""Spectrum -> linear sRGB the way Mitsuba 3's RGB variants project it (CIE 1931 observer, D65).

The CIE tables come from colour-science through :mod:`bsdfkit.spectral.colorimetry`, which also
serves ``bk.Spectrum.to_rgb``; this module keeps the interop entry point.
"""
from __future__ import annotations

import numpy as np

from ..spectral.colorimetry import project

__all__ = ["spectrum_to_rgb"]


def spectrum_to_rgb(wavelengths, values, *, d65: bool = True, bounded: bool = False) -> np.ndarray:
    """Linear sRGB (BT.709 primaries) of a piecewise-linear spectrum, as Mitsuba 3's RGB variants
    compute it (``mitsuba::spectrum_list_to_srgb``).

    wavelengths: increasing, in nm; values: the spectrum at those wavelengths (linear in between,
    0 outside). The product with the CIE 1931 2-degree colour-matching functions (colour-science's
    table at 5 nm steps, linearly interpolated) is summed at Mitsuba's 1000 equally spaced points
    over [360, 830] nm, normalised so that a constant 1 has luminance Y = 1 (Mitsuba's ``MI_CIE_Y_NORMALIZATION``),
    and converted XYZ -> linear sRGB.

    d65: weight by the CIE D65 illuminant (normalised to unit luminance). Mitsuba does so for every
    non-emitter spectrum given in a scene dictionary (``{"type": "spectrum", "value": [(λ, v),
    ...]}``): a constant spectrum then maps to grey. Mitsuba's IOR presets (``material="Cu"``,
    ``bsdfkit.METALS``) are projected without it (``d65=False``).
    bounded: clip to [0, 1] (reflectances); otherwise only negative values are clamped to 0
    (eta, k), as Mitsuba does. Returns float64 (3,).
    """
    return project(wavelengths, values, d65=d65, bounded=bounded, normalization="mitsuba")
