"""Principled and PrincipledThin against Mitsuba 3's ``principled`` / ``principledthin`` plugins
(``bsdfkit.testing.principled_ref``: Mitsuba 3.9.1, ``llvm_ad_rgb``, float32):

* eval and pdf on 20,000 random direction pairs (both sides of the surface) x 9 parameter sets
  (Principled, both transport modes) and x 8 (PrincipledThin). Required: p99.9 of the relative
  error <= 1e-5 on every smooth lobe, i.e. every reflection pair of both models and every pair of
  PrincipledThin (measured: p99.9 <= 8e-6, most sets ~5e-7). Two cases cannot meet it against a
  float32 reference, and the test says why with numbers: Principled's rough *transmission* (its
  half vector wo + eta wi, its Fresnel transmittance near total internal reflection and the GGX
  tail are ill-conditioned in float32: bsdfkit's own float32 kernel strays from its float64 one by
  up to ~3e-3 at p99.9 at the same pairs) and the near-delta "glossy" set (alpha 0.01, clear-coat
  alpha 0.001: float32's own p99.9 ~2e-5). There Mitsuba is held to the float32 rounding of the
  same formula: 99.9 % of the pairs within 1e-5 + 100 x bsdfkit-float32's own error of the pair, and
  p99.9 <= 1e-5 on the pairs float32 evaluates to 1e-6;
* Mitsuba's own test cases (src/bsdfs/tests/test_principled*.py), written anew: the lobes of the
  default, transmissive and anisotropic materials; chi^2 of the configurations its chi^2 tests use
  (at their incidence and at 5 more), and eval/pdf along its 20-angle arc (compared with Mitsuba
  live, not with its stored numbers, which were taken at an unnormalized wi);
* chi^2 (Mitsuba's harness) of bsdfkit's sampler against bsdfkit's pdf at >= 5 incident angles;
* the specular -> eta rule (against Mitsuba's own conversion) and its transmission special cases;
* per-element parameters bit-identical to a loop of scalar models; bad input naming the parameter;
  Mitsuba import (dict, XML, loaded BSDF) and export, round trip through ``mi.load_dict``; spectral
  mode refused with its reason.

The generic contracts (sample vs eval/pdf, float32, pickling, extremes, ...) run on the registered
examples in tests/contract/.
"""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.directions import random_directions
from bsdfkit.models.principled import specular_to_eta

mi_ref = pytest.importorskip("bsdfkit.testing.principled_ref")

PRINCIPLED_SETS = {
    "default": {},
    "metal aniso": dict(base_color=[0.9, 0.6, 0.3], roughness=0.3, anisotropic=0.7, metallic=0.8, spec_tint=0.3),
    "glass": dict(base_color=[0.8, 0.9, 1.0], roughness=0.2, spec_trans=0.9, eta=1.5),
    "coat sheen": dict(base_color=[0.2, 0.5, 0.8], roughness=0.6, clearcoat=0.8, clearcoat_gloss=0.4, sheen=0.7,
                       sheen_tint=0.5),
    "flat": dict(base_color=[0.7, 0.3, 0.2], roughness=0.9, flatness=0.8, sheen=0.3),
    # Mitsuba's test05 material (specular, not eta: Mitsuba converts it)
    "mitsuba arc": dict(metallic=0.3, spec_tint=0.6, specular=0.4, anisotropic=0.3, clearcoat=0.3,
                        clearcoat_gloss=0.5, sheen=0.9, sheen_tint=0.9, spec_trans=0.5, flatness=0.5),
    "eta < 1": dict(roughness=0.8, metallic=0.2, clearcoat=1.0, spec_trans=0.5, eta=0.5),
    "rates": dict(base_color=[0.4, 0.4, 0.1], roughness=0.45, metallic=0.5, spec_trans=0.4, clearcoat=0.5, eta=1.33,
                  main_specular_sampling_rate=0.5, clearcoat_sampling_rate=2.0,
                  diffuse_reflectance_sampling_rate=0.7),
    "glossy": dict(base_color=[0.1, 0.1, 0.1], roughness=0.1, clearcoat=1.0, clearcoat_gloss=1.0, spec_tint=1.0),
}

THIN_SETS = {
    "default": {},
    "glossy sheet": dict(base_color=[0.8, 0.6, 0.4], roughness=0.3, anisotropic=0.5, spec_trans=0.7, eta=1.4,
                         spec_tint=0.4),
    "leaf": dict(base_color=[0.3, 0.7, 0.2], roughness=0.7, diff_trans=1.2, sheen=0.5, sheen_tint=0.6, flatness=0.5),
    "all": dict(base_color=[0.5, 0.4, 0.3], roughness=0.5, spec_trans=0.4, diff_trans=0.8, eta=1.2, spec_tint=0.3,
                sheen=0.4, flatness=0.3, specular_reflectance_sampling_rate=0.5,
                diffuse_transmittance_sampling_rate=2.0),
    "mitsuba arc": dict(eta=1.5, anisotropic=0.5, sheen=0.5, sheen_tint=0.2, spec_trans=0.5, flatness=0.5,
                        diff_trans=0.6),
    "all diffuse transmission": dict(base_color=[0.9, 0.8, 0.7], roughness=0.2, diff_trans=2.0),
    "specular only": dict(base_color=[1.0, 0.9, 0.8], roughness=0.25, spec_trans=1.0, eta=1.7),
    "eta < 1": dict(roughness=0.6, spec_trans=0.6, eta=0.7, diff_trans=0.4, anisotropic=0.9),
}

N_PAIRS = 20_000


def _model(params, thin):
    return (bk.PrincipledThin if thin else bk.Principled)(**params)


def _pairs(seed):
    rng = np.random.default_rng(seed)
    f32 = lambda a: a.astype(np.float32).astype(np.float64)   # noqa: E731  (Mitsuba's inputs)
    return f32(random_directions(N_PAIRS, rng)), f32(random_directions(N_PAIRS, rng))


def _rel(got, want):
    """Per pair: the largest relative error over the channels (0 where both are 0)."""
    got, want = np.atleast_2d(got.T).T, np.atleast_2d(want.T).T
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.abs(got - want) / np.abs(want)
    r = np.where((got == 0) & (want == 0), 0.0, r)
    return r.reshape(len(r), -1).max(axis=1)


def _compare(params, thin, mode):
    """(ours f, pdf), (Mitsuba f, pdf), ours in float32, the comparable mask and the pairs."""
    wo, wi = _pairs(7)
    m = _model(params, thin)
    f, p = m.eval(wo, wi, mode), m.pdf(wo, wi, mode)
    mf, mp = mi_ref.eval_pdf(params, wo, wi, mode, thin=thin)
    f32, p32 = (m.eval(wo.astype(np.float32), wi.astype(np.float32), mode).astype(np.float64),
                m.pdf(wo.astype(np.float32), wi.astype(np.float32), mode).astype(np.float64))
    ok = mi_ref.comparable(params, wo, thin)
    return (f, p), (mf, mp), (f32, p32), ok, wo, wi


#: Near-delta sets (alpha 0.01, clear-coat alpha 0.001): their reflection lobes are as
#: ill-conditioned in float32 as the transmission (bsdfkit's own float32 p99.9 is ~2e-5 there).
NEAR_DELTA = ("glossy",)


def _float32_rule(e, e32, where):
    """Mitsuba (float32) against bsdfkit float64 where float32 rounding itself is large: 99.9 % of
    the pairs within 1e-5 + 100 x bsdfkit-float32's own error of the same pair, and p99.9 <= 1e-5 on
    the pairs float32 evaluates to 1e-6 (bsdfkit-float32 vs float64). Returns the figures."""
    e, e32 = e[where], e32[where]
    within = float(np.mean(e <= 1e-5 + 100 * e32))
    well = e32 <= 1e-6
    q_well = float(np.quantile(e[well], 0.999))
    assert within >= 0.999 and q_well <= 1e-5, (within, q_well)
    return f"float32's own p99.9 {np.quantile(e32, 0.999):.1e}, within x100 {within:.5f}, " \
           f"well-conditioned ({well.sum()}) p99.9 {q_well:.1e}"


@pytest.mark.parametrize("mode", ["radiance", "importance"])
@pytest.mark.parametrize("name", list(PRINCIPLED_SETS))
def test_principled_matches_mitsuba(name, mode):
    params = PRINCIPLED_SETS[name]
    (f, p), (mf, mp), (f32, p32), ok, wo, wi = _compare(params, False, mode)
    assert np.all(f[~ok] == 0) and np.all(p[~ok] == 0)            # black from below without transmission
    refl = ok & (wo[:, 2] * wi[:, 2] > 0)
    trans = ok & (wo[:, 2] * wi[:, 2] < 0)
    for what, e, e32 in (("f", _rel(f, mf), _rel(f32, f)), ("pdf", _rel(p, mp), _rel(p32, p))):
        q, mx = np.quantile(e[refl], 0.999), e[refl].max()
        msg = f"principled {name} {mode} {what} reflection ({refl.sum()}): p99.9 {q:.2e} max {mx:.2e}"
        if name in NEAR_DELTA:
            msg += "; " + _float32_rule(e, e32, refl)
        else:
            assert q <= 1e-5, (what, q)                            # the smooth reflection lobes
        if trans.any() and (f[trans] > 0).any():
            et = e[trans]
            msg += (f" | transmission ({trans.sum()}): p99.9 {np.quantile(et, 0.999):.2e} max {et.max():.2e}; "
                    + _float32_rule(e, e32, trans))
        print(msg)
    # where one of them is 0 and the other not, both are at the float32 edge of a mask (a horizon or
    # the 1e-20 cut of D): a handful of pairs at most (none measured)
    zero_mismatch = ok & ((f.max(1) > 0) != (mf.max(1) > 0))
    assert zero_mismatch.sum() <= N_PAIRS * 1e-3


@pytest.mark.parametrize("name", list(THIN_SETS))
def test_principled_thin_matches_mitsuba(name):
    params = THIN_SETS[name]
    (f, p), (mf, mp), _, ok, wo, wi = _compare(params, True, "radiance")
    assert ok.all()
    for what, e in (("f", _rel(f, mf)), ("pdf", _rel(p, mp))):
        q, mx = np.quantile(e, 0.999), e.max()
        print(f"principledthin {name} {what}: p99.9 {q:.2e} max {mx:.2e}")
        assert q <= 1e-5, (what, q)
    np.testing.assert_array_equal(f, _model(params, True).eval(wo, wi, "importance"))   # no refraction


def test_sheen_follows_the_mask_formula():
    """spec_trans = 1 leaves no diffuse lobe; the sheen stays (Mitsuba's JIT variants; scalar_rgb
    skips it with the diffuse block: principled_ref's notes)."""
    params = dict(spec_trans=1.0, sheen=1.0, roughness=0.5)
    wo, wi = _pairs(3)
    up = (wo[:, 2] > 0) & (wi[:, 2] > 0)
    f = _model(params, False).eval(wo, wi)
    mf, _ = mi_ref.eval_pdf(params, wo, wi)
    assert np.all(f[up] > 0)
    assert np.quantile(_rel(f[up], mf[up]), 0.999) <= 1e-5


# ------------------------------------------------------------------ Mitsuba's own cases, rewritten

def _flags(m):
    return bk.BxDFFlags(m.flags)


def test_lobes_of_the_default_transmissive_and_anisotropic_materials():
    F = bk.BxDFFlags
    d = _flags(bk.Principled())
    assert F.DiffuseReflection in d and F.GlossyReflection in d and not (d & F.Transmission)
    t = _flags(bk.Principled(spec_trans=0.5))
    assert F.DiffuseReflection in t and F.GlossyReflection in t and F.GlossyTransmission in t
    a = _flags(bk.Principled(clearcoat=0.5, anisotropic=0.5))
    assert F.DiffuseReflection in a and F.GlossyReflection in a and not (a & F.Transmission)
    # no lobe of weight 0: spec_trans = 1 has no diffuse lobe, a metal no transmission
    assert F.DiffuseReflection not in _flags(bk.Principled(spec_trans=1.0))
    assert not (_flags(bk.Principled(spec_trans=0.5, metallic=1.0)) & F.Transmission)
    # thin: Mitsuba always lists a glossy reflection; bsdfkit only where spec_trans (its weight) > 0
    assert _flags(bk.PrincipledThin()) == F.DiffuseReflection
    st = _flags(bk.PrincipledThin(spec_trans=0.5))
    assert F.GlossyReflection in st and F.GlossyTransmission in st
    assert F.DiffuseTransmission in _flags(bk.PrincipledThin(diff_trans=0.5))


@pytest.mark.parametrize("thin", [False, True], ids=["principled", "thin"])
def test_eval_pdf_along_mitsubas_arc(thin):
    """Mitsuba's test05 (test03 for the thin plugin): wo at 45 degrees, wi along 20 angles in its
    plane, against Mitsuba live (its stored values were taken with an unnormalized wi)."""
    params = (THIN_SETS if thin else PRINCIPLED_SETS)["mitsuba arc"]
    wo = np.array([1.0, 0.0, 1.0]) / np.sqrt(2)
    th = np.arange(20) / 19 * (np.pi / 2)
    wi = np.stack([np.sin(th), np.zeros(20), np.cos(th)], 1)
    m = _model(params, thin)
    f, p = m.eval(wo, wi), m.pdf(wo, wi)
    mf, mp = mi_ref.eval_pdf(params, np.broadcast_to(wo, wi.shape), wi, thin=thin)
    live = wi[:, 2] > 1e-6                    # the last point is on the horizon (cos = 4e-17 in Mitsuba)
    np.testing.assert_allclose(f[live], mf[live], rtol=1e-5, atol=0)
    np.testing.assert_allclose(p[live], mp[live], rtol=1e-5, atol=0)
    assert np.all(np.diff(p[live]) < 0)       # the pdf falls towards the horizon (Mitsuba's values do)


# chi^2: Mitsuba's configurations at their incidence (wi = (1, 0, +-1) / sqrt 2) and our own at
# five more angles. (x, y, z) -> (x, -z, y): local z to the domain's -y axis, off the harness's pole
# (tests/models/test_pbrt_chi2.py).
R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
MITSUBA_CHI2 = [
    (False, dict(roughness=0.6, metallic=0.4, anisotropic=0.4, clearcoat=0.8, eta=1.33), 0.7071),
    (False, dict(roughness=0.6, metallic=0.2, anisotropic=0.4, clearcoat=0.8, spec_trans=0.7, eta=1.3296), 0.7071),
    (False, dict(roughness=0.5, anisotropic=0.4, clearcoat=0.8, spec_trans=0.7, eta=1.5), -0.7071),
    (False, dict(roughness=0.8, metallic=0.2, clearcoat=1.0, spec_trans=0.5, eta=0.5), 0.7071),
    (True, dict(roughness=0.6, anisotropic=0.5, spec_trans=0.4, eta=1.3296, diff_trans=0.6), 0.7071),
    (True, dict(roughness=0.6, anisotropic=0.5, spec_trans=0.6, eta=1.3296, diff_trans=0.9), -0.7071),
]
OWN_CHI2 = [(thin, params, z) for thin, params in (
    (False, PRINCIPLED_SETS["mitsuba arc"]), (False, PRINCIPLED_SETS["coat sheen"]),
    (False, PRINCIPLED_SETS["rates"]), (True, THIN_SETS["all"]))
    for z in (0.98, 0.6, 0.3, 0.08, -0.5) if z > 0 or thin or params.get("spec_trans", 0) > 0]
CHI2 = MITSUBA_CHI2 + OWN_CHI2


def _dir(z, phi=0.4):
    s = np.sqrt(max(0.0, 1.0 - z * z))
    return np.array([s * np.cos(phi), s * np.sin(phi), z])


@pytest.mark.parametrize("thin, params, z", CHI2,
                         ids=[f"{'thin' if t else 'principled'}-{i}-z{z}" for i, (t, _, z) in enumerate(CHI2)])
def test_chi2_sampling(thin, params, z):
    from bsdfkit.testing import mitsuba as mref
    m = _model(params, thin)
    wo = _dir(z)

    def sample_fn(uc, u):
        s = m.sample(wo, uc, u)
        near_horizon = np.abs(s.wi[:, 2]) < 1e-6   # the harness's float32 edge (test_pbrt_chi2)
        return s.wi @ R.T, s.valid & ~near_horizon

    def pdf_fn(v):
        return m.pdf(wo, v @ R)

    passed, p, msg = mref.chi2_test(sample_fn, pdf_fn, res=101, ires=16, sample_count=1_000_000, seed=5,
                                    significance=0.01, test_count=len(CHI2))
    print(f"chi2 {'PrincipledThin' if thin else 'Principled'} {params} z={z}: p = {p:.4g}")
    assert passed, msg


# ------------------------------------------------------------------ eta / specular

def test_specular_sets_eta_as_mitsuba_does():
    assert specular_to_eta(0.5) == pytest.approx(1.5, rel=1e-15)
    assert bk.Principled(specular=0.4).eta == specular_to_eta(0.4)
    assert bk.Principled().eta == specular_to_eta(0.5)
    with pytest.raises(ValueError, match="eta, specular"):
        bk.Principled(eta=1.5, specular=0.5)
    # against Mitsuba's own conversion and its transmission special cases: from above (the Fresnel
    # term among the other lobes) p99.9 <= 1e-5; from below, where the (1 - metallic) spec_trans
    # weighted Fresnel reflection is alone, Mitsuba's float32 Fresnel amplitudes (cos_i - eta cos_t)
    # cancel as eta -> 1: relative error ~ eps32 / |eta - 1| (measured 2-10x that: 1.4e-4 at eta
    # 1.001, 3e-5 at 1.018), bounded by 1e-5 + 20 x 6e-8 / |eta - 1|
    wo, wi = _pairs(11)
    for params in (dict(specular=0.3, metallic=0.2), dict(specular=0.0, spec_trans=0.6, roughness=0.4),
                   dict(eta=1.0, spec_trans=0.6, roughness=0.4)):
        m = bk.Principled(**params)
        mf, mp = mi_ref.eval_pdf(params, wo, wi)
        above = (wo[:, 2] > 0) & (wi[:, 2] > 0)
        below = (wo[:, 2] < 0) & (wi[:, 2] < 0) & mi_ref.comparable(params, wo)
        for e in (_rel(m.eval(wo, wi), mf), _rel(m.pdf(wo, wi), mp)):
            assert np.quantile(e[above], 0.999) <= 1e-5, params
            if below.any():
                bound = 1e-5 + 20 * 6e-8 / abs(m.eta - 1)
                print(params, f"eta {m.eta}: below p99.9 {np.quantile(e[below], 0.999):.2e} max "
                      f"{e[below].max():.2e} (bound {bound:.1e})")
                assert e[below].max() <= bound, params
    assert bk.Principled(specular=0.0, spec_trans=0.6).eta == specular_to_eta(1e-3)
    assert bk.Principled(eta=1.0, spec_trans=0.6).eta == 1.001
    assert bk.Principled(eta=1.0).eta == 1.0   # no transmission: kept


# ------------------------------------------------------------------ per-element parameters

@pytest.mark.parametrize("thin", [False, True], ids=["principled", "thin"])
def test_per_element_parameters_equal_a_loop_of_scalar_models(thin):
    rng = np.random.default_rng(5)
    shape = (3, 4)
    cls = bk.PrincipledThin if thin else bk.Principled
    names = ["roughness", "anisotropic", "spec_trans", "sheen", "flatness"] + (
        ["diff_trans", "eta"] if thin else ["metallic", "clearcoat", "clearcoat_gloss", "spec_tint"])
    arrays = {k: rng.uniform(0.0, 1.0, shape) for k in names}
    if thin:
        arrays["eta"] = rng.uniform(1.1, 1.8, shape)
    arrays["base_color"] = rng.uniform(0.0, 1.0, shape + (3,))
    m = cls(**arrays)
    assert set(m.varying) == set(arrays)
    wo = random_directions(12, rng).reshape(shape + (3,))
    wi = random_directions(12, rng).reshape(shape + (3,))
    uc, u = rng.uniform(size=shape), rng.uniform(size=shape + (2,))
    for dt in (np.float64, np.float32):
        f, p = m.eval(wo.astype(dt), wi.astype(dt)), m.pdf(wo.astype(dt), wi.astype(dt))
        s = m.sample(wo.astype(dt), uc.astype(dt), u.astype(dt))
        for idx in np.ndindex(shape):
            one = cls(**{k: (v[idx] if k != "base_color" else v[idx].tolist()) for k, v in arrays.items()})
            assert np.array_equal(f[idx], one.eval(wo[idx].astype(dt), wi[idx].astype(dt)))
            assert np.array_equal(p[idx], one.pdf(wo[idx].astype(dt), wi[idx].astype(dt)))
            s1 = one.sample(wo[idx].astype(dt), uc[idx].astype(dt), u[idx].astype(dt))
            assert np.array_equal(s.wi[idx], s1.wi) and np.array_equal(s.f[idx], s1.f)
            assert np.array_equal(s.pdf[idx], s1.pdf)


@pytest.mark.parametrize("thin", [False, True], ids=["principled", "thin"])
def test_textured_parameters_equal_the_per_element_model(thin):
    rng = np.random.default_rng(9)
    grey = bk.Texture(rng.uniform(0.05, 0.95, (6, 5)).astype(np.float32), filter="nearest")
    rgb = bk.Texture(rng.uniform(0.0, 1.0, (4, 7, 3)).astype(np.float32), filter="bilinear")
    cls = bk.PrincipledThin if thin else bk.Principled
    m = cls(rgb, roughness=grey, spec_trans=0.4, sheen=grey)
    assert isinstance(m, bk.Textured) and set(m.textures) == {"base_color", "roughness", "sheen"}
    uv = rng.uniform(0.01, 0.99, (40, 2))
    wo, wi = random_directions(40, rng), random_directions(40, rng)
    per = m.at(uv)
    np.testing.assert_array_equal(m.eval(wo, wi, uv=uv), per.eval(wo, wi))
    np.testing.assert_array_equal(m.pdf(wo, wi, uv=uv), per.pdf(wo, wi))
    g = grey.lookup(uv)[..., 0]
    one = cls(rgb.lookup(uv[3]).tolist(), roughness=float(g[3]), spec_trans=0.4, sheen=float(g[3]))
    np.testing.assert_array_equal(per.eval(wo, wi)[3], one.eval(wo[3], wi[3]))


# ------------------------------------------------------------------ bad input

PRINCIPLED_BAD = [("base_color", 1.5), ("base_color", [0.1, -0.2, 0.3]), ("roughness", -0.1), ("roughness", 1.1),
                  ("anisotropic", 1.5), ("metallic", -1.0), ("spec_trans", 2.0), ("eta", 0.0), ("eta", -1.5),
                  ("eta", float("inf")), ("specular", 1.2), ("specular", -0.1), ("spec_tint", 1.01),
                  ("sheen", float("nan")), ("sheen_tint", -0.5), ("flatness", 3.0), ("clearcoat", -0.01),
                  ("clearcoat_gloss", 1.2), ("main_specular_sampling_rate", -1.0),
                  ("clearcoat_sampling_rate", float("nan")), ("diffuse_reflectance_sampling_rate", -0.5)]
THIN_BAD = [("base_color", 2.0), ("roughness", 1.5), ("anisotropic", -0.2), ("spec_trans", 1.5), ("eta", 0.0),
            ("spec_tint", 2.0), ("sheen", -1.0), ("sheen_tint", 1.5), ("flatness", -0.1), ("diff_trans", 2.5),
            ("diff_trans", -0.1), ("specular_reflectance_sampling_rate", -1.0),
            ("specular_transmittance_sampling_rate", -1.0), ("diffuse_reflectance_sampling_rate", float("inf")),
            ("diffuse_transmittance_sampling_rate", -2.0)]


@pytest.mark.parametrize("name, value", PRINCIPLED_BAD)
def test_principled_bad_input_names_the_parameter(name, value):
    with pytest.raises(ValueError, match=name):
        bk.Principled(**{name: value})


@pytest.mark.parametrize("name, value", THIN_BAD)
def test_principled_thin_bad_input_names_the_parameter(name, value):
    with pytest.raises(ValueError, match=name):
        bk.PrincipledThin(**{name: value})


def test_per_element_bad_values_and_uniform_parameters():
    with pytest.raises(ValueError, match="roughness"):
        bk.Principled(roughness=np.array([0.2, 1.3]))
    with pytest.raises((ValueError, TypeError), match="eta"):
        bk.Principled(eta=np.array([1.2, 1.5]))          # Mitsuba's eta is a float: uniform
    with pytest.raises((ValueError, TypeError), match="main_specular_sampling_rate"):
        bk.Principled(main_specular_sampling_rate=np.array([1.0, 2.0]))


def test_spectral_mode_is_refused_with_its_reason():
    wo = bk.direction(0.3, 0.0)
    for m in (bk.Principled(), bk.PrincipledThin()):
        with pytest.raises(NotImplementedError, match="luminance"):
            m.eval(wo, wo, wavelengths=[450.0, 500.0, 550.0, 600.0])


# ------------------------------------------------------------------ Mitsuba import / export

ROUND_TRIP = [bk.Principled([0.8, 0.2, 0.1], roughness=0.3, anisotropic=0.4, metallic=0.5, spec_trans=0.3,
                            eta=1.4, spec_tint=0.2, sheen=0.3, sheen_tint=0.4, flatness=0.5, clearcoat=0.6,
                            clearcoat_gloss=0.7, main_specular_sampling_rate=0.5, clearcoat_sampling_rate=2.0),
              bk.Principled(), bk.Principled(specular=0.3, spec_trans=0.5),
              bk.PrincipledThin([0.3, 0.6, 0.2], roughness=0.7, diff_trans=1.2, spec_trans=0.3, eta=1.3,
                                diffuse_transmittance_sampling_rate=0.5),
              bk.PrincipledThin()]


@pytest.mark.parametrize("m", ROUND_TRIP, ids=repr)
def test_mitsuba_round_trip(m):
    import mitsuba as mi
    from bsdfkit.testing import mitsuba as mref
    d = m.to_mitsuba()
    assert bk.from_mitsuba(d) == m
    mref.variant()
    loaded = bk.from_mitsuba(mi.load_dict(d))              # a loaded BSDF: float32 values
    assert type(loaded) is type(m)
    for k, v in m._params.items():
        np.testing.assert_allclose(np.asarray(getattr(loaded, k), float), np.asarray(v, float), rtol=1e-6)
    wo, wi = _pairs(13)
    ok = mi_ref.comparable(m._params, wo, isinstance(m, bk.PrincipledThin)) & (wo[:, 2] * wi[:, 2] > 0)
    mf, mp = mref.eval_pdf(d, wo, wi)                      # mi.load_dict of the export
    # the same material (a wrong parameter moves values by far more; the accuracy itself is
    # test_principled_matches_mitsuba's, with the float32 rules it needs)
    assert np.quantile(_rel(m.eval(wo, wi)[ok], mf[ok]), 0.999) <= 1e-4
    assert np.quantile(_rel(m.pdf(wo, wi)[ok], mp[ok]), 0.999) <= 1e-4


def test_mitsuba_xml_import(tmp_path):
    xml = tmp_path / "scene.xml"
    xml.write_text("""<scene version="3.0.0">
  <bsdf type="principled" id="red">
    <rgb name="base_color" value="0.8, 0.1, 0.1"/>
    <float name="roughness" value="0.3"/>
    <float name="specular" value="0.6"/>
    <float name="clearcoat" value="0.5"/>
    <float name="spec_trans" value="0.2"/>
  </bsdf>
  <bsdf type="principledthin" id="leaf">
    <rgb name="base_color" value="0.2, 0.6, 0.1"/>
    <float name="diff_trans" value="1.5"/>
    <float name="eta" value="1.3"/>
  </bsdf>
</scene>""")
    got = bk.from_mitsuba(str(xml))
    assert got["red"] == bk.Principled([0.8, 0.1, 0.1], roughness=0.3, specular=0.6, clearcoat=0.5, spec_trans=0.2)
    assert got["leaf"] == bk.PrincipledThin([0.2, 0.6, 0.1], diff_trans=1.5, eta=1.3)


def test_mitsuba_import_refusals():
    with pytest.raises(ValueError, match="eta.*specular|specular.*eta"):
        bk.from_mitsuba({"type": "principled", "eta": 1.5, "specular": 0.5})
    with pytest.raises(ValueError, match="roughness"):
        bk.from_mitsuba({"type": "principled", "roughness": 1.5})
    with pytest.raises(ValueError, match="unsupported parameters"):
        bk.from_mitsuba({"type": "principled", "diff_trans": 0.5})   # principledthin's, not principled's
    with pytest.raises(NotImplementedError):
        bk.Principled(roughness=np.array([0.1, 0.2])).to_mitsuba()
