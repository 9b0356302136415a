"""bsdfkit.tradeoff / bsdfkit.simplify: the knob registry, errors that match an independent
recomputation, simplify's guarantees on fresh direction sets, lobe dropping, determinism, bad input,
the Table renderers, the Pareto plot and ``python -m bsdfkit simplify``. No timed asserts."""
import importlib.util
import math
import subprocess
import sys

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.plot import pareto
from bsdfkit.tuning import (ALBEDO_COS_THETA, COST_RESOLUTION, FLOOR_FRACTION, DirectionSet, Table, configurations,
                            direction_set, family, knob_costs)

N = 2048          # direction pairs per set: small, the suite stays fast
N_ALB = 2048      # albedo samples per wo


# ------------------------------------------------------------------ independent recomputation

def f_cos(model, dtype, wo, wi):
    """f |cos theta_i| with the model run in `dtype` and the cosine of the float64 wi."""
    return model.eval(wo.astype(dtype), wi.astype(dtype)).astype(np.float64) * np.abs(wi[:, 2:3])


def delta_f_cos(model, dtype, wo, uc, u, ref):
    """Delta lobes: f |cos| of a sample drawn with the same uniforms as the reference sample `ref`
    (0 where the configuration picks another lobe or direction)."""
    s = model.sample(wo.astype(dtype), uc.astype(dtype), u.astype(dtype))
    wi = s.wi.astype(np.float64)
    same = s.valid & (s.flags == ref.flags) & (np.abs(wi - ref.wi).max(axis=1) < 1e-3)
    return np.where(same[:, None], s.f.astype(np.float64) * np.abs(wi[:, 2:3]), 0.0)


def rel_err(v_ref, v, floor):
    return np.abs(v - v_ref) / np.maximum(np.abs(v_ref), floor)


def independent_floor(model):
    """1e-3 mean(albedo) / pi from bsdfkit's own Monte Carlo albedo (not the tradeoff code)."""
    mu = np.asarray(ALBEDO_COS_THETA)
    wo = bk.direction(np.arccos(mu), 0.3 + 2.399963229728653 * np.arange(len(mu)))
    if model.flags & bk.BxDFFlags.Transmission:
        wo = np.concatenate([wo, wo * [1, 1, -1]])
    return FLOOR_FRACTION * float(np.mean(model.albedo(wo, n_samples=1 << 16, seed=3))) / math.pi


def errors_on(ref, model, dtype, ds: DirectionSet, floor):
    """(max, p99) relative error of `model` in `dtype` against `ref` on a direction set."""
    parts_ref, parts = [f_cos(ref, np.float64, ds.wo, ds.wi)], [f_cos(model, dtype, ds.wo, ds.wi)]
    if len(ds.delta_wo):
        r = ref.sample(ds.delta_wo, ds.delta_uc, ds.delta_u)
        parts_ref.append(delta_f_cos(ref, np.float64, ds.delta_wo, ds.delta_uc, ds.delta_u, r))
        parts.append(delta_f_cos(model, dtype, ds.delta_wo, ds.delta_uc, ds.delta_u, r))
    e = rel_err(np.concatenate(parts_ref), np.concatenate(parts), floor)
    return float(e.max()), float(np.quantile(e, 0.99))


def user_pairs(n, seed, sphere=False):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    v[0, :, 2] = np.abs(v[0, :, 2])
    if not sphere:
        v[1, :, 2] = np.abs(v[1, :, 2])
    return v[0], v[1]


# ------------------------------------------------------------------ registry

def test_knobs_of_each_family_and_what_is_moot():
    names = lambda m: {k.name: k.reachable for k in bk.knobs(m)}  # noqa: E731
    assert names(bk.Conductor.from_metal("Cu", alpha=0.3)) == {"fresnel": True, "masking": True, "distribution": True,
                                                                "precision": True}
    assert names(bk.Conductor.from_metal("Au")) == {"fresnel": True, "masking": False, "distribution": False,
                                                    "precision": True}
    assert names(bk.Dielectric(1.5)) == {"masking": False, "distribution": False, "precision": True}
    assert names(bk.Dielectric(1.5, alpha=0.2)) == {"masking": True, "distribution": True, "precision": True}
    for m in (bk.Diffuse(0.5), bk.DiffuseTransmission(0.3, 0.4), bk.ThinDielectric(1.5)):
        assert names(m) == {"precision": True}
    plastic = names(bk.FilamentStandard([0.8, 0.5, 0.3]))        # reflectance 0.5: the f90 rule saturates
    assert plastic == {"clear_coat": False, "sheen": False, "diffuse": True, "visibility": True, "f90": False,
                       "energy_compensation": True, "dfg_lut_size": True, "precision": True}
    dark = names(bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, clear_coat=0.3, sheen_color=0.2))
    assert all(dark.values())
    metal_aniso = names(bk.FilamentStandard(1.0, metallic=1.0, anisotropy=0.5))
    assert not metal_aniso["diffuse"] and not metal_aniso["visibility"]
    cloth = names(bk.FilamentCloth(0.5))
    assert cloth == {"diffuse": True, "dfg_lut_size": False, "precision": True}
    # model-defining parameters are never knobs
    all_names = {k.name for k in bk.knobs(bk.FilamentStandard(clear_coat=0.5))}
    assert not all_names & {"min_roughness", "clear_coat_layering", "clear_coat_ior_change", "roughness"}


def test_settings_are_ordered_most_accurate_first():
    ks = {k.name: k for k in bk.knobs(bk.FilamentStandard(reflectance=0.1, clear_coat=0.2, sheen_color=0.1))}
    assert ks["diffuse"].settings == ("burley", "lambert")
    assert ks["visibility"].settings == ("correlated", "fast")
    assert ks["f90"].settings == ("filament", "one")
    assert ks["energy_compensation"].settings == (True, False)
    assert ks["dfg_lut_size"].settings == (128, 64, 32, 16)
    assert ks["clear_coat"].labels == ("keep", "drop") and ks["clear_coat"].settings == (0.2, 0.0)
    assert ks["precision"].settings == ("float64", "float32")
    c = {k.name: k for k in bk.knobs(bk.Conductor.from_metal("Cu", alpha=0.2))}
    assert c["fresnel"].settings == ("exact", "f82", "schlick")


def test_configurations_are_distinct_and_keep_model_defining_parameters():
    m = bk.FilamentStandard([0.7, 0.6, 0.5], reflectance=0.2, min_roughness="mobile", clear_coat=0.4,
                            clear_coat_layering="doc", diffuse="lambert", dfg_lut_size=64)
    cfgs = configurations(m)
    assert cfgs[0].is_reference and cfgs[0].describe() == "most accurate"
    assert len({c.key for c in cfgs}) == len(cfgs)
    for c in cfgs:
        p = c.model._params
        assert p["min_roughness"] == "mobile" and p["clear_coat_layering"] == "doc"
        if c.labels["dfg_lut_size"] is None:      # moot: the user's value is kept
            assert p["dfg_lut_size"] == 64
    ref = cfgs[0].model
    assert (ref.diffuse, ref.visibility, ref.f90, ref.energy_compensation, ref.dfg_lut_size) == \
        ("burley", "correlated", "filament", True, 128)


# ------------------------------------------------------------------ errors = independent recomputation

@pytest.mark.parametrize("case", ["cu", "fil", "diel", "cloth"])
def test_row_errors_equal_an_independent_recomputation(case):
    model, ref = {
        "cu": (bk.Conductor.from_metal("Cu", alpha=0.3, fresnel="schlick"), bk.Conductor.from_metal("Cu", alpha=0.3)),
        "fil": (bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, roughness=0.4),
                bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, roughness=0.4, diffuse="burley")),
        "diel": (bk.Dielectric(1.5, alpha=0.3, masking="separable"), bk.Dielectric(1.5, alpha=0.3)),
        "cloth": (bk.FilamentCloth([0.1, 0.15, 0.35], roughness=0.8),
                  bk.FilamentCloth([0.1, 0.15, 0.35], roughness=0.8, diffuse="burley")),
    }[case]
    sphere = case == "diel"
    wo, wi = user_pairs(1500, 5, sphere)
    for directions in ((wo, wi), None):
        t = bk.tradeoff(model, directions=directions, n=N, seed=1, n_albedo=N_ALB, measure=False)
        assert t.reference == ref
        assert t.floor == pytest.approx(independent_floor(ref), rel=0.03)
        ds = t.directions
        if directions is not None:
            np.testing.assert_array_equal(ds.wo, wo)
        v_ref = f_cos(ref, np.float64, ds.wo, ds.wi)
        for cfg, row in zip(t.configs, t.to_records()):
            e = rel_err(v_ref, f_cos(cfg.model, cfg.dtype, ds.wo, ds.wi), t.floor)
            assert row["max_err"] == pytest.approx(float(e.max()), rel=1e-12, abs=1e-300)
            assert row["p99_err"] == pytest.approx(float(np.quantile(e, 0.99)), rel=1e-12, abs=1e-300)
            if cfg.dtype is np.float32:           # run in float32 for real: not bit-equal to float64
                assert row["max_err"] > 0


def test_albedo_error_matches_quadrature():
    """albedo_err against a deterministic midpoint quadrature of (f_cfg - f_ref) |cos| (rough lobe)."""
    ref = bk.Conductor.from_metal("Cu", alpha=0.5)
    t = bk.tradeoff(bk.Conductor.from_metal("Cu", alpha=0.5), n=N, n_albedo=8192, measure=False)
    nt, nphi = 400, 200
    th = (np.arange(nt) + 0.5) * (np.pi / 2) / nt
    ph = (np.arange(nphi) + 0.5) * 2 * np.pi / nphi
    T, P = np.meshgrid(th, ph, indexing="ij")
    wi = bk.direction(T, P).reshape(-1, 3)
    dw = (np.sin(T) * (np.pi / 2 / nt) * (2 * np.pi / nphi)).reshape(-1, 1)
    checked = 0
    for cfg, row in zip(t.configs, t.to_records()):
        if cfg.dtype is np.float32:
            continue
        diffs = []
        for wo in t.directions.albedo_wo:
            d = (f_cos(cfg.model, np.float64, np.broadcast_to(wo, wi.shape), wi)
                 - f_cos(ref, np.float64, np.broadcast_to(wo, wi.shape), wi))
            diffs.append(np.abs((d * dw).sum(axis=0)).max())
        assert row["albedo_err"] == pytest.approx(max(diffs), rel=0.05, abs=2e-5)
        checked += 1
    assert checked == 12  # float64: fresnel x masking x distribution


def test_delta_models_are_measured_by_sampling_not_reported_as_zero():
    ref = bk.Conductor.from_metal("Au")
    t = bk.tradeoff(ref, n=N, n_albedo=N_ALB, measure=False)
    assert len(t.directions.wo) == 0 and len(t.directions.delta_wo) == N   # all rows sampled
    assert set(t["op"]) == {"sample"}
    ds = t.directions
    for cfg, row in zip(t.configs, t.to_records()):
        mx, p99 = errors_on(ref, cfg.model, cfg.dtype, ds, t.floor)
        assert row["max_err"] == pytest.approx(mx, rel=1e-12, abs=1e-300)
        assert row["p99_err"] == pytest.approx(p99, rel=1e-12, abs=1e-300)
        if not cfg.is_reference:
            assert row["max_err"] > 0 and row["albedo_err"] > 0
    schlick = next(r for c, r in zip(t.configs, t.to_records()) if c.labels["fresnel"] == "schlick")
    assert schlick["p99_err"] > 1e-2          # Schlick misses gold's blue channel by several percent
    thin = bk.tradeoff(bk.ThinDielectric(1.5), n=512, n_albedo=512, measure=False)
    assert 0 < thin["max_err"][1] < 1e-4       # float32 vs float64: small but measured


# ------------------------------------------------------------------ simplify

SIMPLIFY_MODELS = {
    "cu": lambda: bk.Conductor.from_metal("Cu", alpha=0.3),
    "al_aniso": lambda: bk.Conductor.from_metal("Al", alpha_x=0.4, alpha_y=0.05),
    "au_smooth": lambda: bk.Conductor.from_metal("Au"),
    "glass_rough": lambda: bk.Dielectric(1.5, alpha=0.2),
    "plastic": lambda: bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1),
    "gold": lambda: bk.FilamentStandard([1.0, 0.85, 0.57], metallic=1.0, roughness=0.6),
    "coat_sheen": lambda: bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, clear_coat=0.01,
                                              clear_coat_roughness=0.3, sheen_color=0.01, sheen_roughness=0.5),
    "cloth": lambda: bk.FilamentCloth([0.1, 0.15, 0.35], roughness=0.8),
}


@pytest.mark.parametrize("name", sorted(SIMPLIFY_MODELS))
def test_simplify_holds_on_a_different_direction_set(name):
    model = SIMPLIFY_MODELS[name]()
    ref = model   # the reference is the input as given (issue 11)
    floor = independent_floor(ref)
    fresh = direction_set(model, N, seed=987)
    for tol in (1e-2, 1e-3, 1e-4):
        m, rep = bk.simplify(model, tol, n=N, seed=0, n_albedo=N_ALB)
        assert rep.error["p99"] <= tol and m is rep.model and rep.reference == ref
        mx, p99 = errors_on(ref, m, rep.dtype, fresh, floor)
        assert p99 <= 1.5 * tol, (tol, rep.summary(), p99)


def test_simplify_other_metrics_hold_on_a_different_direction_set():
    model = bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, clear_coat=0.002, clear_coat_roughness=0.2)
    ref = model
    fresh = direction_set(model, N, seed=55)
    for tol in (1e-2, 1e-3):
        m, rep = bk.simplify(model, tol, metric="max", n=N, n_albedo=N_ALB)
        assert rep.error["max"] <= tol
        assert errors_on(ref, m, rep.dtype, fresh, independent_floor(ref))[0] <= 1.5 * tol
    # albedo metric: recomputed with bsdfkit's own Monte Carlo albedo, same seed for both models
    m, rep = bk.simplify(model, 1e-2, metric="albedo", n=N, n_albedo=N_ALB)
    assert rep.error["albedo"] <= 1e-2
    wo = bk.direction(np.radians([0, 45, 80]), 0.0)
    a_ref, a = ref.albedo(wo, 1 << 17, seed=9), m.albedo(wo.astype(rep.dtype), 1 << 17, seed=9)
    assert np.abs(a - a_ref).max() <= 1.5e-2


@pytest.mark.parametrize("name", ["cu", "au_smooth", "plastic", "cloth"])
def test_tol_zero_gives_the_input(name):
    model = SIMPLIFY_MODELS[name]()
    m, rep = bk.simplify(model, 0, n=512, n_albedo=512)
    assert m == model and rep.dtype is np.float64 and rep.changes == [] and rep.unchanged
    assert rep.error == {"max": 0.0, "p99": 0.0, "albedo": 0.0}
    assert rep.tol == 0.0


def _synthetic_costs(model, cheapest_key):
    keys = [c.key for c in configurations(model)]
    costs = {k: 1.0 - 0.01 * i for i, k in enumerate(keys)}   # registry order ~ cheaper, small steps
    costs[cheapest_key] = 0.25
    return {"families": {family(model): {"op": "eval", "costs": costs}}}


def test_huge_tol_gives_the_cheapest_configuration():
    model = bk.Conductor.from_metal("Cu", alpha=0.3)
    cfgs = configurations(model)
    target = next(c for c in cfgs if c.labels == {"fresnel": "f82", "masking": "separable", "distribution": "ggx",
                                                  "precision": "float32"})
    # masking is a modelling choice: reachable only when allowed
    m, rep = bk.simplify(model, 1e9, n=512, n_albedo=512, costs=_synthetic_costs(model, target.key),
                         allow=("masking",))
    assert m == target.model and rep.dtype is np.float32 and rep.expected_speedup == pytest.approx(4.0)
    assert rep.ranked_by == "cost table" and rep.allow == ("masking",)
    assert {k for k, *_ in rep.changes} == {"masking", "fresnel", "precision"}
    # no cost table for the family: registry order, every approximation at its cheapest setting
    m, rep = bk.simplify(model, math.inf, n=512, n_albedo=512, costs={})
    assert (m.fresnel, m.masking, rep.dtype) == ("schlick", "correlated", np.float32)
    assert ("masking", "'correlated'") in rep.fixed
    assert rep.expected_speedup is None and rep.ranked_by.startswith("registry order")
    # with the shipped table (whatever it holds): within COST_RESOLUTION of the cheapest listed cost
    for mod in (model, bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, sheen_color=0.3, sheen_roughness=0.5)):
        cfgs = configurations(mod, allow=())  # what simplify may reach: modelling knobs kept
        table = knob_costs().get("families", {}).get(family(mod), {}).get("costs", {})
        m, rep = bk.simplify(mod, math.inf, n=512, n_albedo=512)
        chosen = next(c for c in cfgs if c.model == m and c.dtype is rep.dtype)
        if table:
            cmin = min(table.get(c.key, 1.0) for c in cfgs)
            assert table.get(chosen.key, 1.0) <= cmin * (1 + COST_RESOLUTION)
        else:
            assert chosen.registry_rank == min(c.registry_rank for c in cfgs)


def test_equally_cheap_configurations_resolve_to_the_most_accurate():
    model = bk.Conductor.from_metal("Cu", alpha=0.3)
    costs = {"families": {family(model): {"costs": {c.key: (0.3 if c.dtype is np.float32 else 1.0)
                                                    for c in configurations(model)}}}}
    m, rep = bk.simplify(model, 1.0, n=512, n_albedo=512, costs=costs)
    # every float32 configuration costs the same: the exact Fresnel / correlated masking one wins
    assert (m.fresnel, m.masking, rep.dtype) == ("exact", "correlated", np.float32)


def test_lobe_dropping():
    small = bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, clear_coat=0.001, sheen_color=1e-5,
                                sheen_roughness=0.5)
    assert type(small._core).__name__ == "FilamentStandardCoatSheen"
    m, rep = bk.simplify(small, 1e-3, n=N, n_albedo=N_ALB)
    assert m.clear_coat == 0 and np.all(m.sheen_color == 0)
    assert type(m._core).__name__ == "FilamentStandard"          # the compiled variant without both lobes
    dropped = {k: why for k, a, b, why in rep.changes if "compiled variant" in why}
    assert set(dropped) == {"clear_coat", "sheen_color"}
    assert "clear_coat: 0.001 -> 0.0" in str(rep)
    # a strong coat stays, and so does a visible sheen at a tight tolerance
    strong = bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, clear_coat=1.0, clear_coat_roughness=0.2,
                                 sheen_color=0.3, sheen_roughness=0.5)
    m, rep = bk.simplify(strong, 1e-2, n=N, n_albedo=N_ALB)
    assert m.clear_coat == 1.0 and np.all(m.sheen_color == 0.3)
    assert {k for k, _ in rep.kept} >= {"clear_coat", "sheen"}
    # everything goes at a huge tolerance when it is cheaper (registry order: drop comes first)
    m, _ = bk.simplify(strong, 1e9, n=512, n_albedo=512, costs={})
    assert m.clear_coat == 0 and np.all(m.sheen_color == 0)


def test_simplify_is_deterministic_for_a_seed():
    model = bk.FilamentStandard([0.8, 0.5, 0.3], reflectance=0.1, clear_coat=0.003)
    a = bk.simplify(model, 1e-3, seed=4, n=N, n_albedo=N_ALB)
    b = bk.simplify(model, 1e-3, seed=4, n=N, n_albedo=N_ALB)
    assert a[0] == b[0] and a[1].dtype is b[1].dtype and a[1].error == b[1].error and str(a[1]) == str(b[1])
    t1 = bk.tradeoff(model, seed=4, n=N, n_albedo=N_ALB, measure=False)
    t2 = bk.tradeoff(model, seed=4, n=N, n_albedo=N_ALB, measure=False)
    assert t1["p99_err"] == t2["p99_err"] and t1["albedo_err"] == t2["albedo_err"]
    d1, d2 = direction_set(model, N, seed=4), direction_set(model, N, seed=5)
    np.testing.assert_array_equal(d1.wo, direction_set(model, N, seed=4).wo)
    assert not np.array_equal(d1.wo, d2.wo)


def test_direction_set_is_stratified_and_reaches_grazing():
    ds = direction_set(bk.Diffuse(0.5), 4096, seed=2)
    n_strat = 2048
    mu_o = ds.wo[:n_strat, 2]
    assert mu_o.min() < 2e-3 and mu_o.min() >= 1e-3 and mu_o.max() > 0.999
    counts = np.histogram(mu_o, bins=16, range=(1e-3, 1))[0]
    assert counts.min() == counts.max() == n_strat // 16                  # one per stratum
    glass = direction_set(bk.Dielectric(1.5, alpha=0.3), 2048, seed=2)
    assert (glass.wi[:1024, 2] < 0).sum() == 512 and (glass.wo[:1024, 2] < 0).sum() == 512
    assert (glass.albedo_wo[:, 2] < 0).sum() == len(ALBEDO_COS_THETA)


def test_float32_errors_use_float32_directions():
    model = bk.Dielectric(1.5, alpha=0.3)
    t = bk.tradeoff(model, n=N, n_albedo=N_ALB, measure=False)
    row = t[1]
    assert t.configs[1].dtype is np.float32 and row["dtype"] == "float32"
    ds = t.directions
    v64 = f_cos(model, np.float64, ds.wo, ds.wi)
    v32 = f_cos(model, np.float32, ds.wo, ds.wi)
    e = rel_err(v64, v32, t.floor)
    assert row["p99_err"] == pytest.approx(float(np.quantile(e, 0.99)), rel=1e-12)
    assert row["max_err"] > 1e-7


# ------------------------------------------------------------------ bad input

def test_bad_input_raises_naming_the_parameter():
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    for tol, exc in ((-1e-3, ValueError), (float("nan"), ValueError), ("1e-3", TypeError), (True, TypeError),
                     (None, TypeError)):
        with pytest.raises(exc, match="tol"):
            bk.simplify(m, tol)
    with pytest.raises(ValueError, match="metric"):
        bk.simplify(m, 1e-3, metric="median")
    for bad in ("Cu", None, 3.0, {"type": "conductor"}):
        with pytest.raises(TypeError, match="model"):
            bk.simplify(bad, 1e-3)
        with pytest.raises(TypeError, match="model"):
            bk.tradeoff(bad)
        with pytest.raises(TypeError, match="model"):
            bk.knobs(bad)
    with pytest.raises(ValueError, match="seed"):
        bk.simplify(m, 1e-3, seed=-1)
    with pytest.raises(ValueError, match="directions"):
        bk.tradeoff(m, directions=(np.zeros((4, 2)), np.zeros((4, 2))), measure=False)
    with pytest.raises(ValueError, match="directions"):
        bk.tradeoff(m, directions=(np.ones((4, 3)), np.ones((4, 3))), measure=False)   # not unit
    with pytest.raises(TypeError, match="directions"):
        bk.simplify(m, 1e-3, directions=np.ones((4, 3)))
    with pytest.raises(TypeError, match="costs"):
        bk.simplify(m, 1e-3, costs=[1, 2])
    with pytest.raises(TypeError, match="table"):
        pareto({"p99_err": [0]})
    t = bk.tradeoff(bk.Diffuse(0.5), n=64, n_albedo=64, measure=False)
    with pytest.raises(ValueError, match="metric"):
        pareto(t, metric="p50")


# ------------------------------------------------------------------ Table and plot

def test_table_renderers_and_conversions():
    t = bk.tradeoff(bk.Conductor.from_metal("Cu", alpha=0.3), n=512, n_albedo=512, n_timing=2048, repeats=1)
    assert isinstance(t, Table) and len(t) == 24 and t.measured
    recs = t.to_records()
    assert recs[0]["config"] == "most accurate" and recs[0]["speedup"] == 1.0
    assert all(r["evals_per_s"] > 0 and r["speedup"] > 0 for r in recs)
    assert recs[0]["pareto"]                                  # error 0: always on the front
    d = t.to_dict()
    assert list(d) == t.columns and all(len(v) == 24 for v in d.values())
    assert {"config", "fresnel", "masking", "dtype", "evals_per_s", "speedup", "expected_speedup", "max_err",
            "p99_err", "albedo_err", "pareto"} <= set(t.columns)
    text = str(t)
    assert all(r["config"] in text for r in recs) and "p99_err" in text.splitlines()[1]
    md = t._repr_markdown_()
    lines = md.splitlines()
    assert lines[2].startswith("| config |") and lines[3].startswith("|---") and len(lines) == 4 + 24
    html = t._repr_html_()
    assert html.count("<tr") == 1 + 24 and "<table>" in html and "Pareto" in html
    assert t["p99_err"] == d["p99_err"] and t[3] == recs[3]
    with pytest.raises(KeyError):
        t["nope"]
    if importlib.util.find_spec("pandas") is None:
        with pytest.raises(ImportError, match="pandas"):
            t.to_pandas()
    else:
        df = t.to_pandas()
        assert list(df.columns) == t.columns and len(df) == 24
    # a table without timing renders too
    u = bk.tradeoff(bk.Diffuse(0.5), n=64, n_albedo=64, measure=False)
    assert u["speedup"] == [None, None] and "—" in str(u) and "—" in u._repr_html_()


def test_pareto_plot_marks_the_front():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = bk.tradeoff(bk.Conductor.from_metal("Cu", alpha=0.3), n=512, n_albedo=512, measure=False,
                    costs=_synthetic_costs(bk.Conductor.from_metal("Cu", alpha=0.3), "x"))
    fig, ax = plt.subplots()
    out = pareto(t, ax=ax, metric="p99")
    assert out is ax
    data = ax.bsdfkit_data
    front = data["front"]
    assert front == t.pareto_front("p99") and 0 in front
    err, sp = data["error"], data["speedup"]
    for i in front:   # nothing dominates a front point
        assert not np.any((err <= err[i]) & (sp >= sp[i]) & ((err < err[i]) | (sp > sp[i])))
    for j in set(range(len(t))) - set(front):
        assert np.any((err <= err[j]) & (sp >= sp[j]) & ((err < err[j]) | (sp > sp[j])))
    assert ax.get_xscale() == "log"
    plt.close(fig)
    ax2 = pareto(t, metric="albedo")
    assert ax2.bsdfkit_data["metric"] == "albedo"
    plt.close(ax2.figure)


# ------------------------------------------------------------------ CLI

PBRT_SCENE = """# generated by tests/test_tradeoff.py
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
WorldBegin
MakeNamedMaterial "copper" "string type" "conductor" "spectrum eta" "metal-Cu-eta" "spectrum k" "metal-Cu-k"
    "float roughness" [0.1]
MakeNamedMaterial "gold mirror" "string type" "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
MakeNamedMaterial "brushed" "string type" "conductor" "rgb reflectance" [0.9 0.8 0.7]
    "float uroughness" [0.2] "float vroughness" [0.02]
MakeNamedMaterial "frosted glass" "string type" "dielectric" "float eta" [1.5] "float roughness" [0.05]
MakeNamedMaterial "window" "string type" "thindielectric"
MakeNamedMaterial "leaf" "string type" "diffusetransmission" "rgb reflectance" [0.2 0.5 0.1]
    "rgb transmittance" [0.3 0.6 0.1]
Material "diffuse" "rgb reflectance" [0.8 0.5 0.2]
Shape "sphere"
"""


def test_cli_simplify_prints_every_material(tmp_path):
    scene = tmp_path / "scene.pbrt"
    scene.write_text(PBRT_SCENE)
    names = list(bk.from_pbrt(PBRT_SCENE))
    assert len(names) == 7
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", str(scene), "--tol", "1e-3", "-n", "1024"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    out = r.stdout
    for name in names:
        assert name in out
    assert out.count("chosen:") == 7 and out.count("expected speedup") == 7
    assert out.count("error vs the material as given: p99") == 7 and out.count("tol met:") == 7
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", str(scene), "--tol", "-1"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "--tol" in r.stderr
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", str(tmp_path / "missing.pbrt")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "missing.pbrt" in r.stderr


# ------------------------------------------------------------------ simplify measures against the input (issue 11)

from bsdfkit.models import registry  # noqa: E402
from bsdfkit.models.spec import parse_spec  # noqa: E402

EXAMPLES = [pytest.param(spec, id=f"{cls.__name__}-{label}") for cls, label, spec in registry.examples()]


@pytest.mark.parametrize("spec", EXAMPLES)
def test_simplify_every_example_stays_within_tol_of_the_input(spec):
    """For every registered example: the simplified model's p99 error against the input (float64)
    on an unseen direction set is <= tol; modelling choices never change; the report lists every
    parameter that differs; the cheapest configuration comes back unchanged."""
    model = parse_spec(spec)
    if not all(c.model.exact_eval for c in configurations(model)):
        # stochastic configurations (a random walk per eval): simplify measures the RMS error against
        # the converged walk; within-tol on unseen directions is tested in tests/models/test_layered_tradeoff.py
        cheap, _ = bk.simplify(model, math.inf, n=64, n_albedo=32)
        again, rep = bk.simplify(cheap, 1e-3, n=64, n_albedo=32)
        assert again == cheap and rep.unchanged, rep.summary()
        return
    floor = max(independent_floor(model), 1e-30)   # a black material: absolute errors of zeros
    fresh = direction_set(model, N, seed=4242)
    modelling = [k.keyword for k in type(model).knobs if k.kind == "modelling"]
    for tol in (1e-2, 1e-3):
        m, rep = bk.simplify(model, tol, n=N, seed=0, n_albedo=N_ALB)
        p99 = errors_on(model, m, rep.dtype, fresh, floor)[1]
        assert p99 <= tol, (tol, rep.summary(), p99)
        for k in modelling:
            assert m._params[k] == model._params[k], k
        differ = {k for k, v in model._params.items() if not np.array_equal(np.asarray(v), np.asarray(m._params[k]))}
        assert {k for k, *_ in rep.changes if k != "precision"} == differ
        assert (("precision", "float64", "float32") in [c[:3] for c in rep.changes]) == (rep.dtype is np.float32)
    cheap, _ = bk.simplify(model, math.inf, n=512, n_albedo=512)
    again, rep = bk.simplify(cheap, 1e-3, n=512, n_albedo=512)
    assert again == cheap and rep.unchanged, rep.summary()


def test_simplify_keeps_modelling_choices_unless_allowed():
    # the README's example: a faint coat is dropped, Lambert stays Lambert
    model = bk.FilamentStandard(clear_coat=0.001)
    m, rep = bk.simplify(model, tol=1e-3, n=N, n_albedo=N_ALB)
    assert m.diffuse == "lambert" and m.clear_coat == 0.0
    assert ("diffuse", "'lambert'") in rep.fixed
    wo = bk.direction(np.radians(80.0), 0.0)
    a_in, a_out = model.albedo(wo, 1 << 16, seed=1), m.albedo(wo.astype(rep.dtype), 1 << 16, seed=1)
    assert np.abs(a_out - a_in).max() < 5e-3
    # a Mitsuba-style separable conductor stays separable
    sep = bk.Conductor.from_metal("Cu", alpha=0.3, masking="separable")
    for tol in (1e-2, 1.0, math.inf):
        m, rep = bk.simplify(sep, tol, n=512, n_albedo=512)
        assert m.masking == "separable" and "masking" not in {k for k, *_ in rep.changes}
    # allow= names the modelling knobs simplify may change
    m, rep = bk.simplify(model, math.inf, n=512, n_albedo=512, costs={}, allow=("diffuse",))
    assert rep.allow == ("diffuse",) and "diffuse" not in {k for k, _ in rep.fixed}
    with pytest.raises(ValueError, match="allow: 'fresnel' is not a modelling knob"):
        bk.simplify(sep, 1e-3, allow=("fresnel",))
    with pytest.raises(ValueError, match="modelling knobs: distribution, masking"):
        bk.simplify(sep, 1e-3, allow="diffuse")


# ------------------------------------------------------------------ a user's model as the reference (issue 11)

def _lambert(rho):
    return bk.Custom(f=lambda wo, wi: np.full(np.broadcast_shapes(wo.shape, wi.shape)[:-1] + (3,), rho / np.pi),
                     name=f"lambert {rho}")


def test_tradeoff_against_a_custom_reference():
    # closed form: Diffuse(0.5) against a user Lambert of 0.6 is off by 1/6 everywhere it reflects,
    # and its albedo (estimated with the reference's cosine samples, exact here) by 0.1
    t = bk.tradeoff(bk.Diffuse(0.5), reference=_lambert(0.6), n=N, n_albedo=N_ALB, measure=False)
    assert t.external_reference is t.reference and t.reference.name == "lambert 0.6"
    assert "errors vs Custom" in str(t) or "errors vs lambert 0.6" in str(t)
    for cfg, row in zip(t.configs, t.to_records()):
        tol = 1e-12 if cfg.dtype is np.float64 else 1e-7
        assert row["max_err"] == pytest.approx(1 / 6, abs=tol)
        assert row["albedo_err"] == pytest.approx(0.1, abs=tol)
    np.testing.assert_allclose(t.reference_albedo, 0.6, rtol=1e-12)
    # a Custom wrapping the most accurate configuration's own eval: the same pointwise errors as the
    # default reference (same direction set, drawn from the model)
    m = bk.Conductor.from_metal("Cu", alpha=0.3, fresnel="schlick")
    exact = bk.Conductor.from_metal("Cu", alpha=0.3)
    c = bk.Custom(f=lambda wo, wi: exact.eval(np.ascontiguousarray(wo), np.ascontiguousarray(wi)), name="exact Cu")
    t0 = bk.tradeoff(m, n=N, n_albedo=N_ALB, measure=False)
    t1 = bk.tradeoff(m, reference=c, n=N, n_albedo=N_ALB, measure=False)
    assert t0.external_reference is None
    for r0, r1 in zip(t0.to_records(), t1.to_records()):
        assert (r1["max_err"], r1["p99_err"]) == (r0["max_err"], r0["p99_err"])


def test_custom_reference_refused_against_delta_lobes_and_simplify_of_custom():
    with pytest.raises(ValueError, match="reference: Dielectric has specular"):
        bk.tradeoff(bk.Dielectric(1.5), reference=_lambert(0.5), n=N, n_albedo=N_ALB, measure=False)
    with pytest.raises(TypeError, match="reference"):
        bk.tradeoff(bk.Diffuse(0.5), reference="lambert", n=N, n_albedo=N_ALB, measure=False)
    # simplify's reference is its input: a Custom model as the input is its own reference
    c = _lambert(0.5)
    out, rep = bk.simplify(c, 1e-3, n=N, n_albedo=N_ALB)
    assert out == c and rep.error["p99"] <= 1e-3
