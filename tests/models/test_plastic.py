"""bk.Plastic against Mitsuba 3's ``plastic`` / ``roughplastic`` (llvm_ad_rgb, float32), plus
sampling, consistency, energy and validation checks.

Both libraries get the same float32-rounded directions; bsdfkit runs float64 kernels on them.
Tolerances (p99.9 of |ours - mitsuba| / max(|mitsuba|, 1e-5 * the set's 99th percentile)):

* smooth coating: 1e-5 for f (cosine included or not: the same relative error) and pdf.
  Everything is closed form; what is left is Mitsuba's float32 arithmetic.
* rough coating: 5e-5. The diffuse part interpolates Mitsuba's 64-entry transmittance table,
  and the internal reflectance Fdr is a 64-node sum of 128^2-node quadratures. We compute the
  same tables with the same quadrature in float64; Mitsuba accumulates 1024 (eta > 1) or 16384
  (eta < 1) float32 terms per entry, so its table entries carry ~1e-6..1e-5 relative rounding
  (measured: see the printed table error), and 1 / (1 - Fdr) amplifies the Fdr error by
  Fdr / (1 - Fdr) (< 1 for eta <= 2). The specular part is closed form (1e-5 as smooth).
* rough coating with eta < 1 (the 16384-term tables): 5e-4 for f, 2e-3 for the pdf. How
  Mitsuba's float32 sums round depends on the host's vector width: p99.9 1.7e-4 (f) and 7.3e-4
  (pdf) on an Intel Sapphire Rapids host (AVX-512), < 5e-5 on AMD Zen 3 (AVX2), for the same
  bsdfkit values. The pdf's lobe ratio (1 - T) w / ((1 - T) w + T (1 - w)) multiplies the
  table's relative error by T / (1 - T) (~25 where T ~ 0.96). So every rough case is also checked
  against the independent float64 Dr.Jit restatement (``testing/plastic_ref``, whose tables are
  computed in float64): there the p99.9 is 1e-13 on both hosts, asserted at 1e-10.
"""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as ref
from bsdfkit.testing import plastic_ref

N = 12_000  # pairs per parameter set


def _dirs(rng, n, zs, sign=1.0):
    z = np.resize(np.asarray(zs, dtype=np.float64), n) * sign
    phi = rng.uniform(0, 2 * np.pi, n)
    r = np.sqrt(np.maximum(0, 1 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _sphere(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _f32(a):
    return np.asarray(a, np.float32).astype(np.float64)


ZS = [1.0, 0.8, 0.5, 0.3, 0.1, 0.03, 0.01]


def _pairs(model, rng, lower=False):
    """wo at several elevations (above or below), wi half uniform on the sphere (both sides, so
    the zero region is checked too), half sampled from the model; float32-rounded."""
    wo = _dirs(rng, N, ZS, -1.0 if lower else 1.0)
    wi = _sphere(rng, N)
    s = model.sample(wo[: N // 2], rng.random(N // 2), rng.random((N // 2, 2)))
    take = s.valid & ((s.flags & bk.BxDFFlags.Specular) == 0)
    wi[: N // 2] = np.where(take[:, None], s.wi, wi[: N // 2])
    return _f32(wo), _f32(wi)


def _rel(ours, theirs):
    pos = theirs[theirs > 0]
    scale = np.quantile(pos, 0.99) if pos.size else 1.0
    return np.abs(ours - theirs) / np.maximum(np.abs(theirs), 1e-5 * scale), scale


def _check(ours, theirs, tol, what):
    err, scale = _rel(ours, theirs)
    p999 = np.quantile(err, 0.999)
    print(f"{what}: p99.9 rel err {p999:.3g}, max {err.max():.3g}")
    assert p999 <= tol, f"{what}: p99.9 relative error {p999:.3g} > {tol}"
    support = (ours > 1e-6 * scale) != (theirs > 1e-6 * scale)
    assert support.mean() < 1e-3, f"{what}: support differs on {support.mean():.2%} of pairs"
    return p999


SMOOTH = [bk.Plastic(0.5, 1.49), bk.Plastic([0.9, 0.3, 0.05], 1.5, nonlinear=True),
          bk.Plastic([0.2, 0.6, 1.0], 1.33, specular_reflectance=[0.8, 0.5, 1.0]),
          bk.Plastic(1.0, 2.2, nonlinear=True), bk.Plastic(0.7, 1 / 1.4)]
ROUGH = [bk.Plastic(0.5, 1.49, alpha=0.1, masking="separable"),
         bk.Plastic([0.9, 0.3, 0.05], 1.5, alpha=0.3, nonlinear=True, masking="separable"),
         bk.Plastic([0.2, 0.6, 1.0], 1.33, alpha=0.05, specular_reflectance=[0.8, 0.5, 1.0], masking="separable"),
         bk.Plastic(1.0, 2.0, alpha=0.6, nonlinear=True, masking="separable"),
         bk.Plastic(0.4, 1 / 1.3, alpha=0.2, masking="separable")]
TOL_SMOOTH, TOL_ROUGH, TOL_ROUGH_INNER, TOL_ROUGH_INNER_PDF, TOL_F64 = 1e-5, 5e-5, 5e-4, 2e-3, 1e-10


@pytest.mark.parametrize("model", SMOOTH + ROUGH, ids=repr)
@pytest.mark.parametrize("lower", [False, True], ids=["above", "below"])
def test_eval_pdf_match_mitsuba(model, lower, rng):
    wo, wi = _pairs(model, rng, lower)
    f_mi, p_mi = ref.eval_pdf(model, wo, wi)
    f, p = model.eval(wo, wi), model.pdf(wo, wi)
    tol = TOL_SMOOTH if model.alpha == 0 else TOL_ROUGH if model.eta > 1 else TOL_ROUGH_INNER
    cos = np.abs(wi[:, 2:3])
    _check(f * cos, f_mi * cos, tol, f"{model!r} f cos")
    if model.alpha > 0:  # Mitsuba's float32 tables aside: the float64 restatement (docstring)
        _check(f * cos, np.asarray(plastic_ref.plastic_f(model, wo, wi)) * cos, TOL_F64, f"{model!r} f cos vs float64")
    # Mitsuba 3.9's roughplastic pdf() / eval_pdf() compute `active` (both cosines > 0) but
    # never apply it to the returned pdf: for wi across the surface it returns the unmasked
    # mixture density (the value is garbage there; sample() never produces such a wi). bsdfkit
    # returns 0, as plastic.cpp does: the pdf conventions coincide only on wo's side.
    same = wo[:, 2] * wi[:, 2] > 0
    tol_pdf = TOL_ROUGH_INNER_PDF if tol == TOL_ROUGH_INNER else tol
    _check(p[same], p_mi[same], tol_pdf, f"{model!r} pdf")
    assert np.all(p[~same] == 0)


@pytest.mark.parametrize("model", SMOOTH + ROUGH, ids=repr)
def test_sampling_matches_mitsuba(model, rng):
    """Same uniforms -> same lobe choice, same direction (Mitsuba's warps), same weight and pdf."""
    n = 20_000
    wo = _f32(np.concatenate([_dirs(rng, n // 2, ZS), _dirs(rng, n // 2, ZS, -1.0)]))
    uc, u = _f32(rng.random(n)), _f32(rng.random((n, 2)))
    s = model.sample(wo, uc, u)
    r = ref.sample(model, wo, uc, u)
    # below the surface Mitsuba's twosided mirrors z only, pbrt/bsdfkit invert the whole vector
    # (wo -> -wo): the same material; the coating's samples (rotation-equivariant about z) then
    # coincide, the cosine-weighted diffuse sample (independent of wo) differs by (x, y) -> -(x, y)
    # (at normal incidence the coating's sampling frame is the same fixed one in both: flip too)
    pole = (wo[:, 0] == 0) & (wo[:, 1] == 0)
    lower = (wo[:, 2] < 0) & ((r["sampled_component"] == 1) | pole)
    r["wi"][lower, :2] *= -1
    spec_ours = (s.flags & (bk.BxDFFlags.Specular | bk.BxDFFlags.Glossy)) != 0
    spec_mi = r["sampled_component"] == 0
    both = s.valid & r["valid"]
    assert abs(s.valid.mean() - r["valid"].mean()) < 1e-3
    # the lobe choice differs only where uc sits within float32 rounding of the threshold
    assert np.mean(spec_ours[both] != spec_mi[both]) < 1e-3
    same = both & (spec_ours == spec_mi)
    dw = np.abs(s.wi[same] - r["wi"][same]).max(1)
    print(f"{model!r}: direction diff p99.9 {np.quantile(dw, 0.999):.3g}")
    assert np.quantile(dw, 0.999) < 1e-4
    close = np.zeros(n, bool)
    close[np.flatnonzero(same)[dw < 1e-5]] = True
    close &= ~lower  # a flipped diffuse sample is another (wo, wi) pair for the rough lobe's value
    tol = 10 * (TOL_SMOOTH if model.alpha == 0 else TOL_ROUGH)
    if model.alpha > 0 and model.eta < 1:  # Mitsuba's host-dependent float32 tables (docstring)
        tol = TOL_ROUGH_INNER_PDF
    _check(s.weight[close], r["weight"][close], tol, f"{model!r} weight")
    _check(s.pdf[close], r["pdf"][close], tol, f"{model!r} sample pdf")


def test_fresnel_diffuse_reflectance_matches_mitsuba():
    mi = ref._mi()[0]
    for eta in (0.5, 1 / 1.49, 0.9, 1.1, 1.33, 1.49, 2.0, 3.0):
        ours = bk._core.fresnel_diffuse_reflectance(eta)
        assert abs(ours - float(mi.fresnel_diffuse_reflectance(eta)[0] if hasattr(
            mi.fresnel_diffuse_reflectance(eta), "__len__") else mi.fresnel_diffuse_reflectance(eta))) < 2e-6


def _transmittance_mc(alpha, eta, mu, rng, n=400_000):
    """Independent float64 estimate of the GGX interface's directional transmittance
    T(mu) = E_{m ~ D_wo}[(1 - F(wo.m)) G1(wt, m)] (Walter 2007; Heitz 2014's VNDF), with
    visible normals drawn by Heitz 2018's hemisphere method (not Mitsuba's warp)."""
    wo = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
    u1, u2 = rng.random(n), rng.random(n)
    vh = np.array([alpha * wo[0], alpha * wo[1], wo[2]])
    vh /= np.linalg.norm(vh)
    t1 = np.cross([0, 0, 1], vh)
    t1 = t1 / np.linalg.norm(t1) if np.linalg.norm(t1) > 0 else np.array([1.0, 0, 0])
    t2 = np.cross(vh, t1)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    p1, p2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1 + vh[2])
    p2 = (1 - s) * np.sqrt(1 - p1 * p1) + s * p2
    nh = p1[:, None] * t1 + p2[:, None] * t2 + np.sqrt(np.maximum(0, 1 - p1 * p1 - p2 * p2))[:, None] * vh
    m = np.stack([alpha * nh[:, 0], alpha * nh[:, 1], np.maximum(1e-6, nh[:, 2])], 1)
    m /= np.linalg.norm(m, axis=1, keepdims=True)
    c = m @ wo
    st2 = (1 - c * c) / eta ** 2
    ct = np.sqrt(np.maximum(0, 1 - st2))
    F = np.where(st2 >= 1, 1.0, 0.5 * (((c - eta * ct) / (c + eta * ct)) ** 2 + ((eta * c - ct) / (eta * c + ct)) ** 2))
    wt = m * (c / eta - ct)[:, None] - wo / eta
    lam = (np.sqrt(1 + alpha ** 2 * (wt[:, 0] ** 2 + wt[:, 1] ** 2) / wt[:, 2] ** 2) - 1) / 2
    g1 = np.where((np.sum(wt * m, 1) * wt[:, 2] > 0) & (wt[:, 2] < 0), 1 / (1 + lam), 0.0)
    v = (1 - F) * g1
    return v.mean(), v.std() / np.sqrt(n)


@pytest.mark.parametrize("alpha, eta", [(0.1, 1.49), (0.5, 1.5), (0.3, 1 / 1.3)])
def test_transmittance_table_against_monte_carlo(alpha, eta, rng):
    """The table is the physical quantity: a float64 Monte Carlo of the same integral with a
    different warp agrees within 4 sigma + the quadrature's own error (1e-3 at grazing mu)."""
    t = bk.Plastic(0.5, eta, alpha=alpha).transmittance_table
    for i in (63, 40, 20, 8, 2):
        mu = i / 63
        mc, se = _transmittance_mc(alpha, eta, mu, rng)
        assert abs(t[i] - mc) < 4 * se + 1e-3 * (1 + 10 * (mu < 0.1)), (i, t[i], mc, se)


def test_smooth_table_is_one_minus_fresnel():
    t = bk.Plastic(0.5, 1.5).transmittance_table
    mu = np.arange(64) / 63
    ct = np.sqrt(1 - (1 - mu ** 2) / 1.5 ** 2)
    F = 0.5 * (((mu - 1.5 * ct) / (mu + 1.5 * ct)) ** 2 + ((1.5 * mu - ct) / (1.5 * mu + ct)) ** 2)
    np.testing.assert_allclose(t, 1 - F, atol=1e-12)


# slow: the rough (alpha 0.2) and smooth models' sampling is also chi-square tested, with fewer
# samples and incidences, by the contract (tests/contract/test_chi2_contract.py: the registered
# Plastic examples "red, rough coat" and "smooth plastic"); alpha 0.05 is too narrow for it.
_SLOW = pytest.mark.slow


@pytest.mark.parametrize("z", [0.999, 0.7, 0.3, 0.05])
@pytest.mark.parametrize("model", [pytest.param(bk.Plastic([0.9, 0.5, 0.1], 1.5, alpha=0.2), marks=_SLOW),
                                   bk.Plastic(0.5, 1.49, alpha=0.05, masking="separable"),
                                   pytest.param(bk.Plastic([0.3, 0.3, 0.8], 1.5), marks=_SLOW)], ids=repr)
def test_chi2_sampling(model, z):
    """Mitsuba's chi^2 harness on the non-delta part (the smooth model's diffuse lobe alone)."""
    s = np.sqrt(1 - z * z)
    wo = np.array([s * np.cos(0.4), s * np.sin(0.4), z])
    R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # lobes off the poles

    def sample_fn(uc, u):
        r = model.sample(wo, uc, u)
        return r.wi @ R.T, r.valid & ((r.flags & bk.BxDFFlags.Specular) == 0)

    def pdf_fn(v):
        return model.pdf(wo, v @ R)

    # ires: the smooth model's non-delta part is its diffuse lobe alone, as easy to integrate as
    # alpha >= 0.1 (p = 0.7711 at ires 32, 0.7707 at 16, smooth z = 0.7); only alpha = 0.05 needs 32
    ok, p, msg = ref.chi2_test(sample_fn, pdf_fn, res=101, ires=16 if model.alpha == 0 or model.alpha >= 0.1 else 32,
                               sample_count=1_000_000, seed=5, significance=0.01, test_count=12)
    print(f"chi2 {model!r} z={z}: p = {p:.4g}")
    assert ok, msg


@pytest.mark.parametrize("model", SMOOTH[:3] + ROUGH[:3] + [bk.Plastic(0.5, alpha=0.3)], ids=repr)
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_sample_consistent_with_eval_and_pdf(model, dtype, rng):
    n = 20_000
    wo = np.concatenate([_dirs(rng, n // 2, ZS), _dirs(rng, n // 2, ZS, -1.0)]).astype(dtype)
    s = model.sample(wo, rng.random(n).astype(dtype), rng.random((n, 2)).astype(dtype))
    assert np.all(np.isfinite(s.f)) and np.all(np.isfinite(s.pdf))
    assert np.all(s.wi[s.valid, 2] * wo[s.valid, 2] > 0)  # reflection only, wo's side
    nd = s.valid & ((s.flags & bk.BxDFFlags.Specular) == 0)
    rtol = 1e-10 if dtype == np.float64 else 2e-4
    np.testing.assert_allclose(model.eval(wo[nd], s.wi[nd]), s.f[nd], rtol=rtol, atol=1e-30)
    np.testing.assert_allclose(model.pdf(wo[nd], s.wi[nd]), s.pdf[nd], rtol=rtol, atol=1e-30)
    d = s.valid & ~nd
    if model.alpha == 0 and d.any():  # delta: mirror direction, f = Ks F / cos
        np.testing.assert_allclose(s.wi[d][:, :2], -wo[d][:, :2], atol=1e-6)


def test_energy_and_white_furnace():
    wo = bk.direction(np.radians([0, 30, 60, 80, 89]), 0.3)
    for m in (bk.Plastic(1.0, 1.5), bk.Plastic(1.0, 1.5, nonlinear=True)):
        a = m.albedo(wo, n_samples=200_000)
        print(f"{m!r}: albedo {a[:, 0]}")
        # R = 1, Ks = 1, smooth: F + T (1 - Fdr_ext) / ((1 - Fdr_int) eta^2) = 1 up to the Fdr fit
        np.testing.assert_allclose(a, 1.0, atol=0.012)
    for m in (bk.Plastic(1.0, 1.5, alpha=0.3), bk.Plastic(1.0, 1.33, alpha=0.8, nonlinear=True),
              bk.Plastic(0.8, 2.5, alpha=0.05)):
        a = m.albedo(wo, n_samples=200_000)
        print(f"{m!r}: albedo {a[:, 0]}")
        assert np.all(a <= 1.0 + 0.01) and np.all(a > 0.15)  # single-scattering rough coats lose energy


def test_flags_and_delta_convention():
    assert bk.Plastic(0.5).flags == bk.BxDFFlags.SpecularReflection | bk.BxDFFlags.DiffuseReflection
    assert bk.Plastic(0.5, alpha=0.2).flags == bk.BxDFFlags.GlossyReflection | bk.BxDFFlags.DiffuseReflection
    assert bk.Plastic(0.0, alpha=0.2).flags == bk.BxDFFlags.GlossyReflection
    wo, wi = bk.direction(0.5, 0.0), bk.direction(0.5, np.pi)   # mirror pair: delta lobe is not in eval
    m = bk.Plastic(0.0, 1.5)
    assert np.all(m.eval(wo, wi) == 0) and m.pdf(wo, wi) == 0
    # transmission is never sampled; sample_flags=Transmission gives no sample
    s = bk.Plastic(0.5, alpha=0.2).sample(wo, n=1000, seed=1, sample_flags=bk.ReflTrans.Transmission)
    assert not s.valid.any()


@pytest.mark.parametrize("kwargs, name", [
    (dict(reflectance=1.5), "reflectance"), (dict(reflectance=-0.1), "reflectance"),
    (dict(reflectance=[0.5, np.nan, 0.1]), "reflectance"), (dict(eta=0.0), "eta"), (dict(eta=1.0), "eta"),
    (dict(eta=np.inf), "eta"), (dict(alpha=-0.1), "alpha"), (dict(masking="smith"), "masking"),
    (dict(specular_reflectance=-1), "specular_reflectance"),
])
def test_bad_input_names_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=name):
        bk.Plastic(**kwargs)
    with pytest.raises(TypeError, match="nonlinear"):
        bk.Plastic(nonlinear="yes")


def test_value_semantics():
    import pickle
    m = bk.Plastic([0.8, 0.2, 0.1], 1.4, alpha=0.2, nonlinear=True, masking="separable", specular_reflectance=0.9)
    assert eval(repr(m), {"Plastic": bk.Plastic}) == m
    assert pickle.loads(pickle.dumps(m)) == m and hash(m) == hash(bk.Plastic(**m._params))
    assert m != bk.Plastic([0.8, 0.2, 0.1], 1.4, alpha=0.2, masking="separable", specular_reflectance=0.9)
    with pytest.raises(AttributeError):
        m.eta = 1.3


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("model", [bk.Plastic(1.0, 1.0001, alpha=1e-3), bk.Plastic(0.0, 4.0, alpha=1.0),
                                   bk.Plastic(1.0, 0.3, nonlinear=True), bk.Plastic(0.5, 1.5, alpha=1e-3),
                                   bk.Plastic(0.5, 1.0001)], ids=repr)
def test_extremes_finite(model, dtype, rng):
    zs = [1.0, 0.5, 1e-3, 1e-7, 0.0, -1e-7, -0.5, -1.0]
    wo = _dirs(rng, 4000, zs).astype(dtype)
    wi = _dirs(rng, 4000, zs[::-1]).astype(dtype)
    assert np.all(np.isfinite(model.eval(wo, wi))) and np.all(model.eval(wo, wi) >= 0)
    assert np.all(np.isfinite(model.pdf(wo, wi)))
    for uc in (0.0, 1 - 1e-7, 0.5):
        s = model.sample(wo, np.full(4000, uc, dtype), np.clip(rng.random((4000, 2)), 0, 1).astype(dtype))
        assert np.all(np.isfinite(s.f)) and np.all(np.isfinite(s.pdf)) and np.all(np.isfinite(s.wi))
    s = model.sample(wo, np.zeros(4000, dtype), np.zeros((4000, 2), dtype))
    assert np.all(np.isfinite(s.f))


def test_mitsuba_interop_round_trip():
    from bsdfkit.testing.mitsuba import to_mitsuba
    for m in SMOOTH[:3] + ROUGH:
        m = bk.Plastic(**{**m._params, "masking": "separable"})
        assert bk.from_mitsuba(to_mitsuba(m)) == m
        assert bk.from_mitsuba(to_mitsuba(m)["bsdf"]) == m       # the bare one-sided plugin too
    m = bk.from_mitsuba({"type": "roughplastic", "distribution": "ggx", "alpha": 0.2, "int_ior": "acrylic glass",
                         "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.2, 0.1]}, "nonlinear": True})
    assert m == bk.Plastic([0.5, 0.2, 0.1], 1.49 / 1.000277, alpha=0.2, nonlinear=True, masking="separable")
    assert bk.from_mitsuba({"type": "plastic"}) == bk.Plastic(0.5, 1.49 / 1.000277, masking="separable")
    for d, word in (({"type": "roughplastic", "alpha": 0.1}, "beckmann"),
                    ({"type": "plastic", "nonlinear": "yes"}, "nonlinear"),
                    ({"type": "plastic", "diffuse_reflectance": 1.5}, "reflectance"),
                    ({"type": "roughplastic", "distribution": "ggx", "alpha_u": 0.1, "alpha_v": 0.2}, "alpha_u")):
        with pytest.raises(ValueError, match=word):
            bk.from_mitsuba(d)
