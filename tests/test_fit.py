"""bk.fit: recovery of a family's own parameters from a perturbed start (Conductor, Dielectric,
FilamentStandard with anisotropy), raw-sample targets, the report, and argument errors."""
import numpy as np
import pytest

import bsdfkit as bk


def _check_recovered(rep, truth, rtol=1e-6):
    for name, v in rep.params.items():
        assert abs(v - truth[name]) <= rtol * max(abs(truth[name]), 1e-3), (name, v, truth[name], rep)


def test_recover_conductor_anisotropic():
    truth_m = bk.Conductor((0.2, 0.9, 1.1), (3.9, 2.4, 2.1), alpha_x=0.35, alpha_y=0.12)
    init = {"eta": (0.3, 0.7, 1.4), "k": (3.0, 2.8, 1.8), "alpha_x": 0.25, "alpha_y": 0.2}
    m, rep = bk.fit(truth_m, bk.Conductor, params=("eta", "k", "alpha_x", "alpha_y"), init=init, n=2048)
    truth = {f"{p}.{c}": getattr(truth_m, p)[i] for p in ("eta", "k") for i, c in enumerate("rgb")}
    truth.update(alpha_x=0.35, alpha_y=0.12)
    _check_recovered(rep, truth)
    assert rep.success and np.all(rep.rel_p99 < 1e-6)
    assert rep.albedo_error < 1e-6   # same model, same sampler, same seed


@pytest.mark.parametrize("fresnel", ["schlick", "f82"])
def test_recover_conductor_isotropic_alpha(fresnel):
    truth_m = bk.Conductor.from_metal("Au", alpha=0.3, fresnel=fresnel)
    # Schlick sees eta and k only through F0 (one number per channel): fit k with eta fixed
    fit_p = ("k", "alpha") if fresnel == "schlick" else ("eta", "k", "alpha")
    fixed = {"fresnel": fresnel, **({"eta": truth_m.eta} if fresnel == "schlick" else {})}
    init = {"k": (3.5, 2.0, 2.0), "alpha": 0.2, **({} if fresnel == "schlick" else {"eta": (0.3, 0.5, 1.2)})}
    m, rep = bk.fit(truth_m, bk.Conductor, params=fit_p, fixed=fixed, init=init, loss="relative", n=2048)
    truth = {f"{p}.{c}": getattr(truth_m, p)[i] for p in fit_p[:-1] for i, c in enumerate("rgb")}
    truth["alpha"] = 0.3
    _check_recovered(rep, truth)
    assert m.alpha_x == m.alpha_y and m.fresnel == fresnel


def test_recover_dielectric():
    truth_m = bk.Dielectric(1.45, alpha_x=0.3, alpha_y=0.15)
    m, rep = bk.fit(truth_m, bk.Dielectric, init={"eta": 1.3, "alpha_x": 0.2, "alpha_y": 0.2}, n=2048)
    _check_recovered(rep, {"eta": 1.45, "alpha_x": 0.3, "alpha_y": 0.15})


def test_recover_filament_anisotropic():
    truth_m = bk.FilamentStandard((0.7, 0.4, 0.2), metallic=0.3, roughness=0.45, reflectance=0.6, anisotropy=0.4)
    params = ("base_color", "metallic", "roughness", "reflectance", "anisotropy")
    init = {"base_color": np.array([0.5, 0.5, 0.5]), "metallic": 0.5, "roughness": 0.6, "reflectance": 0.5,
            "anisotropy": 0.1}
    m, rep = bk.fit(truth_m, bk.FilamentStandard, params=params, init=init, n=1024, loss="l2")
    truth = {f"base_color.{c}": v for c, v in zip("rgb", (0.7, 0.4, 0.2))}
    truth.update(metallic=0.3, roughness=0.45, reflectance=0.6, anisotropy=0.4)
    _check_recovered(rep, truth)


def test_fit_raw_samples_and_report():
    rng = np.random.default_rng(3)
    truth_m = bk.Conductor.from_metal("Cu", alpha=0.2)
    wo = bk.direction(np.arccos(rng.uniform(0.05, 1, 3000)), rng.uniform(0, 2 * np.pi, 3000))
    wi = bk.direction(np.arccos(rng.uniform(0.05, 1, 3000)), rng.uniform(0, 2 * np.pi, 3000))
    v = truth_m.eval(wo, wi)
    m, rep = bk.fit((wo, wi, v), bk.Conductor, params=("alpha",), init={"eta": truth_m.eta, "k": truth_m.k,
                                                                         "alpha": 0.5})
    assert abs(rep.params["alpha"] - 0.2) < 1e-7 and rep.albedo_error is None
    text = repr(rep)
    for word in ("alpha", "rel. error p99", "albedo error", "evaluations", "time"):
        assert word in text
    assert "<table>" in rep._repr_html_()


def test_fit_multistart_keeps_the_best():
    truth_m = bk.Dielectric(1.6, alpha=0.25)
    m, rep = bk.fit(truth_m, bk.Dielectric, params=("eta", "alpha"), init={"eta": 3.5, "alpha": 1.5}, starts=3, n=1024)
    assert rep.starts == 3 and len(rep.start_costs) == 3 and rep.cost == min(rep.start_costs)
    assert abs(rep.params["eta"] - 1.6) < 1e-6


def test_fit_errors():
    t = bk.Conductor.from_metal("Cu", alpha=0.2)
    with pytest.raises(ValueError, match="loss"):
        bk.fit(t, bk.Conductor, loss="huber")
    with pytest.raises(ValueError, match="differentiable"):
        bk.fit(t, bk.Conductor, params=("roughness",))
    with pytest.raises(TypeError, match="family"):
        bk.fit(t, "conductor")
    with pytest.raises(TypeError, match="target"):
        bk.fit(42, bk.Conductor)
    with pytest.raises(ValueError, match="no parameter"):
        bk.fit(t, bk.Conductor, fixed={"colour": 1})
    with pytest.raises(ValueError, match="starts"):
        bk.fit(t, bk.Conductor, starts=0)
    # weights that fit nothing, or that do not match the pairs fitted, are refused (all-zero
    # weights once returned the starting model as a converged fit; a wrong length, a bare
    # numpy broadcast error)
    with pytest.raises(ValueError, match="weights: all zero"):
        bk.fit(t, bk.Conductor, weights=0.0)
    with pytest.raises(ValueError, match="weights: shape"):
        bk.fit(t, bk.Conductor, weights=np.ones(7))


def test_simplify_families_measured_to_analytic(tmp_path):
    """A MERL table of a rough copper: Diffuse cannot fit it, Conductor can, to the table's own
    error (the p99 relative error of the generating model against its MERL tabulation, ~0.37,
    from MERL's grazing bins); the choice is the cheapest family within tol, all are reported."""
    from bsdfkit.tuning.errors import direction_set
    src = bk.Conductor.from_metal("Cu", alpha=0.3)
    target = bk.MERL.load(bk.measured.write_merl(tmp_path / "cu.binary", src), interpolation="linear")
    ds = direction_set(target, n=4096, seed=0, n_albedo=16)   # fit's default set (seed 0)
    y_t = target.eval(ds.wo, ds.wi) * np.abs(ds.wi[:, 2:3])
    y_s = src.eval(ds.wo, ds.wi) * np.abs(ds.wi[:, 2:3])
    floor_err = np.max(np.percentile(np.abs(y_s - y_t) / np.maximum(y_t, 1e-3 * y_t.mean()), 99, axis=0))
    m, rep = bk.simplify(target, 0.5, families=(bk.Diffuse, bk.Conductor))
    by = {f.family: f for f in rep.fits}
    assert set(by) == {"Diffuse", "Conductor"}
    assert by["Diffuse"].error > 0.5 and not by["Diffuse"].ok
    assert by["Conductor"].ok and isinstance(m, bk.Conductor) and rep.chosen is by["Conductor"]
    assert by["Conductor"].error <= 1.1 * floor_err, (by["Conductor"].error, floor_err)
    assert abs(m.alpha_x - 0.3) < 0.01 and abs(m.alpha_y - 0.3) < 0.01
    assert [f.cost for f in rep.fits] == sorted(f.cost for f in rep.fits)
    assert "Conductor <- chosen" in repr(rep) and "<table>" in rep._repr_html_()
    m2, rep2 = bk.simplify(target, 1e-3, families=(bk.Diffuse,))
    assert m2 is None and rep2.chosen is None and "none within tol" in repr(rep2)
