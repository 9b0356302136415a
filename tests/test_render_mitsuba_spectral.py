"""The spectral preview renderer (``render(..., spectral=True)``: hero-wavelength paths, 4
wavelengths each) against Mitsuba 3's `path` integrator in ``llvm_ad_spectral``: the same sphere,
environment, camera and material, both unbiased, so the images differ by noise only.

The materials hold wavelength-dependent parameters given to both renderers as the same spectra
(bsdfkit.testing.mitsuba_scene.spectral_bsdf): a diffuse with a sampled reflectance spectrum, a
rough conductor with Mitsuba's own measured gold (``from_metal("Au", spectral=True)`` carries the
same data) and an anisotropic one with sampled eta / k spectra, and a smooth glass. The
environment is test_render_mitsuba's analytic map made achromatic (its luminance): an achromatic
texel uplifts to a constant spectrum times D65 in both renderers, so the comparison does not
depend on the two RGB-to-spectrum tables (pbrt-v4's and Mitsuba's differ slightly); the colour
comes from the materials' spectra, sampled per wavelength, and the conversion of each path's
4 wavelengths to linear sRGB (CIE 1931 matching functions, D65 white) in both.

Not compared: a dispersive glass (Mitsuba's dielectrics take a scalar int_ior). Mitsuba renders in
a child process (mitsuba_scene.render_spectral): the suite keeps one llvm_ad_rgb variant per
process. Statistics as test_render_mitsuba.py (per-pixel z with 3 x 3 pooled standard errors,
the image mean against its standard error)."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import render as R
from bsdfkit.testing import mitsuba_scene as ms

from test_render_mitsuba import CAMERA, ENV_H, ENV_W, RES, SYS_REL, compare, env_function, latlong

K = 6
SPP = 128           # per seed; K * SPP = 768 spp per renderer
MAX_DEPTH = 8
LUM = np.array([0.2126, 0.7152, 0.0722])


def _grey(env):
    return np.repeat((env @ LUM)[..., None], 3, axis=-1).astype(np.float32)


ENV_OURS = _grey(env_function(latlong((np.arange(ENV_W) + 0.5) / ENV_W, (np.arange(ENV_H) + 0.5) / ENV_H)))
ENV_MI = _grey(env_function(latlong((np.arange(ENV_W) + 0.5) / ENV_W, np.arange(ENV_H) / (ENV_H - 1))))

R_NODES = [360.0, 430.5, 470.0, 520.0, 575.25, 610.0, 680.0, 760.0, 830.0]
R_VALS = [0.05, 0.12, 0.31, 0.62, 0.55, 0.40, 0.71, 0.90, 0.83]
ETA_NODES = [360.0, 410.0, 455.25, 500.0, 560.5, 640.0, 720.0, 830.0]
ETA_VALS = [0.35, 0.42, 0.61, 0.83, 1.05, 1.21, 1.33, 1.40]
K_VALS = [2.10, 2.35, 2.70, 3.05, 3.40, 3.90, 4.40, 4.95]

MATERIALS = {
    "diffuse": lambda: bk.Diffuse(bk.Spectrum(R_NODES, R_VALS)),
    "conductor_au": lambda: bk.Conductor.from_metal("Au", spectral=True, alpha=0.3, masking="separable"),
    "conductor_sampled": lambda: bk.Conductor(bk.Spectrum(ETA_NODES, ETA_VALS), bk.Spectrum(ETA_NODES, K_VALS),
                                              alpha_x=0.4, alpha_y=0.15, masking="separable"),
    "glass": lambda: bk.Dielectric(bk.Spectrum.constant(1.5)),
}


def _scene(model):
    return R.Scene(environment=ENV_OURS).add_sphere(model, center=(0, 0, 0), radius=1.0).look_at(**CAMERA)


@pytest.fixture(scope="module")
def mitsuba_images():
    """Every material's K renders, in one Mitsuba child process."""
    names = sorted(MATERIALS)
    imgs = ms.render_spectral([_scene(MATERIALS[n]()) for n in names], seeds=range(100, 100 + K), width=RES,
                              height=RES, spp=SPP, max_depth=MAX_DEPTH, envmap_bitmap=ENV_MI)
    return dict(zip(names, imgs))


def test_spectral_export():
    """The exported parameters are the models' spectra (end values repeated at 360 / 830 nm), and
    a dispersive glass is refused rather than exported with one IOR."""
    d = ms.spectral_bsdf(MATERIALS["diffuse"]())
    assert d["bsdf"]["reflectance"] == {"type": "spectrum", "value": list(zip(R_NODES, R_VALS))}
    au = ms.spectral_bsdf(MATERIALS["conductor_au"]())["bsdf"]
    eta = bk.Spectrum.named("mitsuba-Au-eta")
    assert au["eta"]["value"][1:-1] == [(float(a), float(b)) for a, b in zip(eta.wavelengths, eta.values)] or \
        au["eta"]["value"] == [(float(a), float(b)) for a, b in zip(eta.wavelengths, eta.values)]
    assert ms.spectral_bsdf(MATERIALS["glass"]())["int_ior"] == 1.5
    with pytest.raises(NotImplementedError, match="int_ior"):
        ms.spectral_bsdf(bk.Dielectric(bk.Spectrum.named("glass-F11")))


@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_spectral_sphere_matches_mitsuba(name, mitsuba_images):
    sc = _scene(MATERIALS[name]())
    ours = np.stack([R.render(sc, width=RES, height=RES, spp=SPP, max_depth=MAX_DEPTH, seed=s, progress=False,
                              spectral=True) for s in range(K)]).astype(np.float64)
    theirs = mitsuba_images[name]
    assert theirs.shape == ours.shape
    s = compare(ours, theirs)
    print(name, {k: round(v, 5) for k, v in s.items()})
    # the image is coloured by the material's spectrum (not a grey comparison); the sampled
    # conductor's mirror is nearly grey under this environment (measured: 1.6 % spread of the
    # channel means), the glass is grey by construction
    mean_rgb = ours.mean(axis=(0, 1, 2))
    assert np.ptp(mean_rgb) > {"glass": 0.0, "conductor_sampled": 0.01}.get(name, 0.02) * mean_rgb.mean()
    assert abs(s["rel_mean_error"]) < 4 * s["se_rel"] + SYS_REL, s
    assert s["mean_z2"] < 1.35, s
    assert s["frac_z_gt_4"] < 0.005, s
    # the comparison has power: a 3 % error of the image fails the mean check
    assert abs(compare(1.03 * ours, theirs)["rel_mean_error"]) > 4 * s["se_rel"] + SYS_REL
