"""measured -> analytic must not add a lobe the material does not have (issue 50, item 4).

simplify(merl, 0.6, families=(Diffuse, Conductor, FilamentStandard)) on a MERL table written
from a coat-less FilamentStandard picked a fit with clear_coat 0.0135, clear_coat_roughness 0.03:
f = 14-19 at the mirror direction against the source's 0.36. Its p99 error on the target's
direction set could not see a lobe that narrow. The error is now also measured on pairs sampled
from each fit, and an optional lobe stays only if the data supports it.
"""
import numpy as np
import pytest

import bsdfkit as bk

FAMILIES = (bk.Diffuse, bk.Conductor, bk.FilamentStandard)


def _merl(tmp_path, src, name):
    return bk.MERL.load(bk.measured.write_merl(str(tmp_path / name), src), interpolation="linear")


def _mirror(theta_deg):
    t = np.radians(theta_deg)
    return bk.direction(t, 0.0), bk.direction(t, np.pi)


def test_no_clear_coat_is_added_to_a_coatless_material(tmp_path):
    src = bk.FilamentStandard((0.8, 0.25, 0.1), roughness=0.45, reflectance=0.5)   # notebook 07's material
    merl = _merl(tmp_path, src, "red.binary")
    best, rep = bk.simplify(merl, 0.6, families=FAMILIES, n=1024)
    fil = next(f for f in rep.fits if f.family == "FilamentStandard")
    assert best is fil.model and best.clear_coat == 0.0 and "clear_coat" in fil.dropped
    assert fil.error_own_pairs is not None and fil.error == max(fil.error_target_pairs, fil.error_own_pairs)
    for th in (20.0, 40.0, 60.0):        # the highlight is the source's, not a coat's spike
        wo, wi = _mirror(th)
        np.testing.assert_allclose(best.eval(wo, wi), src.eval(wo, wi), rtol=0.05)
    # measured where the fit puts its energy, its largest error is small too
    from bsdfkit.fitting.simplify import _own_pairs_error
    assert _own_pairs_error(merl, best, 1e-4, "max", 0) < 5.0


def test_a_real_clear_coat_is_kept(tmp_path):
    src = bk.FilamentStandard((0.8, 0.25, 0.1), roughness=0.45, reflectance=0.5, clear_coat=0.8,
                              clear_coat_roughness=0.1)
    merl = _merl(tmp_path, src, "coated.binary")
    _, rep = bk.simplify(merl, 0.6, families=(bk.FilamentStandard,), n=1024)
    (fil,) = rep.fits
    assert "clear_coat" not in fil.dropped and fil.model.clear_coat > 0.3
    wo, wi = _mirror(40.0)
    np.testing.assert_allclose(fil.model.eval(wo, wi), src.eval(wo, wi), rtol=0.25)


def test_raw_samples_have_no_own_pairs_error():
    src = bk.Diffuse([0.5, 0.4, 0.3])
    wo = bk.direction(np.radians(np.linspace(5, 80, 64)), 0.0)
    wi = bk.direction(np.radians(np.linspace(80, 5, 64)), np.pi)
    _, rep = bk.simplify((wo, wi, src.eval(wo, wi)), 0.01, families=(bk.Diffuse,))
    (f,) = rep.fits
    assert f.error_own_pairs is None and f.ok and f.error == pytest.approx(f.error_target_pairs)
