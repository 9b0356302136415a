"""Scene materials in: Mitsuba 3 plugin dictionaries and pbrt-v4 scene text as bsdfkit models.

* :func:`from_mitsuba` turns a Mitsuba 3 BSDF dictionary (what ``mi.load_dict`` takes) into a
  model; it inverts :func:`bsdfkit.references.mitsuba.to_mitsuba`.
* :func:`from_pbrt` reads the ``Material`` / ``MakeNamedMaterial`` statements of pbrt-v4 scene
  text; :func:`parse_pbrt_materials` gives the parsed statements (type, parameters, line, how
  many shapes use them) without converting them.
* :func:`spectrum_to_rgb` projects a wavelength/value spectrum to linear sRGB the way Mitsuba's
  RGB variants do, so spectra in either format give the RGB values Mitsuba would use.

Only what bsdfkit can represent exactly is accepted; everything else (textures, layered and
measured materials, Beckmann roughness, ``specular_reflectance`` tints ...) is refused with a
``ValueError`` that names the plugin or material, the parameter and what is supported.
"""
from __future__ import annotations

import math
import numbers
import re
from dataclasses import dataclass, field

import numpy as np

from ._models import (METALS, BxDF, Conductor, Dielectric, Diffuse, DiffuseTransmission, ThinDielectric,
                      roughness_to_alpha)

__all__ = ["from_mitsuba", "from_pbrt", "parse_pbrt_materials", "PbrtMaterial", "PbrtParam",
           "spectrum_to_rgb", "MITSUBA_IOR", "PBRT_GLASS_ETA", "MIRROR_ETA"]


# =============================================================================================
# Spectrum -> linear sRGB (Mitsuba 3's RGB-mode projection)
# =============================================================================================

# CIE 1931 2-degree standard observer colour-matching functions x̄, ȳ, z̄ at 5 nm steps from 360 to
# 830 nm (CIE 015:2004 Table T.4; public data, as distributed by CVRL, cvrl.org "ciexyz31"). These
# are the values of Mitsuba 3's ``cie1931_tbl`` (src/core/spectrum.cpp).
_CIE_X = (
    0.0001299, 0.0002321, 0.0004149, 0.0007416, 0.001368, 0.002236, 0.004243, 0.00765,
    0.01431, 0.02319, 0.04351, 0.07763, 0.13438, 0.21477, 0.2839, 0.3285,
    0.34828, 0.34806, 0.3362, 0.3187, 0.2908, 0.2511, 0.19536, 0.1421,
    0.09564, 0.05795001, 0.03201, 0.0147, 0.0049, 0.0024, 0.0093, 0.0291,
    0.06327, 0.1096, 0.1655, 0.2257499, 0.2904, 0.3597, 0.4334499, 0.5120501,
    0.5945, 0.6784, 0.7621, 0.8425, 0.9163, 0.9786, 1.0263, 1.0567,
    1.0622, 1.0456, 1.0026, 0.9384, 0.8544499, 0.7514, 0.6424, 0.5419,
    0.4479, 0.3608, 0.2835, 0.2187, 0.1649, 0.1212, 0.0874, 0.0636,
    0.04677, 0.0329, 0.0227, 0.01584, 0.01135916, 0.008110916, 0.005790346, 0.004109457,
    0.002899327, 0.00204919, 0.001439971, 0.0009999493, 0.0006900786, 0.0004760213, 0.0003323011,
    0.0002348261, 0.0001661505, 0.000117413, 8.307527e-05, 5.870652e-05, 4.150994e-05, 2.935326e-05,
    2.067383e-05, 1.455977e-05, 1.025398e-05, 7.221456e-06, 5.085868e-06, 3.581652e-06, 2.522525e-06,
    1.776509e-06, 1.251141e-06,
)
_CIE_Y = (
    3.917e-06, 6.965e-06, 1.239e-05, 2.202e-05, 3.9e-05, 6.4e-05, 0.00012, 0.000217,
    0.000396, 0.00064, 0.00121, 0.00218, 0.004, 0.0073, 0.0116, 0.01684,
    0.023, 0.0298, 0.038, 0.048, 0.06, 0.0739, 0.09098, 0.1126,
    0.13902, 0.1693, 0.20802, 0.2586, 0.323, 0.4073, 0.503, 0.6082,
    0.71, 0.7932, 0.862, 0.9148501, 0.954, 0.9803, 0.9949501, 1.0,
    0.995, 0.9786, 0.952, 0.9154, 0.87, 0.8163, 0.757, 0.6949,
    0.631, 0.5668, 0.503, 0.4412, 0.381, 0.321, 0.265, 0.217,
    0.175, 0.1382, 0.107, 0.0816, 0.061, 0.04458, 0.032, 0.0232,
    0.017, 0.01192, 0.00821, 0.005723, 0.004102, 0.002929, 0.002091, 0.001484,
    0.001047, 0.00074, 0.00052, 0.0003611, 0.0002492, 0.0001719, 0.00012, 8.48e-05,
    6e-05, 4.24e-05, 3e-05, 2.12e-05, 1.499e-05, 1.06e-05, 7.4657e-06, 5.2578e-06,
    3.7029e-06, 2.6078e-06, 1.8366e-06, 1.2934e-06, 9.1093e-07, 6.4153e-07, 4.5181e-07,
)
_CIE_Z = (
    0.0006061, 0.001086, 0.001946, 0.003486, 0.006450001, 0.01054999, 0.02005001, 0.03621,
    0.06785001, 0.1102, 0.2074, 0.3713, 0.6456, 1.0390501, 1.3856, 1.62296,
    1.74706, 1.7826, 1.77211, 1.7441, 1.6692, 1.5281, 1.28764, 1.0419,
    0.8129501, 0.6162, 0.46518, 0.3533, 0.272, 0.2123, 0.1582, 0.1117,
    0.07824999, 0.05725001, 0.04216, 0.02984, 0.0203, 0.0134, 0.008749999, 0.005749999,
    0.0039, 0.002749999, 0.0021, 0.0018, 0.001650001, 0.0014, 0.0011, 0.001,
    0.0008, 0.0006, 0.00034, 0.00024, 0.00019, 0.0001, 4.999999e-05, 3e-05,
    2e-05, 1e-05) + (0.0,) * 37
# CIE standard illuminant D65, relative spectral power (100 at 560 nm), 5 nm steps from 360 to
# 830 nm (CIE S 014-2 / ISO 11664-2; public data). Mitsuba 3's ``d65_table`` (core/spectrum.h).
_D65 = (
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204,
    91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41,
    117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
    107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026,
    89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207,
    80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979,
    74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054,
    46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054,
    51.959, 54.6998, 57.4406, 58.8765, 60.3125,
)
_CIE_MIN, _CIE_MAX, _CIE_SAMPLES = 360.0, 830.0, 95
#: Mitsuba's MI_CIE_Y_NORMALIZATION (1 / integral of ȳ) and MI_CIE_D65_NORMALIZATION.
_CIE_Y_NORMALIZATION = 1.0 / 106.7502593994140625
_CIE_D65_NORMALIZATION = 1.0 / 98.99741751876255
#: XYZ -> linear sRGB (ITU-R BT.709 primaries, D65 white), Mitsuba's ``xyz_to_srgb``.
_XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                         [-0.969256, 1.875991, 0.041556],
                         [0.055648, -0.204043, 1.057311]])


def _table_lookup(table, w):
    """Mitsuba's ``cie1931_xyz``/``cie_d65`` lookup: linear interpolation in a 95-entry table,
    0 outside [360, 830] nm."""
    t = (w - _CIE_MIN) * ((_CIE_SAMPLES - 1) / (_CIE_MAX - _CIE_MIN))
    i0 = np.clip(t.astype(np.int64), 0, _CIE_SAMPLES - 2)
    w1 = t - i0
    tab = np.asarray(table, dtype=np.float64)
    v = (1.0 - w1) * tab[..., i0] + w1 * tab[..., i0 + 1]
    inside = (w >= _CIE_MIN) & (w <= _CIE_MAX)
    return np.where(inside, v, 0.0)


def spectrum_to_rgb(wavelengths, values, *, d65: bool = True, bounded: bool = False) -> np.ndarray:
    """Linear sRGB (BT.709 primaries) of a piecewise-linear spectrum, as Mitsuba 3's RGB variants
    compute it (``mitsuba::spectrum_list_to_srgb``).

    wavelengths: increasing, in nm; values: the spectrum at those wavelengths (linear in between,
    0 outside). The product with the CIE 1931 2-degree colour-matching functions (5 nm table,
    linearly interpolated) is summed at Mitsuba's 1000 equally spaced points over [360, 830] nm,
    normalised so that a constant 1 has luminance Y = 1 (Mitsuba's ``MI_CIE_Y_NORMALIZATION``),
    and converted XYZ -> linear sRGB.

    d65: weight by the CIE D65 illuminant (normalised to unit luminance). Mitsuba does so for every
    non-emitter spectrum given in a scene dictionary (``{"type": "spectrum", "value": [(λ, v),
    ...]}``): a constant spectrum then maps to grey. Mitsuba's IOR presets (``material="Cu"``,
    ``bsdfkit.METALS``) are projected without it (``d65=False``).
    bounded: clip to [0, 1] (reflectances); otherwise only negative values are clamped to 0
    (eta, k), as Mitsuba does. Returns float64 (3,).
    """
    lam = np.asarray(wavelengths, dtype=np.float64).reshape(-1)
    val = np.asarray(values, dtype=np.float64).reshape(-1)
    if lam.size == 0 or lam.size != val.size:
        raise ValueError(f"wavelengths, values: need the same non-zero length, got {lam.size} and {val.size}")
    if not (np.all(np.isfinite(lam)) and np.all(np.isfinite(val))):
        raise ValueError("wavelengths, values: must be finite")
    if np.any(np.diff(lam) <= 0):
        raise ValueError(f"wavelengths: must be strictly increasing, got {lam.tolist()}")
    w = _CIE_MIN + np.arange(1000) / 999.0 * (_CIE_MAX - _CIE_MIN)
    w = w[(w >= lam[0]) & (w <= lam[-1])]
    if lam.size == 1:
        v = np.full(w.shape, val[0])
    else:
        idx = np.clip(np.searchsorted(lam, w, side="right") - 1, 0, lam.size - 2)
        w0, w1, v0, v1 = lam[idx], lam[idx + 1], val[idx], val[idx + 1]
        v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
    weight = v * (_table_lookup(_D65, w) * _CIE_D65_NORMALIZATION if d65 else 1.0)
    xyz = _table_lookup((_CIE_X, _CIE_Y, _CIE_Z), w) @ weight
    xyz *= (_CIE_MAX - _CIE_MIN) * _CIE_Y_NORMALIZATION / 1000.0
    rgb = _XYZ_TO_SRGB @ xyz
    return np.clip(rgb, 0.0, 1.0) if bounded else np.maximum(rgb, 0.0)


# =============================================================================================
# Mitsuba 3 dictionaries
# =============================================================================================

#: Mitsuba 3's named indices of refraction (``include/mitsuba/render/ior.h``; values from Hecht,
#: "Optics", 4th ed., measured at ~589 nm and 0-20 °C). Names are case-insensitive.
MITSUBA_IOR = {
    "vacuum": 1.0, "helium": 1.000036, "hydrogen": 1.000132, "air": 1.000277,
    "carbon dioxide": 1.00045, "water": 1.3330, "acetone": 1.36, "ethanol": 1.361,
    "carbon tetrachloride": 1.461, "glycerol": 1.4729, "benzene": 1.501, "silicone oil": 1.52045,
    "bromine": 1.661, "water ice": 1.31, "fused quartz": 1.458, "pyrex": 1.470,
    "acrylic glass": 1.49, "polypropylene": 1.49, "bk7": 1.5046, "sodium chloride": 1.544,
    "amber": 1.55, "pet": 1.5750, "diamond": 2.419,
}

#: Stand-in for eta = 0 (Mitsuba's ``material="none"`` conductor is eta = 0, k = 1: a perfect
#: mirror; bsdfkit's Conductor needs eta > 0). With k = 1 the Fresnel reflectance is then
#: 1 - 4 eta cos / (1 + cos^2 + ...) >= 1 - 2e-6.
MIRROR_ETA = 1e-6

_MI_SUPPORTED = ("diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric",
                 "thindielectric", "twosided", "null", "hair")
_MI_CONSTANT_TEXTURES = ("rgb", "spectrum", "uniform", "srgb")
_MI_PARAMS = {
    "diffuse": ("reflectance",),
    "conductor": ("material", "eta", "k", "specular_reflectance"),
    "roughconductor": ("material", "eta", "k", "specular_reflectance", "distribution", "alpha",
                       "alpha_u", "alpha_v", "sample_visible"),
    "dielectric": ("int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"),
    "roughdielectric": ("int_ior", "ext_ior", "specular_reflectance", "specular_transmittance",
                        "distribution", "alpha", "alpha_u", "alpha_v", "sample_visible"),
    "thindielectric": ("int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"),
    "null": (),
    "hair": ("eumelanin", "pheomelanin", "sigma_a", "scale", "int_ior", "ext_ior", "longitudinal_roughness",
             "azimuthal_roughness", "scale_tilt"),
}


class _MiError(ValueError):
    pass


def _mi_fail(where, msg):
    raise _MiError(f"from_mitsuba: {where}: {msg}")


def _is_real(x) -> bool:
    return isinstance(x, (numbers.Real, np.floating, np.integer)) and not isinstance(x, (bool, np.bool_))


def _mi_color(v, where, param, *, bounded):
    """A constant Mitsuba spectrum/colour value -> RGB (3,) float64."""
    if _is_real(v):
        return np.full(3, float(v))
    if isinstance(v, dict):
        kind = v.get("type")
        if kind not in _MI_CONSTANT_TEXTURES:
            _mi_fail(where, f"parameter {param!r} is a texture ({kind!r}); only constant values "
                     "are supported (a float, {'type': 'rgb', ...}, {'type': 'spectrum', ...} or 3 numbers)")
        if kind == "spectrum":
            if "filename" in v:
                _mi_fail(where, f"parameter {param!r}: spectrum files are not read; give "
                         "'value' as a float or a list of (wavelength, value) pairs")
            val = v.get("value")
            if _is_real(val):
                return np.full(3, float(val))
            try:
                pairs = np.asarray(val, dtype=np.float64)
            except (TypeError, ValueError):
                pairs = None
            if pairs is None or pairs.ndim != 2 or pairs.shape[1] != 2 or len(pairs) == 0:
                _mi_fail(where, f"parameter {param!r}: spectrum 'value' must be a float or a list "
                         f"of (wavelength, value) pairs, got {val!r}")
            try:
                return spectrum_to_rgb(pairs[:, 0], pairs[:, 1], d65=True, bounded=bounded)
            except ValueError as e:
                _mi_fail(where, f"parameter {param!r}: {e}")
        key = "color" if kind == "srgb" else "value"
        extra = set(v) - {"type", key, "id"}
        if extra:
            _mi_fail(where, f"parameter {param!r}: unsupported keys {sorted(extra)} in a {kind!r} value")
        return _mi_color(v.get(key), where, param, bounded=bounded)
    if isinstance(v, (str, bytes)) or v is None:
        _mi_fail(where, f"parameter {param!r}: expected a number, an RGB triple or a "
                 f"{{'type': 'rgb'|'spectrum', ...}} dict, got {v!r}")
    try:
        a = np.array(v, dtype=np.float64)
    except (TypeError, ValueError):
        _mi_fail(where, f"parameter {param!r}: {type(v).__name__} values are not supported "
                 "(textures and plugin objects cannot be converted); give a constant value")
    if a.shape == ():
        return np.full(3, float(a))
    if a.shape == (1,):
        return np.full(3, float(a[0]))
    if a.shape != (3,):
        _mi_fail(where, f"parameter {param!r}: expected 1 or 3 numbers, got shape {a.shape}")
    return a


def _mi_float(v, where, param):
    if _is_real(v):
        return float(v)
    if isinstance(v, dict) and v.get("type") not in _MI_CONSTANT_TEXTURES:
        _mi_fail(where, f"parameter {param!r} is a texture ({v.get('type')!r}); only a constant float is supported")
    if isinstance(v, dict):
        rgb = _mi_color(v, where, param, bounded=False)
        if np.all(rgb == rgb[0]):
            return float(rgb[0])
    _mi_fail(where, f"parameter {param!r}: expected a float, got {v!r}")


def _mi_ior(d, where, param, default):
    v = d.get(param, default)
    if isinstance(v, str):
        key = v.lower()
        if key not in MITSUBA_IOR:
            _mi_fail(where, f"parameter {param!r}: unknown IOR name {v!r}; Mitsuba's names are: "
                     + ", ".join(MITSUBA_IOR))
        return MITSUBA_IOR[key]
    x = _mi_float(v, where, param)
    if x < 0:
        _mi_fail(where, f"parameter {param!r}: must be >= 0, got {x}")
    return x


def _mi_unit(d, where, param):
    if param in d:
        rgb = _mi_color(d[param], where, param, bounded=False)
        if not np.all(rgb == 1.0):
            _mi_fail(where, f"parameter {param!r} = {rgb.tolist()} is not supported (bsdfkit models "
                     "have no tint factor; only 1, Mitsuba's default, is accepted)")


def _mi_alphas(d, where):
    dist = d.get("distribution")
    if dist is None:
        _mi_fail(where, "no 'distribution' given: Mitsuba's default is 'beckmann', which bsdfkit "
                 "does not have; only distribution='ggx' (Trowbridge-Reitz) is supported")
    if not isinstance(dist, str) or dist.lower() != "ggx":
        _mi_fail(where, f"distribution {dist!r} is not supported; only 'ggx' (Trowbridge-Reitz) is "
                 "('beckmann' has no bsdfkit counterpart)")
    sv = d.get("sample_visible", True)
    if not isinstance(sv, (bool, np.bool_)):
        _mi_fail(where, f"parameter 'sample_visible': expected True or False, got {sv!r}")
    has_uv = ("alpha_u" in d, "alpha_v" in d)
    if any(has_uv):
        if not all(has_uv):
            _mi_fail(where, "both 'alpha_u' and 'alpha_v' must be given (as Mitsuba requires)")
        if "alpha" in d:
            _mi_fail(where, "give either 'alpha' or 'alpha_u'/'alpha_v', not both")
        ax, ay = _mi_float(d["alpha_u"], where, "alpha_u"), _mi_float(d["alpha_v"], where, "alpha_v")
    else:
        ax = ay = _mi_float(d.get("alpha", 0.1), where, "alpha")
    for a, n in ((ax, "alpha_u"), (ay, "alpha_v")):
        if not (math.isfinite(a) and a >= 0):
            _mi_fail(where, f"parameter {n!r}: must be finite and >= 0, got {a}")
    return ax, ay


def _mi_build(where, fn):
    """Run a model constructor, prefixing its validation errors with the plugin path."""
    try:
        return fn()
    except (ValueError, TypeError) as e:
        if isinstance(e, _MiError):
            raise
        raise _MiError(f"from_mitsuba: {where}: {e}") from None


def _mi_conductor(d, where, rough):
    material = d.get("material", "none")
    if not isinstance(material, str):
        _mi_fail(where, f"parameter 'material': expected a preset name, got {material!r}")
    if "eta" in d or material == "none":
        if material != "none":
            _mi_fail(where, "give either (eta, k) or 'material', not both (as Mitsuba requires)")
        eta = _mi_color(d.get("eta", 0.0), where, "eta", bounded=False)
        k = _mi_color(d.get("k", 1.0), where, "k", bounded=False)
        # Mitsuba's default (material="none", eta = 0, k = 1) is a perfect mirror.
        eta = np.where(eta == 0.0, MIRROR_ETA, eta)
    else:
        if "k" in d:
            _mi_fail(where, f"'k' given together with material={material!r}; give either (eta, k) or 'material'")
        if material not in METALS:
            _mi_fail(where, f"material preset {material!r} is not available; bsdfkit has the RGB "
                     f"projections of: {', '.join(METALS)} (and 'none', the perfect mirror)")
        eta, k = METALS[material]
    _mi_unit(d, where, "specular_reflectance")
    if rough:
        ax, ay = _mi_alphas(d, where)
        return _mi_build(where, lambda: Conductor(eta, k, alpha_x=ax, alpha_y=ay, masking="separable"))
    return _mi_build(where, lambda: Conductor(eta, k))


def _mi_eta(d, where):
    eta_int = _mi_ior(d, where, "int_ior", "bk7")
    eta_ext = _mi_ior(d, where, "ext_ior", "air")
    if eta_ext == 0:
        _mi_fail(where, "parameter 'ext_ior': must be > 0")
    _mi_unit(d, where, "specular_reflectance")
    _mi_unit(d, where, "specular_transmittance")
    return eta_int / eta_ext


def _mi_nested(d, where):
    """The BSDF dictionaries nested in a twosided plugin."""
    nested, bad = [], []
    for key, v in d.items():
        if key in ("type", "id"):
            continue
        if isinstance(v, dict) and "type" in v:
            nested.append((key, v))
        else:
            bad.append(key)
    if bad:
        _mi_fail(where, f"unsupported parameters {bad}; twosided takes one nested BSDF dict "
                 "(or two identical ones)")
    if not nested:
        _mi_fail(where, "no nested BSDF dict found")
    if len(nested) > 2:
        _mi_fail(where, f"at most two nested BSDFs, got {len(nested)}")
    return nested


def _mi_bsdf(d, where):
    if not isinstance(d, dict):
        raise TypeError(f"from_mitsuba: {where or 'd'}: expected a Mitsuba plugin dict, got {type(d).__name__}")
    kind = d.get("type")
    label = f"{where} ({kind!r})" if where else f"plugin {kind!r}"
    if kind not in _MI_SUPPORTED:
        _mi_fail(label, "unsupported plugin; supported: " + ", ".join(_MI_SUPPORTED))
    if kind == "twosided":
        models = []
        for key, sub in _mi_nested(d, label):
            subkind = sub.get("type")
            if subkind not in ("diffuse", "conductor", "roughconductor"):
                _mi_fail(label, f"nested plugin {subkind!r} is not supported inside twosided (only the "
                         "reflection-only diffuse, conductor and roughconductor are)")
            models.append(_mi_bsdf(sub, f"{label}.{key}"))
        if len(models) == 2 and models[0] != models[1]:
            _mi_fail(label, "different front and back BSDFs are not supported (bsdfkit models are "
                     f"two-sided): {models[0]!r} vs {models[1]!r}")
        return models[0]
    unknown = [k for k in d if k not in ("type", "id") + _MI_PARAMS[kind]]
    if unknown:
        _mi_fail(label, f"unsupported parameters {unknown}; {kind} takes: "
                 + (", ".join(_MI_PARAMS[kind]) or "nothing"))
    if kind == "diffuse":
        r = _mi_color(d.get("reflectance", 0.5), label, "reflectance", bounded=True)
        return _mi_build(label, lambda: Diffuse(r))
    if kind in ("conductor", "roughconductor"):
        return _mi_conductor(d, label, kind == "roughconductor")
    if kind == "null":
        return Dielectric(1.0)
    if kind == "hair":
        return _mi_hair(d, label)
    eta = _mi_eta(d, label)
    if kind == "dielectric":
        return _mi_build(label, lambda: Dielectric(eta))
    if kind == "roughdielectric":
        ax, ay = _mi_alphas(d, label)
        return _mi_build(label, lambda: Dielectric(eta, alpha_x=ax, alpha_y=ay, masking="separable"))
    return _mi_build(label, lambda: ThinDielectric(eta))


def _mi_hair(d, where):
    """Mitsuba 3 ``hair`` -> ``Hair`` (h = 0: Mitsuba derives h from the direction, see
    ``bsdfkit.testing.hair_ref.wo_for_h``)."""
    from .models.hair import Hair, sigma_a_from_concentration

    has_pig = "eumelanin" in d or "pheomelanin" in d
    if "sigma_a" in d and has_pig:
        _mi_fail(where, "give either 'sigma_a' or 'eumelanin'/'pheomelanin', not both (Mitsuba refuses it)")
    scale = _mi_float(d.get("scale", 1.0), where, "scale")
    if "sigma_a" in d:
        sigma_a = scale * _mi_color(d["sigma_a"], where, "sigma_a", bounded=False)
    else:
        if "scale" in d and scale != 1.0:
            _mi_fail(where, "'scale' only applies to 'sigma_a' (Mitsuba ignores it for pigments)")
        ce = _mi_float(d.get("eumelanin", 1.3), where, "eumelanin")
        cp = _mi_float(d.get("pheomelanin", 0.2), where, "pheomelanin")
        sigma_a = _mi_build(where, lambda: sigma_a_from_concentration(ce, cp))
    eta = _mi_ior(d, where, "int_ior", "amber") / _mi_ior(d, where, "ext_ior", "air")
    bm = _mi_float(d.get("longitudinal_roughness", 0.3), where, "longitudinal_roughness")
    bn = _mi_float(d.get("azimuthal_roughness", 0.3), where, "azimuthal_roughness")
    alpha = _mi_float(d.get("scale_tilt", 2.0), where, "scale_tilt")
    return _mi_build(where, lambda: Hair(sigma_a=sigma_a, eta=eta, beta_m=bm, beta_n=bn, alpha=alpha, h=0.0))


def from_mitsuba(d: dict) -> BxDF:
    """The bsdfkit model of a Mitsuba 3 BSDF plugin dictionary (the inverse of
    :func:`bsdfkit.references.mitsuba.to_mitsuba`).

    Plugins and parameters (Mitsuba 3.9 names and defaults):

    ==================  ======================================================================
    ``diffuse``          ``reflectance`` (0.5) -> ``Diffuse``
    ``conductor``        ``eta``/``k`` or ``material`` (a preset in ``bsdfkit.METALS``: Cu, Au,
                         Ag, Al, Cr; default ``"none"``: eta = 0, k = 1, the perfect mirror,
                         given as eta = ``MIRROR_ETA``) -> smooth ``Conductor``
    ``roughconductor``   as conductor, plus ``distribution`` (must be ``"ggx"``; Mitsuba's
                         default is ``"beckmann"``, refused), ``alpha`` (0.1) or ``alpha_u``
                         (local x) / ``alpha_v`` (local y), ``sample_visible``
                         -> ``Conductor(..., masking="separable")``
    ``dielectric``       ``int_ior`` ("bk7"), ``ext_ior`` ("air"): floats or Mitsuba's IOR
                         names (``MITSUBA_IOR``); eta = int_ior / ext_ior -> smooth ``Dielectric``
    ``roughdielectric``  as dielectric, plus distribution/alpha as roughconductor
                         -> ``Dielectric(..., masking="separable")``
    ``thindielectric``   ``int_ior``/``ext_ior`` -> ``ThinDielectric(int_ior / ext_ior)``
    ``twosided``         one nested diffuse/conductor/roughconductor (or two identical ones):
                         unwrapped, bsdfkit's Diffuse and Conductor are two-sided
    ``null``             -> ``Dielectric(1.0)`` (pbrt's straight pass-through; ``to_mitsuba``
                         writes eta = 1 dielectrics and thin dielectrics as ``null``)
    ``hair``             ``sigma_a`` (x ``scale``) or ``eumelanin`` (1.3) / ``pheomelanin``
                         (**0.2**, pbrt's default is 0), ``int_ior`` ("amber" 1.55) / ``ext_ior``
                         ("air"), ``longitudinal_roughness`` / ``azimuthal_roughness`` (0.3),
                         ``scale_tilt`` (2 degrees) -> ``Hair(..., h=0)``: Mitsuba has no h, it
                         derives it from the direction (``bsdfkit.testing.hair_ref``); its fibre
                         axis is local y where bsdfkit's (pbrt's) is x
    ==================  ======================================================================

    Colours (reflectance, eta, k) may be a float, 3 numbers (a list, numpy array or
    ``mi.ScalarColor3f``), ``{"type": "rgb", "value": ...}``, ``{"type": "spectrum", "value":
    float | [(wavelength, value), ...]}`` (projected as Mitsuba's RGB variants do, see
    :func:`spectrum_to_rgb`), ``{"type": "uniform", "value": v}`` or ``{"type": "srgb",
    "color": ...}``. ``specular_reflectance`` / ``specular_transmittance`` are accepted only
    when they equal 1. ``id`` keys are ignored.

    Conventions: Mitsuba's microfacet models use the separable Smith masking ``G1 G1``, so rough
    plugins give ``masking="separable"``; smooth plugins keep the default masking (it has no
    effect on delta lobes). bsdfkit always samples visible normals, so ``sample_visible=False``
    changes Mitsuba's sampling and pdf but not the BSDF value returned here. A bare (one-sided)
    ``diffuse``/``conductor``/``roughconductor`` is accepted too; bsdfkit's model equals it on
    the front side (wo.z > 0) and mirrors it to the back. bsdfkit turns rough lobes with
    max(alpha) < 1e-3 into deltas (pbrt's rule); Mitsuba keeps them as very sharp lobes.

    Round trip: ``from_mitsuba(to_mitsuba(m)) == m`` for every model ``to_mitsuba`` accepts with
    ``masking="separable"`` (or no microfacet lobe) and alphas either both < 1e-3 or both >=
    1e-4 (``to_mitsuba`` floors rough alphas at 1e-4). A ``masking="correlated"`` rough model
    comes back with ``masking="separable"``: Mitsuba cannot express the height-correlated form.
    Eta = 1 dielectrics come back as ``Dielectric(1.0)``.

    Raises ``ValueError`` naming the plugin and parameter for anything else: unknown plugins,
    textures, Beckmann roughness, tints, unknown parameters, presets or IOR names.
    """
    return _mi_bsdf(d, "")


# =============================================================================================
# pbrt-v4 scene text
# =============================================================================================

#: Index of refraction at 550 nm of pbrt-v4's named glass spectra: linear interpolation of the
#: tables in pbrt-v4 ``src/pbrt/util/spectrum.cpp`` (from refractiveindex.info, CC0). pbrt
#: renders these dispersively (one wavelength per path); bsdfkit's Dielectric has one eta.
PBRT_GLASS_ETA = {
    "glass-BK7": 1.5185368127022,    # between 542 nm (1.51893348) and 564 nm (1.51784265)
    "glass-BAF10": 1.6730513078597,
    "glass-FK51A": 1.4877955395979,
    "glass-LASF9": 1.8558085679207,
    "glass-F5": 1.6770885733455,     # pbrt's table GlassSF5_eta
    "glass-F10": 1.7335739960381,    # GlassSF10_eta
    "glass-F11": 1.7911193889629,    # GlassSF11_eta
}
#: pbrt-v4 named metal spectra bsdfkit has no data for.
_PBRT_OTHER_METALS = ("CuZn", "MgO", "TiO2")
#: Wavelength at which dielectric eta spectra are evaluated.
_ETA_WAVELENGTH = 550.0

_PBRT_SUPPORTED = ("diffuse", "diffusetransmission", "conductor", "dielectric", "thindielectric", "hair")
_PBRT_UNSUPPORTED = ("coateddiffuse", "coatedconductor", "measured", "mix", "subsurface",
                     "interface", "none", "")
_PBRT_ROUGH = ("roughness", "uroughness", "vroughness", "remaproughness")
_PBRT_PARAMS = {
    "diffuse": ("reflectance",),
    "diffusetransmission": ("reflectance", "transmittance", "scale"),
    "conductor": ("eta", "k", "reflectance") + _PBRT_ROUGH,
    "dielectric": ("eta",) + _PBRT_ROUGH,
    "thindielectric": ("eta",),
    "hair": ("sigma_a", "reflectance", "eumelanin", "pheomelanin", "eta", "beta_m", "beta_n", "alpha"),
}
#: Parameters that shape the geometry, not the BxDF: recorded and left out.
_PBRT_IGNORED = ("displacement", "normalmap")


@dataclass(frozen=True)
class PbrtParam:
    """One parameter of a pbrt statement: ``"type name" values``."""

    type: str
    name: str
    values: tuple
    line: int


@dataclass(frozen=True)
class PbrtMaterial:
    """A parsed ``Material`` or ``MakeNamedMaterial`` statement.

    name: the given name, or ``"material#<n> (line <line>)"`` for the n-th anonymous ``Material``.
    type: pbrt material type ("conductor", ...). line: line of the statement (1-based).
    named: True for ``MakeNamedMaterial``. params: parameter name -> ``PbrtParam`` (without the
    ``"string type"`` of named materials). shapes: number of ``Shape`` statements that use the
    material (following ``AttributeBegin``/``AttributeEnd`` and ``NamedMaterial``).
    """

    name: str
    type: str
    line: int
    named: bool
    params: dict = field(repr=False, hash=False)
    shapes: int = 0

    @property
    def ignored(self) -> tuple:
        """Parameters present but left out of the BxDF (``displacement``, ``normalmap``)."""
        return tuple(p for p in self.params if p in _PBRT_IGNORED)

    def to_bxdf(self) -> BxDF:
        """The bsdfkit model of this material (``ValueError`` if not representable)."""
        return _pbrt_bxdf(self)


class _PbrtError(ValueError):
    pass


# --------------------------------------------------------------------------------- tokenizer

_TOKEN = re.compile(r"""
    (?P<ws>[ \t\r\n]+)
  | (?P<comment>\#[^\r\n]*)
  | (?P<string>"(?:[^"\\\r\n]|\\.)*")
  | (?P<badstring>"(?:[^"\\\r\n]|\\.)*)
  | (?P<bracket>[\[\]])
  | (?P<bare>[^ \t\r\n"\[\]]+)
""", re.VERBOSE)
_ESCAPES = {"b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "\\": "\\", "'": "'", '"': '"'}


def _unescape(s, line):
    if "\\" not in s:
        return s

    def repl(m):
        c = m.group(1)
        if c not in _ESCAPES:
            raise _PbrtError(f"line {line}: unexpected escaped character '\\{c}'")
        return _ESCAPES[c]
    return re.sub(r"\\(.)", repl, s)


def _tokens(text):
    """Yield (kind, value, line): kind is "str" (unquoted value), "[", "]" or "bare"."""
    line, last = 1, 0
    for m in _TOKEN.finditer(text):
        line += text.count("\n", last, m.start())
        last = m.start()
        kind = m.lastgroup
        if kind in ("ws", "comment"):
            continue
        if kind == "badstring":
            raise _PbrtError(f"line {line}: unterminated string {m.group()[:40]!r}")
        s = m.group()
        if kind == "string":
            yield "str", _unescape(s[1:-1], line), line
        elif kind == "bracket":
            yield s, s, line
        else:
            yield "bare", s, line


def _is_keyword(tok):
    return tok[0] == "bare" and (tok[1][0].isalpha() or tok[1][0] == "_") and tok[1] not in ("true", "false")


class _Stream:
    def __init__(self, text):
        self._it = _tokens(text)
        self._peek = None

    def peek(self):
        if self._peek is None:
            self._peek = next(self._it, None)
        return self._peek

    def next(self):
        t = self.peek()
        self._peek = None
        return t


def _read_value(ts, what, line):
    """A parameter value: one token or a bracketed list. Returns (list of raw tokens)."""
    t = ts.next()
    if t is None:
        raise _PbrtError(f"line {line}: {what}: missing value at end of input")
    if t[0] == "[":
        open_line, out = t[2], []
        while True:
            u = ts.next()
            if u is None:
                raise _PbrtError(f"line {open_line}: {what}: unterminated '[' (no matching ']')")
            if u[0] == "]":
                return out
            if u[0] == "[" or _is_keyword(u):
                raise _PbrtError(f"line {u[2]}: {what}: expected a value or ']' to close the '[' of "
                                 f"line {open_line}, got {u[1]!r}")
            out.append(u)
    if t[0] == "]" or _is_keyword(t):
        raise _PbrtError(f"line {t[2]}: {what}: expected a value, got {t[1]!r}")
    return [t]


def _convert_values(raw, ptype, pname, line):
    """Raw tokens -> a tuple of str, bool or float values (homogeneous)."""
    if not raw:
        return ()
    kinds = set()
    out = []
    for kind, s, ln in raw:
        if kind == "str":
            kinds.add("str")
            out.append(s)
        elif s in ("true", "false"):
            kinds.add("bool")
            out.append(s == "true")
        else:
            try:
                x = float(s)
            except ValueError:
                raise _PbrtError(f"line {ln}: parameter {pname!r}: {s!r} is not a number") from None
            kinds.add("num")
            out.append(x)
    if len(kinds) > 1:
        raise _PbrtError(f"line {line}: parameter {pname!r}: mixed value kinds ({', '.join(sorted(kinds))})")
    return tuple(out)


def _read_params(ts, stmt):
    params = {}
    while True:
        t = ts.peek()
        if t is None or t[0] != "str":
            return params
        ts.next()
        decl, line = t[1], t[2]
        words = decl.split()
        if len(words) != 2:
            raise _PbrtError(f"line {line}: {stmt}: malformed parameter declaration {decl!r} "
                             "(expected \"type name\")")
        ptype, pname = words
        if ptype == "color":          # pbrt-v3 spelling, upgraded by pbrt-v4
            ptype = "rgb"
        raw = _read_value(ts, f"parameter {pname!r}", line)
        values = _convert_values(raw, ptype, pname, line)
        if pname in params:
            raise _PbrtError(f"line {line}: {stmt}: parameter {pname!r} given twice "
                             f"(first on line {params[pname].line})")
        params[pname] = PbrtParam(ptype, pname, values, line)


def _skip_args(ts):
    """Skip the arguments of a directive we do not interpret (checking bracket balance)."""
    while True:
        t = ts.peek()
        if t is None or _is_keyword(t):
            return
        if t[0] == "]":
            raise _PbrtError(f"line {t[2]}: unexpected ']'")
        if t[0] == "[":
            _read_value(ts, "list", t[2])
        else:
            ts.next()


def _statement_name(ts, keyword, line):
    t = ts.next()
    if t is None or t[0] != "str":
        got = "end of input" if t is None else repr(t[1])
        raise _PbrtError(f"line {line}: {keyword}: expected a quoted string, got {got}")
    return t[1]


def parse_pbrt_materials(text: str) -> list:
    """The material statements of pbrt-v4 scene text, in order, as ``PbrtMaterial`` records.

    Understands pbrt's tokens (quoted strings with escapes, numbers, ``true``/``false``,
    brackets, ``#`` comments to the end of the line; statements may span lines) and reads
    ``Material "type" params...`` and ``MakeNamedMaterial "name" "string type" "..."
    params...``. ``AttributeBegin``/``AttributeEnd``, ``NamedMaterial`` and ``Shape`` are
    followed to count the shapes using each material; every other directive is skipped
    (``Include``/``Import`` are not followed). Anonymous materials are named
    ``"material#<n> (line <line>)"``. Does not convert parameters: see
    :meth:`PbrtMaterial.to_bxdf` and :func:`from_pbrt`.

    ``ValueError`` with the line number for malformed text: unterminated strings or brackets,
    stray ``]``, non-numbers in lists, malformed parameter declarations, a ``MakeNamedMaterial``
    without ``"string type"``, a redefined named material.
    """
    if not isinstance(text, str):
        raise TypeError(f"text: expected str (pbrt scene text), got {type(text).__name__}")
    ts = _Stream(text)
    recs = []            # mutable [name, type, line, named, params, shapes]
    by_name = {}
    current, stack = None, []
    n_anon = 0
    while True:
        t = ts.next()
        if t is None:
            break
        if not _is_keyword(t):
            if t[0] == "]":
                raise _PbrtError(f"line {t[2]}: unexpected ']'")
            if t[0] == "[":
                _read_value(ts, "list", t[2])  # checks the bracket; pbrt would reject it anyway
                continue
            raise _PbrtError(f"line {t[2]}: unexpected {t[1]!r} (expected a directive)")
        kw, line = t[1], t[2]
        if kw == "Material":
            mtype = _statement_name(ts, kw, line)
            params = _read_params(ts, f"Material {mtype!r}")
            n_anon += 1
            rec = [f"material#{n_anon} (line {line})", mtype, line, False, params, 0]
            recs.append(rec)
            current = rec
        elif kw == "MakeNamedMaterial":
            name = _statement_name(ts, kw, line)
            params = _read_params(ts, f"MakeNamedMaterial {name!r}")
            tp = params.pop("type", None)
            if tp is None or tp.type != "string" or len(tp.values) != 1 or not isinstance(tp.values[0], str):
                raise _PbrtError(f"line {line}: MakeNamedMaterial {name!r}: needs a \"string type\" parameter")
            if name in by_name:
                raise _PbrtError(f"line {line}: MakeNamedMaterial {name!r}: named material redefined "
                                 f"(first defined on line {by_name[name][2]})")
            rec = [name, tp.values[0], line, True, params, 0]
            recs.append(rec)
            by_name[name] = rec
        elif kw == "NamedMaterial":
            name = _statement_name(ts, kw, line)
            current = ("named", name)
        elif kw == "AttributeBegin":
            stack.append(current)
        elif kw == "AttributeEnd":
            if stack:
                current = stack.pop()
            _skip_args(ts)
        elif kw == "Shape":
            cur = current
            if isinstance(cur, tuple):
                cur = by_name.get(cur[1])
            if cur is not None:
                cur[5] += 1
            _skip_args(ts)
        else:
            _skip_args(ts)
    return [PbrtMaterial(name=r[0], type=r[1], line=r[2], named=r[3], params=r[4], shapes=r[5]) for r in recs]


# --------------------------------------------------------------------------------- conversion

def _pfail(rec, msg):
    raise _PbrtError(f"pbrt material {rec.name!r} ({rec.type}, line {rec.line}): {msg}")


def _pfail_param(rec, p, msg):
    raise _PbrtError(f"pbrt material {rec.name!r} ({rec.type}, line {p.line}): parameter {p.name!r}: {msg}")


def _check_texture(rec, p):
    if p.type == "texture":
        tex = p.values[0] if p.values else "?"
        _pfail_param(rec, p, f"is a texture ({tex!r}); only constant values are supported")


def _numbers(rec, p):
    if not all(isinstance(v, float) for v in p.values) or not p.values:
        _pfail_param(rec, p, f"expected numbers for a {p.type!r} parameter, got {list(p.values)!r}")
    return np.array(p.values, dtype=np.float64)


def _named_metal(rec, p, name, part):
    m = re.fullmatch(r"metal-(.+)-(eta|k)", name)
    if m is None or m.group(1) not in METALS:
        have = ", ".join(f"metal-{x}-eta/-k" for x in METALS)
        other = ", ".join(f"metal-{x}" for x in _PBRT_OTHER_METALS)
        extra = " (named glass spectra are only accepted for dielectric eta)" if name in PBRT_GLASS_ETA else ""
        _pfail_param(rec, p, f"named spectrum {name!r} is not available{extra}; bsdfkit has {have} "
                     f"(Mitsuba's RGB projections of Palik's data; pbrt's {other} are not included; "
                     "spectrum files are not read)")
    if m.group(2) != part:
        _pfail_param(rec, p, f"named spectrum {name!r} is the {m.group(2)!r} part, not {part!r}")
    return np.array(METALS[m.group(1)][0 if part == "eta" else 1], dtype=np.float64)


def _spectrum_param(rec, pname, *, albedo):
    """RGB (3,) of a spectrum-valued parameter, or None if absent."""
    p = rec.params.get(pname)
    if p is None:
        return None
    _check_texture(rec, p)
    if p.type == "rgb":
        v = _numbers(rec, p)
        if v.size != 3:
            _pfail_param(rec, p, f"an rgb value needs 3 numbers, got {v.size}")
        if np.any(v < 0):
            _pfail_param(rec, p, f"rgb has a negative component: {v.tolist()}")
        if albedo and np.any(v > 1):
            _pfail_param(rec, p, f"rgb used as a reflectance has a component > 1: {v.tolist()}")
        return v
    if p.type == "float":
        v = _numbers(rec, p)
        if v.size != 1:
            _pfail_param(rec, p, f"expected one float, got {v.size}")
        if v[0] < 0 or (albedo and v[0] > 1):
            _pfail_param(rec, p, f"value {v[0]} out of range{' [0, 1]' if albedo else ' (>= 0)'}")
        return np.full(3, v[0])
    if p.type == "spectrum":
        if p.values and all(isinstance(v, str) for v in p.values):
            if len(p.values) != 1:
                _pfail_param(rec, p, "expected one spectrum name")
            if albedo:
                _pfail_param(rec, p, f"named spectrum {p.values[0]!r} is not a reflectance; give rgb, "
                             "float or wavelength/value pairs")
            return _named_metal(rec, p, p.values[0], pname)
        v = _numbers(rec, p)
        if v.size % 2 or v.size == 0:
            _pfail_param(rec, p, f"a spectrum needs (wavelength, value) pairs, got {v.size} numbers")
        try:
            return spectrum_to_rgb(v[0::2], v[1::2], d65=True, bounded=albedo)
        except ValueError as e:
            _pfail_param(rec, p, str(e))
    if p.type == "blackbody":
        _pfail_param(rec, p, "blackbody spectra describe emission; give rgb, float or a spectrum")
    _pfail_param(rec, p, f"unsupported type {p.type!r}; expected rgb, spectrum or float")


def _eta_param(rec, default=1.5):
    """Scalar IOR of a dielectric: float, spectrum (value at 550 nm) or grey rgb."""
    p = rec.params.get("eta")
    if p is None:
        return default
    _check_texture(rec, p)
    if p.type == "float":
        eta = float(_numbers(rec, p)[0])
    elif p.type == "spectrum" and p.values and isinstance(p.values[0], str):
        name = p.values[0]
        if name not in PBRT_GLASS_ETA:
            _pfail_param(rec, p, f"named spectrum {name!r} is not available; dielectric eta accepts "
                         f"{', '.join(PBRT_GLASS_ETA)} (evaluated at 550 nm), a float or pairs")
        eta = PBRT_GLASS_ETA[name]
    elif p.type == "spectrum":
        v = _numbers(rec, p)
        if v.size % 2 or v.size == 0:
            _pfail_param(rec, p, f"a spectrum needs (wavelength, value) pairs, got {v.size} numbers")
        lam, val = v[0::2], v[1::2]
        if np.any(np.diff(lam) <= 0):
            _pfail_param(rec, p, f"wavelengths must increase, got {lam.tolist()}")
        if not lam[0] <= _ETA_WAVELENGTH <= lam[-1]:
            _pfail_param(rec, p, f"the spectrum ({lam[0]:g}-{lam[-1]:g} nm) does not cover 550 nm, "
                         "where bsdfkit evaluates dielectric eta")
        eta = float(np.interp(_ETA_WAVELENGTH, lam, val))
    elif p.type == "rgb":
        v = _numbers(rec, p)
        if v.size != 3 or not np.all(v == v[0]):
            _pfail_param(rec, p, f"an rgb eta must be grey (bsdfkit's dielectrics have one eta), got {v.tolist()}")
        eta = float(v[0])
    else:
        _pfail_param(rec, p, f"unsupported type {p.type!r}; expected float or spectrum")
    if eta == 0:            # pbrt: "if (sampledEta == 0) sampledEta = 1"
        eta = 1.0
    return eta


def _float_param(rec, pname, default):
    p = rec.params.get(pname)
    if p is None:
        return default
    _check_texture(rec, p)
    if p.type != "float":
        _pfail_param(rec, p, f"expected a \"float {pname}\", got type {p.type!r}")
    v = _numbers(rec, p)
    if v.size != 1:
        _pfail_param(rec, p, f"expected one value, got {v.size}")
    return float(v[0])


def _bool_param(rec, pname, default):
    p = rec.params.get(pname)
    if p is None:
        return default
    if p.type != "bool":
        _pfail_param(rec, p, f"expected a \"bool {pname}\", got type {p.type!r}")
    v = p.values[0] if len(p.values) == 1 else None
    if not (isinstance(v, bool) or v in ("true", "false")):
        _pfail_param(rec, p, f"expected true or false, got {list(p.values)!r}")
    return v is True or v == "true"


def _alphas(rec):
    r = _float_param(rec, "roughness", 0.0)
    u = _float_param(rec, "uroughness", r)
    v = _float_param(rec, "vroughness", r)
    for val, n in ((u, "uroughness"), (v, "vroughness")):
        if not (math.isfinite(val) and val >= 0):
            _pfail(rec, f"{n if n in rec.params else 'roughness'} must be finite and >= 0, got {val}")
    if _bool_param(rec, "remaproughness", True):
        return roughness_to_alpha(u), roughness_to_alpha(v)
    return u, v


def _pbrt_bxdf(rec):
    mtype = rec.type
    if mtype not in _PBRT_SUPPORTED:
        kind = "unsupported" if mtype in _PBRT_UNSUPPORTED else "unknown"
        _pfail(rec, f"{kind} material type {mtype!r}; supported: {', '.join(_PBRT_SUPPORTED)}")
    allowed = _PBRT_PARAMS[mtype] + _PBRT_IGNORED
    for p in rec.params.values():
        if p.name not in allowed:
            _pfail_param(rec, p, f"not a parameter of pbrt-v4's {mtype} material; it takes "
                         + ", ".join(_PBRT_PARAMS[mtype]))
    try:
        if mtype == "diffuse":
            r = _spectrum_param(rec, "reflectance", albedo=True)
            return Diffuse(0.5 if r is None else r)
        if mtype == "diffusetransmission":
            r = _spectrum_param(rec, "reflectance", albedo=True)
            t = _spectrum_param(rec, "transmittance", albedo=True)
            s = _float_param(rec, "scale", 1.0)
            r = np.full(3, 0.25) if r is None else r
            t = np.full(3, 0.25) if t is None else t
            return DiffuseTransmission(np.clip(s * r, 0, 1), np.clip(s * t, 0, 1))
        if mtype == "conductor":
            ax, ay = _alphas(rec)
            refl = _spectrum_param(rec, "reflectance", albedo=True)
            eta = _spectrum_param(rec, "eta", albedo=False)
            k = _spectrum_param(rec, "k", albedo=False)
            if refl is not None:
                if eta is not None or k is not None:
                    _pfail(rec, "give either \"reflectance\" or \"eta\"/\"k\", not both (pbrt-v4 refuses it)")
                return Conductor.from_reflectance(refl, alpha_x=ax, alpha_y=ay, masking="correlated")
            eta = np.array(METALS["Cu"][0]) if eta is None else eta
            k = np.array(METALS["Cu"][1]) if k is None else k
            return Conductor(eta, k, alpha_x=ax, alpha_y=ay, masking="correlated")
        if mtype == "dielectric":
            ax, ay = _alphas(rec)
            return Dielectric(_eta_param(rec), alpha_x=ax, alpha_y=ay, masking="correlated")
        if mtype == "hair":
            return _pbrt_hair(rec)
        return ThinDielectric(_eta_param(rec))
    except _PbrtError:
        raise
    except (ValueError, TypeError) as e:
        _pfail(rec, str(e))


def _pbrt_hair(rec):
    """pbrt-v4 ``HairMaterial``: sigma_a, else reflectance, else eumelanin/pheomelanin (each
    ignored when an earlier one is given, as pbrt-v4 warns and does); neither -> eumelanin 1.3.
    beta_m / beta_n clamped to [0.01, 1] and reflectance to [0, 1] as pbrt-v4's material does."""
    from .models.hair import Hair, sigma_a_from_concentration, sigma_a_from_reflectance

    bm = min(max(_float_param(rec, "beta_m", 0.3), 0.01), 1.0)
    bn = min(max(_float_param(rec, "beta_n", 0.3), 0.01), 1.0)
    kw = dict(eta=_float_param(rec, "eta", 1.55), beta_m=bm, beta_n=bn, alpha=_float_param(rec, "alpha", 2.0), h=0.0)
    sigma_a = _spectrum_param(rec, "sigma_a", albedo=False)
    if sigma_a is None:
        p = rec.params.get("reflectance")
        if p is not None:
            _check_texture(rec, p)
            c = _spectrum_param(rec, "reflectance", albedo=False)
            sigma_a = sigma_a_from_reflectance(np.clip(c, 0.0, 1.0), bn)
        else:
            ce = _float_param(rec, "eumelanin", None)
            cp = _float_param(rec, "pheomelanin", None)
            if ce is None and cp is None:
                ce = 1.3
            sigma_a = sigma_a_from_concentration(ce or 0.0, cp or 0.0)
    return Hair(sigma_a=sigma_a, **kw)


def from_pbrt(text: str, *, skip_unsupported: bool = False) -> dict:
    """bsdfkit models for the materials of pbrt-v4 scene text: ``{name: BxDF}`` in file order.

    Named materials keep their names; anonymous ``Material`` statements are called
    ``"material#<n> (line <line>)"`` (see :func:`parse_pbrt_materials` for the syntax handled).
    Types and parameters follow pbrt-v4's ``src/pbrt/materials.cpp`` (defaults in brackets):

    * ``diffuse``: reflectance [0.5] -> ``Diffuse`` (clamped to [0, 1] as pbrt does).
    * ``diffusetransmission``: reflectance [0.25], transmittance [0.25], scale [1]
      -> ``DiffuseTransmission(clamp(scale r), clamp(scale t))``.
    * ``conductor``: eta/k [metal-Cu-eta / metal-Cu-k] or reflectance (pbrt's artist form,
      ``Conductor.from_reflectance``); roughness [0], uroughness/vroughness [roughness],
      remaproughness [true] -> ``Conductor``.
    * ``dielectric``: eta [1.5], roughness as conductor -> ``Dielectric``.
    * ``thindielectric``: eta [1.5] -> ``ThinDielectric``.
    * ``hair``: sigma_a, else reflectance (``Hair.from_reflectance``, clamped to [0, 1]), else
      eumelanin / pheomelanin [1.3 / 0] (``Hair.from_concentration``); eta [1.55], beta_m, beta_n
      [0.3] (clamped to [0.01, 1]), alpha [2 degrees] -> ``Hair(..., h=0)`` (pbrt-v4 takes h from
      the curve's v coordinate per hit).

    pbrt-v4's microfacet models use height-correlated Smith masking: ``masking="correlated"``.
    Roughness: with remaproughness true, alpha = sqrt(roughness) (``bk.roughness_to_alpha``),
    else alpha = roughness; uroughness is alpha along local x, vroughness along y.

    Values: ``"rgb"`` (3 numbers, used as they are: pbrt's RGB-to-spectrum upsampling followed by
    a projection back to sRGB returns them up to the upsampling error), ``"float"`` (grey; pbrt itself only takes it for dielectric
    eta), ``"spectrum"`` as wavelength/value pairs (projected to linear sRGB as Mitsuba's RGB
    variants do: CIE 1931 and D65, see :func:`spectrum_to_rgb`), or as a named spectrum:
    ``metal-<X>-eta``/``metal-<X>-k`` for X in ``bsdfkit.METALS`` (Cu, Au, Ag, Al; Cr too,
    which pbrt lacks) -- these are Mitsuba's RGB projections of Palik's measured data, not pbrt's
    exact spectral tables, and pbrt's metal-CuZn, metal-MgO and metal-TiO2 are refused. Dielectric
    eta is one number: a float, a grey rgb, a named glass (``PBRT_GLASS_ETA``) or pairs, the
    spectra evaluated at 550 nm (pbrt renders them dispersively). ``displacement`` and
    ``normalmap`` change the geometry, not the BxDF, and are left out
    (``PbrtMaterial.ignored``).

    ``ValueError`` naming the material, its line and the parameter for unsupported types
    (coateddiffuse, coatedconductor, measured, mix, subsurface, interface, ...),
    texture-valued or unknown parameters, bad values, and malformed text (with the line).
    ``skip_unsupported=True`` leaves out materials that cannot be converted (unsupported types,
    textures, unknown spectra) instead of raising; malformed text still raises.
    """
    out = {}
    for rec in parse_pbrt_materials(text):
        try:
            out[rec.name] = rec.to_bxdf()
        except _PbrtError:
            if not skip_unsupported:
                raise
    return out
