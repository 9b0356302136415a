"""The contract suite: every registered (class, example) through every generic contract.

Cases come from the model registry (``bsdfkit.models.registry.examples()``): a new model class
gets every test here by declaring its ``examples``. Contracts are gated by the class's declared
capability flags (``exact_eval``, ``energy_conserving``, ``reciprocal``, ``two_sided``,
``transmission``, ``delta_only``, ``mitsuba``), never by its name. ``exact_eval`` and ``reciprocal``
are read from the example's instance (a class may answer per instance: the layered models'
``method="analytic"`` is exact and reciprocal, their random walk is not). Model-specific tests live in
tests/models/ and the other files of tests/.
"""
import pickle

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models import registry
from bsdfkit.directions import random_directions
from bsdfkit.models.spec import parse_spec, to_spec

RAD, IMP = bk.TransportMode.Radiance, bk.TransportMode.Importance
CASES = registry.examples()
IDS = [f"{cls.__name__}-{label}" for cls, label, _ in CASES]
_MODELS = {}


def model_of(spec):
    if spec not in _MODELS:
        _MODELS[spec] = parse_spec(spec)
    return _MODELS[spec]


def cases(pred=lambda cls, m: True):
    """pytest params (cls, spec) of the registered examples satisfying ``pred(cls, model)``."""
    return [pytest.param(cls, spec, id=i) for (cls, _, spec), i in zip(CASES, IDS) if pred(cls, model_of(spec))]


def has_smooth_lobe(m) -> bool:
    return bool(m.flags & (bk.BxDFFlags.Diffuse | bk.BxDFFlags.Glossy))


def random_dirs(rng, n, upper=False):
    return random_directions(n, rng, upper=upper)


def wo_set(cls):
    """Incidence directions: normal, oblique, grazing, and from below for two-sided classes."""
    zs = [1.0, 0.8, 0.4, 0.05] + ([-0.3, -0.9, -0.02] if cls.two_sided else [])
    phi = np.linspace(0.3, 5.0, len(zs))
    r = np.sqrt(1 - np.square(zs))
    return np.stack([r * np.cos(phi), r * np.sin(phi), zs], 1)


def test_registry_is_complete():
    """Every class is registered with at least one example that builds that class; bk.MODELS is
    the registry; names and aliases resolve."""
    assert tuple(bk.MODELS) == registry.classes() and len(bk.MODELS) >= 7
    for cls, label, spec in CASES:
        assert type(model_of(spec)) is cls, (label, spec)
        assert registry.lookup(cls.__name__) is cls
        for a in cls.aliases:
            assert registry.lookup(a) is cls
        for k in cls.knobs:
            assert k.kind in registry.KINDS
            assert k.keyword in model_of(spec)._params, (cls.__name__, k.name)
    with pytest.raises(TypeError, match="examples"):
        class NoExamples(bk.BxDF):   # noqa: F841  (refused at definition: the registry needs examples)
            pass
    assert "NoExamples" not in {c.__name__ for c in registry.classes()}


# ------------------------------------------------------------------ sampling vs eval / pdf

@pytest.mark.parametrize("cls, spec", cases(lambda c, m: has_smooth_lobe(m)))
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_sample_agrees_with_eval_and_pdf(cls, spec, dtype):
    """At sampled directions of non-delta lobes, sample().f / pdf equal eval() / pdf() (exactly
    up to rounding for exact_eval classes; in mean for stochastic ones)."""
    m = model_of(spec)
    rtol = 1e-9 if dtype == np.float64 else 2e-4
    for wo in wo_set(cls).astype(dtype):
        for mode in (RAD, IMP):
            s = m.sample(wo, n=2000, seed=5, mode=mode)
            keep = s.valid & ((s.flags & bk.BxDFFlags.Specular) == 0)
            if not keep.any():
                continue
            f, p = m.eval(wo, s.wi[keep], mode=mode), m.pdf(wo, s.wi[keep], mode=mode)
            if m.exact_eval:
                ef = np.abs(s.f[keep] - f) / np.maximum(np.abs(f), 1e-30)
                ep = np.abs(s.pdf[keep] - p) / np.maximum(p, 1e-30)
                assert np.quantile(ef, 0.999) < rtol, (wo, mode, np.max(ef))
                assert np.quantile(ep, 0.999) < rtol, (wo, mode, np.max(ep))
            else:  # stochastic (pdf_is_proportional samples): s.f / s.pdf are not eval / pdf of wi;
                # sample() is checked in the mean below (test_stochastic_sample_weights_match_eval)
                assert np.all(np.isfinite(f)) and np.all(np.isfinite(s.f[keep]))
            assert np.all(p > 0)


def _unbiased_twin(m):
    """The model with its unbiased f() estimator: pbrt-v4's layered f() is biased high with a
    rough coat (mis="pbrt", reproduced on purpose; tests/models/test_layered.py measures it), so
    the mean of sample() is compared with the consistent-MIS f(), the same random variable's
    unbiased estimator (sample() does not depend on the MIS rule)."""
    return type(m)._from_params({**m._params, "mis": "consistent"}) if m._params.get("mis") == "pbrt" else m


@pytest.mark.parametrize("cls, spec", cases(lambda c, m: has_smooth_lobe(m) and not m.exact_eval))
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_stochastic_sample_weights_match_eval(cls, spec, dtype):
    """Stochastic models (sample().pdf only proportional, pdf() an approximation): the mean
    sampling weight f |cos| / pdf over the non-specular samples estimates the non-delta albedo
    int E[f] |cos| dwi, which uniform hemisphere sampling of eval() estimates independently.
    Per channel z = (A - B) / sqrt(var_A + var_B) with |z| < 4.5 (about 1e-3 family-wise over
    the stochastic examples x wo x modes x dtypes x channels, Bonferroni).

    Why not eval(wi) |cos| / pdf(wi) at the sampled wi (an earlier attempt, off by 10-55 %):
    pdf() is pbrt-v4's approximate density, not the density of sample(), so that ratio is no
    estimator of the albedo. Grazing wo (|cos| < 0.1) are left out: a narrow coat highlight there
    (car paint: alpha 0.02) is not resolved by uniform sampling (heavy-tailed B)."""
    m, n = model_of(spec), 20000
    mu = _unbiased_twin(m)
    rng = np.random.default_rng(11)
    for wo in wo_set(cls):
        if abs(wo[2]) < 0.1:
            continue
        wo = wo.astype(dtype)
        for mode in (RAD, IMP):
            s = m.sample(wo, n=n, seed=5, mode=mode)
            keep = s.valid & ((s.flags & bk.BxDFFlags.Specular) == 0)
            w = np.where(keep[:, None], s.weight.astype(np.float64), 0.0)
            a, va = w.mean(0), w.var(0) / n
            u1, u2 = rng.random(n), rng.random(n)
            r = np.sqrt(1 - u1 * u1)
            wi = np.stack([r * np.cos(2 * np.pi * u2), r * np.sin(2 * np.pi * u2), u1 * np.sign(wo[2])], 1)
            fc = mu.eval(wo, wi.astype(dtype), mode=mode).astype(np.float64) * (2 * np.pi * u1)[:, None]
            b, vb = fc.mean(0), fc.var(0) / n
            z = (a - b) / np.sqrt(va + vb + 1e-300)
            assert np.all(np.abs(z) < 4.5), (wo, mode, a, b, z)


# delta-only models: a model with a delta and a smooth lobe (a smooth coat over a diffuse base)
# has the smooth lobe's nonzero eval in the delta's direction
@pytest.mark.parametrize("cls, spec", cases(lambda c, m: bool(m.flags & bk.BxDFFlags.Specular) and
                                            not has_smooth_lobe(m)))
def test_delta_samples_have_zero_eval_and_pdf(cls, spec):
    m, rng = model_of(spec), np.random.default_rng(1)
    wo = random_dirs(rng, 400, upper=not cls.two_sided)
    s = m.sample(wo, rng.random(400), rng.random((400, 2)))
    d = s.valid & ((s.flags & bk.BxDFFlags.Specular) != 0)
    assert d.any()
    assert np.all(m.eval(wo[d], s.wi[d]) == 0) and np.all(m.pdf(wo[d], s.wi[d]) == 0)


# ------------------------------------------------------------------ physics

@pytest.mark.parametrize("cls, spec", cases(lambda c, m: m.reciprocal and has_smooth_lobe(m)))
def test_adjoint_reciprocity(cls, spec):
    """f(wo, wi) in Radiance mode equals f(wi, wo) in Importance mode (Veach 1997, ch. 5)."""
    m, rng = model_of(spec), np.random.default_rng(2)
    wo, wi = random_dirs(rng, 5000, not cls.two_sided), random_dirs(rng, 5000, not cls.two_sided)
    np.testing.assert_allclose(m.eval(wo, wi, mode=RAD), m.eval(wi, wo, mode=IMP), rtol=1e-7, atol=1e-300)


@pytest.mark.parametrize("cls, spec", cases())
def test_albedo_bounded(cls, spec):
    """0 <= albedo, and <= 1 for energy-conserving classes (Importance mode: no 1/eta^2)."""
    m, n = model_of(spec), 20000
    a = m.albedo(wo_set(cls), n_samples=n, seed=2, mode=IMP)
    assert np.all(np.isfinite(a)) and np.all(a >= 0)
    if cls.energy_conserving:
        assert np.all(a <= 1 + 5 / np.sqrt(n)), a


# ------------------------------------------------------------------ pdf normalisation

PDF_NT, PDF_NP, PDF_SAMPLES = 800, 400, 200_000
PDF_TOL = 3e-3


def _narrow_lobe(m) -> bool:
    """A glossy lobe narrower than the quadrature below resolves (alpha in [1e-3, 0.06): at
    alpha 0.05 / 0.02 the midpoint rule is off by 5e-3 / 0.17, measured). Such lobes are
    checked in magnified domains by the model-specific chi-square files."""
    p = m._params
    alphas = [v for k, v in p.items() if k.endswith(("alpha", "alpha_x", "alpha_y"))]   # incl. layered interface_*
    alphas += [p[k] ** 2 for k in ("roughness", "clear_coat_roughness", "sheen_roughness") if k in p and
               (k != "clear_coat_roughness" or p.get("clear_coat", 0) > 0)]
    return any(a is not None and 1e-3 <= np.min(a) < 0.06 for a in alphas)


def _pdf_cases():
    out = []
    for p in cases(lambda c, m: has_smooth_lobe(m) and m.exact_eval and not _narrow_lobe(m)):
        out.append(p)
    return out


def _sphere_quadrature(upper_only):
    """Midpoint rule in (theta, phi): 800 x 400 cells per hemisphere (the per-family copies'
    grid this replaces); directions (M, 3) and solid-angle weights (M,)."""
    nt = PDF_NT if upper_only else 2 * PDF_NT
    th_max = np.pi / 2 if upper_only else np.pi
    t = (np.arange(nt) + 0.5) * th_max / nt
    ph = (np.arange(PDF_NP) + 0.5) * 2 * np.pi / PDF_NP
    T, P = np.meshgrid(t, ph, indexing="ij")
    return bk.direction(T, P).reshape(-1, 3), (np.sin(T) * (th_max / nt) * (2 * np.pi / PDF_NP)).reshape(-1)


@pytest.mark.parametrize("cls, spec", _pdf_cases())
def test_pdf_integrates_to_at_most_one(cls, spec):
    """pdf(wo, .) is the density of sample()'s non-delta lobes: over the directions where f > 0 it
    integrates to the fraction of samples that are valid and not delta (<= 1: samples below the
    horizon after a reflection, picks of a delta lobe, and directions where f = 0, which the
    BSDF-level rule rejects as pbrt-v4's BSDF::Sample_f does, are the mass it lacks; e.g.
    NormalizedFresnel from below the surface: the total-internal-reflection cone, where its
    f = (1 - Fr) / (c pi) is 0, holds 1 - 1 / eta^2 of its cosine-weighted samples). Quadrature: midpoint rule, 800 x
    400 cells per hemisphere (the whole sphere for transmitting or two-sided classes); the
    fraction from 200,000 seeded samples (standard error <= 1.1e-3). Tolerance 3e-3 (measured
    worst 1.8e-3, Dielectric separable masking). Exception, on the low side only: Hair's pdf
    integrates 3.3-3.9e-3 short for these examples (pbrt-v4's 10-term I0 series in Mp, see
    tests/models/test_hair.py::test_white_furnace), allowed 5e-3. Stochastic classes (exact_eval
    False) are left out: their pdf() is an estimate, only proportional to the density (see
    tests/models/test_layered.py::test_pdf_positive_and_integrates_to_about_one)."""
    m = model_of(spec)
    zs = [0.95, 0.5, 0.17] + ([-0.5] if cls.two_sided else [])
    wo = bk.direction(np.arccos(zs), 0.4)
    g, dw = _sphere_quadrature(upper_only=not (cls.transmission or cls.two_sided))
    f_pos = np.any(m.eval(wo[:, None, :], g[None]) > 0, axis=-1)
    integral = (np.where(f_pos, m.pdf(wo[:, None, :], g[None]), 0.0) * dw).sum(-1)
    kept = []
    for w in wo:
        s = m.sample(w, n=PDF_SAMPLES, seed=3)
        kept.append(np.mean(s.valid & ((s.flags & bk.BxDFFlags.Specular) == 0)))
    kept = np.array(kept)
    low = 5e-3 if cls is bk.Hair else PDF_TOL
    assert np.all(integral <= kept + PDF_TOL), (zs, integral, kept)
    assert np.all(integral >= kept - low), (zs, integral, kept)


# ------------------------------------------------------------------ numerics

COS = [0.0, 1e-30, -1e-30, 1e-12, -1e-12, 1e-7, -1e-7, 1e-4, -1e-4, 0.5, -0.5, 1.0, -1.0]


def _extreme_dirs():
    out = []
    for c in COS:
        s = np.sqrt(max(0.0, 1 - c * c))
        for phi in (0.0, 0.3, np.pi / 2, 2.5):
            out.append((s * np.cos(phi), s * np.sin(phi), c))
    return np.array(out)


@pytest.mark.parametrize("cls, spec", cases())
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_extremes_finite(cls, spec, dtype):
    """Horizon, normal, wo = +-wi, and the uniforms at exactly 0 and 1 (and 1 - ulp): finite,
    non-negative values; every valid sample has pdf > 0 and is a valid input of eval/pdf."""
    m = model_of(spec)
    d = _extreme_dirs().astype(dtype)
    n = len(d)
    wo, wi = np.repeat(d, n, axis=0), np.tile(d, (n, 1))
    us = np.array([0.0, 1.0, np.nextafter(dtype(1), dtype(0)), 0.5, 1e-7], dtype)
    uc = np.resize(us, len(wo))
    u = np.stack([np.resize(us, len(wo)), np.resize(us[::-1], len(wo))], 1)
    corners = np.array([(a, b, c) for a in (0.0, 1.0) for b in (0.0, 1.0) for c in (0.0, 1.0)], dtype)
    wo_c = np.repeat(d, len(corners), axis=0)
    uc = np.concatenate([uc, np.tile(corners[:, 0], n)])
    u = np.concatenate([u, np.tile(corners[:, 1:], (n, 1))])
    wo_s = np.concatenate([wo, wo_c])
    for mode in (RAD, IMP):
        f, p = m.eval(wo, wi, mode=mode), m.pdf(wo, wi, mode=mode)
        assert np.all(np.isfinite(f)) and np.all(f >= 0)
        assert np.all(np.isfinite(p)) and np.all(p >= 0)
        s = m.sample(wo_s, uc, u, mode=mode)
        for arr in (s.f, s.pdf, s.wi, s.eta, s.weight):
            assert np.all(np.isfinite(arr)), mode
        assert np.all(s.f >= 0) and np.all(s.pdf >= 0) and np.all(s.pdf[s.valid] > 0)
        assert np.all(np.isfinite(m.eval(wo_s[s.valid], s.wi[s.valid], mode=mode)))
    a = m.albedo(d, n_samples=64, seed=1)
    assert np.all(np.isfinite(a)) and np.all(a >= 0)


@pytest.mark.parametrize("cls, spec", cases(lambda c, m: has_smooth_lobe(m)))
def test_float32_close_to_float64(cls, spec):
    """float32 kernels agree with float64 on well-conditioned pairs (away from the horizon):
    p99 of the relative error of f |cos| (floored at 1e-3 of its mean) below 1e-3."""
    m, rng = model_of(spec), np.random.default_rng(3)
    wo, wi = random_dirs(rng, 20000, not cls.two_sided), random_dirs(rng, 20000, not cls.two_sided)
    ok = (np.abs(wo[:, 2]) > 0.05) & (np.abs(wi[:, 2]) > 0.05)
    wo, wi = wo[ok], wi[ok]
    f64 = m.eval(wo, wi) * np.abs(wi[:, 2:3])
    f32 = m.eval(wo.astype(np.float32), wi.astype(np.float32)).astype(np.float64) * np.abs(wi[:, 2:3])
    if not m.exact_eval:   # stochastic: float32 and float64 walk different realizations; agree in the mean
        np.testing.assert_allclose(np.mean(f32, 0), np.mean(f64, 0), rtol=0.03)
        p64, p32 = m.pdf(wo, wi), m.pdf(wo.astype(np.float32), wi.astype(np.float32))
        np.testing.assert_allclose(np.mean(p32), np.mean(p64), rtol=0.03)
        return
    floor = 1e-3 * max(float(np.mean(f64)), 1e-30)
    err = np.abs(f32 - f64) / np.maximum(np.abs(f64), floor)
    assert np.quantile(err, 0.99) < 1e-3, np.quantile(err, 0.99)
    p64, p32 = m.pdf(wo, wi), m.pdf(wo.astype(np.float32), wi.astype(np.float32))
    perr = np.abs(p32 - p64) / np.maximum(p64, 1e-3 * max(float(np.mean(p64)), 1e-30))
    assert np.quantile(perr, 0.99) < 1e-3


# ------------------------------------------------------------------ value semantics and specs

def _params_close(a, b, rtol):
    assert type(a) is type(b)
    assert a._params.keys() == b._params.keys()
    for k, v in a._params.items():
        w = b._params[k]
        if isinstance(v, bk.BxDF):   # a composite model's child
            _params_close(v, w, rtol)
        elif isinstance(v, (str, bool)) or v is None:
            assert v == w, k
        else:
            np.testing.assert_allclose(np.asarray(w, float), np.asarray(v, float), rtol=rtol, err_msg=k)


@pytest.mark.parametrize("cls, spec", cases())
def test_pickle_eq_hash_repr(cls, spec):
    m = model_of(spec)
    m2 = pickle.loads(pickle.dumps(m))
    assert m2 == m and hash(m2) == hash(m) and m2 is not m
    assert m == parse_spec(spec) and hash(m) == hash(parse_spec(spec))
    again = eval(repr(m), {c.__name__: c for c in registry.classes()})   # noqa: S307 - our own repr (children too)
    # repr prints 6 significant digits today (exact round trip: issue 11, item 11)
    _params_close(m, again, rtol=1e-5)
    with pytest.raises(AttributeError):
        m.anything = 1
    d = np.array([0.3, 0.1, 0.9]) / np.linalg.norm([0.3, 0.1, 0.9])
    np.testing.assert_array_equal(m2.eval(d, d * [-1, -1, 1]), m.eval(d, d * [-1, -1, 1]))


@pytest.mark.parametrize("cls, spec", cases())
def test_spec_round_trip(cls, spec):
    m = model_of(spec)
    _params_close(m, parse_spec(to_spec(m)), rtol=1e-3)   # to_spec prints 4 significant digits


# ------------------------------------------------------------------ renderer and Mitsuba

def _compiled(m) -> bool:
    """The model runs compiled code (the renderer's shading takes only those; the Python composites
    Mix, TwoSided, Mask, NormalMap are refused naming the model)."""
    return type(m._core).__module__.startswith("bsdfkit._core")


@pytest.mark.parametrize("cls, spec", cases())
def test_preview_renders_finite(cls, spec):
    if not _compiled(model_of(spec)):
        with pytest.raises(TypeError, match=f"{cls.__name__}.*Python.*compiled models only"):
            bk.render.preview(model_of(spec), width=8, height=8, spp=1, progress=False)
        return
    img = bk.render.preview(model_of(spec), width=8, height=8, spp=1, progress=False)
    assert img.shape[:2] == (8, 8) and np.all(np.isfinite(img)) and np.all(img >= 0)


@pytest.mark.parametrize("cls, spec", cases())
def test_to_mitsuba_round_trip_or_refusal(cls, spec):
    """A class with a Mitsuba plugin converts to it and back unchanged, or refuses a material
    Mitsuba lacks exactly (correlated masking, approximate Fresnel) with MitsubaExportError; then
    approximate=True exports the nearest one with a warning, and it comes back with Mitsuba's
    separable masking. Without a plugin, it refuses with NotImplementedError."""
    m = model_of(spec)
    if cls.mitsuba is None:
        with pytest.raises(NotImplementedError):
            m.to_mitsuba()
        with pytest.raises(NotImplementedError):   # nothing nearer either, and the same keyword everywhere
            m.to_mitsuba(approximate=True)
        return
    try:
        d = m.to_mitsuba()
        exact = True
    except bk.interop.MitsubaExportError as e:
        assert "mitsuba" in str(e).lower()
        exact = False
    except ValueError as e:
        assert "mitsuba" in str(e).lower()
        return
    if not exact:
        with pytest.warns(bk.interop.MitsubaApproximationWarning, match="differs"):
            d = m.to_mitsuba(approximate=True)
    back = bk.from_mitsuba(d)
    if d.get("type") == "null":
        assert float(m.eta) == 1.0
        return
    expect = dict(m._params)
    smooth = "alpha_x" in expect and max(m.alpha_x, m.alpha_y) < 1e-3
    if "masking" in expect:   # Mitsuba has only the separable masking; a mirror has none
        expect["masking"] = back._params["masking"] if smooth else "separable"
    if smooth:                # a mirror's alphas below the smooth threshold are all the same mirror
        assert max(back.alpha_x, back.alpha_y) < 1e-3
        expect["alpha_x"], expect["alpha_y"] = back.alpha_x, back.alpha_y
    if not exact and "fresnel" in expect:   # the nearest Mitsuba conductor has the exact Fresnel term
        expect["fresnel"] = "exact"
    if not exact and "method" in expect:    # Mix: the nearest Mitsuba blend is the linear one
        expect["method"], expect["key"] = "linear", None
    assert type(back) is cls
    for k, v in expect.items():
        if isinstance(v, bk.BxDF) or v is None:   # a composite's child (exported exactly), or no back side
            assert back._params[k] == v, k
        elif isinstance(v, str):
            assert back._params[k] == v, k
        else:
            np.testing.assert_allclose(np.asarray(back._params[k], float), np.asarray(v, float), rtol=1e-6,
                                       err_msg=k)


def test_every_mitsuba_class_round_trips_some_example():
    """Each class that declares a Mitsuba plugin has at least one example converting both ways."""
    for cls in registry.classes():
        if cls.mitsuba is None:
            continue
        ok = False
        for label, spec in cls.examples.items():
            try:
                d = model_of(spec).to_mitsuba()
            except ValueError:
                continue
            ok |= type(bk.from_mitsuba(d)) is cls or d.get("type") == "null"
        assert ok, cls.__name__
