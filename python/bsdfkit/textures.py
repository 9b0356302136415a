"""Textures: parameters that vary over a surface, looked up at texture coordinates ``uv``.

``bk.Texture`` is an image texture: lookups go through OpenImageIO's TextureSystem (tiled,
MIP-mapped, filtered, with wrap modes), in the optional compiled part ``bsdfkit._render``. The
procedural textures pbrt-v4 scenes use are here too: :class:`Constant`, :class:`Scale`,
:class:`Mix` and :class:`Checkerboard` (pbrt-v4 ``textures.cpp`` semantics).

Any model parameter that a class lists in ``varying_params`` accepts a texture. The model then
takes ``uv=`` (and optionally ``duvdx=``, ``duvdy=``) in ``eval``, ``pdf``, ``sample`` and
``albedo``; ``m.at(uv)`` is the model with the textures looked up, as per-element parameters,
and the results are those of that model, bit for bit (``bsdfkit.models.textured``).

uv convention: (0, 0) is the top-left corner of the image as stored (its first row is at v near
0), as in OpenImageIO, glTF and Mitsuba 3's ``bitmap``. Pixel centres are at ((i + 0.5) / W,
(j + 0.5) / H). pbrt-v4 puts v = 0 at the bottom; its importer passes a ``transform`` that flips v.
"""
from __future__ import annotations

import atexit
import math
import numbers
import os
import shutil
import tempfile
import threading

import numpy as np

from . import _render_ext
from ._progress import PROGRESS_DELAY, Progress, check_progress, run_polled
from .io import srgb_to_linear
from ._values import digest, fmt_param, key_value

__all__ = ["TextureBase", "Texture", "Constant", "Scale", "Mix", "Checkerboard", "Normals", "is_texture"]

# OpenImageIO TextureOpt enums (texture.h): InterpMode, MipMode, Wrap.
_FILTERS = {"nearest": (0, 1), "bilinear": (1, 1), "bicubic": (2, 1), "trilinear": (1, 3), "anisotropic": (1, 4)}
_WRAPS = {"black": 1, "clamp": 2, "periodic": 3, "mirror": 4}
_CHUNK = 1 << 20   # lookups per call into bsdfkit._render


def is_texture(x) -> bool:
    """Whether ``x`` is a texture (an instance of :class:`TextureBase`)."""
    return isinstance(x, TextureBase)


def check_uv(uv, name: str = "uv") -> np.ndarray:
    """uv as a float64 (..., 2) array of finite numbers; a bad one raises ValueError naming
    ``name`` and the first bad index."""
    try:
        a = np.asarray(uv, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise TypeError(f"{name}: expected an array of shape (..., 2) of real numbers ({e})") from None
    if a.ndim == 0 or a.shape[-1] != 2:
        raise ValueError(f"{name}: expected shape (..., 2), got {a.shape}")
    bad = ~np.isfinite(a).all(-1)
    if bad.any():
        idx = np.unravel_index(int(np.argmax(bad.reshape(-1))), bad.shape)
        raise ValueError(f"{name}: entries must be finite; the first bad one, at index "
                         f"{tuple(int(j) for j in idx)}, is {a[idx].tolist()}")
    return a


def check_lookup(uv, duvdx, duvdy):
    """(uv, duvdx, duvdy) of a lookup, checked: uv as :func:`check_uv`, the derivatives both or
    neither, each broadcast to uv's shape."""
    uv = check_uv(uv)
    if (duvdx is None) != (duvdy is None):
        raise ValueError("duvdx, duvdy: give both or neither")
    if duvdx is None:
        return uv, None, None
    return (uv, np.broadcast_to(check_uv(duvdx, "duvdx"), uv.shape),
            np.broadcast_to(check_uv(duvdy, "duvdy"), uv.shape))


class TextureBase:
    """A texture: ``lookup(uv, duvdx, duvdy)`` returns float64 values of shape (..., channels).

    Textures are immutable values: ``==``, ``hash``, ``repr`` and pickling work, arrays compared
    by content digest."""

    channels: int = 1

    def lookup(self, uv, duvdx=None, duvdy=None) -> np.ndarray:
        """Values at ``uv`` (..., 2): float64 (..., channels). ``duvdx``, ``duvdy`` (..., 2): the
        screen-space derivatives of uv, for filtered (MIP-mapped) lookups and filtered
        procedural textures; without them, point lookups."""
        return self._lookup(*check_lookup(uv, duvdx, duvdy))

    def _lookup(self, uv, dx, dy) -> np.ndarray:
        raise NotImplementedError

    def _args(self) -> dict:
        raise NotImplementedError

    def _key(self):
        return (type(self).__name__,) + tuple((k, _key(v)) for k, v in self._args().items())

    def __eq__(self, other):
        return type(self) is type(other) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        return f"{type(self).__name__}({', '.join(f'{k}={_fmt(v)}' for k, v in self._args().items())})"

    def __setattr__(self, k, v):
        raise AttributeError(f"{type(self).__name__} is immutable; build a new texture instead")

    def __reduce__(self):
        return (_rebuild, (type(self), self._args()))


def _rebuild(cls, args):
    return cls(**args)


def _key(v):
    return v._key() if isinstance(v, TextureBase) else key_value(v)


def _fmt(v):
    return repr(v) if isinstance(v, TextureBase) else fmt_param(v)


def _value(v, name: str):
    """A texture, or a number / RGB triple as a :class:`Constant`."""
    return v if isinstance(v, TextureBase) else Constant(v, name=name)


def _channels_of(*texs) -> int:
    c = {t.channels for t in texs if t.channels != 1}
    if len(c) > 1:
        raise ValueError(f"textures of {sorted(c)} channels cannot be combined")
    return c.pop() if c else 1


def _blend(w, t1, t2):
    """(1 - w) t1 + w t2, a texture whose weight is exactly 0 left out (pbrt-v4 MixTexture and
    Checkerboard evaluate only the textures with a weight: an Inf there stays out)."""
    return np.where(w != 1, (1 - w) * t1, 0.0) + np.where(w != 0, w * t2, 0.0)


def _match(v: np.ndarray, channels: int) -> np.ndarray:
    return v if v.shape[-1] == channels else np.broadcast_to(v, v.shape[:-1] + (channels,))


class Constant(TextureBase):
    """A constant: a number (1 channel) or an RGB triple (3 channels); pbrt-v4 ``constant``."""

    def __init__(self, value, *, name: str = "value"):
        a = np.asarray(value, dtype=np.float64) if not isinstance(value, bool) else None
        if a is None or a.ndim > 1 or (a.ndim == 1 and a.shape != (3,)):
            raise TypeError(f"{name}: expected a number or 3 numbers (RGB), got {value!r}")
        if not np.isfinite(a).all():
            raise ValueError(f"{name}: must be finite, got {a.tolist()}")
        a = a.reshape(-1)
        a.setflags(write=False)
        object.__setattr__(self, "value", float(a[0]) if a.size == 1 else a)
        object.__setattr__(self, "channels", int(a.size))

    def _args(self):
        return {"value": self.value}

    def _lookup(self, uv, dx, dy):
        return np.broadcast_to(np.asarray(self.value, np.float64).reshape(-1), uv.shape[:-1] + (self.channels,)).copy()


class Scale(TextureBase):
    """``tex * scale``; each a texture or a constant (pbrt-v4 ``scale``; ``scale`` is a float
    texture)."""

    def __init__(self, tex, scale):
        tex, scale = _value(tex, "tex"), _value(scale, "scale")
        if scale.channels != 1:
            raise ValueError("scale: expected a 1-channel texture or a number")
        object.__setattr__(self, "tex", tex)
        object.__setattr__(self, "scale", scale)
        object.__setattr__(self, "channels", tex.channels)

    def _args(self):
        return {"tex": self.tex, "scale": self.scale}

    def _lookup(self, uv, dx, dy):
        return self.tex._lookup(uv, dx, dy) * self.scale._lookup(uv, dx, dy)


class Mix(TextureBase):
    """``(1 - amount) * tex1 + amount * tex2`` (pbrt-v4 ``mix``; ``amount`` is a float texture,
    default 0.5). Where amount is exactly 0 (1), tex2 (tex1) does not contribute, as in pbrt-v4."""

    def __init__(self, tex1=0.0, tex2=1.0, amount=0.5):
        tex1, tex2, amount = _value(tex1, "tex1"), _value(tex2, "tex2"), _value(amount, "amount")
        if amount.channels != 1:
            raise ValueError("amount: expected a 1-channel texture or a number")
        object.__setattr__(self, "tex1", tex1)
        object.__setattr__(self, "tex2", tex2)
        object.__setattr__(self, "amount", amount)
        object.__setattr__(self, "channels", _channels_of(tex1, tex2))

    def _args(self):
        return {"tex1": self.tex1, "tex2": self.tex2, "amount": self.amount}

    def _lookup(self, uv, dx, dy):
        a = self.amount._lookup(uv, dx, dy)
        t1 = _match(self.tex1._lookup(uv, dx, dy), self.channels)
        t2 = _match(self.tex2._lookup(uv, dx, dy), self.channels)
        return _blend(a, t1, t2)


class Checkerboard(TextureBase):
    """pbrt-v4's 2-D ``checkerboard``: tex1 on the squares where floor(s) + floor(t) is even,
    tex2 on the others, with s = uscale u + udelta and t = vscale v + vdelta (pbrt-v4's uv
    mapping). With uv derivatives the pattern is box-filtered as pbrt-v4 does (the closed-form
    integral of the checkerboard against a filter 1.5 times the derivatives' size)."""

    def __init__(self, tex1=1.0, tex2=0.0, uscale=1.0, vscale=1.0, udelta=0.0, vdelta=0.0):
        tex1, tex2 = _value(tex1, "tex1"), _value(tex2, "tex2")
        for n, v in (("uscale", uscale), ("vscale", vscale), ("udelta", udelta), ("vdelta", vdelta)):
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
                raise TypeError(f"{n}: expected a finite real number, got {v!r}")
            object.__setattr__(self, n, float(v))
        object.__setattr__(self, "tex1", tex1)
        object.__setattr__(self, "tex2", tex2)
        object.__setattr__(self, "channels", _channels_of(tex1, tex2))

    def _args(self):
        return {"tex1": self.tex1, "tex2": self.tex2, "uscale": self.uscale, "vscale": self.vscale,
                "udelta": self.udelta, "vdelta": self.vdelta}

    def weight(self, uv, duvdx=None, duvdy=None) -> np.ndarray:
        """tex2's weight in [0, 1] at uv (...,): 0 on tex1's squares, 1 on tex2's."""
        uv = check_uv(uv)
        return self._weight(uv, None if duvdx is None else check_uv(duvdx, "duvdx"),
                            None if duvdy is None else check_uv(duvdy, "duvdy"))

    def _weight(self, uv, dx, dy):
        s = self.uscale * uv[..., 0] + self.udelta
        t = self.vscale * uv[..., 1] + self.vdelta
        if dx is None:
            return 0.5 - _bf(s, 0.0) * _bf(t, 0.0) / 2
        # pbrt-v4 Checkerboard(): filter widths 1.5 max(|d/dx|, |d/dy|) per axis
        ds = 1.5 * np.maximum(np.abs(self.uscale * dx[..., 0]), np.abs(self.uscale * dy[..., 0]))
        dt = 1.5 * np.maximum(np.abs(self.vscale * dx[..., 1]), np.abs(self.vscale * dy[..., 1]))
        return 0.5 - _bf(s, ds) * _bf(t, dt) / 2

    def _lookup(self, uv, dx, dy):
        w = self._weight(uv, dx, dy)[..., None]
        t1 = _match(self.tex1._lookup(uv, dx, dy), self.channels)
        t2 = _match(self.tex2._lookup(uv, dx, dy), self.channels)
        return _blend(w, t1, t2)


class Normals(TextureBase):
    """Tangent-space normals decoded from an RGB texture: n = normalize(2 c - 1) per element, as
    pbrt-v4's and Mitsuba 3's normal maps decode their images (a ``bk.NormalMap``'s ``normals``).
    A value whose 2 c - 1 has zero length decodes to (0, 0, 1)."""

    def __init__(self, tex):
        if not isinstance(tex, TextureBase) or tex.channels < 3:
            raise ValueError(f"tex: expected a texture of 3 (or 4: RGBA) channels, got {tex!r}")
        object.__setattr__(self, "tex", tex)
        object.__setattr__(self, "channels", 3)

    def _args(self):
        return {"tex": self.tex}

    def _lookup(self, uv, dx, dy):
        n = 2.0 * self.tex._lookup(uv, dx, dy)[..., :3] - 1.0
        length = np.sqrt(np.einsum("...i,...i->...", n, n))[..., None]
        ok = length > 0
        return np.where(ok, n / np.where(ok, length, 1.0), np.array([0.0, 0.0, 1.0]))


def _check_d(x):
    # pbrt-v4 Checkerboard(): the integral of the integral of the +-1 square wave of period 2
    y = x / 2 - np.floor(x / 2) - 0.5
    return x / 2 + y * (1 - 2 * np.abs(y))


def _bf(x, r):
    """The +-1 checker function of x box-filtered over [x - r, x + r] (pbrt-v4 ``bf``)."""
    point = 1.0 - 2.0 * (np.floor(x).astype(np.int64) & 1)
    r = np.broadcast_to(r, np.shape(x))
    same = np.floor(x - r) == np.floor(x + r)
    with np.errstate(divide="ignore", invalid="ignore"):
        filt = (_check_d(x + r) - 2 * _check_d(x) + _check_d(x - r)) / (r * r)
    return np.where(same, point, filt)


# ---- image textures
_tmp_lock = threading.Lock()
_tmp_dir = None


def _texture_dir() -> str:
    """This process's directory of converted textures, removed at exit."""
    global _tmp_dir
    with _tmp_lock:
        if _tmp_dir is None:
            _tmp_dir = tempfile.mkdtemp(prefix="bsdfkit-textures-")
            atexit.register(shutil.rmtree, _tmp_dir, True)
        return _tmp_dir


def _write_texture(render, tmp: str, path: str, px: np.ndarray) -> None:
    render.make_texture(tmp, px)
    os.replace(tmp, path)


def _decode(px: np.ndarray, encoding: str) -> np.ndarray:
    """Encoded values in [0, 1] to linear (pbrt-v4 ColorEncoding: sRGB, linear, gamma g)."""
    if encoding == "linear":
        return px
    if encoding == "sRGB":
        return srgb_to_linear(px)
    return np.power(np.clip(px, 0.0, None), float(encoding.split()[1]))


def _encoding(e) -> str:
    if not isinstance(e, str):
        raise TypeError(f"encoding: expected a string, got {type(e).__name__}")
    if e in ("auto", "sRGB", "linear"):
        return e
    if e.lower() == "srgb":
        return "sRGB"
    parts = e.split()
    if len(parts) == 2 and parts[0] == "gamma":
        try:
            g = float(parts[1])
        except ValueError:
            g = float("nan")
        if math.isfinite(g) and g > 0:
            return f"gamma {g:g}"
    raise ValueError(f"encoding: expected 'auto', 'sRGB', 'linear' or 'gamma <g>' (g > 0), got {e!r}")


class Texture(TextureBase):
    """An image texture: an image file or a numpy array, looked up with OpenImageIO's
    TextureSystem (tiled, MIP-mapped; needs ``bsdfkit._render``).

    Parameters
    ----------
    source : str, os.PathLike or array_like
        An image file (any format OpenImageIO reads) or an array (H, W) or (H, W, C) of floats
        (linear) or of uint8 / uint16 (encoded values, scaled to [0, 1]).
    filter : str, optional
        ``"nearest"``, ``"bilinear"`` (default), ``"bicubic"`` (OpenImageIO's cubic B-spline),
        ``"trilinear"`` or ``"anisotropic"`` (MIP-mapped: they use ``duvdx``/``duvdy`` when the
        lookup has them, the full-resolution level otherwise).
    wrap : str or (str, str), optional
        Outside [0, 1]: ``"periodic"`` (default), ``"clamp"``, ``"mirror"`` or ``"black"``; a pair
        gives u and v their own.
    encoding : str, optional
        How stored values map to linear ones: ``"auto"`` (default: 8- and 16-bit integer images
        are sRGB, float images linear), ``"sRGB"``, ``"linear"`` or ``"gamma <g>"``. Decoding
        happens per texel, before filtering (as pbrt-v4 does); an alpha channel (the last of 2 or 4)
        stays linear.
    scale : float, optional
        Multiplies the filtered value (pbrt-v4 ``imagemap`` ``scale``).
    invert : bool, optional
        max(0, 1 - value) after ``scale`` (pbrt-v4 ``invert``).
    channel : int, optional
        Look up this channel only (a 1-channel texture); default: every channel.
    transform : array_like, shape (2, 3), optional
        Affine map applied to uv (and, without its offset, to the derivatives) before the lookup:
        ``(u', v') = M @ (u, v, 1)``.
    progress : bool or callable, optional
        Building the MIP-mapped texture of a large image takes seconds (2048² sRGB: 2-4 s, mostly
        the MIP-mapped write): one bar over reading, decoding and writing it. None (default): on
        stderr when it is a terminal (a bar in Jupyter), once the build has run for a second, and
        never inside a call that shows its own (a scene import); True, False, or a callable
        ``progress(done, total, stage)``.
        Ctrl-C stops the build with ``KeyboardInterrupt``.

    Raises
    ------
    FileNotFoundError
        A missing image file, naming it.
    OSError
        An unreadable or corrupt image, with OpenImageIO's reason.
    ImportError
        This build of bsdfkit has no ``bsdfkit._render`` (no OpenImageIO).

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> t = bk.Texture(np.array([[0.0, 1.0], [2.0, 3.0]]), filter="nearest")
    >>> t.lookup([[0.25, 0.25], [0.75, 0.75]])[:, 0].tolist()
    [0.0, 3.0]
    """

    def __init__(self, source, *, filter: str = "bilinear", wrap="periodic", encoding: str = "auto",
                 scale: float = 1.0, invert: bool = False, channel=None, transform=None, progress=None):
        if filter not in _FILTERS:
            raise ValueError(f"filter: expected one of {list(_FILTERS)}, got {filter!r}")
        wraps = (wrap, wrap) if isinstance(wrap, str) else tuple(wrap) if isinstance(wrap, (tuple, list)) else None
        if wraps is None or len(wraps) != 2 or any(w not in _WRAPS for w in wraps):
            raise ValueError(f"wrap: expected one of {list(_WRAPS)} or a pair of them, got {wrap!r}")
        encoding = _encoding(encoding)
        progress = check_progress(progress)
        if isinstance(scale, bool) or not isinstance(scale, numbers.Real) or not math.isfinite(scale):
            raise TypeError(f"scale: expected a finite real number, got {scale!r}")
        if not isinstance(invert, (bool, np.bool_)):
            raise TypeError(f"invert: expected a bool, got {invert!r}")
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731
        render = _render_ext.load()
        top = None   # a file's largest stored integer (8 or 16 bits), from its header
        if isinstance(source, (str, os.PathLike)):
            path = os.fspath(source)
            if not os.path.isfile(path):
                raise FileNotFoundError(f"source: no such image file: {path}")
            width, height, nch, fmt = render.image_info(path)
            set_("source", path)
            integer = fmt in ("uint8", "uint16", "int8", "int16")
            top = 255 if fmt in ("uint8", "int8") else 65535
        else:
            a = np.asarray(source)
            if a.dtype.kind not in "fui" or a.dtype == np.bool_:
                raise TypeError(f"source: expected a path or an array of numbers, got {type(source).__name__} "
                                f"of dtype {a.dtype}")
            if a.ndim == 2:
                a = a[..., None]
            if a.ndim != 3 or a.shape[0] < 1 or a.shape[1] < 1 or not 1 <= a.shape[2] <= 4:
                raise ValueError(f"source: expected an image array (H, W) or (H, W, C) with C <= 4, got {np.shape(source)}")
            integer = a.dtype.kind in "ui"
            if integer and a.dtype.itemsize > 2:
                raise TypeError(f"source: integer images must be uint8 or uint16, got {a.dtype}")
            if not integer:
                bad = ~np.isfinite(a).all(-1)
                if bad.any():
                    idx = np.unravel_index(int(np.argmax(bad.reshape(-1))), bad.shape)
                    raise ValueError(f"source: pixels must be finite; the first bad one, at (row, column) "
                                     f"{tuple(int(j) for j in idx)}, is {a[idx].tolist()}")
            a = a.copy()
            a.setflags(write=False)
            set_("source", a)
            height, width, nch = a.shape
        if channel is not None:
            if isinstance(channel, bool) or not isinstance(channel, (numbers.Integral,)) or not 0 <= channel < nch:
                raise ValueError(f"channel: expected an integer in [0, {nch - 1}] (the image has {nch} "
                                 f"channels), got {channel!r}")
            channel = int(channel)
        if transform is not None:
            m = np.asarray(transform, dtype=np.float64)
            if m.shape != (2, 3) or not np.isfinite(m).all():
                raise ValueError(f"transform: expected a finite (2, 3) matrix, got shape {m.shape}")
            m.setflags(write=False)
            transform = m
        set_("filter", filter)
        set_("wrap", wraps if wraps[0] != wraps[1] else wraps[0])
        set_("encoding", encoding)
        set_("scale", float(scale))
        set_("invert", bool(invert))
        set_("channel", channel)
        set_("transform", transform)
        set_("width", int(width))
        set_("height", int(height))
        set_("channels", 1 if channel is not None else int(nch))
        decode = {"auto": "sRGB" if integer else "linear"}.get(encoding, encoding)
        set_("_decode", decode)
        set_("_wraps", tuple(_WRAPS[w] for w in wraps))
        if isinstance(self.source, str) and decode == "linear":
            set_("_file", self.source)   # read as it is: nothing to build
        else:
            with Progress(progress, 3, "reading the image", "bk.Texture", delay=PROGRESS_DELAY) as prog:
                set_("_file", self._prepare(render, integer, top, prog))

    def _prepare(self, render, integer: bool, top, prog) -> str:
        """The file the TextureSystem reads for an image that needs decoding (or an array): a tiled,
        MIP-mapped float texture of the decoded pixels (in this process's temporary directory,
        named by content). ``prog``: three steps (read, decode, write)."""
        src = self.source
        if isinstance(src, str):
            try:
                px = run_polled(prog, render.read_image, src)
            except RuntimeError as e:
                raise OSError(f"source: cannot read image {e}") from None
            if integer:   # OpenImageIO gives k / max exactly: back to the stored integers
                src = np.rint(px * top).astype(np.uint8 if top == 255 else np.uint16)
        prog(1, "decoding")
        if isinstance(src, np.ndarray) and integer:
            # a table of the decoded value of every stored integer (the same values as decoding
            # each texel, in a fraction of the time)
            top = np.iinfo(src.dtype).max
            table = _decode(np.arange(top + 1, dtype=np.float64) / top, self._decode).astype(np.float32)
            px = table[src]
            if src.shape[-1] in (2, 4):   # alpha is stored linear
                px[..., -1] = src[..., -1] / np.float32(top)
        else:
            raw = np.asarray(src if isinstance(src, np.ndarray) else px, np.float64)
            px = _decode(raw, self._decode)
            if raw.shape[-1] in (2, 4):
                px[..., -1] = raw[..., -1]
        px = np.ascontiguousarray(px, dtype=np.float32)
        name = digest(px)
        path = os.path.join(_texture_dir(), f"{name}.tx")
        prog(2, "writing the MIP-mapped texture")
        if not os.path.exists(path):
            # written under a name of its own, then renamed: a file at ``path`` is always whole
            # (another thread's build of the same pixels, or one left running by Ctrl-C)
            tmp = os.path.join(_texture_dir(), f"{name}.{os.getpid()}.{threading.get_ident()}.tmp.tx")
            run_polled(prog, _write_texture, render, tmp, path, px)
        prog(3)
        return path

    def _args(self):
        args = {"source": self.source}
        defaults = {"filter": "bilinear", "wrap": "periodic", "encoding": "auto", "scale": 1.0, "invert": False,
                    "channel": None, "transform": None}
        for k, d in defaults.items():
            v = getattr(self, k)
            if not (v is d or (not isinstance(v, np.ndarray) and v == d)):
                args[k] = v
        return args

    def _lookup(self, uv, dx, dy):
        shape = uv.shape[:-1]
        uv = uv.reshape(-1, 2)
        derivs = None
        if self.transform is not None:
            m = self.transform
            uv = uv @ m[:, :2].T + m[:, 2]
        if dx is not None:
            dx, dy = dx.reshape(-1, 2), dy.reshape(-1, 2)
            if self.transform is not None:
                dx, dy = dx @ self.transform[:, :2].T, dy @ self.transform[:, :2].T
            derivs = np.ascontiguousarray(np.concatenate([dx, dy], axis=1))
        interp, mip = _FILTERS[self.filter]
        first = self.channel or 0
        lookup = _render_ext.load().texture_lookup
        uv = np.ascontiguousarray(uv)
        v = np.empty((len(uv), self.channels))
        # in chunks: Ctrl-C (KeyboardInterrupt) stops a long lookup between two of them
        for a in range(0, len(uv), _CHUNK):
            b = min(a + _CHUNK, len(uv))
            v[a:b] = lookup(self._file, uv[a:b], None if derivs is None else derivs[a:b], interp, mip,
                            self._wraps[0], self._wraps[1], first, self.channels)
        if self.scale != 1.0:
            v = v * self.scale
        if self.invert:
            v = np.maximum(0.0, 1.0 - v)
        return v.reshape(shape + (self.channels,))
