"""float32 accuracy of the models on the packet path (issue 17): the float32 kernel against the float64
kernel on the same float32-representable direction pairs, for the models whose per-element code was
restructured for packets and fewer divisions (Plastic, FilamentStandard, Hair, NormalizedFresnel, the
analytic coated models, DiffuseTransmission; ThinDielectric, whose only non-zero output is its sample,
through sample against an independent numpy float64 slab). The
float64 kernels themselves are checked against Mitsuba / the independent references in tests/models/.

Well-conditioned pairs: both |cos| >= 0.1 and a value >= 1e-3 of the median positive value. Below that the
relative error measures conditioning, not arithmetic: values deep in an exponential tail (hair's Mp and
logistic, GGX's D far from the peak) carry float32's rounding of their exponent's argument. Hair's Mp is
exp(LogI0(a) - b + log_norm) with a, b ~ 1/v (its longitudinal variance; v0/4 for TT): the exponent's
terms are O(1/v) and cancel to O(1), so rounding the cosines' products to float32 costs ~eps32 / v
relative whatever the arithmetic (measured on the scalar libm kernel before the packet path: p99.9 9.5e-6
at beta_m = 0.3, 1.3e-4 at beta_m = 0.1, the same as now). Hair's tolerance is therefore
max(1e-5, 5 eps32 / v_min).
"""
import numpy as np
import pytest

import bsdfkit as bk

MODELS = {
    "Plastic-smooth": lambda: bk.Plastic((0.2, 0.5, 0.8), eta=1.49),
    "Plastic-rough": lambda: bk.Plastic((0.7, 0.3, 0.1), eta=1.5, alpha=0.3),
    "Plastic-rough-separable": lambda: bk.Plastic(0.6, eta=1.3, alpha=0.1, masking="separable", nonlinear=True),
    "FilamentStandard": lambda: bk.FilamentStandard((0.8, 0.5, 0.3)),
    "FilamentStandard-aniso": lambda: bk.FilamentStandard((0.91, 0.92, 0.92), metallic=1, roughness=0.5,
                                                          anisotropy=0.8),
    "FilamentStandard-burley-fast": lambda: bk.FilamentStandard((0.3, 0.6, 0.2), roughness=0.3, diffuse="burley",
                                                                visibility="fast"),
    "FilamentStandardCoat": lambda: bk.FilamentStandard((0.05, 0.2, 0.7), metallic=0.7, clear_coat=1,
                                                        clear_coat_roughness=0.1),
    "FilamentStandardSheen": lambda: bk.FilamentStandard((0.3, 0.05, 0.1), roughness=0.6,
                                                         sheen_color=(0.9, 0.6, 0.7), sheen_roughness=0.4),
    "Hair": lambda: bk.Hair(h=0.3),
    "Hair-narrow": lambda: bk.Hair((0.1, 0.8, 1.5), beta_m=0.1, beta_n=0.2, h=-0.7),
    "HairFarField": lambda: bk.Hair(h=None, nodes=16),
    "NormalizedFresnel": lambda: bk.NormalizedFresnel(1.33),
    "CoatedDiffuseAnalytic": lambda: bk.CoatedDiffuse((0.6, 0.35, 0.15), alpha=0.2, albedo=0.8, thickness=0.2,
                                                      g=0.3, method="analytic"),
    "CoatedConductorAnalytic": lambda: bk.CoatedConductor.from_metal("Cu", conductor_alpha=0.3, interface_alpha=0.1,
                                                                     albedo=(0.5, 0.1, 0.1), thickness=0.1,
                                                                     method="analytic"),
    "DiffuseTransmission": lambda: bk.DiffuseTransmission((0.2, 0.6, 0.3), (0.7, 0.1, 0.5)),
}


def _pairs(m, n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    wo, wi = v[0], v[1]
    wo[:, 2] = np.abs(wo[:, 2])  # the Filament models are one-sided; the others are symmetric or need no more
    # half the wi sampled from the model, so the lobes' peaks are well covered
    s = m.sample(wo[: n // 2], rng.random(n // 2), rng.random((n // 2, 2)))
    take = s.valid & ((s.flags & bk.BxDFFlags.Specular) == 0)
    wi[: n // 2] = np.where(take[:, None], s.wi, wi[: n // 2])
    return wo.astype(np.float32), wi.astype(np.float32)


def _tolerance(m):
    if not isinstance(m, bk.Hair):
        return 1e-5
    b = m.beta_m
    v_min = (0.726 * b + 0.812 * b * b + 3.7 * b ** 20) ** 2 / 4  # Chiang 2016 eq. 7; TT's v0 / 4
    return max(1e-5, 5 * 2.0 ** -24 / v_min)


def _p999(v32, v64, good):
    good = good & (v64 >= 1e-3 * np.median(v64[v64 > 0]))
    assert good.sum() > 20_000
    rel = np.abs(v32[good].astype(np.float64) - v64[good]) / v64[good]
    return np.quantile(rel, 0.999), rel.max()


@pytest.mark.parametrize("name", sorted(MODELS))
def test_float32_matches_float64_when_well_conditioned(name):
    m = MODELS[name]()
    wo32, wi32 = _pairs(m, 100_000, 7)
    wo, wi = wo32.astype(np.float64), wi32.astype(np.float64)
    good = (np.abs(wo[:, 2]) >= 0.1) & (np.abs(wi[:, 2]) >= 0.1)
    tol = _tolerance(m)
    f64, f32 = m.eval(wo, wi), m.eval(wo32, wi32)
    for c in range(3):
        p, mx = _p999(f32[:, c], f64[:, c], good)
        print(f"{name} f[{c}]: p99.9 {p:.2g}, max {mx:.2g}")
        assert p <= tol
    p, mx = _p999(m.pdf(wo32, wi32), m.pdf(wo, wi), good)
    print(f"{name} pdf: p99.9 {p:.2g}, max {mx:.2g}")
    assert p <= tol


def _slab_reference(cos_o, eta):
    """pbrt-v4's thin slab in float64 numpy, written from the Fresnel equations: R' = R + T^2 R / (1 - R^2),
    T' = 1 - R' (R of the unpolarized interface, 1 beyond total internal reflection)."""
    cos_o = np.abs(cos_o)
    sin2_t = (1 - cos_o ** 2) / eta ** 2
    cos_t = np.sqrt(np.maximum(0, 1 - sin2_t))
    r_par = (eta * cos_o - cos_t) / (eta * cos_o + cos_t)
    r_perp = (cos_o - eta * cos_t) / (cos_o + eta * cos_t)
    R = np.where(sin2_t >= 1, 1.0, (r_par ** 2 + r_perp ** 2) / 2)
    T = 1 - R
    Rs = np.where(R < 1, R + T * T * R / np.where(R < 1, 1 - R * R, 1), R)
    return Rs, 1 - Rs


@pytest.mark.parametrize("eta", [1.5, 1.2, 0.7, 3.0])
def test_thin_dielectric_sample_matches_float64_reference(eta):
    # ThinDielectric's f and pdf are 0 (delta lobes): its arithmetic is in sample. Lobe choice, f, pdf and
    # weight against the slab formula in float64, for the float32 and float64 kernels, |cos| >= 0.1.
    rng = np.random.default_rng(3)
    n = 100_000
    v = rng.normal(size=(n, 3))
    wo = (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)
    uc = rng.random(n).astype(np.float32)
    u = rng.random((n, 2)).astype(np.float32)
    wo64 = wo.astype(np.float64)
    Rs, Ts = _slab_reference(wo64[:, 2], eta)
    m = bk.ThinDielectric(eta)
    good = np.abs(wo64[:, 2]) >= 0.1
    for dtype, tol in ((np.float32, 1e-5), (np.float64, 1e-12)):
        s = m.sample(wo.astype(dtype), uc.astype(dtype), u.astype(dtype))
        refl = s.wi[:, 2] * wo64[:, 2] > 0
        # the lobe choice is uc < R' (away from ties at the float32 rounding of R')
        clear = good & s.valid & (np.abs(uc - Rs) > 1e-5)
        np.testing.assert_array_equal(refl[clear], (uc < Rs)[clear])
        np.testing.assert_array_equal(s.wi[:, :2], -wo[:, :2].astype(dtype))
        p_ref = np.where(refl, Rs, Ts)
        f_ref = p_ref / np.abs(wo64[:, 2])
        ok = clear & (p_ref > 1e-3)
        rel_f = np.abs(s.f[ok, 0] - f_ref[ok]) / f_ref[ok]
        rel_p = np.abs(s.pdf[ok] - p_ref[ok]) / p_ref[ok]
        print(f"ThinDielectric({eta}) {np.dtype(dtype).name}: f p99.9 {np.quantile(rel_f, 0.999):.2g}, "
              f"pdf p99.9 {np.quantile(rel_p, 0.999):.2g}")
        assert ok.sum() > 50_000
        assert np.quantile(rel_f, 0.999) <= tol and np.quantile(rel_p, 0.999) <= tol
        np.testing.assert_array_equal(s.f[:, 0], s.f[:, 1])
        np.testing.assert_allclose(s.weight[ok, 0], 1.0, rtol=10 * tol)  # f |cos| / pdf: lossless slab


def test_diffuse_transmission_sample_matches_float64():
    m = MODELS["DiffuseTransmission"]()
    rng = np.random.default_rng(5)
    n = 100_000
    v = rng.normal(size=(n, 3))
    wo = (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)
    uc, u = rng.random(n).astype(np.float32), rng.random((n, 2)).astype(np.float32)
    s32 = m.sample(wo, uc, u)
    s64 = m.sample(wo.astype(np.float64), uc.astype(np.float64), u.astype(np.float64))
    same = s32.valid & s64.valid & (s32.flags == s64.flags) & (np.abs(s64.wi[:, 2]) >= 0.1)
    assert same.mean() > 0.85
    rel = np.abs(s32.pdf[same] - s64.pdf[same]) / s64.pdf[same]
    assert np.quantile(rel, 0.999) <= 1e-5
    np.testing.assert_allclose(s32.f[same], s64.f[same], rtol=1e-6)
    # the pdf is the cosine lobe times the chosen lobe's probability (largest channels 0.6 and 0.7)
    p = np.where(s64.flags == bk.BxDFFlags.DiffuseReflection, 0.6, 0.7) / 1.3 * np.abs(s64.wi[:, 2]) / np.pi
    np.testing.assert_allclose(s64.pdf[s64.valid], p[s64.valid], rtol=1e-14)
