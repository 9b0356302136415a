"""Uniforms at the closed ends of [0, 1] and invalid samples (issue 11 item 4, issue 10).

uc and u are documented on [0, 1]: uc = 1 (or 0) must never pick a lobe of probability 0 when
the other lobe is allowed -- with a sample_flags restriction, at total internal reflection,
with DiffuseTransmission's R or T = 0 -- and u = 1 must give a finite, valid direction. The
expected results are closed forms (mirror / refraction directions, cosine lobes) and Mitsuba 3,
whose dielectrics pick reflection when ``uc <= R`` (so at R = 1, uc = 1 gives reflection).
An invalid sample carries the normal (0, 0, 1) with f = pdf = 0, so eval / pdf accept it.
"""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as ref

R, T, ALL = bk.ReflTrans.Reflection, bk.ReflTrans.Transmission, bk.ReflTrans.All


def _dir(theta_deg, phi=0.3, side=1.0):
    t = np.radians(theta_deg)
    return np.array([np.sin(t) * np.cos(phi), np.sin(t) * np.sin(phi), side * np.cos(t)])


def _mirror(wo):
    return wo * np.array([-1.0, -1.0, 1.0])


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_smooth_dielectric_reflection_only_at_uc_1(dtype):
    wo = _dir(40).astype(dtype)
    m = bk.Dielectric(1.5)
    s = m.sample(wo, np.array(1.0, dtype), np.array([0.5, 0.5], dtype), sample_flags=R)
    assert s.valid and s.flags == bk.BxDFFlags.SpecularReflection
    np.testing.assert_allclose(s.wi, _mirror(wo), atol=1e-6)
    assert s.pdf == pytest.approx(1.0)  # the only allowed lobe
    # and the transmission-only restriction at uc = 0 gives the refracted direction
    s = m.sample(wo, np.array(0.0, dtype), np.array([0.5, 0.5], dtype), sample_flags=T)
    assert s.valid and s.flags == bk.BxDFFlags.SpecularTransmission and s.pdf == pytest.approx(1.0)
    sin_t = np.sin(np.radians(40)) / 1.5
    assert s.wi[2] == pytest.approx(-np.sqrt(1 - sin_t ** 2), rel=1e-6)


@pytest.mark.parametrize("alpha", [0.0, 0.3])
def test_dielectric_total_internal_reflection_at_uc_1_matches_mitsuba(alpha):
    """wo inside the denser medium beyond the critical angle: R = 1 for the smooth interface
    (and for most sampled microfacets of the rough one): uc = 1 must reflect, as Mitsuba does."""
    m = bk.Dielectric(1.5, alpha=alpha)
    rng = np.random.default_rng(4)
    n = 2000
    wo = np.stack([_dir(th, phi, -1.0) for th, phi in zip(rng.uniform(60, 80, n), rng.uniform(0, 6, n))])
    wo = wo.astype(np.float32).astype(np.float64)
    u = rng.random((n, 2)).astype(np.float32).astype(np.float64)
    uc = np.ones(n)
    s = m.sample(wo, uc, u)
    # sampling does not depend on the masking: Mitsuba's roughdielectric (separable) samples the same lobes
    r = ref.sample(bk.Dielectric(1.5, alpha=alpha, masking="separable"), wo, uc, u)
    assert r["valid"].mean() > 0.8 and r["reflection"][r["valid"]].mean() > 0.8
    if alpha == 0:  # the same direction and weight for every sample
        assert np.all(s.valid == r["valid"])
        np.testing.assert_allclose(s.wi, r["wi"], atol=5e-6)
        np.testing.assert_allclose(s.weight, r["weight"], rtol=1e-5, atol=1e-6)
    else:  # Mitsuba warps u to the visible normal differently: compare the distributions
        assert abs(s.valid.mean() - r["valid"].mean()) < 0.03
        refl = s.valid & (s.wi[:, 2] < 0)
        assert abs(refl.mean() - (r["valid"] & r["reflection"]).mean()) < 0.03


@pytest.mark.parametrize("alpha", [0.0, 0.3])
def test_dielectric_reflection_only_at_uc_1_rough(alpha):
    m = bk.Dielectric(1.5, alpha=alpha)
    rng = np.random.default_rng(5)
    wo = np.stack([_dir(th) for th in rng.uniform(0, 80, 500)])
    s = m.sample(wo, np.ones(500), rng.random((500, 2)), sample_flags=R)
    # smooth: always the mirror; rough: only reflections below the horizon are lost (pbrt's rule)
    assert s.valid.mean() > (0.999 if alpha == 0 else 0.8)
    assert np.all(s.flags[s.valid] & bk.BxDFFlags.Reflection)
    expected = m.pdf(wo[s.valid], s.wi[s.valid], sample_flags=R) if alpha > 0 else 1.0
    np.testing.assert_allclose(s.pdf[s.valid], expected, rtol=1e-9)


@pytest.mark.parametrize("refl, trans, uc, side", [(0.5, 0.0, 1.0, 1), (0.0, 0.5, 0.0, -1), (0.0, 0.5, 1.0, -1),
                                                    (0.5, 0.0, 0.0, 1)])
def test_diffuse_transmission_only_nonzero_lobe(refl, trans, uc, side):
    m = bk.DiffuseTransmission(refl, trans)
    wo = _dir(30)
    s = m.sample(wo, np.full(100, uc), np.random.default_rng(1).random((100, 2)))
    assert np.all(s.valid)
    assert np.all(np.sign(s.wi[:, 2]) == side)
    np.testing.assert_allclose(s.pdf, np.abs(s.wi[:, 2]) / np.pi, rtol=1e-12)
    np.testing.assert_allclose(s.f, max(refl, trans) / np.pi, rtol=1e-12)


def test_thin_dielectric_restricted_at_uc_ends():
    m = bk.ThinDielectric(1.5)
    wo = _dir(50)
    s = m.sample(wo, np.array(1.0), np.array([0.2, 0.3]), sample_flags=R)
    assert s.valid and s.pdf == pytest.approx(1.0)
    np.testing.assert_allclose(s.wi, _mirror(wo), atol=1e-12)
    s = m.sample(wo, np.array(0.0), np.array([0.2, 0.3]), sample_flags=T)
    assert s.valid and s.pdf == pytest.approx(1.0)
    np.testing.assert_allclose(s.wi, -wo, atol=1e-12)


@pytest.mark.parametrize("model", [bk.Diffuse(0.5), bk.Conductor(0.2, 3.9, alpha=0.3), bk.Dielectric(1.5, alpha=0.3),
                                   bk.FilamentStandard([0.8, 0.5, 0.3]), bk.FilamentCloth([0.1, 0.15, 0.35])],
                         ids=repr)
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_u_at_one_is_finite_and_matches_just_below(model, dtype):
    """u at 1 is used as the largest value below 1 (pbrt's OneMinusEpsilon): the same sample."""
    wo = _dir(35).astype(dtype)
    below = np.nextafter(dtype(1), dtype(0))
    for uc in (0.0, 1.0):
        for u in ([1.0, 1.0], [1.0, 0.0], [0.0, 1.0], [1.0, 0.5]):
            u = np.array(u, dtype)
            s1 = model.sample(wo, np.array(uc, dtype), u)
            s0 = model.sample(wo, np.array(min(uc, below), dtype), np.minimum(u, below))
            assert np.all(np.isfinite(s1.wi)) and np.all(np.isfinite(s1.f))
            assert s1.valid == s0.valid
            np.testing.assert_array_equal(s1.wi, s0.wi)
            np.testing.assert_array_equal(s1.f, s0.f)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_invalid_sample_carries_the_normal(dtype):
    """No transmission lobe: every sample is invalid, with wi = (0, 0, 1), f = pdf = 0, and the
    round trip eval(wo, s.wi) works (it raised 'not finite unit vectors' for wi = 0)."""
    m = bk.Conductor(0.2, 3.9, alpha=0.3)
    wo = np.stack([_dir(th) for th in (0, 30, 60, 89)]).astype(dtype)
    s = m.sample(wo[:, None, :], n=50, seed=2, sample_flags=T)
    assert not s.valid.any()
    np.testing.assert_array_equal(s.wi, np.broadcast_to(np.array([0, 0, 1], dtype), s.wi.shape))
    assert not s.f.any() and not s.pdf.any()
    f = m.eval(wo[:, None, :], s.wi)
    assert f.shape == s.wi.shape and np.all(np.isfinite(f))
    # a sample lost for a geometric reason (reflection below the horizon) too
    g = bk.Conductor(0.2, 3.9, alpha=1.0)
    wo = _dir(89).astype(dtype)
    s = g.sample(wo, n=4000, seed=1)
    assert (~s.valid).any()
    np.testing.assert_array_equal(s.wi[~s.valid], np.broadcast_to(np.array([0, 0, 1], dtype), s.wi[~s.valid].shape))
    assert np.all(np.isfinite(g.pdf(wo, s.wi)))


# ------------------------------------------------------------------ the small-call fast path

@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_fast_path_equals_general_path(dtype):
    """eval / pdf on plain contiguous arrays take a shortcut past the general argument handling
    (tools/perf/overhead.py): the same values, shapes, dtypes and errors as the general path."""
    m = bk.Dielectric(1.5, alpha=0.3)
    rng = np.random.default_rng(0)
    wo = rng.normal(size=(4, 5, 3))
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    wi = wo[::-1].copy()
    wo, wi = wo.astype(dtype), wi.astype(dtype)
    def strided(x):  # the same values, not C-contiguous: the general path
        y = np.repeat(x, 2, axis=-1)[..., ::2]
        assert not y.flags.c_contiguous
        return y
    for a, b in ((wo, wi), (wo[0, 0], wi), (wo, wi[1, 2]), (wo[0, 0], wi[0, 0])):
        for mode in (bk.TransportMode.Radiance, bk.TransportMode.Importance, 1):
            f = m.eval(a, b, mode=mode)
            assert f.dtype == dtype and f.shape == np.broadcast_shapes(a.shape, b.shape)
            np.testing.assert_array_equal(f, m.eval(strided(a), strided(b), mode=mode))
            p = m.pdf(a, b, mode=mode, sample_flags=bk.ReflTrans.Reflection)
            np.testing.assert_array_equal(p, m.pdf(strided(a), strided(b), mode=mode,
                                                   sample_flags=bk.ReflTrans.Reflection))
    with pytest.raises(ValueError, match="wi: 1 direction"):
        m.eval(wo[0, 0], np.array([0.0, 0.0, 2.0], dtype))
    with pytest.raises(ValueError, match="mode"):
        m.eval(wo, wi, mode=7)
    with pytest.raises(ValueError, match="sample_flags"):
        m.pdf(wo, wi, sample_flags=9)
    assert m.eval(np.zeros((0, 3), dtype), wi[0, 0]).shape == (0, 3)
