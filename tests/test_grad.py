"""eval_grad: d f / d theta from the models' own code with dual numbers (core/dual.h), checked
against Dr.Jit's forward-mode AD of the independent float64 references
(bsdfkit.testing.drjit_models through bsdfkit.testing.drjit_grad) and against central finite
differences, on >= 10,000 direction pairs per model, grazing angles and the rough/smooth limit
included. Filament has no Dr.Jit reference that takes differentiable parameters (its derived
parameters are computed in Python floats), so its check is central differences of the
independent reference drjit_filament.standard_f, plus differences of our own eval."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import drjit_models as dj
from bsdfkit.testing.drjit_grad import reference_grad
from conftest import grazing_dirs, random_dirs

N = 12_000
ZS = (1.0, 0.5, 0.1, 1e-2, 1e-3, 1e-4)

# Error statistics are printed (pytest -s) for the closing note.
STATS = {}


def _pairs(model, rng, two_sided=True):
    """Half lobe samples of the model (the interesting region), half anything; wo cycles through
    the grazing cosines ZS, on both sides when two_sided."""
    n2 = N // 2
    wo = grazing_dirs(rng, n2, ZS)
    if two_sided:
        wo = np.concatenate([wo, grazing_dirs(rng, N - n2, ZS, -1.0)])
    else:
        wo = np.concatenate([wo, grazing_dirs(rng, N - n2, ZS)])
    s = model.sample(wo, rng.random(N), rng.random((N, 2)))
    wi = np.where(s.valid[:, None] & (rng.random(N) < 0.5)[:, None], s.wi, random_dirs(rng, N))
    return wo, wi


def _rel_err(ours, ref):
    """Elementwise error relative to the reference, floored at 1e-6 of the column's
    99th-percentile magnitude (the scale of that derivative over the lobe)."""
    a = np.abs(ref)
    flat = a.reshape(-1, a.shape[-1]) if a.ndim > 1 else a[:, None]
    scale = np.array([np.quantile(c[c > 0], 0.99) if np.any(c > 0) else 1.0 for c in flat.T])
    return np.abs(ours - ref) / np.maximum(a, 1e-6 * scale)


def _record(name, kind, err):
    e = err.ravel()
    STATS[(name, kind)] = (float(np.quantile(e, 0.5)), float(np.quantile(e, 0.99)), float(e.max()))
    print(f"\n{name} vs {kind}: p50 {STATS[(name, kind)][0]:.2e} p99 {STATS[(name, kind)][1]:.2e} "
          f"max {STATS[(name, kind)][2]:.2e}")


# ----------------------------------------------------------------------------------- models

def _conductor_case(model):
    cols = [[("c", 0, c)] for c in range(3)] + [[("c", 1, c)] for c in range(3)] + [[("s", 0)], [("s", 1)]]

    def ref(wo, wi):
        return reference_grad(dj.conductor_f, cols, model.eta, model.k, model.alpha_x, model.alpha_y, wo, wi,
                              masking=model.masking, fresnel=model.fresnel)
    return ("eta", "k", "alpha_x", "alpha_y"), ref


def _dielectric_case(model, mode="radiance"):
    cols = [[("s", 0)], [("s", 1)], [("s", 2)]]

    def ref(wo, wi):
        (f, _), (g, _) = reference_grad(dj.dielectric_f_pdf, cols, model.eta, model.alpha_x, model.alpha_y, wo, wi,
                                        mode=mode, masking=model.masking)
        return np.repeat(f[..., None], 3, -1), np.repeat(g[..., None, :], 3, -2)
    return ("eta", "alpha_x", "alpha_y"), ref


def _diffuse_case(model):
    cols = [[("c", 0, c)] for c in range(3)]

    def ref(wo, wi):
        (f, _), (g, _) = reference_grad(dj.diffuse_f_pdf, cols, model.reflectance, wo, wi)
        return f, g
    return ("reflectance",), ref


def _difftrans_case(model):
    cols = [[("c", 0, c)] for c in range(3)] + [[("c", 1, c)] for c in range(3)]

    def ref(wo, wi):
        (f, _), (g, _) = reference_grad(dj.diffuse_transmission_f_pdf, cols, model.reflectance, model.transmittance,
                                        wo, wi)
        return f, g
    return ("reflectance", "transmittance"), ref


CASES = {
    "conductor-Cu-aniso": (lambda: bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.1), _conductor_case),
    "conductor-Au-schlick": (lambda: bk.Conductor.from_metal("Au", alpha=0.25, fresnel="schlick"), _conductor_case),
    "conductor-Cr-f82-separable": (lambda: bk.Conductor.from_metal("Cr", alpha_x=0.5, alpha_y=0.2, fresnel="f82",
                                                                   masking="separable"), _conductor_case),
    "conductor-near-smooth": (lambda: bk.Conductor.from_metal("Al", alpha_x=1.2e-3, alpha_y=1e-3), _conductor_case),
    "dielectric-1.5-aniso": (lambda: bk.Dielectric(1.5, alpha_x=0.3, alpha_y=0.15), _dielectric_case),
    "dielectric-0.75-separable": (lambda: bk.Dielectric(0.75, alpha=0.4, masking="separable"), _dielectric_case),
    "dielectric-near-smooth": (lambda: bk.Dielectric(1.33, alpha_x=2e-3, alpha_y=1.1e-3), _dielectric_case),
    "diffuse": (lambda: bk.Diffuse((0.8, 0.5, 0.2)), _diffuse_case),
    "diffuse-transmission": (lambda: bk.DiffuseTransmission((0.3, 0.5, 0.1), (0.6, 0.2, 0.4)), _difftrans_case),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_grad_against_drjit_ad(name, rng):
    make, case = CASES[name]
    model = make()
    params, ref = case(model)
    wo, wi = _pairs(model, rng, two_sided=True)
    f, g = model.eval_grad(wo, wi, params)
    assert g.shape == (N, 3, len(bk.fitting.grad_columns(model, params)))
    # the value is eval's, bit for bit (the dual number's value path is the double arithmetic)
    np.testing.assert_array_equal(f, model.eval(wo, wi))
    f_ref, g_ref = ref(wo, wi)
    # Near a microfacet's critical angle cos_t = sqrt(1 - sin_t^2) cancels: the float64 value's
    # condition number reaches ~1e8 there (measured: the dielectric eta 0.75 pair with cos_t
    # 5.6e-5 is 6e-9 from its 50-digit value in both our and the reference's operation order).
    # So: 1e-10 on all but 1 pair in 1000, 1e-7 on every pair.
    f_err = np.abs(f - f_ref) / np.maximum(np.abs(f_ref), 1e-300)
    assert np.quantile(f_err, 0.999) <= 1e-10 and f_err.max() <= 1e-7, (np.quantile(f_err, 0.999), f_err.max())
    assert np.count_nonzero(g_ref) > g_ref.size // 4 or "near-smooth" in name or "diffuse" in name
    err = _rel_err(g, g_ref)
    _record(name, "Dr.Jit AD", err)
    assert np.quantile(err, 0.99) < 1e-9 and err.max() < 1e-5, (np.quantile(err, 0.99), err.max())


def _shifted(model, col, sign, h):
    """The model with the column's fields moved by sign * h (None if that leaves the valid range)."""
    lo_hi = type(model).param_ranges
    p = dict(model._params)
    for field, ch in col:
        v = np.array(p[field], dtype=np.float64)
        x = (v if ch == -1 else v[ch]) + sign * h
        lo, hi = lo_hi[field]
        if x < lo or x > hi:
            return None
        if ch == -1:
            v = x
        else:
            v[ch] = x
        p[field] = float(v) if np.ndim(v) == 0 else v
    return type(model)._from_params(p)


def _fd(model, wo, wi, names, h=1e-6, evaluate=None):
    """Differences of f along each gradient column (a column moves its fields by h): central,
    or one-sided where the parameter sits on a bound of its valid range."""
    from bsdfkit.fitting.grad import _columns
    evaluate = evaluate or (lambda m: m.eval(wo, wi))
    _, cols = _columns(model, names)
    out = []
    for col in cols:
        up, down = _shifted(model, col, 1, h), _shifted(model, col, -1, h)
        f_up = evaluate(up) if up is not None else evaluate(model)
        f_dn = evaluate(down) if down is not None else evaluate(model)
        out.append((f_up - f_dn) / (h * ((up is not None) + (down is not None))))
    return np.stack(out, axis=-1)


@pytest.mark.parametrize("name", ["conductor-Cu-aniso", "conductor-Cr-f82-separable", "dielectric-1.5-aniso",
                                  "diffuse-transmission"])
def test_grad_against_finite_differences(name, rng):
    make, case = CASES[name]
    model = make()
    params, _ = case(model)
    wo, wi = _pairs(model, rng, two_sided=True)
    f, g = model.eval_grad(wo, wi, params)
    fd = _fd(model, wo, wi, params)
    err = _rel_err(g, fd)
    _record(name, "central differences", err)
    # truncation O(h^2) and rounding eps f / h: ~1e-8 relative where f is smooth
    assert np.quantile(err, 0.99) < 1e-5, np.quantile(err, 0.99)


def test_alpha_column_is_the_isotropic_derivative(rng):
    m = bk.Conductor.from_metal("Au", alpha=0.2)
    wo, wi = _pairs(m, rng, two_sided=False)
    _, g_xy = m.eval_grad(wo, wi, ("alpha_x", "alpha_y"))
    _, g_a = m.eval_grad(wo, wi, "alpha")
    np.testing.assert_allclose(g_a[..., 0], g_xy.sum(-1), rtol=1e-10, atol=1e-300)
    # against Dr.Jit AD with both alphas seeded together
    f_ref, g_ref = reference_grad(dj.conductor_f, [[("s", 0), ("s", 1)]], m.eta, m.k, 0.2, 0.2, wo, wi)
    err = _rel_err(g_a, g_ref)
    assert np.quantile(err, 0.99) < 1e-9 and err.max() < 1e-5


def test_smooth_lobe_gradient_is_zero(rng):
    m = bk.Conductor.from_metal("Cu", alpha=5e-4)     # below the 1e-3 switch: a delta mirror
    wo, wi = random_dirs(rng, 1000, 1), random_dirs(rng, 1000, 1)
    f, g = m.eval_grad(wo, wi)
    assert np.all(f == 0) and np.all(g == 0)


# ----------------------------------------------------------------------------------- Filament

FILAMENT = {
    "plastic": lambda: bk.FilamentStandard((0.8, 0.5, 0.3), roughness=0.5),
    "metal-aniso": lambda: bk.FilamentStandard((1.0, 0.85, 0.57), metallic=0.8, roughness=0.6, anisotropy=0.5),
    "dark-metal-f90": lambda: bk.FilamentStandard((0.02, 0.01, 0.015), metallic=1.0, roughness=0.35),
    "coat-burley": lambda: bk.FilamentStandard((0.05, 0.2, 0.7), metallic=0.7, roughness=0.5, clear_coat=0.8,
                                               clear_coat_roughness=0.1, diffuse="burley"),
    "sheen": lambda: bk.FilamentStandard((0.3, 0.05, 0.1), roughness=0.6, sheen_color=(0.9, 0.6, 0.7),
                                         sheen_roughness=0.4),
}
# parameters differentiated per case: away from ties of max(sheen_color) (not differentiable)
FIL_PARAMS = {
    "plastic": ("base_color", "metallic", "roughness", "reflectance", "clear_coat", "clear_coat_roughness"),
    "metal-aniso": ("base_color", "metallic", "roughness", "reflectance", "anisotropy"),
    "dark-metal-f90": ("base_color", "metallic", "roughness", "reflectance"),
    "coat-burley": ("base_color", "metallic", "roughness", "reflectance", "clear_coat", "clear_coat_roughness"),
    "sheen": ("base_color", "metallic", "roughness", "sheen_color", "sheen_roughness"),
}


@pytest.mark.parametrize("name", sorted(FILAMENT))
def test_filament_grad(name, rng):
    from bsdfkit import filament
    model = FILAMENT[name]()
    n = N // 2   # one-sided model: upper hemisphere only
    wo = grazing_dirs(rng, n, ZS)
    s = model.sample(wo, rng.random(n), rng.random((n, 2)))
    wi = np.where(s.valid[:, None], s.wi, random_dirs(rng, n, 1))
    wo, wi = np.concatenate([wo, random_dirs(rng, N - n, 1)]), np.concatenate([wi, random_dirs(rng, N - n, 1)])
    params = FIL_PARAMS[name]
    f, g = model.eval_grad(wo, wi, params)
    np.testing.assert_array_equal(f, model.eval(wo, wi))
    lut = filament.dfg_lut(model.dfg_lut_size)
    from bsdfkit.fitting.grad import _columns
    from bsdfkit.testing import drjit_filament as djf
    from bsdfkit.testing.drjit_grad import standard_grad
    # Dr.Jit forward-mode AD of the independent reference, through its own parameter preprocessing
    f_ref, g_ref = standard_grad(model, wo, wi, lut, _columns(model, params)[1])
    np.testing.assert_allclose(f, f_ref, rtol=1e-8, atol=1e-12)
    err = _rel_err(g, g_ref)
    _record("filament-" + name, "Dr.Jit AD", err)
    assert np.quantile(err, 0.99) < 1e-8 and err.max() < 1e-4, (np.quantile(err, 0.99), err.max())
    fd_ref = _fd(model, wo, wi, params, evaluate=lambda m: djf.standard_f(m, wo, wi, lut))
    err = _rel_err(g, fd_ref)
    _record("filament-" + name, "differences of drjit_filament", err)
    # differences lose eps |f| / h where f is large and its derivative small (grazing coat, V_Kelemen)
    assert np.quantile(err, 0.99) < 1e-3, np.quantile(err, 0.99)
    err2 = _rel_err(g, _fd(model, wo, wi, params))
    _record("filament-" + name, "differences", err2)
    assert np.quantile(err2, 0.99) < 1e-3, np.quantile(err2, 0.99)


# ----------------------------------------------------------------------------------- API

def test_eval_grad_api_errors():
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    wo = bk.direction(0.3, 0.0)
    with pytest.raises(ValueError, match="differentiable: alpha, eta, k, alpha_x, alpha_y|differentiable"):
        m.eval_grad(wo, wo, ("roughness",))
    with pytest.raises(ValueError, match="eta"):
        m.eval_grad(wo, wo, ("masking",))
    with pytest.raises(ValueError, match="twice"):
        m.eval_grad(wo, wo, ("eta", "eta.r"))
    with pytest.raises(ValueError, match="at least one"):
        m.eval_grad(wo, wo, ())
    with pytest.raises(TypeError, match="gradient kernel"):
        bk.ThinDielectric(1.5).eval_grad(wo, wo)
    with pytest.raises(ValueError, match="wo"):
        m.eval_grad(np.array([1.0, 1.0, 1.0]), wo, "eta")
    with pytest.raises(ValueError, match="last axis"):
        m.eval_grad(np.zeros((4, 2)), wo, "eta")
    f, g = m.eval_grad(np.broadcast_to(wo, (2, 5, 3)), wo, ("eta.g", "alpha"))
    assert f.shape == (2, 5, 3) and g.shape == (2, 5, 3, 2)
    assert bk.fitting.grad_columns(m, ("eta", "alpha")) == ("eta.r", "eta.g", "eta.b", "alpha")
    assert "alpha" in bk.fitting.differentiable_params(m)
