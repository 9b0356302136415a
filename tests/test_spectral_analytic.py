"""Spectral mode (``wavelengths=``) of the analytic models beyond the pbrt core: Plastic (smooth and
rough), NormalizedFresnel, FilamentStandard (its four lobe variants) and the analytic coated models
(CoatedDiffuse / CoatedConductor with method="analytic"). Plastic against Mitsuba
llvm_ad_spectral is in tests/test_spectral_mitsuba.py.

References (none of them our own output):
* constant spectra: every per-wavelength value equals the RGB model's with the same grey
  parameters (1e-12, float64), for eval, pdf, sample and albedo;
* spectra varying per wavelength: f at lambda equals the RGB model built with the grey parameter
  values param(lambda) where the model's f has no cross-channel term (Plastic, the coated models,
  NormalizedFresnel, Filament with f90="one"), and independent float64 references written from the
  formulas: numpy NormalizedFresnel with a quadrature Fresnel moment (hair_ref) for eta(lambda) of
  BK7, the Dr.Jit float64 analytic-layered restatement (layered_analytic_ref) for a coated metal
  with Au eta(lambda), k(lambda), and the Dr.Jit Filament restatement (drjit_filament) for a
  spectral base colour;
* contract properties in spectral mode: reciprocity (reciprocal models), albedo bounds and the
  NormalizedFresnel furnace, sample/eval consistency, chi^2 (rough Plastic, Filament with sheen and
  coat, rough coated metal), thread-count and array-position bit identity, bad input.
"""
import types

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import hair_ref
from bsdfkit.testing import mitsuba as ref
from bsdfkit.testing import spectral_checks as checks
from conftest import random_dirs, random_wavelengths as _lam

IMP = bk.TransportMode.Importance
RAD = bk.TransportMode.Radiance
LAM4 = np.array([380.0, 455.5, 560.25, 700.0])
R_SPEC = bk.Spectrum([360.0, 430.5, 520.0, 610.0, 700.0, 830.0], [0.05, 0.31, 0.62, 0.40, 0.90, 0.83])
KS_SPEC = bk.Spectrum([360.0, 500.0, 830.0], [0.7, 1.0, 0.85])
ALB_SPEC = bk.Spectrum([360.0, 550.0, 830.0], [0.9, 0.2, 0.6])
BK7 = bk.Spectrum.named("glass-BK7")


def _au():
    return bk.Spectrum.named("mitsuba-Au-eta"), bk.Spectrum.named("mitsuba-Au-k")


MODELS = {
    "Plastic-smooth": lambda: bk.Plastic(R_SPEC, eta=1.5, specular_reflectance=KS_SPEC),
    "Plastic-rough": lambda: bk.Plastic(R_SPEC, eta=1.49, alpha=0.2),
    "Plastic-rough-nonlinear-rgb": lambda: bk.Plastic([0.8, 0.2, 0.1], alpha=0.3, nonlinear=True,
                                                      masking="separable"),
    "NormalizedFresnel-BK7": lambda: bk.NormalizedFresnel(BK7),
    "Filament": lambda: bk.FilamentStandard(R_SPEC, roughness=0.4),
    "Filament-metal-aniso": lambda: bk.FilamentStandard([1.0, 0.85, 0.57], metallic=1.0, roughness=0.5,
                                                        anisotropy=0.6),
    "Filament-coat-sheen": lambda: bk.FilamentStandard(R_SPEC, roughness=0.5, clear_coat=0.8,
                                                       clear_coat_roughness=0.1, sheen_color=ALB_SPEC,
                                                       sheen_roughness=0.4),
    "CoatedDiffuse-analytic": lambda: bk.CoatedDiffuse(R_SPEC, alpha=0.15, albedo=ALB_SPEC, thickness=0.2, g=0.3,
                                                       method="analytic"),
    "CoatedDiffuse-smooth-analytic": lambda: bk.CoatedDiffuse(R_SPEC, method="analytic"),
    "CoatedConductor-analytic": lambda: bk.CoatedConductor(*_au(), conductor_alpha=0.3, interface_alpha=0.05,
                                                           albedo=ALB_SPEC, thickness=0.1, method="analytic"),
    "CoatedConductor-smooth-analytic": lambda: bk.CoatedConductor(*_au(), thickness=0.05, method="analytic"),
}
#: made only of delta lobes (eval is 0 everywhere): checked through sample
DELTA_ONLY = {"CoatedConductor-smooth-analytic"}
RECIPROCAL = [k for k in MODELS if not k.startswith(("Filament", "NormalizedFresnel")) and k not in DELTA_ONLY]


def _grey_rebuild(name, lam):
    """The RGB model whose grey parameters are the spectral model's values at one wavelength."""
    m = MODELS[name]()
    p = dict(m._params)
    for k, v in p.items():
        if isinstance(v, bk.Spectrum):
            p[k] = float(v(np.float64(lam)))
    return type(m)._from_params(p)


# ---- constant spectra: exactly the RGB model ------------------------------------------------

GREY = {
    "Plastic-smooth": lambda: bk.Plastic(0.4, eta=1.5, specular_reflectance=0.8),
    "Plastic-rough": lambda: bk.Plastic(bk.Spectrum.constant(0.6), alpha=0.25, nonlinear=True),
    "NormalizedFresnel": lambda: bk.NormalizedFresnel(bk.Spectrum.constant(1.4)),
    "Filament": lambda: bk.FilamentStandard(0.7, roughness=0.3),
    "Filament-coat-sheen": lambda: bk.FilamentStandard(0.5, metallic=0.3, roughness=0.5, clear_coat=0.7,
                                                       sheen_color=0.4, sheen_roughness=0.5),
    "CoatedDiffuse-analytic": lambda: bk.CoatedDiffuse(0.5, alpha=0.2, albedo=0.3, thickness=0.3, method="analytic"),
    "CoatedConductor-analytic": lambda: bk.CoatedConductor(0.3, 3.1, conductor_alpha=0.2, albedo=0.4, thickness=0.1,
                                                           method="analytic"),
    "CoatedConductor-smooth-analytic": lambda: bk.CoatedConductor(0.3, 3.1, thickness=0.1, method="analytic"),
}


@pytest.mark.parametrize("name", sorted(GREY))
def test_constant_spectra_equal_rgb(name, rng):
    m = GREY[name]()
    n = 3000
    wo, wi, lam = random_dirs(rng, n), random_dirs(rng, n), _lam(rng, n)
    uc, u = rng.random(n), rng.random((n, 2))
    for mode in (RAD, IMP):
        f, f_rgb = m.eval(wo, wi, mode=mode, wavelengths=lam), m.eval(wo, wi, mode=mode)
        np.testing.assert_allclose(f, np.repeat(f_rgb[:, :1], 4, 1), rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(m.pdf(wo, wi, wavelengths=lam), m.pdf(wo, wi), rtol=1e-12, atol=1e-300)
    s, s_rgb = m.sample(wo, uc, u, wavelengths=lam), m.sample(wo, uc, u)
    np.testing.assert_array_equal(s.valid, s_rgb.valid)
    np.testing.assert_allclose(s.wi, s_rgb.wi, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(s.f, np.repeat(s_rgb.f[:, :1], 4, 1), rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(s.pdf, s_rgb.pdf, rtol=1e-12, atol=1e-300)
    np.testing.assert_array_equal(s.flags, s_rgb.flags)
    assert not s.terminated.any()
    assert np.count_nonzero(f) > n or (name.endswith("smooth-analytic") and np.count_nonzero(s.f) > n)
    w3 = wo[:5]
    a, a_rgb = m.albedo(w3, n_samples=2048, seed=4, wavelengths=LAM4), m.albedo(w3, n_samples=2048, seed=4)
    np.testing.assert_allclose(a, np.repeat(a_rgb[:, :1], 4, 1), rtol=1e-12)


# ---- varying spectra: per wavelength the RGB model with that wavelength's grey values -------

@pytest.mark.parametrize("name", ["Plastic-smooth", "Plastic-rough", "NormalizedFresnel-BK7", "CoatedDiffuse-analytic",
                                  "CoatedConductor-analytic", "CoatedConductor-smooth-analytic"])
def test_eval_per_wavelength_is_the_grey_rgb_model(name, rng):
    """f(lambda_i) = f of the RGB model rebuilt with every spectral parameter replaced by its value
    at lambda_i (these models' f has no term coupling the channels); the delta lobes likewise
    through sample (same uniforms; the lobe choice, wavelength-independent, may differ from the
    grey model's, so only samples of the same lobe and direction are compared)."""
    m = MODELS[name]()
    n = 2000
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    f = m.eval(wo, wi, wavelengths=LAM4)
    s = m.sample(wo, rng.random(n), rng.random((n, 2)), wavelengths=LAM4)
    for i, l in enumerate(LAM4):
        g = _grey_rebuild(name, l)
        np.testing.assert_allclose(f[:, i], g.eval(wo, wi)[:, 0], rtol=1e-12, atol=1e-300)
        # delta samples: f = R / |cos|, the grey model's delta value at the same direction
        spec = s.valid & ((s.flags & bk.BxDFFlags.Specular) != 0)
        if spec.any():
            gs = g.sample(wo[spec], np.zeros(spec.sum()), np.full((spec.sum(), 2), 0.5))  # uc = 0: the coat's delta
            same = gs.valid & ((gs.flags & bk.BxDFFlags.Specular) != 0)
            np.testing.assert_allclose(gs.wi[same], s.wi[spec][same], atol=1e-12)
            np.testing.assert_allclose(s.f[spec][same, i], gs.f[same, 0], rtol=1e-12)
    # the wavelengths matter
    v = s.f[s.valid] if name in DELTA_ONLY else f
    assert np.mean(np.ptp(v, axis=1) > 1e-3 * v.max(axis=1)) > 0.3


def test_normalized_fresnel_eta_of_lambda_vs_numpy(rng):
    """eta(lambda) of BK7 per wavelength: numpy float64 (1 - Fr) / (c pi) eta^2 with the Fresnel
    moment by quadrature (pbrt-v4's polynomial fit differs by < 3e-3 relative, as in RGB)."""
    m = MODELS["NormalizedFresnel-BK7"]()
    n = 4000
    wo, wi, lam = random_dirs(rng, n), random_dirs(rng, n), _lam(rng, n)
    for mode, mname in ((RAD, "radiance"), (IMP, "importance")):
        f = m.eval(wo, wi, mode=mode, wavelengths=lam)
        eta = BK7(lam)
        k = 300   # the reference's quadrature runs per eta value: 1200 of them
        expect = np.array([[hair_ref.normalized_fresnel_f(float(eta[i, j]), wo[i], wi[i], mname)
                            for j in range(4)] for i in range(k)])
        assert np.count_nonzero(expect) > k
        np.testing.assert_allclose(f[:k], expect, rtol=3e-3, atol=0)
    # the dispersion is visible: BK7's eta changes f^2-scaled values by > 1 % over the visible range
    assert np.ptp(m.eval([0, 0, 1], [0, 0, 1], wavelengths=[[380.0, 480.0, 600.0, 780.0]])) > 1e-3
    p = m.pdf(wo, wi, wavelengths=lam)
    np.testing.assert_allclose(p, np.where(wo[:, 2] * wi[:, 2] > 0, np.abs(wi[:, 2]) / np.pi, 0.0), rtol=1e-14)


def test_coated_conductor_gold_vs_drjit_reference(rng):
    """The analytic coated metal with Au eta(lambda), k(lambda): f per wavelength against the
    float64 Dr.Jit restatement of the analytic layered formulas, fed the spectra's values."""
    from bsdfkit.testing import layered_analytic_ref as lref
    m = MODELS["CoatedConductor-analytic"]()
    n = 3000
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    lam = np.array([400.0, 480.0, 590.0, 720.0])
    f = m.eval(wo, wi, wavelengths=lam)
    eta, k = _au()
    p = dict(m._params)
    for sl in (slice(0, 3), slice(3, 4)):
        ls = np.resize(lam[sl], 3)
        q = types.SimpleNamespace(**{**p, "conductor_eta": list(eta(ls)), "conductor_k": list(k(ls)),
                                     "albedo": list(ALB_SPEC(ls))})
        expect = lref.coated_f(q, "CoatedConductor", wo, wi)
        np.testing.assert_allclose(f[:, sl], expect[:, :sl.stop - sl.start], rtol=1e-9, atol=1e-12 * f.max())
    assert np.count_nonzero(f) > n


def test_filament_spectral_base_color_vs_drjit_reference(rng):
    """FilamentStandard with a spectral base colour and f90 = 1 (f90 = saturate(16.5 sum f0) is the
    RGB projection's in spectral mode): f per wavelength against the float64 Dr.Jit Filament
    restatement with base_color = the spectrum's values."""
    from bsdfkit import filament
    from bsdfkit.testing import drjit_filament as dref
    m = bk.FilamentStandard(R_SPEC, metallic=0.4, roughness=0.45, clear_coat=0.5, clear_coat_roughness=0.2,
                            f90="one")
    n = 3000
    wo, wi = random_dirs(rng, n, 1), random_dirs(rng, n, 1)
    f = m.eval(wo, wi, wavelengths=LAM4)
    lut = filament.dfg_lut(m.dfg_lut_size)
    for sl in (slice(0, 3), slice(3, 4)):
        g = bk.FilamentStandard(list(np.resize(R_SPEC(LAM4[sl]), 3)), metallic=0.4, roughness=0.45, clear_coat=0.5,
                                clear_coat_roughness=0.2, f90="one")
        np.testing.assert_allclose(f[:, sl], g.eval(wo, wi)[:, :sl.stop - sl.start], rtol=1e-12, atol=1e-300)
        expect = dref.standard_f(g, wo, wi, lut)
        np.testing.assert_allclose(f[:, sl], expect[:, :sl.stop - sl.start], rtol=1e-6, atol=1e-9)


# ---- contract properties in spectral mode ---------------------------------------------------

@pytest.mark.parametrize("name", RECIPROCAL)
def test_reciprocity(name, rng):
    m = MODELS[name]()
    n = 3000
    a, _ = checks.reciprocity(m, random_dirs(rng, n), random_dirs(rng, n), _lam(rng, n))
    assert np.count_nonzero(a) > n


@pytest.mark.parametrize("name", sorted(MODELS))
def test_sample_eval_consistency(name, rng):
    m = MODELS[name]()
    n = 5000
    wo, lam = random_dirs(rng, n), _lam(rng, n)
    s, nd, f, p = checks.sample_consistency(m, wo, rng.random(n), rng.random((n, 2)), lam)
    assert nd.sum() > n // 10 or (name in DELTA_ONLY and s.valid.sum() > n // 2 and not f.any())
    assert not s.terminated.any()
    # pdf has one value per element: the same for any wavelengths
    np.testing.assert_array_equal(p, m.pdf(wo, s.wi, wavelengths=LAM4))


@pytest.mark.parametrize("name", sorted(MODELS))
def test_albedo_bounds(name):
    m = MODELS[name]()
    wo = np.stack([[np.sin(t), 0.0, np.cos(t)] for t in np.radians([5.0, 45.0, 80.0])])
    a = m.albedo(wo, n_samples=4096, seed=3, mode=IMP, wavelengths=LAM4)
    assert a.shape == (3, 4) and np.all(a >= 0)
    if m.energy_conserving:   # NormalizedFresnel: 1 up to pbrt-v4's FresnelMoment1 fit and the MC error
        assert np.all(a <= 1 + (5e-3 if name.startswith("NormalizedFresnel") else 1e-9))


def test_normalized_fresnel_furnace_per_wavelength():
    """Importance mode, wo above: albedo 1 at every wavelength of BK7's eta(lambda), up to
    pbrt-v4's FresnelMoment1 fit (the RGB contract's tolerance) and the Monte Carlo error."""
    m = MODELS["NormalizedFresnel-BK7"]()
    wo = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    a = m.albedo(wo, n_samples=200_000, seed=2, mode=IMP, wavelengths=LAM4)
    np.testing.assert_allclose(a, 1.0, atol=5e-3)


R_ROT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@pytest.mark.parametrize("name, z", [("Plastic-rough", 0.6), ("Filament-coat-sheen", 0.5),
                                     ("CoatedConductor-analytic", 0.8)])
def test_chi2_spectral(name, z):
    """Mitsuba's chi^2 harness (suite's llvm_ad_rgb) on the spectral sampler (random wavelengths per
    sample) against the spectral pdf."""
    m = MODELS[name]()
    s_ = np.sqrt(1 - z * z)
    wo = np.array([s_ * np.cos(0.7), s_ * np.sin(0.7), z])
    rng = np.random.default_rng(11)

    def sample_fn(uc, u):
        r = m.sample(wo, uc, u, wavelengths=_lam(rng, len(uc)))
        return r.wi @ R_ROT.T, r.valid & ((r.flags & bk.BxDFFlags.Specular) == 0)

    def pdf_fn(v):
        return m.pdf(wo, v @ R_ROT, wavelengths=LAM4)

    passed, p, msg = ref.chi2_test(sample_fn, pdf_fn, res=101, ires=32, sample_count=300_000, seed=3,
                                   significance=0.01, test_count=3)
    assert passed, msg


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", ["Plastic-rough", "Plastic-smooth", "Filament-coat-sheen", "CoatedConductor-analytic",
                                  "NormalizedFresnel-BK7"])
def test_thread_count_and_position_bit_identity(name, dtype, rng):
    m = MODELS[name]()
    n = 20_000
    wo, wi = random_dirs(rng, n).astype(dtype), random_dirs(rng, n).astype(dtype)
    uc, u, lam = rng.random(n).astype(dtype), rng.random((n, 2)).astype(dtype), _lam(rng, n)

    def run(sl=slice(None)):
        s = m.sample(wo[sl], uc[sl], u[sl], wavelengths=lam[sl])
        return [m.eval(wo[sl], wi[sl], wavelengths=lam[sl]), m.pdf(wo[sl], wi[sl], wavelengths=lam[sl]),
                s.wi, s.f, s.pdf, s.valid, s.flags, m.albedo(wo[sl][:5], n_samples=3000, wavelengths=lam[sl][:5])]

    bk.set_num_threads(1)
    one = run()
    assert one[0].dtype == dtype and one[3].shape == (n, 4) and np.isfinite(one[0]).all()
    for t in (2, 3):
        bk.set_num_threads(t)
        for a, b in zip(one, run()):
            np.testing.assert_array_equal(a, b)
    for k in (1, 8191):
        for a, b in zip(one[:7], run(slice(k, None))[:7]):
            np.testing.assert_array_equal(a[k:], b)


def test_extremes(rng):
    n = 500
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    ends = np.array([[360.0, 830.0, 360.0, 830.0]])
    for name, make in MODELS.items():
        m = make()
        f = m.eval(wo, wi, wavelengths=ends)
        s = m.sample(wo, rng.random(n), rng.random((n, 2)), wavelengths=ends)
        assert np.isfinite(f).all() and np.isfinite(s.f).all() and np.isfinite(s.pdf).all(), name
    # spectra 0 and 1 everywhere
    black = bk.Plastic(bk.Spectrum.constant(0.0), alpha=0.2, specular_reflectance=bk.Spectrum.constant(0.0))
    assert np.all(black.eval(wo, wi, wavelengths=LAM4) == 0)
    assert not black.sample(wo, rng.random(n), rng.random((n, 2)), wavelengths=LAM4).valid.any()
    white = bk.CoatedDiffuse(bk.Spectrum.constant(1.0), thickness=0.0, method="analytic")
    a = white.albedo(np.array([[0.0, 0.0, 1.0]]), n_samples=4096, mode=IMP, wavelengths=LAM4)
    np.testing.assert_allclose(a, np.repeat(a[:, :1], 4, 1), rtol=1e-12)
    assert 0.99 < a[0, 0] <= 1.0


def test_bad_input_and_models_without_spectral_kernel():
    z = np.array([0.0, 0.0, 1.0])
    for make in MODELS.values():
        m = make()
        for bad in ([359.0, 400, 500, 600], [400, np.nan, 500, 600]):
            with pytest.raises(ValueError, match="wavelengths"):
                m.eval(z, z, wavelengths=np.array(bad, dtype=float))
            with pytest.raises(ValueError, match="wavelengths"):
                m.sample(z, 0.5, [0.5, 0.5], wavelengths=np.array(bad, dtype=float))
        with pytest.raises(ValueError, match="wavelengths"):
            m.pdf(z, z, wavelengths=[400.0, 500.0, 600.0])
    # spectral parameters are validated, naming the parameter
    with pytest.raises(ValueError, match="reflectance"):
        bk.Plastic(bk.Spectrum([400.0, 700.0], [0.5, 1.2]))
    with pytest.raises(ValueError, match="specular_reflectance"):
        bk.Plastic(0.5, specular_reflectance=bk.Spectrum([400.0, 700.0], [0.5, -0.2]))
    with pytest.raises(ValueError, match="base_color"):
        bk.FilamentStandard(bk.Spectrum([400.0, 700.0], [0.5, 1.5]))
    with pytest.raises(ValueError, match="eta"):
        bk.NormalizedFresnel(bk.Spectrum([400.0, 700.0], [1.5, 0.0]))
    with pytest.raises(ValueError, match="conductor_k"):
        bk.CoatedConductor(1.0, bk.Spectrum([400.0, 700.0], [1.0, -1.0]), method="analytic")
    # (a model without a spectral kernel says so, naming wavelengths: since session 7 the only one
    # is an RGB tensor file of Measured, tested in test_spectral_measured.py)


def test_spectral_parameters_in_rgb_mode_and_value_semantics():
    """RGB mode projects a spectrum (linear sRGB under D65 for reflectances); the models keep value
    semantics with spectral parameters."""
    import pickle
    m = bk.Plastic(R_SPEC, alpha=0.2)
    g = bk.Plastic(list(R_SPEC.to_rgb("reflectance", "D65")), alpha=0.2)
    wo, wi = np.array([0.3, 0.0, 0.95]), np.array([-0.2, 0.1, 0.97])
    np.testing.assert_allclose(m.eval(wo / np.linalg.norm(wo), wi / np.linalg.norm(wi)),
                               g.eval(wo / np.linalg.norm(wo), wi / np.linalg.norm(wi)), rtol=1e-14)
    for name, make in MODELS.items():
        a = make()
        assert a == make() and hash(a) == hash(make()), name
        assert pickle.loads(pickle.dumps(a)) == a, name
        assert isinstance(a.describe(), str)


# ---- the color="spectral"|"rgb" knob (bsdfkit.tuning) ------------------------------------------

def test_color_weights_are_the_rgb_mode_projection():
    """The knob's integration of a spectral result (D65 white furnace -> linear sRGB) reproduces
    RGB mode's projection of a reflectance spectrum (Spectrum.to_rgb, colour-science CMFs) for a
    spectrum linear between the 5 nm nodes, and to 1e-4 for one with off-grid nodes."""
    from bsdfkit.tuning.errors import color_weights
    lam, W = color_weights()
    assert lam.shape[1] == 4 and lam.min() == 360.0 and lam.max() == 830.0
    white = bk.Spectrum.constant(1.0).to_rgb("reflectance", "D65")
    np.testing.assert_allclose(W.sum(axis=(0, 1)), white, rtol=1e-12)
    on_grid = bk.Spectrum([360.0, 450.0, 600.0, 830.0], [0.1, 0.7, 0.2, 0.9])
    for spec, tol in ((on_grid, 1e-12), (R_SPEC, 1e-4)):
        z = np.array([0.0, 0.0, 1.0])
        rgb = sum(bk.Diffuse(spec).eval(z, z, wavelengths=lam[g]) @ W[g] for g in range(len(lam))) * np.pi
        np.testing.assert_allclose(rgb, spec.to_rgb("reflectance", "D65"), atol=tol)


def test_color_knob_registry_and_errors():
    """The knob exists for models with a non-constant spectrum (not for RGB ones: their knob sets
    are unchanged), is moot without a spectral kernel, and measures what RGB mode costs in
    accuracy: gold at grazing angles is far off (simplify keeps spectral at tol 1e-2), a
    diffuse spectrum is exact up to the 5 nm quadrature (simplify picks rgb)."""
    names = lambda m: {k.name: k.reachable for k in bk.knobs(m)}   # noqa: E731
    assert "color" not in names(bk.Conductor.from_metal("Au", alpha=0.3))
    assert names(bk.Conductor.from_metal("Au", alpha=0.3, spectral=True))["color"] is True
    # the stochastic walk has no spectral kernel: moot there, reachable through method=analytic
    cfgs = bk.tuning.configurations(bk.CoatedDiffuse(R_SPEC))
    assert all(c.labels["color"] is None for c in cfgs if c.labels["method"] == "stochastic")
    assert {c.labels["color"] for c in cfgs if c.labels["method"] == "analytic"} == {"spectral", "rgb"}
    assert names(bk.CoatedDiffuse(R_SPEC, method="analytic"))["color"] is True
    gold = bk.Conductor.from_metal("Au", alpha=0.3, spectral=True)
    tab = bk.tradeoff(gold, n=1024, n_albedo=256, measure=False)
    rows = {r["config"]: r for r in tab.to_records()}
    e_rgb = rows["color=rgb"]
    assert e_rgb["p99_err"] > 2e-2 and e_rgb["albedo_err"] > 1e-2
    assert rows["most accurate"]["p99_err"] == 0
    m, rep = bk.simplify(gold, 1e-2, n=1024, n_albedo=256)
    assert rep.config["color"] == "spectral" and any(k == "color" for k, _ in rep.kept)
    d = bk.Diffuse(R_SPEC)
    m, rep = bk.simplify(d, 1e-2, n=1024, n_albedo=256)
    assert rep.config["color"] == "rgb" and ("color", "spectral", "rgb") in [c[:3] for c in rep.changes]
    assert rep.error["p99"] < 1e-3
