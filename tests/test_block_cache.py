"""The output block cache (cpp/bindings/block_cache.h) of sample, and of eval / pdf results (the last
test): large blocks are reused after their result is freed, never while any of its arrays is alive,
and bk.release_memory gives them back.
The reference for the values is the same call in slices small enough (< 1 MiB) to take numpy's
own allocation: results are position independent, so the two must agree bit for bit."""
import gc

import numpy as np
import pytest

import bsdfkit as bk

N = 40_000   # float64: ~2.7 MB per block (cached); a slice of 2,000: ~134 kB (not cached)


def inputs(seed, n=N):
    rng = np.random.default_rng(seed)
    wo = bk.direction(theta=np.arccos(rng.uniform(0.05, 1.0, n)), phi=rng.uniform(0, 2 * np.pi, n))
    return wo, rng.random(n), rng.random((n, 2))


def sliced(m, wo, uc, u, step=2_000):
    parts = [m.sample(wo[i:i + step], uc[i:i + step], u[i:i + step]) for i in range(0, len(uc), step)]
    return {k: np.concatenate([getattr(p, k) for p in parts]) for k in ("wi", "f", "pdf", "eta", "flags", "valid")}


def check(r, ref):
    for k, v in ref.items():
        np.testing.assert_array_equal(getattr(r, k), v, err_msg=k)


@pytest.mark.parametrize("model", [bk.Conductor.from_metal("Cu", alpha=0.3), bk.Dielectric(1.5, alpha=0.2)])
def test_reused_blocks_hold_correct_values_and_live_results_are_never_overwritten(model):
    bk.release_memory()
    a_in, b_in, c_in = inputs(1), inputs(2), inputs(3)
    ref_a, ref_b, ref_c = sliced(model, *a_in), sliced(model, *b_in), sliced(model, *c_in)
    ra = model.sample(*a_in)
    rb = model.sample(*b_in)          # a is alive: b must get another block
    check(ra, ref_a)
    check(rb, ref_b)
    wi_a = ra.wi                      # one view keeps a's whole block alive
    del ra
    gc.collect()
    rc = model.sample(*c_in)
    check(rc, ref_c)
    np.testing.assert_array_equal(wi_a, ref_a["wi"])
    del rb
    gc.collect()
    assert bk._core.cached_bytes() >= N * 67   # b's block went back to the cache
    rd = model.sample(*a_in)          # reuses b's block: its old values are overwritten everywhere
    check(rd, ref_a)
    check(rc, ref_c)


def test_release_memory_returns_the_kept_blocks():
    m = bk.Diffuse(0.5)
    r = m.sample(*inputs(4))
    del r
    gc.collect()
    kept = bk._core.cached_bytes()
    assert kept >= N * 67
    assert bk.release_memory() == kept
    assert bk._core.cached_bytes() == 0
    assert bk.release_memory() == 0


def test_at_most_two_blocks_are_kept():
    m = bk.Diffuse(0.5)
    bk.release_memory()
    a, b, c = (m.sample(*inputs(s, n)) for s, n in ((5, N), (6, 2 * N), (7, 4 * N)))
    del a, b, c                       # returned in this order: the last two (2N and 4N) stay
    gc.collect()
    kept = bk._core.cached_bytes()
    # 2N + 4N elements at 67 B each (float64), each block rounded up to 2 MiB granules
    assert 6 * N * 67 <= kept <= 6 * N * 67 + 2 * (2 << 20), kept
    bk.release_memory()


@pytest.mark.parametrize("op", ["eval", "pdf"])
def test_eval_pdf_results_are_cached_blocks_on_a_line(op):
    # eval / pdf results from 1 MiB on come from the cache too (64-byte aligned: the memory-bound
    # models stream into them, batch.h); a live result is never handed out again, a freed one is
    m = bk.DiffuseTransmission(0.4, 0.3)
    bk.release_memory()
    fn = getattr(m, op)
    n = 150_000                       # pdf: 1.2 MB (float64)
    (wo, _, _), (wi, _, _) = inputs(8, n), inputs(9, n)
    wi = wi * np.array([1, 1, -1])    # transmission pairs: non-zero f and pdf
    ref = np.concatenate([fn(wo[i:i + 10_000], wi[i:i + 10_000]) for i in range(0, n, 10_000)])
    a = fn(wo, wi)
    assert a.nbytes >= 1 << 20 and a.ctypes.data % 64 == 0 and a.base is not None
    b = fn(wi, wo)                    # a is alive: another block
    np.testing.assert_array_equal(a, ref)
    del b
    gc.collect()
    assert bk._core.cached_bytes() >= a.nbytes
    c = fn(wo[::-1].copy(), wi[::-1].copy())  # reuses b's block
    np.testing.assert_array_equal(a, ref)
    np.testing.assert_array_equal(c, ref[::-1])
    assert np.count_nonzero(ref) > n // 2
    bk.release_memory()
