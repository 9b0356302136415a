"""Models whose batch_policy.h line says flush_denormals (Hair; core/simd.h DenormalsFlushed) run their batch kernels with
the CPU's flush-to-zero / denormals-are-zero modes set per chunk, and must restore them: a leak would
silently flush every later float computation on that thread (numpy's, other models' kernels) to 0
below 1.2e-38."""
import numpy as np
import pytest

import bsdfkit as bk


def _dirs(n, seed=3):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    v[..., 2] = np.abs(v[..., 2]) + 0.1
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v[0], v[1]


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("call", ["eval", "pdf", "sample", "albedo", "spectral"])
def test_hair_kernels_leave_denormals_enabled(threads, call):
    n = 100_000  # several chunks, so the pool's helper threads run some
    wo, wi = (d.astype(np.float32) for d in _dirs(n))
    # spectral: a sigma_a spectrum of its own (an RGB one would build the uplift table first)
    hair = bk.Hair(bk.Spectrum.constant(0.5) if call == "spectral" else None, h=0.3, beta_m=0.1)
    # Diffuse(1e-38): f = R / pi = 3.18e-39 is a float32 denormal; with FTZ left on it would be 0
    dark = bk.Diffuse(1e-38)
    before = bk.get_num_threads()
    bk.set_num_threads(threads)
    try:
        for _ in range(2):  # the helper threads run chunks of both calls
            if call == "eval":
                hair.eval(wo, wi)
            elif call == "pdf":
                hair.pdf(wo, wi)
            elif call == "sample":
                rng = np.random.default_rng(1)
                hair.sample(wo, rng.random(n, dtype=np.float32), rng.random((n, 2), dtype=np.float32))
            elif call == "albedo":
                hair.albedo(wo[:64], n_samples=4096)
            else:
                lam = np.full((n, 4), 550.0)
                hair.eval(wo, wi, wavelengths=lam)
            f = dark.eval(wo, wi)
            expected = np.float32(np.float32(1e-38) / np.float32(np.pi))
            assert 0 < expected < np.finfo(np.float32).tiny  # a denormal
            np.testing.assert_allclose(f, expected, rtol=1e-3)
            # numpy on the calling thread
            assert np.float32(1e-38) * np.float32(0.01) > 0
    finally:
        bk.set_num_threads(before)


def test_hair_flushed_kernel_matches_float64():
    # outputs in the normal range are the float64 kernel's to float32 accuracy (the flushed
    # intermediates are below 1.2e-38, far under any value that reaches them)
    wo, wi = _dirs(50_000, seed=7)
    m = bk.Hair((0.2, 0.5, 1.1), beta_m=0.1, beta_n=0.2, h=-0.4)
    f32 = m.eval(wo.astype(np.float32), wi.astype(np.float32)).astype(np.float64)
    f64 = m.eval(wo.astype(np.float32).astype(np.float64), wi.astype(np.float32).astype(np.float64))
    big = f64 > 1e-3 * np.median(f64[f64 > 0])
    rel = np.abs(f32[big] - f64[big]) / f64[big]
    assert np.quantile(rel, 0.999) < 5e-4  # tolerance of test_packet_accuracy's narrow hair (5 eps32 / v)
    assert np.all(np.isfinite(f32))
    # where the float64 value is below float32's normal range, float32 gives 0 or a tiny value
    tiny = f64 < 1e-38
    assert np.all(f32[tiny] < 1e-37)
