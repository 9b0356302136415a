"""pbrt-v4 models: closed forms (furnace, R + T), an extremes sweep over parameter grids and
property-based inputs. The generic contracts (sample vs eval/pdf, reciprocity, albedo bound, pdf
normalisation, extremes of every registered example) are in tests/contract/."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import bsdfkit as bk

RAD, IMP = bk.TransportMode.Radiance, bk.TransportMode.Importance


def test_white_furnace_lossless():
    wo = bk.direction(np.radians([0, 30, 60, 85, 120, 179]), 0.7)
    np.testing.assert_allclose(bk.Diffuse(1.0).albedo(wo, n_samples=1000), 1.0, rtol=1e-12)
    np.testing.assert_allclose(bk.DiffuseTransmission(0.4, 0.6).albedo(wo, n_samples=1000), 1.0, rtol=1e-12)
    for eta in (1.5, 1 / 1.5, 1.0 + 1e-6, 4.0):
        # smooth interfaces lose nothing: R + T = 1 in Importance mode
        np.testing.assert_allclose(bk.Dielectric(eta).albedo(wo, n_samples=4000, mode=IMP), 1.0, rtol=1e-9)
        np.testing.assert_allclose(bk.ThinDielectric(eta).albedo(wo, n_samples=4000), 1.0, rtol=1e-9)


@pytest.mark.parametrize("eta", [1.5, 1 / 1.5, 1.33, 4.0])
def test_smooth_dielectric_R_plus_T(eta):
    m = bk.Dielectric(eta)
    th = np.radians(np.linspace(0, 89.9, 50))
    for sign in (1, -1):
        wo = bk.direction(th, 0.2) * [1, 1, sign]
        one = np.ones(len(th))
        sr = m.sample(wo, 0.5 * one, np.full((len(th), 2), 0.5), sample_flags=bk.ReflTrans.Reflection, mode=IMP)
        stt = m.sample(wo, 0.5 * one, np.full((len(th), 2), 0.5), sample_flags=bk.ReflTrans.Transmission, mode=IMP)
        R = np.where(sr.valid, sr.weight[:, 0], 0)
        T = np.where(stt.valid, stt.weight[:, 0], 0)
        np.testing.assert_allclose(R + T, 1.0, rtol=1e-12)
        assert np.all(sr.pdf[sr.valid] == 1) and np.all(stt.pdf[stt.valid] == 1)
        # Radiance mode scales the transmitted part by 1/eta'^2
        st_r = m.sample(wo, 0.5 * one, np.full((len(th), 2), 0.5), sample_flags=bk.ReflTrans.Transmission)
        etap = np.where(sign > 0, eta, 1 / eta)
        np.testing.assert_allclose(st_r.weight[st_r.valid, 0], T[st_r.valid] / etap**2, rtol=1e-12)
        np.testing.assert_allclose(st_r.eta[st_r.valid], etap)


# ------------------------------------------------------------------ extremes

COS = [0.0, 1e-30, -1e-30, 1e-12, -1e-12, 1e-7, -1e-7, 1e-4, -1e-4, 0.5, -0.5, 1.0, -1.0]
ALPHAS = [0.0, 1e-4, 9.99e-4, 1e-3, 1e-2, 1.0]
ETAS = [1.0, 1 + 1e-6, 1 - 1e-6, 1 / 1.5, 1.5, 4.0]


def _extreme_models():
    ms = [bk.Diffuse(1.0), bk.Diffuse(0.0), bk.DiffuseTransmission(1.0, 1.0), bk.DiffuseTransmission(0.0, 0.0)]
    for a in ALPHAS:
        for eta, k in ((0.2, 3.9), (1.0, 0.0), (1e-3, 100.0), (4.0, 100.0), (1.5, 0.0)):
            ms.append(bk.Conductor(eta, k, alpha=a))
            for fr in ("schlick", "f82"):
                ms.append(bk.Conductor(eta, k, alpha=a, fresnel=fr))
        ms.append(bk.Conductor(0.2, 3.9, alpha_x=a, alpha_y=1.0, masking="separable"))
        for eta in ETAS:
            ms.append(bk.Dielectric(eta, alpha=a))
        ms.append(bk.Dielectric(1.5, alpha_x=a, alpha_y=0.5, masking="separable"))
    ms += [bk.ThinDielectric(e) for e in ETAS]
    return ms


def _extreme_dirs():
    dirs = []
    for c in COS:
        s = np.sqrt(max(0.0, 1 - c * c))
        for phi in (0.0, 0.3, np.pi / 2, 2.5):
            dirs.append((s * np.cos(phi), s * np.sin(phi), c))
    return np.array(dirs)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_extremes_sweep_finite(dtype):
    d = _extreme_dirs().astype(dtype)
    n = len(d)
    wo = np.repeat(d, n, axis=0)
    wi = np.tile(d, (n, 1))
    # wo = wi and wo = -wi, both on the horizon included in the product; add them explicitly too
    wo = np.concatenate([wo, d, d, d[:, [0, 1, 2]] * np.array([1, 1, 0], dtype)[None] / np.maximum(
        np.linalg.norm(d[:, :2], axis=1, keepdims=True), 1e-30).astype(dtype)])
    wi = np.concatenate([wi, d, -d, -wo[-n:]])
    ok_rows = np.abs(np.linalg.norm(wo.astype(np.float64), axis=1) - 1) < 1e-5
    wo, wi = wo[ok_rows], wi[ok_rows]
    # both closed ends of [0, 1] for every uniform (issue 11 item 4)
    us = np.array([0.0, 1e-7, 0.5, 0.999, np.nextafter(dtype(1), dtype(0)), 1.0], dtype)
    uc = np.resize(us, len(wo))
    u = np.stack([np.resize(us, len(wo)), np.resize(us[::-1], len(wo))[::-1]], 1)
    for m in _extreme_models():
        for mode in (RAD, IMP):
            f = m.eval(wo, wi, mode=mode)
            p = m.pdf(wo, wi, mode=mode)
            assert np.all(np.isfinite(f)) and np.all(f >= 0), m
            assert np.all(np.isfinite(p)) and np.all(p >= 0), m
            for sf in (bk.ReflTrans.All, bk.ReflTrans.Reflection, bk.ReflTrans.Transmission):
                s = m.sample(wo, uc, u, mode=mode, sample_flags=sf)
                for arr in (s.f, s.pdf, s.wi, s.eta, s.weight):
                    assert np.all(np.isfinite(arr)), (m, mode)
                assert np.all(s.f >= 0) and np.all(s.pdf >= 0)
                assert np.all(s.pdf[s.valid] > 0)
                # every sampled wi, valid or not, is a valid eval / pdf input (issue 10)
                assert np.all(np.isfinite(m.eval(wo, s.wi, mode=mode)))
                assert np.all(np.isfinite(m.pdf(wo, s.wi, mode=mode, sample_flags=sf)))
        a = m.albedo(d, n_samples=64, seed=1)
        assert np.all(np.isfinite(a)) and np.all(a >= 0), m


# ------------------------------------------------------------------ property-based

unit = st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)).filter(
    lambda v: 1e-3 < v[0] ** 2 + v[1] ** 2 + v[2] ** 2)
alpha = st.one_of(st.just(0.0), st.floats(0, 2))
rgb01 = st.lists(st.floats(0, 1), min_size=3, max_size=3)
models = st.one_of(
    st.builds(bk.Diffuse, rgb01),
    st.builds(bk.DiffuseTransmission, rgb01, rgb01),
    st.builds(lambda e, k, ax, ay, ms, fr: bk.Conductor(e, k, alpha_x=ax, alpha_y=ay, masking=ms, fresnel=fr),
              st.floats(1e-3, 10), st.floats(0, 100), alpha, alpha, st.sampled_from(["correlated", "separable"]),
              st.sampled_from(["exact", "schlick", "f82"])),
    st.builds(lambda e, ax, ay, ms: bk.Dielectric(e, alpha_x=ax, alpha_y=ay, masking=ms),
              st.floats(0.1, 10), alpha, alpha, st.sampled_from(["correlated", "separable"])),
    st.builds(bk.ThinDielectric, st.floats(0.1, 10)),
)


@settings(max_examples=300, deadline=None)
@given(models, unit, unit, st.floats(0, 1), st.floats(0, 1), st.floats(0, 1),
       st.sampled_from([np.float32, np.float64]), st.sampled_from([RAD, IMP]))
def test_random_inputs_finite(m, a, b, uc, u0, u1, dtype, mode):
    wo = np.array(a) / np.linalg.norm(a)
    wi = np.array(b) / np.linalg.norm(b)
    wo, wi = wo.astype(dtype), wi.astype(dtype)
    f = m.eval(wo, wi, mode=mode)
    p = m.pdf(wo, wi, mode=mode)
    assert np.all(np.isfinite(f)) and np.all(f >= 0)
    assert np.isfinite(p) and p >= 0
    s = m.sample(wo, np.array(uc, dtype), np.array([u0, u1], dtype), mode=mode)
    assert np.all(np.isfinite(s.f)) and np.all(s.f >= 0) and np.isfinite(s.pdf) and s.pdf >= 0
    assert np.all(np.isfinite(s.wi)) and np.isfinite(s.eta)
    if s.valid:
        assert abs(np.linalg.norm(s.wi.astype(np.float64)) - 1) < 1e-3 and s.pdf > 0
