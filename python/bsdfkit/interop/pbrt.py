"""pbrt-v4 scene text -> bsdfkit models: the ``Material`` / ``MakeNamedMaterial`` statements."""
from __future__ import annotations

import gzip
import math
import os
import re
import warnings
import zlib
from dataclasses import dataclass, field

import numpy as np

from ..models import (BxDF, CoatedConductor, CoatedDiffuse, Conductor, Dielectric, Diffuse, DiffuseTransmission,
                      ThinDielectric, roughness_to_alpha)
from .spectra import spectrum_to_rgb

__all__ = ["PBRT_GLASS_ETA", "PbrtParam", "PbrtMaterial", "PbrtSkipWarning", "PbrtMissingIncludeWarning",
           "PbrtColorSpaceWarning", "parse_pbrt_materials", "from_pbrt"]


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


#: Wavelength at which dielectric eta spectra are evaluated.
_ETA_WAVELENGTH = 550.0


_PBRT_SUPPORTED = ("diffuse", "diffusetransmission", "conductor", "dielectric", "thindielectric",
                   "coateddiffuse", "coatedconductor", "hair")


_PBRT_UNSUPPORTED = ("measured", "mix", "subsurface", "interface", "none", "")


_PBRT_ROUGH = ("roughness", "uroughness", "vroughness", "remaproughness")


_PBRT_PARAMS = {
    "diffuse": ("reflectance",),
    "diffusetransmission": ("reflectance", "transmittance", "scale"),
    "conductor": ("eta", "k", "reflectance") + _PBRT_ROUGH,
    "dielectric": ("eta",) + _PBRT_ROUGH,
    "thindielectric": ("eta",),
    "coateddiffuse": ("reflectance", "eta", "thickness", "albedo", "g", "maxdepth", "nsamples") + _PBRT_ROUGH,
    "coatedconductor": ("interface.roughness", "interface.uroughness", "interface.vroughness", "interface.eta",
                        "conductor.roughness", "conductor.uroughness", "conductor.vroughness", "conductor.eta",
                        "conductor.k", "reflectance", "thickness", "albedo", "g", "maxdepth", "nsamples",
                        "remaproughness"),
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
    file: str | None = None  # the scene file the statement is in (Include/Import), None for text

    @property
    def ignored(self) -> tuple:
        """Parameters present but left out of the BxDF (``displacement``, ``normalmap``)."""
        return tuple(p for p in self.params if p in _PBRT_IGNORED)

    def to_bxdf(self, *, spectral: bool = False, base_dir=None) -> BxDF:
        """The bsdfkit model of this material (``ValueError`` if not representable).
        ``spectral``, ``base_dir`` (where spectrum files are looked up): see :func:`from_pbrt`."""
        return _pbrt_bxdf(self, {"spectral": bool(spectral), "base": None if base_dir is None else os.fspath(base_dir)})


class _PbrtError(ValueError):
    pass


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


# pbrt-v4's scene directives (src/pbrt/parser.cpp), plus pbrt-v3's that v4 files may still carry.
_PBRT_DIRECTIVES = frozenset("""
    Accelerator ActiveTransform AreaLightSource Attribute AttributeBegin AttributeEnd Camera ColorSpace
    ConcatTransform CoordinateSystem CoordSysTransform Film Identity Import Include Integrator LightSource
    LookAt MakeNamedMaterial MakeNamedMedium Material MediumInterface NamedMaterial ObjectBegin ObjectEnd
    ObjectInstance Option PixelFilter ReverseOrientation Rotate Sampler Scale Shape Texture Transform
    TransformBegin TransformEnd TransformTimes Translate WorldBegin WorldEnd
    Renderer SurfaceIntegrator VolumeIntegrator
""".split())

#: Nesting limit of Include/Import (a cycle would otherwise recurse forever).
PBRT_MAX_INCLUDE_DEPTH = 32
#: Limit on the Include/Import statements followed in one scene: files that include the next one
#: twice, 30 deep, are 2^30 includes (a hang without it).
PBRT_MAX_INCLUDES = 10_000

#: ``ActiveTransform``'s argument: a bare word (pbrt-v4 src/pbrt/parser.cpp).
_ACTIVE_TRANSFORM = ("All", "StartTime", "EndTime")

#: Directives that push / pop pbrt-v4's graphics state (the current material among it):
#: TransformBegin/End are pbrt-v4's deprecated spelling of AttributeBegin/End, and ObjectBegin /
#: ObjectEnd push and pop it too (pbrt-v4 BasicSceneBuilder).
_PUSH = ("AttributeBegin", "TransformBegin", "ObjectBegin")
_POP = ("AttributeEnd", "TransformEnd", "ObjectEnd")


class PbrtMissingIncludeWarning(UserWarning):
    """An ``Include`` / ``Import`` whose file does not exist, skipped by
    ``from_pbrt(..., skip_missing_includes=True)`` (attributes: ``file``, the including file or
    None for text; ``line``; ``include``, the name as written; ``path``, where it was looked for)."""


class PbrtColorSpaceWarning(UserWarning):
    """A ``ColorSpace`` other than ``"srgb"``: bsdfkit reads pbrt RGB values as linear sRGB, so
    colours given in that space come out differently (attributes: ``file``, ``line``, ``colorspace``)."""


def parse_pbrt_materials(text: str, *, path=None, skip_missing_includes: bool = False) -> list:
    """The material statements of pbrt-v4 scene text, in order, as ``PbrtMaterial`` records.

    Understands pbrt's tokens (quoted strings with escapes, numbers, ``true``/``false``,
    brackets, ``#`` comments to the end of the line; statements may span lines) and reads
    ``Material "type" params...`` and ``MakeNamedMaterial "name" "string type" "..."
    params...``. ``AttributeBegin``/``AttributeEnd``, ``NamedMaterial`` and ``Shape`` are
    followed to count the shapes using each material; ``Include "file"`` and ``Import "file"``
    are read in place, relative to the including file (``path``; the working directory for text
    without one), at most :data:`PBRT_MAX_INCLUDE_DEPTH` deep; every other pbrt directive is
    skipped (every directive of pbrt-v4's format is known: ``ActiveTransform All | StartTime |
    EndTime``, ``Option``, ``ColorSpace``, ``MediumInterface`` with one or two names, ...;
    ``TransformBegin``/``TransformEnd`` and ``ObjectBegin``/``ObjectEnd`` scope the current material
    as ``AttributeBegin``/``AttributeEnd`` do, as in pbrt-v4). Anonymous materials are named
    ``"material#<n> (line <line>)"`` (``"... (<file> line <line>)"`` inside an included file).
    Does not convert parameters: see :meth:`PbrtMaterial.to_bxdf` and :func:`from_pbrt`.
    ``skip_missing_includes=True``: an Include / Import of a file that does not exist is skipped
    with one :class:`PbrtMissingIncludeWarning` per include (scene files often include geometry a
    material user does not have). A ``ColorSpace`` other than srgb warns once per file
    (:class:`PbrtColorSpaceWarning`): RGB values are read as linear sRGB.

    Parameters
    ----------
    text : str
        pbrt-v4 scene text.
    path : str or os.PathLike, optional
        The file the text came from (includes are relative to it).
    skip_missing_includes : bool, optional
        Skip missing includes with a warning each (above).

    Returns
    -------
    list of PbrtMaterial
        The material statements, in order.

    Raises
    ------
    ValueError
        With the line number (and file) for malformed text: unterminated strings or brackets,
        stray ``]``, non-numbers in lists, malformed parameter declarations, a word that is not
        a pbrt directive, a bad ``ActiveTransform`` argument, a ``MakeNamedMaterial`` without
        ``"string type"``, a redefined named material, Include nested too deep or followed more
        than ``PBRT_MAX_INCLUDES`` times, an include that is not text (or a corrupt ``.gz``).
    OSError
        Naming the file for a missing include (unless ``skip_missing_includes``), or one that is
        not a regular file (a device such as ``/dev/zero``, a FIFO, a directory).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> [m.name for m in bk.parse_pbrt_materials('Material "diffuse" Shape "sphere"')]
    ['material#1 (line 1)']
    """
    if not isinstance(text, str):
        raise TypeError(f"text: expected str (pbrt scene text), got {type(text).__name__}")
    if not isinstance(skip_missing_includes, (bool, np.bool_)):
        raise TypeError(f"skip_missing_includes: expected True or False, got {skip_missing_includes!r}")
    st = {"recs": [], "by_name": {}, "current": None, "stack": [], "n_anon": 0,
          "skip_missing": bool(skip_missing_includes), "colorspace_warned": set()}
    _parse_into(st, text, None if path is None else os.fspath(path), 0)
    return [PbrtMaterial(name=r[0], type=r[1], line=r[2], named=r[3], params=r[4], shapes=r[5], file=r[6])
            for r in st["recs"]]


def _parse_into(st, text, path, depth):
    where = "" if path is None or depth == 0 else f"{os.path.basename(path)} "
    try:
        _parse_statements(st, text, path, depth, where)
    except _PbrtError as e:
        if path is None or depth == 0 or str(e).startswith(f"{path}:"):
            raise
        raise _PbrtError(f"{path}: {e}") from None


def _parse_statements(st, text, path, depth, where):
    ts = _Stream(text)
    recs, by_name, stack = st["recs"], st["by_name"], st["stack"]
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
        if kw not in _PBRT_DIRECTIVES:
            hint = (" (from_pbrt takes scene text or a path to an existing file: is this a file name?)"
                    if ("." in kw or "/" in kw) and len(recs) == 0 else "")
            raise _PbrtError(f"line {line}: unknown directive {kw!r}{hint}")
        if kw == "Material":
            mtype = _statement_name(ts, kw, line)
            params = _read_params(ts, f"Material {mtype!r}")
            st["n_anon"] += 1
            rec = [f"material#{st['n_anon']} ({where}line {line})", mtype, line, False, params, 0,
                   path if depth else None]
            recs.append(rec)
            st["current"] = rec
        elif kw == "MakeNamedMaterial":
            name = _statement_name(ts, kw, line)
            params = _read_params(ts, f"MakeNamedMaterial {name!r}")
            tp = params.pop("type", None)
            if tp is None or tp.type != "string" or len(tp.values) != 1 or not isinstance(tp.values[0], str):
                raise _PbrtError(f"line {line}: MakeNamedMaterial {name!r}: needs a \"string type\" parameter")
            if name in by_name:
                raise _PbrtError(f"line {line}: MakeNamedMaterial {name!r}: named material redefined "
                                 f"(first defined on line {by_name[name][2]})")
            rec = [name, tp.values[0], line, True, params, 0, path if depth else None]
            recs.append(rec)
            by_name[name] = rec
        elif kw in ("Include", "Import"):
            fname = _statement_name(ts, kw, line)
            base = os.path.dirname(path) if path is not None else os.getcwd()
            full = os.path.normpath(fname if os.path.isabs(fname) else os.path.join(base, fname))
            if depth + 1 > PBRT_MAX_INCLUDE_DEPTH:
                raise _PbrtError(f"line {line}: {kw} {fname!r}: nested deeper than {PBRT_MAX_INCLUDE_DEPTH} "
                                 "files (an Include cycle?)")
            st["n_includes"] = st.get("n_includes", 0) + 1
            if st["n_includes"] > PBRT_MAX_INCLUDES:
                raise _PbrtError(f"line {line}: {kw} {fname!r}: more than {PBRT_MAX_INCLUDES} Include / Import "
                                 "statements followed in one scene (files that include each other repeatedly?; "
                                 "bsdfkit.interop.pbrt.PBRT_MAX_INCLUDES)")
            if st["skip_missing"] and not os.path.exists(full):
                w = PbrtMissingIncludeWarning(f"from_pbrt: {path or '<text>'}: line {line}: skipped {kw} "
                                              f"{fname!r}: no file {full!r}")
                w.file, w.line, w.include, w.path = path, line, fname, full
                warnings.warn(w, stacklevel=5)
                continue
            try:
                sub = _read_scene_file(full)
            except ValueError as e:   # not text, a corrupt .gz
                raise _PbrtError(f"line {line}: {kw} {fname!r}: {e}") from None
            except OSError as e:
                hint = ("; from_pbrt(..., skip_missing_includes=True) skips it with a warning"
                        if not os.path.exists(full) else "")
                raise OSError(f"{path or '<text>'}: line {line}: {kw} {fname!r}: cannot read {full!r} "
                              f"({e.strerror or e}){hint}") from None
            _parse_into(st, sub, full, depth + 1)
        elif kw == "NamedMaterial":
            name = _statement_name(ts, kw, line)
            st["current"] = ("named", name)
        elif kw == "ActiveTransform":
            a = ts.next()
            if a is None or a[0] != "bare" or a[1] not in _ACTIVE_TRANSFORM:
                got = "end of input" if a is None else repr(a[1])
                raise _PbrtError(f"line {line}: ActiveTransform: expected {', '.join(_ACTIVE_TRANSFORM)}, got {got}")
        elif kw == "ColorSpace":
            cs = _statement_name(ts, kw, line)
            if cs.lower() != "srgb" and path not in st["colorspace_warned"]:
                st["colorspace_warned"].add(path)
                w = PbrtColorSpaceWarning(
                    f"from_pbrt: {path or '<text>'}: line {line}: ColorSpace {cs!r} is not honoured: bsdfkit reads "
                    "pbrt RGB values as linear sRGB, so colours given in that space differ (one warning per file)")
                w.file, w.line, w.colorspace = path, line, cs
                warnings.warn(w, stacklevel=5)
        elif kw in _PUSH:
            stack.append(st["current"])
            _skip_args(ts)
        elif kw in _POP:
            if stack:
                st["current"] = stack.pop()
            _skip_args(ts)
        elif kw == "Shape":
            cur = st["current"]
            if isinstance(cur, tuple):
                cur = by_name.get(cur[1])
            if cur is not None:
                cur[5] += 1
            _skip_args(ts)
        else:
            _skip_args(ts)


def _read_scene_file(path) -> str:
    """A pbrt scene file's text (``.gz`` files decompressed, as pbrt-v4 reads them). Only regular
    files are opened: a device or FIFO (``Include "/dev/zero"``) raises OSError naming it instead of
    being read until memory runs out or blocking forever."""
    from ..models.measured import _NotRegularFile, _regular_file_opener
    p = os.fspath(path)
    try:
        if "\x00" in p:
            raise FileNotFoundError(f"{p!r}: a file name cannot contain a NUL character")
        if p.endswith(".gz"):
            with open(p, "rb", opener=_regular_file_opener) as raw, \
                    gzip.open(raw, "rt", encoding="utf-8") as fh:
                return fh.read()
        with open(p, encoding="utf-8", opener=_regular_file_opener) as fh:
            return fh.read()
    except UnicodeDecodeError as e:  # a binary file (e.g. a .pbrt.gz without the suffix, a PLY)
        raise ValueError(f"{p}: not a pbrt-v4 scene file (not UTF-8 text at byte {e.start})") from None
    except _NotRegularFile as e:
        raise OSError(f"{p}: {e}, not a pbrt scene file") from None
    except (EOFError, zlib.error, gzip.BadGzipFile) as e:   # a truncated or corrupt .gz
        raise ValueError(f"{p}: not a readable gzip file ({e})") from None


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


def _named_metal(rec, p, name, part, ctx):
    """eta or k of a named metal spectrum: the table of ``bsdfkit.Spectrum.named`` (pbrt-v4's
    ``metal-<X>-eta/k``, also Mitsuba's ``mitsuba-<X>-...`` and ``jc-<X>-...``), kept as a
    Spectrum (``spectral=True``) or projected to RGB as ``Conductor`` projects a spectral eta / k
    (CIE 1931 to linear sRGB, no illuminant)."""
    from ..spectral.spectrum import Spectrum

    if name not in Spectrum.names():
        return _spectrum_file(rec, p, name, ctx, albedo=False)
    m = re.fullmatch(r"(?:metal|mitsuba|jc)-(.+)-(eta|k)", name)
    if m is None:
        extra = " (named glass spectra are only accepted for dielectric eta)" if name in PBRT_GLASS_ETA else ""
        _pfail_param(rec, p, f"named spectrum {name!r} is not a metal's eta or k{extra}")
    if m.group(2) != part:
        _pfail_param(rec, p, f"named spectrum {name!r} is the {m.group(2)!r} part, not {part!r}")
    s = Spectrum.named(name)
    return s if ctx.get("spectral") else np.asarray(s.to_rgb("unbounded", illuminant=None), dtype=np.float64)


def _read_spd(rec, p, full):
    """(wavelengths, values) of a pbrt spectrum file: whitespace-separated pairs, '#' comments."""
    try:
        with open(full, encoding="utf-8") as fh:
            text = fh.read()
    except (OSError, UnicodeDecodeError) as e:
        _pfail_param(rec, p, f"cannot read the spectrum file {full!r} ({getattr(e, 'strerror', None) or e})")
    words = " ".join(line.split("#", 1)[0] for line in text.splitlines()).split()
    try:
        v = np.array([float(w) for w in words], dtype=np.float64)
    except ValueError:
        _pfail_param(rec, p, f"spectrum file {full!r}: expected numbers (wavelength value pairs)")
    if v.size == 0 or v.size % 2 or not np.all(np.isfinite(v)):
        _pfail_param(rec, p, f"spectrum file {full!r}: expected (wavelength, value) pairs, got {v.size} numbers")
    lam, val = v[0::2], v[1::2]
    if np.any(np.diff(lam) <= 0):
        _pfail_param(rec, p, f"spectrum file {full!r}: wavelengths must increase")
    return lam, val


def _spectrum_file(rec, p, name, ctx, *, albedo):
    """A spectrum given by file name (pbrt-v4: a string that is not a named spectrum), relative to
    the scene file's directory (pbrt-v4's search directory; the working directory for text)."""
    from ..spectral.spectrum import Spectrum

    base = ctx.get("base") or os.getcwd()
    full = os.path.normpath(name if os.path.isabs(name) else os.path.join(base, name))
    if not os.path.isfile(full):
        _pfail_param(rec, p, f"{name!r} is neither a named spectrum (bsdfkit.Spectrum.names()) nor a spectrum "
                     f"file (no file {full!r})")
    lam, val = _read_spd(rec, p, full)
    if ctx.get("spectral") and not albedo:
        return Spectrum(lam, val)
    try:
        return spectrum_to_rgb(lam, val, d65=True, bounded=albedo)
    except ValueError as e:
        _pfail_param(rec, p, str(e))


def _spectrum_param(rec, pname, *, albedo, ctx=None):
    """RGB (3,) of a spectrum-valued parameter (a Spectrum for a named or file eta / k with
    ``ctx["spectral"]``), or None if absent."""
    ctx = ctx or {}
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
            from ..spectral.spectrum import Spectrum
            if albedo:
                if p.values[0] in Spectrum.names():
                    _pfail_param(rec, p, f"named spectrum {p.values[0]!r} is not a reflectance; give rgb, "
                                 "float, wavelength/value pairs or a spectrum file")
                return _spectrum_file(rec, p, p.values[0], ctx, albedo=True)
            return _named_metal(rec, p, p.values[0], pname.rsplit(".", 1)[-1], ctx)
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


def _eta_param(rec, default=1.5, param="eta", ctx=None):
    """IOR of a dielectric: float, spectrum (value at 550 nm; with ``ctx["spectral"]`` the
    Spectrum itself, for dispersion) or grey rgb."""
    from ..spectral.spectrum import Spectrum

    ctx = ctx or {}
    p = rec.params.get(param)
    if p is None:
        return default
    _check_texture(rec, p)
    lam = None
    if p.type == "float":
        eta = float(_numbers(rec, p)[0])
    elif p.type == "spectrum" and p.values and isinstance(p.values[0], str):
        name = p.values[0]
        if name in PBRT_GLASS_ETA:
            if ctx.get("spectral"):
                return Spectrum.named(name)
            eta = PBRT_GLASS_ETA[name]
        elif name in Spectrum.names():
            _pfail_param(rec, p, f"named spectrum {name!r} is not a glass; dielectric eta accepts "
                         f"{', '.join(PBRT_GLASS_ETA)} (evaluated at 550 nm), a float, pairs or a spectrum file")
        else:
            base = ctx.get("base") or os.getcwd()
            full = os.path.normpath(name if os.path.isabs(name) else os.path.join(base, name))
            if not os.path.isfile(full):
                _pfail_param(rec, p, f"{name!r} is neither a named glass ({', '.join(PBRT_GLASS_ETA)}) nor a "
                             f"spectrum file (no file {full!r})")
            lam, val = _read_spd(rec, p, full)
    elif p.type == "spectrum":
        v = _numbers(rec, p)
        if v.size % 2 or v.size == 0:
            _pfail_param(rec, p, f"a spectrum needs (wavelength, value) pairs, got {v.size} numbers")
        lam, val = v[0::2], v[1::2]
    if lam is not None:
        if np.any(np.diff(lam) <= 0):
            _pfail_param(rec, p, f"wavelengths must increase, got {lam.tolist()}")
        if not lam[0] <= _ETA_WAVELENGTH <= lam[-1]:
            _pfail_param(rec, p, f"the spectrum ({lam[0]:g}-{lam[-1]:g} nm) does not cover 550 nm, "
                         "where bsdfkit evaluates dielectric eta")
        if ctx.get("spectral"):
            return Spectrum(lam, val)
        eta = float(np.interp(_ETA_WAVELENGTH, lam, val))
    elif p.type == "rgb":
        v = _numbers(rec, p)
        if v.size != 3 or not np.all(v == v[0]):
            _pfail_param(rec, p, f"an rgb eta must be grey (bsdfkit's dielectrics have one eta), got {v.tolist()}")
        eta = float(v[0])
    elif p.type not in ("float", "spectrum"):
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


def _int_param(rec, pname, default):
    p = rec.params.get(pname)
    if p is None:
        return default
    if p.type != "integer" or len(p.values) != 1 or not isinstance(p.values[0], float) or p.values[0] % 1:
        _pfail_param(rec, p, f"expected one \"integer {pname}\", got {p.type!r} {list(p.values)!r}")
    return int(p.values[0])


def _layer_kwargs(rec):
    """pbrt-v4 LayeredBxDF parameters of coateddiffuse / coatedconductor (materials.cpp)."""
    albedo = _spectrum_param(rec, "albedo", albedo=True)
    g = _float_param(rec, "g", 0.0)
    return dict(thickness=_float_param(rec, "thickness", 0.01), albedo=0.0 if albedo is None else albedo,
                g=min(max(g, -1.0), 1.0), max_depth=_int_param(rec, "maxdepth", 10),
                n_samples=_int_param(rec, "nsamples", 1))


def _alphas(rec, prefix=""):
    r = _float_param(rec, prefix + "roughness", 0.0)
    u = _float_param(rec, prefix + "uroughness", r)
    v = _float_param(rec, prefix + "vroughness", r)
    for val, n in ((u, "uroughness"), (v, "vroughness")):
        if not (math.isfinite(val) and val >= 0):
            _pfail(rec, f"{prefix + n if prefix + n in rec.params else prefix + 'roughness'} must be finite "
                   f"and >= 0, got {val}")
    if _bool_param(rec, "remaproughness", True):
        return roughness_to_alpha(u), roughness_to_alpha(v)
    return u, v


def _pbrt_bxdf(rec, ctx=None):
    ctx = ctx or {}
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
            refl = _spectrum_param(rec, "reflectance", albedo=True, ctx=ctx)
            eta = _spectrum_param(rec, "eta", albedo=False, ctx=ctx)
            k = _spectrum_param(rec, "k", albedo=False, ctx=ctx)
            if refl is not None:
                if eta is not None or k is not None:
                    _pfail(rec, "give either \"reflectance\" or \"eta\"/\"k\", not both (pbrt-v4 refuses it)")
                return Conductor.from_reflectance(refl, alpha_x=ax, alpha_y=ay, masking="correlated")
            eta = _default_copper("eta", ctx) if eta is None else eta
            k = _default_copper("k", ctx) if k is None else k
            return Conductor(eta, k, alpha_x=ax, alpha_y=ay, masking="correlated")
        if mtype == "dielectric":
            ax, ay = _alphas(rec)
            return Dielectric(_eta_param(rec, ctx=ctx), alpha_x=ax, alpha_y=ay, masking="correlated")
        if mtype == "coateddiffuse":
            ax, ay = _alphas(rec)
            r = _spectrum_param(rec, "reflectance", albedo=True, ctx=ctx)
            return CoatedDiffuse(0.5 if r is None else r, eta=_eta_param(rec), alpha_x=ax, alpha_y=ay,
                                 **_layer_kwargs(rec))
        if mtype == "coatedconductor":
            iax, iay = _alphas(rec, "interface.")
            cax, cay = _alphas(rec, "conductor.")
            ieta = _eta_param(rec, param="interface.eta")
            refl = _spectrum_param(rec, "reflectance", albedo=True, ctx=ctx)
            eta = _spectrum_param(rec, "conductor.eta", albedo=False, ctx=ctx)
            k = _spectrum_param(rec, "conductor.k", albedo=False, ctx=ctx)
            kw = dict(conductor_alpha_x=cax, conductor_alpha_y=cay, interface_eta=ieta, interface_alpha_x=iax,
                      interface_alpha_y=iay, **_layer_kwargs(rec))
            if refl is not None:
                if eta is not None or k is not None:
                    _pfail(rec, "give either \"reflectance\" or \"conductor.eta\"/\"conductor.k\", not both")
                return CoatedConductor.from_reflectance(refl, **kw)
            eta = _default_copper("eta", ctx) if eta is None else eta
            k = _default_copper("k", ctx) if k is None else k
            return CoatedConductor(eta, k, **kw)
        if mtype == "hair":
            return _pbrt_hair(rec)
        return ThinDielectric(_eta_param(rec, ctx=ctx))
    except _PbrtError:
        raise
    except (ValueError, TypeError) as e:
        _pfail(rec, str(e))


def _default_copper(part, ctx):
    """pbrt-v4's default conductor: metal-Cu-eta / metal-Cu-k, from the named-spectra table."""
    from ..spectral.spectrum import Spectrum
    s = Spectrum.named(f"metal-Cu-{part}")
    return s if ctx.get("spectral") else np.asarray(s.to_rgb("unbounded", illuminant=None), dtype=np.float64)


def _pbrt_hair(rec):
    """pbrt-v4 ``HairMaterial``: sigma_a, else reflectance, else eumelanin/pheomelanin (each
    ignored when an earlier one is given, as pbrt-v4 warns and does); neither -> eumelanin 1.3.
    beta_m / beta_n clamped to [0.01, 1] and reflectance to [0, 1] as pbrt-v4's material does."""
    from ..models.hair import Hair, sigma_a_from_concentration, sigma_a_from_reflectance

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


def from_pbrt(source, *, skip_unsupported: bool = False, skip_missing_includes: bool = False,
              spectral: bool = False) -> dict:
    """bsdfkit models for the materials of a pbrt-v4 scene: ``{name: BxDF}`` in file order.

    ``source``: scene text, or the path of a scene file (an ``os.PathLike``, or a ``str``
    without a newline that names an existing file; ``.gz`` files are decompressed).
    ``Include``/``Import`` are followed relative to the including file (text: the working
    directory); a missing include raises ``OSError`` naming it, or, with
    ``skip_missing_includes=True``, is skipped with one :class:`PbrtMissingIncludeWarning` per
    include (a scene's geometry files are not needed for its materials).

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
    * ``coateddiffuse``: reflectance [0.5], eta [1.5], roughness/uroughness/vroughness [0],
      thickness [0.01], albedo [0], g [0], maxdepth [10], nsamples [1] -> ``CoatedDiffuse``.
    * ``coatedconductor``: interface.eta [1.5], interface.(u|v)roughness [0],
      conductor.eta/conductor.k [metal-Cu-eta / metal-Cu-k] or reflectance,
      conductor.(u|v)roughness [0], thickness, albedo, g, maxdepth, nsamples as coateddiffuse
      -> ``CoatedConductor`` (which divides the conductor's eta and k by interface.eta, as
      pbrt-v4 does).
    * ``hair``: sigma_a, else reflectance (``Hair.from_reflectance``, clamped to [0, 1]), else
      eumelanin / pheomelanin [1.3 / 0] (``Hair.from_concentration``); eta [1.55], beta_m, beta_n
      [0.3] (clamped to [0.01, 1]), alpha [2 degrees] -> ``Hair(..., h=0)`` (pbrt-v4 takes h from
      the curve's v coordinate per hit).
    * ``mix``: materials [two names of materials of the scene, in any order, mixes too], amount
      [0.5] (a constant) -> ``Mix(first, second, amount, method="stochastic")`` (pbrt-v4
      MixMaterial: the second material with probability amount, per shading point). Mixes of
      mixes are refused past 64 levels or 1,024 materials counted once per path
      (``bk.Mix`` evaluates every path; pbrt-v4 picks one).

    pbrt-v4's microfacet models use height-correlated Smith masking: ``masking="correlated"``.
    Roughness: with remaproughness true, alpha = sqrt(roughness) (``bk.roughness_to_alpha``),
    else alpha = roughness; uroughness is alpha along local x, vroughness along y.

    Values: ``"rgb"`` (3 numbers, used as they are: pbrt's RGB-to-spectrum upsampling followed by
    a projection back to sRGB returns them up to the upsampling error), ``"float"`` (grey; pbrt itself only takes it for dielectric
    eta), ``"spectrum"`` as wavelength/value pairs (projected to linear sRGB as Mitsuba's RGB
    variants do: CIE 1931 and D65, see :func:`spectrum_to_rgb`), as a spectrum file (pbrt-v4: a
    name that is not a named spectrum; whitespace-separated wavelength/value pairs, ``#``
    comments; relative to the scene file's directory, pbrt-v4's search directory, or the working
    directory for text; read as pairs), or as a named spectrum from the one table of
    ``bsdfkit.Spectrum.named``: ``metal-<X>-eta``/``metal-<X>-k`` for every pbrt-v4 metal (Ag,
    Al, Au, Cu, CuZn, MgO, TiO2; also ``mitsuba-<X>-...`` and ``jc-<X>-...``), projected to RGB
    as ``Conductor`` projects a spectral eta / k (so RGB mode equals the spectral model's RGB
    mode), and pbrt's glasses ``glass-<X>`` for dielectric eta. Dielectric eta is one number: a
    float, a grey rgb, a named glass (``PBRT_GLASS_ETA``), pairs or a file, evaluated at 550 nm.
    ``spectral=True`` keeps named and file spectra of metal eta / k and of dielectric /
    thin-dielectric eta as ``bsdfkit.Spectrum`` values instead (a named glass then disperses in
    spectral mode, as pbrt renders it; reflectances, the coats' interface eta and rgb values
    stay RGB / scalar). ``displacement`` and
    ``normalmap`` change the geometry, not the BxDF, and are left out
    (``PbrtMaterial.ignored``).

    Parameters
    ----------
    source : str or os.PathLike
        Scene text, or the path of a scene file (above).
    skip_unsupported : bool, optional
        Leave out materials that cannot be converted (unsupported types, textures, unknown
        spectra) instead of raising, with one :class:`PbrtSkipWarning` per material naming it,
        its line and the reason (its ``material``, ``line`` and ``reason`` attributes carry
        them); malformed text still raises.
    skip_missing_includes : bool, optional
        Skip an ``Include`` / ``Import`` of a missing file, with a
        :class:`PbrtMissingIncludeWarning`.
    spectral : bool, optional
        Keep named and file spectra of metal eta / k and dielectric eta as ``bsdfkit.Spectrum``.

    Returns
    -------
    dict
        ``{name: BxDF}`` in file order.

    Raises
    ------
    ValueError
        Naming the material, its line and the parameter for unsupported types (measured, mix,
        subsurface, interface, ...), texture-valued or unknown parameters, bad values, and
        malformed text (with the line).
    OSError
        A missing scene file or include (unless ``skip_missing_includes``).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.from_pbrt('''MakeNamedMaterial "gold" "string type" "conductor"
    ...     "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k" "float roughness" 0.04''')["gold"].alpha_x
    0.2
    """
    if not isinstance(spectral, (bool, np.bool_)):
        raise TypeError(f"spectral: expected True or False, got {spectral!r}")
    text, path = _scene_source(source)
    base = None if path is None else os.path.dirname(os.path.abspath(path))
    out, records = {}, parse_pbrt_materials(text, path=path, skip_missing_includes=skip_missing_includes)

    def skip(rec, e):
        if not skip_unsupported:
            raise e
        w = PbrtSkipWarning(f"from_pbrt: skipped {e}" + (f" [in {rec.file}]" if rec.file else ""))
        w.material, w.line, w.file, w.reason = rec.name, rec.line, rec.file, str(e)
        warnings.warn(w, stacklevel=3)
    for rec in records:
        if rec.type == "mix":   # needs the others: resolved below (interop/_pbrt_mix.py)
            continue
        try:
            out[rec.name] = rec.to_bxdf(spectral=spectral, base_dir=base)
        except _PbrtError as e:
            skip(rec, e)
    from ._pbrt_mix import resolve_mixes
    resolve_mixes([r for r in records if r.type == "mix"], out, _pfail, _pfail_param, _float_param, skip)
    return {rec.name: out[rec.name] for rec in records if rec.name in out}   # file order


class PbrtSkipWarning(UserWarning):
    """A material ``from_pbrt(..., skip_unsupported=True)`` left out (attributes: ``material``,
    ``line``, ``file``, ``reason``)."""


def _scene_source(source):
    """(text, path or None) of from_pbrt's argument."""
    if isinstance(source, os.PathLike):
        p = os.fspath(source)
        return _read_scene_file(p), p
    if isinstance(source, bytes):
        raise TypeError("source: expected scene text (str) or a path (str or os.PathLike), got bytes (decode the text first)")
    if not isinstance(source, str):
        raise TypeError(f"source: expected scene text (str) or a path (str or os.PathLike), "
                        f"got {type(source).__name__}")
    if "\n" not in source and source.strip() and os.path.isfile(source.strip()):
        p = source.strip()
        return _read_scene_file(p), p
    if "\n" not in source and source.strip().endswith((".pbrt", ".pbrt.gz")):
        raise FileNotFoundError(f"source: scene file {source.strip()!r} not found")
    return source, None
