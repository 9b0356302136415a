"""Chi-square goodness of fit of the Filament models' samplers against their own (mixture) pdf,
with Mitsuba's harness (mitsuba.chi2.ChiSquareTest, SphericalDomain): 1e6 samples per case,
significance 0.01 with a Sidak correction over all cases of this file.

As in test_chi2.py, directions are rotated by R (local z to the domain's -y axis, see R and LIFT)
so that lobes do not sit on the domain's poles; narrow or grazing lobes need the finer pdf integration
ires = 32 (the harness's trapezoid rule, not the sampler, is then the limit: a Conductor of the
same alpha fails the same way at ires = 16).

Lobes narrower than the harness can integrate at all (perceptual roughness 0.05 and 0.1, GGX
alpha 0.0025 and 0.01: the pdf integral over the sphere comes out 11 % low at ires = 16) are
tested in a magnified half-vector domain instead: wi -> h = normalize(wo + wi) ->
h' = normalize(h.x / s, h.y / s, h.z), an invertible change of variables whose density is
pdf(wi) |dwi/dh| |dh/dh'| = pdf(wi) 4 |wo.h| s^2 / |(s h'.x, s h'.y, h'.z)|^3 -- the same
test on a domain where the lobe is wide."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as ref

ZS = [0.999, 0.7, 0.3, 0.1, 0.01]  # incidence cos(theta_o); one-sided models: wo above only
# (x, y, z) -> (x, -z, y) as in test_chi2.py: the local horizon lies on the domain's phi = 0 / pi
# cell boundaries.
R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
# A valid sample closer than ~1e-7 rad to the horizon is binned by the harness's float32 atan2 and
# pi + phi rounding into the cell below the horizon, whose expected count is 0, and the harness
# rejects; such samples are lifted to 1e-6 above the horizon for binning (a 1e-6 rad move).
LIFT = 1e-6
SIGNIFICANCE = 0.01


def _models():
    # (name, model, ires)
    return [
        ("metal_r0.224", bk.FilamentStandard([0.95, 0.64, 0.54], metallic=1.0, roughness=0.05 ** 0.5), 32),
        ("metal_r0.5", bk.FilamentStandard(1.0, metallic=1.0, roughness=0.5), 16),
        ("metal_r1", bk.FilamentStandard(1.0, metallic=1.0, roughness=1.0), 16),
        ("dielectric_r0.5", bk.FilamentStandard([0.8, 0.5, 0.2], roughness=0.5), 16),
        ("aniso+0.8", bk.FilamentStandard([0.9, 0.6, 0.3], metallic=0.7, roughness=0.6, anisotropy=0.8), 16),
        ("aniso-0.8", bk.FilamentStandard(0.9, metallic=1.0, roughness=0.45, anisotropy=-0.8), 24),
        ("coat", bk.FilamentStandard(0.5, roughness=0.7, anisotropy=-0.6, clear_coat=1.0, clear_coat_roughness=0.2), 32),
        ("coat_sheen_burley", bk.FilamentStandard([0.2, 0.4, 0.8], metallic=0.3, roughness=0.35, clear_coat=0.6,
                                                  clear_coat_roughness=0.5, clear_coat_layering="doc",
                                                  sheen_color=[0.3, 0.6, 0.9], sheen_roughness=0.5,
                                                  diffuse="burley"), 16),
        ("sheen_only", bk.FilamentStandard(0.0, metallic=1.0, roughness=1.0, sheen_color=1.0, sheen_roughness=0.3), 16),
        ("cloth", bk.FilamentCloth([0.6, 0.3, 0.2], roughness=0.6), 16),
        ("cloth_sheen_r0.2", bk.FilamentCloth(0.05, sheen_color=0.9, roughness=0.2), 16),
        ("cloth_subsurface", bk.FilamentCloth([0.6, 0.3, 0.2], sheen_color=[0.2, 0.4, 0.8],
                                              subsurface_color=[0.5, 0.2, 0.1], roughness=0.3), 16),
    ]


NARROW = [("metal_r0.05", 0.05), ("metal_r0.1", 0.1)]
CASES = [(name, m, ires, z) for name, m, ires in _models() for z in ZS]
N_TESTS = len(CASES) + len(NARROW) * len(ZS)


def _wo(z, phi=0.7):
    s = np.sqrt(1 - z * z)
    return np.array([s * np.cos(phi), s * np.sin(phi), z])


@pytest.mark.parametrize("name, model, ires, z", CASES, ids=[f"{c[0]}-z{c[3]}" for c in CASES])
def test_chi2_filament(name, model, ires, z):
    wo = _wo(z)

    def sample_fn(uc, u):
        r = model.sample(wo, uc, u)
        wi = r.wi.copy()
        wi[:, 2] = np.maximum(wi[:, 2], LIFT)
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        return wi @ R.T, r.valid

    def pdf_fn(v):
        return model.pdf(wo, v @ R)

    passed, p, msg = ref.chi2_test(sample_fn, pdf_fn, res=101, ires=ires, sample_count=1_000_000, seed=3,
                                   significance=SIGNIFICANCE, test_count=N_TESTS)
    print(f"chi2 {name} z={z}: p = {p:.4g}")
    assert passed, msg


@pytest.mark.parametrize("roughness_name, roughness", NARROW, ids=[n[0] for n in NARROW])
@pytest.mark.parametrize("z", ZS)
def test_chi2_narrow_lobe_magnified(roughness_name, roughness, z):
    model = bk.FilamentStandard(1.0, metallic=1.0, roughness=roughness)
    s = max(roughness, 0.045) ** 2 * 4  # a few alphas: the lobe spans the magnified hemisphere
    wo = _wo(z)
    M = np.array([s, s, 1.0])

    def to_hp(wi):
        h = wo + wi
        h /= np.linalg.norm(h, axis=-1, keepdims=True)
        hp = h / M
        return hp / np.linalg.norm(hp, axis=-1, keepdims=True)

    def sample_fn(uc, u):
        r = model.sample(wo, uc, u)
        hp = np.where(r.valid[:, None], to_hp(np.where(r.valid[:, None], r.wi, wo)), [0.0, 0.0, 1.0])
        return hp @ R.T, r.valid

    def pdf_fn(v):
        hp = v @ R
        up = hp[:, 2] > 0
        mh = hp * M
        norm = np.linalg.norm(mh, axis=-1)
        h = mh / norm[:, None]
        woh = h @ wo
        wi = 2 * woh[:, None] * h - wo
        wi /= np.linalg.norm(wi, axis=-1, keepdims=True)
        jac = 4 * np.abs(woh) * s * s / norm ** 3
        return np.where(up, model.pdf(wo, wi) * jac, 0.0)

    passed, p, msg = ref.chi2_test(sample_fn, pdf_fn, res=101, ires=16, sample_count=1_000_000, seed=3,
                                   significance=SIGNIFICANCE, test_count=N_TESTS)
    print(f"chi2 {roughness_name} (magnified) z={z}: p = {p:.4g}")
    assert passed, msg
