"""Spectral mode of the preview renderer (issue 15): bk.render.preview(..., spectral=True).

References: the RGB renderer (a scene whose materials do not depend on wavelength has the same
expected image in both modes: light transport is linear in the emitted spectrum and the uplift
round-trips the environment's RGB), the white furnace (exactly 1), and bk.sample_wavelengths /
bk.spectrum_to_rgb for the wavelength sampling and the colour conversion."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import render as R


def _batches(scene, mode, k, spp, **kw):
    """k independent renders (seeds 0..k-1) of spp samples: per-pixel means of each batch."""
    return np.stack([R.render(scene, spp=spp, seed=1000 * s + 7, progress=False, spectral=mode, **kw)
                     for s in range(k)]).astype(np.float64)


def _coloured_environment(width=64):
    """Smooth, saturated colours (in gamut) and an orange soft light: every texel's uplift
    round-trips to ~1e-4."""
    d = R._latlong_dirs(width, width // 2)
    base = 0.5 + 0.35 * d[..., [0, 1, 2]]                      # red toward +x, green up, blue toward +z
    spot = np.exp(-8.0 * (1.0 - d @ np.array([-0.6, 0.6, 0.53]) / np.linalg.norm([-0.6, 0.6, 0.53])))
    return (base + 6.0 * spot[..., None] * np.array([1.0, 0.55, 0.2])).astype(np.float32)


def _grey_scene(env, models=None):
    """Materials whose value is the same at every wavelength (greys, constant eta / k), lit by a
    coloured environment: the spectral image's expectation is the RGB image's."""
    a, b, c = models or (bk.Diffuse(0.6), bk.Conductor(eta=(1.4, 1.4, 1.4), k=(3.0, 3.0, 3.0), alpha=0.25),
                         bk.Dielectric(eta=1.5, alpha=0.0))
    sc = R.Scene(environment=env)
    sc.add_sphere(a, center=(-1.1, 1.0, 0.0), radius=1.0)
    sc.add_sphere(b, center=(1.1, 1.0, 0.0), radius=1.0)
    sc.add_sphere(c, center=(0.0, 0.6, 1.6), radius=0.6)
    sc.add_ground()   # grey checkerboard (Diffuse 0.45 / 0.15)
    return sc


#: Grey models of the split-channel spectral kernels (batch_spectral.h), three per scene.
GREY_SPLIT_CHANNEL = {
    "plastic-filament-nf": (bk.Plastic(0.5, alpha=0.2), bk.FilamentStandard(0.6, roughness=0.4, clear_coat=0.5,
                                                                            sheen_color=0.3),
                            bk.NormalizedFresnel(1.4)),
    "coated": (bk.CoatedDiffuse(0.5, alpha=0.15, method="analytic"),
               bk.CoatedConductor((1.4, 1.4, 1.4), (3.0, 3.0, 3.0), conductor_alpha=0.3, interface_alpha=0.1,
                                  method="analytic"),
               bk.Plastic(0.4)),
    # spectral forms the renderer gained from the model list (before, its hand list lacked them)
    "cloth-farfield": (bk.FilamentCloth(0.6, roughness=0.6), bk.Hair(sigma_a=(0.4, 0.4, 0.4), h=None),
                       bk.Diffuse(0.5)),
}


def _block_means(x, b):
    k, h, w, c = x.shape
    return x[:, :h // b * b, :w // b * b].reshape(k, h // b, b, w // b, b, c).mean(axis=(2, 4))


@pytest.mark.parametrize("models", [None] + list(GREY_SPLIT_CHANNEL), ids=["pbrt"] + list(GREY_SPLIT_CHANNEL))
def test_spectral_converges_to_rgb_on_a_non_dispersive_scene(models):
    """z-test per 4x4-pixel block and channel: the difference of the spectral and RGB means over
    16 independent batches each, against its standard error from the batch spread."""
    sc = _grey_scene(_coloured_environment(), GREY_SPLIT_CHANNEL.get(models))
    k, spp = 16, 16
    kw = dict(width=32, height=24, max_depth=4)
    rgb = _block_means(_batches(sc, False, k, spp, **kw), 4)
    spc = _block_means(_batches(sc, True, k, spp, **kw), 4)
    d = spc.mean(0) - rgb.mean(0)
    se = np.sqrt(spc.var(0, ddof=1) / k + rgb.var(0, ddof=1) / k)
    # The uplift's round trip (table lookup, pbrt-v4's rule for textures) is exact to ~1e-3 of
    # the value: allow it on top of the noise.
    z = np.abs(d) / np.sqrt(se ** 2 + (1e-3 * np.abs(rgb.mean(0))) ** 2)
    n = z.size
    assert np.all(np.isfinite(z))
    # t statistics with 2(k-1) = 30 degrees of freedom: E z^2 = 30/28, max over 144 cells < 4.5
    assert np.mean(z ** 2) < 1.5, (np.mean(z ** 2), n)
    assert z.max() < 4.5, (z.max(), np.unravel_index(z.argmax(), z.shape))
    # and the test has power: a 2 % colour error would be seen
    z2 = np.abs(d + 0.02 * rgb.mean(0)) / np.sqrt(se ** 2 + (1e-3 * np.abs(rgb.mean(0))) ** 2)
    assert np.mean(z2 ** 2) > 3.0


@pytest.mark.parametrize("model", [bk.Diffuse(1.0), bk.Dielectric(eta=bk.Spectrum.named("glass-F11")),
                                   bk.ThinDielectric(eta=bk.Spectrum.named("glass-BK7")),
                                   bk.DiffuseTransmission(0.5, 0.5)],
                         ids=["diffuse", "dispersive-glass", "dispersive-thin", "difftrans"])
def test_white_furnace_is_one(model):
    """A lossless object in a uniform white environment is invisible: every pixel's expectation
    is (1, 1, 1). The dispersive glass checks TerminateSecondary's pdf rescaling (a wrong factor
    scales every refracted path by 4 or 1/4)."""
    sc = R.Scene(environment="white")
    sc.add_sphere(model, center=(0.0, 1.0, 0.0), radius=1.0)
    sc.look_at((0.0, 1.0, 3.2), (0.0, 1.0, 0.0), fov=40.0)
    img = _batches(sc, True, 8, 16, width=24, height=24, max_depth=64)
    per = img.reshape(8, -1, 3).mean(1)                 # 8 batch means per channel
    mean, se = per.mean(0), per.std(0, ddof=1) / np.sqrt(8)
    assert np.all(se < 0.01)
    # D65 of unit luminance projects to white within ~1e-4 (the matrix's rounding)
    assert np.all(np.abs(mean - 1.0) < 5 * se + 1e-3), (mean, se)
    centre = img[:, 8:16, 8:16].reshape(8, -1, 3).mean(1)   # only the sphere
    cm, cs = centre.mean(0), centre.std(0, ddof=1) / np.sqrt(8)
    assert np.all(np.abs(cm - 1.0) < 5 * cs + 1e-3), (cm, cs)


def test_dispersion_changes_the_image():
    """The same glass with eta(lambda) = glass-F11 renders like its RGB eta(550 nm) on average but
    shows colour (chromatic aberration) in spectral mode; a constant eta does not."""
    env = R.default_environment("studio", width=64)
    sc_d = R.Scene(environment=env).add_sphere(bk.Dielectric(eta=bk.Spectrum.named("glass-F11")))
    sc_c = R.Scene(environment=env).add_sphere(bk.Dielectric(eta=float(bk.Spectrum.named("glass-F11")(550.0))))
    kw = dict(width=32, height=32, spp=64, max_depth=8, progress=False)
    d = R.render(sc_d, spectral=True, **kw).astype(np.float64)
    c = R.render(sc_c, spectral=True, **kw).astype(np.float64)
    assert np.all(np.isfinite(d)) and np.all(np.isfinite(c))
    assert np.abs(d - c).max() > 0.05


def test_bit_identical_for_any_thread_count():
    sc = _grey_scene("sky")
    sc.objects[2]["material"] = bk.Dielectric(eta=bk.Spectrum.named("glass-BK7"))
    n0 = bk.get_num_threads()
    try:
        bk.set_num_threads(1)
        a = R.render(sc, width=40, height=24, spp=6, progress=False, spectral=True)
        bk.set_num_threads(2)
        b = R.render(sc, width=40, height=24, spp=6, progress=False, spectral=True)
    finally:
        bk.set_num_threads(n0)
    assert np.array_equal(a, b)
    assert np.all(np.isfinite(a)) and a.mean() > 0


def test_directional_light_uplifted():
    """A white diffuse plane lit only by a directional light E (black environment): the
    radiance is E cos / pi in both modes (the uplift of E round-trips)."""
    sc = R.Scene(environment=0.0)
    sc.add_ground(bk.Diffuse(1.0))
    e = np.array([0.9, 0.6, 0.3])
    sc.add_directional_light((0.0, 1.0, 0.0), irradiance=e)
    sc.look_at((0.0, 2.0, 2.0), (0.0, 0.0, 0.0))
    img = R.render(sc, width=16, height=16, spp=64, max_depth=1, progress=False, spectral=True)
    mean = img.reshape(-1, 3).mean(0)
    se = img.reshape(-1, 3).std(0) / np.sqrt(16 * 16)
    assert np.all(np.abs(mean - e / np.pi) < 5 * se + 1e-3 * e), (mean, e / np.pi)


def test_bad_input():
    with pytest.raises(TypeError, match="spectral"):
        R.preview(bk.Diffuse(0.5), width=8, height=8, spp=1, progress=False, spectral="yes")
    # a model without a spectral form for its parameters (a tensor file of RGB data): a clear
    # error naming it (no silent RGB fallback)
    tab = bk.measured.tabulate(bk.Conductor.from_metal("Cu", alpha=0.3), resolution=16)
    with pytest.raises(NotImplementedError, match="Measured"):
        R.preview(tab, width=8, height=8, spp=1, progress=False, spectral=True)
    s = bk._render_ext.load().RenderScene()
    s.add_material(bk.Diffuse(0.5))
    with pytest.raises(ValueError, match="material"):
        s.set_spectral_material(3, object())
    with pytest.raises(TypeError, match="spectral model"):
        s.set_spectral_material(0, object())
    acc = np.zeros((4, 4, 3))
    with pytest.raises(ValueError, match="spectral"):   # tables and lights not set
        s.render_spectral([0, 1, 5], [0, 1, 0], [0, 1, 0], 40.0, 2, 0, 0, 1, acc)


def test_cli_spectral(tmp_path, capsys):
    from bsdfkit.__main__ import main
    from bsdfkit.io import read_image
    exr = tmp_path / "glass.exr"
    assert main(["render", "dielectric eta=1.5", "-o", str(exr), "--width", "16", "--height", "12", "--spp", "2",
                 "--spectral", "-q"]) == 0
    img = read_image(str(exr))
    assert img.shape == (12, 16, 3) and np.all(np.isfinite(img)) and img.mean() > 0
    # every compiled model renders spectrally (the renderer's materials come from the model list)
    assert main(["render", "filament_cloth", "-o", str(tmp_path / "c.png"), "--width", "8", "--height", "8",
                 "--spp", "1", "--spectral", "-q"]) == 0
    capsys.readouterr()
    # a model without a spectral form for its data (a tensor file of RGB): exit status 1 and the
    # reason on stderr
    path = bk.measured.tabulate(bk.Conductor.from_metal("Cu", alpha=0.3), resolution=16).save(tmp_path / "cu.bsdf")
    assert main(["render", f"measured {path}", "-o", str(tmp_path / "m.png"), "--width", "8", "--height", "8",
                 "--spp", "1", "--spectral", "-q"]) == 1
    err = capsys.readouterr().err
    assert "Measured" in err and "no spectral" in err


def test_colours_multiply_per_wavelength():
    """A diffuse sphere of colour rho in a constant environment of colour c, direct light only:
    each visible point reflects rho(lambda) c(lambda) (a convex sphere sees the whole upper
    hemisphere of the environment), so the spectral image is the colour of the product of the two
    uplifted spectra. Reference: that product projected with numpy on the 1 nm CIE grid (pbrt-v4's
    SpectrumToXYZ); it differs from the RGB product rho * c by several per cent."""
    from bsdfkit.spectral import colorimetry
    rho, c = np.array([0.2, 0.7, 0.4]), np.array([0.9, 0.5, 0.2])
    sc = R.Scene(environment=c.tolist())
    sc.add_sphere(bk.Diffuse(rho.tolist()), center=(0.0, 1.0, 0.0), radius=1.0)
    sc.look_at((0.0, 1.0, 2.2), (0.0, 1.0, 0.0), fov=30.0)   # the sphere fills the frame
    img = _batches(sc, True, 8, 32, width=12, height=12, max_depth=1)
    per = img.reshape(8, -1, 3).mean(1)
    mean, se = per.mean(0), per.std(0, ddof=1) / np.sqrt(8)
    lam = np.arange(360.0, 831.0)
    prod = bk.Spectrum.from_rgb(rho, "reflectance")(lam) * bk.Spectrum.from_rgb(c, "illuminant")(lam)
    cmf = colorimetry.cmfs(lam)
    expected = colorimetry.xyz_to_srgb(prod @ cmf / cmf[:, 1].sum())
    assert np.abs(expected - rho * c).max() > 0.01          # spectral and RGB products differ here
    assert np.all(np.abs(mean - expected) < 5 * se + 2e-3 * expected), (mean, expected, se)
    assert np.abs(mean - rho * c).max() > 5 * se.max()      # and the render is the spectral one
