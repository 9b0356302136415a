"""bk.NormalizedFresnel (pbrt-v4 NormalizedFresnelBxDF) against its closed form with the first
Fresnel moment computed by quadrature (bsdfkit.testing.hair_ref), its albedo, chi^2, sampling
consistency and bad input."""
import pickle

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as mref
from bsdfkit.models.normalized_fresnel import fresnel_moment1
from bsdfkit.testing import hair_ref as ref

ETAS = [1.0001, 1.2, 1.33, 1.5, 2.0, 0.75]


def test_fresnel_moment1_convention():
    """pbrt-v4's FresnelMoment1(x) fits int_0^1 Fr(mu, 1/x) mu dmu (Fr of relative IOR 1/x), so
    the model's c = 1 - 2 FresnelMoment1(1/eta) = 1 - 2 int Fr(mu, eta) mu dmu."""
    for eta in (1.2, 1.33, 1.5, 2.0, 1 / 1.33, 1 / 1.5):
        q = ref.fresnel_moment1_quad(1 / eta)
        assert abs(fresnel_moment1(eta) - q) < 1e-3, (eta, fresnel_moment1(eta), q)
        # and not the other way round (would differ by far more than the fit error)
        assert abs(fresnel_moment1(eta) - ref.fresnel_moment1_quad(eta)) > 0.01


@pytest.mark.parametrize("eta", ETAS)
@pytest.mark.parametrize("mode", ["radiance", "importance"])
def test_closed_form(eta, mode):
    m = bk.NormalizedFresnel(eta)
    rng = np.random.default_rng(1)
    wo = rng.normal(size=(20000, 3))
    wi = rng.normal(size=(20000, 3))
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    wi /= np.linalg.norm(wi, axis=-1, keepdims=True)
    f = m.eval(wo, wi, mode=mode)
    f_ref = ref.normalized_fresnel_f(eta, wo, wi, mode)
    assert np.all(f[:, 0] == f[:, 1]) and np.all(f[:, 0] == f[:, 2])
    # the model uses pbrt-v4's polynomial for FresnelMoment1, the oracle quadrature: agreement to
    # the polynomial's fit error (< 1e-3 absolute in the moment, < 3e-3 relative in f)
    assert np.allclose(f[:, 0], f_ref, rtol=3e-3, atol=0)
    assert np.all(f[wo[:, 2] * wi[:, 2] <= 0] == 0)  # 0 across the surface (and under TIR below it)
    p = m.pdf(wo, wi)
    assert np.allclose(p, np.where(wo[:, 2] * wi[:, 2] > 0, np.abs(wi[:, 2]) / np.pi, 0.0), rtol=1e-14, atol=0)


@pytest.mark.parametrize("eta", [1.2, 1.33, 1.5, 2.0])
def test_albedo(eta):
    """wo above the surface: int f cos = 1 in Importance mode and eta^2 in Radiance mode (pbrt-v4's
    adjoint factor multiplies f by eta^2 in Radiance mode). Exact quadrature over cos theta."""
    m = bk.NormalizedFresnel(eta)
    x, w = np.polynomial.legendre.leggauss(400)
    mu = 0.5 * (x + 1)
    wi = np.stack([np.sqrt(1 - mu**2), np.zeros_like(mu), mu], -1)
    wo = np.array([0.3, 0.1, np.sqrt(1 - 0.1)])
    for mode, target in (("importance", 1.0), ("radiance", eta**2)):
        a = 2 * np.pi * np.sum(0.5 * w * m.eval(wo, wi, mode=mode)[:, 0] * mu)
        assert abs(a / target - 1) < 2e-3, (mode, a, target)
        mc = m.albedo(wo, n_samples=200_000, mode=mode)
        assert np.allclose(mc, a, rtol=1e-2)


@pytest.mark.parametrize("z, eta", [(0.9, 1.4), (0.2, 1.4), (-0.5, 1 / 1.4)])
def test_chi2(z, eta):
    """Cosine sampling on wo's side (eta chosen so that no sample falls under total internal
    reflection, which pbrt-v4's BSDF rules discard: see test_tir_samples_discarded)."""
    m = bk.NormalizedFresnel(eta)
    s = np.sqrt(1 - z * z)
    wo = np.array([s, 0.0, z])
    R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])

    def sample_fn(uc, u):
        r = m.sample(wo, uc, u)
        return r.wi @ R.T, r.valid

    passed, p, msg = mref.chi2_test(sample_fn, lambda v: m.pdf(wo, v @ R), res=101, ires=4,
                                    sample_count=500_000, seed=4, significance=0.01, test_count=3)
    print(f"chi2 normalized fresnel z={z}: p = {p:.4g}")
    assert passed, msg


def test_tir_samples_discarded():
    """Below the surface (wo.z < 0) Fr uses 1/eta: for eta > 1 it is 1 (f = 0) for |cos wi| < mu_c =
    sqrt(1 - 1/eta^2), and pbrt-v4's BSDF rule discards samples with f = 0; the discarded fraction
    of cosine samples is mu_c^2."""
    eta = 1.4
    m = bk.NormalizedFresnel(eta)
    s = m.sample(np.array([0.6, 0.0, -0.8]), n=200_000, seed=5)
    mu_c2 = 1 - 1 / eta**2
    assert abs((1 - s.valid.mean()) - mu_c2) < 4e-3
    assert np.all(np.abs(s.wi[s.valid, 2]) >= np.sqrt(mu_c2) - 1e-9)


def test_sample_consistency_and_flags():
    m = bk.NormalizedFresnel(1.5)
    rng = np.random.default_rng(3)
    wo = rng.normal(size=(5000, 3))
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    for mode in ("radiance", "importance"):
        s = m.sample(wo, n=5000, seed=1, mode=mode)
        v = s.valid
        assert np.all(v[wo[:, 2] > 0])  # invalid only under TIR below the surface
        assert np.all(s.wi[v, 2] * wo[v, 2] > 0)
        assert np.allclose(s.f[v], m.eval(wo[v], s.wi[v], mode=mode), rtol=1e-14)
        assert np.allclose(s.pdf[v], m.pdf(wo[v], s.wi[v]), rtol=1e-14)
        assert np.all(s.flags[v] == bk.BxDFFlags.DiffuseReflection)
    s = m.sample(wo, n=5000, seed=1, sample_flags=bk.ReflTrans.Transmission)
    assert not s.valid.any()
    assert np.all(m.pdf(wo, wo, sample_flags=bk.ReflTrans.Transmission) == 0)
    w32 = wo.astype(np.float32)
    f32 = m.eval(w32, w32)
    f64 = m.eval(w32.astype(float), w32.astype(float))
    # 1 - Fr is ill-conditioned near grazing and near the TIR edge below the surface (f jumps to 0)
    near_edge = np.abs(np.abs(wo[:, 2]) - np.sqrt(1 - 1 / 1.5**2)) < 1e-5
    assert f32.dtype == np.float32 and np.allclose(f32[~near_edge], f64[~near_edge], rtol=5e-4, atol=1e-6)


def test_value_semantics_and_bad_input():
    m = bk.NormalizedFresnel(1.3300000000000001)
    assert eval(repr(m), {"NormalizedFresnel": bk.NormalizedFresnel}) == m
    assert pickle.loads(pickle.dumps(m)) == m
    for bad in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="eta"):
            bk.NormalizedFresnel(bad)
    with pytest.raises(TypeError, match="eta"):
        bk.NormalizedFresnel("1.5")


@pytest.mark.parametrize("eta, bound", [(1.1, 3e-4), (1.33, 3e-4), (1.5, 3e-4), (2.0, 3e-4), (3.0, 1e-3),
                                        (0.5, 6e-3), (0.75, 6e-3), (0.9, 6e-3)])
def test_importance_albedo_bound_stated_in_the_docstring(eta, bound):
    """The docstring's bounds on the Importance-mode albedo (issue 50, item 11): 1 only up to
    pbrt-v4's FresnelMoment1 polynomial, which is worst for eta < 1 (1.004 at eta 0.5)."""
    wo = bk.direction(theta=0.5, phi=0.0)
    a = bk.NormalizedFresnel(eta).albedo(wo, n_samples=1 << 20, seed=1, mode=bk.TransportMode.Importance)
    assert np.all(np.abs(a - 1) <= bound), a
