"""pbrt-v4 ``Texture`` statements -> bsdfkit textures (``bk.Texture``, ``bsdfkit.textures``), following
pbrt-v4's ``src/pbrt/textures.cpp``, and the texture-valued parameters of materials.

Classes: ``imagemap`` (filename relative to the scene file's directory, filter, wrap, encoding,
scale, invert), ``constant``, ``scale``, ``mix`` and 2-D ``checkerboard``, with the ``uv`` mapping
(uscale, vscale, udelta, vdelta). Other classes (``ptex``, ``marble``, ``fbm``, ``wrinkled``,
``windy``, ``dots``, ``bilerp``, ``directionmix``, 3-D checkerboards, non-uv mappings) are refused
naming the class and the line. A material parameter ``"texture <name>" "<tex>"`` is the float or
spectrum texture of that name, by the parameter's type in pbrt-v4 (``roughness`` float,
``reflectance`` spectrum, ...); :class:`PbrtLookup` applies the per-lookup arithmetic pbrt-v4's
materials do to texture values (clamps, roughness remapping, the conductor's k from a reflectance).
"""
from __future__ import annotations

import math
import os

import numpy as np

from ...textures import Checkerboard, Constant, Mix, Scale, Texture, TextureBase
from .parser import _PbrtError
from .values import (_bool_param, _check_texture, _float_param, _int_param, _pfail, _pfail_param, _spectrum_param,
                     scene_file)

__all__ = ["PbrtLookup", "PBRT_TEXTURE_CLASSES"]

#: Texture classes converted (pbrt-v4 textures.cpp); the others are refused by name.
PBRT_TEXTURE_CLASSES = ("imagemap", "constant", "scale", "mix", "checkerboard")

# pbrt-v4 TextureMapping2D::Create: uv (uscale, vscale, udelta, vdelta); planar also v1, v2
_MAPPING = ("mapping", "uscale", "vscale", "udelta", "vdelta", "v1", "v2")
_PARAMS = {
    "imagemap": ("filename", "filter", "wrap", "encoding", "scale", "invert", "maxanisotropy") + _MAPPING,
    "constant": ("value",),
    "scale": ("tex", "scale"),
    "mix": ("tex1", "tex2", "amount"),
    "checkerboard": ("tex1", "tex2", "dimension", "aamode") + _MAPPING,
}
# pbrt-v4 imagemap "filter" -> bk.Texture filter (EWA: OpenImageIO's anisotropic filter stands in)
_FILTERS = {"point": "nearest", "bilinear": "bilinear", "trilinear": "trilinear", "ewa": "anisotropic"}
_WRAPS = {"repeat": "periodic", "black": "black", "clamp": "clamp"}
# image formats pbrt-v4 reads as floats (Image::Read), where "encoding" does not apply
_FLOAT_FORMATS = (".exr", ".pfm", ".hdr")


def _clamp01(v):
    return np.clip(v, 0.0, 1.0)


def _remap(v):
    # pbrt-v4 TrowbridgeReitzDistribution::RoughnessToAlpha: sqrt (negative values: 0, not NaN)
    return np.sqrt(np.maximum(v, 0.0))


def _conductor_k(v):
    # pbrt-v4 ConductorMaterial: r = clamp(reflectance, 0, 0.9999); k = 2 sqrt(r) / sqrt(1 - r)
    r = np.clip(v, 0.0, 0.9999)
    return 2 * np.sqrt(r) / np.sqrt(1 - r)


def _rgb(v):
    return np.ascontiguousarray(v[..., :3])


def _normal(v):
    # pbrt-v4 NormalMap(): ns = normalize(2 rgb - 1) in the (dp/du, n) frame; SetShadingGeometry
    # then turns a normal below the surface to the geometric normal's side (FaceForward: -ns).
    # bk.NormalMap needs z > 0: z of a texel in the tangent plane is raised to 1e-3 first.
    n = 2 * v[..., :3] - 1
    n = np.where(n[..., 2:] < 0, -n, n)
    n[..., 2] = np.maximum(n[..., 2], 1e-3)
    return n / np.sqrt(n[..., 0] ** 2 + n[..., 1] ** 2 + n[..., 2] ** 2)[..., None]


_OPS = {"clamp01": (_clamp01, None), "remap_roughness": (_remap, None), "conductor_k": (_conductor_k, None),
        "rgb": (_rgb, 3), "normal": (_normal, 3)}


class PbrtLookup(TextureBase):
    """A texture's values through one of the per-lookup operations of pbrt-v4's materials:
    ``"clamp01"`` (reflectances and albedos: Clamp(v, 0, 1)), ``"remap_roughness"`` (sqrt, pbrt's
    RoughnessToAlpha), ``"conductor_k"`` (2 sqrt(r) / sqrt(1 - r) of r clamped to [0, 0.9999]: the
    conductor's k of a reflectance, eta 1), ``"rgb"`` (the first three channels of an RGBA image),
    ``"normal"`` (a normal map's normalize(2 rgb - 1), turned to z > 0 as pbrt-v4's
    FaceForward does; a texel in the tangent plane gets z = 1e-3 before the normalization), or ``"clamp"`` with
    ``bounds`` (lo, hi)."""

    def __init__(self, op, tex, bounds=None):
        if op not in _OPS and op != "clamp":
            raise ValueError(f"op: expected one of {sorted(_OPS) + ['clamp']}, got {op!r}")
        if not isinstance(tex, TextureBase):
            raise TypeError(f"tex: expected a texture, got {type(tex).__name__}")
        if (op == "clamp") != (bounds is not None):
            raise ValueError("bounds: give them with op 'clamp' only")
        object.__setattr__(self, "op", op)
        object.__setattr__(self, "tex", tex)
        object.__setattr__(self, "bounds", None if bounds is None else (float(bounds[0]), float(bounds[1])))
        ch = _OPS[op][1] if op in _OPS else None
        object.__setattr__(self, "channels", tex.channels if ch is None else ch)

    def _args(self):
        a = {"op": self.op, "tex": self.tex}
        if self.bounds is not None:
            a["bounds"] = self.bounds
        return a

    def _lookup(self, uv, dx, dy):
        v = self.tex._lookup(uv, dx, dy)
        if self.op == "clamp":
            return np.clip(v, *self.bounds)
        return _OPS[self.op][0](v)


def lookup_op(op, v, bounds=None):
    """``op`` of :class:`PbrtLookup` on a texture (a PbrtLookup) or on constant values (applied now)."""
    if isinstance(v, TextureBase):
        return PbrtLookup(op, v, bounds)
    if v is None:
        return None
    a = np.asarray(v, dtype=np.float64)
    out = np.clip(a, *bounds) if op == "clamp" else _OPS[op][0](a)
    return float(out) if out.ndim == 0 else out


def is_texture(v) -> bool:
    return isinstance(v, TextureBase)


# ---- material parameters that may be textures
def spectrum_value(rec, pname, *, albedo, ctx):
    """A spectrum-valued parameter: RGB (3,) / Spectrum as ``_spectrum_param``, or the spectrum
    texture it names (clamped to [0, 1] for a reflectance / albedo, as pbrt-v4's materials
    clamp them); None if absent."""
    p = rec.params.get(pname)
    if p is not None and p.type == "texture":
        t = resolve(rec, p, "spectrum", ctx)
        return PbrtLookup("clamp01", t) if albedo else t
    return _spectrum_param(rec, pname, albedo=albedo, ctx=ctx)


def float_value(rec, pname, default, ctx):
    """A float-valued parameter: a float, or the float texture it names; ``default`` if absent."""
    p = rec.params.get(pname)
    if p is not None and p.type == "texture":
        return resolve(rec, p, "float", ctx)
    return _float_param(rec, pname, default)


def resolve(rec, p, kind, ctx):
    """The bsdfkit texture of the ``kind`` ("float" | "spectrum") texture that parameter ``p`` of
    ``rec`` names (converted once per scene: ``ctx["tex_cache"]``)."""
    if len(p.values) != 1 or not isinstance(p.values[0], str):
        _pfail_param(rec, p, f"expected one texture name, got {list(p.values)!r}")
    name = p.values[0]
    key = (kind, name)
    cache, stack = ctx.setdefault("tex_cache", {}), ctx.setdefault("tex_stack", [])
    if key in cache:
        got = cache[key]
        if isinstance(got, Exception):
            _pfail_param(rec, p, str(got))   # names the texture, its class and line
        return got
    trec = (ctx.get("textures") or {}).get(key)
    if trec is None:
        other = "spectrum" if kind == "float" else "float"
        hint = (f" (there is a {other} texture {name!r}; pbrt-v4 takes a {kind} texture here)"
                if (other, name) in (ctx.get("textures") or {}) else "")
        _pfail_param(rec, p, f"no {kind} texture named {name!r} is defined{hint}")
    if key in stack:
        cycle = " -> ".join(n for _, n in stack[stack.index(key):] + [key])
        _pfail_param(rec, p, f"textures refer to each other in a cycle ({cycle})")
    stack.append(key)
    try:
        tex = _build(trec, ctx)
    except ValueError as e:
        cache[key] = e
        _pfail_param(rec, p, str(e))   # "pbrt texture 'name' (float imagemap, line n): ..."
    finally:
        stack.pop()
    cache[key] = tex
    return tex


def _tex_param(trec, pname, default, ctx, kind=None):
    """A parameter of a texture that may itself be a texture: a texture, or a Constant."""
    kind = kind or trec.type
    p = trec.params.get(pname)
    if p is None:
        return Constant(default)
    if p.type == "texture":
        return resolve(trec, p, kind, ctx)
    if kind == "float":
        return Constant(_float_param(trec, pname, default))
    v = _spectrum_param(trec, pname, albedo=False, ctx={"base": ctx.get("base")})
    return Constant(v)


def _build(trec, ctx):
    cls = trec.cls
    if cls not in _PARAMS:
        _pfail(trec, f"unsupported texture class {cls!r} (bsdfkit converts {', '.join(PBRT_TEXTURE_CLASSES)})")
    for p in trec.params.values():
        if p.name not in _PARAMS[cls]:
            _pfail_param(trec, p, f"not a parameter of pbrt-v4's {cls} texture; it takes {', '.join(_PARAMS[cls])}")
    try:
        if cls == "constant":
            return _tex_param(trec, "value", 1.0, ctx)
        if cls == "scale":
            return Scale(_tex_param(trec, "tex", 1.0, ctx), _tex_param(trec, "scale", 1.0, ctx, "float"))
        if cls == "mix":
            return Mix(_tex_param(trec, "tex1", 0.0, ctx), _tex_param(trec, "tex2", 1.0, ctx),
                       _tex_param(trec, "amount", 0.5, ctx, "float"))
        if cls == "checkerboard":
            dim = _int_param(trec, "dimension", 2)
            if dim != 2:
                _pfail_param(trec, trec.params["dimension"], f"a {dim}-D checkerboard is not supported (2-D only)")
            su, sv, du, dv = _uv_mapping(trec)
            return Checkerboard(_tex_param(trec, "tex1", 1.0, ctx), _tex_param(trec, "tex2", 0.0, ctx),
                                uscale=su, vscale=sv, udelta=du, vdelta=dv)
        return _imagemap(trec, ctx)
    except _PbrtError:
        raise
    except (TypeError, ValueError) as e:
        _pfail(trec, str(e))


def _string(rec, pname, default):
    p = rec.params.get(pname)
    if p is None:
        return default
    _check_texture(rec, p)
    if p.type != "string" or len(p.values) != 1 or not isinstance(p.values[0], str):
        _pfail_param(rec, p, f"expected one \"string {pname}\", got {p.type!r} {list(p.values)!r}")
    return p.values[0]


def _uv_mapping(trec):
    """(uscale, vscale, udelta, vdelta) of pbrt-v4's ``uv`` mapping (TexCoord2D st = (su u + du, sv v + dv))."""
    mapping = _string(trec, "mapping", "uv")
    if mapping != "uv":
        _pfail_param(trec, trec.params["mapping"], f"the {mapping!r} mapping is not supported (uv only: bsdfkit "
                     "textures are looked up at uv, and pbrt's planar / spherical / cylindrical mappings take the "
                     "3-D point)")
    out = tuple(_float_param(trec, n, d) for n, d in (("uscale", 1.0), ("vscale", 1.0), ("udelta", 0.0),
                                                      ("vdelta", 0.0)))
    for n, v in zip(("uscale", "vscale", "udelta", "vdelta"), out):
        if not math.isfinite(v):
            _pfail_param(trec, trec.params[n], f"must be finite, got {v}")
    return out


def image_path(rec, p, name, ctx):
    """The image file ``name`` of parameter ``p``, relative to the scene file's directory (pbrt-v4's
    search directory; the working directory for text); a missing file names the path and the line."""
    return scene_file(rec, p, name, ctx, lambda f: f"no image file {f!r}")


def _imagemap(trec, ctx):
    """pbrt-v4 ``imagemap``: bk.Texture of the file with pbrt's v flip and uv mapping as its transform
    (pbrt-v4 looks up st = (su u + du, 1 - (sv v + dv)), its images' first row at the top), filter,
    wrap, encoding (default sRGB for .png files, linear otherwise, as pbrt-v4; float images (.exr,
    .pfm, .hdr) are linear whatever it says), scale and invert;
    a float texture reads the image's channel 0 (pbrt-v4 MIPMap texel<Float>), a spectrum texture
    the first three channels."""
    p = trec.params.get("filename")
    fname = _string(trec, "filename", None)
    if not fname:
        _pfail(trec, "needs a \"string filename\" (the image)")
    path = image_path(trec, p, fname, ctx)
    filt = _string(trec, "filter", "bilinear")
    if filt not in _FILTERS:
        _pfail_param(trec, trec.params["filter"], f"expected one of {', '.join(_FILTERS)}, got {filt!r}")
    wrap = _string(trec, "wrap", "repeat")
    if wrap not in _WRAPS:
        what = "is not supported" if wrap == "octahedralsphere" else "is not a pbrt-v4 wrap mode"
        _pfail_param(trec, trec.params["wrap"], f"{wrap!r} {what} (repeat, black, clamp)")
    enc = _string(trec, "encoding", "sRGB" if fname.lower().endswith(".png") else "linear")
    if os.path.splitext(fname)[1].lower() in _FLOAT_FORMATS:
        enc = "linear"   # pbrt-v4 reads these as float images: the encoding applies to 8-bit ones only
    su, sv, du, dv = _uv_mapping(trec)
    transform = [[su, 0.0, du], [0.0, -sv, 1.0 - dv]]
    scale = _float_param(trec, "scale", 1.0)
    invert = _bool_param(trec, "invert", False)
    try:
        tex = Texture(path, filter=_FILTERS[filt], wrap=_WRAPS[wrap], encoding=enc, scale=scale, invert=invert,
                      channel=0 if trec.type == "float" else None, transform=transform)
    except (OSError, ValueError, TypeError) as e:
        _pfail_param(trec, p, f"{path!r}: {e}")
    if trec.type == "spectrum":
        if tex.channels == 2:
            _pfail_param(trec, p, f"{path!r}: a 2-channel image is not an RGB spectrum texture (pbrt-v4 needs R, G, B)")
        if tex.channels == 4:
            return PbrtLookup("rgb", tex)
    return tex
