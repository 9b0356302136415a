"""Spectral mode (``wavelengths=``) of the measured models and the stochastic coated walk (issue 15).

* Measured (RGL tensor files): a spectral file made through the repo's writer from a tabulated
  conductor, with spectra that vary with wavelength, incidence and sample-space position (the
  RGL files the repo uses are synthetic: bsdfkit.measured.tabulate writes RGB files), against
  Mitsuba 3 ``llvm_ad_spectral``'s ``measured`` plugin on the same file and wavelengths
  (bsdfkit.testing.mitsuba_spectral: one child process for the module), f cos and pdf on
  >= 10,000 pairs; chi^2 of the spectral sampler; wavelengths beyond the file's range clamp.
* MERL (RGB data): f(lambda) = pbrt-v4's RGBUnboundedSpectrum of the RGB value the RGB model
  reads there, against an independent numpy computation (bsdfkit.testing.merl_ref's MERL index
  port, the uplift's coefficients of that RGB value, the sigmoid evaluated with numpy).
* CoatedDiffuse / CoatedConductor, method="stochastic": grey spectra equal the RGB model bit for
  bit (same seed, same path: the walk's channels meet only in Russian roulette's max); coloured
  spectra against the independent photon simulation of the slab (bsdfkit.testing.layered_ref)
  with each wavelength's parameters, by the weighted-histogram / eval-expectation z-test of the
  RGB stochastic models (tests/models/test_layered.py).
* For all: sample / eval consistency, 360 and 830 nm, bit identity for 1/2/3 threads and any
  array position, bad input, the spectral renderer.
"""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models import measured as mm
from bsdfkit.spectral import uplift
from bsdfkit.testing import layered_ref as L
from bsdfkit.testing import mitsuba as ref
from bsdfkit.testing import mitsuba_spectral as ms
from bsdfkit.testing import spectral_checks
from bsdfkit.testing.merl_ref import index_ref, linear_corners
from conftest import random_dirs, random_wavelengths as _lam

LUM = np.array([0.2126, 0.7152, 0.0722])
LAM4 = np.array([380.0, 455.5, 560.25, 700.0])
N = 12_000


def _pairs(rng, n, zmin=0.05):
    def d():
        v = rng.normal(size=(n, 3))
        v[:, 2] = np.abs(v[:, 2]) + zmin
        return v / np.linalg.norm(v, axis=1, keepdims=True)
    return d(), d()


# ---------------------------------------------------------------- spectral RGL files

def _spectral_file(tab, path, wl):
    """A spectral tensor file from a tabulated (RGB) one: spectra = the luminance of its rgb times
    a reflectance peak whose centre moves with the sample-space position (x, y) and whose tilt
    changes with the incidence slice, so f(lambda) is not one spectrum times a scalar field."""
    f = {k: np.array(v) for k, v in tab.fields.items()}
    rgb = f.pop("rgb")                                        # (n_phi, n_theta, 3, N, N)
    lum = np.einsum("c,ptcyx->ptyx", LUM, rgb)
    n = rgb.shape[-1]
    y, x = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="ij")
    lam = wl.astype(np.float64)[:, None, None]
    peak = 0.15 + 0.7 * np.exp(-0.5 * ((lam - (430 + 220 * y + 80 * x)) / 45.0) ** 2)   # (n_lambda, N, N)
    t = np.linspace(0, 1, rgb.shape[1])[None, :, None, None, None]
    tilt = 1 + 0.25 * t * (lam[None, None] - 600) / 240
    f["spectra"] = (lum[:, :, None] * peak[None, None] * tilt).astype(np.float32)
    f["wavelengths"] = wl.astype(np.float32)
    return mm.write_tensor(path, f)


WL_FULL = np.concatenate([np.linspace(360, 700, 18), np.linspace(720, 1000, 8)])   # non-uniform, RGL's span
WL_PART = np.linspace(400, 700, 11)                                                # inside [360, 830]


@pytest.fixture(scope="module")
def spectral_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("tensor_spec")
    srcs = {"iso": bk.Conductor.from_metal("Au", alpha=0.3, masking="separable"),
            "aniso": bk.Conductor([0.2, 0.9, 1.1], [3.9, 2.4, 2.1], alpha_x=0.15, alpha_y=0.45)}
    out = {}
    for name, src in srcs.items():
        tab = bk.measured.tabulate(src, resolution=24, n_theta=6, n_phi=7)
        out[name] = _spectral_file(tab, d / f"{name}_spec.bsdf", WL_FULL)
    out["part"] = _spectral_file(bk.measured.tabulate(srcs["iso"], resolution=16, n_theta=6), d / "part_spec.bsdf",
                                 WL_PART)
    out["rgb"] = bk.measured.tabulate(srcs["iso"], resolution=16, n_theta=6).save(d / "iso_rgb.bsdf")
    return out


@pytest.fixture(scope="module")
def mitsuba_measured(spectral_files):
    rng = np.random.default_rng(15)
    cases = {}
    for name in ("iso", "aniso"):
        wo, wi = _pairs(rng, N)
        lam = _lam(rng, N)
        # Mitsuba sees float32 inputs: compare on the same rounded directions and wavelengths
        wo, wi, lam = (a.astype(np.float32).astype(np.float64) for a in (wo, wi, lam))
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        cases[name] = ({"type": "measured", "filename": str(spectral_files[name])}, wo, wi, lam)
    res = ms.eval_pdf([cases[k] for k in ("iso", "aniso")])
    return {k: (cases[k][1:], r) for k, r in zip(("iso", "aniso"), res)}


@pytest.mark.parametrize("name", ["iso", "aniso"])
def test_measured_vs_mitsuba_spectral(spectral_files, mitsuba_measured, name):
    """f cos and pdf against Mitsuba's spectral ``measured`` on the same file and wavelengths
    (float64 ours, float32 Mitsuba). Tolerance as the RGB comparison (tests/models/test_measured.py):
    both cosines > 0.1: <= 1e-4 relative to the pair's largest value (floored at 1e-3 of the
    maximum); closer to the horizon the float32 reference drifts: 5e-4 at the 99.9th percentile."""
    m = bk.Measured(spectral_files[name])
    assert m.spectral and m.isotropic == (name == "iso")
    (wo, wi, lam), (f_mi, pdf_mi) = mitsuba_measured[name]
    f, pdf = m.eval(wo, wi, wavelengths=lam), m.pdf(wo, wi, wavelengths=lam)
    assert f.shape == (N, 4) and pdf.shape == (N,)
    fc, fc_mi = f * wi[:, 2:3], f_mi * wi[:, 2:3]
    assert np.count_nonzero(fc_mi) > N
    scale = np.maximum(np.abs(fc_mi).max(axis=1, keepdims=True), 1e-3 * np.abs(fc_mi).max())
    err_f = (np.abs(fc - fc_mi) / scale).max(axis=1)
    err_p = np.abs(pdf - pdf_mi) / np.maximum(pdf_mi, 1e-3 * pdf_mi.max())
    core = (wo[:, 2] > 0.1) & (wi[:, 2] > 0.1)
    assert core.sum() >= 10_000
    print(f"Measured {name} spectral vs Mitsuba llvm_ad_spectral: cos > 0.1 ({core.sum()} pairs): f cos max "
          f"{err_f[core].max():.2e} (median {np.median(err_f[core]):.2e}), pdf max {err_p[core].max():.2e}; all "
          f"pairs: f cos p99.9 {np.quantile(err_f, 0.999):.2e} max {err_f.max():.2e}, pdf max {err_p.max():.2e}")
    assert err_f[core].max() <= 1e-4 and err_p[core].max() <= 1e-4
    assert np.quantile(err_f, 0.999) <= 5e-4 and np.quantile(err_p, 0.999) <= 5e-4
    assert err_f.max() < 2e-3 and err_p.max() < 2e-3
    # the wavelengths matter: the 4 values of a pair differ
    assert np.mean(np.ptp(fc, axis=1) > 1e-2 * fc.max(axis=1)) > 0.5


def test_measured_wavelength_interpolation_and_clamp(spectral_files, rng):
    """Linear in wavelength between the file's wavelengths (an exact identity of the tabulated
    values), the end values beyond the file's range (pbrt-v4 and Mitsuba clamp the interpolation
    weight), and pdf / sampled directions independent of the wavelengths (the RGB mode's)."""
    m = bk.Measured(spectral_files["part"])
    n = 3000
    wo, wi = _pairs(rng, n, 0.1)
    lo, hi = WL_PART[3], WL_PART[4]
    t = rng.random(n)
    lam = np.stack([np.full(n, lo), np.full(n, hi), lo + t * (hi - lo), np.full(n, 550.0)], 1)
    f = m.eval(wo, wi, wavelengths=lam)
    np.testing.assert_allclose(f[:, 2], (1 - t) * f[:, 0] + t * f[:, 1], rtol=1e-12, atol=1e-15 * f.max())
    ends = m.eval(wo, wi, wavelengths=np.array([360.0, 400.0, 830.0, 700.0]))
    np.testing.assert_array_equal(ends[:, 0], ends[:, 1])
    np.testing.assert_array_equal(ends[:, 2], ends[:, 3])
    assert np.all(ends[:, 0] != ends[:, 2]) or np.any(ends[:, 0] == 0)
    # pdf: the RGB model's (luminance and VNDF warps), the same for any wavelengths
    np.testing.assert_array_equal(m.pdf(wo, wi, wavelengths=lam), m.pdf(wo, wi))
    u = rng.random((n, 2))
    s, srgb = m.sample(wo, 0.5, u, wavelengths=lam), m.sample(wo, 0.5, u)
    # the same samples: this partial-range file projects to RGB with a negative (out-of-gamut) red
    # channel, which eval reports as 0; sample() used to reject those samples (3 % here) while
    # spectral mode kept them (session 7 fix in measured.h sample_f)
    np.testing.assert_array_equal(s.valid, srgb.valid)
    np.testing.assert_array_equal(s.wi, srgb.wi)
    np.testing.assert_array_equal(s.pdf, srgb.pdf)
    v = srgb.valid
    np.testing.assert_array_equal(srgb.f[v], m.eval(wo[v], srgb.wi[v]))
    assert np.any(srgb.f[v][:, 0] == 0) and np.all(srgb.f[v].max(axis=1) > 0)


def test_measured_rgb_file_has_no_spectra(spectral_files):
    m = bk.Measured(spectral_files["rgb"])
    z = np.array([0.0, 0.0, 1.0])
    with pytest.raises(NotImplementedError, match="wavelengths"):
        m.eval(z, z, wavelengths=LAM4)


@pytest.mark.parametrize("z", [0.9, 0.3])
def test_measured_chi2_spectral_sampler(spectral_files, z):
    """Mitsuba's chi^2 harness (the suite's llvm_ad_rgb process) on the spectral sampler (random
    wavelengths per sample) against the spectral pdf."""
    m = bk.Measured(spectral_files["aniso"])
    s_ = np.sqrt(1 - z * z)
    wo = np.array([s_ * np.cos(0.7), s_ * np.sin(0.7), z])
    rot = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    rng = np.random.default_rng(11)

    def sample_fn(uc, u):
        r = m.sample(wo, uc, u, wavelengths=_lam(rng, len(uc)))
        return r.wi @ rot.T, r.valid

    passed, p, msg = ref.chi2_test(sample_fn, lambda v: m.pdf(wo, v @ rot, wavelengths=LAM4), res=101, ires=16,
                                   sample_count=400_000, seed=3, test_count=2)
    print(f"Measured spectral chi2 z={z}: p = {p:.4g}")
    assert passed, msg


# ---------------------------------------------------------------- MERL

SCALE = np.array([1.0 / 1500, 1.15 / 1500, 1.66 / 1500])


@pytest.fixture(scope="module")
def merl_file(tmp_path_factory):
    rng = np.random.default_rng(7)
    planes = rng.uniform(0, 3000, size=(3, 90, 90, 180))
    planes[rng.random(planes.shape) < 0.02] = -1.0     # not measured
    path = tmp_path_factory.mktemp("merl_spec") / "random.binary"
    with open(path, "wb") as fh:
        fh.write(np.asarray((90, 90, 180), "<i4").tobytes())
        fh.write(np.ascontiguousarray(planes, "<f8").tobytes())
    vals = np.where(planes >= 0, planes * SCALE[:, None, None, None], 0.0)   # (3, 90, 90, 180)
    return str(path), vals


def _uplift_np(rgb, lam):
    """pbrt-v4 RGBUnboundedSpectrum of rgb (n, 3) at lam (n, 4), in numpy: the coefficients of
    rgb / (2 max) from the sRGB table (kept as float32, as the table stores them), the sigmoid
    1/2 + x / (2 sqrt(1 + x^2)) evaluated here."""
    c, scale = uplift.rgb_coefficients(rgb, "unbounded")
    c, scale = c.astype(np.float32).astype(np.float64), scale.astype(np.float32).astype(np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        x = (c[:, 0:1] * lam + c[:, 1:2]) * lam + c[:, 2:3]
        s = 0.5 + 0.5 * x / np.sqrt(1 + x * x)
    s = np.where(np.isinf(x), (x > 0).astype(float), s)
    return scale[:, None] * s


def test_merl_nearest_is_the_uplifted_bin(merl_file, rng):
    path, vals = merl_file
    m = bk.MERL(path)
    n = 20_000
    wo, wi = _pairs(rng, n, 0.02)
    lam = _lam(rng, n)
    ih, idd, ip, *_ = index_ref(wo, wi)
    expect = _uplift_np(vals[:, ih, idd, ip].T, lam)
    got = m.eval(wo, wi, wavelengths=lam)
    # a pair on a bin boundary may round to either side: allow a handful (as the RGB test)
    mismatch = np.any(np.abs(got - expect) > 1e-12 * np.abs(expect) + 1e-15, axis=1)
    print(f"MERL nearest spectral vs numpy uplift: {mismatch.mean():.1e} of pairs on a bin boundary")
    assert mismatch.mean() < 1e-3
    assert np.ptp(got, axis=1).mean() > 1e-2 * got.mean()   # coloured bins: the 4 values differ
    # two-sided by flipping, reflection only
    np.testing.assert_array_equal(m.eval(-wo, -wi, wavelengths=lam), got)
    assert np.all(m.eval(wo, -wi, wavelengths=lam) == 0)


def test_merl_linear_interpolates_the_uplifted_bins(merl_file, rng):
    path, vals = merl_file
    m = bk.MERL(path, interpolation="linear")
    n = 5000
    wo, wi = _pairs(rng, n, 0.02)
    lam = _lam(rng, n)
    _, _, _, th, td, pd = index_ref(wo, wi)
    out = 0
    for (a, b, p), w in linear_corners(th, td, pd):
        out = out + w[:, None] * _uplift_np(vals[:, a, b, p].T, lam)
    np.testing.assert_allclose(m.eval(wo, wi, wavelengths=lam), out, rtol=1e-9, atol=1e-12)


def test_merl_table_memory_pdf_and_sampling(merl_file, rng):
    """The uplifted table: 4 float32 per bin; pdf and the sampled directions are the RGB model's;
    a grey bin uplifts to its exact constant (Jakob & Hanika's closed form)."""
    path, _ = merl_file
    m = bk.MERL(path)
    m.eval([0, 0, 1], [0, 0, 1], wavelengths=LAM4)   # builds the table
    t = mm._merl_spectral_table(m._params["digest"], m._keep[0])
    assert t.nbytes == 90 * 90 * 180 * 4 * 4 == 23_328_000
    n = 4000
    wo, wi = _pairs(rng, n, 0.02)
    lam = _lam(rng, n)
    np.testing.assert_array_equal(m.pdf(wo, wi, wavelengths=lam), m.pdf(wo, wi))
    uc, u = rng.random(n), rng.random((n, 2))
    s, srgb = m.sample(wo, uc, u, wavelengths=lam), m.sample(wo, uc, u)
    # the RGB sampler's directions and pdf (the spectral entry's inlined copy rounds differently in
    # the last bit: measured <= 7e-16 absolute on unit vectors)
    np.testing.assert_array_equal(s.valid, srgb.valid)
    np.testing.assert_allclose(s.wi, srgb.wi, rtol=0, atol=4e-15)
    np.testing.assert_allclose(s.pdf, srgb.pdf, rtol=1e-13, atol=0)
    v = s.valid   # (an invalid sample carries f = 0 and wi = +z, where eval need not be 0)
    assert v.mean() > 0.9
    np.testing.assert_allclose(s.f[v], m.eval(wo[v], s.wi[v], wavelengths=lam[v]), rtol=1e-12, atol=0)
    grey = mm.merl_uplift_coefficients(np.array([[0.3, 0.3, 0.3], [0.0, 0.0, 0.0]]))
    np.testing.assert_array_equal(grey[:, :3], [[0, 0, 0], [0, 0, -np.inf]])
    np.testing.assert_allclose(grey[:, 3], [0.6, 0.0])


def test_merl_uplift_projects_back_to_rgb():
    """The uplifted spectrum of a bin integrates back to its RGB (D65, linear sRGB) to the
    table's round-trip accuracy (pbrt-v4 uses the table lookup as is)."""
    rgb = np.array([[0.02, 0.05, 0.09], [0.4, 0.2, 0.1], [1.7, 1.9, 2.2]])
    c = mm.merl_uplift_coefficients(rgb)
    lam = np.arange(360.0, 831.0)
    x = (c[:, None, 0].astype(float) * lam + c[:, None, 1]) * lam + c[:, None, 2]
    spec = c[:, None, 3] * (0.5 + 0.5 * x / np.sqrt(1 + x * x))
    back = np.stack([bk.Spectrum(lam, s).to_rgb("unbounded", "D65") for s in spec])
    np.testing.assert_allclose(back, rgb, rtol=5e-3, atol=1e-4)


# ---------------------------------------------------------------- the stochastic coated walk

R_SPEC = bk.Spectrum([360.0, 450.0, 520.0, 600.0, 680.0, 830.0], [0.1, 0.25, 0.7, 0.45, 0.8, 0.6])
A_SPEC = bk.Spectrum([360.0, 500.0, 650.0, 830.0], [0.95, 0.5, 0.8, 0.3])
WO = bk.direction(np.radians(40), 0.3)
LAMS = np.array([430.0, 505.0, 590.0, 660.0])


def test_walk_grey_spectra_equal_the_rgb_model_bit_for_bit(rng):
    """Constant spectra: every wavelength's value is the RGB model's (the same seed and path; the
    channels meet only in Russian roulette's max, which is the same for equal channels)."""
    C = bk.Spectrum.constant
    pairs_ = [
        (bk.CoatedDiffuse(C(0.6), alpha=0.2, thickness=0.3, albedo=C(0.7), g=0.4, max_depth=30, n_samples=2),
         bk.CoatedDiffuse(0.6, alpha=0.2, thickness=0.3, albedo=0.7, g=0.4, max_depth=30, n_samples=2)),
        (bk.CoatedConductor(C(0.4), C(3.1), conductor_alpha=0.25, interface_alpha=0.1, thickness=0.1, albedo=C(0.5)),
         bk.CoatedConductor(0.4, 3.1, conductor_alpha=0.25, interface_alpha=0.1, thickness=0.1, albedo=0.5)),
        (bk.CoatedDiffuse(C(0.3)), bk.CoatedDiffuse(0.3)),   # smooth coat, no medium
    ]
    n = 3000
    for spec, rgb in pairs_:
        wo, wi, lam = random_dirs(rng, n), random_dirs(rng, n), _lam(rng, n)
        f, frgb = spec.eval(wo, wi, wavelengths=lam), rgb.eval(wo, wi)
        assert np.count_nonzero(frgb[:, 0]) > n // 4
        np.testing.assert_array_equal(f, np.repeat(frgb[:, :1], 4, axis=1))
        np.testing.assert_array_equal(spec.pdf(wo, wi, wavelengths=lam), rgb.pdf(wo, wi))
        uc, u = rng.random(n), rng.random((n, 2))
        s, sr = spec.sample(wo, uc, u, wavelengths=lam), rgb.sample(wo, uc, u)
        for a, b in ((s.wi, sr.wi), (s.pdf, sr.pdf), (s.valid, sr.valid), (s.flags, sr.flags),
                     (s.f, np.repeat(sr.f[:, :1], 4, axis=1))):
            np.testing.assert_array_equal(a, b)
        a, ar = spec.albedo(wo[:3], n_samples=2000, wavelengths=LAM4), rgb.albedo(wo[:3], n_samples=2000)
        np.testing.assert_array_equal(a, np.repeat(ar[:, :1], 4, axis=1))


_SLAB = {}


def _slab(name, slab):
    if name not in _SLAB:
        _SLAB[name] = L.simulate(slab, WO, 300_000, seed=11)
    return _SLAB[name]


def _at(s, lam):
    return tuple(float(v) for v in s(np.asarray(lam)))


def test_walk_coloured_eval_matches_slab_per_wavelength(rng):
    """CoatedDiffuse (smooth coat, forward-scattering coloured medium): the eval expectation per
    exit bin and wavelength against the slab simulated with each wavelength's reflectance and
    albedo (4 channels)."""
    m = bk.CoatedDiffuse(R_SPEC, eta=1.5, thickness=0.3, albedo=A_SPEC, g=0.5, max_depth=100, n_samples=4)
    slab = L.Slab(eta=1.5, thickness=0.3, albedo=_at(A_SPEC, LAMS), g=0.5, reflectance=_at(R_SPEC, LAMS))
    ref_ = _slab("diffuse", slab)
    assert ref_["truncated"] < 1e-4 and ref_["mean"].shape[-1] == 4
    mean, var = L.bins_eval(m, WO, 256, rng, wavelengths=LAMS)
    z = L.z_scores(mean, var, ref_)
    L.assert_z(z, "CoatedDiffuse spectral eval")
    # power: the slab of the wavelength-swapped parameters is rejected
    swapped = _slab("diffuse-swapped", L.Slab(eta=1.5, thickness=0.3, albedo=_at(A_SPEC, LAMS[::-1]), g=0.5,
                                              reflectance=_at(R_SPEC, LAMS[::-1])))
    assert np.sqrt(np.mean(L.z_scores(mean, var, swapped) ** 2)) > 3


def test_walk_coloured_sample_matches_slab_per_wavelength():
    """CoatedConductor (gold from its eta / k spectra under a rough coat, a coloured medium):
    the weighted histogram of sample()'s f |cos| / pdf per wavelength against the slab with
    eta(lambda) / 1.5, k(lambda) / 1.5."""
    au_eta, au_k = bk.Spectrum.named("metal-Au-eta"), bk.Spectrum.named("metal-Au-k")
    m = bk.CoatedConductor(au_eta, au_k, conductor_alpha=0.3, interface_eta=1.5, interface_alpha=0.15,
                           thickness=0.2, albedo=A_SPEC, g=-0.3, max_depth=100)
    slab = L.Slab(eta=1.5, alpha=0.15, thickness=0.2, albedo=_at(A_SPEC, LAMS), g=-0.3, base="conductor",
                  cond_eta=tuple(np.array(_at(au_eta, LAMS)) / 1.5), cond_k=tuple(np.array(_at(au_k, LAMS)) / 1.5),
                  cond_alpha=0.3)
    ref_ = _slab("conductor", slab)
    mean, var = L.bins_sample(m, WO, 400_000, 5, wavelengths=LAMS)
    L.assert_z(L.z_scores(mean, var, ref_), "CoatedConductor spectral sample")


# ---------------------------------------------------------------- properties of every new kernel

@pytest.fixture(scope="module")
def models(spectral_files, merl_file):
    return {
        "Measured-iso": bk.Measured(spectral_files["iso"]),
        "Measured-aniso": bk.Measured(spectral_files["aniso"]),
        "MERL-nearest": bk.MERL(merl_file[0]),
        "MERL-linear": bk.MERL(merl_file[0], interpolation="linear"),
        "CoatedDiffuse-walk": bk.CoatedDiffuse(R_SPEC, alpha=0.2, thickness=0.2, albedo=A_SPEC, g=0.3),
        "CoatedConductor-walk": bk.CoatedConductor(bk.Spectrum.named("metal-Cu-eta"), bk.Spectrum.named("metal-Cu-k"),
                                                   conductor_alpha=0.2, interface_alpha=0.05, thickness=0.1),
    }


NAMES = ["Measured-iso", "Measured-aniso", "MERL-nearest", "MERL-linear", "CoatedDiffuse-walk",
         "CoatedConductor-walk"]


@pytest.mark.parametrize("name", NAMES)
def test_sample_eval_consistency_and_extremes(models, name, rng):
    """Valid samples: f and pdf equal eval and pdf at the sampled direction (not for the random
    walk, whose sample pdf is only proportional); invalid ones carry f = pdf = 0, wi = +z; MERL is
    reciprocal per wavelength; wavelengths 360 and 830 nm give finite values; the walk's albedo per
    wavelength in [0, 1.05]."""
    m = models[name]
    n = 4000
    wo, lam = random_dirs(rng, n), _lam(rng, n)
    if "walk" in name:   # a random walk's sample pdf is only proportional: no eval / pdf identity
        s = m.sample(wo, rng.random(n), rng.random((n, 2)), wavelengths=lam)
    else:
        s, *_ = spectral_checks.sample_consistency(m, wo, rng.random(n), rng.random((n, 2)), lam)
    if name == "MERL-linear":   # reciprocal (the phi_d fold; nearest bins may split at a boundary)
        a, _ = spectral_checks.reciprocity(m, wo, random_dirs(rng, n), lam)
        assert np.count_nonzero(a) > n
    assert s.valid.mean() > 0.3
    assert np.all(s.f[~s.valid] == 0) and np.all(s.pdf[~s.valid] == 0) and np.all(s.wi[~s.valid] == [0, 0, 1])
    assert not s.terminated.any()
    ends = np.array([[360.0, 830.0, 360.0, 830.0]])
    wi = random_dirs(rng, n)
    for dtype in (np.float32, np.float64):
        f = m.eval(wo.astype(dtype), wi.astype(dtype), wavelengths=ends)
        se = m.sample(wo.astype(dtype), rng.random(n).astype(dtype), rng.random((n, 2)).astype(dtype),
                      wavelengths=ends)
        assert f.dtype == dtype and np.isfinite(f).all() and np.isfinite(se.f).all() and np.all(f >= 0)
    if name.startswith("Coated"):
        a = m.albedo(np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]]), n_samples=4000, wavelengths=LAM4)
        assert np.all(a >= 0) and np.all(a <= 1.05)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", NAMES)
def test_thread_count_and_position_bit_identity(models, name, dtype, rng):
    m = models[name]
    n = 17_000   # > 2 chunks of batch.h's kChunk (8192)
    wo, wi = random_dirs(rng, n).astype(dtype), random_dirs(rng, n).astype(dtype)
    uc, u, lam = rng.random(n).astype(dtype), rng.random((n, 2)).astype(dtype), _lam(rng, n)

    def run(sl=slice(None)):
        s = m.sample(wo[sl], uc[sl], u[sl], wavelengths=lam[sl])
        return [m.eval(wo[sl], wi[sl], wavelengths=lam[sl]), m.pdf(wo[sl], wi[sl], wavelengths=lam[sl]),
                s.wi, s.f, s.pdf, s.valid, s.flags]

    bk.set_num_threads(1)
    one = run()
    assert one[0].dtype == dtype and one[0].shape == (n, 4)
    for t in (2, 3):
        bk.set_num_threads(t)
        for a, b in zip(one, run()):
            np.testing.assert_array_equal(a, b)
    for k in (1, 8193):
        for a, b in zip(one, run(slice(k, None))):
            np.testing.assert_array_equal(a[k:], b)


@pytest.mark.parametrize("name", NAMES)
def test_bad_wavelengths_name_the_argument(models, name):
    m = models[name]
    z = np.array([0.0, 0.0, 1.0])
    for bad in ([359.9, 400, 500, 600], [400, 500, 600, 830.5], [400, np.nan, 500, 600]):
        for call in (lambda w: m.eval(z, z, wavelengths=w), lambda w: m.pdf(z, z, wavelengths=w),
                     lambda w: m.sample(z, 0.5, [0.5, 0.5], wavelengths=w)):
            with pytest.raises(ValueError, match="wavelengths"):
                call(np.array(bad, dtype=float))
    with pytest.raises(ValueError, match="wavelengths"):
        m.eval(z, z, wavelengths=[400.0, 500.0, 600.0])


def test_spectral_render_of_grey_models_converges_to_rgb(tmp_path):
    """The renderer's spectral path through these kernels (render/spectral_material.h): grey
    versions (a flat-spectrum tensor file, a grey MERL table, a grey coated walk) render like the
    RGB images (block z-test of tests/test_render_spectral.py)."""
    from test_render_spectral import _batches, _block_means, _coloured_environment, _grey_scene
    tab = bk.measured.tabulate(bk.Conductor(1.2, 2.8, alpha=0.3), resolution=16, n_theta=6)
    f = {k: np.array(v) for k, v in tab.fields.items()}
    rgb = f.pop("rgb")
    f["spectra"] = np.repeat(rgb[:, :, :1], 3, axis=2)   # channel 0 (grey source), flat in wavelength
    f["wavelengths"] = np.array([360.0, 600.0, 830.0], np.float32)
    flat = bk.Measured(mm.write_tensor(tmp_path / "flat_spec.bsdf", f))
    merl = bk.MERL(bk.measured.write_merl(tmp_path / "grey.binary", bk.Diffuse(0.5)))
    walk = bk.CoatedDiffuse(0.5, alpha=0.15, albedo=0.5, thickness=0.2)
    sc = _grey_scene(_coloured_environment(), (flat, merl, walk))
    k, spp = 12, 12
    kw = dict(width=24, height=16, max_depth=3)
    a = _block_means(_batches(sc, False, k, spp, **kw), 4)
    b = _block_means(_batches(sc, True, k, spp, **kw), 4)
    d = b.mean(0) - a.mean(0)
    se = np.sqrt(b.var(0, ddof=1) / k + a.var(0, ddof=1) / k)
    z = np.abs(d) / np.sqrt(se ** 2 + (1e-3 * np.abs(a.mean(0))) ** 2)
    print(f"spectral vs RGB render: mean z^2 {np.mean(z ** 2):.2f}, max z {z.max():.2f}")
    assert np.all(np.isfinite(z)) and np.mean(z ** 2) < 1.6 and z.max() < 4.5
