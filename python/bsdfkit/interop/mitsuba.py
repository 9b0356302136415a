"""Mitsuba 3 BSDF dictionaries -> bsdfkit models (:func:`from_mitsuba`)."""
from __future__ import annotations

import contextvars
import math
import numbers
import os

import numpy as np

from ..models import Conductor, Dielectric, Diffuse, METALS, Plastic, ThinDielectric
from .spectra import spectrum_to_rgb

__all__ = ["MITSUBA_IOR", "MIRROR_ETA", "MI_MAX_DEPTH", "MI_MAX_PLUGINS", "from_mitsuba", "MitsubaSkipWarning"]


class MitsubaSkipWarning(UserWarning):
    """``from_mitsuba(scene_file)`` skipped a BSDF it cannot convert (attributes, as
    ``PbrtSkipWarning``'s: ``material``, ``line``, ``file``, ``reason``); ``strict=True`` raises
    instead."""


#: Folder that relative ``bitmap`` filenames are resolved against (the scene file's, or
#: ``from_mitsuba(..., base_dir=)``); None: the working directory.
_BASE_DIR = contextvars.ContextVar("bsdfkit_mitsuba_base_dir", default=None)
#: The XML line of a dict read from a scene file (``_mitsuba_xml.LINE_KEY``).
_LINE = "__line__"


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
                 "thindielectric", "measured", "plastic", "roughplastic", "twosided", "null", "hair",
                 "blendbsdf", "mask", "normalmap", "bumpmap", "principled", "principledthin")


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
    "plastic": ("diffuse_reflectance", "specular_reflectance", "nonlinear", "int_ior", "ext_ior"),
    "roughplastic": ("diffuse_reflectance", "specular_reflectance", "nonlinear", "int_ior", "ext_ior",
                     "distribution", "alpha", "sample_visible"),
    "null": (),
    "measured": ("filename",),
    "principled": ("base_color", "roughness", "anisotropic", "metallic", "spec_trans", "eta", "specular",
                   "spec_tint", "sheen", "sheen_tint", "flatness", "clearcoat", "clearcoat_gloss",
                   "main_specular_sampling_rate", "clearcoat_sampling_rate", "diffuse_reflectance_sampling_rate"),
    "principledthin": ("base_color", "roughness", "anisotropic", "spec_trans", "eta", "spec_tint", "sheen",
                       "sheen_tint", "flatness", "diff_trans", "specular_reflectance_sampling_rate",
                       "specular_transmittance_sampling_rate", "diffuse_reflectance_sampling_rate",
                       "diffuse_transmittance_sampling_rate"),
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
        kind = _value_type(v, where, param)
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


def _value_type(v, where, param):
    """The ``type`` of a value dict ({'type': 'rgb', ...}): a string, else a named error (an
    array there made ``in`` raise numpy's ambiguous-truth ValueError)."""
    kind = v.get("type")
    if not isinstance(kind, str):
        _mi_fail(where, f"parameter {param!r}: the value dict's 'type' must be a string such as 'rgb' or "
                 f"'spectrum', got {type(kind).__name__} {kind!r}"[:300])
    return kind


def _mi_float(v, where, param):
    if _is_real(v):
        return float(v)
    if isinstance(v, dict) and _value_type(v, where, param) not in _MI_CONSTANT_TEXTURES:
        _mi_fail(where, f"parameter {param!r} is a texture ({v.get('type')!r}); only a constant float is supported")
    if isinstance(v, dict):
        rgb = _mi_color(v, where, param, bounded=False)
        if np.all(rgb == rgb[0]):
            return float(rgb[0])
    _mi_fail(where, f"parameter {param!r}: expected a float, got {v!r}")


def _is_texture_dict(v) -> bool:
    return isinstance(v, dict) and isinstance(v.get("type"), str) and v["type"] in ("bitmap", "checkerboard")


def _mi_texture(v, where, param, channels):
    """A Mitsuba ``bitmap`` (``checkerboard``) value -> ``bk.Texture`` (``tx.Checkerboard``);
    ``interop/_mitsuba_texture.py``."""
    from . import _mitsuba_texture as mt
    if v["type"] == "checkerboard":
        return mt.checkerboard_texture(v, f"{where}: parameter {param!r}", channels, _mi_fail, _mi_color)
    bm = mt.parse_bitmap(v, f"{where}: parameter {param!r}", _BASE_DIR.get(), _mi_fail)
    return mt.bitmap_texture(bm, channels, _mi_fail)


def _mi_color_tex(v, where, param, *, bounded):
    """A colour parameter that may be a ``bitmap`` texture: the texture, else the RGB constant."""
    if _is_texture_dict(v):
        return _mi_texture(v, where, param, 3)
    return _mi_color(v, where, param, bounded=bounded)


def _mi_float_tex(v, where, param):
    """A float parameter that may be a ``bitmap`` texture (an RGB bitmap gives its luminance)."""
    if _is_texture_dict(v):
        return _mi_texture(v, where, param, 1)
    return _mi_float(v, where, param)


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
    """(alpha_x, alpha_y, microfacet keywords) of a rough plugin; ``distribution`` defaults to
    Mitsuba's "beckmann"."""
    dist = d.get("distribution", "beckmann")
    if not isinstance(dist, str) or dist.lower() not in ("ggx", "beckmann"):
        _mi_fail(where, f"distribution {dist!r} is not supported; Mitsuba has 'beckmann' (its default) and 'ggx'")
    sv = d.get("sample_visible", True)
    if not isinstance(sv, (bool, np.bool_)):
        _mi_fail(where, f"parameter 'sample_visible': expected True or False, got {sv!r}")
    has_uv = ("alpha_u" in d, "alpha_v" in d)
    if any(has_uv):
        if not all(has_uv):
            _mi_fail(where, "both 'alpha_u' and 'alpha_v' must be given (as Mitsuba requires)")
        if "alpha" in d:
            _mi_fail(where, "give either 'alpha' or 'alpha_u'/'alpha_v', not both")
        ax, ay = _mi_float_tex(d["alpha_u"], where, "alpha_u"), _mi_float_tex(d["alpha_v"], where, "alpha_v")
    else:
        ax = ay = _mi_float_tex(d.get("alpha", 0.1), where, "alpha")
    for a, n in ((ax, "alpha_u"), (ay, "alpha_v")):
        if isinstance(a, float) and not (math.isfinite(a) and a >= 0):
            _mi_fail(where, f"parameter {n!r}: must be finite and >= 0, got {a}")
    return ax, ay, {"distribution": dist.lower(), "sample_visible": bool(sv)}


def _alpha_kw(ax, ay):
    """Constructor keywords of the alphas: one texture for both (Mitsuba's ``alpha``) as ``alpha=``."""
    if ax is ay and not isinstance(ax, float):
        return {"alpha": ax}
    return {"alpha_x": ax, "alpha_y": ay}


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
        eta = _mi_color_tex(d.get("eta", 0.0), where, "eta", bounded=False)
        k = _mi_color_tex(d.get("k", 1.0), where, "k", bounded=False)
        # Mitsuba's default (material="none", eta = 0, k = 1) is a perfect mirror.
        if isinstance(eta, np.ndarray):
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
        ax, ay, mf = _mi_alphas(d, where)
        return _mi_build(where, lambda: Conductor(eta, k, **_alpha_kw(ax, ay), masking="separable", **mf))
    return _mi_build(where, lambda: Conductor(eta, k))


def _mi_eta(d, where):
    eta_int = _mi_ior(d, where, "int_ior", "bk7")
    eta_ext = _mi_ior(d, where, "ext_ior", "air")
    if eta_ext == 0:
        _mi_fail(where, "parameter 'ext_ior': must be > 0")
    _mi_unit(d, where, "specular_reflectance")
    _mi_unit(d, where, "specular_transmittance")
    return eta_int / eta_ext


#: Deepest nesting of plugin dicts (twosided / blendbsdf / mask / normalmap) accepted: deeper
#: dicts ran out of Python's recursion limit, here or on the model's first eval.
MI_MAX_DEPTH = 64
#: Most nested plugin dicts converted for one call, each counted once per path to it (blendbsdfs
#: that hold the same dict twice, 30 deep, are 2^30 conversions: a hang without it).
MI_MAX_PLUGINS = 1024


def _mi_bsdf(d, where, ctx=None):
    if ctx is None:
        ctx = {"n": 0, "path": []}
    if not isinstance(d, dict):
        raise TypeError(f"from_mitsuba: {where or 'd'}: expected a Mitsuba plugin dict, got {type(d).__name__}")
    if any(d is p for p in ctx["path"]):
        raise _MiError(f"from_mitsuba: {where}: the plugin dict contains itself (a cycle)")
    if len(ctx["path"]) >= MI_MAX_DEPTH:
        raise _MiError(f"from_mitsuba: {where[:200]}...: plugin dicts nested deeper than {MI_MAX_DEPTH} "
                       "(bsdfkit.interop.mitsuba.MI_MAX_DEPTH)")
    ctx["n"] += 1
    if ctx["n"] > MI_MAX_PLUGINS:
        raise _MiError(f"from_mitsuba: {where[:200]}: more than {MI_MAX_PLUGINS} nested plugin dicts, each counted "
                       "once per path to it (the same dict nested through several paths?; "
                       "bsdfkit.interop.mitsuba.MI_MAX_PLUGINS)")
    ctx["path"].append(d)
    try:
        return _mi_plugin(d, where, ctx)
    finally:
        ctx["path"].pop()


def _mi_plugin(d, where, ctx):
    kind = d.get("type")
    if not isinstance(kind, str):
        raise _MiError(f"from_mitsuba: {where or 'd'}: 'type': expected a plugin name (str), got {kind!r}"[:400])
    line = f", line {d[_LINE]}" if isinstance(d.get(_LINE), int) else ""
    label = f"{where} ({kind!r}{line})" if where else f"plugin {kind!r}" + (f" ({line[2:]})" if line else "")
    if kind not in _MI_SUPPORTED:
        _mi_fail(label, "unsupported plugin; supported: " + ", ".join(_MI_SUPPORTED))
    if kind in ("twosided", "blendbsdf", "mask", "normalmap", "bumpmap"):   # composites: interop/_mitsuba_composite.py
        from . import _mitsuba_composite as mc

        def build(sub, w):
            return _mi_bsdf(sub, w, ctx)
        if kind == "twosided":
            return mc.mi_twosided(d, label, build, _mi_fail)
        if kind == "blendbsdf":
            return _mi_build(label, lambda: mc.mi_blend(d, label, build, _mi_fail, _mi_float_tex))
        if kind == "mask":
            return _mi_build(label, lambda: mc.mi_mask(d, label, build, _mi_fail, _mi_float_tex))
        if kind == "bumpmap":
            return _mi_build(label, lambda: mc.mi_bumpmap(d, label, build, _mi_fail, _mi_float))
        return _mi_build(label, lambda: mc.mi_normalmap(d, label, build, _mi_fail, _mi_color))
    unknown = [k for k in d if k not in ("type", "id", _LINE) + _MI_PARAMS[kind]]
    if unknown:
        _mi_fail(label, f"unsupported parameters {unknown}; {kind} takes: "
                 + (", ".join(_MI_PARAMS[kind]) or "nothing"))
    if kind == "diffuse":
        r = _mi_color_tex(d.get("reflectance", 0.5), label, "reflectance", bounded=True)
        return _mi_build(label, lambda: Diffuse(r))
    if kind in ("conductor", "roughconductor"):
        return _mi_conductor(d, label, kind == "roughconductor")
    if kind == "null":
        return Dielectric(1.0)
    if kind == "measured":
        from ..models.measured import Measured
        fn = d.get("filename")
        if not isinstance(fn, str):
            _mi_fail(label, f"filename: expected the path of an RGL tensor file (str), got {type(fn).__name__}")
        return Measured(fn)
    if kind in ("plastic", "roughplastic"):
        return _mi_plastic(d, label, kind == "roughplastic")
    if kind == "hair":
        return _mi_hair(d, label)
    if kind in ("principled", "principledthin"):
        return _mi_principled(d, label, kind == "principledthin")
    eta = _mi_eta(d, label)
    if kind == "dielectric":
        return _mi_build(label, lambda: Dielectric(eta))
    if kind == "roughdielectric":
        ax, ay, mf = _mi_alphas(d, label)
        return _mi_build(label, lambda: Dielectric(eta, **_alpha_kw(ax, ay), masking="separable", **mf))
    return _mi_build(label, lambda: ThinDielectric(eta))


def _mi_plastic(d, where, rough):
    r = _mi_color_tex(d.get("diffuse_reflectance", 0.5), where, "diffuse_reflectance", bounded=True)
    ks = _mi_color_tex(d.get("specular_reflectance", 1.0), where, "specular_reflectance", bounded=False)
    nl = d.get("nonlinear", False)
    if not isinstance(nl, (bool, np.bool_)):
        _mi_fail(where, f"parameter 'nonlinear': expected True or False, got {nl!r}")
    eta_int = _mi_ior(d, where, "int_ior", "polypropylene")
    eta_ext = _mi_ior(d, where, "ext_ior", "air")
    if eta_ext == 0:
        _mi_fail(where, "parameter 'ext_ior': must be > 0")
    alpha = 0.0
    if rough:
        if _is_texture_dict(d.get("alpha")):
            _mi_fail(where, "parameter 'alpha' is a texture: Mitsuba's roughplastic takes a float alpha only "
                     "(it refuses a texture; bsdfkit's Plastic would take one)")
        ax, ay, mf = _mi_alphas(d, where)
        if mf["distribution"] != "ggx":
            why = "no 'distribution' given: Mitsuba's default is" if "distribution" not in d else "distribution"
            _mi_fail(where, f"{why} 'beckmann', which bsdfkit's Plastic does not have yet (its rough-interface "
                     "tables are GGX's); only distribution='ggx' is supported for roughplastic")
        if ax != ay:
            _mi_fail(where, "roughplastic is isotropic (Mitsuba refuses alpha_u != alpha_v)")
        alpha = ax
    return _mi_build(where, lambda: Plastic(r, eta_int / eta_ext, alpha=alpha, nonlinear=bool(nl),
                                            masking="separable", specular_reflectance=ks))
def _mi_principled(d, where, thin):
    """Mitsuba 3 ``principled`` / ``principledthin`` -> ``Principled`` / ``PrincipledThin`` (the same
    parameters; a weight or the base colour may be a bitmap texture, and principledthin's ``eta``;
    principled's ``eta`` / ``specular`` and the sampling rates are floats)."""
    from ..models import principled as pm

    if thin:
        cls, weights, floats = pm.PrincipledThin, pm._THIN_WEIGHTS + ("diff_trans", "eta"), pm._THIN_RATES
    else:
        if "eta" in d and "specular" in d:
            _mi_fail(where, "give either 'eta' or 'specular', not both (Mitsuba refuses it)")
        cls, weights, floats = pm.Principled, pm._WEIGHTS, ("eta", "specular") + pm._RATES
    kw = {"base_color": _mi_color_tex(d.get("base_color", 0.5), where, "base_color", bounded=True)}
    kw.update({k: _mi_float_tex(d[k], where, k) for k in weights if k in d})
    kw.update({k: _mi_float(d[k], where, k) for k in floats if k in d})
    return _mi_build(where, lambda: cls(**kw))


def _mi_hair(d, where):
    """Mitsuba 3 ``hair`` -> ``Hair`` (h = 0: Mitsuba derives h from the direction, see
    ``bsdfkit.testing.hair_ref.wo_for_h``)."""
    from ..models.hair import Hair, sigma_a_from_concentration

    has_pig = "eumelanin" in d or "pheomelanin" in d
    if "sigma_a" in d and has_pig:
        _mi_fail(where, "give either 'sigma_a' or 'eumelanin'/'pheomelanin', not both (Mitsuba refuses it)")
    scale = _mi_float(d.get("scale", 1.0), where, "scale")
    if not (math.isfinite(scale) and scale >= 0):
        _mi_fail(where, f"parameter 'scale': must be finite and >= 0, got {scale}")
    if "sigma_a" in d:
        with np.errstate(over="ignore", invalid="ignore"):   # an inf product is refused by Hair, named
            sigma_a = scale * _mi_color(d["sigma_a"], where, "sigma_a", bounded=False)
    else:
        if "scale" in d and scale != 1.0:
            _mi_fail(where, "'scale' only applies to 'sigma_a' (Mitsuba ignores it for pigments)")
        ce = _mi_float(d.get("eumelanin", 1.3), where, "eumelanin")
        cp = _mi_float(d.get("pheomelanin", 0.2), where, "pheomelanin")
        sigma_a = _mi_build(where, lambda: sigma_a_from_concentration(ce, cp))
    ext = _mi_ior(d, where, "ext_ior", "air")
    if ext == 0:
        _mi_fail(where, "parameter 'ext_ior': must be > 0")
    eta = _mi_ior(d, where, "int_ior", "amber") / ext
    bm = _mi_float(d.get("longitudinal_roughness", 0.3), where, "longitudinal_roughness")
    bn = _mi_float(d.get("azimuthal_roughness", 0.3), where, "azimuthal_roughness")
    alpha = _mi_float(d.get("scale_tilt", 2.0), where, "scale_tilt")
    return _mi_build(where, lambda: Hair(sigma_a=sigma_a, eta=eta, beta_m=bm, beta_n=bn, alpha=alpha, h=0.0))


def from_mitsuba(d, *, base_dir=None, params=None, strict=False, progress=None):
    """The bsdfkit model of a Mitsuba 3 BSDF plugin dictionary (the inverse of
    :func:`bsdfkit.testing.mitsuba.to_mitsuba`), or of a loaded ``mi.BSDF`` (``mi.load_dict``,
    a scene's BSDF): its plugin class and ``mi.traverse`` parameters are read back into such a
    dictionary. A loaded BSDF stores float32 values (and eta = int_ior / ext_ior), so its model
    equals the dictionary's to float32 precision (loaded BSDFs with textures are not read back).

    Given the path of a Mitsuba scene file (``.xml``), returns ``{name: model}`` for its BSDFs
    (named by ``id``; an unnamed one inline in a shape by the shape's id or position):
    ``bitmap`` filenames are relative to the file's folder, ``$name`` values come from its
    ``<default>`` elements or ``params``. A BSDF that cannot be converted is skipped with a
    :class:`MitsubaSkipWarning` naming it, its line and the reason (``strict=True`` raises).

    ``bitmap`` textures (``filename`` relative to ``base_dir``, default the working directory;
    or an in-memory ``data`` tensor / ``bitmap``), with ``filter_type`` "nearest" / "bilinear",
    ``wrap_mode`` "repeat" / "mirror" / "clamp", ``raw`` (false: sRGB-decoded as Mitsuba does
    for PNG / JPEG, EXR linear) and ``to_uv``, become ``bk.Texture`` values (see
    ``bsdfkit.interop._mitsuba_texture``) on ``reflectance``, ``eta``, ``k``, the alphas
    (not roughplastic's: Mitsuba takes a float), ``diffuse_reflectance`` /
    ``specular_reflectance`` of (rough)plastic, blendbsdf's ``weight``, mask's ``opacity``,
    normalmap's ``normalmap`` and bumpmap's height; evaluate the model with ``uv=``. A float
    parameter given an RGB bitmap takes its luminance (Mitsuba's ``eval_1``): supported for
    in-memory images, refused for RGB image files.

    Plugins and parameters (Mitsuba 3.9 names and defaults):

    =================== ======================================================================
    ``diffuse``          ``reflectance`` (0.5) -> ``Diffuse``
    ``conductor``        ``eta``/``k`` or ``material`` (a preset in ``bsdfkit.METALS``: Cu, Au,
                         Ag, Al, Cr; default ``"none"``: eta = 0, k = 1, the perfect mirror,
                         given as eta = ``MIRROR_ETA``) -> smooth ``Conductor``
    ``roughconductor``   as conductor, plus ``distribution`` (``"beckmann"``, Mitsuba's default,
                         or ``"ggx"``), ``alpha`` (0.1) or ``alpha_u`` (local x) / ``alpha_v``
                         (local y), ``sample_visible`` (true)
                         -> ``Conductor(..., masking="separable", distribution=...)``
    ``dielectric``       ``int_ior`` ("bk7"), ``ext_ior`` ("air"): floats or Mitsuba's IOR
                         names (``MITSUBA_IOR``); eta = int_ior / ext_ior -> smooth ``Dielectric``
    ``roughdielectric``  as dielectric, plus distribution/alpha as roughconductor
                         -> ``Dielectric(..., masking="separable")``
    ``thindielectric``   ``int_ior``/``ext_ior`` -> ``ThinDielectric(int_ior / ext_ior)``
    ``plastic``          ``diffuse_reflectance`` (0.5), ``specular_reflectance`` (1),
                         ``nonlinear`` (false), ``int_ior`` ("polypropylene"), ``ext_ior``
                         ("air") -> ``Plastic(..., masking="separable")``
    ``roughplastic``     as plastic, plus ``distribution`` ("ggx" only so far; Mitsuba's
                         default "beckmann" is refused), ``alpha`` (0.1)
                         -> ``Plastic(..., alpha=alpha, masking="separable")``
    ``twosided``         one nested diffuse/conductor/roughconductor/(rough)plastic (or two
                         identical ones): unwrapped, bsdfkit's Diffuse, Conductor and Plastic are
                         two-sided; any other reflection-only nested BSDF (any model, composites
                         too), or two different ones (two-faced) -> ``TwoSided(front, back)``; a
                         transmitting one is refused (as Mitsuba)
    ``blendbsdf``        ``weight`` (0.5, a constant or a bitmap), two nested BSDFs in the
                         dictionary's order (Mitsuba 3.9's) -> ``Mix(a, b, weight)``
    ``mask``             ``opacity`` (0.5, a constant or a bitmap), one nested BSDF
                         -> ``Mask(model, opacity)``
    ``normalmap``        ``normalmap`` (a constant ``rgb`` or a ``bitmap``: n = 2 rgb - 1,
                         normalized), ``flip_invalid_normals`` / ``use_shadowing_function``
                         (true) -> ``NormalMap``
    ``bumpmap``          a height ``bitmap`` (bilinear: its gradient at each uv, as Mitsuba's
                         ``eval_1_grad``; nearest: zero), ``scale`` (1), the two flags (true)
                         -> ``BumpMap``; other height textures are refused (Mitsuba
                         differentiates bitmaps only)
    ``measured``         ``filename`` (an RGL tensor file) -> ``Measured(filename)``
    ``null``             -> ``Dielectric(1.0)`` (pbrt's straight pass-through; ``to_mitsuba``
                         writes eta = 1 dielectrics and thin dielectrics as ``null``)
    ``hair``             ``sigma_a`` (x ``scale``) or ``eumelanin`` (1.3) / ``pheomelanin``
                         (**0.2**, pbrt's default is 0), ``int_ior`` ("amber" 1.55) / ``ext_ior``
                         ("air"), ``longitudinal_roughness`` / ``azimuthal_roughness`` (0.3),
                         ``scale_tilt`` (2 degrees) -> ``Hair(..., h=0)``: Mitsuba has no h, it
                         derives it from the direction (``bsdfkit.testing.hair_ref``); its fibre
                         axis is local y where bsdfkit's (pbrt's) is x
    ``principled``       ``base_color`` (0.5), ``roughness`` (0.5), ``anisotropic``,
                         ``metallic``, ``spec_trans``, ``spec_tint``, ``sheen``, ``sheen_tint``,
                         ``flatness``, ``clearcoat``, ``clearcoat_gloss`` (0; each a constant or
                         a bitmap), ``eta`` or ``specular`` (0.5), the three sampling rates (1)
                         -> ``Principled`` (the same parameters)
    ``principledthin``   ``base_color``, ``roughness``, ``anisotropic``, ``spec_trans``, ``eta``
                         (1.5), ``spec_tint``, ``sheen``, ``sheen_tint``, ``flatness``,
                         ``diff_trans`` (each a constant or a bitmap), the four sampling rates
                         -> ``PrincipledThin``
    =================== ======================================================================

    Colours (reflectance, eta, k) may be a float, 3 numbers (a list, numpy array or
    ``mi.ScalarColor3f``), ``{"type": "rgb", "value": ...}``, ``{"type": "spectrum", "value":
    float | [(wavelength, value), ...]}`` (projected as Mitsuba's RGB variants do, see
    :func:`spectrum_to_rgb`), ``{"type": "uniform", "value": v}`` or ``{"type": "srgb",
    "color": ...}``. ``specular_reflectance`` / ``specular_transmittance`` are accepted only
    when they equal 1. ``id`` keys are ignored.

    Conventions: Mitsuba's microfacet models use the separable Smith masking ``G1 G1``, so rough
    plugins give ``masking="separable"``; smooth plugins keep the default masking (it has no
    effect on delta lobes). ``sample_visible`` carries over to Conductor and Dielectric; Plastic
    always samples visible normals, so there ``sample_visible=False`` changes Mitsuba's sampling
    and pdf but not the BSDF value returned here. A bare (one-sided)
    ``diffuse``/``conductor``/``roughconductor`` is accepted too; bsdfkit's model equals it on
    the front side (wo.z > 0) and mirrors it to the back. bsdfkit turns rough lobes with
    max(alpha) < 1e-3 into deltas (pbrt's rule); Mitsuba keeps them as very sharp lobes.

    Round trip: ``from_mitsuba(m.to_mitsuba()) == m`` for every model ``to_mitsuba`` exports, with
    alphas either both < 1e-3 or both >= 1e-4 (``to_mitsuba`` floors rough alphas at 1e-4). A
    rough ``masking="correlated"`` model is refused by ``to_mitsuba()`` (Mitsuba cannot express
    the height-correlated form); ``to_mitsuba(approximate=True)`` exports it with a warning and it
    comes back with ``masking="separable"``. Smooth models come back with the default masking
    (a mirror has none). Eta = 1 dielectrics come back as ``Dielectric(1.0)``.

    Parameters
    ----------
    d : dict, mitsuba.BSDF or path
        A plugin dictionary (as ``mi.load_dict`` takes), a loaded Mitsuba BSDF, or a scene file.
    base_dir : str or Path, optional
        Folder of relative ``bitmap`` filenames in a dictionary (a scene file's are relative to it).
    params : dict, optional
        Scene files: values of ``$name`` references (override the file's ``<default>``).
    strict : bool, default False
        Scene files: raise instead of skipping a BSDF with a warning.
    progress : bool or callable, optional
        Scene files: one bar over the BSDFs converted (their bitmaps with them), as
        :func:`bsdfkit.from_pbrt`'s: None (default) shows it on an interactive stderr (a bar in
        Jupyter) once the import has run for a second.

    Returns
    -------
    BxDF or dict
        The equivalent bsdfkit model; for a scene file ``{name: model}``.

    Raises
    ------
    ValueError
        Naming the plugin and parameter for anything else: unknown plugins, textures, Beckmann
        roughness, tints, unknown parameters, presets or IOR names; plugin dicts nested deeper
        than ``MI_MAX_DEPTH``, containing themselves, or expanding to more than
        ``MI_MAX_PLUGINS`` plugins counted once per path.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.from_mitsuba({"type": "roughconductor", "material": "Au", "distribution": "ggx", "alpha": 0.2})
    Conductor(eta=[0.143036, 0.375307, 1.442045], k=[3.982997, 2.385556, 1.603359], alpha_x=0.2, alpha_y=0.2, masking='separable', fresnel='exact', distribution='ggx', sample_visible=True)
    """
    if isinstance(d, os.PathLike) or (isinstance(d, str) and (d.lower().endswith(".xml") or os.path.isfile(d))):
        from ._mitsuba_xml import from_mitsuba_file
        return from_mitsuba_file(d, params=params, strict=strict, progress=progress)
    if not isinstance(d, dict) and type(d).__module__.startswith("mitsuba") and hasattr(d, "class_name"):
        d = _loaded_to_dict(d)
    token = _BASE_DIR.set(None if base_dir is None else os.fspath(base_dir))
    try:
        return _mi_bsdf(d, "")
    finally:
        _BASE_DIR.reset(token)


# Mitsuba class names of loaded BSDFs -> plugin names
_MI_CLASSES = {"SmoothDiffuse": "diffuse", "SmoothConductor": "conductor", "RoughConductor": "roughconductor",
               "SmoothDielectric": "dielectric", "RoughDielectric": "roughdielectric",
               "ThinDielectric": "thindielectric", "Null": "null", "Principled": "principled",
               "PrincipledThin": "principledthin"}


def _unsupported_loaded(cls):
    raise ValueError(f"from_mitsuba: unsupported loaded Mitsuba BSDF {cls!r}; supported: "
                     f"{', '.join(sorted(_MI_CLASSES))} (and TwoSided around one of them)")


def _loaded_to_dict(bsdf) -> dict:
    """A loaded ``mi.BSDF`` as a plugin dictionary (class name + ``mi.traverse`` parameters)."""
    import re
    import mitsuba as mi

    name = bsdf.class_name()
    if not name.startswith("TwoSided") and name not in _MI_CLASSES:
        _unsupported_loaded(name)   # before mi.traverse, which raises a bare TypeError for some (Hair)
    try:
        params = mi.traverse(bsdf)
        vals = {k: params[k] for k in params.keys()}
    except (TypeError, RuntimeError) as e:
        raise ValueError(f"from_mitsuba: cannot read the parameters of the loaded Mitsuba BSDF {name!r} "
                         f"(mi.traverse: {e})") from None
    text = str(bsdf)
    tex = sorted({k.rsplit(".", 1)[0] for k in vals if k.endswith((".data", ".to_uv"))})
    if tex or "BitmapTexture[" in text:
        raise ValueError(f"from_mitsuba: the loaded Mitsuba BSDF {name!r} has bitmap textures ({', '.join(tex)}): a "
                         "loaded bitmap keeps neither its file name nor its filter and wrap modes; pass the plugin "
                         "dict (mi.load_dict's argument) or the scene file instead")
    if name.startswith("TwoSided"):
        kids = re.findall(r"brdf\[(\d)\] = (\w+)\[", text)
        cls = dict(kids).get("0")
        if cls is None:
            raise ValueError(f"from_mitsuba: cannot read the nested BSDF of {name}")
        sub = {k[len("brdf_0."):]: v for k, v in vals.items() if k.startswith("brdf_0.")}
        return {"type": "twosided", "bsdf": _loaded_params_to_dict(cls, sub, text)}
    return _loaded_params_to_dict(name, vals, text)


def _loaded_params_to_dict(cls: str, vals: dict, text: str) -> dict:
    import re

    if cls not in _MI_CLASSES:
        _unsupported_loaded(cls)
    plugin = _MI_CLASSES[cls]
    d = {"type": plugin}

    def val(key):
        v = np.asarray(vals[key], dtype=np.float64).ravel()
        return float(v[0]) if v.size == 1 else [float(x) for x in v]
    known = set()
    for key, v in vals.items():
        base = key[:-len(".value")] if key.endswith(".value") else key
        known.add(key)
        if base == "eta" and plugin in ("dielectric", "roughdielectric", "thindielectric"):
            d["int_ior"], d["ext_ior"] = val(key), 1.0
        else:
            d[base] = val(key)
    if plugin in ("conductor", "roughconductor") and np.all(np.asarray(d.get("eta", 1.0)) == 0) \
            and np.all(np.asarray(d.get("k", 0.0)) == 1):
        d.pop("eta")
        d.pop("k")
        d["material"] = "none"  # Mitsuba's default perfect mirror (eta = 0, k = 1)
    if plugin.startswith("rough"):
        m = re.search(r"distribution = (\w+)", text)
        if m:
            d["distribution"] = m.group(1)
        m = re.search(r"sample_visible = (\w+)", text)
        if m:
            d["sample_visible"] = m.group(1) in ("1", "true")
    return d
