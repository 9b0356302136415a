"""Mitsuba 3 composite plugins -> bsdfkit composite models (``from_mitsuba``'s ``twosided``,
``blendbsdf``, ``mask``, ``normalmap`` and ``bumpmap``); ``bsdfkit.interop.mitsuba`` dispatches here."""
from __future__ import annotations

import numpy as np

from .._enums import BxDFFlags
from ..models import BumpMap, Mask, Mix, NormalMap, TwoSided

__all__ = ["mi_twosided", "mi_blend", "mi_mask", "mi_normalmap", "mi_bumpmap", "REFLECTION_ONLY"]

#: One-sided Mitsuba plugins whose bsdfkit model is two-sided already: ``twosided{x}`` of one of
#: them (or of two identical ones) is that model.
REFLECTION_ONLY = ("diffuse", "conductor", "roughconductor", "plastic", "roughplastic")


def _nested(d, where, fail, keys=()):
    """The nested plugin dicts of ``d`` in Mitsuba's order, the dictionary's (measured with Mitsuba
    3.9.1: blendbsdf's first nested BSDF is the one at weight 0 whatever the names; its docs
    still say alphanumeric order), refusing other keys than ``keys``."""
    nested, bad = [], []
    for key, v in d.items():
        if key in ("type", "id", "__line__") or key in keys:
            continue
        if isinstance(v, dict) and "type" in v:
            nested.append((key, v))
        else:
            bad.append(key)
    if bad:
        fail(where, f"unsupported parameters {bad}; {d['type']} takes " + (", ".join(keys) + " and " if keys else "")
             + "nested BSDF dicts")
    return nested


def _shown(key):
    """A nested plugin's key in messages: an unnamed XML child ('_arg_<i>') as '[i]'."""
    return f"[{key[5:]}]" if key.startswith("_arg_") else key


def _constant(v, where, param, fail, to_float):
    if isinstance(v, dict) and not isinstance(v.get("type"), str):
        fail(where, f"parameter {param!r}: the value dict's 'type' must be a string, got "
             f"{type(v.get('type')).__name__}")
    if isinstance(v, dict) and v.get("type") not in ("rgb", "spectrum", "uniform", "srgb", "bitmap"):
        fail(where, f"parameter {param!r} is a texture ({v.get('type')!r}); only a constant or a bitmap is supported "
             "(a per-element array is a bsdfkit parameter: build the model directly)")
    return to_float(v, where, param)


def _clip01(w):
    """Mitsuba clips blendbsdf's weight and mask's opacity to [0, 1] (a texture too: Clip01)."""
    from ._mitsuba_texture import clip01
    return clip01(w)


def mi_twosided(d, where, build, fail):
    nested = _nested(d, where, fail)
    if not nested:
        fail(where, "no nested BSDF dict found")
    if len(nested) > 2:
        fail(where, f"at most two nested BSDFs, got {len(nested)}")
    kinds = [sub.get("type") for _, sub in nested]
    models = [build(sub, f"{where}.{_shown(key)}") for key, sub in nested]
    for (key, sub), m in zip(nested, models):
        if m.flags & BxDFFlags.Transmission:
            fail(where, f"nested plugin {sub.get('type')!r} ({key}) transmits: Mitsuba's twosided refuses "
                 "transmitting BSDFs (only reflection-only ones, e.g. diffuse, roughconductor, roughplastic, "
                 "blendbsdf of them)")
    if all(k in REFLECTION_ONLY for k in kinds) and (len(models) == 1 or models[0] == models[1]):
        return models[0]   # bsdfkit's Diffuse, Conductor and Plastic are two-sided already
    if len(models) == 1 or models[0] == models[1]:
        return TwoSided(models[0])
    return TwoSided(models[0], models[1])


def mi_blend(d, where, build, fail, to_float):
    nested = _nested(d, where, fail, keys=("weight",))
    if len(nested) != 2:
        fail(where, f"blendbsdf takes two nested BSDFs, got {len(nested)}")
    w = _constant(d.get("weight", 0.5), where, "weight", fail, to_float)
    a, b = (build(sub, f"{where}.{_shown(key)}") for key, sub in nested)
    return Mix(a, b, _clip01(w))


def mi_mask(d, where, build, fail, to_float):
    nested = _nested(d, where, fail, keys=("opacity",))
    if len(nested) != 1:
        fail(where, f"mask takes one nested BSDF, got {len(nested)}")
    o = _constant(d.get("opacity", 0.5), where, "opacity", fail, to_float)
    key, sub = nested[0]
    return Mask(build(sub, f"{where}.{_shown(key)}"), _clip01(o))


def mi_normalmap(d, where, build, fail, to_color):
    nested = _nested(d, where, fail, keys=("normalmap", "flip_invalid_normals", "use_shadowing_function"))
    if len(nested) != 1:
        fail(where, f"normalmap takes one nested BSDF, got {len(nested)}")
    if "normalmap" not in d:
        fail(where, "no 'normalmap' texture given")
    v = d["normalmap"]
    if isinstance(v, dict) and not isinstance(v.get("type"), str):
        fail(where, f"parameter 'normalmap': the value dict's 'type' must be a string, got "
             f"{type(v.get('type')).__name__}")
    if isinstance(v, dict) and v["type"] in ("bitmap", "checkerboard"):   # n = normalize(2 rgb - 1), as Mitsuba
        from ..textures import Normals
        from .mitsuba import _mi_texture
        tex = _mi_texture(v, where, "normalmap", 3)
        if tex.channels < 3:
            fail(where, "parameter 'normalmap': a one-channel bitmap holds no normals (give an RGB image)")
        key, sub = nested[0]
        return NormalMap(build(sub, f"{where}.{_shown(key)}"), Normals(tex), **_flags(d, where, fail))
    if isinstance(v, dict) and v.get("type") not in ("rgb", "srgb", "uniform"):
        fail(where, f"parameter 'normalmap' is a texture ({v.get('type')!r}); only a constant rgb normal is supported "
             "(per-element normals: bk.NormalMap(model, normals=array))")
    rgb = to_color(v, where, "normalmap", bounded=False)
    with np.errstate(over="ignore", invalid="ignore"):
        n = 2 * rgb - 1   # Mitsuba's decoding
        norm = np.linalg.norm(n)
    if not np.isfinite(norm):   # inf / nan components, or ones whose square overflows
        fail(where, f"parameter 'normalmap': expected a finite rgb-encoded normal ((n + 1) / 2), got {rgb.tolist()}")
    if not norm > 0:
        fail(where, f"parameter 'normalmap': the decoded normal {n.tolist()} is zero")
    key, sub = nested[0]
    return NormalMap(build(sub, f"{where}.{_shown(key)}"), n / norm, **_flags(d, where, fail))


#: Mitsuba 3 texture plugins (a bumpmap's nested objects are one texture and one BSDF).
_TEXTURES = ("bitmap", "checkerboard", "mesh_attribute", "volume", "uniform", "rgb", "srgb", "spectrum", "d65",
             "blackbody", "regular", "irregular")


def _flags(d, where, fail):
    flags = {}
    for name, kw in (("flip_invalid_normals", "flip_invalid_normals"), ("use_shadowing_function", "shadowing")):
        val = d.get(name, True)
        if not isinstance(val, (bool, np.bool_)):
            fail(where, f"parameter {name!r}: expected True or False, got {val!r}")
        flags[kw] = bool(val)
    return flags


def mi_bumpmap(d, where, build, fail, to_float):
    """``bumpmap`` of a ``bitmap`` height -> ``BumpMap(model, dh_du, dh_dv, scale)`` with the
    gradient textures of the height image (``_mitsuba_texture.HeightGradient``: Mitsuba's bilinear
    ``eval_1_grad`` at each uv; a nearest bitmap's gradient is 0). Other height textures are
    refused: Mitsuba differentiates bitmaps only."""
    from . import _mitsuba_texture as mt
    from .mitsuba import _BASE_DIR
    nested = _nested(d, where, fail, keys=("scale", "flip_invalid_normals", "use_shadowing_function"))
    tex = [(k, v) for k, v in nested if v.get("type") in _TEXTURES]
    bsdfs = [(k, v) for k, v in nested if v.get("type") not in _TEXTURES]
    if len(bsdfs) != 1:
        fail(where, f"bumpmap takes one nested BSDF, got {len(bsdfs)}")
    if len(tex) != 1:
        fail(where, f"bumpmap takes one nested height texture, got {len(tex)}")
    name, t = tex[0]
    kind = t.get("type")
    if kind != "bitmap":
        fail(where, f"height texture {name!r} is a {kind!r} texture: Mitsuba's bumpmap differentiates bitmap textures "
             "only (eval_1_grad); build bk.BumpMap(model, dh_du, dh_dv) with the gradient at each element's uv")
    bm = mt.parse_bitmap(t, f"{where}: height texture {name!r}", _BASE_DIR.get(), fail)
    du, dv = mt.height_gradients(bm, fail)
    scale = to_float(d.get("scale", 1.0), where, "scale")
    key, sub = bsdfs[0]
    return BumpMap(build(sub, f"{where}.{_shown(key)}"), du, dv, scale=scale, **_flags(d, where, fail))
