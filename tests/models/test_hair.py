"""bk.Hair (Chiang et al. 2016 as pbrt-v4's HairBxDF) against an independent float64 numpy oracle
of pbrt-v4's formulas (bsdfkit.testing.hair_ref), Mitsuba 3's ``hair`` plugin (frame mapped in the
adapter), pbrt-v4's own hair tests (white furnace, sampling weights, sampling consistency), the
sampler's chi^2 over the full sphere, extremes and bad input."""
import pickle

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as mref
from bsdfkit.testing import hair_ref as ref

EUM = np.array([0.419, 0.697, 1.37])

# (label, params): h != 0, alpha != 0, coloured sigma_a, several roughnesses and IORs
PARAMS = {
    "brown_h0.3": dict(sigma_a=1.3 * EUM, eta=1.55, beta_m=0.3, beta_n=0.3, alpha=2.0, h=0.3),
    "white_sharp": dict(sigma_a=0.0, eta=1.55, beta_m=0.1, beta_n=0.2, alpha=3.0, h=-0.7),
    "coloured_rough": dict(sigma_a=[0.05, 0.8, 3.0], eta=1.33, beta_m=0.6, beta_n=0.8, alpha=-2.0, h=0.95),
    "dark_tiny_v": dict(sigma_a=8 * EUM, eta=1.6, beta_m=0.05, beta_n=0.1, alpha=0.0, h=0.0),
    "grey_tilted": dict(sigma_a=0.4, eta=1.55, beta_m=0.25, beta_n=0.5, alpha=5.0, h=-0.2),
}


def uniform_sphere(n, rng):
    z = rng.uniform(-1, 1, n)
    phi = rng.uniform(0, 2 * np.pi, n)
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def close(a, b, rtol, atol_rel):
    """|a - b| <= rtol |b| + atol_rel max|b| elementwise; returns (ok, worst relative error)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    tol = rtol * np.abs(b) + atol_rel * np.max(np.abs(b))
    err = np.abs(a - b)
    return bool(np.all(err <= tol)), float(np.max(err / (np.abs(b) + atol_rel * np.max(np.abs(b)) + 1e-300)))


# ----------------------------------------------------------------------------- reference

@pytest.mark.parametrize("label", list(PARAMS))
def test_eval_pdf_match_pbrt_formulas_float64(label):
    m = bk.Hair(**PARAMS[label])
    rng = np.random.default_rng(hash(label) % 2**32)
    wo, wi = uniform_sphere(20_000, rng), uniform_sphere(20_000, rng)
    f, pdf = m.eval(wo, wi), m.pdf(wo, wi)
    f_ref, pdf_ref = ref.hair_f(m, wo, wi), ref.hair_pdf(m, wo, wi)
    ok, err = close(f, f_ref, 1e-9, 1e-12)
    assert ok, f"f: worst relative error {err:.3g}"
    ok, err = close(pdf, pdf_ref, 1e-9, 1e-12)
    assert ok, f"pdf: worst relative error {err:.3g}"
    assert np.max(f_ref) > 0.1  # the pairs reach the lobes


@pytest.mark.parametrize("label", ["brown_h0.3", "coloured_rough", "grey_tilted"])
def test_eval_pdf_match_pbrt_formulas_float32(label):
    m = bk.Hair(**PARAMS[label])
    rng = np.random.default_rng(7)
    wo, wi = uniform_sphere(20_000, rng), uniform_sphere(20_000, rng)
    wo32, wi32 = wo.astype(np.float32), wi.astype(np.float32)
    f, pdf = m.eval(wo32, wi32), m.pdf(wo32, wi32)
    assert f.dtype == np.float32 and pdf.dtype == np.float32
    f_ref = ref.hair_f(m, wo32.astype(float), wi32.astype(float))
    pdf_ref = ref.hair_pdf(m, wo32.astype(float), wi32.astype(float))
    ok, err = close(f, f_ref, 2e-4, 1e-6)
    assert ok, f"f32 f: worst relative error {err:.3g}"
    ok, err = close(pdf, pdf_ref, 2e-4, 1e-6)
    assert ok, f"f32 pdf: worst relative error {err:.3g}"


def test_frame_fibre_is_x():
    """The R lobe of a smooth-ish fibre reflects theta: wo at +30 deg along x gives a peak at
    wi.x = -sin(30 deg) (specular cone), independent of the z axis chosen as ribbon normal."""
    m = bk.Hair(sigma_a=10.0, beta_m=0.1, beta_n=0.3, alpha=0.0, h=0.0)
    wo = np.array([np.sin(np.radians(30)), 0.0, np.cos(np.radians(30))])
    th = np.radians(np.linspace(-89, 89, 3561))
    wi = np.stack([np.sin(th), np.zeros_like(th), np.cos(th)], -1)  # phi_i = phi_o: R (backscatter) plane
    val = m.eval(wo, wi)[:, 0] * np.abs(wi[:, 2])
    assert abs(np.degrees(th[np.argmax(val)]) + 30) < 0.2


# ----------------------------------------------------------------------------- Mitsuba

def _mitsuba_pairs(m, n, rng):
    theta_o = rng.uniform(-np.pi / 2 + 0.02, np.pi / 2 - 0.02, n)
    wo = ref.wo_for_h(m.h, theta_o)  # Mitsuba derives h from wo; this wo gives the model's h
    wi = uniform_sphere(n, rng)
    return wo, wi


@pytest.mark.parametrize("label", ["brown_h0.3", "coloured_rough", "grey_tilted", "white_sharp"])
def test_mitsuba_hair(label):
    """Mitsuba 3's ``hair`` (float32) vs bsdfkit and vs the pbrt-v4 oracle, on 10,000 pairs.

    Frame: Mitsuba's fibre axis is its local y and its azimuth atan2(z, x); pbrt's are x and
    atan2(z, y): mi = (pbrt.y, pbrt.x, pbrt.z) (z, the shading normal, is shared, so the cosine
    Mitsuba includes in eval is |wi.z| in both). Mitsuba has no h: it takes h from its si.wi
    (pbrt's wo), h = -wo.y / |wo.yz|; the pairs use such a wo (wo.z > 0).

    Two differences between Mitsuba 3.9 and pbrt-v4, shown to be exactly that:
    * Mitsuba's I0 series has 11 terms (warp.h detail::i0), pbrt-v4's 10: the oracle with
      i0_terms=11 matches Mitsuba's f to float32 precision, the pbrt-v4 one differs where the
      Bessel argument cos_i cos_o / v is large (narrow lobes, v <~ 0.1).
    * Mitsuba picks lobes in proportion to the Rec.709 luminance of Ap, pbrt-v4 to its spectral
      average: Mitsuba's pdf matches the oracle with weights="luminance"; for grey sigma_a both
      weightings coincide."""
    m = bk.Hair(**PARAMS[label])
    rng = np.random.default_rng(11)
    wo, wi = _mitsuba_pairs(m, 10_000, rng)
    assert np.allclose(ref.mitsuba_h(wo), m.h, atol=1e-12)
    f_mi, pdf_mi = ref.mitsuba_eval_pdf(m, wo, wi)
    # Mitsuba computes in float32 from float32-rounded directions: compare against the oracle at
    # the same rounded directions.
    wo32, wi32 = wo.astype(np.float32).astype(float), wi.astype(np.float32).astype(float)
    f_mi_model = ref.hair_f(m, wo32, wi32, i0_terms=11)
    pdf_mi_model = ref.hair_pdf(m, wo32, wi32, i0_terms=11, weights="luminance")
    ok, err = close(f_mi, f_mi_model, 2e-3, 2e-5)
    assert ok, f"Mitsuba f vs oracle(11-term I0): worst relative error {err:.3g}"
    ok, err = close(pdf_mi, pdf_mi_model, 2e-3, 2e-5)
    assert ok, f"Mitsuba pdf vs oracle(luminance weights): worst relative error {err:.3g}"
    # bsdfkit (pbrt-v4) against Mitsuba: equal up to those two documented differences
    f_bk, pdf_bk = m.eval(wo, wi), m.pdf(wo, wi)
    f_pbrt11 = ref.hair_f(m, wo, wi, i0_terms=11)
    f_pbrt10 = ref.hair_f(m, wo, wi)
    # the I0 difference: bsdfkit / Mitsuba equals oracle(10) / oracle(11) where f matters
    sel = f_pbrt11[:, 1] > 1e-3 * f_pbrt11[:, 1].max()
    ratio_bk_mi = f_bk[sel] / f_mi[sel]
    ratio_terms = f_pbrt10[sel] / f_pbrt11[sel]
    ok, err = close(ratio_bk_mi, ratio_terms, 3e-3, 0)
    assert ok, f"bsdfkit/Mitsuba is not the 10/11-term I0 ratio: worst relative error {err:.3g}"
    pdf_lum = ref.hair_pdf(m, wo, wi, weights="luminance")
    pdf_avg = ref.hair_pdf(m, wo, wi)
    ok, err = close(pdf_bk, pdf_avg, 1e-9, 1e-12)
    assert ok
    grey = np.ptp(np.asarray(m.sigma_a)) == 0
    if grey:
        assert np.allclose(pdf_lum, pdf_avg, rtol=1e-9, atol=1e-12 * pdf_avg.max())
    else:
        assert np.max(np.abs(pdf_lum - pdf_avg) / (pdf_avg + 1e-3 * pdf_avg.max())) > 1e-3


# ----------------------------------------------------------------------------- pbrt-v4's hair tests

def _sphere_grid(n_theta, n_phi):
    """Midpoint grid over the sphere in the hair frame: theta (longitudinal, wi.x = sin theta) and
    phi, with the solid-angle weights cos theta dtheta dphi."""
    th = (np.arange(n_theta) + 0.5) * np.pi / n_theta - np.pi / 2
    ph = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    T, P = np.meshgrid(th, ph, indexing="ij")
    wi = np.stack([np.sin(T), np.cos(T) * np.cos(P), np.cos(T) * np.sin(P)], -1).reshape(-1, 3)
    w = (np.cos(T) * (np.pi / n_theta) * (2 * np.pi / n_phi)).reshape(-1)
    return wi, w


BETAS = [0.1, 0.3, 0.5, 0.7, 0.9]


def test_white_furnace():
    """pbrt-v4 Hair.WhiteFurnace: sigma_a = 0, beta_m, beta_n in {.1,.3,.5,.7,.9}, random h and wo:
    int f |cos| dw = 1. Integrated on a 700 x 700 midpoint grid in (theta, phi) (exact to ~1e-6 for
    these lobe widths) rather than pbrt's uniform Monte Carlo (pbrt-v4 asserts [0.95, 1.05]).

    pbrt-v4's model itself is not exactly 1: its I0 is a 10-term series, 2-3 % short for Bessel
    arguments 8..12, which the TT lobe reaches at beta_m = 0.5 (v1 = 0.08 < 0.1, 1/v1 = 12.5). The
    kernel reproduces that (worst 0.9893 here) and the oracle with an exact I0 closes the gap."""
    rng = np.random.default_rng(5)
    wi, w = _sphere_grid(700, 700)
    vals, worst = [], None
    for bm in BETAS:
        for bn in BETAS:
            h = rng.uniform(-0.999999, 0.999999)
            m = bk.Hair(sigma_a=0.0, eta=1.55, beta_m=bm, beta_n=bn, alpha=0.0, h=h)
            wo = uniform_sphere(1, rng)[0]
            e = np.sum(m.eval(wo, wi)[:, 0] * np.abs(wi[:, 2]) * w)
            vals.append(e)
            if worst is None or abs(e - 1) > abs(worst[0] - 1):
                worst = (e, m, wo)
    vals = np.array(vals)
    print(f"furnace: min {vals.min():.5f} max {vals.max():.5f}")
    assert np.all(np.abs(vals - 1) < 0.012), vals
    assert np.sum(np.abs(vals - 1) < 0.005) >= 20  # all but the beta_m = 0.5 row within 0.5 %
    e, m, wo = worst
    oracle = np.sum(ref.hair_f(m, wo, wi)[:, 0] * np.abs(wi[:, 2]) * w)
    exact = np.sum(ref.hair_f(m, wo, wi, i0_terms=None)[:, 0] * np.abs(wi[:, 2]) * w)
    print(f"worst: kernel {e:.6f}, pbrt oracle {oracle:.6f}, oracle with exact I0 {exact:.6f}")
    assert abs(oracle - e) < 1e-9 and abs(exact - 1) < 1e-3


@pytest.mark.parametrize("alpha", [0.0, 2.0])
def test_white_furnace_sampled_and_weights(alpha):
    """pbrt-v4 Hair.WhiteFurnaceSampled and Hair.SamplingWeights: with sigma_a = 0 every sample's
    weight f |cos| / pdf is 1 (the sampler is exact), so the mean is 1 within 1e-2 (pbrt-v4) --
    here every single weight within 1e-6."""
    rng = np.random.default_rng(6)
    for bm in BETAS:
        for bn in (0.4, 0.6, 0.8):
            m = bk.Hair(sigma_a=0.0, beta_m=bm, beta_n=bn, alpha=alpha, h=rng.uniform(-1, 1))
            wo = uniform_sphere(1, rng)[0]
            s = m.sample(wo, n=10_000, seed=int(rng.integers(1 << 30)))
            wgt = s.weight[s.valid, 0]
            assert s.valid.mean() > 0.999
            assert np.all(np.abs(wgt - 1) < 1e-6), (bm, bn, wgt.min(), wgt.max())


def test_sampling_consistency():
    """pbrt-v4 Hair.SamplingConsistency: sigma_a = 0.25, Li(w) = w.z^2: importance-sampled and
    uniform-sphere estimates of int f |cos| Li agree within 5 % (here: 2 %, with a grid)."""
    rng = np.random.default_rng(8)
    wi_g, w_g = _sphere_grid(600, 600)
    for bm in (0.2, 0.4, 0.6, 0.8):
        for bn in (0.4, 0.6, 0.8):
            m = bk.Hair(sigma_a=0.25, beta_m=bm, beta_n=bn, h=rng.uniform(-1, 1))
            wo = uniform_sphere(1, rng)[0]
            s = m.sample(wo, n=64_000, seed=3)
            imp = np.mean(np.where(s.valid, s.weight[:, 0] * s.wi[:, 2] ** 2, 0.0))
            uni = np.sum(m.eval(wo, wi_g)[:, 0] * np.abs(wi_g[:, 2]) * wi_g[:, 2] ** 2 * w_g)
            assert abs(imp - uni) / uni < 0.02, (bm, bn, imp, uni)


@pytest.mark.parametrize("label", list(PARAMS))
def test_sample_matches_eval_and_pdf(label):
    m = bk.Hair(**PARAMS[label])
    rng = np.random.default_rng(9)
    wo = uniform_sphere(2000, rng)
    s = m.sample(wo, rng.random(2000), rng.random((2000, 2)))
    v = s.valid
    assert v.mean() > 0.99
    assert np.allclose(np.linalg.norm(s.wi[v], axis=-1), 1, atol=1e-12)
    assert np.allclose(s.f[v], m.eval(wo[v], s.wi[v]), rtol=1e-9, atol=0)
    assert np.allclose(s.pdf[v], m.pdf(wo[v], s.wi[v]), rtol=1e-7, atol=0)
    assert np.all(s.flags[v] == bk.BxDFFlags.GlossyReflection)


# ----------------------------------------------------------------------------- chi^2

CHI2 = [(label, z, h) for label, z in [("brown", 0.9), ("brown", -0.3), ("rough", 0.2), ("sharp", 0.6)]
        for h in (0.0, 0.6, -0.95)]


@pytest.mark.parametrize("label, z, h", CHI2, ids=[f"{c[0]}-z{c[1]}-h{c[2]}" for c in CHI2])
def test_chi2_full_sphere(label, z, h):
    """Mitsuba's chi^2 harness (SphericalDomain: the whole sphere) against the pdf. Directions are
    rotated (hair x axis to the domain's z axis) so that the longitudinal structure is binned in
    cos theta, where the harness's cells are uniform."""
    kw = {"brown": dict(sigma_a=1.3 * EUM, beta_m=0.3, beta_n=0.3, alpha=2.0),
          "rough": dict(sigma_a=[0.1, 0.4, 0.9], beta_m=0.7, beta_n=0.8, alpha=-3.0),
          "sharp": dict(sigma_a=0.2, beta_m=0.15, beta_n=0.25, alpha=4.0)}[label]
    m = bk.Hair(h=h, **kw)
    r = np.sqrt(1 - z * z)
    wo = np.array([z, r * np.cos(1.1), r * np.sin(1.1)])  # wo.x = sin theta_o = z
    R = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])  # (x, y, z) -> (y, z, x)

    def sample_fn(uc, u):
        s = m.sample(wo, uc, u)
        return s.wi @ R.T, s.valid

    def pdf_fn(v):
        return m.pdf(wo, v @ R)

    ires = 24 if label == "sharp" else 12
    passed, p, msg = mref.chi2_test(sample_fn, pdf_fn, res=101, ires=ires, sample_count=1_000_000, seed=2,
                                    significance=0.01, test_count=len(CHI2))
    print(f"chi2 hair {label} z={z} h={h}: p = {p:.4g}")
    assert passed, msg


# ----------------------------------------------------------------------------- constructors

def test_from_concentration_and_reflectance():
    m = bk.Hair.from_concentration(1.3, 0.2, beta_m=0.4)
    assert np.allclose(m.sigma_a, 1.3 * EUM + 0.2 * np.array([0.187, 0.4, 1.05]), rtol=0, atol=1e-15)
    assert m.beta_m == 0.4
    assert bk.Hair() == bk.Hair.from_concentration(1.3, 0.0)  # pbrt-v4's default
    c = np.array([0.5, 0.3, 0.1])
    bn = 0.45
    m = bk.Hair.from_reflectance(c, beta_n=bn)
    den = 5.969 - 0.215 * bn + 2.532 * bn**2 - 10.73 * bn**3 + 5.574 * bn**4 + 0.245 * bn**5
    assert np.allclose(m.sigma_a, (np.log(c) / den) ** 2, rtol=1e-15)
    z = bk.Hair.from_reflectance([0.0, 0.5, 1.0])
    assert z.sigma_a[0] == 1e4 and z.sigma_a[2] == 0.0


def test_value_semantics():
    m = bk.Hair(sigma_a=[0.1, 0.2, 0.30000000000000004], beta_m=0.25, alpha=-1.5, h=0.125)
    assert eval(repr(m), {"Hair": bk.Hair}) == m
    assert pickle.loads(pickle.dumps(m)) == m and hash(m) == hash(bk.Hair(**m._params))
    with pytest.raises(AttributeError):
        m.h = 0.5


@pytest.mark.parametrize("kw, name", [
    (dict(sigma_a=-0.1), "sigma_a"), (dict(sigma_a=[0.1, np.nan, 0.2]), "sigma_a"), (dict(sigma_a=[1, 2]), "sigma_a"),
    (dict(eta=0.9), "eta"), (dict(eta=np.inf), "eta"), (dict(beta_m=0.0), "beta_m"), (dict(beta_m=1.5), "beta_m"),
    (dict(beta_n=-1), "beta_n"), (dict(beta_n=np.nan), "beta_n"), (dict(alpha=120.0), "alpha"),
    (dict(h=1.5), "h"), (dict(h=np.nan), "h"), (dict(h="a"), "h"), (dict(h=-1.01), "h"),
])
def test_bad_input(kw, name):
    with pytest.raises((ValueError, TypeError), match=name):
        bk.Hair(**kw)


def test_bad_constructor_input():
    with pytest.raises(ValueError, match="eumelanin"):
        bk.Hair.from_concentration(-1.0)
    with pytest.raises(ValueError, match="color"):
        bk.Hair.from_reflectance([0.5, 1.2, 0.1])


# ----------------------------------------------------------------------------- extremes

EXTREMES = [
    dict(h=1.0), dict(h=-1.0), dict(beta_m=0.01, beta_n=0.01), dict(beta_m=1.0, beta_n=1.0),
    dict(beta_m=0.01, beta_n=1.0, h=0.999), dict(sigma_a=0.0), dict(sigma_a=1e4), dict(eta=1.0), dict(eta=1.0001, h=1.0),
    dict(sigma_a=bk.Hair.from_reflectance([0.0, 0.2, 1.0]).sigma_a), dict(alpha=90.0), dict(alpha=-90.0, h=-1.0),
]


@pytest.mark.parametrize("kw", EXTREMES, ids=[str(k) for k in EXTREMES])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_extremes_finite(kw, dtype):
    m = bk.Hair(**kw)
    rng = np.random.default_rng(1)
    wo = np.concatenate([uniform_sphere(500, rng), [[1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, 1, 0],
                                                    [np.sin(1e-4), 0, np.cos(1e-4)]]]).astype(dtype)
    wi = np.concatenate([uniform_sphere(500, rng), [[-1, 0, 0], [1, 0, 0], [0, 0, -1], [0, -1, 0],
                                                    [0, 0, 1]]]).astype(dtype)
    for a in (m.eval(wo, wi), m.pdf(wo, wi), m.eval(wo[:, None], wi[None, :50]), m.pdf(wo[:, None], wi[None, :50])):
        assert np.all(np.isfinite(a)) and np.all(a >= 0)
    u = np.array([[0, 0], [1, 1], [0, 1], [1, 0], [0.5, 0.5]], dtype)
    uc = np.array([0, 1, 1, 0, 0.5], dtype)
    s = m.sample(wo[:, None], uc[None], u[None])
    for a in (s.wi, s.f, s.pdf):
        assert np.all(np.isfinite(a))
    assert np.allclose(np.linalg.norm(s.wi[s.valid], axis=-1), 1, atol=1e-3)
    s = m.sample(wo, n=len(wo), seed=2)
    assert np.all(np.isfinite(s.f)) and np.all(np.isfinite(s.pdf))


# ----------------------------------------------------------------------------- far field (h=None)

def test_far_field_matches_quadrature_of_h():
    """Hair(h=None) is (1/2) int f(h) dh: against the oracle with a 64-point rule in gamma = asin h
    (the kernel's default is 64 points too, computed by its own code); smooth lobes (beta_n = 0.5)
    agree to 1e-3 of the peak."""
    m = bk.Hair(sigma_a=[0.2, 0.5, 1.0], beta_m=0.3, beta_n=0.5, alpha=2.0, h=None)
    assert m.h is None and eval(repr(m), {"Hair": bk.Hair}) == m
    rng = np.random.default_rng(21)
    wo, wi = uniform_sphere(3000, rng), uniform_sphere(3000, rng)
    f = m.eval(wo, wi) * np.abs(wi[:, 2:3])
    f_ref = ref.far_field_f(m, wo, wi) * np.abs(wi[:, 2:3])
    err = np.max(np.abs(f - f_ref)) / np.max(f_ref)
    print(f"far field vs 64-point oracle: {err:.2e} of the peak of f|cos|")
    assert err < 1e-3
    # and with nodes=16 it is the weighted mean of 16 single-h models (Gauss-Legendre in gamma)
    m16 = bk.Hair(sigma_a=[0.2, 0.5, 1.0], beta_m=0.3, beta_n=0.5, alpha=2.0, h=None, nodes=16)
    x, w = np.polynomial.legendre.leggauss(16)
    g = x * np.pi / 2
    wk = w * np.cos(g) / np.sum(w * np.cos(g))
    mix = sum(wgt * bk.Hair(sigma_a=[0.2, 0.5, 1.0], beta_m=0.3, beta_n=0.5, alpha=2.0, h=float(np.sin(gk)))
              .eval(wo[:200], wi[:200]) for gk, wgt in zip(g, wk))
    assert np.allclose(m16.eval(wo[:200], wi[:200]), mix, rtol=1e-12, atol=0)


def test_far_field_furnace_and_sampling():
    m = bk.Hair(sigma_a=0.0, beta_m=0.4, beta_n=0.6, h=None)
    wi, w = _sphere_grid(400, 400)
    wo = np.array([0.3, 0.4, np.sqrt(0.75)])
    e = np.sum(m.eval(wo, wi)[:, 0] * np.abs(wi[:, 2]) * w)
    assert abs(e - 1) < 5e-3, e
    s = m.sample(wo, n=5000, seed=3)
    v = s.valid
    assert v.mean() > 0.999
    assert np.all(np.abs(s.weight[v, 0] - 1) < 1e-6)  # sigma_a = 0: exact sampling
    m = bk.Hair(sigma_a=[0.3, 0.6, 1.2], beta_m=0.3, beta_n=0.4, h=None)
    s = m.sample(wo, n=2000, seed=4)
    v = s.valid
    assert np.allclose(s.f[v], m.eval(wo, s.wi[v]), rtol=1e-9)
    assert np.allclose(s.pdf[v], m.pdf(wo, s.wi[v]), rtol=1e-9)
    R = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    passed, p, msg = mref.chi2_test(lambda uc, u: ((r := m.sample(wo, uc, u)).wi @ R.T, r.valid),
                                    lambda d: m.pdf(wo, d @ R), res=101, ires=12, sample_count=500_000, seed=5,
                                    significance=0.01)
    print(f"chi2 far field: p = {p:.4g}")
    assert passed, msg
    for dt in (np.float32, np.float64):
        for mm in (bk.Hair(h=None, beta_m=0.01, beta_n=0.01), bk.Hair(h=None, sigma_a=1e4, eta=1.0)):
            r = np.random.default_rng(1)
            a = mm.eval(uniform_sphere(200, r).astype(dt), uniform_sphere(200, r).astype(dt))
            assert np.all(np.isfinite(a))
