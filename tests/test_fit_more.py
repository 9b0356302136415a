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
    # simplify also measures each fit on pairs sampled from the fit itself: the source measured so
    # (against its own tabulation) is the floor there
    from bsdfkit.fitting.simplify import _own_pairs_error
    floor_err = max(floor_err, _own_pairs_error(target, src, 1e-3 * y_t.mean(), "p99", 0))
    tol = max(0.5, 1.5 * floor_err)
    m, rep = bk.simplify(target, tol, families=(bk.Diffuse, bk.Conductor, bk.FilamentCloth, bk.CoatedDiffuse),
                         n=1024)
    by = {f.family: f for f in rep.fits}
    assert set(by) == {"Diffuse", "Conductor", "FilamentCloth", "CoatedDiffuse"}
    print("\n" + repr(rep), "\ntabulation floor", floor_err)
    for name in ("Diffuse", "Conductor", "FilamentCloth"):
        assert not by[name].ok, (name, by[name].error)
    # ordered by the cost table, which times the analytic coated family too (not n/a, not last)
    costs = [f.cost for f in rep.fits]
    assert all(np.isfinite(costs)) and costs == sorted(costs), [(f.family, f.cost) for f in rep.fits]
    assert by["Diffuse"].cost < by["CoatedDiffuse"].cost
    assert by["CoatedDiffuse"].ok and isinstance(m, bk.CoatedDiffuse) and m.method == "analytic"
    assert by["CoatedDiffuse"].error <= 1.1 * floor_err + 1e-3, (by["CoatedDiffuse"].error, floor_err)
    assert abs(m.alpha_x - 0.15) < 0.01


def test_recover_plastic_rough():
    """Rough Plastic, every parameter (R, eta, alpha, Ks per channel) from a perturbed start:
    eval_grad differentiates the coat's tables in alpha and eta."""
    truth_m = bk.Plastic((0.6, 0.3, 0.15), eta=1.6, alpha=0.15, specular_reflectance=(0.9, 0.8, 0.7))
    init = {"reflectance": (0.5, 0.5, 0.5), "eta": 1.4, "alpha": 0.25, "specular_reflectance": (1.0, 1.0, 1.0)}
    m, rep = bk.fit(truth_m, bk.Plastic, params=("reflectance", "eta", "alpha", "specular_reflectance"),
                    init=init, n=1024, albedo=False)
    print("\n" + repr(rep))
    truth = {**_rgb_truth("reflectance", (0.6, 0.3, 0.15)), "eta": 1.6, "alpha": 0.15,
             **_rgb_truth("specular_reflectance", (0.9, 0.8, 0.7))}
    _check_recovered(rep, truth)
    assert rep.success and np.all(rep.rel_p99 < 1e-6)


def test_recover_plastic_smooth():
    """Smooth Plastic (alpha fixed at 0): R and eta, nonlinear internal reflections. The coat's
    delta lobe is 0 in eval, so Ks is not identifiable (its derivative is 0) and is held."""
    truth_m = bk.Plastic((0.7, 0.4, 0.2), eta=1.7, nonlinear=True)
    m, rep = bk.fit(truth_m, bk.Plastic, params=("reflectance", "eta"), init={"reflectance": 0.5, "eta": 1.3},
                    fixed={"alpha": 0.0, "nonlinear": True}, n=1024, albedo=False)
    assert m.alpha == 0.0
    _check_recovered(rep, {**_rgb_truth("reflectance", (0.7, 0.4, 0.2)), "eta": 1.7})
    assert rep.success and np.all(rep.rel_p99 < 1e-6)


ANALYTIC_COATED = {
    "CoatedDiffuse/analytic": lambda: bk.CoatedDiffuse((0.6, 0.35, 0.15), alpha=0.05, method="analytic"),
    "CoatedDiffuse/medium/analytic": lambda: bk.CoatedDiffuse(0.2, albedo=0.8, thickness=0.2, g=0.3,
                                                              method="analytic"),
    "CoatedConductor/analytic": lambda: bk.CoatedConductor.from_metal("Au", thickness=0.05, method="analytic"),
    "CoatedConductor/medium/analytic": lambda: bk.CoatedConductor.from_metal(
        "Cu", conductor_alpha=0.3, interface_alpha=0.02, albedo=(0.5, 0.1, 0.1), thickness=0.1, method="analytic"),
}


@pytest.mark.parametrize("fam", sorted(ANALYTIC_COATED))
def test_cost_table_times_the_analytic_coated_families(fam):
    """The shipped cost table has the analytic coated families (bench/tradeoff.py --configs
    method=analytic): simplify_families' cost of such a model is its own configuration's time (the
    analytic method, a fraction of the reference 64-sample walk), and the knob simplifier ranks
    the analytic configurations by the measured entries, the walks by the model's cost model."""
    from bsdfkit.fitting.simplify import _cost, _own_key
    from bsdfkit.tuning import configurations, family
    from bsdfkit.tuning.costs import _costs_for, knob_costs
    m = ANALYTIC_COATED[fam]()
    assert family(m) == fam
    table = knob_costs()
    entry = table["families"][fam]
    key = _own_key(m)
    assert key.startswith("method=analytic;") and key.endswith("precision=float64") and key in entry["costs"]
    own = entry["costs"][key]
    # the analytic method vs 64 random walks of depth <= 100 (a smooth coat over a smooth metal is
    # delta-only: the timed op is sample, one walk against one closed-form lobe choice)
    assert 0 < own < (0.01 if entry["op"] == "eval" else 1.0), (entry["op"], own)
    assert _cost(m, table) == pytest.approx(own / entry["reference_rate_per_s"], rel=1e-12)
    cfgs = configurations(m)
    assert cfgs[0].labels["method"] == "stochastic" and entry["costs"][cfgs[0].key] == 1.0   # the reference walk
    got = _costs_for(m, cfgs, table)
    for c, v in zip(cfgs, got):
        if c.key in entry["costs"]:
            assert v == entry["costs"][c.key]
        else:   # the walks' entries come from the model's cost model (linear in n_samples)
            assert c.labels["method"] == "stochastic" and v == m.relative_cost(c.model._params) / \
                m.relative_cost(cfgs[0].model._params)
