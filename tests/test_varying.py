"""Per-element parameters (issue 47): a model whose numeric parameters are numpy arrays evaluates
element i with the model built from element i's values. The reference is a loop of uniform models
(each built by the public class from one element's values, called on that element's inputs):
results must be bit-identical, in float32 and float64, for eval, pdf, sample and albedo, whatever
the thread count and array position. Mitsuba 3 cross-checks the per-element values through its
``bitmap`` textures (nearest lookups at each element's texel centre)."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

import bsdfkit as bk
from conftest import random_dirs

N = 150


def _runs(rng, n, k):
    """Indices 0..k-1 in runs of 1-5 repeats, plus one long run (40): elements sharing values."""
    idx = np.repeat(np.arange(k), rng.integers(1, 6, size=k))
    idx = np.concatenate([idx[: n // 2], np.full(40, idx[n // 2]), idx[n // 2:]])[:n]
    return idx


def _alpha(rng, k):
    """Alphas with smooth lanes (0 and just below 1e-3), rough ones, and the 1e-3 boundary."""
    a = rng.uniform(0.01, 0.8, k)
    a[rng.random(k) < 0.3] = 0.0
    a[rng.random(k) < 0.05] = 9e-4
    a[rng.random(k) < 0.05] = 1e-3
    return a


def _cases():
    def conductor(fresnel):
        def gen(rng, k):
            return dict(eta=rng.uniform(0.1, 3.0, (k, 3)), k=rng.uniform(0.0, 5.0, (k, 3)),
                        alpha_x=_alpha(rng, k), alpha_y=_alpha(rng, k))
        return (f"conductor-{fresnel}", gen,
                lambda eta, k, alpha_x, alpha_y: bk.Conductor(eta, k, alpha_x=alpha_x, alpha_y=alpha_y,
                                                              fresnel=fresnel))

    def dielectric(rng, k):
        eta = rng.uniform(1.05, 2.5, k)
        eta[rng.random(k) < 0.2] = 0.7
        eta[rng.random(k) < 0.1] = 1.0   # index matched lanes
        return dict(eta=eta, alpha_x=_alpha(rng, k), alpha_y=_alpha(rng, k))

    def plastic(rng, k):
        return dict(reflectance=rng.uniform(0, 1, (k, 3)), eta=rng.uniform(1.2, 1.8, k), alpha=_alpha(rng, k),
                    specular_reflectance=rng.uniform(0.5, 1, (k, 3)))

    def filament(rng, k):
        return dict(base_color=rng.uniform(0, 1, (k, 3)), metallic=rng.uniform(0, 1, k),
                    roughness=rng.uniform(0, 1, k), reflectance=rng.uniform(0, 1, k),
                    anisotropy=rng.uniform(-1, 1, k), clear_coat=rng.uniform(0.1, 1, k),
                    clear_coat_roughness=rng.uniform(0, 1, k), sheen_color=rng.uniform(0.05, 1, (k, 3)),
                    sheen_roughness=rng.uniform(0, 1, k))

    return [
        conductor("exact"), conductor("schlick"), conductor("f82"),
        ("dielectric", dielectric,
         lambda eta, alpha_x, alpha_y: bk.Dielectric(eta, alpha_x=alpha_x, alpha_y=alpha_y)),
        ("thin-dielectric", lambda rng, k: dict(eta=rng.uniform(1.0, 2.0, k)), bk.ThinDielectric),
        ("diffuse", lambda rng, k: dict(reflectance=rng.uniform(0, 1, (k, 3))), bk.Diffuse),
        ("diffuse-transmission",
         lambda rng, k: dict(reflectance=rng.uniform(0, 0.5, (k, 3)), transmittance=rng.uniform(0, 0.5, (k, 3))),
         bk.DiffuseTransmission),
        ("eon", lambda rng, k: dict(reflectance=rng.uniform(0, 1, (k, 3)), roughness=rng.uniform(0, 1, k)), bk.EON),
        ("plastic", plastic, bk.Plastic),
        ("filament-standard", filament, bk.FilamentStandard),
        ("normalized-fresnel", lambda rng, k: dict(eta=rng.uniform(1.1, 2.0, k)), bk.NormalizedFresnel),
        ("filament-cloth",
         lambda rng, k: dict(base_color=rng.uniform(0, 1, (k, 3)), sheen_color=rng.uniform(0, 1, (k, 3)),
                             roughness=rng.uniform(0, 1, k)), bk.FilamentCloth),
        ("coated-diffuse",
         lambda rng, k: dict(reflectance=rng.uniform(0, 1, (k, 3)), eta=rng.uniform(1.2, 1.8, k),
                             alpha_x=_alpha(rng, k), alpha_y=_alpha(rng, k), thickness=rng.uniform(0.01, 1, k),
                             albedo=rng.uniform(0, 1, (k, 3)), g=rng.uniform(-0.5, 0.5, k)),
         lambda **kw: bk.CoatedDiffuse(**kw, n_samples=2)),
        ("coated-conductor",
         lambda rng, k: dict(conductor_eta=rng.uniform(0.2, 2, (k, 3)), conductor_k=rng.uniform(1, 4, (k, 3)),
                             conductor_alpha_x=_alpha(rng, k), conductor_alpha_y=_alpha(rng, k),
                             interface_eta=rng.uniform(1.2, 1.8, k), interface_alpha_x=_alpha(rng, k),
                             interface_alpha_y=_alpha(rng, k), albedo=rng.uniform(0, 1, (k, 3))),
         bk.CoatedConductor),
        ("hair",
         lambda rng, k: dict(sigma_a=rng.uniform(0, 3, (k, 3)), eta=rng.uniform(1.3, 1.7, k),
                             beta_m=rng.uniform(0.1, 0.9, k), beta_n=rng.uniform(0.1, 0.9, k),
                             alpha=rng.uniform(-5, 5, k), h=rng.uniform(-1, 1, k)), bk.Hair),
    ]


CASES = _cases()


def _setup(case, n=N, seed=0):
    name, gen, make = case
    rng = np.random.default_rng(seed)
    k = n // 2
    base = gen(rng, k)
    idx = _runs(rng, n, k)
    arrays = {key: v[idx] for key, v in base.items()}
    wo = random_dirs(rng, n)
    wi = random_dirs(rng, n)
    return make, arrays, wo, wi, rng


def _one(make, arrays, i):
    return make(**{key: v[i] for key, v in arrays.items()})


def _eq(a, b, what):
    np.testing.assert_array_equal(a, b, err_msg=what)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_eval_pdf_sample_equal_a_loop_of_uniform_models(case, dtype):
    make, arrays, wo, wi, rng = _setup(case)
    m = make(**arrays)
    assert set(m.varying) == set(arrays)
    wo, wi = wo.astype(dtype), wi.astype(dtype)
    uc, u = rng.random(N).astype(dtype), rng.random((N, 2)).astype(dtype)
    f, p, s = m.eval(wo, wi), m.pdf(wo, wi), m.sample(wo, uc, u)
    assert f.dtype == dtype and f.shape == (N, 3) and p.shape == (N,)
    for i in range(N):
        mi = _one(make, arrays, i)
        _eq(f[i], mi.eval(wo[i], wi[i]), f"eval element {i}")
        _eq(p[i], mi.pdf(wo[i], wi[i]), f"pdf element {i}")
        si = mi.sample(wo[i:i + 1], uc[i:i + 1], u[i:i + 1])
        for field in ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional"):
            _eq(getattr(s, field)[i], getattr(si, field)[0], f"sample.{field} element {i}")


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_albedo_equals_a_loop_of_uniform_models(case, dtype):
    make, arrays, wo, _, _ = _setup(case, n=24, seed=1)
    m = make(**arrays)
    wo = wo.astype(dtype)
    a = m.albedo(wo, n_samples=300, seed=5)
    for i in range(len(wo)):
        # the estimator's uniforms depend on the direction's index: the uniform model on the same array
        _eq(a[i], _one(make, arrays, i).albedo(wo, n_samples=300, seed=5)[i], f"albedo element {i}")


@pytest.mark.parametrize("case", [CASES[0], CASES[3], CASES[9]], ids=["conductor", "dielectric", "filament"])
def test_any_thread_count_and_array_position(case):
    make, arrays, wo, wi, rng = _setup(case, n=400, seed=2)
    m = make(**arrays)
    uc, u = rng.random(len(wo)), rng.random((len(wo), 2))
    ref = (m.eval(wo, wi), m.pdf(wo, wi), m.sample(wo, uc, u).wi)
    perm = rng.permutation(len(wo))
    mp = make(**{k: v[perm] for k, v in arrays.items()})
    before = bk.get_num_threads()
    try:
        for threads in (1, 2, 3):
            bk.set_num_threads(threads)
            _eq(m.eval(wo, wi), ref[0], f"eval, {threads} threads")
            _eq(m.pdf(wo, wi), ref[1], f"pdf, {threads} threads")
            _eq(m.sample(wo, uc, u).wi, ref[2], f"sample, {threads} threads")
            _eq(mp.eval(wo[perm], wi[perm]), ref[0][perm], f"eval permuted, {threads} threads")
            _eq(mp.sample(wo[perm], uc[perm], u[perm]).wi, ref[2][perm], f"sample permuted, {threads} threads")
    finally:
        bk.set_num_threads(before)


GRAD_CASES = [c for c in CASES if c[0] in ("conductor-exact", "conductor-f82", "dielectric", "diffuse", "eon",
                                             "plastic", "filament-standard")]


@pytest.mark.parametrize("case", GRAD_CASES, ids=[c[0] for c in GRAD_CASES])
def test_eval_grad_equals_a_loop_of_uniform_models(case):
    make, arrays, wo, wi, _ = _setup(case, n=60, seed=7)
    m = make(**arrays)
    f, g = m.eval_grad(wo, wi)
    assert f.shape == (60, 3) and g.shape[:2] == (60, 3)
    for i in range(60):
        fi, gi = _one(make, arrays, i).eval_grad(wo[i], wi[i])
        _eq(f[i], fi, f"eval_grad f, element {i}")
        _eq(g[i], gi, f"eval_grad grad, element {i}")
    # a parameter map under one direction pair: the map's batch shape
    alpha = np.random.default_rng(8).uniform(0.05, 0.5, (3, 4))
    f, g = bk.Conductor.from_metal("Au", alpha=alpha).eval_grad(bk.direction(0.3, 0.0), bk.direction(0.4, 2.0),
                                                               ["alpha"])
    assert f.shape == (3, 4, 3) and g.shape == (3, 4, 3, 1)
    _eq(g[2, 1], bk.Conductor.from_metal("Au", alpha=alpha[2, 1]).eval_grad(
        bk.direction(0.3, 0.0), bk.direction(0.4, 2.0), ["alpha"])[1], "map element (2, 1)")


def test_parameter_maps_broadcast_with_the_directions():
    rng = np.random.default_rng(3)
    alpha = rng.uniform(0, 0.6, (5, 7))
    m = bk.Conductor.from_metal("Cu", alpha=alpha)
    wo, wi = bk.direction(0.4, 0.1), bk.direction(0.6, 2.5)
    f = m.eval(wo, wi)              # one direction pair under a (5, 7) map
    assert f.shape == (5, 7, 3)
    for r in range(5):
        for c in range(7):
            _eq(f[r, c], bk.Conductor.from_metal("Cu", alpha=alpha[r, c]).eval(wo, wi), f"texel {(r, c)}")
    # a row of alphas against a column of directions: the (5, 7) outer product
    col = random_dirs(rng, 5)[:, None, :]
    m7 = bk.Conductor.from_metal("Cu", alpha=alpha[0])
    f = m7.eval(col, wi)
    assert f.shape == (5, 7, 3)
    _eq(f[3, 4], bk.Conductor.from_metal("Cu", alpha=alpha[0, 4]).eval(col[3, 0], wi), "outer product")
    s = m7.sample(col, n=None, uc=np.full((5, 7), 0.3), u=np.full((5, 7, 2), 0.6))
    assert s.wi.shape == (5, 7, 3)
    assert m7.albedo(col, n_samples=16).shape == (5, 7, 3)
    # n= and seed= draw the uniforms over the broadcast batch
    s = bk.Diffuse(rng.uniform(0, 1, (6, 3))).sample(bk.direction(0.3, 0.0), n=6, seed=1)
    assert s.wi.shape == (6, 3)


def test_filament_standard_from_maps():
    rng = np.random.default_rng(4)
    img, r, mtl = rng.uniform(0, 1, (4, 6, 3)), rng.uniform(0, 1, (4, 6)), rng.uniform(0, 1, (4, 6))
    m = bk.FilamentStandard(base_color=img, roughness=r, metallic=mtl)
    wo = random_dirs(rng, 24, hemisphere=True).reshape(4, 6, 3)
    wi = random_dirs(rng, 24, hemisphere=True).reshape(4, 6, 3)
    f = m.eval(wo, wi)
    for y, x in [(0, 0), (3, 5), (2, 1)]:
        ref = bk.FilamentStandard(base_color=img[y, x], roughness=r[y, x], metallic=mtl[y, x])
        _eq(f[y, x], ref.eval(wo[y, x], wi[y, x]), f"pixel {(y, x)}")


def test_flags_are_the_union_over_elements():
    m = bk.Conductor.from_metal("Au", alpha=np.array([0.0, 0.3]))
    assert m.flags == bk.BxDFFlags.SpecularReflection | bk.BxDFFlags.GlossyReflection
    assert bk.Conductor.from_metal("Au", alpha=np.array([0.0, 0.0])).flags == bk.BxDFFlags.SpecularReflection
    # smoothness needs both alphas of the same element
    m = bk.Conductor.from_metal("Au", alpha_x=np.array([0.0, 0.5]), alpha_y=np.array([0.0, 0.5]))
    assert m.flags == bk.BxDFFlags.SpecularReflection | bk.BxDFFlags.GlossyReflection


def test_value_semantics_with_arrays():
    rng = np.random.default_rng(5)
    a = rng.uniform(0.1, 0.5, (300, 400))
    m = bk.Conductor.from_metal("Cu", alpha=a)
    same = bk.Conductor.from_metal("Cu", alpha=a.copy())
    other = bk.Conductor.from_metal("Cu", alpha=a * 1.01)
    assert m == same and hash(m) == hash(same) and m != other
    r = repr(m)
    assert len(r) < 400 and "(300, 400)" in r and "digest" in r
    assert m.varying == ("alpha_x", "alpha_y")
    m2 = pickle.loads(pickle.dumps(m))
    assert m2 == m
    wo = bk.direction(0.5, 0.0)
    _eq(m2.eval(wo, wo * [-1, -1, 1]), m.eval(wo, wo * [-1, -1, 1]), "pickled model")
    # small arrays print in full and evaluate back
    small = bk.Diffuse(np.array([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]]))
    assert eval(repr(small), {"Diffuse": bk.Diffuse}) == small
    # the model keeps its own read-only copy
    arr = np.full(4, 0.2)
    m = bk.Dielectric(1.5, alpha=arr)
    arr[:] = 0.9
    assert float(m.alpha_x[0]) == 0.2 and not m.alpha_x.flags.writeable


def test_bad_per_element_input_names_parameter_and_index():
    with pytest.raises(ValueError, match=r"alpha.*index \(1, 2\).*-0.5"):
        a = np.full((2, 3), 0.2)
        a[1, 2] = -0.5
        bk.Conductor.from_metal("Cu", alpha=a)
    with pytest.raises(ValueError, match=r"reflectance.*index \(3,\).*> 1"):
        r = np.full((5, 3), 0.5)
        r[3, 1] = 1.5
        bk.Diffuse(r)
    with pytest.raises(ValueError, match=r"eta.*index \(1,\).*not finite"):
        bk.Dielectric(np.array([1.5, np.nan]))
    with pytest.raises(ValueError, match=r"eta.*index \(0,\)"):
        bk.Dielectric(np.array([0.0, 1.5]))
    with pytest.raises(ValueError, match=r"eta: must differ from 1 \(at index \(2,\)\)"):
        bk.Plastic(eta=np.array([1.5, 1.4, 1.0]))
    with pytest.raises(ValueError, match=r"reflectance: expected trailing shape \(3,\)"):
        bk.Diffuse(np.full((4, 2), 0.5))
    m = bk.Conductor.from_metal("Cu", alpha=np.full(5, 0.2))
    with pytest.raises(ValueError, match=r"(wo|alpha_x).*\(5,\).*\(4,\)|\(4,\).*\(5,\)"):
        m.eval(random_dirs(np.random.default_rng(0), 4), bk.direction(0.2, 0.0))
    with pytest.raises(ValueError, match="wo: 5 direction"):   # counted per element, as broadcast
        m.eval(np.array([[0, 0, 2.0]]), bk.direction(0.2, 0.0))
    # the compiled class names the field of a knob given as an array
    with pytest.raises(TypeError, match=r"Conductor.masking: takes one value"):
        bk._core.Conductor(masking=np.zeros(3, dtype=int))
    with pytest.raises(ValueError, match=r"Diffuse.reflectance: must be finite.*index \(1,\)"):
        bk._core.Diffuse(reflectance=np.array([[0.5, 0.5, 0.5], [0.5, np.inf, 0.5]]))


def test_operations_that_need_one_material_refuse_clearly():
    m = bk.Conductor.from_metal("Cu", alpha=np.array([0.1, 0.2]))
    wo = bk.direction(0.3, 0.0)
    with pytest.raises(NotImplementedError, match="spectral mode.*alpha_x"):
        m.eval(wo, wo, wavelengths=[500.0, 550.0, 600.0, 650.0])
    with pytest.raises(NotImplementedError, match="to_mitsuba"):
        m.to_mitsuba()
    with pytest.raises(NotImplementedError, match="tradeoff"):
        bk.tradeoff(m)
    with pytest.raises(ValueError, match="eval_grad: a model with per-element parameters needs the batch shape"):
        m._core.eval_grad(np.zeros((2, 3)) + [0, 0, 1], np.zeros((2, 3)) + [0, 0, 1], 0, [[("alpha_x", -1)]],
                          np.zeros((2, 3)), np.zeros((2, 3, 1)))
    assert "per element" in m.describe()


def test_uniform_models_are_unchanged():
    m = bk.Conductor.from_metal("Cu", alpha=0.2)
    assert m.varying == () and m._core.varying == ()
    assert bk.Conductor.from_metal("Cu", alpha=np.float64(0.2)) == m   # a 0-d value is uniform


# ---- Mitsuba 3: per-element parameters as bitmap textures looked up at each element's texel centre

def _mitsuba_eval_pdf(bsdf_dict, wo, wi, uv):
    from bsdfkit.testing import mitsuba as ref
    mi, dr = ref._mi()
    bsdf = mi.load_dict(bsdf_dict)
    wo32, wi32 = wo.astype(np.float32), wi.astype(np.float32)
    si = ref._make_si(wo32)
    si.uv = mi.Point2f(np.ascontiguousarray(uv[:, 0], np.float32), np.ascontiguousarray(uv[:, 1], np.float32))
    val, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, ref._v3(wi32))
    dr.eval(val, pdf)
    n = len(wo)
    return ref._div_cos(ref._np(val, n, 3), np.abs(wi32[:, 2].astype(np.float64))), ref._np(pdf, n)


def _bitmap(values, H, W):
    from bsdfkit.testing import mitsuba as ref
    mi, _ = ref._mi()
    ch = 1 if values.ndim == 1 else values.shape[1]
    return {"type": "bitmap", "data": mi.TensorXf(values.astype(np.float32).reshape(H, W, ch)),
            "filter_type": "nearest", "raw": True}


def _rel(a, b):
    scale = np.quantile(np.abs(b[b != 0]), 0.99) if np.any(b != 0) else 1.0
    return np.abs(a - b) / np.maximum(np.abs(b), 1e-5 * scale)


@pytest.mark.parametrize("which", ["diffuse", "conductor-iso", "conductor-aniso", "dielectric"])
def test_per_element_parameters_match_mitsuba_bitmaps(which):
    pytest.importorskip("mitsuba")
    rng = np.random.default_rng(6)
    H, W = 40, 50
    n = H * W
    r, c = np.divmod(np.arange(n), W)
    uv = np.stack([(c + 0.5) / W, (r + 0.5) / H], axis=1)
    f32 = lambda x: x.astype(np.float32).astype(np.float64)   # noqa: E731  (the bitmap holds float32)
    wo = f32(random_dirs(rng, n, hemisphere=True))
    wi = random_dirs(rng, n)
    if which != "dielectric":
        wi[:, 2] = np.abs(wi[:, 2])
    wi = f32(wi)
    if which == "diffuse":
        refl = f32(rng.uniform(0, 1, (n, 3)))
        ours = bk.Diffuse(refl)
        d = {"type": "diffuse", "reflectance": _bitmap(refl, H, W)}
    elif which.startswith("conductor"):
        eta, k = f32(rng.uniform(0.2, 2.5, (n, 3))), f32(rng.uniform(0.5, 4, (n, 3)))
        ax = f32(rng.uniform(0.05, 0.7, n))
        ay = ax if which == "conductor-iso" else f32(rng.uniform(0.05, 0.7, n))
        ours = bk.Conductor(eta, k, alpha_x=ax, alpha_y=ay, masking="separable")
        d = {"type": "roughconductor", "distribution": "ggx", "sample_visible": True, "eta": _bitmap(eta, H, W),
             "k": _bitmap(k, H, W), "alpha_u": _bitmap(ax, H, W), "alpha_v": _bitmap(ay, H, W)}
    else:
        # Mitsuba's int_ior is a float, not a texture: eta stays uniform, the roughness varies
        ax = f32(rng.uniform(0.05, 0.7, n))
        ours = bk.Dielectric(1.5, alpha_x=ax, alpha_y=ax, masking="separable")
        d = {"type": "roughdielectric", "distribution": "ggx", "sample_visible": True, "int_ior": 1.5,
             "ext_ior": 1.0, "alpha": _bitmap(ax, H, W)}
    f_ref, p_ref = _mitsuba_eval_pdf(d, wo, wi, uv)
    f, p = ours.eval(wo, wi), ours.pdf(wo, wi)
    assert np.quantile(_rel(f, f_ref), 0.999) <= 1e-5
    assert np.quantile(_rel(p, p_ref), 0.999) <= 1e-5


def test_composites_over_per_element_children():
    rng = np.random.default_rng(9)
    n = 20
    inner = bk.FilamentStandard(base_color=rng.uniform(0, 1, (n, 3)), roughness=rng.uniform(0.2, 1, n))
    nm = bk.NormalMap(inner, normals=(0.1, 0.0, np.sqrt(1 - 0.01)))
    wo, wi = random_dirs(rng, n, hemisphere=True), random_dirs(rng, n, hemisphere=True)
    f = nm.eval(wo, wi)   # flat maps, one value per row: element i is NormalMap of element i's model
    for i in (0, 7, 19):
        ref = bk.NormalMap(bk.FilamentStandard(base_color=inner.base_color[i], roughness=inner.roughness[i]),
                           normals=(0.1, 0.0, np.sqrt(1 - 0.01)))
        _eq(f[i], ref.eval(wo[i:i + 1], wi[i:i + 1])[0], f"NormalMap element {i}")
    with pytest.raises(NotImplementedError, match="inside a composite.*albedo"):
        nm.albedo(wo, n_samples=8)
    # a (4, 5) map broadcasts with the composite's call: element (i, j) is the composite of (i, j)'s model
    R = rng.uniform(0, 1, (4, 5, 3))
    grid = bk.NormalMap(bk.Diffuse(R), normals=(0.1, 0.0, np.sqrt(1 - 0.01)))
    g = grid.eval(bk.direction(0.3, 0.0), bk.direction(0.4, 1.0))
    assert g.shape == (4, 5, 3)
    for i, j in ((0, 0), (2, 3), (3, 4)):
        ref = bk.NormalMap(bk.Diffuse(R[i, j]), normals=(0.1, 0.0, np.sqrt(1 - 0.01)))
        _eq(g[i, j], ref.eval(bk.direction(0.3, 0.0), bk.direction(0.4, 1.0)), f"NormalMap grid element {(i, j)}")
