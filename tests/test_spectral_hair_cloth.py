"""Spectral mode of Hair (and its far field) and FilamentCloth (``wavelengths=``; issue 15).

Mitsuba 3 has neither model spectrally, so the references are:
(a) per wavelength, the RGB model rebuilt with that wavelength's parameter values (grey
    channels), float64, for f; the spectral pdf / sample against the numpy hair oracle
    (``bsdfkit.testing.hair_ref``, generic in the channel count) with pbrt-v4's ApPDF average
    over the 4 wavelengths;
(b) the independent float64 references (``hair_ref`` for hair, ``drjit_filament.cloth_f`` for
    cloth) evaluated per wavelength with the parameters from an independent numpy evaluation of the
    uplift (scale * sigmoid(c0 lambda^2 + c1 lambda + c2) from the coefficient table) and of
    pbrt-v4's SigmaAFromConcentration / SigmaAFromReflectance;
(c) spectral-mode properties: furnace and exact sampling weights for sigma_a = 0, sample / eval /
    pdf consistency, chi^2 of the spectral sampler against the spectral pdf, extremes, thread-count
    and array-position bit identity, bad input.
Neither model is reciprocal (pbrt-v4 disables its hair reciprocity test; Filament's cloth is
declared non-reciprocal): the spectral mode inherits that, per wavelength, through (a)."""
from types import SimpleNamespace

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models import _spectral as _sp
from bsdfkit.spectral import uplift
from bsdfkit.testing import drjit_filament as dfil
from bsdfkit.testing import hair_ref
from bsdfkit.testing import mitsuba as mref
from conftest import random_dirs, random_wavelengths as _lam

LAM4 = np.array([380.0, 455.5, 560.25, 700.0])
#: pbrt-v4 HairBxDF::SigmaAFromConcentration's RGB constants (eumelanin, pheomelanin)
EUMELANIN = np.array([0.419, 0.697, 1.37])
PHEOMELANIN = np.array([0.187, 0.4, 1.05])
SIGMA_SPEC = bk.Spectrum([360.0, 450.0, 520.0, 610.0, 700.0, 830.0], [2.1, 1.4, 0.9, 0.55, 0.3, 0.2])
BASE_SPEC = bk.Spectrum([360.0, 430.5, 520.0, 610.0, 700.0, 830.0], [0.05, 0.31, 0.62, 0.40, 0.90, 0.83])
HAIR_KW = dict(eta=1.55, beta_m=0.3, beta_n=0.35, alpha=2.0)


def _sigmoid(x):
    """Jakob & Hanika 2019 eq. 3, written out here (c2 may be +-inf)."""
    with np.errstate(invalid="ignore"):
        s = 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))
    return np.where(np.isinf(x), (x > 0).astype(float), s)


def _uplift_np(rgb, kind, lam):
    """An RGB parameter's spectrum at lam: the coefficients from the (polished) table, the sigmoid
    polynomial evaluated here (pbrt-v4 RGBUnboundedSpectrum: scale 2 max(rgb); albedo: scale 1)."""
    c, scale = uplift.rgb_coefficients(np.asarray(rgb, float), kind, exact=True)
    lam = np.asarray(lam, float)
    return float(scale) * _sigmoid((c[0] * lam + c[1]) * lam + c[2])


def _rel_err(a, b):
    """Largest |a - b| relative to max |b| (the values span decades; near-zero lanes are absolute)."""
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _hair_models():
    return {
        "rgb sigma_a, h 0.3": bk.Hair([0.3, 0.9, 2.2], h=0.3, **HAIR_KW),
        "concentration, h -0.7": bk.Hair.from_concentration(1.1, 0.6, h=-0.7, **HAIR_KW),
        "sampled spectrum, h 0": bk.Hair(SIGMA_SPEC, h=0.0, **HAIR_KW),
        "reflectance spectral, h 0.5": bk.Hair.from_reflectance([0.6, 0.35, 0.2], spectral=True, h=0.5, **HAIR_KW),
        "far field 16 nodes": bk.Hair([0.3, 0.9, 2.2], h=None, nodes=16, **HAIR_KW),
    }


def _sigma_values(m, lam):
    """sigma_a at lam as the kernel reads it (core SpectralParam)."""
    return _sp.spectral_param(m.sigma_a, "unbounded")(np.ascontiguousarray(lam, dtype=np.float64))


# ------------------------------------------------------------------- (a) the grey RGB model per wavelength

@pytest.mark.parametrize("label", list(_hair_models()))
def test_hair_eval_per_wavelength_is_the_grey_rgb_model(label, rng):
    m = _hair_models()[label]
    n = 1500
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    worst = 0.0
    for lam in (LAM4, np.array([360.0, 500.0, 640.0, 830.0]), _lam(rng, 1)[0]):
        f = m.eval(wo, wi, wavelengths=lam)
        assert f.shape == (n, 4) and f.dtype == np.float64
        sig = _sigma_values(m, lam)
        for i in range(4):
            g = bk.Hair(float(sig[i]), **{k: v for k, v in m._params.items() if k != "sigma_a"})
            worst = max(worst, _rel_err(f[:, i], g.eval(wo, wi)[:, 0]))
    print(f"hair {label}: spectral f vs grey RGB model per wavelength, max rel err {worst:.2e}")
    assert worst < 1e-12


@pytest.mark.parametrize("label", ["rgb sigma_a, h 0.3", "sampled spectrum, h 0", "far field 16 nodes"])
def test_hair_pdf_is_the_wavelength_average_appdf(label, rng):
    """pbrt-v4 ApPDF: the lobe weights are A_p averaged over the 4 wavelengths. The numpy oracle
    (generic in the channel count) with the 4 sigma_a values gives that pdf; it differs from every
    single wavelength's (grey RGB) pdf, so the test sees the average."""
    m = _hair_models()[label]
    n = 1200
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    sig = _sigma_values(m, LAM4)
    p = m.pdf(wo, wi, wavelengths=LAM4)
    q = {k: v for k, v in m._params.items() if k != "sigma_a"}
    if m.h is None:
        # the far field's pdf: the same Gauss-Legendre mixture over h of the single-h oracle pdfs
        x, w = np.polynomial.legendre.leggauss(m.nodes)
        wk = w * np.cos(x * np.pi / 2)
        wk /= wk.sum()
        ref = sum(wgt * hair_ref.hair_pdf(dict(q, sigma_a=sig, h=float(np.sin(g * np.pi / 2))), wo, wi)
                  for g, wgt in zip(x, wk))
    else:
        ref = hair_ref.hair_pdf(dict(q, sigma_a=sig), wo, wi)
    err = _rel_err(p, ref)
    print(f"hair {label}: spectral pdf vs oracle (ApPDF averaged over 4 wavelengths): max rel err {err:.2e}")
    assert err < 1e-9
    # not any single wavelength's pdf (the grey RGB models)
    for i in range(4):
        single = bk.Hair(float(sig[i]), **q).pdf(wo, wi)
        assert _rel_err(single, p) > 1e-3
    # a constant spectrum: the RGB pdf exactly (all channels equal)
    c = bk.Hair(bk.Spectrum.constant(0.8), **q)
    np.testing.assert_allclose(c.pdf(wo, wi, wavelengths=LAM4), bk.Hair(0.8, **q).pdf(wo, wi), rtol=1e-12, atol=0)


@pytest.mark.parametrize("label", list(_hair_models()))
def test_hair_sample_agrees_with_eval_and_pdf(label, rng):
    m = _hair_models()[label]
    n = 4000 if m.h is None else 20_000
    wo = random_dirs(rng, n)
    lam = _lam(rng, n)
    s = m.sample(wo, rng.random(n), rng.random((n, 2)), wavelengths=lam)
    assert s.f.shape == (n, 4) and not s.terminated.any()
    v = s.valid
    assert v.mean() > 0.99
    np.testing.assert_allclose(s.pdf[v], m.pdf(wo[v], s.wi[v], wavelengths=lam[v]), rtol=1e-10, atol=0)
    np.testing.assert_allclose(s.f[v], m.eval(wo[v], s.wi[v], wavelengths=lam[v]), rtol=1e-10, atol=1e-300)
    assert np.all(s.f[~v] == 0) and np.all(s.pdf[~v] == 0)


CHI2 = [("rgb sigma_a, h 0.3", 0.5), ("reflectance spectral, h 0.5", -0.4)]


@pytest.mark.parametrize("label, z", CHI2)
def test_hair_chi2_spectral(label, z):
    """Mitsuba's chi^2 harness (the whole sphere, as tests/models/test_hair.py) on the spectral
    sampler against the spectral pdf, at fixed wavelengths (the pdf depends on them)."""
    m = _hair_models()[label]
    r = np.sqrt(1 - z * z)
    wo = np.array([z, r * np.cos(1.1), r * np.sin(1.1)])
    R = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])  # hair x axis -> the domain's z

    def sample_fn(uc, u):
        s = m.sample(wo, uc, u, wavelengths=LAM4)
        return s.wi @ R.T, s.valid

    def pdf_fn(v):
        return m.pdf(wo, v @ R, wavelengths=LAM4)

    passed, p, msg = mref.chi2_test(sample_fn, pdf_fn, res=101, ires=12, sample_count=400_000, seed=4,
                                    significance=0.01, test_count=len(CHI2) + 1)
    print(f"chi2 spectral hair {label} z={z}: p = {p:.4g}")
    assert passed, msg


# ------------------------------------------------------------------- (b) independent references

def test_hair_vs_numpy_oracle_with_independent_uplift(rng):
    """hair_ref (numpy float64, pbrt-v4's formulas) per wavelength quadruple, sigma_a(lambda) from
    the sigmoid polynomial evaluated here: an RGB sigma_a (RGBUnboundedSpectrum), melanin
    concentrations (pbrt-v4's RGB constants, then unbounded), a colour (RGBAlbedoSpectrum then
    SigmaAFromReflectance per wavelength, pbrt-v4 HairMaterial::GetBxDF)."""
    n = 1500
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    bn = HAIR_KW["beta_n"]
    den = 5.969 - 0.215 * bn + 2.532 * bn**2 - 10.73 * bn**3 + 5.574 * bn**4 + 0.245 * bn**5
    cases = {
        "rgb": (bk.Hair([0.3, 0.9, 2.2], h=0.3, **HAIR_KW), lambda l: _uplift_np([0.3, 0.9, 2.2], "unbounded", l)),
        "melanin": (bk.Hair.from_concentration(1.1, 0.6, h=-0.7, **HAIR_KW),
                    lambda l: _uplift_np(1.1 * EUMELANIN + 0.6 * PHEOMELANIN, "unbounded", l)),
        "colour": (bk.Hair.from_reflectance([0.6, 0.35, 0.2], spectral=True, h=0.5, **HAIR_KW),
                   lambda l: (np.log(np.clip(_uplift_np([0.6, 0.35, 0.2], "reflectance", l), 0, 1)) / den) ** 2),
    }
    # whole nm for the colour: its sigma_a is tabulated per nm (exact there, linear between)
    quads = [LAM4, np.array([360.0, 471.0, 589.0, 830.0]), np.array([402.0, 517.0, 655.0, 777.0])]
    for name, (m, sigma) in cases.items():
        worst_f = worst_p = 0.0
        for lam in quads:
            if name == "colour":
                lam = np.round(lam)
            q = dict(m._params, sigma_a=sigma(lam))
            worst_f = max(worst_f, _rel_err(m.eval(wo, wi, wavelengths=lam), hair_ref.hair_f(q, wo, wi)))
            worst_p = max(worst_p, _rel_err(m.pdf(wo, wi, wavelengths=lam), hair_ref.hair_pdf(q, wo, wi)))
        print(f"hair {name} vs numpy oracle + numpy uplift: f {worst_f:.2e}, pdf {worst_p:.2e}")
        assert worst_f < 1e-9 and worst_p < 1e-9
    # the colour's tabulation between whole nm: sigma_a linear in between (measured 5.5e-5 of the formula)
    m, sigma = cases["colour"]
    l = np.linspace(360.0, 830.0, 4701)
    np.testing.assert_allclose(_sigma_values(m, l), sigma(l), rtol=1e-4)


def test_hair_far_field_vs_oracle_quadrature(rng):
    n = 600
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    m = bk.Hair(SIGMA_SPEC, h=None, nodes=16, **HAIR_KW)
    sig = SIGMA_SPEC(LAM4)   # a sampled spectrum: numpy's piecewise-linear interpolation
    ref = hair_ref.far_field_f(SimpleNamespace(_params=dict(m._params, sigma_a=sig)), wo, wi, n=16)
    err = _rel_err(m.eval(wo, wi, wavelengths=LAM4), ref)
    print(f"hair far field vs oracle quadrature: max rel err {err:.2e}")
    assert err < 1e-9


def _cloth_ns(m, lam, channels):
    """A parameter namespace of the cloth at 3 wavelengths (one per RGB channel) for cloth_f."""
    p = m._params

    def at(v):
        if v is None:
            return None
        if isinstance(v, bk.Spectrum):
            return [float(x) for x in v(lam[channels])]
        v = np.asarray(v, float)
        return [float(x) for x in _uplift_np(v, "reflectance", lam[channels])] if np.ptp(v) else [float(v[0])] * 3
    return SimpleNamespace(base_color=at(p["base_color"]), sheen_color=at(p["sheen_color"]),
                           subsurface_color=at(p["subsurface_color"]), roughness=p["roughness"],
                           diffuse=p["diffuse"], min_roughness=p["min_roughness"])


def _cloths():
    return {
        "spectral base, default sheen": bk.FilamentCloth(BASE_SPEC, roughness=0.6),
        "rgb colours, subsurface": bk.FilamentCloth([0.35, 0.02, 0.08], sheen_color=[0.9, 0.4, 0.5],
                                                    subsurface_color=[0.3, 0.05, 0.05], roughness=0.35),
        "spectral sheen, burley": bk.FilamentCloth(0.4, sheen_color=BASE_SPEC, subsurface_color=BASE_SPEC,
                                                   roughness=0.8, diffuse="burley"),
    }


@pytest.mark.parametrize("label", list(_cloths()))
def test_cloth_vs_drjit_reference_and_grey_rgb(label, rng):
    """Dr.Jit float64 cloth_f with the colours at each wavelength (the uplift evaluated here), and
    the RGB model rebuilt with grey colours per wavelength."""
    m = _cloths()[label]
    n = 3000
    wo, wi = random_dirs(rng, n, 1), random_dirs(rng, n, 1)
    lam = np.array([361.0, 472.5, 588.0, 829.0])
    f = m.eval(wo, wi, wavelengths=lam)
    ref = np.concatenate([dfil.cloth_f(_cloth_ns(m, lam, [0, 1, 2]), wo, wi),
                          dfil.cloth_f(_cloth_ns(m, lam, [3, 3, 3]), wo, wi)[:, :1]], axis=1)
    err = _rel_err(f, ref)
    grey = 0.0
    for i in range(4):
        ns = _cloth_ns(m, lam, [i, i, i])
        g = bk.FilamentCloth(ns.base_color[0], sheen_color=None if ns.sheen_color is None else ns.sheen_color[0],
                             subsurface_color=None if ns.subsurface_color is None else ns.subsurface_color[0],
                             roughness=m.roughness, diffuse=m.diffuse)
        grey = max(grey, _rel_err(f[:, i], g.eval(wo, wi)[:, 0]))
    print(f"cloth {label}: vs Dr.Jit reference {err:.2e}, vs grey RGB model {grey:.2e}")
    assert err < 1e-9 and grey < 1e-12
    # the pdf is the RGB projection's (lobe weights on the RGB triple, as Filament defines them)
    rgb = type(m)._from_params({k: (_sp.rgb_of(v, "reflectance") if isinstance(v, bk.Spectrum) else v)
                                for k, v in m._params.items()})
    np.testing.assert_allclose(m.pdf(wo, wi, wavelengths=lam), rgb.pdf(wo, wi), rtol=1e-13, atol=0)
    if any(isinstance(v, bk.Spectrum) for v in m._params.values()):
        assert m != rgb and m.describe().endswith("spectral)")


@pytest.mark.parametrize("label", list(_cloths()))
def test_cloth_sample_agrees_and_chi2(label, rng):
    m = _cloths()[label]
    n = 20_000
    wo = random_dirs(rng, n, 1)
    lam = _lam(rng, n)
    s = m.sample(wo, rng.random(n), rng.random((n, 2)), wavelengths=lam)
    v = s.valid
    assert v.mean() > 0.8   # Charlie directions below the horizon are invalid (0.89 for the velvet, as in RGB)
    np.testing.assert_allclose(s.pdf[v], m.pdf(wo[v], s.wi[v], wavelengths=lam[v]), rtol=1e-12, atol=0)
    np.testing.assert_allclose(s.f[v], m.eval(wo[v], s.wi[v], wavelengths=lam[v]), rtol=1e-12, atol=0)
    wo1 = np.array([np.sin(0.8), 0.0, np.cos(0.8)])
    passed, p, msg = mref.chi2_test(lambda uc, u: ((r := m.sample(wo1, uc, u, wavelengths=LAM4)).wi, r.valid),
                                    lambda w: m.pdf(wo1, w, wavelengths=LAM4), res=101, ires=8,
                                    sample_count=300_000, seed=5, significance=0.01, test_count=3)
    print(f"chi2 spectral cloth {label}: p = {p:.4g}")
    assert passed, msg


# ------------------------------------------------------------------- (c) properties

def test_hair_spectral_furnace_and_exact_weights(rng):
    """sigma_a = 0 at every wavelength (pbrt-v4 Hair.WhiteFurnaceSampled / SamplingWeights in
    spectral mode): every sample's weight f |cos| / pdf is 1 at all 4 wavelengths, and the grid
    integral of f |cos| is the RGB model's furnace value at each."""
    for bm, bn in ((0.2, 0.4), (0.5, 0.8)):
        m = bk.Hair(bk.Spectrum.constant(0.0), beta_m=bm, beta_n=bn, alpha=2.0, h=float(rng.uniform(-1, 1)))
        wo = random_dirs(rng, 1)[0]
        s = m.sample(wo, n=5000, seed=3, wavelengths=_lam(rng, 5000))
        assert s.valid.mean() > 0.999
        w = s.f[s.valid] * np.abs(s.wi[s.valid, 2:3]) / s.pdf[s.valid, None]
        assert np.all(np.abs(w - 1) < 1e-6), (w.min(), w.max())


def test_hair_extremes(rng):
    """lambda at 360 and 830 nm, sigma_a 0 and huge (a black colour: sigma_a capped at 1e4), h = +-1,
    wo along the fibre: finite everywhere, the absorbing fibre keeps its R lobe only."""
    n = 3000
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    wo[:3] = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    lam = np.tile([360.0, 360.0, 830.0, 830.0], (n, 1))
    for m in (bk.Hair(bk.Spectrum.constant(0.0), h=1.0), bk.Hair(bk.Spectrum.constant(1e4), h=-1.0),
              bk.Hair.from_reflectance([0.0, 0.2, 1.0], spectral=True, h=0.999),
              bk.Hair(SIGMA_SPEC, h=None, nodes=4), bk.Hair(bk.Spectrum.constant(1e4), h=None, nodes=4)):
        for dt in (np.float32, np.float64):
            f = m.eval(wo.astype(dt), wi.astype(dt), wavelengths=lam)
            p = m.pdf(wo.astype(dt), wi.astype(dt), wavelengths=lam)
            s = m.sample(wo.astype(dt), rng.random(n).astype(dt), rng.random((n, 2)).astype(dt), wavelengths=lam)
            for a in (f, p, s.f, s.pdf):
                assert np.all(np.isfinite(a)) and np.all(a >= 0)
            assert np.all(np.isfinite(s.wi)) and s.valid.mean() > 0.9
    black = bk.Hair(bk.Spectrum.constant(1e4), h=0.2, beta_m=0.3, beta_n=0.3, alpha=0.0)
    grey_r = bk.Hair(1e4, h=0.2, beta_m=0.3, beta_n=0.3, alpha=0.0)
    assert _rel_err(black.eval(wo, wi, wavelengths=LAM4)[:, 0], grey_r.eval(wo, wi)[:, 0]) < 1e-12


def test_cloth_extremes(rng):
    n = 2000
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    wo[:2], wi[:2] = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]], [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    lam = np.tile([360.0, 830.0, 360.0, 830.0], (n, 1))
    for m in (bk.FilamentCloth(bk.Spectrum.constant(0.0)), bk.FilamentCloth(bk.Spectrum.constant(1.0), roughness=0.0),
              bk.FilamentCloth(BASE_SPEC, sheen_color=0.0, subsurface_color=bk.Spectrum.constant(1.0), roughness=1.0)):
        f, p = m.eval(wo, wi, wavelengths=lam), m.pdf(wo, wi, wavelengths=lam)
        s = m.sample(wo, rng.random(n), rng.random((n, 2)), wavelengths=lam)
        for a in (f, p, s.f, s.pdf, s.wi):
            assert np.all(np.isfinite(a))
        assert np.all(f >= 0) and np.all(f[(wo[:, 2] <= 0) | (wi[:, 2] <= 0)] == 0)


SPECTRAL = {
    "Hair": lambda: bk.Hair([0.3, 0.9, 2.2], h=0.3),
    "Hair far field": lambda: bk.Hair(SIGMA_SPEC, h=None, nodes=4),
    "FilamentCloth": lambda: bk.FilamentCloth(BASE_SPEC, subsurface_color=[0.3, 0.05, 0.05]),
}


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", list(SPECTRAL))
def test_thread_count_and_position_bit_identity(name, dtype, rng):
    m = SPECTRAL[name]()
    n = 20_000   # > 2 chunks of batch.h's kChunk
    wo, wi = random_dirs(rng, n).astype(dtype), random_dirs(rng, n).astype(dtype)
    uc, u, lam = rng.random(n).astype(dtype), rng.random((n, 2)).astype(dtype), _lam(rng, n)

    def run(sl=slice(None)):
        s = m.sample(wo[sl], uc[sl], u[sl], wavelengths=lam[sl])
        return [m.eval(wo[sl], wi[sl], wavelengths=lam[sl]), m.pdf(wo[sl], wi[sl], wavelengths=lam[sl]),
                s.wi, s.f, s.pdf, s.valid, s.flags, m.albedo(wo[sl][:5], n_samples=3000, wavelengths=lam[sl][:5])]

    bk.set_num_threads(1)
    one = run()
    assert one[0].dtype == dtype and one[0].shape == (n, 4)
    for t in (2, 3):
        bk.set_num_threads(t)
        for a, b in zip(one, run()):
            np.testing.assert_array_equal(a, b)
    for k in (1, 8191):
        for a, b in zip(one[:7], run(slice(k, None))[:7]):
            np.testing.assert_array_equal(a[k:], b)


def test_rgb_mode_value_semantics_and_color_knob():
    """RGB mode projects (sigma_a without an illuminant, cloth colours under D65); value semantics
    hold with spectra; the tuning registry's color knob is there and simplify picks a mode."""
    import pickle
    h = bk.Hair(SIGMA_SPEC, h=0.3)
    np.testing.assert_allclose(h._make_core().params["sigma_a"], np.maximum(SIGMA_SPEC.to_rgb("unbounded", None), 0),
                               rtol=1e-12)
    assert pickle.loads(pickle.dumps(h)) == h and eval(repr(h), {"Hair": bk.Hair, "Spectrum": bk.Spectrum}) == h
    assert hash(h) == hash(bk.Hair(SIGMA_SPEC, h=0.3)) and h != bk.Hair(h=0.3)
    assert "spectral" in h.describe()
    c = bk.FilamentCloth(BASE_SPEC, sheen_color=0.5)
    assert pickle.loads(pickle.dumps(c)) == c
    assert np.allclose(c._make_core().params["base_color"], BASE_SPEC.to_rgb("reflectance", "D65"))
    # from_concentration is an RGB sigma_a: spectral mode uplifts it (pbrt-v4)
    assert isinstance(bk.Hair.from_concentration(1.3).sigma_a, np.ndarray)
    # the color knob: present for a non-constant spectrum
    for m in (bk.Hair.from_reflectance([0.6, 0.35, 0.2], spectral=True, h=0.0), c):
        names = [k.name for k in bk.knobs(m)]
        assert "color" in names, names
    m, rep = bk.simplify(bk.FilamentCloth(BASE_SPEC, roughness=0.6), tol=0.5)
    assert rep.config["color"] == "rgb"
    m, rep = bk.simplify(bk.FilamentCloth(BASE_SPEC, roughness=0.6), tol=1e-6)
    assert rep.config["color"] == "spectral"


def test_bad_input():
    z = np.array([0.0, 0.6, 0.8])
    for m in (bk.Hair(h=0.2), bk.Hair(h=None, nodes=2), bk.FilamentCloth()):
        for bad in ([359.9, 400, 500, 600], [400, 500, 600, 830.5], [400, np.nan, 500, 600], [400, np.inf, 5, 6]):
            for call in (lambda w: m.eval(z, z, wavelengths=w), lambda w: m.pdf(z, z, wavelengths=w),
                         lambda w: m.sample(z, 0.5, [0.5, 0.5], wavelengths=w), lambda w: m.albedo(z, wavelengths=w)):
                with pytest.raises(ValueError, match="wavelengths"):
                    call(np.array(bad, dtype=float))
        with pytest.raises(ValueError, match="wavelengths"):
            m.eval(z, z, wavelengths=[400.0, 500.0, 600.0])
    with pytest.raises(ValueError, match="sigma_a"):
        bk.Hair(bk.Spectrum([400.0, 700.0], [0.5, -0.1]))
    with pytest.raises(ValueError, match="color"):
        bk.Hair.from_reflectance(bk.Spectrum([400.0, 700.0], [0.5, 1.2]))
    with pytest.raises(TypeError, match="spectral"):
        bk.Hair.from_reflectance([0.5, 0.4, 0.3], spectral="yes")
    with pytest.raises(ValueError, match="base_color"):
        bk.FilamentCloth(bk.Spectrum([400.0, 700.0], [0.5, 1.5]))
    with pytest.raises(ValueError, match="sheen_color"):
        bk.FilamentCloth(0.5, sheen_color=bk.Spectrum([400.0, 700.0], [-0.5, 0.5]))
    with pytest.raises(ValueError, match="subsurface_color"):
        bk.FilamentCloth(0.5, subsurface_color=bk.Spectrum([400.0, 700.0], [0.5, 1.01]))
