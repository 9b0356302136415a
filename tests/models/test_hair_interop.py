"""Hair and NormalizedFresnel in the registry-facing places: bk.MODELS, the spec parser, from_pbrt
(pbrt-v4 HairMaterial's three sigma_a forms), from_mitsuba / to_mitsuba (Mitsuba 3 ``hair``), the
preview renderer, and the plots."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models.spec import parse_spec
from bsdfkit.testing import mitsuba as mref
from bsdfkit.testing import hair_ref


def test_models_and_specs():
    assert bk.Hair in bk.MODELS and bk.NormalizedFresnel in bk.MODELS
    assert parse_spec("hair") == bk.Hair()
    assert parse_spec("hair beta_m=0.2 h=-0.5") == bk.Hair(beta_m=0.2, h=-0.5)
    assert parse_spec("hair concentration=0.3 pheomelanin=1.5") == bk.Hair.from_concentration(0.3, 1.5)
    assert parse_spec("hair reflectance=0.1,0.5,0.5 beta_n=0.4") == bk.Hair.from_reflectance([0.1, 0.5, 0.5],
                                                                                            beta_n=0.4)
    assert parse_spec("normalized_fresnel eta=1.4") == bk.NormalizedFresnel(1.4)
    for spec in bk.Hair.examples.values():
        assert isinstance(parse_spec(spec), bk.Hair)
    with pytest.raises(ValueError, match="beta_m"):
        parse_spec("hair beta_m=0")


PBRT = '''
MakeNamedMaterial "sig" "string type" "hair" "rgb sigma_a" [0.2 0.3 0.9] "float beta_m" 0.2 "float alpha" 3
MakeNamedMaterial "refl" "string type" "hair" "rgb reflectance" [0.5 0.3 0.0] "float beta_n" 0.5
MakeNamedMaterial "mel" "string type" "hair" "float eumelanin" 0.4 "float pheomelanin" 1.1 "float eta" 1.5
MakeNamedMaterial "default" "string type" "hair" "float beta_m" 0.001
'''


def test_from_pbrt_hair():
    got = bk.from_pbrt(PBRT)
    assert got["sig"] == bk.Hair(sigma_a=[0.2, 0.3, 0.9], beta_m=0.2, alpha=3.0)
    assert got["refl"] == bk.Hair.from_reflectance([0.5, 0.3, 0.0], beta_n=0.5)
    assert got["mel"] == bk.Hair.from_concentration(0.4, 1.1, eta=1.5)
    assert got["default"] == bk.Hair(beta_m=0.01)  # pbrt-v4's material clamps beta to >= 0.01
    with pytest.raises(ValueError, match="roughness"):
        bk.from_pbrt('Material "hair" "float roughness" 0.1')


def test_mitsuba_round_trip_and_plugin():
    m = bk.Hair(sigma_a=[0.2, 0.3, 0.9], eta=1.5, beta_m=0.2, beta_n=0.4, alpha=3.0)
    d = mref.to_mitsuba(m)
    assert d["type"] == "hair"
    assert bk.from_mitsuba(d) == m
    # Mitsuba's pigment defaults: eumelanin 1.3, pheomelanin 0.2 (pbrt-v4: 0); air is 1.000277
    got = bk.from_mitsuba({"type": "hair", "ext_ior": 1.0})
    assert got == bk.Hair.from_concentration(1.3, 0.2)
    got = bk.from_mitsuba({"type": "hair"})
    assert abs(got.eta - 1.55 / 1.000277) < 1e-12
    with pytest.raises(ValueError, match="sigma_a"):
        bk.from_mitsuba({"type": "hair", "sigma_a": 0.5, "eumelanin": 1.0})
    with pytest.raises(NotImplementedError):
        mref.to_mitsuba(bk.NormalizedFresnel(1.3))
    # the dict loads in Mitsuba and its value at one pair matches (frame mapping in hair_ref)
    wo = hair_ref.wo_for_h(m.h, np.array([0.3]))
    wi = np.array([[-0.3, -0.5, np.sqrt(1 - 0.34)]])
    f_mi, _ = hair_ref.mitsuba_eval_pdf(m, wo, wi)
    f_ref = hair_ref.hair_f(m, wo, wi, i0_terms=11)
    assert np.allclose(f_mi, f_ref, rtol=1e-4)


def test_render_preview_hair():
    for m in (bk.Hair(h=0.3), bk.NormalizedFresnel(1.33)):
        img = bk.render.preview(m, width=24, height=24, spp=2, progress=False)
        assert img.shape == (24, 24, 3) and np.all(np.isfinite(img)) and img.mean() > 0


def test_hair_plots(tmp_path):
    import matplotlib
    matplotlib.use("Agg")
    from bsdfkit.plot import hair as plot_hair

    m = bk.Hair.from_concentration(0.8, 0.3, h=0.4, beta_m=0.25)
    fig = plot_hair.hair_lobes(m, theta_o=30, n=181)
    d = fig.bsdfkit_data
    # each longitudinal lobe is a density in theta_i with the cos measure: int Mp cos = 1
    th = np.radians(d["theta_i_deg"])
    integ = np.trapezoid(d["Mp"] * np.cos(th), th, axis=-1)
    assert np.allclose(integ, 1, atol=2e-2), integ
    # azimuthal lobes are densities over [-pi, pi]
    assert np.allclose(np.trapezoid(d["Np"], np.radians(d["phi_deg"]), axis=-1), 1, atol=1e-2)
    fig.savefig(tmp_path / "lobes.png")
    ax = plot_hair.hair_lobe3d(m, theta_o=30, n_theta=19, n_phi=25)
    assert ax.bsdfkit_data["sphere"] and ax.bsdfkit_data["cosine"]
    with pytest.raises(TypeError, match="model"):
        plot_hair.hair_lobes(bk.Diffuse())
    with pytest.raises(ValueError, match="theta_o"):
        plot_hair.hair_lobes(m, theta_o=120)
    with pytest.raises(ValueError, match="h=None"):
        plot_hair.hair_lobes(bk.Hair(h=None))
    ax = plot_hair.hair_lobe3d(bk.Hair(h=None), n_theta=13, n_phi=17)
    assert np.isfinite(np.asarray(ax.bsdfkit_data["radius"][0])).all()
