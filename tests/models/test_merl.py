"""MERL tables: the file format, MERL's lookup (against an independent numpy port of
BRDFRead.cpp's lookup_brdf_val), the write_merl -> MERL.load round trip, the tabulated sampler
(chi^2, consistency, efficiency), extremes and hostile files."""
import os
import pickle
import re

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as ref
from bsdfkit.testing.merl_ref import index_ref as merl_index_ref, linear_corners

SCALE = np.array([1.0 / 1500, 1.15 / 1500, 1.66 / 1500])


def write_raw(path, planes, dims=(90, 90, 180)):
    with open(path, "wb") as fh:
        fh.write(np.asarray(dims, "<i4").tobytes())
        fh.write(np.ascontiguousarray(planes, "<f8").tobytes())
    return str(path)


def upper_pairs(rng, n, zmin=0.02):
    def d():
        v = rng.normal(size=(n, 3))
        v[:, 2] = np.abs(v[:, 2]) + zmin
        return v / np.linalg.norm(v, axis=1, keepdims=True)
    return d(), d()


@pytest.fixture(scope="module")
def random_file(tmp_path_factory):
    rng = np.random.default_rng(7)
    planes = rng.uniform(0, 3000, size=(3, 90, 90, 180))
    planes[rng.random(planes.shape) < 0.02] = -1.0     # not measured
    path = write_raw(tmp_path_factory.mktemp("merl") / "random.binary", planes)
    return path, planes


@pytest.fixture(scope="module")
def glossy_file(tmp_path_factory):
    model = bk.Conductor.from_metal("Cu", alpha=0.25)
    path = bk.measured.write_merl(tmp_path_factory.mktemp("merl") / "cu.binary", model)
    return path, model


# ---------------------------------------------------------------- format and lookup

def test_nearest_lookup_matches_merl_reference(random_file):
    path, planes = random_file
    m = bk.MERL.load(path)
    rng = np.random.default_rng(1)
    wo, wi = upper_pairs(rng, 20000)
    ih, idd, ip, *_ = merl_index_ref(wo, wi)
    raw = planes[:, ih, idd, ip].T                      # (n, 3), file values
    expect = np.where(raw >= 0, raw * SCALE, 0.0)       # channel scales; negative = not measured -> 0
    got = m.eval(wo, wi)
    # a direction pair sitting on a bin boundary may round to either side: allow a handful
    mismatch = np.any(np.abs(got - expect) > 1e-12 * np.abs(expect) + 1e-15, axis=1)
    assert mismatch.mean() < 1e-3, mismatch.mean()
    assert m.measured.shape == (90, 90, 180, 3) and (~m.measured).sum() == (planes < 0).sum()
    # two-sided by flipping, reflection only
    np.testing.assert_array_equal(m.eval(-wo, -wi), got)
    assert np.all(m.eval(wo, -wi) == 0)


def test_linear_lookup_matches_trilinear_reference(random_file):
    path, planes = random_file
    m = bk.MERL(path, interpolation="linear")
    vals = np.where(planes >= 0, planes * SCALE[:, None, None, None], 0.0)
    rng = np.random.default_rng(2)
    wo, wi = upper_pairs(rng, 5000)
    _, _, _, th, td, pd = merl_index_ref(wo, wi)
    out = 0
    for (a, b, p), w in linear_corners(th, td, pd):
        out = out + w[:, None] * vals[:, a, b, p].T
    np.testing.assert_allclose(m.eval(wo, wi), out, rtol=1e-9, atol=1e-12)
    # linear is reciprocal (the fold makes phi_d pi-periodic and the rest is symmetric)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-7, atol=1e-12)


def test_file_bytes_are_merl_layout(tmp_path):
    """write_merl's bytes decoded independently: header, channel planes, scales."""
    model = bk.Diffuse([0.2, 0.5, 0.8])
    path = bk.measured.write_merl(tmp_path / "d.binary", model)
    data = open(path, "rb").read()
    assert len(data) == 12 + 8 * 3 * 90 * 90 * 180 == 34992012
    assert tuple(np.frombuffer(data[:12], "<i4")) == (90, 90, 180)
    planes = np.frombuffer(data, "<f8", offset=12).reshape(3, 90, 90, 180)
    wo, wi = bk.measured.merl_directions()
    ok = (wo[..., 2] > 0) & (wi[..., 2] > 0)
    for c in range(3):
        np.testing.assert_allclose(planes[c][ok] * SCALE[c], [0.2, 0.5, 0.8][c] / np.pi, rtol=1e-12)
        assert np.all(planes[c][~ok] == -1)
    m = bk.MERL.load(path)
    rng = np.random.default_rng(3)
    wo, wi = upper_pairs(rng, 2000, zmin=0.3)
    f = m.eval(wo, wi)
    # bins whose centre lies below the horizon read 0 even for an above-horizon pair
    ok = np.all(f > 0, axis=1)
    assert ok.mean() > 0.95
    np.testing.assert_allclose(f[ok], np.broadcast_to([0.2 / np.pi, 0.5 / np.pi, 0.8 / np.pi], f[ok].shape), rtol=1e-12)


@pytest.mark.parametrize("interp", ["nearest", "linear"])
def test_round_trip_error(glossy_file, interp):
    """write_merl(model) -> MERL.load -> eval vs model: median / p90 relative error (luminance)
    over random pairs away from the horizon."""
    path, model = glossy_file
    m = bk.MERL(path, interpolation=interp)
    rng = np.random.default_rng(4)
    wo, wi = upper_pairs(rng, 50000, zmin=0.15)
    lum = np.array([0.2126, 0.7152, 0.0722])
    a, b = model.eval(wo, wi) @ lum, m.eval(wo, wi) @ lum
    keep = a > 1e-3 * a.max()
    err = np.abs(b[keep] - a[keep]) / a[keep]
    med, p90 = np.median(err), np.quantile(err, 0.9)
    print(f"MERL round trip ({interp}): median {med:.4f} p90 {p90:.4f} relative error")
    assert med < (0.005 if interp == "linear" else 0.03) and p90 < (0.01 if interp == "linear" else 0.08)
    if interp == "linear":
        near = bk.MERL(path, interpolation="nearest").eval(wo, wi) @ lum
        assert np.median(err) < np.median(np.abs(near[keep] - a[keep]) / a[keep])


def test_write_merl_rejects_anisotropic(tmp_path):
    with pytest.raises(ValueError, match="isotropic"):
        bk.measured.write_merl(tmp_path / "a.binary", bk.Conductor(0.2, 3.0, alpha_x=0.1, alpha_y=0.5))
    assert not os.path.exists(tmp_path / "a.binary")


def test_write_merl_refuses_what_read_merl_refuses(tmp_path):
    """A model whose values leave float32's range once divided by MERL's scales: write_merl
    refuses to write a file read_merl would refuse."""
    def huge(wo, wi):
        return np.full(np.broadcast_shapes(wo.shape, wi.shape), 1e300)
    with pytest.raises(ValueError, match=r"^model: .* gave values up to 1\.5e\+303 on the MERL grid .* beyond "
                                         r"float32's max 3\.40282347e\+38"):
        bk.measured.write_merl(tmp_path / "h.binary", bk.Custom(huge, name="huge"))
    assert not os.path.exists(tmp_path / "h.binary")


# ---------------------------------------------------------------- model contract

def test_value_semantics_and_pickle(glossy_file, tmp_path):
    path, _ = glossy_file
    a, b = bk.MERL(path), bk.MERL.load(path)
    assert a == b and hash(a) == hash(b) and a != bk.MERL(path, interpolation="linear")
    assert eval(repr(a), {"MERL": bk.MERL}) == a
    c = pickle.loads(pickle.dumps(a))
    assert c == a
    rng = np.random.default_rng(5)
    wo, wi = upper_pairs(rng, 100)
    np.testing.assert_array_equal(c.eval(wo, wi), a.eval(wo, wi))
    with pytest.raises(AttributeError):
        a.interpolation = "linear"
    # a changed file is refused on unpickling
    p2 = str(tmp_path / "copy.binary")
    bk.measured.write_merl(p2, bk.Diffuse(0.5))
    s = pickle.dumps(bk.MERL(p2))
    bk.measured.write_merl(p2, bk.Diffuse(0.6))
    with pytest.raises(ValueError, match="digest"):
        pickle.loads(s)


@pytest.mark.parametrize("interp", ["nearest", "linear"])
def test_sample_eval_pdf_consistency_and_extremes(glossy_file, interp):
    path, _ = glossy_file
    m = bk.MERL(path, interpolation=interp)
    rng = np.random.default_rng(6)
    for z in (1.0, 0.9, 0.5, 0.1, 1e-4, -0.6):
        wo = np.array([np.sqrt(1 - z * z), 0.0, z])
        s = m.sample(wo, n=4000, seed=1)
        assert np.all(np.isfinite(s.f)) and np.all(np.isfinite(s.pdf)) and s.valid.mean() > 0.5
        v = s.valid
        np.testing.assert_allclose(m.eval(wo, s.wi[v]), s.f[v], rtol=1e-12)
        np.testing.assert_allclose(m.pdf(wo, s.wi[v]), s.pdf[v], rtol=1e-12)
        assert np.all(np.sign(s.wi[v][:, 2]) == np.sign(z))
        # wi = -wo: different hemispheres -> 0
        assert np.all(m.eval(wo, -wo) == 0) and m.pdf(wo, -wo) == 0
    wo, wi = upper_pairs(rng, 1000, zmin=0.0)
    for dt in (np.float32, np.float64):
        assert np.all(np.isfinite(m.eval(wo.astype(dt), wi.astype(dt))))
        assert np.all(np.isfinite(m.pdf(wo.astype(dt), wi.astype(dt))))


ZS = [0.999, 0.8, 0.5, 0.25, 0.05, -0.6]
CHI2 = [(interp, z) for interp in ("nearest", "linear") for z in ZS]
R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@pytest.mark.parametrize("interp, z", CHI2, ids=[f"{i}-z{z}" for i, z in CHI2])
def test_chi2(glossy_file, interp, z):
    path, _ = glossy_file
    m = bk.MERL(path, interpolation=interp)
    s = np.sqrt(1 - z * z)
    wo = np.array([s * np.cos(0.7), s * np.sin(0.7), z])

    def sample_fn(uc, u):
        r = m.sample(wo, uc, u)
        return r.wi @ R.T, r.valid

    passed, p, msg = ref.chi2_test(sample_fn, lambda v: m.pdf(wo, v @ R), res=101, ires=16,
                                   sample_count=1_000_000, seed=3, significance=0.01, test_count=len(CHI2))
    print(f"MERL chi2 {interp} z={z}: p = {p:.4g}")
    assert passed, msg


def test_sampler_beats_cosine(glossy_file):
    """Relative variance of the luminance weights f cos / pdf: tabulated sampler vs cosine
    sampling (the efficiency reported in bench/MEASURED.md)."""
    path, _ = glossy_file
    m = bk.MERL(path)
    lum = np.array([0.2126, 0.7152, 0.0722])
    rng = np.random.default_rng(8)
    for z in (0.9, 0.5, 0.2):
        wo = np.array([np.sqrt(1 - z * z), 0.0, z])
        s = m.sample(wo, n=200000, seed=2)
        w = s.weight @ lum
        u = rng.random((200000, 2))
        r, ph = np.sqrt(u[:, 0]), 2 * np.pi * u[:, 1]
        wi = np.stack([r * np.cos(ph), r * np.sin(ph), np.sqrt(1 - u[:, 0])], axis=1)
        wc = (m.eval(wo, wi) @ lum) * np.pi     # f cos / (cos / pi)
        rv_t, rv_c = w.var() / w.mean() ** 2, wc.var() / wc.mean() ** 2
        print(f"MERL sampler z={z}: relative weight variance {rv_t:.3f} (tabulated) vs {rv_c:.3f} (cosine); "
              f"albedo {w.mean():.4f} vs {wc.mean():.4f}")
        assert abs(w.mean() - wc.mean()) < 0.03 * wc.mean()
        assert rv_t < 0.25 * rv_c


# ---------------------------------------------------------------- hostile files

def test_missing_and_directory(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.binary"):
        bk.MERL.load(tmp_path / "nope.binary")
    with pytest.raises(IsADirectoryError, match=str(tmp_path)):
        bk.MERL.load(tmp_path)
    with pytest.raises(ValueError, match="interpolation"):
        bk.MERL(tmp_path / "x", interpolation="cubic")


def test_truncated_and_inconsistent(tmp_path):
    good = bk.measured.write_merl(tmp_path / "g.binary", bk.Diffuse(0.5))
    data = open(good, "rb").read()
    for cut in (0, 3, 4, 8, 11, 12, 13, 20, len(data) - 8, len(data) - 1):
        p = tmp_path / f"cut{cut}.binary"
        p.write_bytes(data[:cut])
        with pytest.raises(ValueError, match="dims|values") as e:
            bk.MERL.load(p)
        assert str(p) in str(e.value)
    p = tmp_path / "long.binary"
    p.write_bytes(data + b"\0" * 8)
    with pytest.raises(ValueError, match="values"):
        bk.MERL.load(p)
    for dims in ((90, 90, 360), (180, 90, 90), (-1, 90, 180), (2**31 - 1, 2**31 - 1, 2**31 - 1)):
        p = tmp_path / "dims.binary"
        p.write_bytes(np.asarray(dims, "<i4").tobytes() + data[12:])
        with pytest.raises(ValueError, match="dims"):
            bk.MERL.load(p)
    planes = np.frombuffer(data, "<f8", offset=12).copy()
    for bad in (np.nan, np.inf):
        planes[12345] = bad
        p = tmp_path / "nan.binary"
        p.write_bytes(data[:12] + planes.tobytes())
        with pytest.raises(ValueError, match="values: non-finite"):
            bk.MERL.load(p)
    # finite float64 values beyond float32's max (the table is evaluated in float32 too, where
    # they became inf and then 0 with no error); negative values of any size mark unmeasured bins
    planes = np.frombuffer(data, "<f8", offset=12).copy()
    for big in (1e300, 1e39, 3.4028236e38):
        planes[12345] = big
        p = tmp_path / "big.binary"
        p.write_bytes(data[:12] + planes.tobytes())
        msg = (rf"big\.binary: values: {re.escape(f'{big:.9g}')} at \(channel, theta_h, theta_d, phi_d\) = "
               r"\(0, 0, 68, 105\) exceeds float32's max 3\.40282347e\+38")
        with pytest.raises(ValueError, match=msg):
            bk.MERL.load(p)
    planes[12345], planes[54321] = np.finfo(np.float32).max, -1e300
    p = tmp_path / "edge.binary"
    p.write_bytes(data[:12] + planes.tobytes())
    m = bk.MERL.load(p)
    assert not m.measured[3, 31, 141, 0] and m.values[3, 31, 141, 0] == 0
    np.testing.assert_allclose(m.values[0, 68, 105, 0], float(np.finfo(np.float32).max) / 1500, rtol=1e-15)
    wo = bk.hemisphere_grid(6, 12)
    assert np.all(np.isfinite(m.eval(wo.astype(np.float32), wo[::-1].astype(np.float32))))
