"""bk.fit_texels (issue 47 item 4): per-texel parameters fitted from observations, vectorized
across texels. Synthetic ground truth: T texels of true parameters, M random direction pairs each,
observations from the true per-texel models (numpy per-element parameters, checked elsewhere to
equal a loop of uniform models) with multiplicative Gaussian noise of known sigma."""
import re

import numpy as np
import pytest

import bsdfkit as bk

T, M = 300, 40


def _dirs(rng, T, M):
    u = rng.random((2, T, M, 2))
    th = np.arccos(np.sqrt(1 - 0.95 * u[..., 0]))     # cos theta in [0.22, 1]
    ph = 2 * np.pi * u[..., 1]
    w = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    return w[0], w[1]


def _case(name, rng, T):
    """(family, true params {name: (T,) or (T, 3)}, fitted names, fixed per texel, fit keywords)."""
    if name == "Diffuse":
        return bk.Diffuse, {"reflectance": rng.uniform(0.1, 0.9, (T, 3))}, ["reflectance"], {}, {}
    if name == "Conductor":   # eta per texel known (held), k and alpha fitted. Below eta ~ 0.3 a second
        # minimum near k = 0 traps some texels from the one start (bk.fit too; starts= helps)
        eta = rng.uniform(0.5, 1.5, (T, 3))
        return (bk.Conductor, {"k": rng.uniform(2, 4, (T, 3)), "alpha": rng.uniform(0.1, 0.6, T)}, ["k", "alpha"],
                {"eta": eta}, {})
    if name == "FilamentStandard":   # 4 starts: one start stalls at a bound on a few texels of 300
        return (bk.FilamentStandard, {"base_color": rng.uniform(0.1, 0.9, (T, 3)),
                                      "roughness": rng.uniform(0.3, 0.9, T), "metallic": rng.uniform(0.1, 0.9, T)},
                ["base_color", "roughness", "metallic"], {}, {"starts": 4})
    raise KeyError(name)


def _truth_model(family, truth, fixed):
    q = {k: (v[:, None] if v.ndim == 1 else v[:, None, :]) for k, v in {**truth, **fixed}.items()}
    if family is bk.Conductor:
        return bk.Conductor(q["eta"], q["k"], alpha=q["alpha"])
    return family(**q)


def _synth(name, sigma, seed, T=T):
    rng = np.random.default_rng(seed)
    family, truth, params, fixed, kw = _case(name, rng, T)
    wo, wi = _dirs(rng, T, M)
    f = _truth_model(family, truth, fixed).eval(wo, wi)
    values = f * (1 + sigma * rng.standard_normal(f.shape))
    return family, truth, params, fixed, kw, wo, wi, values


CASES = ("Diffuse", "Conductor", "FilamentStandard")


@pytest.mark.parametrize("name", CASES)
def test_noiseless_recovers_the_parameters(name):
    family, truth, params, fixed, kw, wo, wi, values = _synth(name, 0.0, 1)
    res = bk.fit_texels(family, wo, wi, values, params=params, fixed=fixed or None, **kw)
    assert res.converged.all()
    for p in params:
        rel = np.abs(res.params[p] - truth[p]) / truth[p]
        assert rel.max() < 1e-6, (p, rel.max(), np.argmax(rel.reshape(T, -1).max(1)))
        assert res.params[p].shape == truth[p].shape == res.errors[p].shape
    assert res.rms.max() < 1e-6
    # the fitted model: one model with per-element arrays (T,) / (T, 3); texel i's row is the
    # uniform model of texel i's fitted values
    f = res.model.eval(wo[:, 0], wi[:, 0])
    for i in (0, 7, T - 1):
        one = {k: v[i] for k, v in {**res.params, **{k: v for k, v in fixed.items()}}.items()}
        m = bk.Conductor(one["eta"], one["k"], alpha=one["alpha"]) if family is bk.Conductor else family(**one)
        np.testing.assert_array_equal(f[i], m.eval(wo[i, 0], wi[i, 0]))


@pytest.mark.parametrize("name", CASES)
def test_coverage_of_the_95_percent_intervals(name):
    # A statistical test with a fixed seed: with 2 % multiplicative noise and the log loss, the
    # residuals are close to i.i.d. normal, so about 95 % of the true parameters lie within
    # +-1.96 standard errors. Binomial s.d. of the fraction: 1.3 % over 300 texels (0.7 % over
    # 900 RGB entries): [0.90, 0.99] is a wide band around 0.95.
    family, truth, params, fixed, kw, wo, wi, values = _synth(name, 0.02, 2)
    res = bk.fit_texels(family, wo, wi, values, params=params, fixed=fixed or None, **kw)
    assert res.converged.all()
    assert 0.015 < np.median(res.rms) < 0.025     # the noise level, seen through the log loss
    for p in params:
        inside = np.abs(res.params[p] - truth[p]) <= 1.96 * res.errors[p]
        assert 0.90 <= inside.mean() <= 0.99, (p, inside.mean())


@pytest.mark.parametrize("name", ("Conductor", "FilamentStandard"))
def test_equals_a_loop_of_bk_fit(name):
    family, truth, params, fixed, kw, wo, wi, values = _synth(name, 0.02, 3, T=6)
    init = {p: np.clip(v * 1.15, 0.05, 0.95) if family is bk.FilamentStandard else v * 1.15 for p, v in truth.items()}
    res = bk.fit_texels(family, wo, wi, values, params=params, fixed=fixed or None, init=init)
    assert res.converged.all()
    for i in range(6):
        one = lambda d: {k: v[i] for k, v in d.items()}  # noqa: E731
        _, rep = bk.fit((wo[i], wi[i], values[i]), family, params=params, init=one(init), fixed=one(fixed) or None,
                        loss="log")
        assert rep.success
        for j, c in enumerate(res.columns):   # two different optimizers, one minimum
            np.testing.assert_allclose(res.x[i, j], rep.params[c], rtol=1e-4, err_msg=f"texel {i} {c}")


def test_dask_chunks_are_bit_identical():
    distributed = pytest.importorskip("distributed")
    family, truth, params, fixed, kw, wo, wi, values = _synth("FilamentStandard", 0.02, 4, T=120)
    kw = dict(params=params, starts=2)
    ref = bk.fit_texels(family, wo, wi, values, **kw)
    chunked = bk.fit_texels(family, wo, wi, values, chunk=50, **kw)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cl, \
            distributed.Client(cl) as client:
        dask = bk.fit_texels(family, wo, wi, values, chunk=32, client=client, **kw)
    for r in (chunked, dask):
        for k in ("x", "stderr", "covariance", "rms", "cost", "converged", "iterations", "n_obs"):
            np.testing.assert_array_equal(getattr(r, k), getattr(ref, k), err_msg=k)
        assert r.model == ref.model


def test_weights_and_loss_linear():
    family, truth, params, fixed, kw, wo, wi, values = _synth("Diffuse", 0.0, 5, T=20)
    values = values.copy()
    values[:, 0] *= 3.0                            # one corrupted pair per texel, weighted out
    w = np.ones((20, M))
    w[:, 0] = 0
    for loss in ("log", "linear", "relative"):
        res = bk.fit_texels(family, wo, wi, values, weights=w, loss=loss)
        np.testing.assert_allclose(res.params["reflectance"], truth["reflectance"], rtol=1e-6)
        assert (res.n_obs == 3 * (M - 1)).all()
    assert re.search(r"converged\s+20/20", res.summary())


def test_bad_input_names_the_argument():
    family, truth, params, fixed, kw, wo, wi, values = _synth("Diffuse", 0.0, 6, T=4)
    fit = bk.fit_texels
    with pytest.raises(ValueError, match="values: expected shape"):
        fit(bk.Diffuse, wo, wi, values[0])
    with pytest.raises(ValueError, match="wo, wi, values: shapes"):
        fit(bk.Diffuse, wo[:, :3], wi, values)
    with pytest.raises(ValueError, match=r"wi: 1 direction\(s\) are not finite unit vectors, first at index \(2, 5\)"):
        bad = wi.copy()
        bad[2, 5] *= 2
        fit(bk.Diffuse, wo, bad, values)
    with pytest.raises(ValueError, match=r"values: must be finite and >= 0; first bad entry at index \(1, 0, 2\)"):
        bad = values.copy()
        bad[1, 0, 2] = np.nan
        fit(bk.Diffuse, wo, wi, bad)
    with pytest.raises(ValueError, match="params: 'roughness' is not a differentiable parameter of Diffuse"):
        fit(bk.Diffuse, wo, wi, values, params=["roughness"])
    with pytest.raises(ValueError, match="loss: must be one of"):
        fit(bk.Diffuse, wo, wi, values, loss="l1")
    with pytest.raises(ValueError, match="weights: shape"):
        fit(bk.Diffuse, wo, wi, values, weights=np.ones(7))
    with pytest.raises(ValueError, match=r"init: 'reflectance' must be uniform \(3,\) or per texel \(4, 3\)"):
        fit(bk.Diffuse, wo, wi, values, init={"reflectance": np.ones((5, 3)) * 0.5})
    with pytest.raises(ValueError, match="fixed: alpha_x, alpha_y also fitted"):
        fit(bk.Conductor, wo, wi, values, params=["alpha"], fixed={"alpha": np.full(4, 0.3)})
    with pytest.raises(ValueError, match="max_iter: must be an integer >= 1"):
        fit(bk.Diffuse, wo, wi, values, max_iter=0)
    with pytest.raises(ValueError, match="chunk: must be an integer >= 1"):
        fit(bk.Diffuse, wo, wi, values, chunk=0)
    with pytest.raises(ValueError, match="starts: must be an integer >= 1"):
        fit(bk.Diffuse, wo, wi, values, starts=0)
    with pytest.raises(TypeError, match="family: expected a model class"):
        fit("Diffuse", wo, wi, values)
    with pytest.raises(TypeError, match="client: expected a dask.distributed.Client"):
        fit(bk.Diffuse, wo, wi, values, client=42)
