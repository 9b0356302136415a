"""BumpMap (issue 47 item 2): Mitsuba 3.9's ``bumpmap`` around a model, with the height's uv
gradient per element.

References: Mitsuba 3.9 (llvm_ad_rgb, float32) ``bumpmap`` of a ``bitmap`` height texture
(``filter_type="bilinear"``) around ``diffuse`` and ``roughconductor``, each element at its own
uv and with its own dp/du, dp/dv, the gradient passed to bsdfkit being Mitsuba's own
``texture.eval_1_grad(si)``; Mitsuba's ``eval_1_grad`` against ``height_gradient``; the
flat-patch closed form n = normalize(-s dh/du, -s dh/dv, 1) (a NormalMap of that normal); a
quadrature of the rule for the white furnace; chi-square of the sampler.

As in tests/models/test_composite_mitsuba.py, Mitsuba computes the bumped frame in float32
(~1e-7 absolute on a shading cosine): pairs whose geometric or shading cosine of wi is below 0.02
(a few %) are left out of the 1e-5 statistic and checked at 1e-3.
"""
import pickle

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models.bump_map import bump_normals, height_gradient
from bsdfkit.models.normal_map import shading_frame, shadow_terminator
from bsdfkit.testing import mitsuba as ref
from conftest import grazing_dirs, random_dirs

RAD, IMP = bk.TransportMode.Radiance, bk.TransportMode.Importance
N = 12_000
TOL = 1e-5
ZS = [1.0, 0.8, 0.5, 0.3, 0.15, 0.07, 0.03]
GOLD = bk.Conductor.from_metal("Au", alpha=0.3, masking="separable")
ANISO = bk.Conductor([0.2, 0.9, 1.1], [3.9, 2.4, 2.1], alpha_x=0.4, alpha_y=0.08, masking="separable")
ORANGE = bk.Diffuse([0.8, 0.5, 0.2])
RED = bk.Diffuse([0.8, 0.1, 0.1])


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _dir(z, phi=0.7):
    s = np.sqrt(1 - z * z)
    return np.array([s * np.cos(phi), s * np.sin(phi), z])


# ------------------------------------------------------------------ Mitsuba 3 bumpmap

def _f32(a):
    return np.asarray(a, np.float32).astype(np.float64)


def _height(rng, rows=12, cols=16):
    return rng.uniform(0.0, 0.15, (rows, cols)).astype(np.float32)


def _bitmap(h, wrap="repeat"):
    mi, _ = ref._mi()
    return {"type": "bitmap", "bitmap": mi.Bitmap(np.ascontiguousarray(h[..., None])), "raw": True,
            "filter_type": "bilinear", "wrap_mode": wrap}


def _si(wo, uv, dp_du=None, dp_dv=None):
    """Mitsuba SurfaceInteraction3f of float32 rows: wi = wo, n = sh_frame.n = z, uv, dp/du, dp/dv."""
    mi, dr = ref._mi()
    n = len(wo)
    si = ref._make_si(wo.astype(np.float32))
    si.uv = mi.Point2f(mi.Float(uv[:, 0].astype(np.float32)), mi.Float(uv[:, 1].astype(np.float32)))
    du = np.broadcast_to([1.0, 0, 0] if dp_du is None else dp_du, (n, 3))
    dv = np.broadcast_to([0, 1.0, 0] if dp_dv is None else dp_dv, (n, 3))
    si.dp_du, si.dp_dv = ref._v3(du.astype(np.float32)), ref._v3(dv.astype(np.float32))
    return si


def _mi_grad(h, uv, wrap="repeat"):
    mi, dr = ref._mi()
    tex = mi.load_dict(_bitmap(h, wrap))
    g = tex.eval_1_grad(_si(np.tile([0, 0, 1.0], (len(uv), 1)), uv))
    dr.eval(g)
    return np.asarray(g.numpy(), np.float64).reshape(2, -1)


def _mi_eval_pdf(d, wo, wi, uv, dp_du=None, dp_dv=None):
    mi, dr = ref._mi()
    bsdf = mi.load_dict(d)
    wi32 = wi.astype(np.float32)
    val, pdf = bsdf.eval_pdf(mi.BSDFContext(), _si(wo, uv, dp_du, dp_dv), ref._v3(wi32))
    dr.eval(val, pdf)
    n = len(wo)
    return ref._div_cos(ref._np(val, n, 3), np.abs(wi32[:, 2].astype(np.float64))), ref._np(pdf, n)


def _err(ours, theirs):
    pos = theirs[theirs > 0]
    scale = np.quantile(pos, 0.99) if pos.size else 1.0
    err = np.abs(ours - theirs) / np.maximum(np.abs(theirs), 1e-5 * scale)
    return err.reshape(len(err), -1).max(1)


def _tangents(rng, n):
    """Per-element dp/du, dp/dv: skewed, stretched, with a small normal component (a smooth mesh's
    dp/du is not perpendicular to its shading normal; Mitsuba replaces that component)."""
    du = np.array([1.0, 0, 0]) + rng.normal(0, 0.3, (n, 3)) * [1, 1, 0.2]
    dv = np.array([0, 1.0, 0]) * rng.uniform(0.5, 2.0, (n, 1)) + rng.normal(0, 0.3, (n, 3)) * [1, 1, 0.2]
    return _f32(du), _f32(dv)


CASES = {   # name: (model, scale, per-element dp/du dp/dv?, flip_invalid_normals, shadowing)
    "diffuse": (ORANGE, 1.0, False, True, True),
    "diffuse-dp": (ORANGE, 0.7, True, True, True),
    "gold": (GOLD, 1.0, False, True, True),
    "aniso-dp": (ANISO, 1.0, True, True, True),
    "aniso-dp-noflip-noshadow": (ANISO, 0.5, True, False, False),
}


@pytest.mark.parametrize("lower", [False, True], ids=["above", "below"])
@pytest.mark.parametrize("name", sorted(CASES))
def test_eval_pdf_against_mitsuba_bumpmap(name, lower, rng):
    model, scale, with_dp, flip, shadow = CASES[name]
    h = _height(rng)
    uv = _f32(rng.random((N, 2)))
    du, dv = _tangents(rng, N) if with_dp else (None, None)
    g = _mi_grad(h, uv)   # Mitsuba's own gradient at each uv, given to both
    ours = bk.BumpMap(model, g[0], g[1], scale=scale, dp_du=du, dp_dv=dv, flip_invalid_normals=flip,
                      shadowing=shadow)
    d = {"type": "bumpmap", "height": _bitmap(h), "scale": scale, "flip_invalid_normals": flip,
         "use_shadowing_function": shadow, "bsdf": model.to_mitsuba()}
    wo = grazing_dirs(rng, N, ZS, -1.0 if lower else 1.0)
    wi = random_dirs(rng, N)
    s = ours.sample(wo, rng.random(N), rng.random((N, 2)))   # half the pairs sampled from the model
    wi[: N // 2] = np.where(s.valid[: N // 2, None], s.wi[: N // 2], wi[: N // 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo, wi = _f32(wo), _f32(wi)
    f_mi, p_mi = _mi_eval_pdf(d, wo, wi, uv, du, dv)
    f, p = ours.eval(wo, wi), ours.pdf(wo, wi)
    n_s = shading_frame(ours._param_arrays()["normals"], wo, flip,
                        None if du is None else du)[2]
    ok = (np.abs(wi[:, 2]) >= 0.02) & (np.abs(np.einsum("ij,ij->i", wi, n_s)) >= 0.02)
    assert ok.mean() > 0.9
    ef, ep = _err(f, f_mi), _err(p, p_mi)
    print(f"bumpmap {name} {'below' if lower else 'above'}: f max {ef[ok].max():.3g} p99.9 "
          f"{np.quantile(ef[ok], 0.999):.3g} | pdf max {ep[ok].max():.3g} p99.9 {np.quantile(ep[ok], 0.999):.3g} | "
          f"all pairs: f p99.9 {np.quantile(ef, 0.999):.3g}, pdf p99.9 {np.quantile(ep, 0.999):.3g}")
    assert np.quantile(ef[ok], 0.999) <= TOL and np.quantile(ep[ok], 0.999) <= TOL
    assert np.quantile(ef, 0.999) <= 1e-3 and np.quantile(ep, 0.999) <= 1e-3
    assert np.mean((f.max(1) > 0) != (f_mi.max(1) > 0)) < 2e-3   # the same zeros (leaks, the other side)
    assert (f.max(1) > 0).mean() > 0.3


def test_sampled_directions_agree_with_mitsuba(rng):
    """Diffuse child (bsdfkit's and Mitsuba's cosine samplers are the same mapping): the same
    uniforms give the same direction, pdf and weight in the bumped frame."""
    mi, dr = ref._mi()
    n = 4000
    h = _height(rng)
    uv = _f32(rng.random((n, 2)))
    du, dv = _tangents(rng, n)
    g = _mi_grad(h, uv)
    ours = bk.BumpMap(ORANGE, g[0], g[1], scale=0.8, dp_du=du, dp_dv=dv)
    bsdf = mi.load_dict({"type": "bumpmap", "height": _bitmap(h), "scale": 0.8, "bsdf": ORANGE.to_mitsuba()})
    wo = _f32(random_dirs(rng, n))
    uc, u = _f32(rng.random(n)), _f32(rng.random((n, 2)))
    bs, w = bsdf.sample(mi.BSDFContext(), _si(wo, uv, du, dv), mi.Float(uc.astype(np.float32)),
                        mi.Point2f(mi.Float(u[:, 0].astype(np.float32)), mi.Float(u[:, 1].astype(np.float32))))
    dr.eval(bs, w)
    wi_mi, p_mi, w_mi = ref._np(bs.wo, n, 3), ref._np(bs.pdf, n), ref._np(w, n, 3)
    s = ours.sample(wo, uc, u)
    valid_mi = np.any(w_mi != 0, axis=1)
    assert np.mean(s.valid != valid_mi) < 1e-3
    both = s.valid & valid_mi
    assert both.mean() > 0.7
    dwi = np.abs(s.wi - wi_mi)[both].max()
    ew, ep = _err(s.weight[both], w_mi[both]), _err(s.pdf[both], p_mi[both])
    print(f"bumpmap sample: wi max |diff| {dwi:.3g}, weight p99.9 {np.quantile(ew, 0.999):.3g}, pdf p99.9 "
          f"{np.quantile(ep, 0.999):.3g}")
    assert dwi < 1e-5
    # Mitsuba's sampled direction is float32: as test_composite_mitsuba, 1e-4 for pdf and weight
    assert np.quantile(ew, 0.999) <= 1e-4 and np.quantile(ep, 0.999) <= 1e-4


@pytest.mark.parametrize("wrap", ["repeat", "clamp", "mirror"])
def test_height_gradient_is_mitsuba_bitmaps(wrap, rng):
    """height_gradient against Mitsuba's bitmap eval_1_grad (bilinear, float32), uv beyond [0, 1]
    too (the wrap modes)."""
    h = _height(rng, 7, 11)
    uv = _f32(rng.uniform(-1.2, 2.2, (20000, 2)))
    g_mi = _mi_grad(h, uv, wrap)
    du, dv = height_gradient(h, uv, wrap)
    scale = np.abs(g_mi).max()
    err = np.maximum(np.abs(du - g_mi[0]), np.abs(dv - g_mi[1])) / scale
    print(f"height_gradient {wrap}: max |diff| / max |grad| {err.max():.3g}, p99.9 {np.quantile(err, 0.999):.3g}")
    # a float32 uv on a texel centre may fall on either side in float32 and float64 (the bilinear
    # gradient jumps there): a few such pairs are allowed
    assert np.quantile(err, 0.999) <= 1e-5 and np.mean(err > 1e-5) < 1e-3


# ------------------------------------------------------------------ closed forms

def test_flat_patch_is_the_normal_map_of_the_closed_form(rng):
    """dp/du = x, dp/dv = y: n = normalize(-s dh/du, -s dh/dv, 1) (pbrt-v4 / Mitsuba on a flat uv
    patch), so BumpMap is NormalMap of that normal; an explicit dp/du = x is the same frame."""
    a, b = rng.normal(0, 1.5, 50), rng.normal(0, 1.5, 50)
    wo, wi = random_dirs(rng, 50, 1), random_dirs(rng, 50)
    for model in (GOLD, ANISO, RED):
        for mode in (RAD, IMP):
            bm = bk.BumpMap(model, a, b, scale=0.6)
            nm = bk.NormalMap(model, _unit(np.stack([-0.6 * a, -0.6 * b, np.ones(50)], -1)))
            np.testing.assert_allclose(bm.eval(wo, wi, mode), nm.eval(wo, wi, mode), rtol=1e-12, atol=1e-300)
            np.testing.assert_allclose(bm.pdf(wo, wi, mode), nm.pdf(wo, wi, mode), rtol=1e-12, atol=1e-300)
            bx = bk.BumpMap(model, a, b, scale=0.6, dp_du=(1.0, 0, 0), dp_dv=(0, 1.0, 0))
            np.testing.assert_allclose(bx.eval(wo, wi, mode), nm.eval(wo, wi, mode), rtol=1e-12, atol=1e-300)


def test_bump_normals_formula():
    """Hand-worked: dp/du = (2, 0, 0), dp/dv = (0, 1, 0), s = 1, dh/du = 2, dh/dv = -1: dp/du' = (2, 0, 2),
    dp/dv' = (0, 1, -1), cross = (-2, 2, 2), n = (-1, 1, 1)/sqrt(3) (dh/dx = 1, dh/dy = -1). The same
    surface in a left-handed uv (dp/dv = -y, so dh/dv = +1): cross = (2, -2, -2), flipped to the
    surface's side, the same normal. A normal component of dp/du is replaced by the gradient, not
    added to (Mitsuba)."""
    np.testing.assert_allclose(bump_normals(2.0, -1.0, 1.0, (2.0, 0, 0), (0, 1.0, 0)), _unit([-1, 1, 1]), rtol=1e-15)
    np.testing.assert_allclose(bump_normals(2.0, 1.0, 1.0, (2.0, 0, 0), (0, -1.0, 0)), _unit([-1, 1, 1]), rtol=1e-15)
    np.testing.assert_allclose(bump_normals(2.0, -1.0, 1.0, (2.0, 0, 5.0), (0, 1.0, -3.0)), _unit([-1, 1, 1]),
                               rtol=1e-15)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("model", [GOLD, ANISO, RED, bk.Dielectric(1.5, alpha=0.3), bk.Plastic(0.5, alpha=0.2),
                                   bk.Mix(RED, GOLD, 0.4)], ids=lambda m: type(m).__name__)
def test_zero_gradient_is_the_model_bit_for_bit(model, dtype, rng):
    wo, wi = random_dirs(rng, 3000, dtype=dtype), random_dirs(rng, 3000, dtype=dtype)
    uc, u = rng.random(3000).astype(dtype), rng.random((3000, 2)).astype(dtype)
    for m in (bk.BumpMap(model), bk.BumpMap(model, 0.0, np.zeros(3000), scale=3.0)):
        for mode in (RAD, IMP):
            np.testing.assert_array_equal(m.eval(wo, wi, mode), model.eval(wo, wi, mode))
            np.testing.assert_array_equal(m.pdf(wo, wi, mode), model.pdf(wo, wi, mode))
            a, b = m.sample(wo, uc, u, mode=mode), model.sample(wo, uc, u, mode=mode)
            for k in ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional"):
                np.testing.assert_array_equal(getattr(a, k), getattr(b, k), err_msg=k)


def _bump_albedo_quadrature(n, wo, shadowing=True, nt=1200, nphi=2400):
    """The rule (NormalMap/BumpMap docstrings) for a white Lambertian, Radiance: the integral over
    wi above both the geometric and the (flipped) shading surface of (wi . n) / pi G(wi) dwi.
    Midpoint rule in (theta, phi)."""
    n = np.array(n, float)
    if wo[2] * np.dot(wo, n) <= 0:
        n[:2] *= -1
    t = (np.arange(nt) + 0.5) * (np.pi / 2) / nt
    p = (np.arange(nphi) + 0.5) * 2 * np.pi / nphi
    T, P = np.meshgrid(t, p, indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    cs = wi @ n
    g = shadow_terminator(n, wi) if shadowing else 1.0
    return (np.where(cs > 0, cs / np.pi * g, 0.0) * np.sin(T) * (np.pi / 2 / nt) * (2 * np.pi / nphi)).sum()


@pytest.mark.parametrize("shadowing", [True, False])
@pytest.mark.parametrize("g, z", [((0.6, -0.4), 0.9), ((0.6, -0.4), 0.3), ((1.5, 0.0), 0.15), ((0.0, -2.0), 0.5),
                                  ((-1.2, 0.8), 0.7)])
def test_white_furnace_of_bump_mapped_diffuse(g, z, shadowing):
    """Bump-mapped white Lambertian under the rule (Mitsuba's): albedo <= 1 in Radiance mode, equal
    to the quadrature of the rule at the closed-form normal normalize(-dh/du, -dh/dv, 1)."""
    m = bk.BumpMap(bk.Diffuse(1.0), *g, shadowing=shadowing)
    wo = _dir(z)
    a = m.albedo(wo, n_samples=1 << 19, seed=3)
    expect = _bump_albedo_quadrature(_unit([-g[0], -g[1], 1.0]), wo, shadowing)
    print(f"furnace g={g} z={z} shadowing={shadowing}: albedo {a[0]:.5f}, quadrature {expect:.5f}")
    np.testing.assert_allclose(a, expect, atol=2e-3)
    assert np.all(a <= 1 + 1e-12) and expect < 1


def test_no_leaks_and_adjoint_reciprocity(rng):
    """f = pdf = 0 where wi lies on different sides of the geometric and the bumped normal;
    f(wo, wi, Radiance) = f(wi, wo, Importance) where neither direction needs the flip (the frame,
    from n and dp/du, is then the same for both)."""
    n = 20000
    du, dv = _tangents(rng, n)
    m = bk.BumpMap(ANISO, rng.normal(0, 1, n), rng.normal(0, 1, n), dp_du=du, dp_dv=dv)
    nb = m._param_arrays()["normals"]
    wo, wi = random_dirs(rng, n, 1), random_dirs(rng, n, 1)
    c_o, c_i = np.einsum("ij,ij->i", wo, nb), np.einsum("ij,ij->i", wi, nb)
    ns = np.where((c_o <= 0)[:, None], nb * [-1, -1, 1], nb)
    leak = wi[:, 2] * np.einsum("ij,ij->i", wi, ns) <= 0
    assert leak.any()
    assert np.all(m.eval(wo, wi)[leak] == 0) and np.all(m.pdf(wo, wi)[leak] == 0)
    noflip = (c_o > 0) & (c_i > 0)
    np.testing.assert_allclose(m.eval(wo, wi, mode=RAD)[noflip], m.eval(wi, wo, mode=IMP)[noflip], rtol=1e-9,
                               atol=1e-300)


# ------------------------------------------------------------------ arrays, values, bad input

def test_per_element_parameters_equal_a_loop_of_scalar_models(rng):
    n = 40
    du, dv = _tangents(rng, n)
    a, b, sc = rng.normal(0, 1, n), rng.normal(0, 1, n), rng.uniform(0.2, 2, n)
    m = bk.BumpMap(ANISO, a, b, scale=sc, dp_du=du, dp_dv=dv)
    wo, wi = random_dirs(rng, n, 1), random_dirs(rng, n)
    uc, u = rng.random(n), rng.random((n, 2))
    f, p, s = m.eval(wo, wi), m.pdf(wo, wi), m.sample(wo, uc, u)
    for i in range(n):
        mi_ = bk.BumpMap(ANISO, a[i], b[i], scale=sc[i], dp_du=du[i], dp_dv=dv[i])
        np.testing.assert_array_equal(f[i], mi_.eval(wo[i], wi[i]))
        np.testing.assert_array_equal(p[i], mi_.pdf(wo[i], wi[i]))
        si = mi_.sample(wo[i], uc[i], u[i])
        np.testing.assert_array_equal(s.wi[i], si.wi)
        np.testing.assert_array_equal(s.f[i], si.f)
    # broadcasting: a (4, 5) map against (5, 3) directions
    m2 = bk.BumpMap(GOLD, rng.normal(0, 1, (4, 5)), 0.3)
    assert m2.eval(wo[:5], wi[:5]).shape == (4, 5, 3)
    assert m2.albedo(wo[0], n_samples=64).shape == (4, 5, 3)


def test_from_height_is_height_gradient(rng):
    h = _height(rng)
    uv = rng.random((6, 7, 2))
    du, dv = height_gradient(h, uv)
    assert du.shape == (6, 7)
    assert bk.BumpMap.from_height(GOLD, h, uv, scale=0.5) == bk.BumpMap(GOLD, du, dv, scale=0.5)
    # a height plane's gradient is the plane's slope wherever the bilinear cells do not wrap
    plane = 0.3 * np.arange(16)[None, :] / 16 - 0.2 * np.arange(12)[:, None] / 12
    du, dv = height_gradient(plane, rng.uniform(0.1, 0.9, (50, 2)), "clamp")
    np.testing.assert_allclose(du, 0.3, rtol=1e-12)
    np.testing.assert_allclose(dv, -0.2, rtol=1e-12)


def test_value_semantics_with_arrays(rng):
    big = bk.BumpMap(GOLD, rng.normal(size=(64, 64)), rng.normal(size=(64, 64)), dp_du=rng.normal(size=(64, 64, 3)))
    same = bk.BumpMap(GOLD, big.dh_du.copy(), big.dh_dv.copy(), dp_du=big.dp_du.copy())
    assert big == same and hash(big) == hash(same)
    assert big != bk.BumpMap(GOLD, big.dh_du * 2, big.dh_dv, dp_du=big.dp_du)
    back = pickle.loads(pickle.dumps(big))
    assert back == big
    r = repr(big)
    assert "digest" in r and len(r) < 800
    with pytest.raises(ValueError):
        big.dh_du[0, 0] = 1.0   # read-only
    small = bk.BumpMap(RED, np.array([0.5, -0.2]), 0.1, dp_dv=(0.0, 2.0, 0.0))
    assert eval(repr(small), {"BumpMap": bk.BumpMap, "Diffuse": bk.Diffuse}) == small   # noqa: S307


def test_bad_input_names_the_parameter_and_index():
    h = np.zeros((3, 4))
    h[1, 2] = np.nan
    x = np.zeros((2, 3))
    x[1, 1] = np.inf
    for call, words in [
        (lambda: bk.BumpMap(RED, x), ["dh_du", "(1, 1)", "finite"]),
        (lambda: bk.BumpMap(RED, 0.0, x), ["dh_dv", "(1, 1)"]),
        (lambda: bk.BumpMap(RED, 0.0, 0.0, scale=np.array([1.0, np.nan])), ["scale", "(1,)"]),
        (lambda: bk.BumpMap(RED, np.zeros(3), np.zeros(4)), ["dh_du", "dh_dv", "(3,)", "(4,)"]),
        (lambda: bk.BumpMap(RED, dp_du=(1.0, 0.0)), ["dp_du", "(3,)"]),
        (lambda: bk.BumpMap(RED, np.zeros(3), dp_du=np.ones((4, 3))), ["dp_du", "(4,)", "(3,)"]),
        (lambda: bk.BumpMap(RED, dp_du=[[1, 0, 0], [1, 0, 0.0]], dp_dv=[[0, 1, 0], [2, 0, 0.0]]),
         ["dp_du, dp_dv", "parallel", "(1,)"]),
        (lambda: bk.BumpMap(RED, dp_du=(0.0, 0.0, 1.0)), ["dp_du", "parallel", "()"]),
        (lambda: height_gradient(h, (0.5, 0.5)), ["height", "(1, 2)"]),
        (lambda: height_gradient(np.zeros(4), (0.5, 0.5)), ["height", "(H, W)"]),
        (lambda: height_gradient(np.zeros((2, 2)), (0.5, 0.5), "wrap"), ["wrap_mode"]),
        (lambda: height_gradient(np.zeros((2, 2)), [[0.5, np.nan]]), ["uv", "(0,)"]),
    ]:
        with pytest.raises(ValueError) as e:
            call()
        for w in words:
            assert w in str(e.value), (w, str(e.value))
    with pytest.raises(TypeError, match="dh_du"):
        bk.BumpMap(RED, "steep")
    with pytest.raises(TypeError, match="shadowing"):
        bk.BumpMap(RED, shadowing=1)
    with pytest.raises(TypeError, match="model"):
        bk.BumpMap(None)


# ------------------------------------------------------------------ chi-square of the sampler

R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])   # local z to the domain's -y (test_pbrt_chi2)
CHI2 = [("gold-flat-patch", bk.BumpMap(GOLD, 0.8, -0.3), 0.8),
        ("red-steep", bk.BumpMap(RED, -1.5, 0.4), 0.5),
        ("aniso-skewed-uv", bk.BumpMap(ANISO, 0.5, 0.9, dp_du=(1.0, 0.3, 0.1), dp_dv=(-0.2, 1.5, 0.0)), 0.3),
        ("gold-scaled", bk.BumpMap(GOLD, 3.0, 2.0, scale=0.25, dp_du=(0.5, 0.0, 0.0)), 0.6),
        ("aniso-below", bk.BumpMap(ANISO, -0.7, -0.2, dp_du=(0.8, -0.6, 0.0), dp_dv=(0.6, 0.8, 0.0)), -0.7),
        ("plastic-noflip", bk.BumpMap(bk.Plastic(0.5, alpha=0.2, masking="separable"), 0.6, 0.6,
                                      flip_invalid_normals=False), 0.4)]


@pytest.mark.parametrize("name, model, z", CHI2, ids=[c[0] for c in CHI2])
def test_chi2_sampling(name, model, z):
    wo = _dir(z)

    def sample_fn(uc, u):
        r = model.sample(wo, uc, u)
        return r.wi @ R.T, r.valid & ((r.flags & bk.BxDFFlags.Specular) == 0) & (np.abs(r.wi[:, 2]) > 1e-6)

    def pdf_fn(v):
        return model.pdf(wo, v @ R)

    passed, p, msg = ref.chi2_test(sample_fn, pdf_fn, res=101, ires=16, sample_count=400_000, seed=5,
                                   significance=0.01, test_count=len(CHI2))
    print(f"bumpmap chi2 {name}: p = {p:.4g}")
    assert passed, msg


# ------------------------------------------------------------------ Mitsuba interop

def test_to_and_from_mitsuba():
    mi, _ = ref._mi()
    flat = bk.BumpMap(GOLD, 0.0, 0.0, scale=2.0, shadowing=False)
    d = flat.to_mitsuba()
    assert d["type"] == "bumpmap" and d["scale"] == 2.0 and d["use_shadowing_function"] is False
    assert bk.from_mitsuba(d) == flat
    mi.load_dict(d)
    inner = GOLD.to_mitsuba()
    const = {"type": "bitmap", "bitmap": mi.Bitmap(np.full((4, 4, 1), 0.3, np.float32)), "raw": True}
    assert bk.from_mitsuba({"type": "bumpmap", "h": const, "bsdf": inner}) == bk.BumpMap(GOLD)
    vary = np.arange(16, dtype=np.float32).reshape(4, 4, 1)
    nearest = {"type": "bitmap", "bitmap": mi.Bitmap(vary), "raw": True, "filter_type": "nearest"}
    assert bk.from_mitsuba({"type": "bumpmap", "h": nearest, "bsdf": inner, "scale": 0.5}) == \
        bk.BumpMap(GOLD, scale=0.5)   # Mitsuba: a nearest lookup's gradient is 0
    for bad, words in [
        ({"type": "bumpmap", "h": {"type": "bitmap", "bitmap": mi.Bitmap(vary),
                                   "to_uv": [[1, 0.5, 0], [0, 1, 0], [0.5, 0, 1]]}, "bsdf": inner},
         ["'h'", "to_uv", "projective"]),
        ({"type": "bumpmap", "h": {"type": "checkerboard"}, "bsdf": inner}, ["'checkerboard'", "eval_1_grad"]),
        ({"type": "bumpmap", "bsdf": inner}, ["one nested height texture"]),
        ({"type": "bumpmap", "h": const, "a": inner, "b": inner}, ["one nested BSDF"]),
    ]:
        with pytest.raises(ValueError) as e:
            bk.from_mitsuba(bad)
        for w in words:
            assert w in str(e.value), (w, str(e.value))
    for m in (bk.BumpMap(GOLD, 0.5, 0.0), bk.BumpMap(GOLD, np.zeros(3)), bk.BumpMap(GOLD, dp_du=(1.0, 0.0, 0.0))):
        with pytest.raises(ValueError, match="Mitsuba"):
            m.to_mitsuba()


def test_spectral_mode_passes_through(rng):
    """wavelengths= reaches the child in the bumped frame: the same as NormalMap of the closed-form
    normal, spectral."""
    m = bk.Conductor.from_metal("Cu", alpha=0.25)
    lam = np.array([420.0, 510.0, 600.0, 700.0])
    wo, wi = random_dirs(rng, 500, 1), random_dirs(rng, 500)
    bm, nm = bk.BumpMap(m, 0.4, -0.9), bk.NormalMap(m, _unit([-0.4, 0.9, 1.0]))
    np.testing.assert_allclose(bm.eval(wo, wi, wavelengths=lam), nm.eval(wo, wi, wavelengths=lam), rtol=1e-12,
                               atol=1e-300)
    s = bm.sample(wo, n=500, seed=1, wavelengths=lam)
    assert s.f.shape == (500, 4) and s.valid.mean() > 0.5
