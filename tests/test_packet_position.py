"""The packet path of the batch kernels (batch.h, core/simd.h): models that run on packets give every
element a result that depends on its own inputs only, bit for bit: the same for any array position (an
array shifted by 1..15 elements, so each element sits in every lane and in the padded tail), any chunking
(one-element calls) and any thread count, in float32 and float64, for eval, pdf and sample."""
import numpy as np
import pytest

import bsdfkit as bk
from conftest import random_dirs

# The models on the packet path (`Vectorized = true` in their headers), rough and smooth branches.
PACKET_MODELS = {
    "Diffuse": lambda: bk.Diffuse((0.2, 0.5, 0.8)),
    "Conductor-rough": lambda: bk.Conductor.from_metal("Au", alpha_x=0.3, alpha_y=0.1),
    "Conductor-separable": lambda: bk.Conductor.from_metal("Cu", alpha=0.2, masking="separable"),
    "Conductor-smooth": lambda: bk.Conductor.from_metal("Ag"),
    "ConductorSchlick": lambda: bk.Conductor.from_metal("Cu", alpha=0.25, fresnel="schlick"),
    "ConductorF82": lambda: bk.Conductor.from_metal("Al", alpha=0.4, fresnel="f82"),
    "Dielectric-rough": lambda: bk.Dielectric(1.5, alpha_x=0.3, alpha_y=0.15),
    "Dielectric-inside": lambda: bk.Dielectric(0.7, alpha=0.2),
    "Dielectric-smooth": lambda: bk.Dielectric(1.33),
    "Plastic-smooth": lambda: bk.Plastic((0.2, 0.5, 0.8), eta=1.49),
    "Plastic-rough": lambda: bk.Plastic((0.7, 0.3, 0.1), eta=1.5, alpha=0.3),
    "Plastic-rough-separable-nonlinear": lambda: bk.Plastic(0.6, eta=1.3, alpha=0.1, masking="separable",
                                                            nonlinear=True, specular_reflectance=0.7),
    "FilamentStandard": lambda: bk.FilamentStandard((0.8, 0.5, 0.3)),
    "FilamentStandard-aniso-metal": lambda: bk.FilamentStandard((0.91, 0.92, 0.92), metallic=1, roughness=0.5,
                                                                anisotropy=0.8),
    "FilamentStandard-burley-fast": lambda: bk.FilamentStandard((0.3, 0.6, 0.2), roughness=0.3, diffuse="burley",
                                                                visibility="fast"),
    "FilamentStandardCoat": lambda: bk.FilamentStandard((0.05, 0.2, 0.7), metallic=0.7, clear_coat=1,
                                                        clear_coat_roughness=0.1, clear_coat_layering="doc"),
    "FilamentStandardSheen": lambda: bk.FilamentStandard((0.3, 0.05, 0.1), roughness=0.6,
                                                         sheen_color=(0.9, 0.6, 0.7), sheen_roughness=0.4),
    "FilamentStandardCoatSheen": lambda: bk.FilamentStandard((0.5, 0.5, 0.5), clear_coat=0.5,
                                                             sheen_color=(0.2, 0.3, 0.4), sheen_roughness=0.7),
    "Hair": lambda: bk.Hair(h=0.3),
    "Hair-smooth-red": lambda: bk.Hair((0.1, 0.8, 1.5), beta_m=0.1, beta_n=0.2, h=-0.7, alpha=-3.0),
    "HairFarField": lambda: bk.Hair(h=None, nodes=8),
    "NormalizedFresnel": lambda: bk.NormalizedFresnel(1.33),
    "NormalizedFresnel-inside": lambda: bk.NormalizedFresnel(0.8),
    "CoatedDiffuseAnalytic-rough-medium": lambda: bk.CoatedDiffuse((0.6, 0.35, 0.15), alpha=0.2, albedo=0.8,
                                                                   thickness=0.2, g=0.3, method="analytic"),
    "CoatedDiffuseAnalytic-smooth": lambda: bk.CoatedDiffuse(0.5, eta=1.5, method="analytic"),
    "CoatedConductorAnalytic-rough": lambda: bk.CoatedConductor.from_metal("Cu", conductor_roughness=None,
                                                                           conductor_alpha=0.3, interface_alpha=0.1,
                                                                           albedo=(0.5, 0.1, 0.1), thickness=0.1,
                                                                           method="analytic"),
    "CoatedConductorAnalytic-smooth": lambda: bk.CoatedConductor.from_metal("Au", method="analytic"),
    "ThinDielectric": lambda: bk.ThinDielectric(1.5),
    "ThinDielectric-inside": lambda: bk.ThinDielectric(0.7),  # total internal reflection beyond 44 deg
    "ThinDielectric-index-matched": lambda: bk.ThinDielectric(1.0),
    "DiffuseTransmission": lambda: bk.DiffuseTransmission((0.2, 0.6, 0.3), (0.7, 0.1, 0.5)),
    "DiffuseTransmission-reflect-only": lambda: bk.DiffuseTransmission(0.5, 0.0),
}


def _inputs(rng, n, dtype):
    # both hemispheres, a few exact horizon / pole / non-unit-free edge rows included
    wo, wi = random_dirs(rng, n), random_dirs(rng, n)
    wo[:4] = [[0, 0, 1], [1, 0, 0], [0, 0, -1], [0.6, 0, 0.8]]
    wi[:4] = [[0, 0, 1], [0, 0, 1], [0.6, 0, -0.8], [-0.6, 0, 0.8]]
    uc, u = rng.random(n), rng.random((n, 2))
    u[:2] = [[0, 0], [1, 1]]
    return wo.astype(dtype), wi.astype(dtype), uc.astype(dtype), u.astype(dtype)


def _run(m, wo, wi, uc, u):
    s = m.sample(wo, uc, u)
    return [m.eval(wo, wi), m.pdf(wo, wi), s.wi, s.f, s.pdf, s.eta, s.valid, s.flags]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", sorted(PACKET_MODELS))
def test_position_and_chunking_independent(name, dtype, rng):
    m = PACKET_MODELS[name]()
    n = 16 * 5 + 7
    wo, wi, uc, u = _inputs(rng, n, dtype)
    full = _run(m, wo, wi, uc, u)
    assert np.isfinite(full[0]).all() and np.isfinite(full[1]).all()
    assert full[6].any()  # some valid samples: the comparison is not between zeros
    for k in range(1, 16):
        part = _run(m, wo[k:], wi[k:], uc[k:], u[k:])
        for a, b in zip(full, part):
            np.testing.assert_array_equal(a[k:], b, err_msg=f"{name}: shifted by {k}")
    # one element per call: every element alone in a padded packet
    for i in (0, 1, 2, 3, 17, n - 1):
        one = _run(m, wo[i:i + 1], wi[i:i + 1], uc[i:i + 1], u[i:i + 1])
        for a, b in zip(full, one):
            np.testing.assert_array_equal(a[i:i + 1], b, err_msg=f"{name}: element {i} alone")


@pytest.mark.parametrize("name", sorted(PACKET_MODELS))
def test_thread_count_independent(name, rng):
    m = PACKET_MODELS[name]()
    n = 3 * 8192 + 13  # several chunks and a ragged last chunk
    wo, wi, uc, u = _inputs(rng, n, np.float32)
    res = []
    for t in (1, 2):
        bk.set_num_threads(t)
        res.append(_run(m, wo, wi, uc, u))
    for a, b in zip(*res):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("name", sorted(PACKET_MODELS))
def test_broadcast_direction_matches_rows(name, rng):
    # a single wo broadcast against N wi (the S = 0 load of the packet path) equals the explicit rows
    m = PACKET_MODELS[name]()
    wo = np.array([0.3, -0.2, np.sqrt(1 - 0.13)])
    wi = random_dirs(rng, 37)
    rows = np.ascontiguousarray(np.broadcast_to(wo, wi.shape))
    np.testing.assert_array_equal(m.eval(wo, wi), m.eval(rows, wi))
    np.testing.assert_array_equal(m.pdf(wo, wi), m.pdf(rows, wi))
    uc, u = rng.random(37), rng.random((37, 2))
    np.testing.assert_array_equal(m.sample(wo, uc, u).f, m.sample(rows, uc, u).f)


# Direction layouts: (N, 3) arrays in C order (rows, transposed to packets) and in Fortran order (three
# component planes, read without transposition; bind_model.h / batch.h eval_batch_dirs), mixed with each
# other and with one broadcast direction, and out= in either order: the same values bit for bit.
LAYOUT_MODELS = sorted(PACKET_MODELS) + ["FilamentCloth"]  # + one without packets (the general path)


def _layout_model(name):
    if name == "FilamentCloth":
        return bk.FilamentCloth((0.6, 0.3, 0.2), roughness=0.5)
    return PACKET_MODELS[name]()


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", LAYOUT_MODELS)
def test_planes_layout_bit_identical(name, dtype, rng):
    m = _layout_model(name)
    n = 16 * 4 + 5  # full packets and a padded tail
    wo, wi, _, _ = _inputs(rng, n, dtype)
    f, p = m.eval(wo, wi), m.pdf(wo, wi)
    wo_f, wi_f = np.asfortranarray(wo), np.asfortranarray(wi)
    assert wo_f.flags.f_contiguous and not wo_f.flags.c_contiguous
    for a, b, tag in ((wo_f, wi_f, "planes"), (wo_f, wi, "planes/rows"), (wo, wi_f, "rows/planes"),
                      (np.ascontiguousarray(wi.T).T, wo_f, "(3, N).T")):
        ref_f, ref_p = (f, p) if tag != "(3, N).T" else (m.eval(wi, wo), m.pdf(wi, wo))
        fa, pa = m.eval(a, b), m.pdf(a, b)
        np.testing.assert_array_equal(fa, ref_f, err_msg=f"{name} eval {tag}")
        np.testing.assert_array_equal(pa, ref_p, err_msg=f"{name} pdf {tag}")
        assert fa.dtype == dtype and pa.dtype == dtype
        # numpy's order='K': planes out when every full-length direction input is planes
        both = a.flags.f_contiguous and b.flags.f_contiguous
        assert fa.flags.f_contiguous == both and fa.flags.c_contiguous == (not both), tag
    # every position of the padded tail, through planes
    for k in (1, 7, 15):
        np.testing.assert_array_equal(m.eval(wo_f[k:], wi_f[k:]), f[k:], err_msg=f"{name} planes shifted by {k}")
        np.testing.assert_array_equal(m.pdf(wo_f[k:], wi_f[k:]), p[k:], err_msg=f"{name} planes shifted by {k}")
    # one broadcast direction against planes
    np.testing.assert_array_equal(m.eval(wo[5], wi_f), m.eval(np.broadcast_to(wo[5], wi.shape).copy(), wi))
    np.testing.assert_array_equal(m.pdf(wi_f, wo[5]), m.pdf(wi, np.broadcast_to(wo[5], wi.shape).copy()))
    # out= in either order, with inputs in either order
    for a, b in ((wo, wi), (wo_f, wi_f)):
        for order in "CF":
            out = np.full((n, 3), np.nan, dtype=dtype, order=order)
            r = m.eval(a, b, out=out)
            assert r is out
            np.testing.assert_array_equal(out, f, err_msg=f"{name} out order {order}")
            outp = np.full(n, np.nan, dtype=dtype)
            assert m.pdf(a, b, out=outp) is outp
            np.testing.assert_array_equal(outp, p)


def test_planes_bad_directions_counted_once(rng):
    # the planes path counts non-unit directions like the rows path (and raises naming the argument)
    m = bk.Diffuse(0.5)
    wo, wi = random_dirs(rng, 40), random_dirs(rng, 40)
    wi[[3, 17, 39]] *= 2
    for f in (m.eval, m.pdf):
        with pytest.raises(ValueError, match=r"wi: 3 direction\(s\)"):
            f(np.asfortranarray(wo), np.asfortranarray(wi))
        with pytest.raises(ValueError, match=r"wo: 40 direction\(s\)"):
            f(np.array([0, 0, 2.0]), np.asfortranarray(wi))
