"""bk.albedo_table (issue 49 item 5): E(mu) / E_avg tables with their own error bounds, against an
independent float64 integration written here from the papers (not from bsdfkit's C++)."""
import json

import numpy as np
import pytest
from scipy.stats import binom

import bsdfkit as bk
from bsdfkit import compensation


def white(alpha):
    """A white GGX metal: Schlick with F0 = k^2 / (4 + k^2) = 1 - 4e-8 (eta = 1, k = 1e4), so F >= 1 - 4e-8."""
    return bk.Conductor(1.0, 1e4, alpha=alpha, fresnel="schlick")


def lam(c, alpha):
    """Smith Lambda of GGX (Heitz 2014, "Understanding the masking-shadowing function", eq. 86)."""
    c = np.clip(c, 1e-300, 1.0)
    return (-1 + np.sqrt(1 + alpha ** 2 * (1 - c * c) / (c * c))) / 2


def ref_E(mus, alpha, n=256):
    """E(mu) = integral f cos_i dwi of GGX with F = 1 and height-correlated G2 = 1 / (1 + L(wo) + L(wi))
    (Heitz 2014 eq. 99), for each mu of ``mus``: with wi = reflect(wo, h), dwi = 4 (wo.h) dwh (Walter
    2007 eq. 14) and f cos_i = D G2 / (4 cos_o), E = integral D(h) cos_h [G2 (wo.h) / (cos_o cos_h)] dwh.
    The GGX measure D cos_h dwh becomes du1 du2 under tan^2 theta_h = alpha^2 u1 / (1 - u1),
    phi_h = 2 pi u2 (Walter 2007 eq. 35-36), integrated by an n x n Gauss-Legendre rule in float64."""
    x, w = np.polynomial.legendre.leggauss(n)
    u, w = 0.5 * (x + 1), 0.5 * w
    ww = np.outer(w, w).ravel()
    u1, u2 = (a.ravel() for a in np.meshgrid(u, u, indexing="ij"))
    t2 = alpha ** 2 * u1 / (1 - u1)
    ch = 1 / np.sqrt(1 + t2)
    hx = np.sqrt(t2) * ch * np.cos(2 * np.pi * u2)
    out = []
    for mu in np.atleast_1d(mus):
        oh = hx * np.sqrt(1 - mu * mu) + ch * mu        # wo = (sin, 0, cos)
        ci = 2 * oh * ch - mu                           # (reflect(wo, h)).z
        with np.errstate(divide="ignore"):
            g2 = 1 / (1 + lam(mu, alpha) + lam(ci, alpha))
        out.append(ww @ np.where((oh > 0) & (ci > 0), g2 * oh / (mu * ch), 0.0))
    return np.array(out)


def ref_E_avg(alpha, n=40):
    """2 integral_0^1 E(mu) mu dmu by Gauss-Legendre over mu."""
    x, w = np.polynomial.legendre.leggauss(n)
    mu = 0.5 * (x + 1)
    return float(np.sum(0.5 * w * 2 * mu * ref_E(mu, alpha, 192)))


def test_reference_is_converged():
    # the quadrature itself: two orders agree 100x below the Monte Carlo errors tested
    assert abs(ref_E(0.3, 0.6)[0] - ref_E(0.3, 0.6, 384)[0]) < 1e-5
    assert abs(ref_E(0.05, 1.0)[0] - ref_E(0.05, 1.0, 384)[0]) < 3e-5
    assert abs(ref_E_avg(1.0) - ref_E_avg(1.0, 56)) < 1e-5


@pytest.fixture(scope="module")
def table():
    return bk.albedo_table(white, grid={"alpha": [0.25, 0.5, 0.75, 1.0], "mu": 16}, n_samples=1 << 14,
                           channel="mean", cache=False, progress=False)


def test_white_conductor_against_reference(table):
    assert table.axes == ("alpha", "mu") and table.E.shape == (4, 16)
    ref = np.array([ref_E(table.grid["mu"], a) for a in table.grid["alpha"]])
    err = np.abs(table.E - ref)
    z = err / table.E_se
    assert np.all(z < 4.5), z.max()                       # no gross error anywhere
    # the bound covers the error in most entries: at 95 % per entry, 64 entries, at least 55 covered
    # fails by chance with probability binom.cdf(54, 64, 0.95) ~ 0.2 % (for this fixed seed: never)
    covered = int(np.sum(err <= table.E_err))
    assert binom.cdf(54, 64, 0.95) < 0.005
    assert covered >= 55, (covered, err.max())
    # and is not vacuous: the bounds are within a factor ~2.5 of the typical error
    assert np.median(table.E_err) < 2.5 * 2 * np.median(err) + 1e-4


def test_E_avg_against_reference(table):
    ref = np.array([ref_E_avg(a) for a in table.grid["alpha"]])
    assert np.all(np.diff(ref) < 0) and 0.3 < ref[-1] < ref[0] < 1      # rougher loses more
    assert np.all(np.abs(table.E_avg - ref) <= 1.5 * table.E_avg_err), (table.E_avg - ref, table.E_avg_err)
    assert np.all(np.abs(table.E_avg_quad - ref) <= 1.5 * table.E_avg_quad_err), (table.E_avg_quad - ref,
                                                                                 table.E_avg_quad_err)
    assert np.all(table.E_avg_err < 0.02) and np.all(table.E_avg_quad_err < 0.02)


def test_lambertian_is_exact():
    r = [0.2, 0.5, 0.8]
    t = bk.albedo_table(bk.Diffuse(r), grid={"mu": [0.1, 0.5, 0.9, 1.0]}, n_samples=256, cache=False)
    assert t.axes == ("mu", "channel") and t.E.shape == (4, 3)
    np.testing.assert_allclose(t.E, np.broadcast_to(r, (4, 3)), rtol=0, atol=1e-12)
    assert np.all(t.E_err < 1e-12) and np.all(t.E_se < 1e-12)
    np.testing.assert_allclose(t.E_avg, r, atol=1e-12)
    np.testing.assert_allclose(t.E_avg_quad, r, atol=1e-12)
    assert np.all(t.E_avg_quad_err < 1e-12)


def test_smooth_furnace_and_dielectric_axes():
    # a smooth white mirror and a smooth dielectric in importance mode (R + T = 1): E = 1 exactly;
    # three axes, in the grid's order
    t = bk.albedo_table(bk.Dielectric, grid={"eta": [1.33, 1.5], "alpha": [0.0, 0.3], "mu": 8},
                        mode="importance", channel=1, n_samples=2048, cache=False)
    assert t.E.shape == (2, 2, 8) and t.E_avg.shape == (2, 2) and t.axes == ("eta", "alpha", "mu")
    np.testing.assert_allclose(t.E[:, 0], 1.0, atol=1e-6)
    np.testing.assert_allclose(t.E_avg[:, 0], 1.0, atol=1e-6)
    assert np.all(t.E[:, 1] <= 1 + t.E_err[:, 1]) and np.all(t.E[:, 1] > 0.8)
    assert "Dielectric(eta=1.33" in t.info["models"][0]
    m = bk.albedo_table(white(0.0), grid={"mu": 5}, n_samples=64, cache=False)
    np.testing.assert_allclose(m.E, 1.0, atol=1e-7)


def test_tol_reached_and_not_reached():
    t = bk.albedo_table(white(0.8), grid={"mu": 6}, n_samples=1 << 12, tol=4e-3, channel="mean", cache=False)
    assert t.converged and t.E_err.max() <= 4e-3 and t.E_avg_err <= 4e-3
    assert t.n_samples.max() > 1 << 12                   # it had to sample more
    with pytest.warns(RuntimeWarning, match="tol=1e-05 not reached"):
        u = bk.albedo_table(white(0.8), grid={"mu": 4}, n_samples=1 << 10, tol=1e-5, max_samples=1 << 13,
                            channel="mean", cache=False)
    assert not u.converged and "NOT reached" in u.report()
    assert u.n_samples.max() <= 1 << 13


def test_cached_table_warns_again(tmp_path):
    kw = dict(grid={"mu": 4}, n_samples=1 << 10, tol=1e-5, max_samples=1 << 12, cache=tmp_path)
    with pytest.warns(RuntimeWarning, match="not reached"):
        bk.albedo_table(white(0.5), **kw)
    with pytest.warns(RuntimeWarning, match="cached.*not reached"):
        bk.albedo_table(white(0.5), **kw)


def test_cache_hit_without_recomputation(tmp_path, monkeypatch):
    calls = []
    real = compensation._albedo
    monkeypatch.setattr(compensation, "_albedo", lambda *a: calls.append(1) or real(*a))
    monkeypatch.delenv("BSDFKIT_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    kw = dict(grid={"alpha": [0.3, 0.6], "mu": 4}, n_samples=1024)
    a = bk.albedo_table(white, **kw)
    n = len(calls)
    assert n > 0 and len(list((tmp_path / "xdg" / "bsdfkit" / "albedo-tables").glob("*.npz"))) == 1
    b = bk.albedo_table(white, **kw)
    assert len(calls) == n                               # no compiled call: read from the cache
    for k in compensation.AlbedoTable._ARRAYS:
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k))
    assert b.axes == a.axes and b.info["key"] == a.info["key"]
    # the key is the content: another parameter value, sample count or a relocated cache computes
    bk.albedo_table(lambda alpha: white(alpha + 0.01), **kw)
    assert len(calls) > n
    n = len(calls)
    bk.albedo_table(white, **kw, cache=tmp_path / "elsewhere")
    assert len(calls) > n and len(list((tmp_path / "elsewhere").glob("*.json"))) == 1
    n = len(calls)
    bk.albedo_table(white, **kw, cache=False)
    assert len(calls) > n


def test_export_layout(tmp_path):
    t = bk.albedo_table(white, grid={"alpha": 3, "mu": 5}, n_samples=512, channel="mean", cache=False)
    npy, avg, npz, js = t.save(tmp_path / "ggx_E")
    e = np.load(npy)
    assert e.dtype == np.float32 and e.shape == (3, 5)
    np.testing.assert_allclose(e, t.E, rtol=1e-6)
    np.testing.assert_allclose(np.load(avg), t.E_avg, rtol=1e-6)
    meta = json.load(open(js))
    assert meta["axes"] == ["alpha", "mu"] and meta["shape"] == [3, 5]
    np.testing.assert_allclose(meta["grid"]["mu"], (np.arange(5) + 0.5) / 5)
    np.testing.assert_allclose(meta["grid"]["alpha"], (np.arange(3) + 0.5) / 3)
    assert meta["E_avg_axes"] == ["alpha"] and len(meta["E_avg_values"]) == 3
    back = bk.AlbedoTable.load(npy)
    np.testing.assert_array_equal(back.E, t.E)
    np.testing.assert_array_equal(back.E_avg_err, t.E_avg_err)


def test_progress_and_interrupt(monkeypatch):
    seen = []
    bk.albedo_table(white, grid={"alpha": [0.2, 0.4], "mu": 4}, n_samples=256, cache=False,
                    progress=lambda d, t, s: seen.append((d, t, s)))
    assert seen and seen[-1][0] == seen[-1][1] and seen[-1][2] == "samples"
    calls = []
    real = compensation._albedo

    def stop(*a):
        calls.append(1)
        if len(calls) == 3:            # E and E_avg of the first model done, then Ctrl-C
            raise KeyboardInterrupt
        return real(*a)

    monkeypatch.setattr(compensation, "_albedo", stop)
    with pytest.warns(RuntimeWarning, match="interrupted"):
        t = bk.albedo_table(white, grid={"alpha": [0.2, 0.4], "mu": 4}, n_samples=256, cache=False,
                            interrupt="return")
    assert np.all(np.isfinite(t.E[0])) and np.all(np.isnan(t.E[1])) and not t.converged
    calls.clear()
    with pytest.raises(KeyboardInterrupt) as ei:
        bk.albedo_table(white, grid={"alpha": [0.2, 0.4], "mu": 4}, n_samples=256, cache=False)
    assert isinstance(ei.value.table, bk.AlbedoTable)


@pytest.mark.parametrize("kwargs, match", [
    (dict(model=white(0.3), grid={"alpha": 4}), "grid: needs the 'mu' axis"),
    (dict(model=white(0.3), grid=[0.1, 0.2]), "grid: expected a dict"),
    (dict(model=white(0.3), grid={"mu": [0.0, 0.5, 1.0]}), "grid: axis 'mu'"),
    (dict(model=white(0.3), grid={"mu": [0.5, 0.2, 1.0]}), "grid: axis 'mu'"),
    (dict(model=white(0.3), grid={"mu": 2}), r"grid\['mu'\]"),
    (dict(model=white(0.3), grid={"mu": 8, "alpha": 4}), "grid: a fixed model takes only"),
    (dict(model=white, grid={"mu": 8, "eta": 4}), "grid: axis 'eta' takes explicit values"),
    (dict(model=white, grid={"mu": 8, "alpha": [-0.1]}), "grid: building the model"),
    (dict(model=white(0.3), tol=-1e-3), "tol: must be"),
    (dict(model=white(0.3), tol=0), "tol: must be"),
    (dict(model=white(0.3), n_samples=0), "n_samples: must be"),
    (dict(model=white(0.3), channel="r"), "channel: must be"),
    (dict(model=white(0.3), mode="both"), "mode: must be"),
    (dict(model=white(0.3), params={"k": 1}), "params: only with a model class"),
    (dict(model=bk.Conductor, grid={"mu": 4, "alpha": 2}, params={"eta": 1, "k": 1e4, "alpha": 0.1}),
     "params: .*grid axes"),
])
def test_bad_input_names_the_parameter(kwargs, match):
    with pytest.raises(ValueError, match=match):
        bk.albedo_table(**{"n_samples": 64, **kwargs}, cache=False)


@pytest.mark.parametrize("model, match", [("Cu", "model: expected"), (dict, "model: expected"),
                                          (lambda alpha: 3, "model: the callable returned int")])
def test_non_model_raises(model, match):
    with pytest.raises(TypeError, match=match):
        bk.albedo_table(model, grid={"mu": 4, "alpha": [0.2]} if callable(model) and not isinstance(model, type)
                        else {"mu": 4}, cache=False)
