"""bk.OpenPBR (the OpenPBR v1 contract, /work/wt/_shared/OPENPBR.md) against the independent float64
reference bsdfkit.testing.openpbr_ref, written from the OpenPBR specification, the papers and the
MaterialX pbrlib formulas.

(a) the reference's lobes against the spec's / papers' identities (F82 -> Schlick, Airy limits,
    Gulbrandsen, the sheen LTC's normalisation, the albedo quadrature against Monte Carlo and
    against its own refinement, EON through the composition);
(b) the spec's white-furnace list ("White furnace testing") on bk.OpenPBR(...).albedo with
    compensation="turquin";
(c) bk.OpenPBR(...).eval against the reference on 10,000 direction pairs per parameter set
    (compensation="none"), p99.9 relative error;
(d) the OpenPBR repository's example materials (tests/data/openpbr_examples.json, extracted once
    by scripts/extract_openpbr_examples) as test vectors;
(e) chi^2 of bk.OpenPBR.sample against its pdf.
"""
import functools
import json
from pathlib import Path

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import eon_ref
from bsdfkit.testing import openpbr_ref as ref
from conftest import random_dirs

EXAMPLES = json.loads((Path(__file__).resolve().parents[1] / "data" / "openpbr_examples.json").read_text())


def _dir(z, phi=0.7):
    s = np.sqrt(max(0.0, 1.0 - z * z))
    return np.array([s * np.cos(phi), s * np.sin(phi), z])


@functools.lru_cache(maxsize=None)
def _sphere_rule(n_th=200, n_ph=200):
    """Product Gauss-Legendre nodes (theta, phi) on the upper hemisphere: directions (n, 3), weights (n,)."""
    th, wt = np.polynomial.legendre.leggauss(n_th)
    th = 0.25 * np.pi * (th + 1.0)
    wt = 0.25 * np.pi * wt * np.sin(th)
    ph, wp = np.polynomial.legendre.leggauss(n_ph)
    ph, wp = np.pi * (ph + 1.0), np.pi * wp
    T, P = np.meshgrid(th, ph, indexing="ij")
    d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
    return d, (wt[:, None] * wp[None, :]).ravel()


# =============================================================================== (a) the reference itself

def test_f82_tint_is_schlick_at_white_tint():
    """OpenPBR "Metal": F82-tint reduces to Schlick at specular_color = 1 and equals
    specular_color * Schlick at mu = 1/7."""
    mu = np.linspace(0, 1, 101)[:, None]
    F0 = np.array([0.9, 0.5, 0.04])
    np.testing.assert_allclose(ref.f82_tint(F0, 1.0, mu), ref.schlick(F0, mu), rtol=0, atol=1e-15)
    tint = np.array([0.3, 0.7, 1.0])
    np.testing.assert_allclose(ref.f82_tint(F0, tint, np.full((1, 1), 1 / 7)),
                               tint * ref.schlick(F0, 1 / 7)[None], rtol=1e-13)


def test_fresnel_dielectric_against_polarized_and_hemispherical():
    c = np.linspace(0.0, 1.0, 257)
    for eta in (1.1, 1.5, 2.4):
        rp, rs = ref.fresnel_dielectric_polarized(c, eta)
        np.testing.assert_allclose(ref.fresnel_dielectric(c, eta), 0.5 * (rp + rs), rtol=1e-12, atol=1e-15)
    # from inside: 1 beyond the critical angle, and F(-c, eta) == F(c, 1/eta)
    np.testing.assert_allclose(ref.fresnel_dielectric(-c, 1.5), ref.fresnel_dielectric(c, 1 / 1.5), rtol=1e-14)
    assert ref.fresnel_dielectric(-0.3, 1.5) == 1.0
    # hemispherical albedo of the Fresnel factor: scipy's adaptive quadrature as the independent value
    from scipy.integrate import quad
    for eta in (1.6, 1 / 1.5):
        pts = [np.sqrt(1 - eta * eta)] if eta < 1 else None
        v = 2 * quad(lambda m: float(ref.fresnel_dielectric(m, eta)) * m, 0, 1, points=pts, epsabs=1e-12)[0]
        assert abs(ref.hemispherical_fresnel(eta) - v) < (1e-10 if eta > 1 else 5e-8)   # sqrt kink at TIR


def test_gulbrandsen_normal_incidence():
    """Gulbrandsen 2014: the (n, k) of (r, g) reflect exactly r at normal incidence."""
    r = np.array([0.95, 0.6, 0.2])
    for g in (0.0, 0.5, 1.0):
        n, k = ref.gulbrandsen_nk(r, g)
        np.testing.assert_allclose(((n - 1) ** 2 + k * k) / ((n + 1) ** 2 + k * k), r, rtol=1e-12)


def test_airy_limits():
    """Belcour & Barla 2017: a film index-matched to the outside (n_film = 1) leaves the substrate's
    Fresnel; a film index-matched to the substrate reflects as the bare film interface (the XYZ -> RGB
    matrix's rows sum to 1 within 1e-7)."""
    c = np.linspace(0.02, 1.0, 50)
    for eta in (1.2, 1.5, 2.0):
        F = ref.fresnel_dielectric(c, eta)[:, None]
        np.testing.assert_allclose(ref.fresnel_airy(c, 0.4, 1.0, eta), F * np.ones(3), rtol=0, atol=2e-7)
        Ff = ref.fresnel_dielectric(c, 1.4)[:, None]
        np.testing.assert_allclose(ref.fresnel_airy(c, 0.4, 1.4, 1.4), Ff * np.ones(3), rtol=0, atol=2e-7)
    v = ref.fresnel_airy(c, 0.35, 2.0, 1.5)
    assert np.all((v >= 0) & (v <= 1)) and np.ptp(v[-1]) > 0.05       # coloured (iridescent) at normal incidence
    n, k = ref.gulbrandsen_nk(np.array([0.9, 0.7, 0.4]), np.array([1.0, 0.9, 0.8]))
    vm = ref.fresnel_airy(c, 0.3, 1.5, n, k)
    assert np.all((vm >= 0) & (vm <= 1))


def _airy_spectral(c1, d_um, n2, n3, lam, cmf):
    """First-principles thin-film reflectance: per wavelength the Airy sum of the two interfaces'
    complex amplitude coefficients (s and p averaged), integrated against the CIE 1931 CMFs
    (Y-normalized, illuminant E) and mapped to RGB; n3 may be complex (a conductor)."""
    s1 = np.sqrt(1 - c1 * c1)
    c2, c3 = np.sqrt(1 - (s1 / n2) ** 2 + 0j), np.sqrt(1 - (s1 / n3) ** 2 + 0j)
    amps = (((c1 - n2 * c2) / (c1 + n2 * c2), (n2 * c2 - n3 * c3) / (n2 * c2 + n3 * c3)),
            ((n2 * c1 - c2) / (n2 * c1 + c2), (n3 * c2 - n2 * c3) / (n3 * c2 + n2 * c3)))
    e = np.exp(4j * np.pi * n2 * d_um * 1e3 * c2 / lam)
    R = sum(0.5 * np.abs((r12 + r23 * e) / (1 + r12 * r23 * e)) ** 2 for r12, r23 in amps)
    return np.clip(ref._XYZ_TO_RGB @ ((R[:, None] * cmf).sum(0) / cmf[:, 1].sum()), 0, 1)


def test_airy_against_spectral_thin_film():
    """Belcour & Barla's Fourier-space RGB Airy term against the spectral thin-film reflectance
    integrated with Mitsuba's CIE 1931 tables, both in linear Rec. 709 (bsdfkit's RGB). Measured
    (films 0.05-1 um): <= 0.017 (dielectric substrates) and <= 0.040 (conductors) at cos >= 0.4,
    <= 0.074 / 0.023 at cos 0.15 and 0.05 (the Gaussian fits of the CMFs' spectra are the
    difference; Rec. 709's saturated primaries amplify it over CIE RGB's). The series summed to convergence matters
    there: truncated at MaterialX's 2 orders the soap film (1.33 on 1) is off by up to 0.2."""
    from bsdfkit.testing import mitsuba as mref
    mref.variant()
    import mitsuba as mi
    lam = np.arange(360.0, 831.0, 1.0)
    cmf = np.array([np.ravel(np.array(mi.cie1931_xyz(float(x)), dtype=np.float64)) for x in lam]).reshape(-1, 3)
    for d in (0.05, 0.1, 0.3, 0.5, 1.0):
        for c in (1.0, 0.7, 0.4, 0.15, 0.05):
            tol_d, tol_m = (0.02, 0.045) if c >= 0.4 else (0.08, 0.028)
            for n2, n3 in ((1.33, 1.0001), (2.0, 1.5), (1.4, 1.5)):
                a = ref.fresnel_airy(np.array([c]), d, n2, n3)[0]
                assert np.abs(a - _airy_spectral(c, d, n2, n3, lam, cmf)).max() < tol_d, (d, c, n2, n3)
            for n2, n, k in ((1.4, 0.2, 3.0), (1.5, 1.5, 2.0), (2.0, 2.5, 3.5)):
                a = ref.fresnel_airy(np.array([c]), d, n2, np.full(3, n), np.full(3, k))[0]
                assert np.abs(a - _airy_spectral(c, d, n2, n + 1j * k, lam, cmf)).max() < tol_m, (d, c, n2, n, k)
    # a coloured (Gulbrandsen) metal: channel j against the spectral RGB of the grey metal n_j + i k_j,
    # component j (measured <= 0.012; MaterialX's channel-mixing vec3 form reaches 1.0 vs 0.92 here)
    n, k = ref.gulbrandsen_nk(np.array([0.9, 0.6, 0.3]), np.array([1.0, 0.9, 0.8]))
    for c in (1.0, 0.7, 0.3):
        a = ref.fresnel_airy(np.array([c]), 0.3, 1.5, n, k)[0]
        s = [_airy_spectral(c, 0.3, 1.5, n[j] + 1j * k[j], lam, cmf)[j] for j in range(3)]
        assert np.abs(a - s).max() < 0.015, (c, a, s)


@pytest.mark.parametrize("r", [0.01, 0.2, 0.5, 1.0])
def test_sheen_ltc_integrates_to_one(r):
    """Zeltner 2022: the LTC lobe is a normalized density over the hemisphere (cosine included)."""
    d, w = _sphere_rule(256, 128)
    for mu in (0.05, 0.4, 1.0):
        wo = _dir(mu, 0.3)
        v = ref.zeltner_sheen_ltc(np.broadcast_to(wo, d.shape), d, r)
        assert abs(np.sum(v * w) - 1.0) < 1e-7, (mu, np.sum(v * w))   # measured <= 1e-8
    e = ref.zeltner_sheen_albedo(np.linspace(0, 1, 11), r)
    assert np.all((e > 0) & (e < 1))


@pytest.mark.parametrize("alpha", [1e-3, 0.05, 0.3, 1.0])
def test_ggx_albedo_quadrature(alpha):
    """The half-vector quadrature of the albedo tables against 3x / 2x its nodes (measured <= 5e-7) and
    against an independent Monte Carlo in wi (uniform sphere, 4 sigma), Fresnel at eta 1.5."""
    fr = lambda c: ref.fresnel_dielectric(c, 1.5)[..., None] * np.ones(3)
    mus = np.array([0.003, 0.05, 0.3, 0.7, 1.0])
    e = ref.ggx_albedo(mus, alpha, fr)[:, 0]
    e4 = ref.ggx_albedo(mus, alpha, fr, n_phi=192, n_u=48)[:, 0]
    np.testing.assert_allclose(e, e4, rtol=0, atol=1e-6)
    if alpha >= 0.05:
        rng = np.random.default_rng(7)
        n = 200_000
        wi = random_dirs(rng, n, hemisphere=1)
        for mu, ev in zip(mus[1::2], e[1::2]):
            wo = np.broadcast_to(_dir(mu, 0.0), wi.shape)
            v = ref.microfacet_brdf(wo, wi, alpha, alpha, fr)[:, 0] * wi[:, 2] * 2 * np.pi
            assert abs(v.mean() - ev) < 4 * v.std() / np.sqrt(n) + 1e-12, (mu, v.mean(), ev)
    # the table (cubic spline in sqrt mu) against the direct quadrature
    tab = ref._Table(lambda m: ref.ggx_albedo(m, alpha, fr))
    m = np.concatenate([np.linspace(0.01, 1, 40), np.geomspace(1e-4, 0.01, 10)])
    np.testing.assert_allclose(tab(m), ref.ggx_albedo(m, alpha, fr), rtol=0, atol=1e-4)
    np.testing.assert_allclose(tab(m[:40]), ref.ggx_albedo(m[:40], alpha, fr), rtol=0, atol=1e-5)


def test_walter_btdf_generalized_reciprocity(rng):
    """Radiance-mode BTDF (pbrt-v4 / Walter 2007): f(a, b) = f(b, a) / eta^2 for a above, b below."""
    a = random_dirs(rng, 2000, hemisphere=1)
    b = random_dirs(rng, 2000, hemisphere=-1)
    for eta in (1.5, 1 / 1.33):
        fab = ref.walter_btdf(a, b, eta, 0.3, 0.1)
        fba = ref.walter_btdf(b, a, eta, 0.3, 0.1)
        np.testing.assert_allclose(fab, fba / eta ** 2, rtol=1e-10, atol=1e-12 * fab.max())


@pytest.mark.parametrize("eta, ax, ay", [(1.5, 0.3, 0.1), (1.33, 0.6, 0.6), (1 / 1.5, 0.2, 0.4)])
def test_dielectric_interface_against_mitsuba(eta, ax, ay):
    """The rough dielectric interface (GGX reflection with exact Fresnel + Walter 2007 BTDF in
    radiance transport) against Mitsuba 3's roughdielectric, whose masking is the separable
    G1(wo) G1(wi): the reference times G1 G1 / G2 (its own G functions) must equal Mitsuba's value
    (float32: p99 relative measured ~5e-6); D and G1 themselves against Mitsuba's helpers."""
    from bsdfkit.testing import mitsuba as mref
    rng = np.random.default_rng(21)
    n = 20000
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    f = ref.microfacet_brdf(wo, wi, ax, ay, lambda c: ref.fresnel_dielectric(
        np.where(wo[:, 2] < 0, -c, c), eta)[..., None] * np.ones(3)) + ref.walter_btdf(wo, wi, eta, ax, ay)
    sep = ref.smith_g1(wo, ax, ay) * ref.smith_g1(wi, ax, ay) / ref.smith_g2(wo, wi, ax, ay)
    g, _ = mref.eval_pdf({"type": "roughdielectric", "distribution": "ggx", "alpha_u": ax, "alpha_v": ay,
                          "int_ior": eta, "ext_ior": 1.0}, wo, wi)
    ok = (np.abs(wo[:, 2]) > 1e-2) & (np.abs(wi[:, 2]) > 1e-2)
    fs, g = (f * sep[:, None])[ok, 0], g[ok, 0]
    big = g > 1e-4 * g.max()
    rel = np.abs(fs - g)[big] / g[big]
    print(f"roughdielectric eta={eta:.3g}: p99 rel {np.quantile(rel, 0.99):.3g}, max {rel.max():.3g}")
    assert np.quantile(rel, 0.99) < 3e-5
    assert np.all(np.abs(fs - g)[~big] < 1e-3 * g.max())
    h = random_dirs(rng, 5000, hemisphere=1)
    np.testing.assert_allclose(ref.ggx_d(h, ax, ay), mref.ggx_D(ax, ay, h), rtol=2e-5, atol=0)
    v = random_dirs(rng, 5000, hemisphere=1)
    np.testing.assert_allclose(ref.smith_g1(v, ax, ay), mref.ggx_G1(ax, ay, v, np.array([0.0, 0.0, 1.0])),
                               rtol=2e-5, atol=1e-7)


def test_composition_diffuse_is_eon_without_specular():
    """specular_weight = 0 gives eta' = 1: no specular lobe, E_R = 0, f = EON(base_weight base_color, sigma)."""
    rng = np.random.default_rng(3)
    wo, wi = random_dirs(rng, 3000, 1), random_dirs(rng, 3000, 1)
    p = dict(specular_weight=0.0, base_color=(0.9, 0.5, 0.2), base_weight=0.8, base_diffuse_roughness=0.6)
    np.testing.assert_allclose(ref.eval(p, wo, wi), eon_ref.eval(wo, wi, 0.8 * np.array([0.9, 0.5, 0.2]), 0.6),
                               rtol=1e-12, atol=1e-15)
    for z in (0.2, 0.9):
        np.testing.assert_allclose(ref.albedo(p, _dir(z)), eon_ref.albedo(z, 0.8 * np.array([0.9, 0.5, 0.2]), 0.6),
                                   rtol=0, atol=2e-6)


@pytest.mark.parametrize("extra", [{}, dict(coat_weight=1.0, coat_roughness=0.4, coat_darkening=0.0),
                                   dict(fuzz_weight=1.0, fuzz_roughness=0.4)], ids=["plain", "coat", "fuzz"])
@pytest.mark.parametrize("r", [0.3, 1.0])
def test_reference_albedo_scaling_closes(r, extra):
    """Albedo scaling over a white Lambertian conserves energy by construction, whatever the
    multiple-scattering loss: E_R(quadrature of the lobe) + (1 - E_R(table)) = 1, likewise for the coat
    (darkening off) and the fuzz. Checks the tables against the full-sphere quadrature (<= 2e-4)."""
    p = dict(base_color=(1, 1, 1), specular_roughness=r, **extra)
    for z in (0.15, 0.5, 0.95):
        np.testing.assert_allclose(ref.albedo(p, _dir(z)), 1.0, rtol=0, atol=2e-4)


@pytest.mark.parametrize("p", [dict(base_metalness=1.0, base_color=(1, 1, 1), specular_roughness=1.0),
                               dict(base_metalness=1.0, base_color=(1, 1, 1), specular_roughness=0.4,
                                    coat_weight=1.0, coat_roughness=0.7),
                               dict(base_metalness=0.5, base_color=(1, 1, 1), subsurface_weight=0.5,
                                    subsurface_color=(1, 1, 1), fuzz_weight=1.0, coat_weight=0.5, coat_roughness=0.5,
                                    specular_roughness=0.8)],
                         ids=["metal", "coated_metal", "mix_coat_fuzz"])
def test_reference_turquin_furnace(p):
    """The reference's own Turquin compensation closes the white furnace (isotropic, no thin film, no
    transmission): measured |albedo - 1| < 1e-5."""
    for z in (0.2, 0.95):
        np.testing.assert_allclose(ref.albedo(p, _dir(z), compensation="turquin"), 1.0, rtol=0, atol=1e-4)


def test_reference_turquin_furnace_anisotropic_is_approximate():
    """The contract computes every albedo with the isotropic alpha = r^2 while the lobe is anisotropic
    (alpha_t, alpha_b of the spec's formula, RMS r^2): the compensated anisotropic lobe and the layering
    factors then miss the furnace. Measured on the reference at azimuth 0.7: bare white metal r=0.4,
    a=0.6: -0.2 .. +0.4 %; coated (coat r 0.7, so the base is roughened to 0.84) up to +4 %."""
    p = dict(base_metalness=1.0, base_color=(1, 1, 1), specular_roughness=0.4, specular_roughness_anisotropy=0.6)
    iso = dict(compensation="turquin", aniso_albedo="isotropic")
    dev = [abs(ref.albedo(p, _dir(z), **iso)[0] - 1) for z in (0.2, 0.95)]
    assert 1e-3 < max(dev) < 1e-2
    # the anisotropic lobe's own albedo (the reference's default, bk.OpenPBR's tables) closes it
    dev = [abs(ref.albedo(p, _dir(z), compensation="turquin")[0] - 1) for z in (0.2, 0.95)]
    assert max(dev) < 1e-4
    p.update(coat_weight=1.0, coat_roughness=0.7)
    dev = [abs(ref.albedo(p, _dir(z), **iso)[0] - 1) for z in (0.2, 0.95)]
    assert 1e-2 < max(dev) < 5e-2


# =============================================================================== (b) white furnace (bk.OpenPBR)

WHITE_BASES = {
    "metal": dict(base_metalness=1.0, base_color=(1, 1, 1), specular_color=(1, 1, 1)),
    "diffuse": dict(base_color=(1, 1, 1), base_diffuse_roughness=0.5),
    "subsurface": dict(subsurface_weight=1.0, subsurface_color=(1, 1, 1)),
    "translucent": dict(transmission_weight=1.0, transmission_color=(1, 1, 1)),
    "mix": dict(base_metalness=0.3, transmission_weight=0.3, subsurface_weight=0.5, base_color=(1, 1, 1),
                subsurface_color=(1, 1, 1)),
}
WHITE_LAYERS = {"bare": {}, "coat": dict(coat_weight=1.0, coat_color=(1, 1, 1), coat_ior=1.6),
                "fuzz": dict(fuzz_weight=1.0, fuzz_color=(1, 1, 1), fuzz_roughness=0.5)}
WHITE_MODS = {"none": {}, "film": dict(thin_film_weight=1.0, thin_film_thickness=0.4, thin_film_ior=1.4),
              "aniso": dict(specular_roughness_anisotropy=0.8, coat_roughness_anisotropy=0.5)}
FURNACE = [(b, l, m, r) for b in WHITE_BASES for l in WHITE_LAYERS for m in WHITE_MODS for r in (0.1, 0.5, 1.0)]
FURNACE_TOL = 1e-2
FURNACE_Z = (0.85, 0.3)
#: Monte Carlo samples per roughness: the Turquin-compensated rough metal's sample weights spread
#: (std of one albedo estimate 0.010 at 2^14 samples, r = 1; 4x less at r = 0.5), other bases' and
#: narrow lobes' far less
FURNACE_N = {0.1: 1 << 13, 0.5: 1 << 14, 1.0: 1 << 15}
FURNACE_N_METAL = {0.1: 1 << 13, 0.5: 1 << 15, 1.0: 1 << 17}


@pytest.mark.parametrize("base, layer, mod, r", FURNACE, ids=["-".join(map(str, c)) for c in FURNACE])
def test_white_furnace_turquin(base, layer, mod, r):
    """The spec's white-furnace list: albedo(wo) = 1 with compensation="turquin". The translucent
    base is checked in importance transport (in radiance mode the transmitted part is divided by
    eta'^2, the radiance change across the interface, so the single-interface albedo is not 1)."""
    p = dict(WHITE_BASES[base], **WHITE_LAYERS[layer], **WHITE_MODS[mod], specular_roughness=r)
    if layer == "coat":
        p["coat_roughness"] = r
    m = bk.OpenPBR(**p, compensation="turquin")
    wo = np.stack([_dir(z) for z in FURNACE_Z])
    mode = "importance" if p.get("transmission_weight", 0) > 0 else "radiance"
    n = (FURNACE_N_METAL if WHITE_BASES[base].get("base_metalness", 0) > 0 else FURNACE_N)[r]
    a = m.albedo(wo, n_samples=n, seed=1, mode=mode)
    print(f"furnace {base}-{layer}-{mod}-r{r}: max|a-1| {np.abs(a - 1).max():.4f} min {a.min():.4f} max {a.max():.4f}")
    np.testing.assert_allclose(a, 1.0, rtol=0, atol=FURNACE_TOL)


QFURNACE = [c for c in FURNACE if c[3] >= 0.5 and c[0] in ("metal", "diffuse", "subsurface")]
QFURNACE_TOL = 6e-3


@pytest.mark.parametrize("base, layer, mod, r", QFURNACE, ids=["-".join(map(str, c)) for c in QFURNACE])
def test_white_furnace_turquin_quadrature(base, layer, mod, r):
    """The same furnace list, deterministic: bk.OpenPBR.eval integrated by the reference's sphere
    quadrature (openpbr_ref.sphere_albedo, ~1e-13 for these reflection-only lobes) at 3 incidences down
    to grazing, roughness >= 0.5 (narrower lobes need more nodes). Bases with transmission are left to
    the Monte Carlo test: the rule does not resolve the BTDF's jump along h.z = 0 (errors up to 6e-2 at
    grazing incidence, 96-384 nodes)."""
    p = dict(WHITE_BASES[base], **WHITE_LAYERS[layer], **WHITE_MODS[mod], specular_roughness=r)
    if layer == "coat":
        p["coat_roughness"] = r
    m = bk.OpenPBR(**p, compensation="turquin")
    mode = "importance" if p.get("transmission_weight", 0) > 0 else "radiance"
    eta = ref.derived(ref.normalize_params(p))["eta_p"]
    a = np.array([ref.sphere_albedo(lambda o, i: m.eval(o, i, mode=mode), _dir(z), eta, 96, 96)
                  for z in (0.9, 0.4, 0.08)])
    print(f"qfurnace {base}-{layer}-{mod}-r{r}: max|a-1| {np.abs(a - 1).max():.4f} min {a.min():.4f} max {a.max():.4f}")
    np.testing.assert_allclose(a, 1.0, rtol=0, atol=QFURNACE_TOL)


# =============================================================================== (c) eval against the reference

CROSS = {
    "default": {},
    "rough_diffuse": dict(base_color=(0.7, 0.4, 0.2), base_diffuse_roughness=0.8, specular_roughness=0.6),
    "metal": dict(base_metalness=1.0, base_color=(0.95, 0.64, 0.54), specular_color=(0.9, 0.8, 0.7),
                  specular_roughness=0.35),
    "glass": dict(transmission_weight=1.0, transmission_color=(0.9, 0.95, 1.0), specular_roughness=0.25,
                  specular_ior=1.45),
    "coat": dict(coat_weight=1.0, coat_roughness=0.15, coat_color=(0.8, 0.9, 1.0), base_color=(0.2, 0.3, 0.6),
                 specular_roughness=0.4),
    "fuzz": dict(fuzz_weight=0.8, fuzz_color=(0.9, 0.4, 0.4), fuzz_roughness=0.6, base_color=(0.3, 0.1, 0.1)),
    "thin_film": dict(thin_film_weight=1.0, thin_film_thickness=0.45, thin_film_ior=1.35, base_metalness=0.5,
                      specular_roughness=0.3),
    "anisotropic": dict(base_metalness=1.0, base_color=(0.9, 0.9, 0.9), specular_roughness=0.4,
                        specular_roughness_anisotropy=0.7),
    "thin_walled": dict(geometry_thin_walled=True, transmission_weight=0.4, subsurface_weight=0.5,
                        subsurface_scatter_anisotropy=0.3, subsurface_color=(0.8, 0.7, 0.6), specular_roughness=0.4),
    "everything": dict(base_metalness=0.2, transmission_weight=0.3, subsurface_weight=0.3, coat_weight=0.6,
                       coat_roughness=0.3, coat_color=(0.9, 0.8, 0.7), fuzz_weight=0.4, thin_film_weight=0.5,
                       specular_roughness=0.45, specular_weight=0.8, specular_color=(1.0, 0.9, 0.8),
                       base_diffuse_roughness=0.3, coat_darkening=0.7),
}
#: p99.9 of the relative error (per channel, where the reference exceeds 1e-3 of its maximum).
#: Where no albedo table enters (metal, glass, anisotropic metal with "none") the lobes agree to
#: rounding (<= 2e-14): 1e-12. Elsewhere bk's layering albedos come from its tables (48 cosines x 9
#: azimuths, Gauss-Legendre 24 x 24 over visible normals, within ~4e-3 absolute of the exact
#: albedo, worst near grazing), the reference's from a converged quadrature (~1e-5): measured
#: against bk.OpenPBR (2026-12-05) "none" default 4.8e-3, rough_diffuse 2.6e-3, coat 4.7e-3, fuzz
#: 1.6e-3, thin_film 2.2e-3, thin_walled 4.5e-3, everything 2.4e-3; "turquin" (the E1 table too)
#: metal 4.4e-3, anisotropic 4.0e-3, thin_film 6.2e-3: 8e-3.
CROSS_TOL = {k: 1e-12 if k in ("metal", "glass", "anisotropic") else 8e-3 for k in CROSS}
TURQUIN_TOL = 8e-3
N_PAIRS = 10_000


def _rel_err(f, g):
    g_scale = np.max(np.abs(g))
    mask = np.abs(g) > 1e-3 * g_scale
    rel = np.abs(f - g)[mask] / np.abs(g)[mask]
    absmax = np.max(np.abs(f - g)[~mask]) / g_scale if np.any(~mask) else 0.0
    return rel, absmax


def _pairs(seed, n=N_PAIRS):
    rng = np.random.default_rng(seed)
    return random_dirs(rng, n), random_dirs(rng, n)


@pytest.mark.parametrize("name", list(CROSS))
def test_eval_against_reference(name):
    p = CROSS[name]
    wo, wi = _pairs(11)
    g = ref.eval(p, wo, wi)
    f = bk.OpenPBR(**p, compensation="none").eval(wo, wi)
    rel, absmax = _rel_err(f, g)
    p999 = np.quantile(rel, 0.999)
    print(f"eval {name}: p99.9 rel {p999:.3g}, max rel {rel.max():.3g}, outside-mask max {absmax:.3g}")
    assert p999 < CROSS_TOL[name]
    assert absmax < 1e-3


TURQUIN_SETS = ["default", "rough_diffuse", "metal", "coat", "fuzz", "thin_film", "anisotropic"]


@pytest.mark.parametrize("name", TURQUIN_SETS)
def test_eval_turquin_against_reference(name):
    """compensation="turquin" on the sets without transmission (the reference leaves the
    transmission lobe uncompensated; the contract leaves that choice to the implementation)."""
    p = CROSS[name]
    # the anisotropic lobe's albedo is a direct quadrature per direction in the reference (~9 ms each)
    wo, wi = _pairs(14, 400 if p.get("specular_roughness_anisotropy", 0) > 0 else 3000)
    g = ref.eval(p, wo, wi, compensation="turquin")
    f = bk.OpenPBR(**p, compensation="turquin").eval(wo, wi)
    rel, absmax = _rel_err(f, g)
    p999 = np.quantile(rel, 0.999)
    print(f"eval turquin {name}: p99.9 rel {p999:.3g}, outside-mask {absmax:.3g}")
    assert p999 < TURQUIN_TOL and absmax < 1e-3


@pytest.mark.parametrize("name", ["default", "coat", "thin_walled"])
def test_eval_reciprocal_layering_against_reference(name):
    p = CROSS[name]
    wo, wi = _pairs(12, 3000)
    g = ref.eval(p, wo, wi, layering="reciprocal")
    f = bk.OpenPBR(**p, compensation="none", layering="reciprocal").eval(wo, wi)
    rel, absmax = _rel_err(f, g)
    print(f"eval reciprocal {name}: p99.9 rel {np.quantile(rel, 0.999):.3g}")
    assert np.quantile(rel, 0.999) < CROSS_TOL[name] and absmax < 1e-3


@pytest.mark.parametrize("name", ["default", "metal", "coat", "glass"])
def test_albedo_against_reference_quadrature(name):
    """bk's Monte Carlo albedo (compensation none) against the reference's quadrature (5 sigma)."""
    p = CROSS[name]
    m = bk.OpenPBR(**p, compensation="none")
    for z in (0.9, 0.4):
        a = m.albedo(_dir(z), n_samples=1 << 16, seed=2)
        g = ref.albedo(p, _dir(z))
        assert np.all(np.abs(a - g) < 5e-3), (z, a, g)


# =============================================================================== (d) the spec's example materials

def _modelled(inputs):
    return all(np.allclose(np.asarray(inputs.get(k, v), float), v) for k, v in ref.NOT_MODELLED.items())


EXAMPLE_NAMES = sorted(k for k, v in EXAMPLES.items() if _modelled(v))
EXAMPLE_SUBSET = ["open_pbr_default", "open_pbr_carpaint", "open_pbr_velvet", "open_pbr_soapbubble", "open_pbr_pearl",
                  "open_pbr_aluminum_brushed", "open_pbr_honey_liquid", "open_pbr_skin_iii", "open_pbr_copper",
                  "open_pbr_office_paper", "open_pbr_marble", "open_pbr_blackboard"]


def test_examples_file():
    """The committed test vectors: 83 materials of OpenPBR v1.1.1, 69 within the contract."""
    assert len(EXAMPLES) == 83 and len(EXAMPLE_NAMES) == 69
    assert set(EXAMPLE_SUBSET) <= set(EXAMPLE_NAMES)
    for inputs in EXAMPLES.values():
        assert set(inputs) <= set(ref.DEFAULTS) | set(ref.NOT_MODELLED) | set(ref.IGNORED)


def test_examples_construct():
    """Every example within the contract constructs. The spec's tables give specular_color the range
    [0, 1], but 7 of its own metal examples (brass, cesium, gold, lithium, potassium, rubidium,
    sodium) carry F82 edge tints up to 1.394; the F82-tint formula is defined there too."""
    refused = {}
    for name in EXAMPLE_NAMES:
        try:
            bk.OpenPBR(**EXAMPLES[name])
        except ValueError as e:
            refused[name] = str(e)
    assert not refused, refused


@pytest.mark.parametrize("name", EXAMPLE_SUBSET)
def test_example_material_against_reference(name):
    """The spec's examples against the reference: p99.9 of the relative error 8e-3 where |wo.z| >=
    0.02 (the tables' accuracy, as the cross-check sets), and everywhere 2e-2 of the material's
    largest value. Within ~1 degree of the horizon a nearly smooth lobe's 1 - E is ~0.05 and changes
    fastest, so the tables' ~4e-3 there is up to 10 % of the scaled lobes (measured: marble, coat-less
    r 0: 2.2e-2 relative over all pairs; carpaint, coat r 0.02)."""
    p = {k: v for k, v in EXAMPLES[name].items() if k in ref.DEFAULTS}
    wo, wi = _pairs(13, 3000)
    g = ref.eval(p, wo, wi)
    f = bk.OpenPBR(**EXAMPLES[name], compensation="none").eval(wo, wi)
    away = np.abs(wo[:, 2]) >= 0.02
    rel, absmax = _rel_err(f[away], g[away])
    p999 = np.quantile(rel, 0.999) if rel.size else 0.0
    worst = np.max(np.abs(f - g)) / np.max(np.abs(g))
    print(f"example {name}: p99.9 rel {p999:.3g} (|wo.z| >= 0.02), max |f - g| / max g {worst:.3g}")
    assert p999 < 8e-3 and absmax < 1e-3 and worst < 2e-2


# =============================================================================== (e) sampling: chi^2

CHI2_SETS = {"default": CROSS["default"], "metal_aniso": CROSS["anisotropic"], "glass": CROSS["glass"],
             "layered": dict(coat_weight=0.7, coat_roughness=0.3, fuzz_weight=0.5, thin_film_weight=0.5,
                             subsurface_weight=0.4, base_diffuse_roughness=0.5, specular_roughness=0.5)}
CHI2_CASES = [(k, z) for k in CHI2_SETS for z in (0.999, 0.7, 0.3, 0.05, -0.6)]
# (x, y, z) -> (x, -z, y): the local z axis to the domain's -y axis, off the harness's pole (test_pbrt_chi2.py)
R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


#: the harness integrates the pdf over each bin with ires^2 points: the glass's transmission lobe
#: (alpha 0.0625) needs 16 (at 8 the bin integrals are off enough to fail at 1M samples, p ~ 0)
CHI2_IRES = {"glass": 16}


@pytest.mark.parametrize("name, z", CHI2_CASES, ids=[f"{k}-z{z}" for k, z in CHI2_CASES])
def test_chi2_sampling(name, z):
    from bsdfkit.testing import mitsuba as mref
    model = bk.OpenPBR(**CHI2_SETS[name])
    wo = _dir(z)

    def sample_fn(uc, u):
        s = model.sample(wo, uc, u)
        near_horizon = np.abs(s.wi[:, 2]) < 1e-6   # see test_pbrt_chi2: the harness's float32 edge
        return s.wi @ R.T, s.valid & ~near_horizon

    passed, p, msg = mref.chi2_test(sample_fn, lambda v: model.pdf(wo, v @ R), res=101, ires=CHI2_IRES.get(name, 8),
                                    sample_count=300_000, seed=3, significance=0.01, test_count=len(CHI2_CASES))
    print(f"chi2 OpenPBR {name} z={z}: p = {p:.4g}")
    assert passed, msg
