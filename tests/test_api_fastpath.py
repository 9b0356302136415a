"""The compiled door (bind_model.h eval / pdf / sample / albedo; issue 10 per-call overhead, issue 17
item 3, issue 46 one door): plain ndarrays go straight to the kernels, anything else is converted in
the same call. Both must give the same values and the same errors; uniforms are checked by the kernel;
sample's outputs are views of one block; sample accepts out=."""
import numpy as np
import pytest

import bsdfkit as bk


def _dirs(rng, n, upper=True):
    w = rng.normal(size=(n, 3))
    if upper:
        w[:, 2] = np.abs(w[:, 2])
    return w / np.linalg.norm(w, axis=1, keepdims=True)


MODELS = [lambda: bk.Conductor.from_metal("Cu", alpha=0.3), lambda: bk.Dielectric(1.5, alpha=0.2),
          lambda: bk.Diffuse([0.2, 0.5, 0.8])]


@pytest.mark.parametrize("make", MODELS)
def test_fast_and_general_paths_agree(make, rng):
    m = make()
    wo, wi = _dirs(rng, 40), _dirs(rng, 40, upper=False)
    uc, u = rng.random(40), rng.random((40, 2))
    # plain ndarrays (fast) vs lists / a strided view (general): bit-identical
    np.testing.assert_array_equal(m.eval(wo, wi), m.eval(wo.tolist(), wi.tolist()))
    np.testing.assert_array_equal(m.pdf(wo, wi), m.pdf(wo.tolist(), wi[:, :].copy(order="F")))
    s_fast, s_gen = m.sample(wo, uc, u), m.sample(wo.tolist(), uc.tolist(), u.tolist())
    for k in ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional"):
        a, b = getattr(s_fast, k), getattr(s_gen, k)
        assert a.dtype == b.dtype and a.shape == b.shape
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(m.albedo(wo[:3], n_samples=256, seed=5),
                                  m.albedo(wo[:3].tolist(), n_samples=256, seed=5))
    # one direction against many, both ways, and (1, 3) against (n, 3): numpy broadcasting
    for a, b in ((wo[0], wi), (wo, wi[0]), (wo[:1], wi), (wo, wi[:1])):
        want = m.eval(np.broadcast_to(a, wi.shape).tolist(), np.broadcast_to(b, wi.shape).tolist())
        np.testing.assert_array_equal(m.eval(a, b), want)
        assert m.eval(a, b).shape == (40, 3) and m.pdf(a, b).shape == (40,)
    # (1, 1, 3) against (40, 3) broadcasts to (1, 40): the general path
    assert m.eval(wo[:1, None], wi).shape == (1, 40, 3)
    # batch shapes are kept, float32 runs float32
    assert m.eval(wo.reshape(4, 10, 3), wi.reshape(4, 10, 3)).shape == (4, 10, 3)
    assert m.sample(wo.reshape(4, 10, 3), uc.reshape(4, 10), u.reshape(4, 10, 2)).wi.shape == (4, 10, 3)
    assert m.sample(wo[0], uc.reshape(4, 10), u.reshape(4, 10, 2)).pdf.shape == (4, 10)
    f32 = m.eval(wo.astype(np.float32), wi.astype(np.float32))
    assert f32.dtype == np.float32
    assert m.sample(wo.astype(np.float32), uc.astype(np.float32), u.astype(np.float32)).f.dtype == np.float32
    assert m.albedo(wo[:2].astype(np.float32), n_samples=16).dtype == np.float32
    # mode and sample_flags: IntEnum, int and string spellings agree
    imp = m.eval(wo, wi, mode=bk.TransportMode.Importance)
    np.testing.assert_array_equal(imp, m.eval(wo, wi, mode=1))
    np.testing.assert_array_equal(imp, m.eval(wo, wi, mode="importance"))
    np.testing.assert_array_equal(m.pdf(wo, wi, sample_flags=bk.ReflTrans.Reflection), m.pdf(wo, wi, sample_flags=1))


def test_empty_batches():
    m = bk.Diffuse(0.5)
    e = np.empty((0, 3))
    assert m.eval(e, e).shape == (0, 3) and m.pdf(e, e).shape == (0,)
    s = m.sample(e, np.empty(0), np.empty((0, 2)))
    assert s.wi.shape == (0, 3) and s.valid.shape == (0,)
    assert m.albedo(e).shape == (0, 3)


def test_bad_values_name_the_argument_on_both_paths():
    m = bk.Conductor.from_metal("Au", alpha=0.2)
    z = np.array([[0, 0, 1.0]] * 4)
    bad = z.copy()
    bad[1] = [0, 0, 2.0]
    bad[3, 0] = np.nan
    for conv in (np.asarray, lambda a: a.tolist()):   # fast path, general path
        with pytest.raises(ValueError, match=r"^wo: 2 direction\(s\) are not finite unit vectors"):
            m.eval(conv(bad), conv(z))
        with pytest.raises(ValueError, match=r"^wi: 2 direction\(s\)"):
            m.pdf(conv(z), conv(bad))
        with pytest.raises(ValueError, match=r"^wo: 2 direction\(s\)"):
            m.sample(conv(bad), conv(np.full(4, 0.5)), conv(np.full((4, 2), 0.5)))
        with pytest.raises(ValueError, match=r"^wo: 2 direction\(s\)"):
            m.albedo(conv(bad), n_samples=8)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_uniforms_are_checked_by_the_kernel(dtype):
    m = bk.Dielectric(1.5, alpha=0.1)
    z = np.array([0, 0, 1.0], dtype)
    uc, u = np.full(5, 0.5, dtype), np.full((5, 2), 0.5, dtype)
    for conv in (np.asarray, lambda a: a.tolist()):
        for bad_uc, n in (([1.5], 1), ([np.nan, -0.1], 2), ([np.inf], 1), ([-np.inf, 2, 3], 3)):
            c = uc.copy()
            c[:len(bad_uc)] = bad_uc
            with pytest.raises(ValueError, match=rf"^uc: {n} sample value\(s\) are outside \[0, 1\] or NaN"):
                m.sample(conv(z), conv(c), conv(u))
        w = u.copy()
        w[2, 1], w[4, 0] = np.nan, 1.0 + 1e-6
        with pytest.raises(ValueError, match=r"^u: 2 sample value\(s\) are outside \[0, 1\] or NaN"):
            m.sample(conv(z), conv(uc), conv(w))
    # the closed ends are valid
    ends = np.array([0.0, 1.0, 0.0, 1.0, 0.5], dtype)
    s = m.sample(z, ends, np.stack([ends, ends[::-1]], -1))
    assert np.all(np.isfinite(s.f)) and np.all(np.isfinite(s.pdf))


def test_sample_outputs_are_views_of_one_block(rng):
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    wo = _dirs(rng, 1000)
    for s in (m.sample(wo, rng.random(1000), rng.random((1000, 2))),            # fast path
              m.sample(wo.tolist(), rng.random(1000).tolist(), rng.random((1000, 2)))):  # general path
        arrays = [s.wi, s.f, s.pdf, s.flags, s.eta, s.valid, s.pdf_is_proportional]
        base = s.wi.base
        assert base is not None and all(a.base is base for a in arrays)
        assert all(a.flags.c_contiguous and a.flags.writeable for a in arrays)
        # disjoint: writing one output leaves the others alone
        for a in arrays:
            for b in arrays:
                assert a is b or not np.shares_memory(a, b)
        # every value was written (an invalid sample has the documented defaults)
        assert np.all(np.isfinite(s.wi)) and np.all(np.isfinite(s.f)) and np.all(s.pdf >= 0)
        np.testing.assert_array_equal(s.valid, s.pdf > 0)


def test_sample_out_argument(rng):
    m = bk.Dielectric(1.5, alpha=0.3)
    wo, uc, u = _dirs(rng, 200), rng.random(200), rng.random((200, 2))
    want = m.sample(wo, uc, u)
    out = m.sample(wo, np.zeros(200), np.zeros((200, 2)))   # a result of the same shapes
    got = m.sample(wo, uc, u, out=out)
    assert got is out
    for k in ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional"):
        np.testing.assert_array_equal(getattr(got, k), getattr(want, k))
    with pytest.raises(TypeError, match="out"):
        m.sample(wo, uc, u, out=np.empty((200, 3)))
    with pytest.raises(ValueError, match="out.wi"):
        m.sample(wo[:100], uc[:100], u[:100], out=out)
    with pytest.raises(TypeError, match="out.wi: dtype"):
        m.sample(wo.astype(np.float32), uc.astype(np.float32), u.astype(np.float32), out=out)
    n = m.sample(wo, n=200, seed=3)
    assert m.sample(wo, n=200, seed=3, out=out) is out
    np.testing.assert_array_equal(out.wi, n.wi)


def test_sample_out_on_the_fast_path(rng):
    # plain arrays and a SampleResult of plain arrays (not views of one block): the compiled door
    # writes into them and returns out; outputs that do not fit are worded by the door, naming them
    m = bk.Plastic(0.4, alpha=0.2)
    n = 300
    wo, uc, u = _dirs(rng, n).astype(np.float32), rng.random(n, dtype=np.float32), rng.random((n, 2), dtype=np.float32)
    want = m.sample(wo, uc, u)

    def fresh():
        return bk.SampleResult(wi=np.full((n, 3), np.nan, np.float32), f=np.full((n, 3), np.nan, np.float32),
                               pdf=np.full(n, np.nan, np.float32), flags=np.full(n, 255, np.uint8),
                               eta=np.full(n, np.nan, np.float32), valid=np.zeros(n, bool),
                               pdf_is_proportional=np.ones(n, bool))

    out = fresh()
    assert m._core.sample(wo, uc, u, 0, 3, out) is out
    for k in ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional"):
        np.testing.assert_array_equal(getattr(out, k), getattr(want, k))
    out = fresh()
    assert m.sample(wo, uc, u, out=out) is out
    np.testing.assert_array_equal(out.f, want.f)
    # one broadcast direction
    one = m.sample(wo[7], uc, u)
    assert m.sample(wo[7], uc, u, out=out) is out
    np.testing.assert_array_equal(out.wi, one.wi)
    # outputs that do not fit: worded by the door
    bad = fresh()
    object.__setattr__(bad, "flags", np.zeros(n, np.int8))
    with pytest.raises(TypeError, match="out.flags: dtype must be uint8"):
        m._core.sample(wo, uc, u, 0, 3, bad)
    with pytest.raises(TypeError, match="out.flags: dtype"):
        m.sample(wo, uc, u, out=bad)
    bad = fresh()
    object.__setattr__(bad, "wi", np.zeros((3, n), np.float32).T)
    with pytest.raises(ValueError, match="out.wi: must be a writeable C-contiguous array"):
        m.sample(wo, uc, u, out=bad)
    # bad uniforms raise on the compiled path too, naming the argument
    with pytest.raises(ValueError, match="uc: 1 sample value"):
        m.sample(wo, np.where(np.arange(n) == 5, np.float32(2), uc), u, out=fresh())


SAMPLE_FIELDS = ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional")


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_sample_takes_planes_on_the_fast_path(rng, dtype):
    # Fortran-order wo and u (the .T of (3, N) and (2, N) arrays): the compiled entry transposes them
    # into rows itself (it returned None and the general path converted them with numpy before);
    # values bit-identical to C-order inputs, bad values still named, out= still written
    m = bk.Dielectric(1.5, alpha=0.2)
    n = 1000 + 13  # several packets and a partial one
    wo, uc, u = _dirs(rng, n).astype(dtype), rng.random(n).astype(dtype), rng.random((n, 2)).astype(dtype)
    wo_f, u_f = np.asfortranarray(wo), np.asfortranarray(u)
    assert wo_f.flags.f_contiguous and not wo_f.flags.c_contiguous and not u_f.flags.c_contiguous
    want = m.sample(wo, uc, u)
    for a, b in ((wo_f, u), (wo, u_f), (wo_f, u_f)):
        got = m.sample(a, uc, b)
        for k in SAMPLE_FIELDS:
            np.testing.assert_array_equal(getattr(got, k), getattr(want, k), err_msg=k)
        out = m.sample(wo, uc, u)  # an earlier result, overwritten
        out.pdf[...] = np.nan
        assert m.sample(a, uc, b, out=out) is out
        np.testing.assert_array_equal(out.pdf, want.pdf)
    bad_wo = wo_f.copy(order="F")
    bad_wo[17] *= 2
    with pytest.raises(ValueError, match=r"wo: 1 direction\(s\) are not finite unit"):
        m.sample(bad_wo, uc, u_f)
    bad_u = u_f.copy(order="F")
    bad_u[3, 1] = -0.5
    with pytest.raises(ValueError, match="u: 1 sample value"):
        m.sample(wo_f, uc, bad_u)


@pytest.mark.parametrize("name, n", [("Diffuse", 300_001), ("Dielectric", 2 * 8192 + 3085),
                                     ("CoatedDiffuse", 8192 + 1024 + 5)])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_sample_planes_across_chunks_equal_rows(rng, name, n, dtype):
    # Fortran-order wo / u transposed into rows on the pool's threads (planes_to_rows, chunks of
    # 8192), then the rows kernel: across chunks, the partial packet and both thread counts the
    # values are those of C-order inputs bit for bit; Diffuse's float32 call is large enough to
    # stream its outputs, CoatedDiffuse (a random walk) runs the scalar loop
    m = {"Diffuse": lambda: bk.Diffuse(0.7), "Dielectric": lambda: bk.Dielectric(1.5, alpha=0.3),
         "CoatedDiffuse": lambda: bk.CoatedDiffuse(reflectance=0.5, alpha=0.1)}[name]()
    wo, uc, u = _dirs(rng, n).astype(dtype), rng.random(n).astype(dtype), rng.random((n, 2)).astype(dtype)
    want = m.sample(wo, uc, u)
    assert np.count_nonzero(want.pdf) > n // 2
    for threads in (1, 2):  # conftest restores the thread count
        bk.set_num_threads(threads)
        for a, b in ((np.asfortranarray(wo), u), (wo, np.asfortranarray(u)), (np.asfortranarray(wo), np.asfortranarray(u))):
            got = m.sample(a, uc, b)
            for k in SAMPLE_FIELDS:
                np.testing.assert_array_equal(getattr(got, k), getattr(want, k), err_msg=f"{k}, {threads} thread(s)")
    bad = np.asfortranarray(wo)
    bad[n - 2] = [np.nan, 0, 1]  # in the last chunk's partial packet
    with pytest.raises(ValueError, match=r"wo: 1 direction\(s\) are not finite unit"):
        m.sample(bad, uc, np.asfortranarray(u))


def test_eval_out_on_the_fast_path(rng):
    m = bk.Diffuse(0.5)
    wo, wi = _dirs(rng, 10), _dirs(rng, 10)
    out = np.full((10, 3), np.nan)
    assert m.eval(wo, wi, out=out) is out
    np.testing.assert_array_equal(out, m.eval(wo, wi))
    pout = np.full(10, np.nan)
    assert m.pdf(wo, wi, out=pout) is pout
    np.testing.assert_array_equal(pout, m.pdf(wo, wi))
    ro = np.empty((10, 3))
    ro.setflags(write=False)
    with pytest.raises(ValueError, match="out"):
        m.eval(wo, wi, out=ro)


def test_arrays_through_pickle_are_accepted(rng):
    """An array that came through pickle (a Dask block, a multiprocessing result) carries a dtype
    descriptor equal to numpy's canonical one but not the same object: inputs and out= must still
    be accepted, with the same values as plain arrays; byte-swapped inputs are converted and a
    byte-swapped out= is refused by name."""
    import pickle

    m = bk.Conductor.from_metal("Au", alpha=0.25)
    wo, wi = _dirs(rng, 32), _dirs(rng, 32)
    wo_p, wi_p = pickle.loads(pickle.dumps(wo)), pickle.loads(pickle.dumps(wi))
    out = pickle.loads(pickle.dumps(np.full((32, 3), np.nan)))
    assert m.eval(wo_p, wi_p, out=out) is out
    np.testing.assert_array_equal(out, m.eval(wo, wi))
    pout = pickle.loads(pickle.dumps(np.full(32, np.nan, np.float32)))
    assert m.pdf(wo_p.astype(np.float32), wi_p.astype(np.float32), out=pout) is pout
    np.testing.assert_array_equal(pout, m.pdf(wo.astype(np.float32), wi.astype(np.float32)))
    # byte-swapped arrays: inputs are converted (same values), an out= is refused by name (the
    # kernels write native floats)
    swap = np.dtype(">f8") if np.little_endian else np.dtype("<f8")
    np.testing.assert_array_equal(m.eval(wo.astype(swap), wi.astype(swap)), m.eval(wo, wi))
    np.testing.assert_array_equal(m.pdf(wo.astype(swap), wi), m.pdf(wo, wi))
    with pytest.raises(TypeError, match="out"):
        m.eval(wo, wi, out=np.full((32, 3), np.nan, dtype=swap))
    with pytest.raises(TypeError, match="out"):
        m.pdf(wo, wi, out=np.full(32, np.nan, dtype=swap))
