"""Shading frames (issue 47 item 2): ``normal=`` / ``tangent=`` in eval, pdf, sample and albedo.

References, each independent of bsdfkit's frame code:
* Mitsuba 3 (``llvm_ad_rgb``, float32): ``mi.Frame3f(n)`` (and ``Frame3f(s, t, n)`` for a given
  tangent) takes the world directions to Mitsuba's local frame, where Mitsuba's BSDF is
  evaluated; bsdfkit evaluates the same world directions with ``normal=`` (float64). This checks
  that the default frame is Mitsuba's (and pbrt-v4's) Duff et al. 2017 basis.
* Plain numpy rotations written here (a random orthonormal frame from a QR decomposition, given
  as ``tangent=``), around the local calls.
"""
import dask.array as da
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.testing import mitsuba as ref
from conftest import random_dirs


# --------------------------------------------------------------------------- helpers

def _rot_frames(rng, n):
    """n random right-handed orthonormal frames (s, t, nrm) as rows, from numpy's QR (independent
    of bsdfkit's frame code)."""
    q, r = np.linalg.qr(rng.normal(size=(n, 3, 3)))
    q = q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 2] *= -1
    return q[:, :, 0], q[:, :, 1], q[:, :, 2]


def _local(w, s, t, n):
    return np.stack([np.sum(w * s, -1), np.sum(w * t, -1), np.sum(w * n, -1)], -1)


def _world(v, s, t, n):
    return v[..., :1] * s + v[..., 1:2] * t + v[..., 2:] * n


def _unit32(v):
    """v rounded to float32 and renormalised in float32: the inputs both libraries see."""
    v = v.astype(np.float32)
    return (v / np.linalg.norm(v, axis=-1, keepdims=True)).astype(np.float32)


def _mi_frame(n32, s32=None):
    """Mitsuba's Frame3f of float32 normals (and tangents), vectorised."""
    import mitsuba as mi
    n = mi.Vector3f(np.ascontiguousarray(n32), flip_axes=True)
    if s32 is None:
        return mi.Frame3f(n)
    import drjit as dr
    s = mi.Vector3f(np.ascontiguousarray(s32), flip_axes=True)
    return mi.Frame3f(s, dr.cross(n, s), n)


def _np3(v):
    a = np.array(v.numpy(), dtype=np.float64)
    return a.T if a.shape[0] == 3 else a


def _rel_err(a, b, scale):
    """|a - b| / |b| with a floor of 1e-5 of the values' typical magnitude (as test_mitsuba.py:
    values far below the lobe's scale carry no float32 digits)."""
    return np.abs(a - b) / np.maximum(np.abs(b), 1e-5 * scale)


def _scale(theirs):
    pos = theirs[theirs > 0]
    return np.quantile(pos, 0.99) if pos.size else 1.0


def _p999(ours, theirs, cond=None):
    err = _rel_err(ours, theirs, _scale(theirs))
    if cond is not None:   # subtract what float32 rounding of the inputs alone explains
        err = np.maximum(0.0, err - 4 * cond.reshape(cond.shape + (1,) * (err.ndim - 1)))
    return float(np.quantile(err, 0.999))


def _conditioning(fn, args, rng, scale):
    """Relative change of our float64 value when the unit-vector inputs move by ~1 float32 ulp:
    the part of a float32 library's error no implementation avoids (Mitsuba rotates the
    directions into its frame in float32; bsdfkit in float64). As test_mitsuba.py."""
    base = fn(*args)
    worst = np.zeros(len(args[0]))
    for _ in range(2):
        moved = []
        for a in args:
            b = a * (1 + rng.normal(size=a.shape) * 6e-8)
            moved.append(b / np.linalg.norm(b, axis=1, keepdims=True))
        worst = np.maximum(worst, _rel_err(fn(*moved), base, scale).reshape(len(base), -1).max(1))
    return worst


# --------------------------------------------------------------------------- Mitsuba 3

def _normals(rng, n):
    """Random unit normals plus the awkward ones: the axes, n.z near -1 (Duff's branch), n.z = 0."""
    special = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0.6, 0.8, 0], [0.6, -0.8, 0],
                        [1e-4, 0, -np.sqrt(1 - 1e-8)], [0, 1e-3, -np.sqrt(1 - 1e-6)]], float)
    return _unit32(np.concatenate([special, random_dirs(rng, n - len(special))]))


def test_default_frame_is_mitsubas(rng):
    ref.variant()
    from bsdfkit.models._frames import frame
    n32 = _normals(rng, 20000)
    fr = _mi_frame(n32)
    s, t, n = (x.T for x in frame(n32.astype(np.float64)))   # frame() gives component planes (3, N)
    err = max(np.abs(s - _np3(fr.s)).max(), np.abs(t - _np3(fr.t)).max())
    print(f"default frame vs mi.Frame3f(n): max |diff| {err:.3g} (Mitsuba float32)")
    assert err < 1e-6
    # the frames documented in BxDF.eval: the identity for +z, (x, -y, -z) for -z
    for z, (es, et) in ((1.0, ([1, 0, 0], [0, 1, 0])), (-1.0, ([1, 0, 0], [0, -1, 0]))):
        s, t, n = frame(np.array([0.0, 0.0, z]))
        assert np.array_equal(s, es) and np.array_equal(t, et) and np.array_equal(n, [0, 0, z])


MI_MODELS = [bk.Diffuse(0.5), bk.Diffuse([0.9, 0.2, 0.1]),
             bk.Conductor.from_metal("Cu", alpha=0.3, masking="separable"),
             bk.Conductor.from_reflectance([0.9, 0.6, 0.3], alpha=0.15, masking="separable"),
             bk.Conductor([0.2, 0.9, 1.1], [3.9, 2.4, 2.1], alpha_x=0.4, alpha_y=0.08, masking="separable"),
             bk.Conductor.from_metal("Au", alpha_x=0.05, alpha_y=0.5, masking="separable")]


@pytest.mark.parametrize("model", MI_MODELS, ids=repr)
@pytest.mark.parametrize("with_tangent", [False, True], ids=["default", "tangent"])
def test_world_eval_pdf_against_mitsuba(model, with_tangent, rng):
    ref.variant()
    N = 12000
    n32 = _normals(rng, N)
    s32 = None
    if with_tangent:   # a random tangent perpendicular to the normal (float32-rounded, within 1e-6)
        s32 = _unit32(np.cross(n32.astype(np.float64), random_dirs(rng, N)))
    # world wo on both sides of the surface, down to grazing; wi half uniform, half from the lobe
    wo = random_dirs(rng, N)
    wo -= n32 * (np.sum(wo * n32, 1) * 0.999 * (rng.random(N) < 0.3))[:, None]   # a third near grazing
    wo = _unit32(wo)
    wi = random_dirs(rng, N)
    smp = model.sample(wo[: N // 2].astype(np.float64), rng.random(N // 2), rng.random((N // 2, 2)),
                       normal=n32[: N // 2].astype(np.float64),
                       tangent=None if s32 is None else s32[: N // 2].astype(np.float64))
    wi[: N // 2] = np.where(smp.valid[:, None], smp.wi, wi[: N // 2])
    wi = _unit32(wi)
    # Mitsuba: its frame takes the world directions to its local frame, its BSDF runs there
    fr = _mi_frame(n32, s32)
    import mitsuba as mi
    wo_l = _np3(fr.to_local(mi.Vector3f(np.ascontiguousarray(wo), flip_axes=True)))
    wi_l = _np3(fr.to_local(mi.Vector3f(np.ascontiguousarray(wi), flip_axes=True)))
    f_mi, p_mi = ref.eval_pdf(model, wo_l, wi_l)
    args = [wo.astype(np.float64), wi.astype(np.float64), n32.astype(np.float64)]
    if s32 is not None:
        args.append(s32.astype(np.float64))

    def ours(op):
        return lambda wo, wi, n, s=None: getattr(model, op)(wo, wi, normal=n, tangent=s)
    f, p = ours("eval")(*args), ours("pdf")(*args)
    ef, ep = _p999(f, f_mi), _p999(p, p_mi)
    cf = _conditioning(ours("eval"), args, rng, _scale(f_mi))
    cp = _conditioning(ours("pdf"), args, rng, _scale(p_mi))
    ef_c, ep_c = _p999(f, f_mi, cf), _p999(p, p_mi, cp)
    # the same BSDF comparison without frames: ours at Mitsuba's (float32) local directions
    el = _p999(model.eval(wo_l, wi_l), f_mi)
    print(f"{model!r} {'tangent' if with_tangent else 'default frame'}: p99.9 rel err f {ef:.3g} (after the "
          f"float32 conditioning {ef_c:.3g}), pdf {ep:.3g} ({ep_c:.3g}); local f at Mitsuba's local directions "
          f"{el:.3g}")
    assert ef_c <= 1e-5 and ep_c <= 1e-5
    assert ef <= 4e-5 and ep <= 4e-5   # raw, float32 rounding of a narrow (alpha 0.05) lobe included
    assert (f_mi > 0).mean() > 0.3


# --------------------------------------------------------------------------- local identities

LOCAL_MODELS = [bk.Diffuse([0.7, 0.5, 0.3]),
                bk.Conductor.from_metal("Cu", alpha_x=0.35, alpha_y=0.1),
                bk.Dielectric(1.5, alpha=0.3),
                bk.Dielectric(1.5),
                bk.Mix(bk.Diffuse(0.8), bk.Conductor.from_metal("Au", alpha=0.2), 0.3),
                bk.TwoSided(bk.Conductor.from_metal("Al", alpha=0.3), bk.Diffuse(0.4)),
                bk.Mask(bk.Diffuse(0.6), 0.7),
                bk.NormalMap(bk.Conductor.from_metal("Ag", alpha_x=0.3, alpha_y=0.1), [0.3, -0.2, np.sqrt(0.87)])]


def _pairs(rng, n, dtype=np.float64):
    return random_dirs(rng, n, dtype=dtype), random_dirs(rng, n, dtype=dtype)


@pytest.mark.parametrize("model", LOCAL_MODELS, ids=repr)
@pytest.mark.parametrize("dtype", [np.float32, np.float64], ids=["f32", "f64"])
def test_normal_z_is_the_local_call_bit_for_bit(model, dtype, rng):
    wo, wi = _pairs(rng, 500, dtype)
    z = np.array([0.0, 0.0, 1.0])
    assert np.array_equal(model.eval(wo, wi, normal=z), model.eval(wo, wi))
    assert np.array_equal(model.pdf(wo, wi, normal=z), model.pdf(wo, wi))
    uc, u = rng.random(500).astype(dtype), rng.random((500, 2)).astype(dtype)
    a, b = model.sample(wo, uc, u, normal=z), model.sample(wo, uc, u)
    for k in ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k
        assert getattr(a, k).dtype == getattr(b, k).dtype, k
    assert np.array_equal(a.weight, b.weight)
    assert np.array_equal(model.albedo(wo[:8], 256, normal=z), model.albedo(wo[:8], 256))
    # n = -z: Duff's frame is (x, -y, -z), exactly
    m = np.array([1.0, -1.0, -1.0], dtype)
    assert np.array_equal(model.eval(wo, wi, normal=-z), model.eval(wo * m, wi * m))


@pytest.mark.parametrize("model", LOCAL_MODELS, ids=repr)
def test_world_calls_equal_rotated_local_calls(model, rng):
    """With a tangent, a world call is the local call on directions rotated by the test's own
    numpy frames; sample's wi is the local wi rotated back; pdf at the world wi is sample's pdf."""
    N = 2000
    s, t, n = _rot_frames(rng, N)
    wo, wi = _pairs(rng, N)
    lo, li = _local(wo, s, t, n), _local(wi, s, t, n)
    kw = dict(normal=n, tangent=s)
    np.testing.assert_allclose(model.eval(wo, wi, **kw), model.eval(lo, li), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(model.pdf(wo, wi, **kw), model.pdf(lo, li), rtol=1e-9, atol=1e-12)
    uc, u = rng.random(N), rng.random((N, 2))
    a, b = model.sample(wo, uc, u, **kw), model.sample(lo, uc, u)
    # float64 rounding of the rotation can move a sample across a lobe boundary: compare where
    # both calls took the same branch
    same = (a.flags == b.flags) & (a.valid == b.valid)
    assert same.mean() > 0.999
    np.testing.assert_allclose(a.wi[same], _world(b.wi, s, t, n)[same], atol=1e-12)
    np.testing.assert_allclose(a.f[same], b.f[same], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(a.pdf[same], b.pdf[same], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(a.weight[same], b.weight[same], rtol=1e-8, atol=1e-12)
    assert np.array_equal(a.eta[same], b.eta[same])
    assert np.allclose(np.linalg.norm(a.wi, axis=1), 1, atol=1e-12)
    # invalid samples: wi is the shading normal (local (0, 0, 1))
    np.testing.assert_allclose(a.wi[~a.valid], n[~a.valid], rtol=0, atol=1e-15)
    # pdf of the world-space sample, evaluated with the same frame, is sample's pdf
    ok = a.valid & ((a.flags & int(bk.BxDFFlags.Specular)) == 0) & ~a.pdf_is_proportional
    if ok.any():
        np.testing.assert_allclose(model.pdf(wo[ok], a.wi[ok], normal=n[ok], tangent=s[ok]), a.pdf[ok], rtol=1e-7)
    alb_w = model.albedo(wo[:6], 512, seed=3, **{k: v[:6] for k, v in kw.items()})
    np.testing.assert_allclose(alb_w, model.albedo(lo[:6], 512, seed=3), rtol=1e-9, atol=1e-12)


def test_default_frame_sample_against_mitsubas_frame(rng):
    """sample(normal=n) returns the local sample rotated by Mitsuba's Frame3f(n)."""
    ref.variant()
    import mitsuba as mi
    N = 3000
    m = bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.1)
    n32 = _normals(rng, N)
    fr = _mi_frame(n32)
    s, t, n = _np3(fr.s), _np3(fr.t), n32.astype(np.float64)
    wo = random_dirs(rng, N)
    lo = _np3(fr.to_local(mi.Vector3f(np.ascontiguousarray(wo, dtype=np.float32), flip_axes=True)))
    wo = wo.astype(np.float32).astype(np.float64)
    uc, u = rng.random(N), rng.random((N, 2))
    a, b = m.sample(wo, uc, u, normal=n), m.sample(lo / np.linalg.norm(lo, axis=1, keepdims=True), uc, u)
    ok = a.valid & b.valid
    assert ok.mean() > 0.5
    err = np.abs(a.wi[ok] - _world(b.wi, s, t, n)[ok]).max()
    print(f"sample(normal=n).wi vs Mitsuba-frame rotation of the local sample: max |diff| {err:.3g}")
    assert err < 1e-5


# --------------------------------------------------------------------------- dtype, broadcasting, out

@pytest.mark.parametrize("ndt", [np.float32, np.float64])
def test_float32_directions_stay_float32(ndt, rng):
    m = bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.1)
    wo, wi = _pairs(rng, 64, np.float32)
    s, t, n = _rot_frames(rng, 64)
    n, s = n.astype(ndt), s.astype(ndt)
    for kw in (dict(normal=n), dict(normal=n, tangent=s)):
        assert m.eval(wo, wi, **kw).dtype == np.float32
        assert m.pdf(wo, wi, **kw).dtype == np.float32
        r = m.sample(wo, n=64, seed=1, **kw)
        assert r.wi.dtype == r.f.dtype == r.pdf.dtype == np.float32
        assert m.albedo(wo[:4], 64, **{k: v[:4] for k, v in kw.items()}).dtype == np.float32
        assert m.eval(wo, wi, wavelengths=[400.0, 500, 600, 700], **kw).dtype == np.float32
    # float64 directions with float32 normals: float64 (the normal's dtype chooses nothing)
    assert m.eval(wo.astype(np.float64), wi.astype(np.float64), normal=n.astype(np.float32)).dtype == np.float64
    # float32 results agree with float64 ones to float32 rounding
    f32 = m.eval(wo, wi, normal=n)
    f64 = m.eval(wo.astype(np.float64), wi.astype(np.float64), normal=n.astype(np.float64))
    np.testing.assert_allclose(f32, f64, rtol=2e-4, atol=1e-5)


def test_broadcasting_is_per_element(rng):
    m = bk.Conductor.from_metal("Au", alpha_x=0.4, alpha_y=0.15)
    wo = random_dirs(rng, 1)[0]                     # (3,)
    wi = random_dirs(rng, 20).reshape(4, 5, 3)      # (4, 5, 3)
    s, t, n = _rot_frames(rng, 5)                   # (5, 3)
    f = m.eval(wo, wi, normal=n, tangent=s)
    p = m.pdf(wo, wi, normal=n)
    assert f.shape == (4, 5, 3) and p.shape == (4, 5)
    for i in range(4):
        for j in range(5):
            assert np.array_equal(f[i, j], m.eval(wo, wi[i, j], normal=n[j], tangent=s[j]))
            assert np.array_equal(p[i, j], m.pdf(wo, wi[i, j], normal=n[j]))
    # one normal for many directions, and sample's n= batch
    r = m.sample(wo, n=7, seed=2, normal=n[0])
    assert r.wi.shape == (7, 3)
    assert m.albedo(wo, 128, normal=n).shape == (5, 3)


def test_out_arrays(rng):
    m = bk.Dielectric(1.5, alpha=0.3)
    wo, wi = _pairs(rng, 50)
    s, t, n = _rot_frames(rng, 50)
    out = np.empty((50, 3))
    assert m.eval(wo, wi, out=out, normal=n) is out
    assert np.array_equal(out, m.eval(wo, wi, normal=n))
    uc, u = rng.random(50), rng.random((50, 2))
    ref_w = m.sample(wo, uc, u, normal=n, tangent=s)
    res = m.sample(wo, uc, u)
    assert m.sample(wo, uc, u, out=res, normal=n, tangent=s) is res
    assert np.array_equal(res.wi, ref_w.wi) and np.array_equal(res.weight, ref_w.weight)
    # the same out reused by a local call: its weight is the local one again
    m.sample(_local(wo, s, t, n), uc, u, out=res)
    np.testing.assert_allclose(res.weight, ref_w.weight, rtol=1e-8, atol=1e-12)
    assert np.array_equal(res.weight, m.sample(_local(wo, s, t, n), uc, u).weight)


def test_spectral_and_dask(rng):
    m = bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.1)
    wo, wi = _pairs(rng, 400)
    s, t, n = _rot_frames(rng, 400)
    lam = np.array([420.0, 510.0, 600.0, 700.0])
    lo, li = _local(wo, s, t, n), _local(wi, s, t, n)
    np.testing.assert_allclose(m.eval(wo, wi, wavelengths=lam, normal=n, tangent=s), m.eval(lo, li, wavelengths=lam),
                               rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(m.pdf(wo, wi, wavelengths=lam, normal=n, tangent=s), m.pdf(lo, li, wavelengths=lam),
                               rtol=1e-9, atol=1e-12)
    sw = m.sample(wo, n=400, seed=4, wavelengths=lam, normal=n, tangent=s)
    sl = m.sample(lo, n=400, seed=4, wavelengths=lam)
    ok = sw.valid & sl.valid
    np.testing.assert_allclose(sw.wi[ok], _world(sl.wi, s, t, n)[ok], atol=1e-12)
    assert sw.terminated is not None
    mix = bk.Mix(bk.Diffuse(0.8), m, 0.4)
    np.testing.assert_allclose(mix.eval(wo, wi, wavelengths=lam, normal=n, tangent=s),
                               mix.eval(lo, li, wavelengths=lam), rtol=1e-9, atol=1e-12)
    # Dask: lazy, blockwise, the same values as numpy
    dwo, dn = da.from_array(wo, chunks=(150, 3)), da.from_array(n, chunks=(100, 3))
    f = m.eval(dwo, wi, normal=dn, tangent=s)
    p = m.pdf(wo, da.from_array(wi, chunks=(70, 3)), normal=n)
    assert isinstance(f, da.Array) and isinstance(p, da.Array)
    assert np.array_equal(f.compute(), m.eval(wo, wi, normal=n, tangent=s))
    assert np.array_equal(p.compute(), m.pdf(wo, wi, normal=n))
    assert np.array_equal(mix.eval(dwo, wi, normal=n).compute(), mix.eval(wo, wi, normal=n))


# --------------------------------------------------------------------------- bad input

def _raises(match, fn, *a, **kw):
    with pytest.raises(ValueError, match=match):
        fn(*a, **kw)


def test_bad_normals_and_tangents_name_the_argument_and_index(rng):
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    wo, wi = random_dirs(rng, 12).reshape(3, 4, 3), random_dirs(rng, 12).reshape(3, 4, 3)
    s, t, n = (x.reshape(3, 4, 3) for x in _rot_frames(rng, 12))
    calls = [lambda **k: m.eval(wo, wi, **k), lambda **k: m.pdf(wo, wi, **k),
             lambda **k: m.sample(wo, n=None, uc=0.5, u=[0.3, 0.6], **k), lambda **k: m.albedo(wo, 16, **k),
             lambda **k: bk.Mix(bk.Diffuse(0.5), m).eval(wo, wi, **k)]
    bad = n.copy()
    bad[2, 1] *= 1.01
    nan = n.copy()
    nan[1, 3, 0] = np.nan
    par = s.copy()
    par[0, 2] = n[0, 2]
    oblique = s.copy()
    oblique[1, 0] = (s[1, 0] + 0.01 * n[1, 0]) / np.linalg.norm(s[1, 0] + 0.01 * n[1, 0])
    longt = s.copy()
    longt[2, 3] *= 1.001
    for call in calls:
        _raises(r"normal: .*unit.*index \(2, 1\)", call, normal=bad)
        _raises(r"normal: .*index \(1, 3\)", call, normal=nan)
        _raises(r"normal: .*index \(\)", call, normal=[0.0, 0.0, 0.5])
        _raises(r"tangent: .*perpendicular.*index \(0, 2\)", call, normal=n, tangent=par)
        _raises(r"tangent: .*perpendicular.*index \(1, 0\)", call, normal=n, tangent=oblique)
        _raises(r"tangent: .*unit.*index \(2, 3\)", call, normal=n, tangent=longt)
        _raises(r"tangent: given without normal", call, tangent=s)
        _raises(r"normal.*\(5,\)", call, normal=random_dirs(rng, 5))
        _raises(r"\(3, 4\).*\(2,\)|\(2,\).*\(3, 4\)", call, normal=n, tangent=s[0, :2])
        with pytest.raises((ValueError, TypeError), match="normal"):
            call(normal=np.ones((3, 4, 2)))
    # a non-unit world direction names it
    wo2 = wo.copy()
    wo2[1, 2] *= 1.1
    _raises(r"wo: 1 direction", m.eval, wo2, wi, normal=n)
    _raises(r"wo: 1 direction", m.sample, wo2, n=12, normal=n[0, 0])
    _raises(r"wi: ", m.pdf, wo, wi * 2, normal=n)
    # the shape error names both shapes
    with pytest.raises(ValueError) as e:
        m.eval(wo, wi, normal=random_dirs(rng, 5))
    assert "(3, 4)" in str(e.value) and "(5,)" in str(e.value)


def test_bad_normal_in_a_dask_block_names_its_global_index(rng):
    m = bk.Diffuse(0.5)
    wo, wi = _pairs(rng, 300)
    n = random_dirs(rng, 300)
    n[217] *= 0.9
    f = m.eval(da.from_array(wo, chunks=(100, 3)), wi, normal=da.from_array(n, chunks=(100, 3)))
    with pytest.raises(ValueError, match=r"normal: .*index \(217,\)"):
        f.compute(scheduler="synchronous")


def test_chunking_changes_no_bits(rng, monkeypatch):
    """The rotations run in chunks of elements: a tiny chunk (many boundaries, a ragged last one)
    gives the bits of one chunk, and a bad normal in a later chunk is still found at its index."""
    from bsdfkit.models import _frames
    m = bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.1)
    wo = random_dirs(rng, 6 * 7).reshape(6, 7, 3)
    wi = random_dirs(rng, 7)                      # broadcast over the first axis
    s, t, n = (x.reshape(6, 7, 3) for x in _rot_frames(rng, 42))
    calls = [lambda: m.eval(wo, wi, normal=n), lambda: m.eval(wo, wi, normal=n, tangent=s),
             lambda: m.pdf(wo, wi, normal=n[0, 0]), lambda: m.sample(wo, n=None, uc=0.4, u=[0.2, 0.7], normal=n).wi,
             lambda: m.albedo(wo, 32, normal=n, tangent=s)]
    whole = [c() for c in calls]
    monkeypatch.setattr(_frames, "_CHUNK", 5)
    for c, w in zip(calls, whole):
        assert np.array_equal(c(), w)
    bad = n.copy()
    bad[4, 6] *= 1.1
    _raises(r"normal: .*index \(4, 6\)", m.eval, wo, wi, normal=bad)
    par = s.copy()
    par[5, 2] = n[5, 2]
    _raises(r"tangent: .*perpendicular.*index \(5, 2\)", m.eval, wo, wi, normal=n, tangent=par)
