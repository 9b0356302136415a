"""eval_grad of FilamentCloth and of the analytic coated models (CoatedDiffuse / CoatedConductor,
method="analytic"), against Dr.Jit forward-mode AD of independent float64 references
(bsdfkit.testing.drjit_filament.cloth_f and bsdfkit.testing.layered_analytic_ref.coated_f, through
bsdfkit.testing.drjit_grad) and against central finite differences of our own eval, on >= 10,000
pairs per model: grazing wo down to cos 1e-4, both sides for the two-sided coated models, lobe
samples and uniform directions, rough and near-smooth coats, eta < 1, a medium."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.fitting.grad import _columns
from bsdfkit.testing.drjit_grad import cloth_grad, coated_analytic_grad
from conftest import grazing_dirs, random_dirs

N = 12_000
ZS = (1.0, 0.5, 0.1, 1e-2, 1e-3, 1e-4)


def _pairs(model, rng, two_sided):
    n2 = N // 2
    wo = grazing_dirs(rng, n2, ZS)
    wo = np.concatenate([wo, grazing_dirs(rng, N - n2, ZS, -1.0 if two_sided else 1.0)])
    s = model.sample(wo, rng.random(N), rng.random((N, 2)))
    other = random_dirs(rng, N) if two_sided else random_dirs(rng, N, 1)
    wi = np.where(s.valid[:, None] & (rng.random(N) < 0.6)[:, None], s.wi, other)
    return wo, wi


def _rel_err(ours, ref):
    """Elementwise error relative to the reference, floored at 1e-6 of the column's 99th
    percentile magnitude (the scale of that derivative over the lobe)."""
    a = np.abs(ref)
    flat = a.reshape(-1, a.shape[-1])
    scale = np.array([np.quantile(c[c > 0], 0.99) if np.any(c > 0) else 1.0 for c in flat.T])
    return np.abs(ours - ref) / np.maximum(a, 1e-6 * scale)


def _grad_and_ref(model, params, rng, two_sided, ref):
    """eval_grad of ``model`` on _pairs and the reference ``ref(model, wo, wi, columns)``; checks the
    gradient's shape and that its value path is eval's arithmetic (bit for bit).
    Returns (wo, wi, f, g, column names, f_ref, g_ref)."""
    wo, wi = _pairs(model, rng, two_sided=two_sided)
    f, g = model.eval_grad(wo, wi, params)
    names, cols = _columns(model, params)
    assert g.shape == (N, 3, len(cols))
    np.testing.assert_array_equal(f, model.eval(wo, wi))   # the dual's value path is eval's arithmetic
    f_ref, g_ref = ref(model, wo, wi, cols)
    return wo, wi, f, g, names, f_ref, g_ref


def _fd_check(name, g, fd_h, f, tol=1e-5, noise_eps=64, min_clean=0.3):
    """Central differences against eval_grad. The differences carry a rounding error of about
    eps |f| / h, which swamps them where f is huge and its derivative small (a grazing coat peak,
    f ~ 1e6); so: (1) on the entries where that rounding is below 1e-6 of |fd| (the majority of
    the nonzero ones), the relative error (floored at 1e-6 of the column's p99 scale) must be
    < tol at p99; (2) on 99.8 % of the entries, |g - fd| <= tol max(|fd|, floor) + 64 eps |f| / h
    (the rest: differences straddling a kink, e.g. the critical angle of the refraction).
    noise_eps: the rounding of f in units of eps |f| (64; more where f sums a long quadrature);
    min_clean: the fraction of nonzero entries that must be clean (criterion 1 applies to them)."""
    fd, h = fd_h
    a = np.abs(fd)
    flat = a.reshape(-1, a.shape[-1])
    scale = np.array([np.quantile(c[c > 0], 0.99) if np.any(c > 0) else 1.0 for c in flat.T])
    ref = np.maximum(a, 1e-6 * scale)
    noise = noise_eps * np.finfo(np.float64).eps * np.abs(f)[..., None] / h
    rel = np.abs(g - fd) / ref
    nz = (g != 0) | (fd != 0)
    clean = nz & (noise < 1e-6 * ref)
    assert clean.sum() >= min_clean * nz.sum() and nz.sum() > 0, (clean.sum(), nz.sum())
    if not clean.all():
        _report(name, "central differences (all nonzero entries, rounding included)", rel[nz])
    if clean.any():
        _report(name, f"central differences ({clean.sum() / nz.sum():.1%} of nonzero entries above rounding)",
                rel[clean])
        assert np.quantile(rel[clean], 0.99) < tol, np.quantile(rel[clean], 0.99)
    ratio = np.abs(g - fd) / (tol * ref + noise)
    assert np.quantile(ratio, 0.998) <= 1, np.quantile(ratio, 0.998)


def _fd(model, wo, wi, names, rel_step=None):
    """(central differences of our eval along each gradient column, the steps h): h = 1e-6
    max(|theta|, 1e-2) (small against a near-smooth alpha), one-sided at a range bound.
    rel_step: {column name: factor replacing 1e-6} (a smaller step where the model has kinks
    closer than 1e-6, e.g. Plastic's quadrature tables)."""
    col_names, cols = _columns(model, names)
    ranges = type(model).param_ranges
    out, hs = [], []
    base = model.eval(wo, wi)
    for name, col in zip(col_names, cols):
        f0, c0 = col[0]
        x0 = np.asarray(model._params[f0], dtype=np.float64)
        h = (rel_step or {}).get(name, 1e-6) * max(abs(float(x0 if c0 == -1 else x0[c0])), 1e-2)
        shifted = []
        for sign in (1, -1):
            p = dict(model._params)
            ok = True
            for field, ch in col:
                v = np.array(p[field], dtype=np.float64)
                x = (v if ch == -1 else v[ch]) + sign * h
                lo, hi = ranges[field]
                ok &= lo <= x <= hi
                if ch == -1:
                    v = x
                else:
                    v[ch] = x
                p[field] = float(v) if np.ndim(v) == 0 else v
            shifted.append((ok, p))
        if not (shifted[0][0] or shifted[1][0]):   # outside the fitting range (eta < 1): both sides
            shifted = [(True, q) for _, q in shifted]
        up, dn = (type(model)._from_params(q).eval(wo, wi) if ok else None for ok, q in shifted)
        n = (up is not None) + (dn is not None)
        out.append(((up if up is not None else base) - (dn if dn is not None else base)) / (h * n))
        hs.append(h)
    return np.stack(out, axis=-1), np.array(hs)


def _report(name, kind, err):
    e = err.ravel()
    print(f"\n{name} vs {kind}: p50 {np.quantile(e, 0.5):.2e} p99 {np.quantile(e, 0.99):.2e} max {e.max():.2e}")


# ----------------------------------------------------------------------------------- cloth

CLOTH = {
    "denim": (lambda: bk.FilamentCloth((0.1, 0.15, 0.35), sheen_color=(0.3, 0.35, 0.6), roughness=0.8),
              ("base_color", "sheen_color", "roughness")),
    "velvet-subsurface-burley": (lambda: bk.FilamentCloth((0.35, 0.02, 0.08), sheen_color=(0.9, 0.4, 0.5),
                                                          subsurface_color=(0.3, 0.05, 0.05), roughness=0.35,
                                                          diffuse="burley"),
                                 ("base_color", "sheen_color", "subsurface_color", "roughness")),
    "near-smooth": (lambda: bk.FilamentCloth((0.5, 0.4, 0.3), sheen_color=(0.6, 0.6, 0.7), roughness=0.06),
                    ("base_color", "sheen_color", "roughness")),
    "rough": (lambda: bk.FilamentCloth((0.2, 0.5, 0.3), sheen_color=(0.4, 0.8, 0.5), roughness=0.97,
                                       diffuse="burley"), ("sheen_color", "roughness")),
}


@pytest.mark.parametrize("name", sorted(CLOTH))
def test_cloth_grad(name, rng):
    make, params = CLOTH[name]
    model = make()
    wo, wi, f, g, _, f_ref, g_ref = _grad_and_ref(model, params, rng, False, cloth_grad)
    np.testing.assert_allclose(f, f_ref, rtol=1e-9, atol=1e-300)
    assert np.count_nonzero(g_ref) > g_ref.size // 4
    err = _rel_err(g, g_ref)
    _report("cloth-" + name, "Dr.Jit AD", err)
    assert np.quantile(err, 0.99) < 1e-9 and err.max() < 1e-5, (np.quantile(err, 0.99), err.max())
    _fd_check("cloth-" + name, g, _fd(model, wo, wi, params), f)


def test_cloth_default_sheen_is_held():
    """sheen_color=None (sqrt(base_color)): eval_grad's base_color column holds sheen at its value."""
    m = bk.FilamentCloth((0.3, 0.2, 0.1), roughness=0.5)
    m2 = bk.FilamentCloth((0.3, 0.2, 0.1), sheen_color=m.effective_sheen_color, roughness=0.5)
    wo, wi = bk.direction(0.4, 0.0), bk.direction(0.7, 2.5)
    f, g = m.eval_grad(wo, wi, ("base_color", "sheen_color"))
    f2, g2 = m2.eval_grad(wo, wi, ("base_color", "sheen_color"))
    np.testing.assert_array_equal(f, f2)
    np.testing.assert_array_equal(g, g2)


# ----------------------------------------------------------------------------------- coated

COATED = {
    "diffuse-wood": (lambda: bk.CoatedDiffuse((0.6, 0.35, 0.15), alpha=0.05, method="analytic"),
                     ("reflectance", "eta", "alpha", "thickness")),
    "diffuse-medium-aniso": (lambda: bk.CoatedDiffuse(0.2, albedo=(0.8, 0.5, 0.3), thickness=0.2, g=0.3,
                                                      alpha_x=0.3, alpha_y=0.1, method="analytic"),
                             ("reflectance", "eta", "alpha_x", "alpha_y", "thickness", "albedo", "g")),
    "diffuse-eta-below-1": (lambda: bk.CoatedDiffuse(0.5, eta=0.8, alpha=0.2, albedo=0.3, g=-0.4,
                                                     masking="separable", method="analytic"),
                            ("reflectance", "eta", "alpha", "thickness", "albedo", "g")),
    "conductor-car-paint": (lambda: bk.CoatedConductor.from_metal("Cu", conductor_alpha=0.3, interface_alpha=0.02,
                                                                  albedo=(0.5, 0.1, 0.1), thickness=0.1,
                                                                  method="analytic"),
                            ("conductor_eta", "conductor_k", "conductor_alpha", "interface_eta", "interface_alpha",
                             "thickness", "albedo", "g")),
    "conductor-aniso": (lambda: bk.CoatedConductor.from_metal("Au", conductor_alpha_x=0.3, conductor_alpha_y=0.1,
                                                              interface_alpha_x=0.2, interface_alpha_y=0.05,
                                                              method="analytic"),
                        ("conductor_eta", "conductor_k", "conductor_alpha_x", "conductor_alpha_y", "interface_eta",
                         "interface_alpha_x", "interface_alpha_y", "thickness")),
    "conductor-near-smooth-coat": (lambda: bk.CoatedConductor.from_metal("Al", conductor_alpha=0.25,
                                                                         interface_alpha_x=1.2e-3,
                                                                         interface_alpha_y=1e-3, thickness=0.05,
                                                                         method="analytic"),
                                   ("conductor_eta", "conductor_k", "conductor_alpha", "interface_eta",
                                    "interface_alpha_x", "interface_alpha_y", "thickness")),
    "conductor-smooth-coat": (lambda: bk.CoatedConductor.from_metal("Cu", conductor_alpha=0.4, interface_eta=1.6,
                                                                    method="analytic"),
                              ("conductor_eta", "conductor_k", "conductor_alpha", "interface_eta", "thickness")),
}


@pytest.mark.parametrize("name", sorted(COATED))
def test_coated_analytic_grad(name, rng):
    make, params = COATED[name]
    model = make()
    assert len(bk.fitting.grad_columns(model, params)) == len(_columns(model, params)[1])
    wo, wi, f, g, _, f_ref, g_ref = _grad_and_ref(model, params, rng, True, coated_analytic_grad)
    err_f = _rel_err(f[..., None], f_ref[..., None])
    assert np.quantile(err_f, 0.99) < 1e-10 and err_f.max() < 1e-6, (np.quantile(err_f, 0.99), err_f.max())
    assert np.count_nonzero(g_ref) > g_ref.size // 8   # per-channel columns are 0 in the other channels
    err = _rel_err(g, g_ref)
    _report("coated-" + name, "Dr.Jit AD", err)
    assert np.quantile(err, 0.99) < 1e-9 and err.max() < 1e-4, (np.quantile(err, 0.99), err.max())
    # near-smooth coat (alpha 1e-3): the lobe's curvature makes the differences' truncation ~1e-5
    _fd_check("coated-" + name, g, _fd(model, wo, wi, params), f, tol=1e-4 if "near-smooth" in name else 1e-5)


def test_stochastic_coated_has_no_gradient_kernel():
    m = bk.CoatedDiffuse(0.5, alpha=0.1)
    with pytest.raises(TypeError, match="gradient kernel"):
        m.eval_grad(bk.direction(0.3, 0.0), bk.direction(0.5, 1.0))


def test_prefixed_isotropic_alpha_columns(rng):
    m = bk.CoatedConductor.from_metal("Cu", conductor_alpha=0.3, interface_alpha=0.1, method="analytic")
    assert {"conductor_alpha", "interface_alpha"} <= set(bk.fitting.differentiable_params(m))
    wo, wi = _pairs(m, rng, two_sided=True)
    _, g_xy = m.eval_grad(wo, wi, ("conductor_alpha_x", "conductor_alpha_y", "interface_alpha_x",
                                   "interface_alpha_y"))
    _, g_a = m.eval_grad(wo, wi, ("conductor_alpha", "interface_alpha"))
    np.testing.assert_allclose(g_a[..., 0], g_xy[..., :2].sum(-1), rtol=1e-10, atol=1e-300)
    np.testing.assert_allclose(g_a[..., 1], g_xy[..., 2:].sum(-1), rtol=1e-10, atol=1e-300)
