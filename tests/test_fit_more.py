"""bk.fit for the families with new gradient kernels: FilamentCloth and the analytic coated models
(recovery of their own parameters from a perturbed start), and bk.simplify(measured, tol,
families=...) choosing among them for a MERL table."""
import numpy as np
import pytest

import bsdfkit as bk


def _check_recovered(rep, truth, rtol=1e-6):
    for name, v in rep.params.items():
        assert abs(v - truth[name]) <= rtol * max(abs(truth[name]), 1e-3), (name, v, truth[name], rep)


def _rgb_truth(name, v):
    return {f"{name}.{c}": x for c, x in zip("rgb", np.broadcast_to(v, (3,)))}


def test_recover_cloth():
    truth_m = bk.FilamentCloth((0.35, 0.1, 0.15), sheen_color=(0.8, 0.5, 0.6), roughness=0.55)
    init = {"base_color": (0.5, 0.5, 0.5), "sheen_color": (0.5, 0.5, 0.5), "roughness": 0.8}
    m, rep = bk.fit(truth_m, bk.FilamentCloth, params=("base_color", "sheen_color", "roughness"), init=init,
                    n=2048, albedo=False)
    truth = {**_rgb_truth("base_color", (0.35, 0.1, 0.15)), **_rgb_truth("sheen_color", (0.8, 0.5, 0.6)),
             "roughness": 0.55}
    _check_recovered(rep, truth)
    assert rep.success and np.all(rep.rel_p99 < 1e-6)


def test_cloth_default_sheen_starts_from_its_value():
    """A start with sheen_color=None fits sheen_color from sqrt(base_color) (held on its own)."""
    truth_m = bk.FilamentCloth((0.3, 0.2, 0.1), sheen_color=(0.4, 0.4, 0.4), roughness=0.5)
    m, rep = bk.fit(truth_m, bk.FilamentCloth, init=bk.FilamentCloth((0.5, 0.5, 0.5), roughness=0.6), n=1024,
                    albedo=False)
    assert "sheen_color.r" in rep.params and "subsurface_color.r" not in rep.params
    assert rep.init["sheen_color.g"] == pytest.approx(np.sqrt(0.5))
    _check_recovered(rep, {**_rgb_truth("base_color", (0.3, 0.2, 0.1)), **_rgb_truth("sheen_color", 0.4),
                           "roughness": 0.5})


def test_recover_coated_diffuse_analytic():
    truth_m = bk.CoatedDiffuse((0.6, 0.35, 0.15), eta=1.45, alpha=0.08, thickness=0.05, albedo=(0.3, 0.2, 0.1),
                               g=0.2, method="analytic")
    params = ("reflectance", "eta", "alpha", "thickness", "albedo", "g")
    init = {"reflectance": (0.5, 0.5, 0.5), "eta": 1.3, "alpha": 0.15, "thickness": 0.02, "albedo": (0.2, 0.2, 0.2),
            "g": 0.0}
    # the family's first example is the stochastic walk: fit switches to the analytic method
    m, rep = bk.fit(truth_m, bk.CoatedDiffuse, params=params, init=init, n=2048, albedo=False)
    assert m.method == "analytic"
    truth = {**_rgb_truth("reflectance", (0.6, 0.35, 0.15)), "eta": 1.45, "alpha": 0.08, "thickness": 0.05,
             **_rgb_truth("albedo", (0.3, 0.2, 0.1)), "g": 0.2}
    _check_recovered(rep, truth)


def test_recover_coated_conductor_analytic():
    truth_m = bk.CoatedConductor.from_metal("Cu", conductor_alpha_x=0.3, conductor_alpha_y=0.2,
                                            interface_alpha=0.05, interface_eta=1.5, thickness=0.1,
                                            albedo=(0.5, 0.1, 0.1), method="analytic")
    params = ("conductor_k", "conductor_alpha_x", "conductor_alpha_y", "interface_eta", "interface_alpha",
              "thickness", "albedo")
    init = {"conductor_k": (3.0, 3.0, 3.0), "conductor_alpha_x": 0.2, "conductor_alpha_y": 0.25,
            "interface_eta": 1.4, "interface_alpha": 0.1, "thickness": 0.05, "albedo": (0.3, 0.3, 0.3),
            "conductor_eta": truth_m.conductor_eta}
    m, rep = bk.fit(truth_m, bk.CoatedConductor, params=params, init=init, n=2048, albedo=False)
    truth = {**_rgb_truth("conductor_k", truth_m.conductor_k), "conductor_alpha_x": 0.3, "conductor_alpha_y": 0.2,
             "interface_eta": 1.5, "interface_alpha": 0.05, "thickness": 0.1,
             **_rgb_truth("albedo", (0.5, 0.1, 0.1))}
    _check_recovered(rep, truth)


def test_simplify_families_picks_a_coated_model_for_a_varnish(tmp_path):
    """A MERL table of a varnished diffuse (analytic CoatedDiffuse): neither Diffuse nor Conductor
    nor FilamentCloth reaches tol, the coated family does (to the tabulation's own error); the
    report lists every family."""
    from bsdfkit.tuning.errors import direction_set
    src = bk.CoatedDiffuse((0.6, 0.35, 0.15), alpha=0.15, thickness=0.02, method="analytic")
    target = bk.MERL.load(bk.measured.write_merl(tmp_path / "varnish.binary", src), interpolation="linear")
    ds = direction_set(target, n=1024, seed=0, n_albedo=16)   # fit's set for n=1024, seed 0
    y_t = target.eval(ds.wo, ds.wi) * np.abs(ds.wi[:, 2:3])
    y_s = src.eval(ds.wo, ds.wi) * np.abs(ds.wi[:, 2:3])
    floor_err = np.max(np.percentile(np.abs(y_s - y_t) / np.maximum(y_t, 1e-3 * y_t.mean()), 99, axis=0))
    tol = max(0.5, 1.5 * floor_err)
    m, rep = bk.simplify(target, tol, families=(bk.Diffuse, bk.Conductor, bk.FilamentCloth, bk.CoatedDiffuse),
                         n=1024)
    by = {f.family: f for f in rep.fits}
    assert set(by) == {"Diffuse", "Conductor", "FilamentCloth", "CoatedDiffuse"}
    print("\n" + repr(rep), "\ntabulation floor", floor_err)
    for name in ("Diffuse", "Conductor", "FilamentCloth"):
        assert not by[name].ok, (name, by[name].error)
    assert by["CoatedDiffuse"].ok and isinstance(m, bk.CoatedDiffuse) and m.method == "analytic"
    assert by["CoatedDiffuse"].error <= 1.1 * floor_err + 1e-3, (by["CoatedDiffuse"].error, floor_err)
    assert abs(m.alpha_x - 0.15) < 0.01
