"""One door per operation (issue 46 item 4): seeded sampling from the counter hash, Python scalars
and broadcasting shapes converted by the compiled door, its argument errors worded once."""
import numpy as np
import pytest

import bsdfkit as bk


def _splitmix64_uniforms(seed, n, dtype):
    """uc, u of sample(n=, seed=) written out with Python integers (an implementation independent
    of both the C++ door and bsdfkit._arrays.seeded_uniforms): SplitMix64's finaliser (Steele, Lea,
    Flood 2014) over (seed, index, stream 0x5A3D1E), the top 24 / 53 bits as the uniform."""
    M = (1 << 64) - 1

    def mix(z):
        z = (z + 0x9E3779B97F4A7C15) & M
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & M
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & M
        return z ^ (z >> 31)

    def uni(b):
        return (b >> 40) * 2.0 ** -24 if dtype == np.float32 else (b >> 11) * 2.0 ** -53

    uc, u = np.empty(n, dtype), np.empty((n, 2), dtype)
    for i in range(n):
        h = mix(mix(mix(seed & M) ^ i) ^ 0x5A3D1E)
        uc[i], u[i, 0], u[i, 1] = uni(mix(h ^ 1)), uni(mix(h ^ 2)), uni(mix(h ^ 3))
    return uc, u


MODELS = [lambda: bk.Diffuse(0.6), lambda: bk.Dielectric(1.5, alpha=0.2), lambda: bk.Conductor.from_metal("Au", alpha=0.3),
          lambda: bk.CoatedDiffuse(reflectance=0.5, alpha=0.1)]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("make", MODELS)
def test_seeded_sample_uses_the_counter_hash(make, dtype):
    m = make()
    wo = bk.direction(theta=np.radians(35), phi=0.4).astype(dtype)
    for seed in (0, 7, 2 ** 64 + 5):  # used modulo 2**64
        uc, u = _splitmix64_uniforms(seed, 257, dtype)
        want = m.sample(wo, uc, u)
        got = m.sample(wo, n=257, seed=seed)
        for k in ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional"):
            np.testing.assert_array_equal(getattr(got, k), getattr(want, k), err_msg=k)
    # the Python twin (spectral calls and Custom draw with it) agrees with the door
    uc32, u32 = bk._arrays.seeded_uniforms(11, (300,), dtype)
    want_uc, want_u = _splitmix64_uniforms(11, 300, dtype)
    np.testing.assert_array_equal(uc32, want_uc)
    np.testing.assert_array_equal(u32, want_u)


def test_seeded_sample_is_thread_count_independent_and_uniform():
    m = bk.Diffuse(0.5)
    wo = bk.direction(theta=0.3, phi=0.0)
    n = 3 * 2 ** 15 + 17  # several fill chunks
    bk.set_num_threads(1)
    a = m.sample(wo, n=n, seed=42)
    bk.set_num_threads(2)
    b = m.sample(wo, n=n, seed=42)
    np.testing.assert_array_equal(a.wi, b.wi)
    # the sampled cosines of a Lambertian lobe: cos^2 theta is uniform on [0, 1] (Malley), so its
    # mean is 1/2 and its variance 1/12 (4 standard errors)
    c2 = a.wi[:, 2] ** 2
    assert abs(c2.mean() - 0.5) < 4 * np.sqrt(1 / 12 / n)
    # different seeds, different draws; seed=None draws a fresh seed
    assert not np.array_equal(m.sample(wo, n=64, seed=1).wi, m.sample(wo, n=64, seed=2).wi)
    assert not np.array_equal(m.sample(wo, n=64).wi, m.sample(wo, n=64).wi)


def test_scalar_and_broadcast_uniforms():
    m = bk.Dielectric(1.5, alpha=0.25)
    rng = np.random.default_rng(3)
    wo = rng.normal(size=(50, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    u = rng.random((50, 2))
    want = m.sample(wo, np.full(50, 0.25), u)
    for uc in (0.25, np.float64(0.25), np.array(0.25), [0.25], 1 / 4):
        got = m.sample(wo, uc, u)
        np.testing.assert_array_equal(got.wi, want.wi)
        np.testing.assert_array_equal(got.pdf, want.pdf)
    # one u for every wo, and a (5, 1) wo against (1, 10) uniforms: numpy broadcasting
    got = m.sample(wo, 0.25, u[0])
    np.testing.assert_array_equal(got.wi, m.sample(wo, np.full(50, 0.25), np.tile(u[0], (50, 1))).wi)
    g = m.sample(wo[:5, None, :], rng.random((1, 10)), rng.random((1, 10, 2)))
    assert g.wi.shape == (5, 10, 3) and g.pdf.shape == (5, 10)


def test_door_words_argument_errors():
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    wo = bk.direction(theta=0.2, phi=0.0)
    with pytest.raises(ValueError, match="n: give either n"):
        m.sample(wo, 0.5, [0.5, 0.5], n=3)
    with pytest.raises(ValueError, match="uc, u: pass both"):
        m.sample(wo, 0.5)
    with pytest.raises(TypeError, match="n: expected an integer, got float"):
        m.sample(wo, n=3.0)
    with pytest.raises(ValueError, match="n: must be >= 0"):
        m.sample(wo, n=-1)
    with pytest.raises(ValueError, match=r"seed: must be >= 0 \(or None\), got -3"):
        m.sample(wo, n=3, seed=-3)
    with pytest.raises(TypeError, match="seed: expected a non-negative integer or None, got float"):
        m.sample(wo, n=3, seed=1.5)
    with pytest.raises(ValueError, match=r"u: expected trailing shape \(2,\), got \(3,\)"):
        m.sample(wo, 0.5, [0.1, 0.2, 0.3])
    with pytest.raises(TypeError, match="uc: expected a real numeric array, got dtype <U1"):
        m.sample(wo, "a", [0.5, 0.5])
    with pytest.raises(ValueError, match=r"wo and n: batch shapes cannot be broadcast together \(wo \(2,\), n \(3,\)\)"):
        m.sample(np.array([wo, wo]), n=3)
    with pytest.raises(ValueError, match="mode: must be a TransportMode, got 'sideways'"):
        m.eval(wo, wo, mode="sideways")
    with pytest.raises(ValueError, match=r"sample_flags: must be a ReflTrans \(0..3\), got 7"):
        m.pdf(wo, wo, sample_flags=7)
    with pytest.raises(TypeError, match="n_samples: expected an integer, got float"):
        m.albedo(wo, n_samples=10.0)
    with pytest.raises(ValueError, match="n_samples: must be >= 1, got 0"):
        m.albedo(wo, n_samples=0)
    with pytest.raises(TypeError, match="wo: cannot be converted to a numeric array"):
        m.eval([[0, 0, 1], [0, 1]], wo)
    with pytest.raises(TypeError, match="out: expected a numpy.ndarray, got list"):
        m.eval(wo, wo, out=[0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"out: shape must be \(3,\), got \(1, 3\)"):
        m.eval(wo, wo, out=np.empty((1, 3)))
    # mode by name and IntEnum are taken as before
    np.testing.assert_array_equal(m.eval(wo, wo, mode="importance"), m.eval(wo, wo, mode=bk.TransportMode.Importance))


def test_python_float_uc_keeps_float32():
    # a Python scalar uc is weak (numpy's NEP 50): float32 directions and u run the float32 kernels
    m = bk.Conductor.from_metal("Au", alpha=0.2)
    wo = bk.direction(theta=0.4, phi=0.1).astype(np.float32)
    u = np.array([[0.2, 0.7], [0.9, 0.1]], np.float32)
    got = m.sample(wo, 0.5, u)
    want = m.sample(wo, np.full(2, 0.5, np.float32), u)
    assert got.f.dtype == np.float32
    np.testing.assert_array_equal(got.wi, want.wi)
    # a float64 array uc still promotes, as numpy does
    assert m.sample(wo, np.full(2, 0.5), u).f.dtype == np.float64
