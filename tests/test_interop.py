"""Scene materials in: bk.from_mitsuba (Mitsuba 3 dicts) and bk.from_pbrt (pbrt-v4 scene text).

Loaded models are checked three ways: by value (== a model built by hand from the documented
mapping), by eval on direction pairs, and -- for Mitsuba dicts and spectra -- against Mitsuba
itself (llvm_ad_rgb, float32, through bsdfkit.testing.mitsuba).
"""
import re

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.interop import MIRROR_ETA, MITSUBA_IOR, PBRT_GLASS_ETA, spectrum_to_rgb
from bsdfkit.testing.mitsuba import to_mitsuba
from conftest import random_dirs

SMOOTH = 1e-3


def _mi():
    from bsdfkit.testing import mitsuba as ref
    ref.variant()
    import mitsuba as mi
    return ref, mi


def _pairs(rng, n=4000, lower_wi=True):
    """wo on the upper hemisphere (z >= 0.05), wi uniform on the sphere (or upper hemisphere)."""
    wo = random_dirs(rng, n, hemisphere=1)
    wo[:, 2] = np.maximum(wo[:, 2], 0.05)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = random_dirs(rng, n, hemisphere=None if lower_wi else 1)
    return wo, wi


def _same_eval(a, b, rng):
    wo, wi = _pairs(rng)
    np.testing.assert_array_equal(a.eval(wo, wi), b.eval(wo, wi))
    np.testing.assert_array_equal(a.pdf(wo, wi), b.pdf(wo, wi))


def _separable(m):
    """The model with masking='separable' (what Mitsuba can express)."""
    return type(m)._from_params(dict(m._params, masking="separable"))


def _is_rough(m):
    return hasattr(m, "alpha_x") and max(m.alpha_x, m.alpha_y) >= SMOOTH


# ============================================================================ from_mitsuba

@pytest.mark.parametrize("m", [
    bk.Conductor([0.3, 0.5, 1.2], [2.0, 3.0, 4.0], alpha_x=0.05, alpha_y=0.6, masking="separable"),
    bk.Dielectric(1 / 1.33, alpha=0.2, masking="separable"),
    bk.Dielectric(2.4),
    bk.ThinDielectric(1.33),
    bk.Diffuse(0.25),
    bk.Conductor.from_reflectance([0.9, 0.5, 0.2]),
], ids=repr)
def test_round_trip_more(m):
    assert bk.from_mitsuba(to_mitsuba(m)) == m


def test_null_is_pass_through():
    assert bk.from_mitsuba({"type": "null"}) == bk.Dielectric(1.0)
    assert bk.from_mitsuba(to_mitsuba(bk.Dielectric(1.0))) == bk.Dielectric(1.0)


def test_mitsuba_value_forms():
    _, mi = _mi()
    rgb = [0.2, 0.9, 1.1]
    want = bk.Conductor(rgb, [3.9, 2.4, 2.1], alpha=0.3, masking="separable")
    for eta in (rgb, np.array(rgb), tuple(rgb), {"type": "rgb", "value": rgb}, mi.ScalarColor3f(*rgb),
                {"type": "srgb", "color": rgb}):
        d = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "eta": eta,
             "k": {"type": "rgb", "value": [3.9, 2.4, 2.1]}, "id": "metal"}
        got = bk.from_mitsuba(d)
        if isinstance(eta, mi.ScalarColor3f):       # float32 storage
            np.testing.assert_allclose(got.eta, rgb, rtol=1e-7)
            got = bk.Conductor(rgb, got.k, alpha_x=got.alpha_x, alpha_y=got.alpha_y, masking=got.masking)
        assert got == want, eta
    grey = bk.Diffuse(0.3)
    for r in (0.3, [0.3], {"type": "rgb", "value": 0.3}, {"type": "spectrum", "value": 0.3},
              {"type": "uniform", "value": 0.3}):
        assert bk.from_mitsuba({"type": "diffuse", "reflectance": r}) == grey, r
    assert bk.from_mitsuba({"type": "diffuse"}) == bk.Diffuse(0.5)          # Mitsuba's default
    # twosided unwraps; two identical nested BSDFs are accepted too.
    inner = {"type": "diffuse", "reflectance": 0.3}
    assert bk.from_mitsuba({"type": "twosided", "front": inner, "back": dict(inner)}) == grey


def test_mitsuba_ior_names():
    """Named IORs use Mitsuba's table (ior.h; Hecht), eta = int_ior / ext_ior, case-insensitive."""
    assert MITSUBA_IOR["bk7"] == 1.5046 and MITSUBA_IOR["air"] == 1.000277
    assert MITSUBA_IOR["water"] == 1.3330 and MITSUBA_IOR["diamond"] == 2.419
    assert MITSUBA_IOR["acrylic glass"] == 1.49 and MITSUBA_IOR["vacuum"] == 1.0
    m = bk.from_mitsuba({"type": "dielectric"})                          # defaults: bk7 in air
    assert m == bk.Dielectric(1.5046 / 1.000277)
    m = bk.from_mitsuba({"type": "thindielectric", "int_ior": "Water", "ext_ior": "vacuum"})
    assert m == bk.ThinDielectric(1.333)
    m = bk.from_mitsuba({"type": "roughdielectric", "distribution": "ggx", "alpha_u": 0.2, "alpha_v": 0.1,
                         "int_ior": "acrylic glass", "ext_ior": "water"})
    assert m == bk.Dielectric(1.49 / 1.333, alpha_x=0.2, alpha_y=0.1, masking="separable")
    assert bk.from_mitsuba({"type": "dielectric", "int_ior": "diamond", "ext_ior": 1.0}) == bk.Dielectric(2.419)


def test_mitsuba_presets_and_mirror():
    ref, mi = _mi()
    for name in bk.METALS:
        d = {"type": "twosided", "bsdf": {"type": "roughconductor", "distribution": "ggx", "material": name,
                                          "alpha": 0.2}}
        m = bk.from_mitsuba(d)
        assert m == bk.Conductor.from_metal(name, alpha=0.2, masking="separable")
        # The METALS table is what Mitsuba loads for the preset.
        p = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
        # (METALS keeps 6 significant digits)
        np.testing.assert_allclose(m.eta, np.array(p["eta.value"]).reshape(-1), rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(m.k, np.array(p["k.value"]).reshape(-1), rtol=1e-6, atol=1e-6)
    # material="none" (the default): eta = 0, k = 1, a perfect mirror.
    mirror = bk.from_mitsuba({"type": "conductor"})
    assert mirror == bk.Conductor(MIRROR_ETA, 1.0)
    assert bk.from_mitsuba({"type": "conductor", "material": "none", "eta": 0.0, "k": 1.0}) == mirror
    wo = bk.direction(np.radians([0.0, 30.0, 60.0, 85.0, 89.0]), 0.3)
    s = mirror.sample(wo, np.full(5, 0.5), np.full((5, 2), 0.5))
    ms = ref.sample({"type": "conductor"}, wo, np.full(5, 0.5), np.full((5, 2), 0.5))
    np.testing.assert_allclose(ms["weight"], 1.0, atol=1e-6)
    np.testing.assert_allclose(s.weight, 1.0, atol=3e-6)


# Dicts as a scene would write them (presets, named IORs, spectra, one-sided plugins).
MITSUBA_DICTS = {
    "twosided_rough_Au": {"type": "twosided", "bsdf": {"type": "roughconductor", "distribution": "ggx",
                                                       "material": "Au", "alpha": 0.2}},
    "aniso_rgb_onesided": {"type": "roughconductor", "distribution": "GGX", "alpha_u": 0.4, "alpha_v": 0.08,
                           "eta": {"type": "rgb", "value": [0.2, 0.9, 1.1]}, "k": 2.5},
    "spectral_eta": {"type": "twosided", "bsdf": {"type": "roughconductor", "distribution": "ggx", "alpha": 0.5,
                                                  "eta": {"type": "spectrum",
                                                          "value": [(380, 0.3), (550, 0.9), (780, 1.6)]},
                                                  "k": 3.0}},
    "rough_bk7": {"type": "roughdielectric", "distribution": "ggx", "int_ior": "bk7", "ext_ior": "air",
                  "alpha_u": 0.3, "alpha_v": 0.1},
    "rough_water_in_acrylic": {"type": "roughdielectric", "distribution": "ggx", "int_ior": "water",
                               "ext_ior": "acrylic glass", "alpha": 0.25, "sample_visible": True},
    "diffuse_spectrum": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": [
        (400, 0.1), (500, 0.6), (600, 0.8), (700, 0.3)]}},
}


@pytest.mark.parametrize("key", sorted(MITSUBA_DICTS))
def test_mitsuba_eval_agreement(key, rng):
    """Our eval/pdf of the loaded model vs Mitsuba's eval/pdf of the same dict.

    Measured (p99.9 / max relative error, floor 1e-4 of the lobe's p99 value): conductors and
    diffuse ~1e-6 / 1.3e-6; rough dielectrics ~2e-5 / 1.2e-4 (float32 near TIR and grazing
    transmission). pdfs: <= 6e-5."""
    ref, _ = _mi()
    d = MITSUBA_DICTS[key]
    m = bk.from_mitsuba(d)
    n = 12_000
    wo, wi = _pairs(rng, n)
    s = m.sample(wo, rng.random(n), rng.random((n, 2)))
    wi[: n // 2] = np.where(s.valid[: n // 2, None], s.wi[: n // 2], wi[: n // 2])
    wo = wo.astype(np.float32).astype(np.float64)
    wi = wi.astype(np.float32).astype(np.float64)
    f, pdf = m.eval(wo, wi), m.pdf(wo, wi)
    fm, pm = ref.eval_pdf(d, wo, wi)
    assert np.any(fm > 0)
    for ours, theirs, what in ((f, fm, "f"), (pdf, pm, "pdf")):
        scale = np.quantile(theirs[theirs > 0], 0.99)
        err = np.abs(ours - theirs) / np.maximum(np.abs(theirs), 1e-4 * scale)
        assert np.quantile(err, 0.999) < 5e-5, (what, np.quantile(err, 0.999))
        assert err.max() < 5e-4, (what, err.max())


def test_spectrum_projection_matches_mitsuba():
    """spectrum_to_rgb == what Mitsuba's llvm_ad_rgb variant loads for {"type": "spectrum", "value":
    pairs} (D65-weighted, clamped at 0 for eta, clipped to [0, 1] for reflectance), and
    mi.spectrum_list_to_srgb without D65. The CIE tables come from colour-science (equal to
    Mitsuba's to 5e-12 in RGB). Measured (relative to max(1, value)): <= 8.5e-8 (dict path),
    5.5e-8 (reflectance), 2.9e-6 (no D65: Mitsuba's float32 sum)."""
    _, mi = _mi()
    rng = np.random.default_rng(3)
    for _ in range(25):
        lam = np.unique(np.sort(rng.uniform(rng.uniform(300, 500), rng.uniform(600, 900), rng.integers(2, 40))))
        val = rng.uniform(0, 4, len(lam))
        pairs = [(float(a), float(b)) for a, b in zip(lam, val)]
        p = mi.traverse(mi.load_dict({"type": "conductor", "eta": {"type": "spectrum", "value": pairs}, "k": 1.0}))
        theirs = np.array(p["eta.value"]).reshape(-1)
        np.testing.assert_allclose(spectrum_to_rgb(lam, val), theirs, atol=1e-5 * max(1, theirs.max()))
        refl = [(a, b / 4) for a, b in pairs]
        p = mi.traverse(mi.load_dict({"type": "diffuse", "reflectance": {"type": "spectrum", "value": refl}}))
        np.testing.assert_allclose(spectrum_to_rgb(lam, val / 4, bounded=True),
                                   np.array(p["reflectance.value"]).reshape(-1), atol=1e-5)
        nod65 = np.array(mi.spectrum_list_to_srgb(lam.tolist(), val.tolist(), False, False)).reshape(-1)
        np.testing.assert_allclose(spectrum_to_rgb(lam, val, d65=False), nod65, atol=1e-5 * max(1, nod65.max()))
    # A constant spectrum is grey with D65 weighting (as Mitsuba does for reflectances).
    np.testing.assert_allclose(spectrum_to_rgb([360, 830], [0.5, 0.5]), 0.5, atol=2e-3)


def test_mitsuba_spectrum_dict_loads_same_rgb():
    pairs = [(400, 0.2), (500, 0.9), (600, 1.1), (700, 1.3)]
    m = bk.from_mitsuba({"type": "conductor", "eta": {"type": "spectrum", "value": pairs}, "k": 2.0})
    lam, val = np.array(pairs).T
    assert m == bk.Conductor(spectrum_to_rgb(lam, val), 2.0)


@pytest.mark.parametrize("d, words", [
    ({"type": "pplastic"}, ["'pplastic'", "unsupported plugin", "diffuse", "roughconductor", "thindielectric"]),
    ({"type": "roughconductor", "distribution": "phong", "alpha": 0.2}, ["roughconductor", "'phong'", "beckmann", "ggx"]),
    ({"type": "roughplastic", "alpha": 0.2}, ["roughplastic", "no 'distribution'", "beckmann", "Plastic", "'ggx'"]),
    ({"type": "roughplastic", "distribution": "beckmann", "alpha": 0.1}, ["roughplastic", "beckmann", "Plastic"]),
    ({"type": "diffuse", "reflectance": {"type": "mesh_attribute", "name": "vertex_color"}},
     ["diffuse", "'reflectance'", "texture", "'mesh_attribute'"]),
    ({"type": "roughconductor", "distribution": "ggx", "alpha": {"type": "mesh_attribute", "name": "r"}},
     ["'alpha'", "texture"]),
    ({"type": "conductor", "material": "Cu", "specular_reflectance": 0.5}, ["'specular_reflectance'", "1"]),
    ({"type": "dielectric", "specular_transmittance": {"type": "rgb", "value": [1, 0.5, 1]}},
     ["'specular_transmittance'"]),
    ({"type": "conductor", "material": "W"}, ["'W'", "Cu", "Au", "Ag", "Al", "Cr", "none"]),
    ({"type": "conductor", "material": "Au", "eta": 1.0}, ["either", "material"]),
    ({"type": "dielectric", "int_ior": "glass"}, ["'int_ior'", "'glass'", "bk7", "water"]),
    ({"type": "dielectric", "int_ior": 1.5, "foo": 1}, ["['foo']", "int_ior", "ext_ior"]),
    ({"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.1}, ["alpha_u", "alpha_v"]),
    ({"type": "twosided", "bsdf": {"type": "dielectric"}}, ["twosided", "'dielectric'"]),
    ({"type": "twosided", "a": {"type": "diffuse"}, "b": {"type": "diffuse"}, "c": {"type": "diffuse"}},
     ["at most two"]),
    ({"type": "twosided", "bsdf": {"type": "roughplastic", "distribution": "beckmann"}},
     ["twosided", "roughplastic", "beckmann"]),
    ({"type": "diffuse", "reflectance": [0.5, 1.5, 0.2]}, ["diffuse", "reflectance", "<= 1"]),
    ({"type": "diffuse", "reflectance": {"type": "spectrum", "filename": "r.spd"}}, ["spectrum files"]),
])
def test_mitsuba_errors(d, words):
    with pytest.raises(ValueError) as e:
        bk.from_mitsuba(d)
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_mitsuba_type_error():
    with pytest.raises(TypeError, match="dict"):
        bk.from_mitsuba("diffuse")


# ============================================================================ from_pbrt

def _one(text):
    ms = bk.from_pbrt(text)
    assert len(ms) == 1, ms
    return next(iter(ms.values()))


def _check(text, expected, rng):
    got = _one(text)
    assert got == expected, (got, expected)
    _same_eval(got, expected, rng)
    return got


def _pbrt_metal(name):
    """pbrt-v4's named metal: eta and k from the one table of Spectrum.named, projected as
    Conductor projects a spectral eta / k. Equal to Mitsuba's preset (METALS, checked against
    Mitsuba in test_mitsuba) to its 6 digits: pbrt and Mitsuba ship the same measured data."""
    out = tuple(np.asarray(bk.Spectrum.named(f"metal-{name}-{part}").to_rgb("unbounded", illuminant=None))
                for part in ("eta", "k"))
    if name in bk.METALS:
        np.testing.assert_allclose(out, bk.METALS[name], rtol=5e-6)
    return out


def test_pbrt_named_metals(rng):
    eta, k = _pbrt_metal("Au")
    _check('Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k" "float roughness" 0.09',
           bk.Conductor(eta, k, alpha=0.3, masking="correlated"), rng)
    # pbrt's default conductor is copper, smooth.
    eta, k = _pbrt_metal("Cu")
    _check('Material "conductor"', bk.Conductor(eta, k), rng)
    # eta and k are independent parameters (here: Ag's eta with an rgb k).
    _check('Material "conductor" "spectrum eta" "metal-Ag-eta" "rgb k" [4 3 2]',
           bk.Conductor(_pbrt_metal("Ag")[0], [4, 3, 2]), rng)


def test_pbrt_rgb_and_float(rng):
    _check('Material "conductor" "rgb eta" [0.2 0.9 1.1] "rgb k" [3.9 2.4 2.1] "float roughness" 0.25',
           bk.Conductor([0.2, 0.9, 1.1], [3.9, 2.4, 2.1], alpha=0.5), rng)
    _check('Material "conductor" "float eta" 1.2 "float k" 3', bk.Conductor(1.2, 3.0), rng)
    _check('Material "diffuse" "rgb reflectance" [0.8 0.5 0.2]', bk.Diffuse([0.8, 0.5, 0.2]), rng)
    _check('Material "diffuse" "color reflectance" [0.8 0.5 0.2]', bk.Diffuse([0.8, 0.5, 0.2]), rng)  # pbrt-v3
    _check('Material "diffuse" "float reflectance" 0.3', bk.Diffuse(0.3), rng)
    _check('Material "diffuse"', bk.Diffuse(0.5), rng)
    _check('Material "dielectric" "float eta" 1.33', bk.Dielectric(1.33), rng)
    _check('Material "dielectric"', bk.Dielectric(1.5), rng)
    _check('Material "thindielectric" "float eta" 1.7', bk.ThinDielectric(1.7), rng)
    _check('Material "thindielectric"', bk.ThinDielectric(1.5), rng)


def test_pbrt_diffusetransmission(rng):
    _check('Material "diffusetransmission"', bk.DiffuseTransmission(0.25, 0.25), rng)
    # scale multiplies both and pbrt clamps to [0, 1].
    _check('Material "diffusetransmission" "rgb reflectance" [0.3 0.6 0.1] "rgb transmittance" [0.2 0.1 0.4]'
           ' "float scale" 2', bk.DiffuseTransmission([0.6, 1.0, 0.2], [0.4, 0.2, 0.8]), rng)


def test_pbrt_spectrum_pairs(rng):
    """Wavelength/value pairs are projected as Mitsuba's RGB variants project the same spectrum:
    the reference model is built from the RGB Mitsuba itself loads."""
    _, mi = _mi()
    eta_pairs = [(400, 0.25), (450, 0.4), (520, 0.9), (600, 1.0), (700, 1.2)]
    k_pairs = [(380, 3.5), (780, 2.0)]
    refl = [(380, 0.1), (480, 0.2), (560, 0.7), (780, 0.9)]
    text = ('Material "conductor" "spectrum eta" [' + " ".join(f"{a} {b}" for a, b in eta_pairs) + ']\n'
            '  "spectrum k" [ ' + " ".join(f"{a} {b}" for a, b in k_pairs) + ' ] "float roughness" 0.16')
    p = mi.traverse(mi.load_dict({"type": "conductor", "eta": {"type": "spectrum", "value": eta_pairs},
                                  "k": {"type": "spectrum", "value": k_pairs}}))
    want = bk.Conductor(np.array(p["eta.value"]).reshape(-1), np.array(p["k.value"]).reshape(-1), alpha=0.4)
    got = _one(text)
    np.testing.assert_allclose(got.eta, want.eta, rtol=1e-5)
    np.testing.assert_allclose(got.k, want.k, rtol=1e-5)
    wo, wi = _pairs(rng)
    np.testing.assert_allclose(got.eval(wo, wi), want.eval(wo, wi), rtol=1e-4, atol=1e-7)
    p = mi.traverse(mi.load_dict({"type": "diffuse", "reflectance": {"type": "spectrum", "value": refl}}))
    got = _one('Material "diffuse" "spectrum reflectance" [' + " ".join(f"{a} {b}" for a, b in refl) + "]")
    np.testing.assert_allclose(got.reflectance, np.array(p["reflectance.value"]).reshape(-1), rtol=1e-5)


def test_pbrt_dielectric_eta_forms(rng):
    # Named glass: pbrt's BK7 table at 550 nm = interpolation between 542 and 564 nm.
    bk7 = 1.5189334783109 + (550 - 542) / (564 - 542) * (1.5178426478869 - 1.5189334783109)
    assert PBRT_GLASS_ETA["glass-BK7"] == pytest.approx(bk7, abs=1e-12)
    _check('Material "dielectric" "spectrum eta" "glass-BK7"', bk.Dielectric(PBRT_GLASS_ETA["glass-BK7"]), rng)
    _check('Material "thindielectric" "spectrum eta" "glass-F11"', bk.ThinDielectric(PBRT_GLASS_ETA["glass-F11"]),
           rng)
    # Pairs: linear interpolation at 550 nm.
    _check('Material "dielectric" "spectrum eta" [500 1.6 600 1.5]', bk.Dielectric(1.55), rng)
    _check('Material "dielectric" "rgb eta" [1.4 1.4 1.4]', bk.Dielectric(1.4), rng)


def test_pbrt_roughness_remapping(rng):
    for r in (0.0, 0.01, 0.2, 0.7):
        _check(f'Material "conductor" "float roughness" {r}',
               bk.Conductor(*_pbrt_metal("Cu"), alpha=np.sqrt(r)), rng)
        _check(f'Material "conductor" "float roughness" {r} "bool remaproughness" false',
               bk.Conductor(*_pbrt_metal("Cu"), alpha=r), rng)
        _check(f'Material "dielectric" "float roughness" {r} "bool remaproughness" true',
               bk.Dielectric(1.5, alpha=np.sqrt(r)), rng)
    assert _one('Material "dielectric" "float roughness" 0.3') == bk.Dielectric(alpha=bk.roughness_to_alpha(0.3))
    # pbrt-v3 style quoted bools.
    assert _one('Material "dielectric" "float roughness" 0.3 "bool remaproughness" "false"') == \
        bk.Dielectric(alpha=0.3)
    # pbrt-v4's microfacet models are height-correlated.
    assert _one('Material "dielectric" "float roughness" 0.3').masking == "correlated"


def test_pbrt_anisotropy(rng):
    text = 'Material "conductor" "float uroughness" 0.25 "float vroughness" 0.01 "float roughness" 0.5'
    got = _check(text, bk.Conductor(*_pbrt_metal("Cu"), alpha_x=0.5, alpha_y=0.1), rng)
    # uroughness is along local x: the lobe is wider in x than in y.
    wo = bk.direction(np.radians(30), 0.0)
    spec_x = bk.direction(np.radians(30), np.pi)         # mirror direction
    off_x = bk.direction(np.radians(50), np.pi)          # 20 deg off along x
    off_y = bk.direction(np.radians(30), np.pi) + np.array([0, 0.34, 0])
    off_y /= np.linalg.norm(off_y)
    assert got.eval(wo, off_x)[1] > 10 * got.eval(wo, off_y)[1]
    swapped = bk.Conductor(*_pbrt_metal("Cu"), alpha_x=0.1, alpha_y=0.5)
    assert got.eval(wo, off_x)[1] > 10 * swapped.eval(wo, off_x)[1]
    assert got.eval(wo, spec_x)[1] > 0
    # Only one of u/v given: the other falls back to roughness (default 0).
    assert _one('Material "dielectric" "float vroughness" 0.04 "bool remaproughness" false') == \
        bk.Dielectric(alpha_x=0.0, alpha_y=0.04)
    assert _one('Material "dielectric" "float uroughness" 0.09 "float roughness" 0.16') == \
        bk.Dielectric(alpha_x=0.3, alpha_y=0.4)


def test_pbrt_reflectance_form(rng):
    got = _check('Material "conductor" "rgb reflectance" [0.9 0.6 0.3] "float roughness" 0.04',
                 bk.Conductor.from_reflectance([0.9, 0.6, 0.3], alpha=0.2), rng)
    # pbrt's artist form: eta = 1, k = 2 sqrt(r) / sqrt(1 - r), so that F(0) = r.
    np.testing.assert_allclose(got.k, 2 * np.sqrt([0.9, 0.6, 0.3]) / np.sqrt(1 - np.array([0.9, 0.6, 0.3])))
    smooth = _one('Material "conductor" "rgb reflectance" [0.9 0.6 0.3]')
    s = smooth.sample(np.array([0.0, 0.0, 1.0]), 0.5, [0.5, 0.5])
    np.testing.assert_allclose(s.weight, [0.9, 0.6, 0.3], rtol=1e-9)


SCENE = """# A small scene: named and anonymous materials, comments and statements over several lines.
LookAt 0 0 5   0 0 0   0 1 0   # "quoted" [brackets] in a comment
Camera "perspective" "float fov" [ 45 ]
WorldBegin
Texture "checks" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]

MakeNamedMaterial "gold"
    "string type" [ "conductor" ]        # type as a one-element list
    "spectrum eta" "metal-Au-eta"
    "spectrum k" "metal-Au-k"
    "float roughness" [
        0.04  # a comment inside a list
    ]
MakeNamedMaterial "glass" "string type" "dielectric" "float eta" 1.5

AttributeBegin
    Material "diffuse" "rgb reflectance" [ 0.8 0.5
                                           0.2 ]
    Shape "sphere" "float radius" 1
    Shape "sphere" "float radius" 2
    AttributeBegin
        NamedMaterial "glass"
        Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2]
    AttributeEnd
    Shape "disk"
AttributeEnd
NamedMaterial "gold"
Shape "sphere"
Material "thindielectric" "float eta" 1.33
"""


def test_pbrt_scene(rng):
    recs = bk.parse_pbrt_materials(SCENE)
    assert [(r.name, r.type, r.line, r.named, r.shapes) for r in recs] == [
        ("gold", "conductor", 7, True, 1),
        ("glass", "dielectric", 14, True, 1),
        ("material#1 (line 17)", "diffuse", 17, False, 3),
        ("material#2 (line 29)", "thindielectric", 29, False, 0),
    ]
    assert recs[0].params["roughness"].values == (0.04,) and "type" not in recs[0].params
    ms = bk.from_pbrt(SCENE)
    assert list(ms) == ["gold", "glass", "material#1 (line 17)", "material#2 (line 29)"]
    expected = [bk.Conductor(*_pbrt_metal("Au"), alpha=0.2), bk.Dielectric(1.5), bk.Diffuse([0.8, 0.5, 0.2]),
                bk.ThinDielectric(1.33)]
    for got, want in zip(ms.values(), expected):
        assert got == want
        _same_eval(got, want, rng)


def test_pbrt_named_vs_anonymous_same_model():
    a = _one('MakeNamedMaterial "m" "string type" "conductor" "rgb eta" [1 1 1] "rgb k" [2 2 2]')
    b = _one('Material "conductor" "rgb eta" [1 1 1] "rgb k" [2 2 2]')
    assert a == b == bk.Conductor(1.0, 2.0)
    assert list(bk.from_pbrt('MakeNamedMaterial "m" "string type" "diffuse"')) == ["m"]


def test_pbrt_tokens():
    # Escapes in strings, CRLF line ends, numbers in exponent form, tabs.
    text = 'Material\t"diffuse"\r\n  "rgb reflectance" [5e-1 2.5E-1 +0.125]\r\nMakeNamedMaterial "a \\"q\\" b"' \
           ' "string type" "diffuse"'
    recs = bk.parse_pbrt_materials(text)
    assert recs[0].line == 1 and recs[1].line == 3 and recs[1].name == 'a "q" b'
    assert bk.from_pbrt(text)["material#1 (line 1)"] == bk.Diffuse([0.5, 0.25, 0.125])


def test_pbrt_ignored_params():
    # A constant displacement moves a flat element without tilting it: left out, and listed. A
    # normal map is used (tests/test_pbrt_textures.py): a missing image names the path and line.
    rec = bk.parse_pbrt_materials('Material "diffuse" "float displacement" 0.1')[0]
    assert rec.ignored == ("displacement",)
    assert rec.to_bxdf() == bk.Diffuse(0.5)
    rec = bk.parse_pbrt_materials('\nMaterial "diffuse" "string normalmap" "n.png" "float displacement" 0.1')[0]
    with pytest.raises(ValueError, match=r"line 2\): parameter 'normalmap': no image file '.*n\.png'"):
        rec.to_bxdf()


@pytest.mark.parametrize("mtype", ["subsurface", "plastic"])
def test_pbrt_unsupported_types(mtype):
    text = f'WorldBegin\n\nMakeNamedMaterial "thing" "string type" "{mtype}" "float roughness" 0.1'
    with pytest.raises(ValueError) as e:
        bk.from_pbrt(text)
    msg = str(e.value)
    for w in ("'thing'", "line 3", repr(mtype), "diffuse, diffusetransmission, conductor, dielectric, thindielectric, "
              "coateddiffuse, coatedconductor, hair, measured, mix"):
        assert w in msg, (w, msg)
    # The syntax is fine: parse_pbrt_materials lists it, skip_unsupported leaves it out.
    assert bk.parse_pbrt_materials(text)[0].type == mtype
    assert bk.from_pbrt(text + '\nMaterial "diffuse"', skip_unsupported=True) == {"material#1 (line 4)": bk.Diffuse()}


@pytest.mark.parametrize("text, words", [
    ('Material "diffuse" "texture reflectance" "checks"', ["'reflectance'", "texture", "'checks'", "line 1"]),
    ('\nMaterial "conductor" "texture roughness" "r"', ["'roughness'", "texture", "line 2"]),
    ('Material "conductor" "spectrum eta" "metal-Au-k"', ["'k' part"]),
    ('Material "conductor" "spectrum eta" "glass-BK7"', ["dielectric eta"]),
    ('Material "dielectric" "spectrum eta" "glass-XYZ"', ["'glass-XYZ'", "glass-BK7"]),
    ('Material "dielectric" "spectrum eta" [600 1.5 700 1.4]', ["550"]),
    ('Material "conductor" "rgb reflectance" [0.5 0.5 0.5] "rgb eta" [1 1 1]', ["reflectance", "eta", "not both"]),
    ('Material "conductor" "float sharpness" 3', ["'sharpness'", "roughness", "remaproughness"]),
    ('Material "diffuse" "rgb reflectance" [0.5 1.2 0.5]', ["> 1"]),
    ('Material "diffuse" "blackbody reflectance" 3000', ["blackbody"]),
    ('Material "dielectric" "rgb eta" [1.5 1.4 1.3]', ["grey"]),
    ('Material "dielectric" "float roughness" -0.1', ["roughness", ">= 0"]),
    ('Material "diffuse" "spectrum reflectance" [400 0.5 500]', ["pairs", "3 numbers"]),
    ('Material "diffuse" "spectrum reflectance" [500 0.5 400 0.4]', ["increasing"]),
    ('Material "conductor" "bool remaproughness" 1', ["true or false"]),
    ('Material "dielectric" "string type" "conductor"', ["'type'"]),
])
def test_pbrt_conversion_errors(text, words):
    with pytest.raises(ValueError) as e:
        bk.from_pbrt(text)
    for w in words:
        assert w in str(e.value), (w, str(e.value))


@pytest.mark.parametrize("text, words", [
    ('Material "diffuse"\n"rgb reflectance [0.1 0.2 0.3]\n', ["line 2", "unterminated string"]),
    ('Material "diffuse"\n  "rgb reflectance" [0.1 0.2 0.3\n', ["line 2", "unterminated '['"]),
    ('Material "diffuse"\n  "rgb reflectance" [0.1 0.2 0.3\nShape "sphere"', ["line 3", "'Shape'", "line 2"]),
    ('Material "diffuse" "rgb reflectance" [0.1 0.2]', ["line 1", "3 numbers", "got 2"]),
    ('\n\nMaterial "diffuse" "rgb reflectance" [0.1 0.2 0.3 0.4]', ["line 3", "3 numbers", "got 4"]),
    ('Material "diffuse" "rgb reflectance" [0.1 1.2.3 0.3]', ["line 1", "'1.2.3'", "not a number"]),
    ('Material "diffuse" "rgb reflectance" [0.1 abc 0.3]', ["line 1", "'abc'", "expected a value or ']'"]),
    ('Material "diffuse" "rgb reflectance" [0.1 "x" 0.3]', ["line 1", "mixed"]),
    ('Material "diffuse" "reflectance" [0.1 0.2 0.3]', ["line 1", "malformed parameter declaration"]),
    ('Material "diffuse" "rgb reflectance"', ["line 1", "missing value"]),
    ('Material "diffuse" "rgb reflectance" Shape "sphere"', ["line 1", "expected a value", "'Shape'"]),
    ('Material\n', ["line 1", "Material", "quoted string"]),
    ('Material diffuse', ["line 1", "quoted string"]),
    ('\nMakeNamedMaterial "m" "rgb reflectance" [1 1 1]', ["line 2", "'m'", "string type"]),
    ('MakeNamedMaterial "m" "string type" "diffuse"\nMakeNamedMaterial "m" "string type" "diffuse"',
     ["line 2", "redefined", "line 1"]),
    ('Material "diffuse" "rgb reflectance" [0.1 0.2 0.3] "rgb reflectance" [0 0 0]', ["given twice"]),
    ('Shape "sphere" ]\n', ["line 1", "unexpected ']'"]),
    ('Material "diffuse" 0.5', ["line 1", "'0.5'"]),
    ('Material "diffuse" "string name" "a\\qb"', ["line 1", "escaped"]),
])
def test_pbrt_malformed(text, words):
    with pytest.raises(ValueError) as e:
        bk.from_pbrt(text)
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_pbrt_type_error():
    with pytest.raises(TypeError, match="scene text"):
        bk.from_pbrt(b'Material "diffuse"')


def test_exports():
    assert bk.from_mitsuba is bk.interop.from_mitsuba and bk.from_pbrt is bk.interop.from_pbrt
    for name in ("from_mitsuba", "from_pbrt", "parse_pbrt_materials"):
        assert name in bk.__all__
    assert re.search(r"masking=\"?separable", bk.from_mitsuba.__doc__)


def test_from_pbrt_binary_file_names_it(tmp_path):
    p = tmp_path / "scene.pbrt"
    p.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(ValueError, match="not a pbrt-v4 scene file"):
        bk.from_pbrt(p)
