"""The composite models (issue 47 items 2-3): Mix, TwoSided, Mask, NormalMap. Closed forms
(furnace, the reciprocity of the normal-map rule), per-element arrays against a loop of scalar
models, chi-square of the samplers, bad input, spectral pass-through, the renderer's refusal and
plots. The Mitsuba 3 cross-check is tests/models/test_composite_mitsuba.py."""
import pickle

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models.normal_map import shadow_terminator
from bsdfkit.testing import mitsuba as ref
from conftest import random_dirs

RAD, IMP = bk.TransportMode.Radiance, bk.TransportMode.Importance
GOLD = bk.Conductor.from_metal("Au", alpha=0.3, masking="separable")
RED = bk.Diffuse([0.8, 0.1, 0.1])


def _dir(z, phi=0.7):
    s = np.sqrt(1 - z * z)
    return np.array([s * np.cos(phi), s * np.sin(phi), z])


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


# ------------------------------------------------------------------ closed forms

@pytest.mark.parametrize("w", [0.0, 0.3, 1.0])
def test_white_furnace_of_mixed_white_diffuse(w, rng):
    """Mix(Diffuse(1), Diffuse(1), w): f = 1/pi, pdf = cos/pi, every sample's weight is 1, albedo 1."""
    m = bk.Mix(bk.Diffuse(1.0), bk.Diffuse(1.0), w)
    wo, wi = random_dirs(rng, 2000, 1), random_dirs(rng, 2000, 1)
    np.testing.assert_allclose(m.eval(wo, wi), 1 / np.pi, rtol=1e-15)
    np.testing.assert_allclose(m.pdf(wo, wi), wi[:, 2] / np.pi, rtol=1e-14)
    s = m.sample(wo, n=2000, seed=1)
    assert s.valid.all()
    np.testing.assert_allclose(s.weight, 1.0, rtol=1e-12)
    np.testing.assert_allclose(m.albedo(wo[:5], n_samples=4096), 1.0, rtol=1e-12)


def test_white_furnace_per_element_weights(rng):
    w = rng.random((3, 4))
    m = bk.Mix(bk.Diffuse(1.0), bk.Diffuse(1.0), w)
    np.testing.assert_allclose(m.albedo(_dir(0.6), n_samples=2048), 1.0, rtol=1e-12)
    assert m.albedo(_dir(0.6), n_samples=64).shape == (3, 4, 3)


def _normal_map_albedo_quadrature(n, wo, shadowing=True, nt=1200, nphi=2400):
    """Independent reference of the rule (NormalMap docstring) for a white Lambertian, Radiance:
    albedo(wo) = int over wi above both the geometric and the (flipped) shading surface of
    (wi . n) / pi G(wi) dwi (f |cos_g| = |cos_s| / pi G). Midpoint rule in (theta, phi)."""
    n = np.array(n, float)
    if wo[2] * np.dot(wo, n) <= 0:
        n[:2] *= -1
    t = (np.arange(nt) + 0.5) * (np.pi / 2) / nt
    p = (np.arange(nphi) + 0.5) * 2 * np.pi / nphi
    T, P = np.meshgrid(t, p, indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    cs = wi @ n
    g = shadow_terminator(n, wi) if shadowing else 1.0
    val = np.where(cs > 0, cs / np.pi * g, 0.0) * np.sin(T) * (np.pi / 2 / nt) * (2 * np.pi / nphi)
    return val.sum()


@pytest.mark.parametrize("shadowing", [True, False])
@pytest.mark.parametrize("n, z", [((0.36, -0.48, 0.8), 0.9), ((0.36, -0.48, 0.8), 0.3), ((0.6, 0.0, 0.8), 0.15),
                                  ((0.0, 0.28, 0.96), 0.5), ((-0.8, 0.0, 0.6), 0.7)])
def test_white_furnace_of_normal_mapped_diffuse(n, z, shadowing):
    """Normal-mapped white Lambertian under the rule we follow (Mitsuba 3.9 normalmap): its
    Radiance albedo is the quadrature of the rule (< 1: the wedge below the geometric surface is
    lost, and G < 1), sampled with weights G; <= 1 always."""
    m = bk.NormalMap(bk.Diffuse(1.0), _unit(n), shadowing=shadowing)
    wo = _dir(z)
    a = m.albedo(wo, n_samples=1 << 19, seed=3)
    expect = _normal_map_albedo_quadrature(_unit(n), wo, shadowing)
    np.testing.assert_allclose(a, expect, atol=2e-3)
    assert np.all(a <= 1 + 1e-12) and expect < 1


def test_normal_map_no_leaks_and_adjoint_reciprocity(rng):
    """The rule's consequences: f = pdf = 0 where wi is on different sides of the geometric and
    the shading normal; f(wo, wi, Radiance) = f(wi, wo, Importance) wherever neither direction
    needs the flip (then the frames agree), and a flip breaks it (as in Mitsuba)."""
    n = _unit([0.5, -0.3, 0.8])
    for model in (bk.Diffuse(0.7), GOLD, bk.Conductor(2.0, 4.0, alpha_x=0.5, alpha_y=0.1, masking="separable")):
        m = bk.NormalMap(model, n)
        wo, wi = random_dirs(rng, 20000, 1), random_dirs(rng, 20000, 1)
        ns = np.where((wo @ n <= 0)[:, None], n * [-1, -1, 1], n)   # the flipped normal where wo needs it
        leak = wi[:, 2] * np.einsum("ij,ij->i", wi, ns) <= 0
        assert leak.any()
        assert np.all(m.eval(wo, wi)[leak] == 0) and np.all(m.pdf(wo, wi)[leak] == 0)
        noflip = (wo @ n > 0) & (wi @ n > 0)
        f_rad, f_imp = m.eval(wo, wi, mode=RAD), m.eval(wi, wo, mode=IMP)
        np.testing.assert_allclose(f_rad[noflip], f_imp[noflip], rtol=1e-9, atol=1e-300)
        flip = (wo @ n <= 0) & (f_rad.max(1) > 0)
        assert flip.any() and not np.allclose(f_rad[flip], f_imp[flip])


def test_normal_map_flat_normal_is_the_model_times_g(rng):
    """n = +z: the shading frame is the geometric one, f = f_model G(wi), G = 1 at n = z."""
    m = bk.NormalMap(GOLD, (0.0, 0.0, 1.0))
    wo, wi = random_dirs(rng, 5000, 1), random_dirs(rng, 5000, 1)
    np.testing.assert_allclose(m.eval(wo, wi), GOLD.eval(wo, wi), rtol=1e-14)
    np.testing.assert_allclose(m.pdf(wo, wi), GOLD.pdf(wo, wi), rtol=1e-14)


def test_two_sided_sides_and_no_transmission(rng):
    """Above: the front; below: the back with z of both directions flipped; 0 across."""
    m = bk.TwoSided(GOLD, RED)
    wo, wi = random_dirs(rng, 4000), random_dirs(rng, 4000)
    f, p = m.eval(wo, wi), m.pdf(wo, wi)
    up, dn = (wo[:, 2] > 0) & (wi[:, 2] > 0), (wo[:, 2] < 0) & (wi[:, 2] < 0)
    flip = np.array([1, 1, -1])
    np.testing.assert_array_equal(f[up], GOLD.eval(wo[up], wi[up]))
    np.testing.assert_array_equal(f[dn], RED.eval(wo[dn] * flip, wi[dn] * flip))
    np.testing.assert_array_equal(p[dn], RED.pdf(wo[dn] * flip, wi[dn] * flip))
    assert np.all(f[~(up | dn)] == 0) and np.all(p[~(up | dn)] == 0)
    # a dielectric's reflection alone, sampled alone: sampled weights average to its reflectance
    glass = bk.TwoSided(bk.Dielectric(1.5))
    s = glass.sample(_dir(0.8), n=1000, seed=2)
    assert s.valid.all() and np.all(s.wi[:, 2] > 0)
    assert not glass.flags & bk.BxDFFlags.Transmission


def test_mask_pass_through(rng):
    """Mitsuba mask: f and pdf scaled by the opacity; the pass-through is a delta wi = -wo of
    throughput weight 1 drawn with probability 1 - opacity."""
    m = bk.Mask(RED, 0.7)
    wo, wi = random_dirs(rng, 3000, 1), random_dirs(rng, 3000, 1)
    np.testing.assert_allclose(m.eval(wo, wi), 0.7 * RED.eval(wo, wi), rtol=1e-15)
    np.testing.assert_allclose(m.pdf(wo, wi), 0.7 * RED.pdf(wo, wi), rtol=1e-15)
    np.testing.assert_allclose(m.pdf(wo, wi, sample_flags=bk.ReflTrans.Reflection), RED.pdf(wo, wi), rtol=1e-15)
    s = m.sample(wo[0], n=20000, seed=4)
    thru = s.valid & ((s.flags & bk.BxDFFlags.Specular) != 0)
    assert abs(thru.mean() - 0.3) < 0.015
    np.testing.assert_allclose(s.wi[thru], -np.broadcast_to(wo[0], s.wi[thru].shape))
    np.testing.assert_allclose(s.weight[thru], 1.0, rtol=1e-12)
    assert np.all(s.flags[thru] == bk.BxDFFlags.SpecularTransmission)
    # the albedo of a white model under a mask counts the pass-through: 1
    np.testing.assert_allclose(bk.Mask(bk.Diffuse(1.0), 0.4).albedo(wo[:3], n_samples=4096), 1.0, rtol=1e-12)


def test_mix_sample_matches_mitsuba_rules():
    """b where uc <= weight, the child given uc / w or (uc - w) / (1 - w); the returned f and pdf
    are the mixture's; a delta lobe returns its own f and pdf times the selection probability."""
    mirror = bk.Conductor.from_metal("Ag")
    m = bk.Mix(RED, mirror, 0.25)
    wo = _dir(0.6)
    uc = np.array([0.1, 0.25, 0.26, 0.9])
    u = np.full((4, 2), 0.3)
    s = m.sample(wo, uc, u)
    sm = mirror.sample(wo, uc[:2] / 0.25, u[:2])
    sr = RED.sample(wo, (uc[2:] - 0.25) / 0.75, u[2:])
    np.testing.assert_allclose(s.wi[:2], sm.wi)
    np.testing.assert_allclose(s.f[:2], 0.25 * sm.f)
    np.testing.assert_allclose(s.pdf[:2], 0.25 * sm.pdf)
    np.testing.assert_allclose(s.wi[2:], sr.wi)
    np.testing.assert_allclose(s.f[2:], 0.75 * sr.f)            # the mirror's eval is 0
    np.testing.assert_allclose(s.pdf[2:], 0.75 * sr.pdf)


# ------------------------------------------------------------------ per-element arrays

def _loop_equal(m_arr, scalar_of, wo, wi, uc, u):
    f, p, s = m_arr.eval(wo, wi), m_arr.pdf(wo, wi), m_arr.sample(wo, uc, u)
    for i in range(len(wo)):
        mi = scalar_of(i)
        np.testing.assert_array_equal(f[i], mi.eval(wo[i], wi[i]))
        np.testing.assert_array_equal(p[i], mi.pdf(wo[i], wi[i]))
        si = mi.sample(wo[i], uc[i], u[i])
        for k in ("wi", "f", "pdf", "flags", "valid"):
            np.testing.assert_array_equal(getattr(s, k)[i], getattr(si, k), err_msg=k)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_per_element_parameters_equal_a_loop_of_scalar_models(dtype, rng):
    n = 48
    wo, wi = random_dirs(rng, n, dtype=dtype), random_dirs(rng, n, dtype=dtype)
    uc, u = rng.random(n).astype(dtype), rng.random((n, 2)).astype(dtype)
    w = rng.random(n)
    w[:4] = [0, 1, 0.5, 1e-9]
    _loop_equal(bk.Mix(RED, GOLD, w), lambda i: bk.Mix(RED, GOLD, float(w[i])), wo, wi, uc, u)
    key = rng.integers(0, 2 ** 40, n)
    _loop_equal(bk.Mix(RED, GOLD, w, method="stochastic", key=key),
                lambda i: bk.Mix(RED, GOLD, float(w[i]), method="stochastic", key=int(key[i])), wo, wi, uc, u)
    _loop_equal(bk.Mask(GOLD, w), lambda i: bk.Mask(GOLD, float(w[i])), wo, wi, uc, u)
    nrm = random_dirs(rng, n, 1)
    nrm[:, 2] += 1.5
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    _loop_equal(bk.NormalMap(GOLD, nrm), lambda i: bk.NormalMap(GOLD, nrm[i]), wo, wi, uc, u)


def test_parameter_maps_broadcast_the_batch():
    wmap = np.linspace(0, 1, 12).reshape(3, 4)
    m = bk.Mix(RED, GOLD, wmap)
    f = m.eval(_dir(0.5), _dir(0.7, 2.0))
    assert f.shape == (3, 4, 3)
    np.testing.assert_allclose(f[2, 3], GOLD.eval(_dir(0.5), _dir(0.7, 2.0)))
    assert m.sample(_dir(0.5), 0.3, (0.2, 0.4)).wi.shape == (3, 4, 3)
    with pytest.raises(ValueError, match=r"weight.*\(3, 4\).*\(5,\)|\(5,\).*weight.*\(3, 4\)"):
        m.eval(np.tile(_dir(0.5), (5, 1)), _dir(0.7))


def test_stochastic_mix_picks_by_weight_and_hash(rng):
    wo = random_dirs(rng, 40000, 1)
    m = bk.Mix(bk.Diffuse(0.2), bk.Diffuse(0.9), 0.3, method="stochastic")
    f = m.eval(wo, _dir(0.9))[:, 0]
    frac_b = np.mean(f > 0.5 / np.pi)
    assert abs(frac_b - 0.3) < 0.01
    # float32 and float64 choose alike; another key per element chooses otherwise
    f32 = m.eval(wo.astype(np.float32), _dir(0.9).astype(np.float32))[:, 0]
    assert np.array_equal(f32 > 0.5 / np.pi, f > 0.5 / np.pi)
    mk = bk.Mix(bk.Diffuse(0.2), bk.Diffuse(0.9), 0.3, method="stochastic", key=np.arange(40000))
    assert not np.array_equal(mk.eval(wo, _dir(0.9))[:, 0] > 0.5 / np.pi, f > 0.5 / np.pi)
    # in expectation the linear blend
    lin = bk.Mix(bk.Diffuse(0.2), bk.Diffuse(0.9), 0.3)
    np.testing.assert_allclose(f.mean(), lin.eval(wo[0], _dir(0.9))[0], rtol=0.01)


# ------------------------------------------------------------------ value semantics, bad input

def test_value_semantics_with_arrays(rng):
    big = rng.random((256, 256))
    m = bk.Mix(RED, GOLD, big)
    r = repr(m)
    assert len(r) < 600 and "digest" in r and "(256, 256)" in r
    m2 = pickle.loads(pickle.dumps(m))
    assert m2 == m and hash(m2) == hash(m)
    other = big.copy()
    other[7, 9] += 1e-9
    assert bk.Mix(RED, GOLD, other) != m
    small = bk.NormalMap(RED, np.array([[0, 0, 1.0], [0.6, 0, 0.8]]))
    assert eval(repr(small), {c: getattr(bk, c) for c in bk.__all__}) == small   # noqa: S307


def test_bad_input_names_the_parameter_and_index():
    w = np.full((2, 3), 0.5)
    w[1, 2] = 1.5
    with pytest.raises(ValueError, match=r"weight.*index \(1, 2\).*1\.5"):
        bk.Mix(RED, GOLD, w)
    with pytest.raises(ValueError, match=r"opacity.*index \(3,\).*nan"):
        bk.Mask(RED, [0.1, 0.2, 0.3, np.nan])
    with pytest.raises(ValueError, match=r"weight"):
        bk.Mix(RED, GOLD, -0.1)
    n = np.tile([0.0, 0.0, 1.0], (4, 1))
    n[2] = (0.3, 0.3, 0.9)
    with pytest.raises(ValueError, match=r"normals.*unit.*index \(2,\)"):
        bk.NormalMap(RED, n)
    with pytest.raises(ValueError, match=r"normals.*z > 0.*index \(\)"):
        bk.NormalMap(RED, (0.0, 0.6, -0.8))
    with pytest.raises(ValueError, match="convention"):
        bk.NormalMap(RED, (0, 0, 1.0), convention="vulkan")
    with pytest.raises(TypeError, match="b: expected a bsdfkit model"):
        bk.Mix(RED, 3.0)
    with pytest.raises(ValueError, match="method"):
        bk.Mix(RED, GOLD, method="average")
    with pytest.raises(ValueError, match="wo: 1 direction"):
        bk.Mix(RED, GOLD).eval([0, 0, 2.0], [0, 0, 1.0])
    with pytest.raises(ValueError, match="uc:"):
        bk.TwoSided(RED).sample(_dir(0.5), 1.5, (0.1, 0.1))


def test_directx_convention_flips_y(rng):
    n = _unit([0.3, 0.4, 0.8])
    wo, wi = random_dirs(rng, 500, 1), random_dirs(rng, 500, 1)
    a = bk.NormalMap(GOLD, n, convention="directx").eval(wo, wi)
    b = bk.NormalMap(GOLD, n * [1, -1, 1]).eval(wo, wi)
    np.testing.assert_array_equal(a, b)


# ------------------------------------------------------------------ spectral, renderer, plots

def test_spectral_mode_passes_through(rng):
    lam = bk.sample_wavelengths(rng.random(300))[0]
    wo, wi = random_dirs(rng, 300, 1), random_dirs(rng, 300, 1)
    m = bk.Mix(RED, GOLD, 0.3)
    f = m.eval(wo, wi, wavelengths=lam)
    np.testing.assert_allclose(f, 0.7 * RED.eval(wo, wi, wavelengths=lam) + 0.3 * GOLD.eval(wo, wi, wavelengths=lam),
                               rtol=1e-14)
    s = bk.NormalMap(m, _unit([0.2, 0.1, 0.9])).sample(wo, n=300, seed=1, wavelengths=lam)
    assert s.f.shape == (300, 4) and s.terminated.shape == (300,)
    assert bk.Mask(m, 0.5).albedo(wo[:2], n_samples=256, wavelengths=lam[:2]).shape == (2, 4)
    custom = bk.Custom(f=lambda a, b: np.full(np.broadcast_shapes(a.shape, b.shape)[:-1] + (3,), 0.1), name="flat")
    with pytest.raises(NotImplementedError, match="Custom"):
        bk.Mix(RED, custom).eval(wo, wi, wavelengths=lam)


def test_renderer_refuses_python_composites_by_name():
    for m in (bk.Mix(RED, GOLD), bk.TwoSided(GOLD), bk.Mask(RED, 0.5), bk.NormalMap(RED, (0, 0, 1.0))):
        with pytest.raises(TypeError, match=f"{type(m).__name__}.*compiled models only"):
            bk.render.preview(m, width=4, height=4, spp=1, progress=False)


def test_polar_plot_of_composites(tmp_path):
    from bsdfkit import plot as bkplot
    ax = bkplot.polar([bk.Mix(RED, GOLD, 0.4), bk.NormalMap(GOLD, _unit([0.3, 0, 0.9]))], theta_o=40, log=True)
    ax.figure.savefig(tmp_path / "composite_polar.png", dpi=60)
    assert (tmp_path / "composite_polar.png").stat().st_size > 5000


# ------------------------------------------------------------------ chi-square of the samplers

R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])   # local z to the domain's -y (test_pbrt_chi2)
_TILTS = [_unit(v) for v in ([0.5, 0.1, 0.8], [-0.3, 0.6, 0.7], [0.0, 0.0, 1.0], [0.7, -0.2, 0.6], [0.1, 0.1, 0.95])]
CHI2 = ([(f"mix-z{z}", bk.Mix(RED, GOLD, 0.35), z) for z in (0.95, 0.6, 0.3, 0.1, -0.5)]
        + [("mix-weights-z0.7", bk.Mix(bk.Diffuse(0.5), bk.Conductor.from_metal("Cu", alpha=0.5, masking="separable"),
                                       0.8), 0.7)]
        + [(f"twosided-z{z}", bk.TwoSided(GOLD, bk.Mix(RED, bk.Conductor.from_metal("Al", alpha=0.2), 0.5)), z)
           for z in (0.9, 0.4, 0.1, -0.3, -0.8)]
        + [(f"normalmap-{i}", bk.NormalMap(GOLD if i % 2 else RED, n), z)
           for i, (n, z) in enumerate(zip(_TILTS, (0.8, 0.5, 0.3, 0.6, -0.7)))])


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
    print(f"{name}: p = {p:.4g}")
    assert passed, msg
