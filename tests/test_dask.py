"""Dask: ``bk.fit_many`` on a real LocalCluster of two worker processes, and Dask arrays of
directions in ``eval`` / ``pdf``, compared with the in-process results bit for bit; per-target
errors reported, not raised; models (measured, table-backed ones included) travel pickled, and a
model that cannot travel fails with a clear error. One cluster for the module (start-up ~2 s)."""
import pickle
import threading

import dask
import dask.array as da
import numpy as np
import pytest
from distributed import Client, LocalCluster

import bsdfkit as bk
from bsdfkit.fitting.distributed import QUIET_CLUSTER

FIT_KW = dict(params=("eta", "k", "alpha"), n=512, max_nfev=40, albedo=False)


@pytest.fixture(scope="module")
def client():
    cluster = LocalCluster(n_workers=2, processes=True, threads_per_worker=1, **QUIET_CLUSTER)
    c = Client(cluster, set_as_default=False)
    yield c
    c.close()
    cluster.close()


def _samples(seed):
    rng = np.random.default_rng(seed)
    m = bk.Conductor.from_metal("Au", alpha=0.25)
    wo = bk.direction(np.arccos(rng.uniform(0.05, 1, 600)), rng.uniform(0, 2 * np.pi, 600))
    wi = bk.direction(np.arccos(rng.uniform(0.05, 1, 600)), rng.uniform(0, 2 * np.pi, 600))
    return wo, wi, m.eval(wo, wi)


def _same_fit(a, b):
    """(model, report) pairs equal bit for bit in everything but the wall time."""
    ma, ra = a
    mb, rb = b
    assert ma == mb
    assert ra.params == rb.params and ra.init == rb.init and ra.cost == rb.cost
    for k in ("rel_p50", "rel_p90", "rel_p99", "rel_max"):
        np.testing.assert_array_equal(getattr(ra, k), getattr(rb, k))
    assert (ra.nfev, ra.njev, ra.success, ra.albedo_error) == (rb.nfev, rb.njev, rb.success, rb.albedo_error)


def test_fit_many_matches_in_process_and_reports_failures(client):
    targets = [bk.Conductor.from_metal("Cu", alpha=0.3), bk.Conductor.from_metal("Al", alpha_x=0.2, alpha_y=0.1),
               _samples(1),
               (np.zeros((4, 3)), np.zeros((4, 3)), -np.ones((4, 3))),    # raises in bk.fit: reported
               bk.Conductor.from_metal("Ag", alpha=0.15)]
    seen = []
    res = bk.fit_many(targets, bk.Conductor, client=client, progress=lambda d, t, o: seen.append((d, t, o.index)),
                      **FIT_KW)
    assert len(res) == 5 and [o.index for o in res] == [0, 1, 2, 3, 4]
    assert sorted(s[2] for s in seen) == [0, 1, 2, 3, 4] and [s[0] for s in seen] == [1, 2, 3, 4, 5]
    assert all(s[1] == 5 for s in seen)
    assert list(res.errors) == [3] and res.errors[3].startswith("ValueError: target")
    assert "Traceback" in res[3].traceback and res[3].model is None and not res[3].ok
    for i in (0, 1, 2, 4):
        assert res[i].ok
        _same_fit((res[i].model, res[i].report), bk.fit(targets[i], bk.Conductor, **FIT_KW))
    text = repr(res)
    assert "FAILED: ValueError" in text and "4 fitted, 1 failed" in text
    assert "<table>" in res._repr_html_()
    assert res.models[3] is None and res.reports[0] is res[0].report


def test_fit_many_own_cluster_with_measured_targets(tmp_path):
    # a table-backed target pickles by (path, digest): the workers read the same file
    src = bk.Conductor.from_metal("Cu", alpha=0.3)
    merl = bk.MERL.load(bk.measured.write_merl(tmp_path / "cu.binary", src), interpolation="linear")
    kw = dict(params=("eta", "k", "alpha"), n=256, max_nfev=20, albedo=False)
    res = bk.fit_many([merl, src], bk.Conductor, n_workers=1, labels=["merl", "analytic"], **kw)
    assert res.n_workers == 1 and [o.label for o in res] == ["merl", "analytic"]
    for o, t in zip(res, (merl, src)):
        assert o.ok, o.traceback
        _same_fit((o.model, o.report), bk.fit(t, bk.Conductor, **kw))


def test_fit_many_arguments(client):
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    with pytest.raises(TypeError, match="family"):
        bk.fit_many([m], "Conductor", client=client)
    with pytest.raises(TypeError, match="targets"):
        bk.fit_many(m, bk.Conductor, client=client)
    with pytest.raises(TypeError, match="bk.fit"):
        bk.fit_many([m], bk.Conductor, client=client, no_such_keyword=1)
    with pytest.raises(ValueError, match="labels"):
        bk.fit_many([m], bk.Conductor, client=client, labels=["a", "b"])
    with pytest.raises(ValueError, match="n_workers"):
        bk.fit_many([m], bk.Conductor, client=client, n_workers=2)
    with pytest.raises(ValueError, match="kernel_threads"):
        bk.fit_many([m], bk.Conductor, client=client, kernel_threads=0)
    with pytest.raises(TypeError, match="client"):
        bk.fit_many([m], bk.Conductor, client=3)
    assert len(bk.fit_many([], bk.Conductor, client=client)) == 0


# ----------------------------------------------------------------------------------- arrays

def _dirs(rng, n, shape=None):
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v if shape is None else v.reshape(shape + (3,))


MODELS = {
    "conductor": lambda tmp: bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.1),
    "dielectric": lambda tmp: bk.Dielectric(1.5, alpha=0.2),
    "filament-coat": lambda tmp: bk.FilamentStandard((0.7, 0.3, 0.2), clear_coat=0.8, roughness=0.4),
    "coated-analytic": lambda tmp: bk.CoatedConductor.from_metal("Au", conductor_alpha=0.3, interface_alpha=0.05,
                                                                 method="analytic"),
    "merl": lambda tmp: bk.MERL.load(bk.measured.write_merl(tmp / "cu.binary", bk.Conductor.from_metal("Cu", alpha=0.3))),
    "measured-in-memory": lambda tmp: bk.measured.tabulate(bk.Conductor.from_metal("Au", alpha=0.3), resolution=8),
}


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_dask_arrays_are_bit_identical(name, dtype, client, tmp_path):
    rng = np.random.default_rng(7)
    m = MODELS[name](tmp_path)
    wo = np.abs(_dirs(rng, 1).reshape(3)).astype(dtype)   # above the surface (one-sided models)
    wi = _dirs(rng, 5000).astype(dtype)
    wi_d = da.from_array(wi, chunks=(777, 3))
    f = m.eval(wo, wi_d)
    p = m.pdf(wo, wi_d)
    assert isinstance(f, da.Array) and isinstance(p, da.Array)
    assert f.shape == (5000, 3) and p.shape == (5000,) and f.dtype == dtype and p.dtype == dtype
    assert f.chunks[0] == wi_d.chunks[0] and p.chunks[0] == wi_d.chunks[0]   # blockwise, chunks aligned
    fc, pc = client.compute([f, p], sync=True)
    np.testing.assert_array_equal(fc, m.eval(wo, wi))
    np.testing.assert_array_equal(pc, m.pdf(wo, wi))
    assert np.count_nonzero(fc) > 100


def test_dask_arrays_broadcast_and_align_chunks(client):
    rng = np.random.default_rng(8)
    m = bk.FilamentCloth((0.3, 0.1, 0.1), roughness=0.6)
    wo = _dirs(rng, 4, (4, 1))
    wi = _dirs(rng, 4 * 300, (4, 300))
    wo_d = da.from_array(wo, chunks=(1, 1, 3))
    wi_d = da.from_array(wi, chunks=(2, 100, 2))   # the direction axis split: rechunked to one chunk
    f = m.eval(wo_d, wi_d)
    assert f.shape == (4, 300, 3)
    np.testing.assert_array_equal(client.compute(f, sync=True), m.eval(wo, wi))
    p = m.pdf(wo_d, wi, mode="importance")        # a numpy side mixes in
    np.testing.assert_array_equal(client.compute(p, sync=True), m.pdf(wo, wi, mode="importance"))
    # the local scheduler computes the same graph
    with dask.config.set(scheduler="synchronous"):
        np.testing.assert_array_equal(f.compute(), m.eval(wo, wi))


def test_dask_array_errors(client, tmp_path):
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    wo = np.array([0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="wi: expected an array of directions"):
        m.eval(wo, da.zeros((10, 2), chunks=5))
    with pytest.raises(TypeError, match="out"):
        m.eval(wo, da.zeros((10, 3), chunks=5), out=np.empty((10, 3)))
    with pytest.raises(ValueError, match="broadcast"):
        m.pdf(da.zeros((4, 3), chunks=2), da.zeros((5, 3), chunks=5))
    with pytest.raises(TypeError, match="wo: expected a real numeric array"):
        m.eval(da.from_array(np.array([["a", "b", "c"]])), wo)
    # a bad direction is found where the block is evaluated, with eval's own words
    bad = da.from_array(np.array([[0.0, 0.0, 1.0], [1.0, 1.0, 1.0]]), chunks=1)
    with pytest.raises(ValueError, match="wi: 1 direction"):
        client.compute(m.eval(wo, bad), sync=True)
    # a model that cannot be pickled is refused when the array is built
    lock = threading.Lock()
    custom = bk.Custom(lambda o, i: np.full(np.broadcast_shapes(o.shape, i.shape)[:-1] + (3,), lock.locked() * 0.1))
    with pytest.raises(TypeError, match="cannot be pickled"):
        custom.eval(wo, da.zeros((4, 3), chunks=2))
    # a table-backed model whose file the workers cannot read fails with the file named
    path = bk.measured.write_merl(tmp_path / "gone.binary", bk.Conductor.from_metal("Cu", alpha=0.3))
    merl = bk.MERL.load(path)
    with open(path, "r+b") as fh:
        fh.seek(100)
        fh.write(b"\x00\x01\x02\x03")  # the content changes: workers refuse the digest
    wi = da.from_array(_dirs(np.random.default_rng(1), 8), chunks=4)
    with pytest.raises((OSError, ValueError), match="gone.binary.*same file at the same path"):
        client.compute(merl.eval(wo, wi), sync=True)


def test_models_pickle_for_workers(tmp_path):
    """Every registered example (and the table-backed ones) survives the round trip the workers do."""
    from bsdfkit.models.registry import classes
    import cloudpickle

    from bsdfkit.models.spec import parse_spec
    for cls in classes():
        for spec in cls.examples.values():
            m = parse_spec(spec)
            assert pickle.loads(cloudpickle.dumps(m)) == m
