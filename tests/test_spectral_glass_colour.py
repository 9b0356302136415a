"""Clear glass stays clear in spectral mode (issue 50, item 8).

The README's spectral example converted a BK7 glass's sampling weights with
``bk.spectrum_to_rgb(s.weight, lam, pdf)``, which took them as radiance: [0.558, 0.437, 0.416],
a red glass. Weights are the material under white light: illuminant="D65" gives the grey the
RGB model has. The argument is now required, so the mistake cannot be made silently.
"""
import numpy as np
import pytest

import bsdfkit as bk


def _glass_weights():
    glass = bk.Dielectric(eta=bk.Spectrum.named("glass-BK7"))
    rng = np.random.default_rng(3)
    n = 200_000
    lam, lam_pdf = bk.sample_wavelengths(rng.random(n))
    wo = bk.direction(theta=np.radians(40.0), phi=0.0)
    s = glass.sample(wo, rng.random(n), rng.random((n, 2)), wavelengths=lam)
    return glass, wo, s, lam, bk.spectral.terminate_secondary(lam_pdf, s.terminated)


def test_clear_glass_is_grey_under_white_light():
    glass, wo, s, lam, pdf = _glass_weights()
    rgb = bk.spectrum_to_rgb(s.weight, lam, pdf, illuminant="D65").mean(0)
    # the RGB-mode model (eta at 550 nm): reflected R plus transmitted (1 - R) / eta^2, grey
    ref = bk.Dielectric(float(glass.eta(550.0))).albedo(wo, n_samples=1 << 18, seed=1)
    assert np.ptp(ref) < 1e-12
    np.testing.assert_allclose(rgb, ref, rtol=0.02)
    assert np.ptp(rgb) / rgb.mean() < 0.03          # grey, not [0.558, 0.437, 0.416]


def test_illuminant_is_required():
    _, _, s, lam, pdf = _glass_weights()
    with pytest.raises(TypeError, match="illuminant: required: 'D65' if values are reflectances"):
        bk.spectrum_to_rgb(s.weight[:10], lam[:10], pdf[:10])
    radiance = bk.spectrum_to_rgb(s.weight[:10], lam[:10], pdf[:10], illuminant=None)   # explicit: allowed
    assert radiance.shape == (10, 3)
