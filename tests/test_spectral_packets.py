"""Spectral mode on packets (issue 15; cpp/include/bsdfkit/batch_spectral.h): the pbrt-core spectral
adapters run kPacketWidth elements at a time with per-lane parameters (core/spectral.h
SpectralParam::lanes). Checked here:

- the packet path against the scalar per-element path (``packets=False`` on the ``_core`` entry, the
  code every adapter had before): eval and pdf bit for bit (the same operations in the same order; the
  build does not contract), samples bit for bit in their discrete outputs (valid, flags, terminated)
  and within 4 ulp-scale tolerances in their values (the rough models' visible-normal and the
  cosine sampling call sincos: Dr.Jit's packet form against libm's, ~1 ulp apart);
- every element's result independent of its array position (shifted by 1..15, so each element sits in
  every lane and in the padded tail), of one-element calls and of the thread count (1, 2, 3);
- the parameters per lane (SpectralParam on packets of float64) equal the scalar values bit for bit,
  including tables with several nodes inside one nm (the lookup's step loop);
- a dispersive glass whose eta reaches 1 stays on the scalar path (same values either way).
"""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models._spectral import _spectral_core
from conftest import random_dirs

# nodes denser than 1 nm around 500 nm (the table lookup steps past nodes inside one nm)
DENSE = bk.Spectrum([360.0, 499.2, 499.5, 499.9, 500.3, 500.35, 501.0, 640.0, 830.0],
                    [0.1, 0.3, 0.9, 0.2, 0.7, 0.05, 0.6, 0.4, 0.8])
RAMP = bk.Spectrum([360.0, 830.0], [0.2, 0.8])

MODELS = {
    "Diffuse-uplift": lambda: bk.Diffuse((0.8, 0.3, 0.1)),
    "Diffuse-table": lambda: bk.Diffuse(DENSE),
    "Diffuse-constant": lambda: bk.Diffuse(bk.Spectrum.constant(0.4)),
    "DiffuseTransmission": lambda: bk.DiffuseTransmission(RAMP, (0.1, 0.6, 0.3)),
    "DiffuseTransmission-reflect-only": lambda: bk.DiffuseTransmission(DENSE, 0.0),
    "Conductor-Au-rough": lambda: bk.Conductor.from_metal("Au", alpha_x=0.3, alpha_y=0.1, spectral=True),
    "Conductor-Cu-smooth": lambda: bk.Conductor.from_metal("Cu", spectral=True),
    "Conductor-Cu-schlick": lambda: bk.Conductor.from_metal("Cu", alpha=0.25, fresnel="schlick", spectral=True),
    "Conductor-Al-f82": lambda: bk.Conductor.from_metal("Al", alpha=0.4, fresnel="f82", spectral=True),
    "Conductor-rgb-uplift": lambda: bk.Conductor.from_metal("Cu", alpha=0.2, masking="separable"),
    "Dielectric-constant-rough": lambda: bk.Dielectric(bk.Spectrum.constant(1.5), alpha=0.3),
    "Dielectric-BK7-rough": lambda: bk.Dielectric(bk.Spectrum.named("glass-BK7"), alpha_x=0.3, alpha_y=0.15),
    "Dielectric-BK7-smooth": lambda: bk.Dielectric(bk.Spectrum.named("glass-BK7")),
    "Dielectric-inside-dispersive": lambda: bk.Dielectric(bk.Spectrum([360.0, 830.0], [0.62, 0.7]), alpha=0.2),
    "ThinDielectric-BK7": lambda: bk.ThinDielectric(bk.Spectrum.named("glass-BK7")),
    "ThinDielectric-constant": lambda: bk.ThinDielectric(1.5),
    "ThinDielectric-index-matched": lambda: bk.ThinDielectric(1.0),
}


def _inputs(rng, n, dtype):
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    wo[:4] = [[0, 0, 1], [1, 0, 0], [0, 0, -1], [0.6, 0, 0.8]]
    wi[:4] = [[0, 0, 1], [0, 0, 1], [0.6, 0, -0.8], [-0.6, 0, 0.8]]
    wi[4:8] = wo[4:8] * [-1, -1, 1]  # mirror pairs: the smooth lobes' directions
    lam = bk.sample_wavelengths(rng.random(n))[0]
    lam[:3] = [[360.0, 830.0, 500.0, 499.5], [830.0, 360.0, 499.9, 500.35], [360.0, 360.0, 830.0, 830.0]]
    uc, u = rng.random(n), rng.random((n, 2))
    u[:2] = [[0, 0], [1, 1]]
    uc[:2] = [0, 1]
    return wo.astype(dtype), wi.astype(dtype), np.ascontiguousarray(lam), uc.astype(dtype), u.astype(dtype)


def _run(core, wo, wi, lam, uc, u, packets=True, mode=0, sf=3):
    n, dt = len(wo), wo.dtype
    f, pdf = np.empty((n, 4), dt), np.empty(n, dt)
    assert not any(core.eval(wo, wi, lam, mode, f, packets=packets))
    assert not any(core.pdf(wo, wi, lam, mode, sf, pdf, packets=packets))
    s = [np.empty((n, 3), dt), np.empty((n, 4), dt), np.empty(n, dt), np.empty(n, np.uint8), np.empty(n, dt),
         np.empty(n, bool), np.empty(n, bool), np.empty(n, bool)]
    assert not any(core.sample(wo, uc, u, lam, mode, sf, *s, packets=packets))
    return {"eval": f, "pdf": pdf, "wi": s[0], "f": s[1], "spdf": s[2], "flags": s[3], "eta": s[4], "valid": s[5],
            "prop": s[6], "terminated": s[7]}


EXACT = ("eval", "pdf", "flags", "valid", "prop", "terminated")


@pytest.mark.parametrize("mode,sf", [(0, 3), (1, 3), (0, 1), (0, 2)])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", sorted(MODELS))
def test_packets_equal_scalar_path(name, dtype, mode, sf, rng):
    core = _spectral_core(MODELS[name]())
    n = 16 * 40 + 9
    wo, wi, lam, uc, u = _inputs(rng, n, dtype)
    pk = _run(core, wo, wi, lam, uc, u, True, mode, sf)
    sc = _run(core, wo, wi, lam, uc, u, False, mode, sf)
    for k in EXACT:
        np.testing.assert_array_equal(pk[k], sc[k], err_msg=f"{name}: {k}")
    # sampled values: the direction comes through sincos (packet vs libm, ~1 ulp); f and pdf follow it
    tol = 4e-5 if dtype == np.float32 else 1e-12
    for k in ("wi", "f", "spdf", "eta"):
        np.testing.assert_allclose(pk[k], sc[k], rtol=tol, atol=tol * 1e-3, err_msg=f"{name}: {k}")
    assert np.isfinite(pk["eval"]).all() and np.isfinite(pk["f"]).all()
    if sf == 3 and name != "ThinDielectric-index-matched":
        assert pk["valid"].mean() > 0.3   # the comparison is not between rejected samples


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", sorted(MODELS))
def test_position_chunking_threads_independent(name, dtype, rng):
    core = _spectral_core(MODELS[name]())
    n = 16 * 3 + 7
    args = _inputs(rng, n, dtype)
    full = _run(core, *args)
    assert full["valid"].any()
    for k in range(1, 16):
        part = _run(core, *(a[k:] for a in args))
        for key in full:
            np.testing.assert_array_equal(full[key][k:], part[key], err_msg=f"{name}: {key} shifted by {k}")
    for i in (0, 1, 5, n - 1):
        one = _run(core, *(a[i:i + 1] for a in args))
        for key in full:
            np.testing.assert_array_equal(full[key][i:i + 1], one[key], err_msg=f"{name}: {key} element {i} alone")
    big = _inputs(rng, 2 * 8192 + 21, dtype)  # several chunks, a ragged last one
    res = []
    for t in (1, 2, 3):
        bk.set_num_threads(t)
        res.append(_run(core, *big))
    for r in res[1:]:
        for key in r:
            np.testing.assert_array_equal(res[0][key], r[key], err_msg=f"{name}: {key} threads")


def test_broadcast_rows_match(rng):
    # one broadcast wo and one broadcast row of wavelengths (stride 0 loads) equal explicit rows
    for name in ("Conductor-Au-rough", "Dielectric-BK7-rough", "DiffuseTransmission"):
        m = MODELS[name]()
        wo = np.array([0.3, -0.2, np.sqrt(1 - 0.13)])
        wi = random_dirs(rng, 37)
        lam = np.array([400.0, 520.5, 610.25, 700.0])
        rows, lrows = np.broadcast_to(wo, wi.shape).copy(), np.broadcast_to(lam, (37, 4)).copy()
        np.testing.assert_array_equal(m.eval(wo, wi, wavelengths=lam), m.eval(rows, wi, wavelengths=lrows))
        np.testing.assert_array_equal(m.pdf(wo, wi, wavelengths=lam), m.pdf(rows, wi, wavelengths=lrows))
        uc, u = rng.random(37), rng.random((37, 2))
        np.testing.assert_array_equal(m.sample(wo, uc, u, wavelengths=lam).f,
                                      m.sample(rows, uc, u, wavelengths=lrows).f)


def test_bad_wavelengths_counted_on_packets(rng):
    # the packet loop counts rows with a bad wavelength as the scalar loop does (padding is valid)
    core = _spectral_core(MODELS["Conductor-Au-rough"]())
    wo, wi, lam, uc, u = _inputs(rng, 37, np.float32)
    lam[[3, 20, 36], 1] = [359.0, np.nan, 831.0]
    out = np.empty((37, 4), np.float32)
    assert core.eval(wo, wi, lam, 0, out)[2] == 3
    assert core.eval(wo, wi, lam, 0, out, packets=False)[2] == 3
    one = np.ascontiguousarray(lam[3:4])  # one broadcast bad row: every element counts
    assert core.eval(wo, wi, one, 0, out)[2] == 37
    with pytest.raises(ValueError, match="wavelengths"):
        bk.Conductor.from_metal("Au", alpha=0.3, spectral=True).eval(wo, wi, wavelengths=lam)


def test_eta_reaching_one_stays_scalar(rng):
    # a dispersive eta crossing 1 cannot run on packets (DielectricBxDF's index-matched switch is per
    # model): the packet entry falls back to the scalar path, so both calls agree exactly
    m = bk.Dielectric(bk.Spectrum([360.0, 830.0], [0.9, 1.1]), alpha=0.2)
    core = _spectral_core(m)
    wo, wi, lam, uc, u = _inputs(rng, 100, np.float64)
    a, b = _run(core, wo, wi, lam, uc, u, True), _run(core, wo, wi, lam, uc, u, False)
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_spectral_param_lanes_equal_scalar():
    # the parameter values the packet path evaluates equal SpectralParam.__call__ (the scalar path):
    # eval of Diffuse with 4 channels at the element's wavelengths is R(lambda) / pi exactly
    lam = np.linspace(360.0, 830.0, 4 * 301).reshape(-1, 4)
    lam[::7] += 0.37
    lam = np.clip(lam, 360, 830)
    wo = np.tile([0.0, 0.0, 1.0], (len(lam), 1))
    for spec in (DENSE, RAMP, (0.8, 0.3, 0.1), (0.0, 0.0, 1.0), bk.Spectrum.constant(0.25)):
        m = bk.Diffuse(spec)
        core = _spectral_core(m)
        f = np.empty((len(lam), 4))
        core.eval(wo, wo, lam, 0, f)
        p = core_param(m)
        np.testing.assert_array_equal(f, p(lam) * 0.31830988618379067154)  # R / pi, InvPi as the C++ literal


def core_param(m):
    """The model's reflectance as the _core.SpectralParam the kernels evaluate."""
    from bsdfkit.models._spectral import spectral_param
    return spectral_param(m._params["reflectance"], "reflectance")
