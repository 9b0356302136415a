"""The Beckmann distribution and the ``sample_visible`` knob of Conductor and Dielectric.

Mitsuba 3 is the reference: its ``roughconductor`` / ``roughdielectric`` default to Beckmann
(eval and pdf for separable masking: tests/test_mitsuba.py, whose CONDUCTORS / DIELECTRICS
lists hold the Beckmann and ``sample_visible=False`` cases). Here: the height-correlated form
against Mitsuba's own Beckmann G1, the samplers by chi-square at five incidences, the
importer's default, export round trips and bad input."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as ref
from conftest import grazing_dirs, random_dirs

# incidence cos theta_o (negative: from below), with an azimuth that is not on an axis
ZS = [0.999, 0.8, 0.4, 0.05, -0.6]


def _chi2_models():
    cu = ([0.2, 0.9, 1.1], [3.9, 2.4, 2.1])
    return [
        ("conductor_a0.05", bk.Conductor(*cu, alpha=0.05, distribution="beckmann"), 101, 32),
        ("conductor_a0.4", bk.Conductor(*cu, alpha=0.4, distribution="beckmann"), 101, 16),
        ("conductor_a1", bk.Conductor(*cu, alpha=1.0, distribution="beckmann"), 101, 16),
        ("conductor_aniso", bk.Conductor(*cu, alpha_x=0.5, alpha_y=0.1, distribution="beckmann"), 101, 16),
        ("conductor_dcos", bk.Conductor(*cu, alpha=0.3, distribution="beckmann", sample_visible=False), 101, 16),
        ("conductor_ggx_dcos", bk.Conductor(*cu, alpha_x=0.2, alpha_y=0.6, sample_visible=False), 101, 16),
        ("dielectric_a0.1", bk.Dielectric(1.5, alpha=0.1, distribution="beckmann"), 101, 32),
        ("dielectric_a0.5", bk.Dielectric(1.5, alpha=0.5, distribution="beckmann"), 101, 16),
        ("dielectric_inv", bk.Dielectric(1 / 1.5, alpha=0.3, distribution="beckmann"), 101, 16),
        ("dielectric_dcos", bk.Dielectric(1.33, alpha=0.3, distribution="beckmann", sample_visible=False), 101, 16),
    ]


CASES = [(name, m, res, ires, z) for name, m, res, ires in _chi2_models() for z in ZS]
# (x, y, z) -> (x, -z, y): lobes off the harness's poles (as tests/models/test_pbrt_chi2.py)
R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@pytest.mark.parametrize("name, model, res, ires, z", CASES, ids=[f"{c[0]}-z{c[4]}" for c in CASES])
def test_chi2_sampling(name, model, res, ires, z):
    s = np.sqrt(1 - z * z)
    wo = np.array([s * np.cos(0.7), s * np.sin(0.7), z])

    def sample_fn(uc, u):
        r = model.sample(wo, uc, u)
        near_horizon = np.abs(r.wi[:, 2]) < 1e-6  # see test_pbrt_chi2.py
        return r.wi @ R.T, r.valid & ~near_horizon

    passed, p, msg = ref.chi2_test(sample_fn, lambda v: model.pdf(wo, v @ R), res=res, ires=ires,
                                   sample_count=1_000_000, seed=5, significance=0.01, test_count=len(CASES))
    print(f"chi2 {name} z={z}: p = {p:.4g}")
    assert passed, msg


@pytest.mark.parametrize("ax, ay", [(0.3, 0.3), (0.05, 0.5), (1.0, 1.0)])
def test_correlated_conductor_from_mitsuba_terms(ax, ay, rng):
    """Height-correlated Beckmann has no Mitsuba plugin: built from Mitsuba's separable
    roughconductor and its Beckmann G1 (Lambda = 1 / G1 - 1, G = 1 / (1 + L_o + L_i))."""
    n = 20000
    wo = grazing_dirs(rng, n, [1.0, 0.7, 0.3, 0.1, 0.03]).astype(np.float32).astype(np.float64)
    wi = random_dirs(rng, n, hemisphere=1).astype(np.float32).astype(np.float64)
    sep = bk.Conductor.from_metal("Cu", alpha_x=ax, alpha_y=ay, masking="separable", distribution="beckmann")
    cor = bk.Conductor.from_metal("Cu", alpha_x=ax, alpha_y=ay, distribution="beckmann")
    f_sep_mi, _ = ref.eval_pdf(sep, wo, wi)
    wm = wo + wi
    wm /= np.linalg.norm(wm, axis=1, keepdims=True)
    g1o = ref.microfacet_G1("beckmann", ax, ay, wo, wm)
    g1i = ref.microfacet_G1("beckmann", ax, ay, wi, wm)
    ok = (g1o > 1e-3) & (g1i > 1e-3) & (f_sep_mi[:, 1] > 1e-6)
    g_cor = 1.0 / (1.0 / g1o[ok] + 1.0 / g1i[ok] - 1.0)
    expect = f_sep_mi[ok] * (g_cor / (g1o[ok] * g1i[ok]))[:, None]
    got = cor.eval(wo[ok], wi[ok])
    err = np.abs(got - expect) / expect
    print(f"correlated Beckmann vs Mitsuba terms: p99.9 {np.quantile(err, 0.999):.3g}, max {err.max():.3g}")
    assert np.quantile(err, 0.999) < 5e-5
    # correlated masking never shadows more than the separable product, up to the fit: Walter's
    # Lambda dips to -5.7e-5 just below a = 1.6 (G1 slightly above 1, in Mitsuba too)
    assert np.all(got >= sep.eval(wo[ok], wi[ok]) * (1 - 2e-4))


def test_distribution_changes_the_material_and_sampling_does_not(rng):
    """Beckmann and GGX differ at the same alpha (a modelling knob); sample_visible changes the
    pdf and the samples but not f."""
    wo = grazing_dirs(rng, 4000, [0.9, 0.5, 0.2])
    wi = random_dirs(rng, 4000, hemisphere=1)
    g = bk.Conductor.from_metal("Au", alpha=0.3)
    b = bk.Conductor.from_metal("Au", alpha=0.3, distribution="beckmann")
    bn = bk.Conductor.from_metal("Au", alpha=0.3, distribution="beckmann", sample_visible=False)
    assert np.max(np.abs(g.eval(wo, wi) - b.eval(wo, wi))) > 0.05
    np.testing.assert_array_equal(b.eval(wo, wi), bn.eval(wo, wi))
    assert not np.allclose(b.pdf(wo, wi), bn.pdf(wo, wi))
    assert b != bn and hash(b) != hash(bn) and b != g
    assert "Beckmann" in b.describe() and "beckmann" in repr(b)


@pytest.mark.parametrize("model_mi", [
    bk.Conductor.from_metal("Cu", alpha=0.3, masking="separable", distribution="beckmann"),
    bk.Dielectric(1.5, alpha=0.3, masking="separable", distribution="beckmann")], ids=repr)
def test_visible_samples_follow_mitsubas_map(model_mi, rng):
    """Beckmann visible normals are drawn by Jakob 2014's inversion as Mitsuba does, so the same
    uniforms give the same direction (up to float32 rounding and Newton-step convergence)."""
    n = 20000
    wo = grazing_dirs(rng, n, [1.0, 0.8, 0.5, 0.2, 0.05]).astype(np.float32).astype(np.float64)
    uc = rng.random(n).astype(np.float32).astype(np.float64)
    u = rng.random((n, 2)).astype(np.float32).astype(np.float64)
    s = model_mi.sample(wo, uc, u)
    r = ref.sample(model_mi, wo, uc, u)
    both = s.valid & r["valid"] & (np.sign(s.wi[:, 2]) == np.sign(r["wi"][:, 2]))
    assert both.mean() > 0.95
    close = np.linalg.norm(s.wi[both] - r["wi"][both], axis=1) < 1e-3
    print(f"same direction (1e-3) on {close.mean():.4%} of {both.sum()} samples")
    assert close.mean() > 0.999


# ------------------------------------------------------------------ interop

def test_mitsuba_default_distribution_is_beckmann(rng):
    """A roughconductor / roughdielectric without 'distribution' is Beckmann, and evaluates as
    Mitsuba's own plugin of that very dict."""
    cases = [({"type": "roughconductor", "material": "Au", "alpha": 0.25}, bk.Conductor),
             ({"type": "roughdielectric", "int_ior": 1.5, "alpha": 0.2, "sample_visible": False}, bk.Dielectric)]
    wo = grazing_dirs(rng, 5000, [0.9, 0.6, 0.3, 0.1]).astype(np.float32).astype(np.float64)
    wi = random_dirs(rng, 5000).astype(np.float32).astype(np.float64)
    for d, cls in cases:
        m = bk.from_mitsuba(d)
        assert isinstance(m, cls) and m.distribution == "beckmann" and m.masking == "separable"
        assert m.sample_visible == d.get("sample_visible", True)
        if cls is bk.Conductor:
            wi = np.abs(wi) * [1, 1, 1]  # Mitsuba's bare roughconductor is one-sided
        f_mi, p_mi = ref.eval_pdf(d, wo, wi)
        f, p = m.eval(wo, wi), m.pdf(wo, wi)
        keep = f_mi[:, 1] > 1e-4 * np.quantile(f_mi[:, 1], 0.99)
        assert np.quantile(np.abs(f[keep] - f_mi[keep]) / f_mi[keep], 0.999) < 5e-4
        # Mitsuba's visible-normal pdf uses Walter's fitted G1(wo), bsdfkit's the exact one (the
        # density its sampler draws): up to 0.31 % apart (tests/test_mitsuba.py::_visible_pdf_ratio)
        keep = p_mi > 1e-4 * np.quantile(p_mi, 0.99)
        tol = 3.5e-3 if m.sample_visible else 5e-4
        assert np.quantile(np.abs(p[keep] - p_mi[keep]) / p_mi[keep], 0.999) < tol
        # the loaded plugin (its to_string; float32 values) carries the same knobs
        loaded = bk.from_mitsuba(ref.load(d))
        assert (loaded.distribution, loaded.sample_visible) == (m.distribution, m.sample_visible)


def test_mitsuba_round_trip():
    for m in (bk.Conductor.from_metal("Cu", alpha_x=0.2, alpha_y=0.4, masking="separable", distribution="beckmann",
                                      sample_visible=False),
              bk.Dielectric(1.33, alpha=0.3, masking="separable", distribution="beckmann"),
              bk.Dielectric(1.5, alpha=0.1, masking="separable", sample_visible=False)):
        d = m.to_mitsuba()
        inner = d.get("bsdf", d)
        assert inner["distribution"] == m.distribution and inner["sample_visible"] == m.sample_visible
        assert bk.from_mitsuba(d) == m


def test_mitsuba_xml_beckmann(tmp_path):
    xml = tmp_path / "s.xml"
    xml.write_text('<scene version="3.0.0"><bsdf type="roughconductor" id="m">'
                   '<string name="material" value="Al"/><float name="alpha" value="0.3"/></bsdf></scene>')
    assert bk.from_mitsuba(str(xml))["m"].distribution == "beckmann"


def test_roughplastic_beckmann_is_refused():
    with pytest.raises(ValueError, match="beckmann.*Plastic"):
        bk.from_mitsuba({"type": "roughplastic", "alpha": 0.2})
    with pytest.raises(ValueError, match="distribution 'phong'"):
        bk.from_mitsuba({"type": "roughconductor", "distribution": "phong"})


# ------------------------------------------------------------------ bad input, per element

def test_bad_input_names_the_parameter():
    with pytest.raises(ValueError, match="distribution"):
        bk.Conductor.from_metal("Cu", alpha=0.2, distribution="phong")
    with pytest.raises(ValueError, match="distribution"):
        bk.Dielectric(1.5, alpha=0.2, distribution=1)
    with pytest.raises(TypeError, match="sample_visible"):
        bk.Dielectric(1.5, alpha=0.2, sample_visible="no")


def test_per_element_alphas_equal_scalar_models(rng):
    """Per-element alphas with the Beckmann knob: each element equals its own uniform model,
    bit for bit (the knob is uniform; lanes differ in alpha, smooth and rough mixed)."""
    alphas = np.array([0.0, 0.05, 0.3, 1.0, 0.0005, 0.2, 0.7, 0.4, 0.9, 0.12, 0.33, 0.6, 0.01, 0.25, 0.8, 0.45, 0.15])
    n = alphas.size
    wo = random_dirs(rng, n, hemisphere=1)
    wi = random_dirs(rng, n, hemisphere=1)
    u, uc = rng.random((n, 2)), rng.random(n)
    for cls, kw in ((bk.Conductor.from_metal, {"name": "Au"}), (bk.Dielectric, {"eta": 1.5})):
        for vis in (True, False):
            m = cls(**kw, alpha=alphas, distribution="beckmann", sample_visible=vis)
            f, p, s = m.eval(wo, wi), m.pdf(wo, wi), m.sample(wo, uc, u)
            for i, a in enumerate(alphas):
                mi_ = cls(**kw, alpha=float(a), distribution="beckmann", sample_visible=vis)
                np.testing.assert_array_equal(f[i], mi_.eval(wo[i], wi[i]))
                np.testing.assert_array_equal(p[i], mi_.pdf(wo[i], wi[i]))
                si = mi_.sample(wo[i], uc[i], u[i])
                np.testing.assert_array_equal(s.wi[i], si.wi)
                np.testing.assert_array_equal(s.pdf[i], si.pdf)
