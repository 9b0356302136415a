"""Wavelength sampling (pbrt-v4 ``SampledWavelengths``) and Monte Carlo estimates of colour."""
from __future__ import annotations

import numpy as np

from . import colorimetry

__all__ = ["N_SPECTRUM_SAMPLES", "sample_wavelengths", "visible_pdf", "spectrum_to_rgb", "terminate_secondary"]

#: Wavelengths per sample (pbrt-v4 ``NSpectrumSamples``).
N_SPECTRUM_SAMPLES = 4
_METHODS = ("visible", "uniform")


def visible_pdf(wavelengths) -> np.ndarray:
    """pbrt-v4 ``VisibleWavelengthsPDF``: 0.0039398042 / cosh^2(0.0072 (lambda - 538)) on
    [360, 830] nm, 0 outside (Radziszewski et al. 2009's fit to the luminous efficiency).

    Parameters
    ----------
    wavelengths : array_like
        In nm.

    Returns
    -------
    numpy.ndarray
        The density per nm, the input's shape."""
    lam = np.asarray(wavelengths, dtype=np.float64)
    inside = (lam >= colorimetry.LAMBDA_MIN) & (lam <= colorimetry.LAMBDA_MAX)
    return np.where(inside, 0.0039398042 / np.cosh(0.0072 * (lam - 538.0)) ** 2, 0.0)


def _sample_visible(u):
    # pbrt-v4 SampleVisibleWavelengths: the inverse CDF of visible_pdf.
    return 538.0 - 138.888889 * np.arctanh(0.85691062 - 1.82750197 * u)


def _check_u(u):
    a = np.asarray(u)
    if a.dtype.kind not in "fiu" or a.dtype == np.bool_:
        raise TypeError(f"u: expected real numbers in [0, 1), got dtype {a.dtype}")
    a = a.astype(np.float64)
    if not np.all(np.isfinite(a)) or np.any((a < 0) | (a > 1)):
        raise ValueError("u: every value must be finite and in [0, 1]")
    return a


def sample_wavelengths(u, method: str = "visible"):
    """Four stratified wavelengths per uniform sample ``u`` (any shape, values in [0, 1]), as
    pbrt-v4's ``SampledWavelengths``: the i-th uses u + i/4 (wrapped into [0, 1)).

    Parameters
    ----------
    u : float or array_like
        Uniforms in [0, 1], any shape.
    method : {"visible", "uniform"}, optional
        ``SampleVisible`` (importance sampling of the visible range by :func:`visible_pdf`) or
        ``SampleUniform`` (uniform on [360, 830] nm, the others offset by a quarter of the
        range, wrapped).

    Returns
    -------
    wavelengths : numpy.ndarray, shape (..., 4)
        In nm, float64.
    pdf : numpy.ndarray, shape (..., 4)
        Per nm, of each wavelength alone (a Monte Carlo estimate averages f / pdf over the four).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> lam, pdf = bk.sample_wavelengths([0.1, 0.6])
    >>> lam.shape, bool(((lam >= 360) & (lam <= 830)).all())
    ((2, 4), True)
    """
    if method not in _METHODS:
        raise ValueError(f"method: expected 'visible' or 'uniform', got {method!r}")
    a = _check_u(u)
    lo, hi = colorimetry.LAMBDA_MIN, colorimetry.LAMBDA_MAX
    i = np.arange(N_SPECTRUM_SAMPLES) / N_SPECTRUM_SAMPLES
    if method == "visible":
        up = a[..., None] + i
        up = np.where(up > 1.0, up - 1.0, up)
        # pbrt's rounded constants map u = 1 to 830.0000076 nm (pdf 0 there); clamp to the range.
        lam = np.clip(_sample_visible(up), lo, hi)
        return lam, visible_pdf(lam)
    lam = lo + a[..., None] * (hi - lo) + i * (hi - lo)
    lam = np.where(lam > hi, lo + (lam - hi), lam)
    return lam, np.full(lam.shape, 1.0 / (hi - lo))


_REQUIRED = object()


def spectrum_to_rgb(values, wavelengths, pdf, *, space: str = "srgb", illuminant=_REQUIRED) -> np.ndarray:
    """Monte Carlo estimate of the colour of spectral samples (pbrt-v4
    ``SampledSpectrum::ToXYZ`` / ``ToRGB``): XYZ = mean over the last axis of
    values * cmf(lambda) / pdf, divided by the integral of y-bar (pbrt-v4's 1 nm CIE 1931 table
    from colour-science); samples with pdf = 0 contribute 0 (terminated secondary wavelengths).

    Parameters
    ----------
    values, wavelengths, pdf : array_like
        Broadcast together, last axis = the wavelengths of one estimate (4 from
        :func:`sample_wavelengths`).
    space : {"srgb", "xyz"}, optional
        Linear sRGB (BT.709 primaries; default) or CIE XYZ.
    illuminant : {"D65", None}
        Required, keyword: ``"D65"`` when ``values`` are reflectances or BSDF sampling
    weights (``s.weight``: the colour of the material lit by white D65 light of unit luminance),
    ``None`` when they are radiance (a rendered path's spectrum). There is no default: the
    function cannot tell the two apart, and taking a clear glass's weights as radiance turns it
    red ([0.558, 0.437, 0.416] instead of [0.463, 0.461, 0.458]).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        float64, one estimate per leading index; average them for the pixel value.

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> lam, pdf = bk.sample_wavelengths(np.linspace(0, 1, 4096, endpoint=False))
    >>> rgb = bk.spectrum_to_rgb(np.ones_like(lam), lam, pdf, illuminant="D65").mean(0)
    >>> np.allclose(rgb, 1, atol=0.02)   # a white reflectance under D65 is white
    True
    """
    if illuminant is _REQUIRED:
        raise TypeError("illuminant: required: 'D65' if values are reflectances or BSDF weights (s.weight: the "
                        "material under white light), None if they are radiance")
    if space not in ("srgb", "xyz"):
        raise ValueError(f"space: expected 'srgb' or 'xyz', got {space!r}")
    if illuminant not in (None, "D65"):
        raise ValueError(f"illuminant: expected None or 'D65', got {illuminant!r}")
    arrs = []
    for x, name in ((values, "values"), (wavelengths, "wavelengths"), (pdf, "pdf")):
        a = np.asarray(x)
        if a.dtype.kind not in "fiu" or a.dtype == np.bool_:
            raise TypeError(f"{name}: expected real numbers, got dtype {a.dtype}")
        a = a.astype(np.float64)
        if a.ndim == 0:
            raise ValueError(f"{name}: expected at least one axis (the wavelengths of an estimate)")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name}: must be finite")
        arrs.append(a)
    val, lam, p = arrs
    if np.any(p < 0):
        raise ValueError("pdf: must be >= 0")
    if np.any((lam < colorimetry.LAMBDA_MIN) | (lam > colorimetry.LAMBDA_MAX)):
        raise ValueError(f"wavelengths: must be in [{colorimetry.LAMBDA_MIN:g}, {colorimetry.LAMBDA_MAX:g}] nm")
    try:
        val, lam, p = np.broadcast_arrays(val, lam, p)
    except ValueError:
        raise ValueError(f"values, wavelengths, pdf: shapes {np.shape(values)}, {np.shape(wavelengths)}, "
                         f"{np.shape(pdf)} do not broadcast") from None
    if illuminant == "D65":
        val = val * colorimetry.d65(lam) * colorimetry._grid("pbrt")[4]   # D65 of luminance 1
    w = np.divide(val, p, out=np.zeros(val.shape), where=p > 0)
    xyz = np.einsum("...k,...kc->...c", w, colorimetry.cmfs(lam)) / (val.shape[-1] * colorimetry.cie_y_integral())
    return colorimetry.xyz_to_srgb(xyz) if space == "srgb" else xyz


def terminate_secondary(pdf, terminated):
    """pbrt-v4's ``SampledWavelengths::TerminateSecondary`` applied where ``terminated``: the
    wavelength pdfs (..., 4) with lambda1..3 set to 0 and lambda0's divided by 4 (a new array).
    Use it on the wavelength pdf of a path whose sample refracted through a dispersive
    dielectric (``SampleResult.terminated``) before ``bsdfkit.spectrum_to_rgb``.

    Parameters
    ----------
    pdf : array_like, shape (..., 4)
        The wavelength pdfs.
    terminated : array_like of bool, shape (...)
        Where the secondary wavelengths were terminated.

    Returns
    -------
    numpy.ndarray, shape (..., 4)
        The new pdfs."""
    p = np.array(pdf, dtype=np.float64, copy=True)
    t = np.asarray(terminated, dtype=bool)
    if p.ndim == 0 or p.shape[-1] != 4:
        raise ValueError(f"pdf: expected last axis of length 4, got shape {p.shape}")
    try:
        t = np.broadcast_to(t, p.shape[:-1])
    except ValueError:
        raise ValueError(f"terminated: shape {t.shape} does not broadcast with pdf {p.shape[:-1]}") from None
    p[..., 0] = np.where(t, p[..., 0] / 4.0, p[..., 0])
    p[..., 1:] = np.where(t[..., None], 0.0, p[..., 1:])
    return p
