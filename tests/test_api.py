"""Array API contract: shapes, broadcasting, dtype rule, out=, threads, value semantics, bad input."""
import pickle

import numpy as np
import pytest

import bsdfkit as bk
from conftest import random_dirs


def test_shapes_and_broadcasting(any_model, rng):
    wo = bk.direction(np.radians(40), 0.3)
    wi = random_dirs(rng, 60).reshape(4, 15, 3)
    f = any_model.eval(wo, wi)
    assert f.shape == (4, 15, 3) and f.dtype == np.float64
    assert any_model.pdf(wo, wi).shape == (4, 15)
    # broadcasting equals the explicit loop over the broadcast rows
    wo_b = np.broadcast_to(wo, wi.shape)
    np.testing.assert_array_equal(f, any_model.eval(np.ascontiguousarray(wo_b), wi))
    # (4,1,3) against (1,15,3) -> (4,15,3), not a trivial 1-vs-N case
    wo2 = random_dirs(rng, 4).reshape(4, 1, 3)
    wi2 = random_dirs(rng, 15).reshape(1, 15, 3)
    f2 = any_model.eval(wo2, wi2)
    assert f2.shape == (4, 15, 3)
    np.testing.assert_array_equal(f2[2, 7], any_model.eval(wo2[2, 0], wi2[0, 7]))
    # empty batch
    assert any_model.eval(wo, np.zeros((0, 3))).shape == (0, 3)


def test_dtype_rule(any_model, rng):
    wo = random_dirs(rng, 1000, 1)
    wi = random_dirs(rng, 1000)
    f64 = any_model.eval(wo, wi)
    f32 = any_model.eval(wo.astype(np.float32), wi.astype(np.float32))
    assert f32.dtype == np.float32 and f64.dtype == np.float64
    # mixed precision promotes to float64, integer arrays are converted to float64
    assert any_model.eval(wo.astype(np.float32), wi).dtype == np.float64
    assert any_model.eval(np.array([0, 0, 1]), np.array([0, 0, 1])).dtype == np.float64
    assert any_model.pdf(wo.astype(np.float32), wi.astype(np.float32)).dtype == np.float32
    s = any_model.sample(wo[0].astype(np.float32), n=100, seed=1)
    assert s.wi.dtype == np.float32 and s.f.dtype == np.float32 and s.pdf.dtype == np.float32


def test_out_argument(rng):
    m = bk.Conductor.from_metal("Cu", alpha=0.2)
    wo, wi = random_dirs(rng, 100, 1), random_dirs(rng, 100, 1)
    out = np.empty((100, 3))
    r = m.eval(wo, wi, out=out)
    assert r is out
    np.testing.assert_array_equal(out, m.eval(wo, wi))
    pout = np.empty(100)
    assert m.pdf(wo, wi, out=pout) is pout
    with pytest.raises(ValueError, match="out"):
        m.eval(wo, wi, out=np.empty((99, 3)))
    with pytest.raises(TypeError, match="out"):
        m.eval(wo, wi, out=np.empty((100, 3), np.float32))
    with pytest.raises(TypeError, match="out"):
        m.eval(wo, wi, out=[[0, 0, 0]] * 100)
    with pytest.raises(ValueError, match="out"):
        m.eval(wo, wi, out=np.empty((100, 6))[:, ::2])


def test_threads_bit_identical(rng):
    n = 200_000
    wo, wi = random_dirs(rng, n, 1), random_dirs(rng, n)
    uc, u = rng.random(n), rng.random((n, 2))
    for m in (bk.Dielectric(1.5, alpha=0.3), bk.Conductor.from_metal("Au", alpha_x=0.3, alpha_y=0.1)):
        res = []
        for t in (1, 2, 3):
            bk.set_num_threads(t)
            s = m.sample(wo, uc, u)
            res.append((m.eval(wo, wi), m.pdf(wo, wi), s.wi, s.f, s.pdf, m.albedo(wo[:3], n_samples=20000, seed=3)))
        bk.set_num_threads(bk._core.hardware_concurrency())
        for r in res[1:]:
            for a, b in zip(res[0], r):
                np.testing.assert_array_equal(a, b)


def test_sample_seeded_reproducible():
    m = bk.Diffuse(0.5)
    wo = bk.direction(0.3, 0.0)
    a = m.sample(wo, n=1000, seed=7)
    b = m.sample(wo, n=1000, seed=7)
    c = m.sample(wo, n=1000, seed=8)
    np.testing.assert_array_equal(a.wi, b.wi)
    assert not np.array_equal(a.wi, c.wi)
    assert a.wi.shape == (1000, 3) and a.valid.all()


def test_value_semantics():
    m = bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.2, masking="separable")
    assert m == bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.2, masking="separable")
    assert m != bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.2)
    assert hash(m) == hash(bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.2, masking="separable"))
    assert "Conductor(" in repr(m) and "alpha_x=0.3" in repr(m) and "separable" in repr(m)
    with pytest.raises(AttributeError):
        m.alpha_x = 0.5
    with pytest.raises(ValueError):
        m.eta[0] = 2.0  # parameter arrays are read-only
    for model in (m, bk.Diffuse(0.3), bk.DiffuseTransmission(0.1, 0.2), bk.Dielectric(1.33, alpha=0.1),
                  bk.ThinDielectric(1.2)):
        m2 = pickle.loads(pickle.dumps(model))
        assert m2 == model and type(m2) is type(model)
        d = bk.direction(0.5, 0.1)
        np.testing.assert_array_equal(m2.eval(d, -d * [1, 1, -1]), model.eval(d, -d * [1, 1, -1]))


def test_flags():
    F = bk.BxDFFlags
    assert bk.Diffuse(0.5).flags == F.DiffuseReflection
    assert bk.Diffuse(0.0).flags == F.Unset
    assert bk.DiffuseTransmission(0.2, 0.3).flags == F.DiffuseReflection | F.DiffuseTransmission
    assert bk.Conductor(1, 1).flags == F.SpecularReflection
    assert bk.Conductor(1, 1, alpha=0.1).flags == F.GlossyReflection
    assert bk.Dielectric(1.5).flags == F.SpecularReflection | F.SpecularTransmission
    assert bk.Dielectric(1.0, alpha=0.2).flags == F.GlossyTransmission
    assert bk.ThinDielectric(1.5).flags == F.Reflection | F.Transmission | F.Specular


def test_helpers():
    np.testing.assert_allclose(bk.roughness_to_alpha(0.25), 0.5)
    np.testing.assert_allclose(bk.roughness_to_alpha([0.0, 0.04]), [0.0, 0.2])
    g = bk.hemisphere_grid(10, 20)
    assert g.shape == (200, 3) and np.all(g[:, 2] > 0)
    np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1)
    d = bk.direction(np.radians([0, 90]), 0.0)
    np.testing.assert_allclose(d, [[0, 0, 1], [1, 0, 0]], atol=1e-15)
    # from_reflectance: normal-incidence Fresnel equals r (pbrt-v4 artist form)
    m = bk.Conductor.from_reflectance([0.9, 0.5, 0.1])
    s = m.sample([0, 0, 1.0], [0.5], [[0.5, 0.5]])
    np.testing.assert_allclose(s.f[0] * s.wi[0, 2] / s.pdf[0], [0.9, 0.5, 0.1], rtol=1e-12)


# ------------------------------------------------------------------ bad input

def test_bad_directions():
    m = bk.Diffuse(0.5)
    z = np.array([0, 0, 1.0])
    with pytest.raises(ValueError, match="wo"):
        m.eval(np.zeros((5, 2)), z)
    with pytest.raises(ValueError, match="wi"):
        m.eval(z, np.zeros(4))
    with pytest.raises(ValueError, match="wo and wi"):
        m.eval(np.tile(z, (3, 1)), np.tile(z, (4, 1)))
    with pytest.raises(TypeError, match="wo"):
        m.eval(z.astype(complex), z)
    with pytest.raises(TypeError, match="wi"):
        m.eval(z, np.array(["a", "b", "c"]))
    with pytest.raises(TypeError, match="wo"):
        m.eval(np.array([None, None, None]), z)
    with pytest.raises(ValueError, match="wi"):
        m.eval(z, [0, 0, 2.0])  # not unit
    with pytest.raises(ValueError, match="wo"):
        m.pdf([np.nan, 0, 1], z)
    with pytest.raises(ValueError, match="wo"):
        m.sample([0, 0, np.inf], n=3)
    with pytest.raises(ValueError, match="wo"):
        m.albedo([1.0, 1.0, 1.0])


def test_direction_helpers_refuse_bad_input():
    # bk.direction gave [nan nan nan] for theta=nan; the angles must be finite real numbers
    for bad in (np.nan, np.inf, -np.inf, [0.1, np.nan]):
        with pytest.raises(ValueError, match=r"^theta: must be finite"):
            bk.direction(bad, 0.3)
        with pytest.raises(ValueError, match=r"^phi: must be finite"):
            bk.direction(0.3, bad)
    with pytest.raises(ValueError, match=r"theta: must be finite, got 2 NaN or infinite"):
        bk.direction([np.nan, 0.2, np.inf])
    for name, kw in (("theta", dict(theta="0.3")), ("phi", dict(theta=0.3, phi=[True, False]))):
        with pytest.raises(TypeError, match=f"^{name}: expected a real numeric array"):
            bk.direction(**kw)
    d = bk.direction(np.float32(0.5), [0, 1])   # good input unchanged: float64, broadcast
    assert d.dtype == np.float64 and d.shape == (2, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1)
    rd = bk.directions.random_directions
    rng = np.random.default_rng(0)
    for n, err in ((-1, ValueError), (2 ** 28 + 1, ValueError), (2.5, TypeError), (np.nan, TypeError),
                   (True, TypeError)):
        with pytest.raises(err, match=r"^n: "):
            rd(n, rng)
    with pytest.raises(TypeError, match=r"^rng: expected a numpy.random.Generator"):
        rd(4, 0)
    assert rd(0, rng).shape == (0, 3)
    v = rd(100, rng, upper=True)
    assert v.shape == (100, 3) and np.all(v[:, 2] >= 0)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1)
    for n_theta, n_phi in ((np.nan, 4), (4, np.inf), (0, 4), (4, 2.0)):
        with pytest.raises(ValueError, match=r"^n_(theta|phi): must be a positive integer"):
            bk.hemisphere_grid(n_theta, n_phi)


def test_bad_sample_arguments():
    m = bk.Dielectric(1.5, alpha=0.1)
    z = np.array([0, 0, 1.0])
    with pytest.raises(ValueError, match="uc"):
        m.sample(z, [1.5], [[0.1, 0.1]])
    with pytest.raises(ValueError, match="u"):
        m.sample(z, [0.5], [[0.1, np.nan]])
    with pytest.raises(ValueError, match="u"):
        m.sample(z, [0.5], [[0.1, 0.2, 0.3]])
    with pytest.raises(ValueError):
        m.sample(z)
    with pytest.raises(ValueError, match="n"):
        m.sample(z, [0.5], [[0.1, 0.1]], n=4)
    with pytest.raises(ValueError, match="n"):
        m.sample(z, n=-1)
    with pytest.raises(TypeError, match="n"):
        m.sample(z, n=2.5)
    with pytest.raises(ValueError, match="mode"):
        m.eval(z, z, mode=7)
    with pytest.raises(ValueError, match="sample_flags"):
        m.pdf(z, z, sample_flags=9)
    with pytest.raises(ValueError, match="n_samples"):
        m.albedo(z, n_samples=0)
    with pytest.raises(ValueError, match="seed"):
        m.albedo(z, seed=-3)


@pytest.mark.parametrize("ctor, match", [
    (lambda: bk.Diffuse(1.2), "reflectance"),
    (lambda: bk.Diffuse([-0.1, 0.5, 0.5]), "reflectance"),
    (lambda: bk.Diffuse([0.1, 0.5]), "reflectance"),
    (lambda: bk.Diffuse(np.nan), "reflectance"),
    (lambda: bk.DiffuseTransmission(0.5, 1.5), "transmittance"),
    (lambda: bk.Conductor(0.0, 1.0), "eta"),
    (lambda: bk.Conductor(1.0, -1.0), "k"),
    (lambda: bk.Conductor(1.0, 1.0, alpha=-0.1), "alpha"),
    (lambda: bk.Conductor(1.0, 1.0, alpha_y=np.inf), "alpha_y"),
    (lambda: bk.Conductor(1.0, 1.0, masking="fast"), "masking"),
    (lambda: bk.Conductor.from_metal("Unobtainium"), "name"),
    (lambda: bk.Conductor.from_metal("Cu", roughness=-1), "roughness"),
    (lambda: bk.Conductor.from_metal("Cu", roughness=0.1, alpha=0.1), "roughness"),
    (lambda: bk.Conductor.from_reflectance(1.5), "reflectance"),
    (lambda: bk.Dielectric(0.0), "eta"),
    (lambda: bk.Dielectric(-1.5), "eta"),
    (lambda: bk.Dielectric(1.5, alpha=-1), "alpha"),
    (lambda: bk.ThinDielectric(np.nan), "eta"),
])
def test_bad_parameters(ctor, match):
    with pytest.raises(ValueError, match=match):
        ctor()


def test_bad_parameter_types():
    with pytest.raises(TypeError, match="eta"):
        bk.Dielectric("glass")
    with pytest.raises(TypeError, match="reflectance"):
        bk.Diffuse("red")
    with pytest.raises(TypeError, match="n"):
        bk.set_num_threads(1.5)
    with pytest.raises(ValueError, match="n"):
        bk.set_num_threads(0)


def _unit_boundary_dirs(dtype, per_side=40):
    """Directions (x, 0, 0) whose |w|^2 = x*x (one rounding, as the kernels' dot) straddles both
    ends of the accepted range |w|^2 - 1 in [-1e-4, 1e-4], a few ulps apart, with the count of
    the ones the rule rejects, computed here in the array's own dtype."""
    tol = dtype(1e-4)
    xs = []
    for end in (dtype(1) - tol, dtype(1) + tol):
        x = np.sqrt(end, dtype=dtype)
        lo = hi = x
        for _ in range(per_side):
            lo, hi = np.nextafter(lo, dtype(0)), np.nextafter(hi, dtype(2))
            xs += [lo, hi]
        xs.append(x)
    # |w|^2 at the special values too: NaN of either sign, infinity (also by overflow), 0 and -0,
    # a subnormal and 0 by underflow, exactly 1 from a negative x, the largest finite and 2
    fi = np.finfo(dtype)
    xs += [np.nan, -np.nan, np.inf, -np.inf, 0.0, -0.0, np.sqrt(fi.smallest_subnormal), fi.smallest_subnormal,
           -1.0, np.sqrt(fi.max), fi.max, np.sqrt(dtype(2))]
    x = np.array(xs, dtype)
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        rejected = int(np.count_nonzero(~(np.abs(x * x - dtype(1)) <= tol)))
    w = np.zeros((len(x), 3), dtype)
    w[:, 0] = x
    return w, rejected


def _expect_bad_directions(calls, count, first_spectral):
    """Each (name, call) raises the kernels' ValueError naming `name` and `count` directions; calls
    from index first_spectral on are spectral, which an RGB-only model may not implement."""
    for k, (name, call) in enumerate(calls):
        try:
            with pytest.raises(ValueError, match=rf"{name}: {count} direction\(s\) are not finite unit"):
                call()
        except NotImplementedError:
            assert k >= first_spectral  # only an RGB-only model's spectral mode may be missing


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_unit_tolerance_boundary(any_model, dtype):
    # The kernels test |w|^2 against a precomputed range (batch.h kUnitRange) instead of
    # |(|w|^2 - 1)| <= 1e-4: both must reject exactly the same directions, on the packet path
    # (full packets and the padded tail: 163 rows), the scalar path and the spectral kernels.
    w, rejected = _unit_boundary_dirs(dtype)
    assert 0 < rejected < len(w)
    z = np.array([0, 0, 1], dtype)
    calls = [("wi", lambda: any_model.eval(z, w)), ("wo", lambda: any_model.pdf(w, z)),
             ("wo", lambda: any_model.sample(w, n=len(w), seed=1)),
             ("wi", lambda: any_model.eval(z, w, wavelengths=np.full((len(w), 4), 550.0, dtype))),
             ("wo", lambda: any_model.sample(w, n=len(w), seed=1, wavelengths=np.full((len(w), 4), 550.0, dtype)))]
    _expect_bad_directions(calls, rejected, first_spectral=3)
    # both directions of the pair rejected in the same packets (batch.h tests the pair's keys
    # together and counts each only when that test fails): wo's count is the one reported
    with pytest.raises(ValueError, match=rf"wo: {rejected} direction\(s\) are not finite unit"):
        any_model.eval(w, w[::-1].copy())
    with np.errstate(over="ignore", invalid="ignore"):
        ok = w[np.abs(w[:, 0] * w[:, 0] - dtype(1)) <= dtype(1e-4)]
    assert np.all(np.isfinite(any_model.eval(z, ok)))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_nonfinite_directions_raise_without_crashing(any_model, dtype):
    # NaN / infinite / zero / huge directions in every entry point (RGB and spectral eval, pdf,
    # sample, albedo) raise ValueError naming the argument, for every model: the table models
    # (MERL, Measured) once indexed their tables with a NaN direction and crashed the interpreter
    # (batch.h check_dir now hands the model the normal instead; the call still raises).
    z = np.array([0, 0, 1], dtype)
    bad = np.array([[np.nan, 0, 1], [0, -np.nan, 1], [np.inf, 0, 0], [0, 0, -np.inf], [0, 0, 0],
                    [1e30, 1e30, 1e30], [np.finfo(dtype).max, 0, 0], [0.6, 0, np.nan]], dtype)
    w = np.tile(np.array([0.6, 0, 0.8], dtype), (40, 1))
    w[5:5 + len(bad)] = bad
    lam = np.full((len(w), 4), 550.0, dtype)
    calls = [("wi", lambda: any_model.eval(z, w)), ("wo", lambda: any_model.eval(w, z)),
             ("wi", lambda: any_model.pdf(z, w)), ("wo", lambda: any_model.pdf(w, z)),
             ("wo", lambda: any_model.sample(w, n=len(w), seed=3)), ("wo", lambda: any_model.albedo(bad, n_samples=64)),
             ("wi", lambda: any_model.eval(z, w, wavelengths=lam)), ("wo", lambda: any_model.pdf(w, z, wavelengths=lam)),
             ("wo", lambda: any_model.sample(w, n=len(w), seed=3, wavelengths=lam)),
             ("wo", lambda: any_model.albedo(bad, n_samples=64, wavelengths=lam[:len(bad)]))]
    _expect_bad_directions(calls, len(bad), first_spectral=6)
    try:  # the gradient kernels (models_grad.cpp) check the same way
        with pytest.raises(ValueError, match=rf"wi: {len(bad)} direction\(s\) are not finite unit"):
            any_model.eval_grad(z, w)
    except TypeError as e:
        assert "no gradient kernel" in str(e)


def test_out_must_not_overlap_inputs():
    # The kernels' output pointers are restrict and they write a packet's rows before reading the
    # next packet's: out= sharing memory with an input raises instead of returning values computed
    # from half-overwritten inputs (sample's fast path once returned pdf = 1 for an out= whose eta
    # array was its pdf array). Both the bindings' fast path and the general path.
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    n = 64
    buf = np.zeros(4 * n)
    wo = buf[:3 * n].reshape(n, 3)
    wo[:] = bk.direction(0.4, 0.3)
    wi = np.tile(bk.direction(0.5, 2.0), (n, 1))
    with pytest.raises(ValueError, match="out: must not overlap"):
        m.eval(wo, wi, out=wo)                                  # fast path, exactly aliased
    with pytest.raises(ValueError, match="out: must not overlap"):
        m.eval(wo[1:], wi[1:], out=buf[:3 * n - 3].reshape(n - 1, 3))  # one row behind (refused too)
    with pytest.raises(ValueError, match="out: must not overlap"):
        m.eval(wo, wi.astype(np.float32), out=wo)               # general path (mixed dtypes)
    with pytest.raises(ValueError, match="out: must not overlap"):
        m.pdf(wo, wi, out=buf[3 * n - n:3 * n])
    with pytest.raises(ValueError, match="out: must not overlap"):
        m.eval(wo, wi, out=buf[n:].reshape(n, 3))               # ahead: a packet's rows land on later inputs
    lam = np.full((n, 4), 550.0)
    with pytest.raises(ValueError, match="out: must not overlap"):
        m.eval(wo, wi, wavelengths=lam, out=buf.reshape(n, 4))  # spectral: out (n, 4) over wo
    with pytest.raises(ValueError, match="out: must not overlap"):
        m.eval(wi, wi, wavelengths=lam, out=lam)                # spectral: out over the wavelengths
    rng = np.random.default_rng(0)
    uc, u = rng.random(32), rng.random((32, 2))
    s = m.sample(bk.direction(0.7, 0.3), uc, u)
    SR = type(s)
    with pytest.raises(ValueError, match="must not overlap"):
        m.sample(bk.direction(0.7, 0.3), uc, u, out=SR(wi=s.wi, f=s.f, pdf=s.pdf, flags=s.flags, eta=s.pdf,
                                                       valid=s.valid, pdf_is_proportional=s.pdf_is_proportional))
    with pytest.raises(ValueError, match="must not overlap"):
        m.sample(bk.direction(0.7, 0.3), uc, u, out=SR(wi=s.wi, f=s.wi, pdf=s.pdf, flags=s.flags, eta=s.eta,
                                                       valid=s.valid, pdf_is_proportional=s.pdf_is_proportional))
    # disjoint arrays still work, into the arrays given, and equal the plain call
    fields = ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional")
    r = m.sample(bk.direction(0.7, 0.3), uc, u, out=SR(**{k: np.empty_like(getattr(s, k)) for k in fields}))
    for k in fields:
        np.testing.assert_array_equal(getattr(r, k), getattr(s, k))


def test_size_limits_raise():
    # sizes that would run for days or exhaust memory (or threads) are refused up front, naming
    # the argument (2**63 samples and 2**31 threads once failed inside pybind's argument casts)
    for n in (1025, 2 ** 31, 10 ** 6):
        with pytest.raises(ValueError, match=r"n: number of threads must be in \[1, 1024\]"):
            bk.set_num_threads(n)
    m = bk.Diffuse(0.5)
    for ns in (2 ** 40 + 1, 2 ** 62, 2 ** 63, 2 ** 70):
        with pytest.raises(ValueError, match="n_samples: must be <="):
            m.albedo(bk.direction(0.3), n_samples=ns)
        with pytest.raises(ValueError, match="n_samples: must be <="):
            m.albedo(bk.direction(0.3), n_samples=ns, wavelengths=[[450.0, 500, 550, 600]])
    with pytest.raises(ValueError, match=r"n_theta \* n_phi"):
        bk.hemisphere_grid(10 ** 9, 10 ** 9)
    with pytest.raises(ValueError, match=r"max_depth \* n_samples"):
        bk.CoatedDiffuse(0.5, max_depth=10 ** 5, n_samples=10 ** 5)
    bk.CoatedDiffuse(0.5, max_depth=10 ** 4, n_samples=10 ** 4)  # 1e8 steps per pair: allowed


def test_sample_flags_out_of_range():
    # IntFlag takes -1 as ~0 (All): out-of-range values are refused, as the compiled path does
    m = bk.Diffuse(0.5)
    z = bk.direction(0.2)
    for sf in (-1, 4, 255):
        with pytest.raises(ValueError, match="sample_flags"):
            m.pdf(z, z, sample_flags=sf)
        with pytest.raises(ValueError, match="sample_flags"):
            m.sample(z, n=4, sample_flags=sf)
