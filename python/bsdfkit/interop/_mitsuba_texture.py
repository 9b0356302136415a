"""Mitsuba 3 ``bitmap`` (and colour ``checkerboard``) textures -> bsdfkit textures, for
:func:`bsdfkit.from_mitsuba` (the other way: ``_mitsuba_textured_export``).

Mitsuba 3.9's ``bitmap`` (measured with the installed Mitsuba, see tests/test_mitsuba_textures.py):

* uv (0, 0) is the top-left corner of the image as stored: v = 0.1 reads the first row (of a
  4-row image; OpenImageIO's and bsdfkit's convention, no flip); texel centres at (i + 0.5) / W.
* ``filter_type``: "bilinear" (default) or "nearest"; ``wrap_mode``: "repeat" (default),
  "mirror", "clamp".
* ``raw=false`` (default): a file whose format stores sRGB (PNG of 8 or 16 bits, JPEG, ...;
  ``mi.Bitmap.srgb_gamma()``) is sRGB-decoded, EXR / HDR / PFM stay linear; ``raw=true``: no
  decoding. An in-memory ``data`` tensor is linear either way; an ``mi.Bitmap`` is decoded when
  its ``srgb_gamma()`` flag is set and raw is false.
* ``to_uv``: uv' = M (u, v, 1) with M the 3x3 (a 4x4 transform gives its rows and columns 0, 1, 3).
* A float parameter (roughness, a blend weight, an opacity) given an RGB bitmap takes its
  luminance, 0.212671 R + 0.715160 G + 0.072169 B (``eval_1``); a 1-channel bitmap for a colour is
  replicated (``eval_3``).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..textures import TextureBase

__all__ = ["LUMINANCE", "MI_SRGB_EXTENSIONS", "MI_LINEAR_EXTENSIONS", "parse_bitmap", "bitmap_texture",
           "luminance", "height_gradients", "height_texels", "MiBitmap"]

#: Mitsuba 3's ``luminance()`` weights (linear sRGB primaries, CIE Y row).
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])
#: File formats Mitsuba's ``raw=false`` sRGB-decodes (their ``mi.Bitmap`` has srgb_gamma set).
MI_SRGB_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".ppm", ".pgm")
#: File formats Mitsuba reads as linear.
MI_LINEAR_EXTENSIONS = (".exr", ".hdr", ".rgbe", ".pfm")

_FILTERS = {"nearest": "nearest", "bilinear": "bilinear"}
_WRAPS = {"repeat": "periodic", "mirror": "mirror", "clamp": "clamp"}
_KEYS = ("type", "id", "filename", "bitmap", "data", "filter_type", "wrap_mode", "raw", "to_uv", "accel", "format")


class MiBitmap:
    """A parsed Mitsuba ``bitmap``: ``source`` (an absolute path, or a float64 (H, W, C) array of
    linear or sRGB-encoded values per ``encoding``), bsdfkit's ``filter`` / ``wrap`` /
    ``encoding`` names, ``transform`` ((2, 3) or None) and where it was found (for messages)."""

    __slots__ = ("source", "filter", "wrap", "encoding", "transform", "where")

    def __init__(self, source, filter, wrap, encoding, transform, where):
        self.source, self.filter, self.wrap, self.encoding = source, filter, wrap, encoding
        self.transform, self.where = transform, where

    def __repr__(self):
        src = self.source if isinstance(self.source, str) else f"<array {self.source.shape}>"
        return (f"MiBitmap({src!r}, filter={self.filter!r}, wrap={self.wrap!r}, encoding={self.encoding!r}, "
                f"transform={None if self.transform is None else self.transform.tolist()})")


def _matrix(v, where, fail):
    """A Mitsuba to_uv transform (mi.ScalarTransform3f/4f, a 3x3 / 4x4 / 2x3 array) -> (2, 3)."""
    m = getattr(v, "matrix", v)
    try:
        a = np.array(m, dtype=np.float64)
    except (TypeError, ValueError):
        fail(where, f"'to_uv': expected a transform (mi.ScalarTransform3f/4f or a 3x3 matrix), got {type(v).__name__}")
    if a.shape == (4, 4):   # Mitsuba's bitmap: rows and columns 0, 1, 3 of a 4x4 (measured)
        a = a[np.ix_([0, 1, 3], [0, 1, 3])]
    if a.shape == (2, 3):
        a = np.vstack([a, [0.0, 0.0, 1.0]])
    if a.shape != (3, 3):
        fail(where, f"'to_uv': expected a 3x3 (or 4x4) matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        fail(where, f"'to_uv': entries must be finite, got {a.tolist()}")
    if not np.allclose(a[2], [0.0, 0.0, 1.0], rtol=0, atol=1e-12):
        fail(where, f"'to_uv': a projective uv transform (last row {a[2].tolist()}) is not supported; "
             "only affine ones")
    return None if np.array_equal(a[:2], np.eye(3)[:2]) else a[:2].copy()


def _resolve(fn, base_dir, where, fail):
    if not isinstance(fn, (str, os.PathLike)):
        fail(where, f"'filename': expected a path (str), got {type(fn).__name__}")
    p = Path(os.fspath(fn)).expanduser()
    if not p.is_absolute():
        p = Path(base_dir or os.getcwd()) / p
    if not p.is_file():
        raise FileNotFoundError(f"from_mitsuba: {where}: image file not found: {str(p)!r}"
                                + (f" (from {fn!r}, relative to {str(base_dir)!r})" if base_dir else ""))
    return str(p)


def parse_bitmap(d, where, base_dir, fail) -> MiBitmap:
    """A Mitsuba ``bitmap`` dict -> :class:`MiBitmap` (no image read). Relative filenames are
    resolved against ``base_dir`` (the XML file's folder; default the working directory); a
    missing file raises FileNotFoundError naming the path."""
    extra = [k for k in d if k not in _KEYS and k != "__line__"]
    if extra:
        fail(where, f"bitmap: unsupported parameters {extra}; bitmap takes: " + ", ".join(_KEYS[2:]))
    given = [k for k in ("filename", "bitmap", "data") if k in d]
    if len(given) != 1:
        fail(where, f"bitmap: give exactly one of 'filename', 'bitmap', 'data', got {given or 'none'}")
    ft = d.get("filter_type", "bilinear")
    if ft not in _FILTERS:
        fail(where, f"bitmap: filter_type {ft!r} is not one of Mitsuba's {tuple(_FILTERS)}")
    wm = d.get("wrap_mode", "repeat")
    if wm not in _WRAPS:
        fail(where, f"bitmap: wrap_mode {wm!r} is not one of Mitsuba's {tuple(_WRAPS)}")
    raw = d.get("raw", False)
    if not isinstance(raw, (bool, np.bool_)):
        fail(where, f"bitmap: 'raw': expected True or False, got {raw!r}")
    transform = _matrix(d["to_uv"], where, fail) if "to_uv" in d else None
    if "filename" in d:
        path = _resolve(d["filename"], base_dir, where, fail)
        ext = Path(path).suffix.lower()
        if raw:
            enc = "linear"
        elif ext in MI_SRGB_EXTENSIONS + MI_LINEAR_EXTENSIONS:
            enc = "auto"   # bk.Texture's auto: integer (PNG, JPEG) images sRGB, float (EXR, HDR, PFM) linear: Mitsuba's
        else:
            fail(where, f"bitmap {path!r}: Mitsuba's colour decoding of {ext!r} files is not known here; "
                 f"give raw=true (no decoding) or a {'/'.join(MI_SRGB_EXTENSIONS + MI_LINEAR_EXTENSIONS)} file")
        return MiBitmap(path, _FILTERS[ft], _WRAPS[wm], enc, transform, where)
    if "data" in d:   # a tensor: linear whatever raw says (measured)
        a, enc = _array(d["data"], where, "data", fail), "linear"
    else:
        b = d["bitmap"]
        srgb = bool(b.srgb_gamma()) if hasattr(b, "srgb_gamma") else False
        a = _array(b, where, "bitmap", fail)
        enc = "sRGB" if srgb and not raw else "linear"
    return MiBitmap(a, _FILTERS[ft], _WRAPS[wm], enc, transform, where)


def _array(v, where, key, fail):
    try:
        a = np.array(v)
    except Exception as e:
        fail(where, f"bitmap: cannot read '{key}' as an array ({type(e).__name__}: {e})")
    if a.dtype == np.uint8:
        a = a.astype(np.float64) / 255.0
    elif a.dtype == np.uint16:
        a = a.astype(np.float64) / 65535.0
    try:
        a = a.astype(np.float64)
    except (TypeError, ValueError):
        fail(where, f"bitmap: '{key}' is not numeric (dtype {a.dtype})")
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or a.shape[0] == 0 or a.shape[1] == 0 or a.shape[2] not in (1, 3):
        fail(where, f"bitmap: '{key}' must be (H, W), (H, W, 1) or (H, W, 3), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        fail(where, f"bitmap: '{key}' holds non-finite texels")
    return a


class Luminance(TextureBase):
    """Mitsuba's ``eval_1`` of an RGB bitmap: 0.212671 R + 0.715160 G + 0.072169 B of the
    filtered linear RGB (a linear map: the same as filtering the luminance)."""

    channels = 1

    def __init__(self, tex):
        if not isinstance(tex, TextureBase) or tex.channels < 3:
            raise ValueError(f"tex: expected a texture of 3 (or 4) channels, got {tex!r}")
        object.__setattr__(self, "tex", tex)

    def _args(self):
        return {"tex": self.tex}

    def _lookup(self, uv, dx, dy):
        return (self.tex._lookup(uv, dx, dy)[..., :3] @ LUMINANCE)[..., None]


class Clip01(TextureBase):
    """A float texture clipped to [0, 1], as Mitsuba's blendbsdf and mask clip their weight and
    opacity (``dr::clip(eval_1(si), 0, 1)``)."""

    channels = 1

    def __init__(self, tex):
        if not isinstance(tex, TextureBase) or tex.channels != 1:
            raise ValueError(f"tex: expected a 1-channel texture, got {tex!r}")
        object.__setattr__(self, "tex", tex)

    def _args(self):
        return {"tex": self.tex}

    def _lookup(self, uv, dx, dy):
        return np.clip(self.tex._lookup(uv, dx, dy), 0.0, 1.0)


def _in_unit(tex) -> bool:
    """Whether a texture's values are known to lie in [0, 1] (integer images, arrays in range)."""
    from ..textures import Texture
    if isinstance(tex, Luminance):
        return _in_unit(tex.tex)
    if not isinstance(tex, Texture) or tex.scale != 1.0 or tex.invert:
        return False
    if isinstance(tex.source, str):
        from .. import _render_ext
        return _render_ext.load().image_info(tex.source)[3] in ("uint8", "uint16")
    a = tex.source
    return bool(a.dtype.kind == "u" or (a.size and a.min() >= 0 and a.max() <= 1))


def clip01(w):
    """Mitsuba's clip of a blend weight / opacity to [0, 1]: a float clipped, a texture wrapped in
    :class:`Clip01` unless its values are known to lie in [0, 1]."""
    if isinstance(w, float):
        return float(np.clip(w, 0.0, 1.0))
    return w if _in_unit(w) else Clip01(w)


def luminance(tex):
    """The :class:`Luminance` texture of an RGB(A) texture (Mitsuba's ``eval_1`` of it)."""
    return Luminance(tex)


def bitmap_texture(bm: MiBitmap, channels: int, fail):
    """The texture of a parsed bitmap for a parameter of ``channels`` (1: a float, 3: a colour):
    a ``bk.Texture``, wrapped in :func:`luminance` for a float parameter given an RGB(A) bitmap
    (Mitsuba's ``eval_1``). A 1-channel bitmap for a colour is replicated by the model; an RGBA
    one for a colour gives its RGB (Mitsuba drops the alpha too)."""
    from ..textures import Texture
    kw = dict(filter=bm.filter, wrap=bm.wrap, transform=bm.transform, encoding=bm.encoding)
    try:
        t = Texture(bm.source, **kw)
    except FileNotFoundError:
        raise
    except (ValueError, TypeError, OSError, RuntimeError) as e:
        fail(bm.where, f"bitmap {bm.source if isinstance(bm.source, str) else 'data'}: {e}")
    if t.channels not in (1, 3, 4):
        fail(bm.where, f"bitmap has {t.channels} channels; Mitsuba reads 1 (Y), 3 (RGB) or 4 (RGBA)")
    if channels == 1 and t.channels != 1:
        return luminance(t)
    return t


def height_texels(bm: MiBitmap, fail) -> np.ndarray:
    """The one-channel texels (H, W), float32-rounded as Mitsuba stores them, of a height bitmap:
    decoded per ``encoding``, the luminance of an RGB(A) one (Mitsuba's eval_1)."""
    enc = bm.encoding
    if isinstance(bm.source, str):
        from .. import _render_ext
        try:
            render = _render_ext.load()
            px = np.asarray(render.read_image(bm.source), np.float64)
            if enc == "auto":   # bk.Texture's rule (Mitsuba's): integer images sRGB, float ones linear
                enc = "sRGB" if render.image_info(bm.source)[3] in ("uint8", "uint16", "int8", "int16") else "linear"
        except (RuntimeError, OSError) as e:
            fail(bm.where, f"bitmap {bm.source!r}: cannot read the image ({e})")
    else:
        px = np.asarray(bm.source, np.float64)
    if px.ndim == 2:
        px = px[..., None]
    if enc == "sRGB":
        from ..io import srgb_to_linear
        px = srgb_to_linear(px)
    px = px.astype(np.float32).astype(np.float64)
    if px.shape[2] >= 3:
        px = (px[..., :3] @ LUMINANCE).astype(np.float32).astype(np.float64)
    return px[..., 0]


class HeightGradient(TextureBase):
    """d height / d u (``axis=0``) or d v (``axis=1``) of a height image (H, W) at uv, as Mitsuba
    3's bilinear ``bitmap.eval_1_grad`` computes it (``bsdfkit.models.bump_map.height_gradient``),
    after the bitmap's ``to_uv`` M: (W, H) times M^T times the per-texel differences, as Mitsuba
    3.9 orders it."""

    channels = 1

    def __init__(self, height, axis, wrap_mode="repeat", transform=None):
        h = np.array(height, dtype=np.float64)
        if h.ndim != 2 or h.size == 0 or axis not in (0, 1):
            raise ValueError(f"HeightGradient: expected an (H, W) height and axis 0 or 1, got {h.shape}, {axis!r}")
        h.setflags(write=False)
        if transform is not None:
            transform = np.array(transform, np.float64)
            transform.setflags(write=False)
        object.__setattr__(self, "height", h)
        object.__setattr__(self, "axis", int(axis))
        object.__setattr__(self, "wrap_mode", wrap_mode)
        object.__setattr__(self, "transform", transform)

    def _args(self):
        return {"height": self.height, "axis": self.axis, "wrap_mode": self.wrap_mode, "transform": self.transform}

    def _lookup(self, uv, dx, dy):
        from ..models.bump_map import height_gradient
        m = self.transform
        if m is None:
            return np.asarray(height_gradient(self.height, uv, self.wrap_mode)[self.axis], np.float64)[..., None]
        gu, gv = height_gradient(self.height, uv @ m[:, :2].T + m[:, 2], self.wrap_mode)
        rows, cols = self.height.shape
        # Mitsuba 3.9 bitmap.cpp eval_1_grad: res * (M^T (per-texel differences)), the resolution
        # applied after the transpose (the chain rule would apply it before: they differ for a
        # rotated or sheared to_uv of a non-square image; reproduced as Mitsuba computes it)
        px, py = gu / cols, gv / rows
        g = cols * (m[0, 0] * px + m[1, 0] * py) if self.axis == 0 else rows * (m[0, 1] * px + m[1, 1] * py)
        return np.asarray(g, np.float64)[..., None]


_WRAP_MI = {v: k for k, v in _WRAPS.items()}


def height_gradients(bm: MiBitmap, fail):
    """(dh/du, dh/dv) textures of a bumpmap's height bitmap (``HeightGradient``), or (0.0, 0.0)
    for ``filter_type="nearest"`` (Mitsuba's gradient of a nearest lookup is 0)."""
    if bm.filter == "nearest":
        return 0.0, 0.0
    h = height_texels(bm, fail)
    if np.all(h == h.flat[0]):   # constant texels: a zero gradient everywhere
        return 0.0, 0.0
    cls = HeightGradient
    return (cls(h, 0, _WRAP_MI[bm.wrap], bm.transform), cls(h, 1, _WRAP_MI[bm.wrap], bm.transform))




def checkerboard_texture(d, where, channels, fail, color):
    """Mitsuba 3's ``checkerboard`` (``color0`` 0.4, ``color1`` 0.2, ``to_uv``) -> pbrt-v4's
    ``tx.Checkerboard`` with uscale = vscale = 2: Mitsuba picks color0 where the fractional parts
    of u and v are both above or both at most 1/2, i.e. where floor(2u) + floor(2v) is even (they
    differ only on the lines u, v = k / 2); to_uv (scale and translation) gives the scales and
    deltas. Colour parameters only: Mitsuba 3.9's ``eval_1`` of a checkerboard (a float
    parameter) returns the other square's value, as the mean of its RGB (measured), which is not
    reproduced."""
    from ..textures import Checkerboard
    if channels == 1:
        fail(where, "a checkerboard for a float parameter: Mitsuba 3.9's checkerboard eval_1 swaps the two squares "
             "(and takes the mean of an RGB colour); only colour parameters take a checkerboard here")
    extra = [k for k in d if k not in ("type", "id", "color0", "color1", "to_uv", "__line__")]
    if extra:
        fail(where, f"checkerboard: unsupported parameters {extra}; checkerboard takes color0, color1, to_uv")
    c0 = color(d.get("color0", 0.4), where, "color0", bounded=False)
    c1 = color(d.get("color1", 0.2), where, "color1", bounded=False)
    m = _matrix(d["to_uv"], where, fail) if "to_uv" in d else np.array([[1.0, 0, 0], [0, 1.0, 0]])
    if m[0, 1] != 0 or m[1, 0] != 0:
        fail(where, f"checkerboard: a to_uv with rotation or shear ({m.tolist()}) has no pbrt-style checkerboard")
    return Checkerboard(c0, c1, uscale=2 * m[0, 0], vscale=2 * m[1, 1], udelta=2 * m[0, 2], vdelta=2 * m[1, 2])
