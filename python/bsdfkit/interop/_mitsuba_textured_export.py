"""``to_mitsuba`` of textured models (``bsdfkit.models.textured.Textured``): Mitsuba 3 plugin
dictionaries whose textured parameters are ``bitmap`` dicts, for :func:`textured_to_mitsuba`.

Each leaf model is exported by its own ``to_mitsuba`` with its textures replaced by placeholder
constants (so its rules, refusals and warnings apply unchanged), then the placeholders' keys get
the bitmaps; composites are rebuilt here around their children's exports. Exactly what Mitsuba's
``bitmap`` can express is exported, anything else raises naming the reason:

* an image file: ``filename`` (absolute), ``filter_type`` nearest / bilinear, ``wrap_mode``
  repeat / mirror / clamp (one for u and v), ``raw`` from the texture's encoding and the file
  format (Mitsuba sRGB-decodes PNG / JPEG unless raw, reads EXR linear), ``to_uv``;
* an array: its decoded linear values written as a float EXR into ``texture_dir`` (named by
  content), else an in-memory ``data`` tensor (needs the ``mitsuba`` package; such a dict loads
  in this process only);
* ``scale``, ``invert``, ``channel`` of a multi-channel image, other filters, the ``black`` wrap,
  ``gamma`` encodings and procedural textures (but ``Constant``) are refused;
* a float parameter given through :class:`~bsdfkit.interop._mitsuba_texture.Luminance` exports its
  RGB bitmap (Mitsuba's ``eval_1`` is that luminance); ``tx.Normals`` of a normal map its RGB
  bitmap; a BumpMap's ``HeightGradient`` pair its height bitmap.
"""
from __future__ import annotations

import os

import numpy as np

from .. import textures as tx
from ..models import BumpMap, Conductor, Dielectric, Diffuse, Mask, Mix, NormalMap, Plastic, TwoSided
from ..models import _mitsuba_export as _me
from ..models.textured import Textured
from . import _mitsuba_texture as mt

__all__ = ["textured_to_mitsuba"]

_WRAPS = {"periodic": "repeat", "mirror": "mirror", "clamp": "clamp"}

#: leaf classes: {argument: (Mitsuba key(s) of the plugin, channels)}; arguments absent here that
#: hold a texture are refused (Mitsuba takes a float there).
_LEAF_KEYS = {
    Diffuse: {"reflectance": (("reflectance",), 3)},
    Conductor: {"eta": (("eta",), 3), "k": (("k",), 3), "alpha": (("alpha",), 1),
                "alpha_x": (("alpha_u",), 1), "alpha_y": (("alpha_v",), 1)},
    Dielectric: {"alpha": (("alpha",), 1), "alpha_x": (("alpha_u",), 1), "alpha_y": (("alpha_v",), 1)},
    Plastic: {"reflectance": (("diffuse_reflectance",), 3), "specular_reflectance": (("specular_reflectance",), 3)},
}
_WHY_FLOAT = {(Dielectric, "eta"): "Mitsuba's int_ior is a float", (Plastic, "eta"): "Mitsuba's int_ior is a float",
              (Plastic, "alpha"): "Mitsuba's roughplastic alpha is a float"}


class _Ctx:
    def __init__(self, texture_dir, approximate, plain=False):
        self.dir, self.approximate, self.plain = texture_dir, approximate, plain


class PlainTransform:
    """A to_uv transform for the XML writer (``.matrix``: 4x4), where no Mitsuba variant is needed."""

    def __init__(self, matrix):
        self.matrix = matrix


def _name(m):
    return m.model_class.__name__ if isinstance(m, Textured) else type(m).__name__


def _refuse(where, why):
    raise NotImplementedError(f"{where}.to_mitsuba: {why}")


def _mi():
    try:
        import mitsuba as mi
    except ImportError:
        return None
    return mi


def _to_uv(m, where, ctx):
    a = np.eye(4)
    a[np.ix_([0, 1, 3], [0, 1, 3])] = np.vstack([m, [0.0, 0.0, 1.0]])   # Mitsuba reads rows/columns 0, 1, 3
    if ctx.plain:
        return PlainTransform(a)
    mi = _mi()
    if mi is None or not mi.variant():
        _refuse(where, "a texture transform becomes Mitsuba's to_uv, an mi.ScalarTransform4f: install the mitsuba "
                "package and select a variant (mi.set_variant)")
    return mi.ScalarTransform4f(a)


def _array_bitmap(px, where, ctx):
    """Linear float texels (H, W, C) as a bitmap source: an EXR in ctx.dir, else a data tensor."""
    px = np.ascontiguousarray(px, dtype=np.float32)
    if px.ndim == 2:
        px = px[..., None]
    if ctx.dir is not None:
        from .. import _render_ext
        from .._values import digest
        os.makedirs(ctx.dir, exist_ok=True)
        path = os.path.abspath(os.path.join(os.fspath(ctx.dir), f"bsdfkit-{digest(px)}.exr"))
        if not os.path.exists(path):
            _render_ext.load().write_image(path, px)
        return {"filename": path, "raw": True}
    mi = _mi()
    if mi is None:
        _refuse(where, "a texture built from an array needs texture_dir= (its texels are written there as an EXR "
                "file) or the mitsuba package (an in-memory data tensor)")
    if not mi.variant():
        _refuse(where, "a texture built from an array becomes an in-memory mi.TensorXf: select a Mitsuba variant "
                "first (mi.set_variant), or give texture_dir= to write its texels as an EXR file")
    return {"data": mi.TensorXf(px), "raw": True}


def _image_bitmap(t, where, ctx):
    """A ``tx.Texture`` -> a Mitsuba ``bitmap`` dict."""
    if t.scale != 1.0 or t.invert:
        _refuse(where, f"{t!r}: Mitsuba's bitmap has no scale or invert")
    if t.filter not in ("nearest", "bilinear"):
        _refuse(where, f"{t!r}: Mitsuba's bitmap filters are nearest and bilinear, not {t.filter!r}")
    if not isinstance(t.wrap, str) or t.wrap not in _WRAPS:
        _refuse(where, f"{t!r}: Mitsuba's bitmap wraps are repeat (periodic), mirror and clamp, one for u and v; "
                f"not {t.wrap!r}")
    d = {"type": "bitmap", "filter_type": t.filter, "wrap_mode": _WRAPS[t.wrap]}
    src = t.source
    if t.channel is not None and isinstance(src, str):
        _refuse(where, f"{t!r}: channel={t.channel} of an image file: Mitsuba's bitmap has no channel selection (a "
                "float parameter takes the RGB's luminance); build the texture from the channel's array instead")
    if isinstance(src, str):
        ext = os.path.splitext(src)[1].lower()
        dec = t._decode
        if ext in mt.MI_SRGB_EXTENSIONS:
            if dec == "sRGB":
                raw = False
            elif dec == "linear":
                raw = True
            else:
                _refuse(where, f"{t!r}: Mitsuba decodes {ext} files as sRGB (or not at all, raw), not {dec!r}")
        elif ext in mt.MI_LINEAR_EXTENSIONS:
            if dec != "linear":
                _refuse(where, f"{t!r}: Mitsuba reads {ext} files as linear, not {dec!r}")
            raw = t.encoding == "linear"   # the same in RGB variants; "auto" comes back as auto
        else:
            _refuse(where, f"{t!r}: Mitsuba's decoding of {ext!r} files is not known here (PNG, JPEG, EXR, HDR, PFM "
                    "are)")
        d.update(filename=os.path.abspath(src), raw=raw)
    else:
        a = np.asarray(src)
        px = a.astype(np.float64) / float(np.iinfo(a.dtype).max) if a.dtype.kind in "ui" else a.astype(np.float64)
        px = tx._decode(px, t._decode)
        if t.channel is not None:
            px = px[..., t.channel:t.channel + 1]
        d.update(_array_bitmap(px, where, ctx))
    if t.transform is not None:
        d["to_uv"] = _to_uv(t.transform, where, ctx)
    return d


def _texture_value(v, where, channels, ctx):
    """A texture (or a constant) as a Mitsuba value for a parameter of ``channels``."""
    if isinstance(v, tx.Constant):
        val = np.asarray(v.value, np.float64).reshape(-1)
        if channels == 1:
            if val.size != 1:
                _refuse(where, f"{v!r}: an RGB constant for a float parameter")
            return float(val[0])
        return {"type": "rgb", "value": [float(x) for x in np.broadcast_to(val, (3,))]}
    if isinstance(v, mt.Luminance):
        if channels != 1:
            _refuse(where, f"{v!r}: a luminance texture for a colour parameter")
        return _image_bitmap(v.tex, where, ctx)
    if isinstance(v, tx.Checkerboard) and channels == 3:
        if not (isinstance(v.tex1, tx.Constant) and isinstance(v.tex2, tx.Constant)):
            _refuse(where, f"{v!r}: Mitsuba's checkerboard takes constant colours here")
        # Mitsuba: color0 where floor(2u') + floor(2v') is even, uv' = to_uv(uv) (see _mitsuba_texture)
        m = np.array([[v.uscale / 2, 0.0, v.udelta / 2], [0.0, v.vscale / 2, v.vdelta / 2]])
        d = {"type": "checkerboard", "color0": _texture_value(v.tex1, where, 3, ctx),
             "color1": _texture_value(v.tex2, where, 3, ctx)}
        if not np.array_equal(m, np.eye(3)[:2]):
            d["to_uv"] = _to_uv(m, where, ctx)
        return d
    if isinstance(v, tx.Texture):
        if channels == 1 and v.channels != 1:
            _refuse(where, f"{v!r}: a {v.channels}-channel texture for a float parameter")
        return _image_bitmap(v, where, ctx)
    _refuse(where, f"{type(v).__name__} textures have no Mitsuba bitmap ({v!r}); image textures (bk.Texture) and "
            "constants do")


def _is_tex(v):
    return isinstance(v, (tx.TextureBase, Textured))


# ------------------------------------------------------------------------------------------ leaves

def _placeholder(kind):
    return np.full(3, 0.5) if kind == 3 else 0.25


def _leaf(m, ctx):
    cls, p = m.model_class, m._params
    name = cls.__name__
    keys = _LEAF_KEYS.get(cls)
    if keys is None:
        _refuse(name, f"textured parameters ({', '.join(m.textures)}): Mitsuba export of a textured {name} is not "
                "supported (textured Diffuse, Conductor, Dielectric, Plastic and the composites are)")
    tex = {k: v for k, v in p.items() if _is_tex(v)}
    for k in tex:
        if k not in keys:
            _refuse(name, f"{k!r} is textured: " + _WHY_FLOAT.get((cls, k), f"Mitsuba's {name} takes no texture there"))
    kinds = cls.varying_params
    args, kwargs = m._call
    names = list(p)
    a = [_placeholder(kinds.get(names[i], 1)) if i < len(names) and names[i] in tex else v for i, v in enumerate(args)]
    kw = {k: (_placeholder(kinds.get(k, 1)) if k in tex else v) for k, v in kwargs.items()}
    d = cls(*a, **kw).to_mitsuba(approximate=ctx.approximate)
    inner = d["bsdf"] if d.get("type") == "twosided" and "bsdf" in d else d
    for k, v in tex.items():
        (key,), ch = keys[k]
        inner[key] = _texture_value(v, f"{name}({k}=...)", ch, ctx)
        if key == "alpha":
            inner.pop("alpha_u", None)
            inner.pop("alpha_v", None)
    return d


# -------------------------------------------------------------------------------------- composites

def _scalar_or_texture(v, where, ctx, lo=0.0, hi=1.0):
    if isinstance(v, mt.Clip01):   # Mitsuba clips blendbsdf's weight and mask's opacity itself
        v = v.tex
    if _is_tex(v):
        return _texture_value(v, where, 1, ctx)
    if isinstance(v, np.ndarray) and v.ndim:
        _refuse(where, "a per-element array has no Mitsuba dictionary (Mitsuba takes a texture at uv)")
    return float(v)


def _export(m, ctx):
    if not isinstance(m, Textured):
        return m.to_mitsuba(approximate=ctx.approximate)
    cls, p = m.model_class, m._params
    if cls is Mix:
        method = p.get("method", "linear")
        if method == "stochastic":
            why = ("Mitsuba 3 has no per-point choice (pbrt-v4 MixMaterial); blendbsdf is its expectation, the linear "
                   "blend")
            if not ctx.approximate:
                raise _me.MitsubaExportError(f"Mix.to_mitsuba: {why}; to_mitsuba(approximate=True) exports the linear "
                                             "blend with a warning")
            import warnings
            warnings.warn(f"Mix.to_mitsuba(approximate=True): exported a different material: {why}",
                          _me.MitsubaApproximationWarning, stacklevel=4)
        return {"type": "blendbsdf", "weight": _scalar_or_texture(p.get("weight", 0.5), "Mix(weight=...)", ctx),
                "bsdf_0": _export(p["a"], ctx), "bsdf_1": _export(p["b"], ctx)}
    if cls is Mask:
        return {"type": "mask", "opacity": _scalar_or_texture(p.get("opacity", 0.5), "Mask(opacity=...)", ctx),
                "material": _export(p["model"], ctx)}
    if cls is TwoSided:
        from .._enums import BxDFFlags
        sides = [("front", p["front"]), ("back", p.get("back"))]
        for side, c in sides:
            if c is not None and c.flags & BxDFFlags.Transmission:
                raise ValueError(f"TwoSided.to_mitsuba: {side} transmits; Mitsuba's twosided refuses transmitting "
                                 "BSDFs (bsdfkit's TwoSided leaves the transmission out)")

        def one(c):
            d = _export(c, ctx)
            if d.get("type") == "twosided" and "bsdf" in d and len(d) == 2:
                d = d["bsdf"]
            return d
        if p.get("back") is None:
            return {"type": "twosided", "bsdf": one(p["front"])}
        return {"type": "twosided", "bsdf_0": one(p["front"]), "bsdf_1": one(p["back"])}
    if cls is NormalMap:
        n = p.get("normals")
        if p.get("convention", "opengl") != "opengl" and _is_tex(n):
            _refuse("NormalMap", "a textured DirectX normal map (y negated) has no Mitsuba bitmap; flip the image's "
                    "green channel")
        if _is_tex(n):
            if not isinstance(n, tx.Normals):
                _refuse("NormalMap", f"normals={n!r}: Mitsuba's normalmap decodes 2 rgb - 1 of a bitmap; give "
                        "tx.Normals(bk.Texture(image)) (what from_mitsuba builds)")
            nm = _texture_value(n.tex, "NormalMap(normals=...)", 3, ctx)
        else:
            twin = NormalMap(Diffuse(0.5), n, p.get("convention", "opengl"))
            nm = twin.to_mitsuba()["normalmap"]
        return {"type": "normalmap", "normalmap": nm,
                "flip_invalid_normals": bool(p.get("flip_invalid_normals", True)),
                "use_shadowing_function": bool(p.get("shadowing", True)), "bsdf": _export(p["model"], ctx)}
    if cls is BumpMap:
        return _bumpmap(p, ctx)
    return _leaf(m, ctx)


def _bumpmap(p, ctx):
    if p.get("dp_du") is not None or p.get("dp_dv") is not None:
        _refuse("BumpMap", "dp_du / dp_dv are the mesh's in Mitsuba (not BSDF parameters)")
    du, dv, scale = p.get("dh_du", 0.0), p.get("dh_dv", 0.0), p.get("scale", 1.0)
    if _is_tex(scale):
        _refuse("BumpMap", "a textured scale: Mitsuba's bumpmap scale is a float")
    ok = (isinstance(du, mt.HeightGradient) and isinstance(dv, mt.HeightGradient) and du.axis == 0 and dv.axis == 1
          and du.wrap_mode == dv.wrap_mode and np.array_equal(du.height, dv.height)
          and (du.transform is None) == (dv.transform is None)
          and (du.transform is None or np.array_equal(du.transform, dv.transform)))
    if not ok:
        _refuse("BumpMap", "Mitsuba's bumpmap differentiates a height bitmap: export needs dh_du, dh_dv to be the "
                "HeightGradient pair of one height image (what from_mitsuba builds)")
    h = _array_bitmap(du.height[..., None], "BumpMap(height)", ctx)
    height = {"type": "bitmap", "filter_type": "bilinear", "wrap_mode": du.wrap_mode, **h}
    if du.transform is not None:
        height["to_uv"] = _to_uv(du.transform, "BumpMap", ctx)
    return {"type": "bumpmap", "height": height, "scale": float(scale),
            "flip_invalid_normals": bool(p.get("flip_invalid_normals", True)),
            "use_shadowing_function": bool(p.get("shadowing", True)), "bsdf": _export(p["model"], ctx)}


def textured_to_mitsuba(model, approximate: bool = False, texture_dir=None, *, _plain=False) -> dict:
    """The Mitsuba 3 plugin dictionary of a textured model (its textures as ``bitmap`` dicts; see
    the module docstring for what is exported and what is refused). ``texture_dir``: where the
    texels of textures built from arrays are written (EXR files named by content); without it they
    become in-memory ``data`` tensors (the ``mitsuba`` package is needed, and the dict loads in
    this process only). Untextured models are exported by their own ``to_mitsuba``."""
    approximate = _me.check_approximate(approximate)
    return _export(model, _Ctx(texture_dir, approximate, _plain))
