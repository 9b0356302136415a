"""Filament models against the independent float64 Dr.Jit reference
(bsdfkit.testing.drjit_filament) term by term and as whole models, and the GGX pieces against
Mitsuba 3's MicrofacetDistribution (ggx).

Errors are relative, reported as p99.9 over >= 1e4 direction pairs per parameter set (half of
the wi importance-sampled from the model, so the lobes are covered densely; wo down to
NoV = 1e-3). float64 kernels must agree to 1e-9, float32 kernels to 1e-5 (the reference then
runs on the float32-rounded directions, so only the kernel's own rounding is measured).
Run with ``-s`` to see the error table."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as ref
from conftest import grazing_dirs, random_dirs

ref.variant()  # selects libLLVM before Dr.Jit is imported
from bsdfkit.testing import drjit_filament as dj  # noqa: E402

N = 12_000
ZS = [1.0, 0.8, 0.5, 0.3, 0.1, 0.03, 0.01, 0.003, 0.001]
TOL64, TOL32 = 1e-9, 1e-5

# >= 8 parameter sets covering every lobe and knob
PARAMS = {
    "default": lambda: bk.FilamentStandard(),
    "dielectric_burley": lambda: bk.FilamentStandard([0.8, 0.5, 0.2], roughness=0.35, diffuse="burley"),
    "metal_smooth": lambda: bk.FilamentStandard([0.95, 0.64, 0.54], metallic=1.0, roughness=0.08),
    "metal_rough_nocomp": lambda: bk.FilamentStandard(1.0, metallic=1.0, roughness=0.9, energy_compensation=False),
    "aniso_pos": lambda: bk.FilamentStandard([0.9, 0.6, 0.3], metallic=0.7, roughness=0.6, anisotropy=0.8),
    "aniso_neg_coat": lambda: bk.FilamentStandard(0.5, metallic=1.0, roughness=0.7, anisotropy=-0.8, clear_coat=1.0,
                                                  clear_coat_roughness=0.2),
    "coat_doc_sheen": lambda: bk.FilamentStandard([0.2, 0.4, 0.8], metallic=0.5, roughness=0.3, clear_coat=0.6,
                                                  clear_coat_roughness=0.5, clear_coat_layering="doc",
                                                  sheen_color=[0.3, 0.6, 0.9], sheen_roughness=0.5),
    "sheen_strong_grazing": lambda: bk.FilamentStandard(0.6, roughness=0.4, sheen_color=1.0, sheen_roughness=0.15),
    "lowq": lambda: bk.FilamentStandard(0.4, roughness=0.8, visibility="fast", f90="one", min_roughness="mobile",
                                        reflectance=0.8, clear_coat=0.3, clear_coat_ior_change=False),
    "cloth": lambda: bk.FilamentCloth([0.6, 0.3, 0.2], roughness=0.6),
    "cloth_ss_burley": lambda: bk.FilamentCloth([0.6, 0.3, 0.2], sheen_color=[0.2, 0.4, 0.8],
                                                subsurface_color=[0.5, 0.2, 0.1], roughness=0.3, diffuse="burley"),
}


def _pairs(model, rng):
    wo = grazing_dirs(rng, N, ZS)
    wi = random_dirs(rng, N, 1)
    s = model.sample(wo[: N // 2], rng.random(N // 2), rng.random((N // 2, 2)))
    wi[: N // 2] = np.where(s.valid[:, None], s.wi, wi[: N // 2])
    return wo, wi


def _ref_f(model, wo, wi):
    lut = bk.filament.dfg_lut(model.dfg_lut_size)
    fn = dj.cloth_f if isinstance(model, bk.FilamentCloth) else dj.standard_f
    return fn(model, wo, wi, lut)


def _rel(a, b):
    pos = b[b > 0]
    scale = np.quantile(pos, 0.99) if pos.size else 1.0
    # relative error, with a floor 1e-12 (f64) of the set's typical magnitude for values that vanish
    return np.abs(a - b) / np.maximum(np.abs(b), 1e-12 * scale)


_TABLE = {}


@pytest.mark.parametrize("name", sorted(PARAMS))
def test_model_eval_against_drjit(name, rng):
    m = PARAMS[name]()
    wo, wi = _pairs(m, rng)
    f64, r64 = m.eval(wo, wi), _ref_f(m, wo, wi)
    e64 = _rel(f64, r64)
    wo32, wi32 = wo.astype(np.float32), wi.astype(np.float32)
    f32 = m.eval(wo32, wi32).astype(np.float64)
    r32 = _ref_f(m, wo32.astype(np.float64), wi32.astype(np.float64))
    pos = r32[r32 > 0]
    e32 = np.abs(f32 - r32) / np.maximum(np.abs(r32), 1e-7 * np.quantile(pos, 0.99))
    p64, p32 = np.quantile(e64, 0.999), np.quantile(e32, 0.999)
    _TABLE[name] = (p64, e64.max(), p32, e32.max())
    print(f"{name:20s} f64 p99.9 {p64:.2e} max {e64.max():.2e} | f32 p99.9 {p32:.2e} max {e32.max():.2e}")
    assert np.all((f64 > 0) == (r64 > 0)), "support differs"
    assert p64 <= TOL64
    assert p32 <= TOL32


# ------------------------------------------------------------------ terms

def _u(rng, n, lo=0.0, hi=1.0):
    return rng.uniform(lo, hi, n)


def test_terms_against_drjit(rng):
    """Every C++ term (bk.filament.term, the functions the models call) equals its Dr.Jit
    restatement in float64 to 1e-12 and in float32 to 1e-5 (p99.9) on random arguments."""
    n = 20000
    a = _u(rng, n, 0.002, 1.0)
    at, ab = _u(rng, n, 0.002, 1.0), _u(rng, n, 0.002, 1.0)
    NoV, NoL, LoH = _u(rng, n, 1e-4, 1.0), _u(rng, n, 1e-4, 1.0), _u(rng, n, 0.05, 1.0)
    # (the core's Trowbridge-Reitz D is 0 for NoH < 1e-4, pbrt's cutoff; stay above it)
    h = grazing_dirs(rng, n, rng.uniform(1e-3, 1.0, n))
    NoH = h[:, 2]
    v, l_ = random_dirs(rng, n, 1), random_dirs(rng, n, 1)
    f0, f90 = _u(rng, n), _u(rng, n)
    cases = {
        "D_GGX": ((at, ab, h[:, 0], h[:, 1], h[:, 2]), lambda: dj.D_GGX_Anisotropic(at, ab, h[:, 0], h[:, 1], NoH)),
        "D_Charlie": ((a, NoH), lambda: dj.D_Charlie(a, NoH)),
        "D_Ashikhmin": ((a, NoH), lambda: dj.D_Ashikhmin(a, NoH)),
        "V_SmithGGXCorrelated": ((a, NoV, NoL), lambda: dj.V_SmithGGXCorrelated(a, NoV, NoL)),
        "V_SmithGGXCorrelated_Fast": ((a, NoV, NoL), lambda: dj.V_SmithGGXCorrelated_Fast(a, NoV, NoL)),
        "V_SmithGGXCorrelated_Anisotropic": (
            (at, ab, v[:, 0], v[:, 1], l_[:, 0], l_[:, 1], v[:, 2], l_[:, 2]),
            lambda: dj.V_SmithGGXCorrelated_Anisotropic(at, ab, v[:, 0], v[:, 1], l_[:, 0], l_[:, 1], v[:, 2], l_[:, 2])),
        "V_Kelemen": ((LoH,), lambda: dj.V_Kelemen(LoH)),
        "V_Neubelt": ((NoV, NoL), lambda: dj.V_Neubelt(NoV, NoL)),
        "F_Schlick": ((f0, f90, LoH), lambda: dj.F_Schlick(f0, f90, LoH)),
        "Fd_Lambert": ((a,), lambda: dj.Fd_Lambert(a)),
        "Fd_Burley": ((a, NoV, NoL, LoH), lambda: dj.Fd_Burley(a, NoV, NoL, LoH)),
        "Fd_Wrap": ((2 * NoL - 1, f0), lambda: dj.Fd_Wrap(2 * NoL - 1, f0)),
        "f0ClearCoatToSurface": ((f0,), lambda: dj.f0ClearCoatToSurface(f0)),
    }
    assert set(cases) == set(bk.filament.TERMS)
    for name, (args, reffn) in cases.items():
        r = reffn()
        c64 = bk.filament.term(name, *args)
        e64 = np.abs(c64 - r) / np.maximum(np.abs(r), 1e-300)
        args32 = [np.asarray(x, np.float32) for x in args]
        c32 = bk.filament.term(name, *args32, dtype=np.float32).astype(np.float64)
        r32 = _ref_on(name, [x.astype(np.float64) for x in args32])
        e32 = np.abs(c32 - r32) / np.maximum(np.abs(r32), 1e-30)
        print(f"{name:34s} f64 max {e64.max():.1e}  f32 p99.9 {np.quantile(e32, 0.999):.1e}")
        assert e64.max() < 1e-12, name
        assert np.quantile(e32, 0.999) < 1e-5, name


def _ref_on(name, args):
    """The reference term on the float32-rounded arguments."""
    if name == "D_GGX":
        at, ab, hx, hy, hz = args
        return dj.D_GGX_Anisotropic(at, ab, hx, hy, np.clip(hz, 0, 1))
    if name == "Fd_Lambert":
        return dj.Fd_Lambert(args[0])
    return getattr(dj, name)(*args)


def test_isotropic_d_ggx_forms_agree(rng):
    """Filament's isotropic D_GGX(a, NoH) is the anisotropic form with at = ab (the C++ core uses
    one Trowbridge-Reitz D for both)."""
    h = random_dirs(rng, 5000, 1)
    a = rng.uniform(0.002, 1, 5000)
    np.testing.assert_allclose(dj.D_GGX(a, h[:, 2]), dj.D_GGX_Anisotropic(a, a, h[:, 0], h[:, 1], h[:, 2]), rtol=1e-8)


def test_d_charlie_floor_and_normalisation():
    """D_Charlie without its floor is a normalised NDF (integral of D cos = 1); the shader's floor
    sin^2 >= 2^-7 only adds mass near the normal."""
    t = np.linspace(0, np.pi / 2, 200001)
    for a in (0.05, 0.3, 1.0):
        d = dj.D_Charlie(a, np.cos(t))
        exact = (2 + 1 / a) * np.sin(t) ** (1 / a) / (2 * np.pi)
        integral = np.trapezoid(exact * np.cos(t) * np.sin(t), t) * 2 * np.pi
        assert abs(integral - 1) < 1e-6
        np.testing.assert_allclose(d[np.sin(t) ** 2 >= 2 ** -7], exact[np.sin(t) ** 2 >= 2 ** -7], rtol=1e-12)
        assert np.all(d >= exact * (1 - 1e-12))


# ------------------------------------------------------------------ Mitsuba

@pytest.mark.parametrize("roughness, anisotropy", [(0.3, 0.0), (0.6, 0.8), (0.5, -0.7), (1.0, 0.0), (0.1, 0.0)])
def test_ggx_D_and_vndf_pdf_match_mitsuba(roughness, anisotropy, rng):
    """The base lobe's D and visible-normal density are Mitsuba's MicrofacetDistribution(ggx):
    D via the term API, the pdf via a pure metal (its only lobe)."""
    m = bk.FilamentStandard(1.0, metallic=1.0, roughness=roughness, anisotropy=anisotropy)
    a = roughness ** 2
    at, ab = max(a * (1 + anisotropy), 0.045 ** 2), max(a * (1 - anisotropy), 0.045 ** 2)
    n = 20000
    w = grazing_dirs(rng, n, [1.0, 0.5, 0.2, 0.05, 0.01]).astype(np.float32).astype(np.float64)
    wi = m.sample(w, rng.random(n), rng.random((n, 2))).wi.astype(np.float32).astype(np.float64)
    keep = wi[:, 2] > 1e-3
    wm = w[keep] + wi[keep]
    wm /= np.linalg.norm(wm, axis=1, keepdims=True)
    wm = wm.astype(np.float32).astype(np.float64)
    D = bk.filament.term("D_GGX", at, ab, wm[:, 0], wm[:, 1], wm[:, 2])
    np.testing.assert_allclose(D, ref.ggx_D(at, ab, wm), rtol=5e-5)
    # pdf = D_w(wm) / (4 |w.wm|) for a single GGX lobe
    vndf = m.pdf(w[keep], wi[keep]) * 4 * np.abs(np.sum(w[keep] * wm, 1))
    vndf_mi = ref.ggx_vndf_pdf(at, ab, w[keep], wm)
    err = np.abs(vndf - vndf_mi) / np.maximum(vndf_mi, 1e-5 * np.quantile(vndf_mi, 0.99))
    assert np.quantile(err, 0.999) < 1e-4, np.quantile(err, 0.999)
