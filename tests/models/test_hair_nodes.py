"""The far-field fibre's quadrature order (Hair(h=None, nodes=N)): against an independent fine
integration over h of the single-h fibre, convergence with N, the trade-off knob, bad input."""
import math

import numpy as np
import pytest

import bsdfkit as bk

LUM = np.array([0.2126, 0.7152, 0.0722])


def dirs(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def far_field_reference(kw, wo, wi, m=2000):
    """(1/2) int_{-1}^{1} f(h) dh by the midpoint rule in gamma = asin h (dh = cos gamma dgamma)
    with ``m`` points, from the single-h model."""
    g = (np.arange(m) + 0.5) / m * math.pi - math.pi / 2
    w = np.cos(g) * (math.pi / m) / 2
    acc = 0.0
    for gk, wk in zip(g, w):
        acc = acc + wk * bk.Hair(h=math.sin(gk), **kw).eval(wo, wi)
    return acc


# max |error| / peak of f |cos| bound per node count (measured at 4000 midpoints: beta_n 0.5:
# 16 -> 4.6e-4, 32 -> 5.8e-7; beta_n 0.3: 16 -> 3.1e-2, 32 -> 8.2e-4, 64 -> 8.5e-7)
@pytest.mark.parametrize("beta_n, bounds", [(0.5, {16: 1e-3, 32: 2e-6, 64: 1e-6}),
                                            (0.3, {16: 0.05, 32: 2e-3, 64: 3e-6})])
def test_far_field_converges_to_the_integral_over_h(beta_n, bounds):
    kw = dict(sigma_a=[0.3, 0.6, 1.2], beta_m=0.3, beta_n=beta_n, alpha=2.0)
    wo, wi = dirs(300, 1), dirs(300, 2)
    ref = far_field_reference(kw, wo, wi) * np.abs(wi[:, 2:3])
    peak = ref.max()
    errs = {}
    for n in (4, 8, 16, 32, 64):
        v = bk.Hair(h=None, nodes=n, **kw).eval(wo, wi) * np.abs(wi[:, 2:3])
        errs[n] = np.abs(v - ref).max() / peak
    for n, b in bounds.items():
        assert errs[n] < b, (n, errs[n])
    assert errs[4] > errs[8] > errs[16] > errs[32] > errs[64]
    assert errs[4] > 0.1   # 4 nodes visibly miss the azimuthal lobes


def test_nodes_do_not_change_a_single_h_fibre():
    wo, wi = dirs(50, 3), dirs(50, 4)
    a = bk.Hair(h=0.3).eval(wo, wi)
    b = bk.Hair(h=0.3, nodes=4).eval(wo, wi)
    np.testing.assert_array_equal(a, b)


def test_sampling_stays_consistent_for_any_order():
    m = bk.Hair(sigma_a=0.0, h=None, nodes=7)
    wo = np.array([0.3, 0.4, math.sqrt(1 - 0.25)])
    s = m.sample(wo, n=4000, seed=3)
    ok = s.valid
    np.testing.assert_allclose(s.f[ok], m.eval(wo, s.wi[ok]), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(s.pdf[ok], m.pdf(wo, s.wi[ok]), rtol=1e-9, atol=1e-12)
    # sigma_a = 0: the weight f |cos| / pdf is 1 (a mixture of exactly sampled fibres)
    np.testing.assert_allclose(s.weight[ok] @ LUM, 1.0, rtol=2e-6)


def test_repr_round_trip_and_bad_nodes():
    m = bk.Hair(h=None, nodes=32)
    assert eval(repr(m), {"Hair": bk.Hair}) == m and m != bk.Hair(h=None)
    assert "nodes" not in repr(bk.Hair(h=None))
    for bad in (0, 65, 2.5, True, "16", None):
        with pytest.raises(ValueError, match="nodes"):
            bk.Hair(h=None, nodes=bad)


def test_nodes_is_a_tradeoff_knob_of_the_far_field_fibre_only():
    k = {x.name: x for x in bk.knobs(bk.Hair(h=None, beta_n=0.2))}
    assert k["nodes"].reachable and k["nodes"].settings == (64, 32, 16, 8, 4)
    k1 = {x.name: x for x in bk.knobs(bk.Hair(h=0.2))}
    assert not k1["nodes"].reachable
    t = bk.tradeoff(bk.Hair(h=None, beta_n=0.2), n=512, seed=0, measure=False)
    rec = {(r["nodes"], r["dtype"]): r for r in t.to_records()}
    assert rec[("64", "float64")]["max_err"] == 0
    assert rec[("4", "float64")]["p99_err"] > rec[("16", "float64")]["p99_err"] > rec[("32", "float64")]["p99_err"]
    m, rep = bk.simplify(bk.Hair(h=None, beta_n=0.2), 1e-1, seed=0, n=512)
    assert isinstance(m, bk.Hair) and m.h is None and rep.error["p99"] <= 1e-1
