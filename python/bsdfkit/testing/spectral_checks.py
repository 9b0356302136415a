"""Contract properties of spectral mode (``wavelengths=``), shared by the spectral test modules.

Each check takes a model and its inputs, asserts, and returns what a test may check further:

``reciprocity(m, wo, wi, lam, keep=None)``
    f(wo, wi) in Radiance mode equals f(wi, wo) in Importance mode per wavelength (rtol 1e-7 as
    the RGB contract; atol 1e-12 of the maximum for values that cancel). ``keep``: a mask of the
    pairs to compare (e.g. the reflection pairs of a dispersive model). Returns the compared
    values (the caller checks they are not all 0 where the model has a non-delta lobe).
``sample_consistency(m, wo, u_c, u, lam)``
    valid samples of a non-delta lobe carry f and pdf equal to ``eval`` / ``pdf`` at the sampled
    direction (rtol 1e-9); invalid samples have f = pdf = 0 and wi = +z; everything is finite.
    Returns ``(sample, glossy mask, eval f, pdf)``.
"""
from __future__ import annotations

import numpy as np

from .._enums import BxDFFlags, TransportMode

__all__ = ["reciprocity", "sample_consistency"]


def reciprocity(m, wo, wi, lam, keep=None, rtol: float = 1e-7):
    a = m.eval(wo, wi, mode=TransportMode.Radiance, wavelengths=lam)
    b = m.eval(wi, wo, mode=TransportMode.Importance, wavelengths=lam)
    if keep is not None:
        a, b = a[keep], b[keep]
    np.testing.assert_allclose(a, b, rtol=rtol, atol=1e-12 * a.max())
    return a, b


def sample_consistency(m, wo, u_c, u, lam):
    s = m.sample(wo, u_c, u, wavelengths=lam)
    f = m.eval(wo, s.wi, wavelengths=lam)
    p = m.pdf(wo, s.wi, wavelengths=lam)
    glossy = s.valid & ((s.flags & BxDFFlags.Specular) == 0)
    np.testing.assert_allclose(s.f[glossy], f[glossy], rtol=1e-9, atol=1e-300)
    np.testing.assert_allclose(s.pdf[glossy], p[glossy], rtol=1e-9, atol=1e-300)
    assert np.all(s.f[~s.valid] == 0) and np.all(s.pdf[~s.valid] == 0)
    assert np.all(s.wi[~s.valid] == [0, 0, 1])
    assert np.isfinite(s.f).all() and np.isfinite(f).all() and np.isfinite(p).all()
    return s, glossy, f, p
