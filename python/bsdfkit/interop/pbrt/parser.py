"""pbrt-v4 scene text: tokens, statements, ``Include`` / ``Import``, and the parsed records of the
``Material`` / ``MakeNamedMaterial`` / ``Texture`` statements (converted in ``materials`` and ``textures``)."""
from __future__ import annotations

import gzip
import os
import re
import warnings
import zlib
from dataclasses import dataclass, field

import numpy as np

from ...models import BxDF

#: Parameters of every pbrt-v4 material that shape the surface, not the BxDF: ``normalmap`` ->
#: ``bk.NormalMap``, ``displacement`` -> ``bk.BumpMap`` (``materials``); a constant displacement
#: moves a flat element without tilting it, and is left out (``PbrtMaterial.ignored``).
_PBRT_SHADING = ("displacement", "normalmap")

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
    #: The scene's ``Texture`` statements, ``{("float" | "spectrum", name): PbrtTexture}`` (shared
    #: by every record of one parse; ``"texture <param>" "<name>"`` values refer to them).
    textures: dict = field(default_factory=dict, repr=False, hash=False, compare=False)
    kind = "material"

    @property
    def ignored(self) -> tuple:
        """Parameters present but left out of the model: a constant ``"float displacement"`` (it
        moves a flat surface element without tilting it: no bump), or a displacement beside a
        ``normalmap`` (pbrt-v4 uses the normal map then)."""
        p = self.params.get("displacement")
        return ("displacement",) if p is not None and (p.type != "texture" or "normalmap" in self.params) else ()

    def to_bxdf(self, *, spectral: bool = False, base_dir=None) -> BxDF:
        """The bsdfkit model of this material (``ValueError`` if not representable).
        ``spectral``, ``base_dir`` (where spectrum files and images are looked up): see
        :func:`from_pbrt`. Textures are looked up in :attr:`textures`."""
        from .materials import _pbrt_bxdf
        return _pbrt_bxdf(self, _context(self.textures, spectral, base_dir))


@dataclass(frozen=True)
class PbrtTexture:
    """A parsed ``Texture "name" "float" | "spectrum" "class" params...`` statement.

    type: ``"float"`` or ``"spectrum"`` (pbrt-v3's ``"color"`` is read as ``"spectrum"``); cls: the
    texture class (``"imagemap"``, ``"checkerboard"``, ...); line, file as for :class:`PbrtMaterial`.
    Float and spectrum textures have separate names, as in pbrt-v4.
    """

    name: str
    type: str
    cls: str
    line: int
    params: dict = field(repr=False, hash=False)
    file: str | None = None
    kind = "texture"


def _context(textures, spectral, base_dir, cache=None):
    """What converting a record needs besides the record: the scene's textures and the converted
    ones (``cache``, shared across the records of one scene), the spectral flag and the directory
    relative file names start from (None: the working directory)."""
    return {"spectral": bool(spectral), "base": None if base_dir is None else os.fspath(base_dir),
            "textures": textures, "tex_cache": {} if cache is None else cache, "tex_stack": []}


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


def _tokens(text, at=None):
    """Yield (kind, value, line): kind is "str" (unquoted value), "[", "]" or "bare". ``at``: a
    one-element list that holds the offset read so far (progress)."""
    line, last = 1, 0
    for m in _TOKEN.finditer(text):
        line += text.count("\n", last, m.start())
        last = m.start()
        if at is not None:
            at[0] = last
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
        self.at = [0]   # characters read
        self._it = _tokens(text, self.at)
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


def parse_pbrt_materials(text: str, *, path=None, skip_missing_includes: bool = False, _progress=None) -> list:
    """The material statements of pbrt-v4 scene text, in order, as ``PbrtMaterial`` records.

    Understands pbrt's tokens (quoted strings with escapes, numbers, ``true``/``false``,
    brackets, ``#`` comments to the end of the line; statements may span lines) and reads
    ``Material "type" params...`` and ``MakeNamedMaterial "name" "string type" "..."
    params...``, and the ``Texture "name" "float" | "spectrum" "class" params...`` statements
    (every record's ``textures``: ``{(type, name): PbrtTexture}``; a texture redefined with the
    same type is an error, as in pbrt-v4). ``AttributeBegin``/``AttributeEnd``, ``NamedMaterial`` and ``Shape`` are
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
        a pbrt directive, a bad ``ActiveTransform`` argument, a redefined texture or a texture
        type other than float / spectrum, a ``MakeNamedMaterial`` without
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
    st = {"recs": [], "by_name": {}, "current": None, "stack": [], "n_anon": 0, "textures": {},
          "skip_missing": bool(skip_missing_includes), "colorspace_warned": set(),
          "progress": _progress, "chars_done": 0, "open": []}   # progress: characters read, includes too
    _parse_into(st, text, None if path is None else os.fspath(path), 0)
    return [PbrtMaterial(name=r[0], type=r[1], line=r[2], named=r[3], params=r[4], shapes=r[5], file=r[6],
                         textures=st["textures"]) for r in st["recs"]]


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
    prog = st["progress"]
    if prog is not None:
        st["open"].append(ts.at)
    n = 0
    while True:
        t = ts.next()
        if t is None:
            break
        n += 1
        if prog is not None and n % 64 == 0:   # a redraw (and a Ctrl-C point) every 64 statements
            prog(st["chars_done"] + sum(a[0] for a in st["open"]))
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
        elif kw == "Texture":
            _texture_statement(st, ts, line, path if depth else None)
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
            if prog is not None:
                prog.total += len(sub)
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
    if prog is not None:   # this file read whole
        st["open"].remove(ts.at)
        st["chars_done"] += len(text)
        prog(st["chars_done"] + sum(a[0] for a in st["open"]))


def _texture_statement(st, ts, line, file):
    """``Texture "name" "float" | "spectrum" "class" params...`` into ``st["textures"]``; a redefined
    texture is an error, as in pbrt-v4 (BasicSceneBuilder::Texture)."""
    name = _statement_name(ts, "Texture", line)
    ttype = _statement_name(ts, f"Texture {name!r}", line)
    cls = _statement_name(ts, f"Texture {name!r}", line)
    params = _read_params(ts, f"Texture {name!r}")
    if ttype == "color":   # pbrt-v3 spelling, upgraded by pbrt-v4
        ttype = "spectrum"
    if ttype not in ("float", "spectrum"):
        raise _PbrtError(f"line {line}: Texture {name!r}: type {ttype!r} is not \"float\" or \"spectrum\"")
    old = st["textures"].get((ttype, name))
    if old is not None:
        where = f" of {old.file}" if old.file and old.file != file else ""
        raise _PbrtError(f"line {line}: Texture {name!r}: {ttype} texture redefined (first defined on line "
                         f"{old.line}{where})")
    st["textures"][(ttype, name)] = PbrtTexture(name=name, type=ttype, cls=cls, line=line, params=params, file=file)


def _read_scene_file(path) -> str:
    """A pbrt scene file's text (``.gz`` files decompressed, as pbrt-v4 reads them). Only regular
    files are opened: a device or FIFO (``Include "/dev/zero"``) raises OSError naming it instead of
    being read until memory runs out or blocking forever."""
    from ...models.measured import _NotRegularFile, _regular_file_opener
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
