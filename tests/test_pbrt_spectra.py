"""from_pbrt and named spectra: one table for every path (issue 50, item 7).

``metal-CuZn-eta`` was refused as "not available" although ``Spectrum.named("metal-CuZn-eta")``
and ``Conductor.from_metal("CuZn")`` worked; ``spectral=True`` keeps named metals and glasses
as spectra (glass-F11 collapsed to eta at 550 nm); spectrum files named in the scene are read.
"""
import numpy as np
import pytest

import bsdfkit as bk

PBRT_METALS = ("Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2")     # pbrt-v4's named metal spectra


@pytest.mark.parametrize("name", PBRT_METALS)
def test_every_pbrt_metal_is_the_named_spectrum(name):
    text = f'Material "conductor" "spectrum eta" "metal-{name}-eta" "spectrum k" "metal-{name}-k" "float roughness" 0.1'
    (rgb,) = bk.from_pbrt(text).values()
    (spec,) = bk.from_pbrt(text, spectral=True).values()
    eta, k = bk.Spectrum.named(f"metal-{name}-eta"), bk.Spectrum.named(f"metal-{name}-k")
    assert spec == bk.Conductor(eta, k, alpha=np.sqrt(0.1))              # the spectra themselves
    # RGB import = the spectral model in RGB mode: the same numbers through either path
    wo = bk.direction(theta=np.radians([10.0, 50.0, 75.0]), phi=0.0)
    wi = bk.direction(theta=np.radians([20.0, 45.0, 70.0]), phi=np.pi)
    np.testing.assert_allclose(rgb.eval(wo, wi), spec.eval(wo, wi), rtol=1e-6)
    # and the spectral model integrates, per wavelength, pbrt's eta / k (spot check at 550 nm)
    lam = np.full((3, 4), 550.0)
    f_spec = spec.eval(wo, wi, wavelengths=lam)[:, 0]
    mono = bk.Conductor(float(eta(550.0)), float(k(550.0)), alpha=np.sqrt(0.1))
    np.testing.assert_allclose(f_spec, mono.eval(wo, wi)[:, 0], rtol=1e-6)


def test_glass_stays_a_dispersive_spectrum_when_asked():
    (g,) = bk.from_pbrt('Material "dielectric" "spectrum eta" "glass-F11"', spectral=True).values()
    assert g == bk.Dielectric(bk.Spectrum.named("glass-F11"))
    (g1,) = bk.from_pbrt('Material "dielectric" "spectrum eta" "glass-F11"').values()
    assert g1.eta == pytest.approx(bk.Spectrum.named("glass-F11")(550.0), rel=1e-12)   # RGB: eta at 550 nm
    # dispersion: a rough interface refracts 450 and 650 nm differently
    rough = bk.Dielectric(g.eta, alpha=0.2)
    wo, wi = bk.direction(theta=0.6, phi=0.0), bk.direction(theta=np.pi - 0.35, phi=np.pi)
    f450 = rough.eval(wo, wi, wavelengths=np.array([450.0, 451, 452, 453]))[0]
    f650 = rough.eval(wo, wi, wavelengths=np.array([650.0, 651, 652, 653]))[0]
    assert abs(f450 / f650 - 1) > 1e-3


def test_spectrum_files_relative_to_the_scene(tmp_path):
    (tmp_path / "spds").mkdir()
    eta = bk.Spectrum.named("metal-Au-eta")
    k = bk.Spectrum.named("metal-Au-k")
    for nm, s in (("Au.eta.spd", eta), ("Au.k.spd", k)):
        rows = "\n".join(f"{a:.6f} {b:.9f}" for a, b in zip(s.wavelengths, s.values))
        (tmp_path / "spds" / nm).write_text("# wavelength value\n" + rows + "\n")
    scene = tmp_path / "scene.pbrt"
    scene.write_text('Material "conductor" "spectrum eta" "spds/Au.eta.spd" "spectrum k" "spds/Au.k.spd"\n')
    (m,) = bk.from_pbrt(scene, spectral=True).values()
    np.testing.assert_allclose(m.eta(np.array([400.0, 550.0, 700.0])), eta(np.array([400.0, 550.0, 700.0])),
                               rtol=1e-6)
    (m_rgb,) = bk.from_pbrt(scene).values()
    assert np.all(np.isfinite(m_rgb.eta)) and m_rgb.eta.shape == (3,)
    with pytest.raises(ValueError, match=r"'spds/Ag.eta.spd' is neither a named spectrum.*no file"):
        bk.from_pbrt('Material "conductor" "spectrum eta" "spds/Ag.eta.spd"')


def test_spectral_must_be_a_bool():
    with pytest.raises(TypeError, match="spectral"):
        bk.from_pbrt('Material "diffuse"', spectral="yes")
