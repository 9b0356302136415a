"""Streaming (non-temporal) stores of a large call's outputs (batch.h, kStreamMinBytes; the models whose
batch_policy.h line says stream_outputs: Diffuse, DiffuseTransmission, and Conductor, Dielectric and ThinDielectric when
smooth). A call of at least 16 MiB of traffic writes whole lines with streaming stores: eval / pdf from
the first element whose output row starts on a 64-byte line (the rows before it, fewer than a packet,
plainly: numpy's arrays start 16 bytes past a line), the sampler where its output starts on one. Only
how the values are stored changes: these calls must give the values of small calls (the plain path) bit
for bit, with outputs on a line or at any offset from one, as rows or as planes (Fortran order), at any
thread count, in float32 and float64, for eval, pdf and sample (the delta lobes' eval and pdf: zeros
written over NaN). A rough Conductor (its instance does not stream) runs the same checks as a control."""
import numpy as np
import pytest

import bsdfkit as bk
from conftest import random_dirs

MODELS = {
    "Diffuse": lambda: bk.Diffuse((0.2, 0.5, 0.8)),
    "DiffuseTransmission": lambda: bk.DiffuseTransmission((0.2, 0.6, 0.3), (0.7, 0.1, 0.5)),
    "Conductor-rough": lambda: bk.Conductor.from_metal("Au", alpha=0.3),
    "Conductor-smooth": lambda: bk.Conductor.from_metal("Cu", alpha=0),
    "Dielectric-smooth": lambda: bk.Dielectric(1.5),
    "ThinDielectric": lambda: bk.ThinDielectric(1.33),
}
DELTA = {"Conductor-smooth", "Dielectric-smooth", "ThinDielectric"}  # f = pdf = 0 for every given pair
# eval over N pairs moves 36 N bytes in float32 (two (N, 3) inputs, one (N, 3) output): N = 600013 is
# 21.6 MB, past the 16 MiB threshold, and not a multiple of the packet (16) or the chunk (8192).
N = 600_013
PIECE = 49_999  # the reference's calls: 1.8 MB each (plain stores), packets shifted against the big call's


def _inputs(dtype):
    rng = np.random.default_rng(21)
    wo, wi = random_dirs(rng, N), random_dirs(rng, N)
    uc, u = rng.random(N), rng.random((N, 2))
    return wo.astype(dtype), wi.astype(dtype), uc.astype(dtype), u.astype(dtype)


def _pieces(fn, *args):
    parts = [fn(*(a[i:i + PIECE] for a in args)) for i in range(0, N, PIECE)]
    return parts


def _view(shape, dtype, misalign):
    """An uninitialized (NaN-filled) C-order array of `shape` starting on a 64-byte line, or `misalign`
    elements past one."""
    dtype = np.dtype(dtype)
    count = int(np.prod(shape))
    buf = np.full(count + 64, np.nan, dtype)
    off = (-buf.ctypes.data % 64) // dtype.itemsize + misalign
    out = buf[off:off + count].reshape(shape)
    assert (out.ctypes.data % 64 == 0) == (misalign == 0)
    return out


@pytest.fixture(scope="module", params=[np.float32, np.float64], ids=["f32", "f64"])
def inputs(request):
    return _inputs(request.param)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_eval_pdf_streamed_equal_small_calls(name, inputs):
    m = MODELS[name]()
    wo, wi, _, _ = inputs
    dtype = wo.dtype
    ref_f = np.concatenate(_pieces(m.eval, wo, wi))
    ref_p = np.concatenate(_pieces(m.pdf, wo, wi))
    if name in DELTA:
        # zeros, written over the NaN that _view's buffers start with
        assert not np.any(ref_f) and not np.any(ref_p) and ref_f.shape == (N, 3)
    else:
        assert np.count_nonzero(ref_f) > N  # not a comparison of zeros
    for threads in (1, 2):  # conftest restores the thread count
        bk.set_num_threads(threads)
        f, p = m.eval(wo, wi), m.pdf(wo, wi)
        # bsdfkit's own results start on a line (BlockCache blocks): the streamed case
        assert f.ctypes.data % 64 == 0 and p.ctypes.data % 64 == 0
        np.testing.assert_array_equal(f, ref_f, err_msg=f"{name} eval, {threads} thread(s)")
        np.testing.assert_array_equal(p, ref_p, err_msg=f"{name} pdf, {threads} thread(s)")
        # every offset from a line a float can have (numpy's own: 16 bytes): the first rows plainly,
        # up to a packet of them, the rest streamed
        for misalign in range(64 // dtype.itemsize):
            out_f, out_p = _view((N, 3), dtype, misalign), _view((N,), dtype, misalign)
            assert m.eval(wo, wi, out=out_f) is out_f and m.pdf(wo, wi, out=out_p) is out_p
            np.testing.assert_array_equal(out_f, ref_f, err_msg=f"{name} eval out= +{misalign}")
            np.testing.assert_array_equal(out_p, ref_p, err_msg=f"{name} pdf out= +{misalign}")
        # planes (Fortran order) in and out, the output's planes at other offsets from a line too
        wo_f, wi_f = np.asfortranarray(wo), np.asfortranarray(wi)
        for misalign in (0, 1, 4, 7):
            out_f = _view((3, N), dtype, misalign).T
            out_p = _view((N,), dtype, misalign)
            assert m.eval(wo_f, wi_f, out=out_f) is out_f and m.pdf(wo_f, wi_f, out=out_p) is out_p
            np.testing.assert_array_equal(out_f, ref_f, err_msg=f"{name} eval planes out= +{misalign}")
            np.testing.assert_array_equal(out_p, ref_p, err_msg=f"{name} pdf planes out= +{misalign}")


FIELDS = ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional")


@pytest.mark.parametrize("name", sorted(MODELS))
def test_sample_streamed_equal_small_calls(name, inputs):
    m = MODELS[name]()
    wo, _, uc, u = inputs
    dtype = wo.dtype
    parts = _pieces(m.sample, wo, uc, u)
    ref = {k: np.concatenate([getattr(s, k) for s in parts]) for k in FIELDS}
    assert ref["valid"].sum() > N // 2
    for threads in (1, 2):
        bk.set_num_threads(threads)
        s = m.sample(wo, uc, u)
        assert s.wi.ctypes.data % 64 == 0 and s.f.ctypes.data % 64 == 0  # the sample block
        for k in FIELDS:
            np.testing.assert_array_equal(getattr(s, k), ref[k], err_msg=f"{name} sample {k}, {threads} thread(s)")
        # into an earlier result (on lines; overwritten with other values first), and into arrays
        # of which only some start on a line
        for k in FIELDS:
            a = getattr(s, k)
            a[...] = np.nan if a.dtype.kind == "f" else ~ref[k] if a.dtype == bool else 255
        assert m.sample(wo, uc, u, out=s) is s
        for k in FIELDS:
            np.testing.assert_array_equal(getattr(s, k), ref[k], err_msg=f"{name} sample out=result {k}")
        mixed = type(s)(wi=_view((N, 3), dtype, 1), f=_view((N, 3), dtype, 0), pdf=_view((N,), dtype, 2),
                        flags=np.zeros(N, np.uint8), eta=_view((N,), dtype, 0), valid=np.zeros(N, bool),
                        pdf_is_proportional=np.ones(N, bool))
        assert m.sample(wo, uc, u, out=mixed) is mixed
        for k in FIELDS:
            np.testing.assert_array_equal(getattr(mixed, k), ref[k], err_msg=f"{name} sample out=mixed {k}")
