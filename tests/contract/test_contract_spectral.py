"""The contract suite's spectral axis: every registered example whose model has a spectral form
(read from ``_core`` by ``_has_spectral_kernel``, not listed here) keeps the array contract in
spectral mode (``wavelengths=``): finite, non-negative values at the extremes, samples that agree
with eval and pdf at the sampled direction, and adjoint reciprocity per wavelength."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models import registry
from bsdfkit.models.spec import parse_spec
from bsdfkit.directions import random_directions

RAD, IMP = bk.TransportMode.Radiance, bk.TransportMode.Importance
_MODELS = {}


def model_of(spec):
    if spec not in _MODELS:
        _MODELS[spec] = parse_spec(spec)
    return _MODELS[spec]


def cases(pred=lambda cls, m: True):
    """(cls, spec) of the registered examples with a spectral form satisfying ``pred``."""
    out = []
    for cls, label, spec in registry.examples():
        m = model_of(spec)
        if m._has_spectral_kernel() and pred(cls, m):
            out.append(pytest.param(cls, spec, id=f"{cls.__name__}-{label}"))
    return out


def _lam(rng, n):
    return rng.uniform(360.0, 830.0, size=(n, 4))


def test_the_spectral_axis_covers_the_registry():
    names = {p.values[0].__name__ for p in cases()}
    assert len(names) >= 12, names


@pytest.mark.parametrize("cls, spec", cases())
def test_spectral_extremes_finite(cls, spec):
    """Horizon, normal and +-1e-7 cosines, uniforms at 0 and 1, wavelengths at 360 and 830 nm:
    finite non-negative f and pdf; valid samples have pdf > 0."""
    m = model_of(spec)
    cos = np.array([0.0, 1e-7, -1e-7, 0.5, -0.5, 1.0, -1.0])
    d = np.stack([np.sqrt(1 - cos ** 2) * np.cos(0.3), np.sqrt(1 - cos ** 2) * np.sin(0.3), cos], 1)
    wo, wi = np.repeat(d, len(d), axis=0), np.tile(d, (len(d), 1))
    lam = np.resize(np.array([[360.0, 830.0, 550.0, 361.5], [830.0, 360.0, 700.0, 420.0]]), (len(wo), 4))
    u = np.resize(np.array([0.0, 1.0, 0.5, np.nextafter(1.0, 0.0)]), (len(wo), 2))
    uc = np.resize(np.array([1.0, 0.0, 0.3]), len(wo))
    for mode in (RAD, IMP):
        f, p = m.eval(wo, wi, mode=mode, wavelengths=lam), m.pdf(wo, wi, mode=mode, wavelengths=lam)
        assert f.shape == (len(wo), 4) and np.all(np.isfinite(f)) and np.all(f >= 0)
        assert np.all(np.isfinite(p)) and np.all(p >= 0)
        s = m.sample(wo, uc, u, mode=mode, wavelengths=lam)
        for arr in (s.f, s.pdf, s.wi, s.eta):
            assert np.all(np.isfinite(arr))
        assert np.all(s.f >= 0) and np.all(s.pdf[s.valid] > 0)


@pytest.mark.parametrize("cls, spec", cases(lambda c, m: m.exact_eval and bool(
    m.flags & (bk.BxDFFlags.Diffuse | bk.BxDFFlags.Glossy))))
def test_spectral_sample_agrees_with_eval_and_pdf(cls, spec):
    """At sampled directions of non-delta lobes, sample().f and .pdf equal eval() and pdf() with
    the same wavelengths (a dispersive refraction keeps its hero wavelength only, in both)."""
    m, rng = model_of(spec), np.random.default_rng(4)
    n = 3000
    wo = random_directions(n, rng, upper=not cls.two_sided)
    lam = _lam(rng, n)
    for mode in (RAD, IMP):
        s = m.sample(wo, rng.random(n), rng.random((n, 2)), mode=mode, wavelengths=lam)
        keep = s.valid & ((s.flags & bk.BxDFFlags.Specular) == 0)
        if not keep.any():
            continue
        f = m.eval(wo[keep], s.wi[keep], mode=mode, wavelengths=lam[keep])
        p = m.pdf(wo[keep], s.wi[keep], mode=mode, wavelengths=lam[keep])
        ef = np.abs(s.f[keep] - f) / np.maximum(np.abs(f), 1e-30)
        ep = np.abs(s.pdf[keep] - p) / np.maximum(p, 1e-30)
        assert np.quantile(ef, 0.999) < 1e-9, (mode, ef.max())
        assert np.quantile(ep, 0.999) < 1e-9, (mode, ep.max())


@pytest.mark.parametrize("cls, spec", cases(lambda c, m: m.reciprocal and m.exact_eval and bool(
    m.flags & (bk.BxDFFlags.Diffuse | bk.BxDFFlags.Glossy))))
def test_spectral_adjoint_reciprocity(cls, spec):
    """f(wo, wi) in Radiance mode equals f(wi, wo) in Importance mode at every wavelength."""
    m, rng = model_of(spec), np.random.default_rng(5)
    n = 3000
    wo, wi = random_directions(n, rng, upper=not cls.two_sided), random_directions(n, rng, upper=not cls.two_sided)
    lam = _lam(rng, n)
    np.testing.assert_allclose(m.eval(wo, wi, mode=RAD, wavelengths=lam), m.eval(wi, wo, mode=IMP, wavelengths=lam),
                               rtol=1e-7, atol=1e-300)
