"""eval_grad of Plastic (smooth and rough coats), against Dr.Jit forward-mode AD of an independent
float64 reference (bsdfkit.testing.plastic_ref.plastic_f, whose rough-coat tables are computed
from the seeded alpha and eta with Dr.Jit, through bsdfkit.testing.drjit_grad.plastic_grad) and
against central finite differences of our own eval, on 12,000 pairs per case: grazing wo down to
cos 1e-4 on both sides (two-sided model), lobe samples and uniform directions; smooth, rough,
near-smooth (alpha just above the 1e-3 switch), very rough, eta < 1, nonlinear, separable masking."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing.drjit_grad import plastic_grad
from test_grad_more import N, _fd, _fd_check, _grad_and_ref, _pairs, _rel_err, _report

ALL = ("reflectance", "eta", "alpha", "specular_reflectance")

CASES = {
    "smooth": (lambda: bk.Plastic((0.8, 0.1, 0.1), eta=1.49), ALL),
    "smooth-nonlinear-eta-below-1": (lambda: bk.Plastic((0.3, 0.6, 0.9), eta=0.9, nonlinear=True,
                                                        specular_reflectance=(0.5, 0.8, 1.0)), ALL),
    "rough": (lambda: bk.Plastic((0.8, 0.1, 0.1), alpha=0.2, specular_reflectance=(0.9, 1.0, 0.8)), ALL),
    "near-smooth": (lambda: bk.Plastic((0.5, 0.4, 0.3), eta=1.5, alpha=1.2e-3, nonlinear=True),
                    ("reflectance", "eta", "alpha")),
    "rough-eta-below-1-separable": (lambda: bk.Plastic((0.2, 0.5, 0.3), eta=0.7, alpha=0.3, masking="separable",
                                                       specular_reflectance=(0.5, 0.8, 1.0)), ALL),
    "very-rough": (lambda: bk.Plastic(0.6, eta=2.2, alpha=0.9), ("reflectance.g", "eta", "alpha")),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_plastic_grad(name, rng):
    make, params = CASES[name]
    model = make()
    wo, wi, f, g, names, f_ref, g_ref = _grad_and_ref(model, params, rng, True, plastic_grad)
    err_f = _rel_err(f[..., None], f_ref[..., None])
    assert np.quantile(err_f, 0.99) < 1e-11 and err_f.max() < 1e-9, (np.quantile(err_f, 0.99), err_f.max())
    # per-channel columns are 0 in the other channels; eta < 1 from outside: T = 0 below the
    # critical cosine (0.44 at eta 0.9), where most of the grazing-heavy wo lie
    assert np.count_nonzero(g_ref) > g_ref.size // (40 if model.eta < 1 else 8)
    if model.alpha < 1e-3 and "alpha" in names:      # smooth coat: f does not depend on alpha
        k = names.index("alpha")
        assert not np.any(g[..., k]) and not np.any(g_ref[..., k])
    err = _rel_err(g, g_ref)
    _report("plastic-" + name, "Dr.Jit AD", err)
    assert np.quantile(err, 0.99) < 1e-9 and err.max() < 1e-6, (np.quantile(err, 0.99), err.max())
    # central differences of our eval: the columns that do not reach the rough coat's tables with
    # the usual step; alpha and eta of a rough coat (the tables' quadratures: kinks per node,
    # fitting.grad's docstring, which steps of 1e-6 straddle) with h = 1e-8 theta, whose rounding
    # is that of f summed over the quadrature's 1024-16384 nodes (1024 eps |f| / h)
    # (smooth coat: alpha's column is 0, checked above; differences would leave alpha >= 0)
    table = [n for n in names if n in ("eta", "alpha")] if model.alpha >= 1e-3 else []
    plain = [n for n in names if n not in table and not (n == "alpha" and model.alpha < 1e-3)]
    if plain:
        k = [names.index(n) for n in plain]
        _fd_check("plastic-" + name, g[..., k], _fd(model, wo, wi, plain), f, tol=1e-5)
    if table:
        k = [names.index(n) for n in table]
        fd, h = _fd(model, wo, wi, table, rel_step={"eta": 1e-8, "alpha": 1e-8})
        _fd_check("plastic-" + name + " (alpha, eta: h = 1e-8 theta)", g[..., k], (fd, h), f, tol=1e-4,
                  noise_eps=1024, min_clean=0.0)


def test_plastic_grad_fields_and_default_columns():
    m = bk.Plastic(0.5, alpha=0.1)
    assert bk.fitting.differentiable_params(m) == ALL
    assert bk.fitting.grad_columns(m) == ("reflectance.r", "reflectance.g", "reflectance.b", "eta", "alpha",
                                          "specular_reflectance.r", "specular_reflectance.g",
                                          "specular_reflectance.b")
    f, g = m.eval_grad(bk.direction(0.6, 0.0), bk.direction(0.8, 2.0))
    assert f.shape == (3,) and g.shape == (3, 8) and np.all(np.isfinite(g))


def test_plastic_reflectance_derivative_is_closed_form(rng):
    """d f / d R_c of the linear (nonlinear=False) base term is f_diffuse_c / R_c and does not
    touch the other channels; Ks's derivative is the coat lobe, the same in every channel."""
    m = bk.Plastic((0.4, 0.5, 0.6), alpha=0.25, specular_reflectance=(1.0, 0.5, 0.25))
    wo, wi = _pairs(m, rng, two_sided=True)
    f, g = m.eval_grad(wo, wi, ("reflectance", "specular_reflectance"))
    m0 = bk.Plastic(0.0, alpha=0.25, specular_reflectance=(1.0, 0.5, 0.25))
    f_coat = m0.eval(wo, wi)
    for c, R in enumerate((0.4, 0.5, 0.6)):   # f = R df/dR + f_coat (the base term is linear in R)
        np.testing.assert_allclose(R * g[:, c, c] + f_coat[:, c], f[:, c], rtol=1e-13, atol=1e-300)
        np.testing.assert_array_equal(np.delete(g[:, :, c], c, axis=1), 0.0)
    assert np.count_nonzero(g[:, 0, 0]) > N // 3
    coat1 = f_coat[:, 0] / 1.0   # Ks.r = 1
    for c, ks in enumerate((1.0, 0.5, 0.25)):
        np.testing.assert_allclose(g[:, c, 3 + c], coat1, rtol=1e-12, atol=1e-300)
        np.testing.assert_allclose(f_coat[:, c], ks * coat1, rtol=1e-12, atol=1e-300)
