"""Mitsuba 3 scene XML -> plugin dictionaries (what ``mi.load_dict`` takes), for the BSDFs and
textures of a scene: :func:`read_mitsuba_xml`. Only the parts a material needs are read:
``bsdf`` / ``texture`` elements, their ``float``/``integer``/``boolean``/``string``/``rgb``/
``spectrum``/``transform`` properties, ``ref``, ``default`` and ``$name`` substitution. Each dict
remembers the XML line it came from (:data:`LINE_KEY`, read by the importer's messages)."""
from __future__ import annotations

import os
import re
import xml.parsers.expat
from pathlib import Path

import numpy as np

__all__ = ["read_mitsuba_xml", "MitsubaXMLError", "LINE_KEY"]

#: Key of the XML line number in the dicts built here (removed before ``mi.load_dict``).
LINE_KEY = "__line__"


class MitsubaXMLError(ValueError):
    """A malformed or unsupported Mitsuba scene file (the message names the file and line)."""


class _Node:
    __slots__ = ("tag", "attrs", "children", "line")

    def __init__(self, tag, attrs, line):
        self.tag, self.attrs, self.children, self.line = tag, attrs, [], line


def _parse(text, path):
    root = _Node("#root", {}, 0)
    stack = [root]
    p = xml.parsers.expat.ParserCreate()

    def start(tag, attrs):
        n = _Node(tag, dict(attrs), p.CurrentLineNumber)
        stack[-1].children.append(n)
        stack.append(n)

    def end(tag):
        stack.pop()
    p.StartElementHandler, p.EndElementHandler = start, end
    try:
        p.Parse(text, True)
    except xml.parsers.expat.ExpatError as e:
        why = xml.parsers.expat.ErrorString(e.code)
        raise MitsubaXMLError(f"{path}: line {e.lineno}: not well-formed XML ({why})") from None
    if len(root.children) != 1 or root.children[0].tag not in ("scene", "bsdf"):
        raise MitsubaXMLError(f"{path}: expected one <scene> (or <bsdf>) root element")
    top = root.children[0]
    if top.tag == "bsdf":   # a file of one BSDF (mi.load_file takes it too)
        scene = _Node("scene", {"version": top.attrs.get("version", "")}, top.line)
        scene.children.append(top)
        return scene
    return top


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def _floats(s, where):
    parts = [x for x in re.split(r"[,\s]+", s.strip()) if x]
    try:
        return [float(x) for x in parts]
    except ValueError:
        raise MitsubaXMLError(f"{where}: expected numbers, got {s!r}") from None


class _Reader:
    def __init__(self, path, defaults):
        self.path, self.params, self.ids = path, dict(defaults), {}

    def where(self, n):
        return f"{self.path}: line {n.line}"

    def sub(self, s, n):
        def rep(m):
            name = m.group(1)
            if name not in self.params:
                raise MitsubaXMLError(f"{self.where(n)}: ${name} has no value (no <default name={name!r}> and "
                                      "none given)")
            return str(self.params[name])
        return re.sub(r"\$([A-Za-z_][A-Za-z0-9_]*)", rep, s)

    def attr(self, n, key, required=True):
        v = n.attrs.get(key)
        if v is None:
            if required:
                raise MitsubaXMLError(f"{self.where(n)}: <{n.tag}> needs a {key!r} attribute")
            return None
        return self.sub(v, n)

    def value(self, n):
        """(name, python value) of a property element."""
        tag = n.tag
        name = self.attr(n, "name")
        if tag == "transform":
            return name, self.transform(n)
        v = self.attr(n, "value")
        if tag in ("float", "integer"):
            try:
                return name, (int(v) if tag == "integer" else float(v))
            except ValueError:
                raise MitsubaXMLError(f"{self.where(n)}: <{tag} name={name!r}>: not a number: {v!r}") from None
        if tag == "boolean":
            if v.lower() not in ("true", "false"):
                raise MitsubaXMLError(f"{self.where(n)}: <boolean name={name!r}>: expected true or false, got {v!r}")
            return name, v.lower() == "true"
        if tag == "string":
            return name, v
        if tag == "rgb":
            f = _floats(v, self.where(n))   # Mitsuba 3.9 refuses "#rrggbb" too
            if len(f) not in (1, 3):
                raise MitsubaXMLError(f"{self.where(n)}: <rgb name={name!r}>: expected 1 or 3 numbers, got {v!r}")
            return name, {"type": "rgb", "value": f * 3 if len(f) == 1 else f}
        if tag == "spectrum":
            if "filename" in n.attrs:
                return name, {"type": "spectrum", "filename": self.attr(n, "filename")}
            if ":" in v:
                pairs = [tuple(_floats(p.replace(":", " "), self.where(n))) for p in v.split(",") if p.strip()]
                return name, {"type": "spectrum", "value": pairs}
            f = _floats(v, self.where(n))
            if len(f) != 1:
                raise MitsubaXMLError(f"{self.where(n)}: <spectrum name={name!r}>: expected one value or "
                                      f"wavelength:value pairs, got {v!r}")
            return name, {"type": "spectrum", "value": f[0]}
        if tag in ("vector", "point"):
            if "value" in n.attrs:
                return name, _floats(v, self.where(n))
            return name, [float(self.sub(n.attrs.get(k, "0"), n)) for k in ("x", "y", "z")]
        raise MitsubaXMLError(f"{self.where(n)}: unsupported property element <{tag}>")

    def transform(self, n):
        """A <transform> as a 4x4 matrix (operations applied in order: each left-multiplies)."""
        m = np.eye(4)
        for op in n.children:
            a = {k: self.sub(v, op) for k, v in op.attrs.items()}
            if op.tag == "translate":
                t = np.eye(4)
                t[:3, 3] = _xyz(a, 0.0, self.where(op))
            elif op.tag == "scale":
                if "value" in a:
                    s = _floats(a["value"], self.where(op))
                    s = s * 3 if len(s) == 1 else s
                else:
                    s = _xyz(a, 1.0, self.where(op))
                t = np.diag(list(s) + [1.0])
            elif op.tag == "rotate":
                axis = np.array(_xyz(a, 0.0, self.where(op)))
                angle = a.get("angle", "0")
                ang = np.radians(_floats(angle, self.where(op))[0] if angle.strip() else 0.0)
                nrm = np.linalg.norm(axis)
                if nrm == 0:
                    raise MitsubaXMLError(f"{self.where(op)}: <rotate> needs a nonzero axis")
                x, y, z = axis / nrm
                c, s = np.cos(ang), np.sin(ang)
                r = np.array([[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                              [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
                              [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]])
                t = np.eye(4)
                t[:3, :3] = r
            elif op.tag == "matrix":
                f = _floats(a.get("value", ""), self.where(op))
                if len(f) == 9:
                    t = np.eye(4)
                    t[np.ix_([0, 1, 3], [0, 1, 3])] = np.reshape(f, (3, 3))   # a 3x3 is a 2-D transform
                elif len(f) == 16:
                    t = np.reshape(f, (4, 4))
                else:
                    raise MitsubaXMLError(f"{self.where(op)}: <matrix> needs 9 or 16 values, got {len(f)}")
            else:
                raise MitsubaXMLError(f"{self.where(op)}: unsupported transform operation <{op.tag}>")
            m = t @ m
        return m

    def obj(self, n):
        """A <bsdf>/<texture>/... element -> its plugin dict (nested objects by name, or by
        position as '_arg_<i>' when unnamed; references resolved to the same dict)."""
        d = {"type": self.attr(n, "type"), LINE_KEY: n.line}
        if "id" in n.attrs:
            d["id"] = self.attr(n, "id")
        k = 0
        for c in n.children:
            if c.tag in ("bsdf", "texture", "spectrum") and "type" in c.attrs:
                key = c.attrs.get("name")
                key = self.sub(key, c) if key else f"_arg_{k}"
                k += 1
                val = self.obj(c)
            elif c.tag == "ref":
                rid = self.attr(c, "id")
                if rid not in self.ids:
                    raise MitsubaXMLError(f"{self.where(c)}: <ref id={rid!r}>: no object with that id before it")
                key = c.attrs.get("name") or f"_arg_{k}"
                k += 1
                val = self.ids[rid]
            elif c.tag in ("float", "integer", "boolean", "string", "rgb", "spectrum", "vector", "point", "transform"):
                key, val = self.value(c)
            else:
                raise MitsubaXMLError(f"{self.where(c)}: unsupported element <{c.tag}> inside <{n.tag} "
                                      f"type={d['type']!r}>")
            if key in d:
                raise MitsubaXMLError(f"{self.where(c)}: {key!r} given twice in <{n.tag} type={d['type']!r}>")
            d[key] = val
        if "id" in d:
            self.ids[d["id"]] = d
        return d


def _xyz(a, default, where):
    try:
        return [float(a.get(k, default)) for k in ("x", "y", "z")]
    except ValueError:
        raise MitsubaXMLError(f"{where}: x/y/z must be numbers, got {a}") from None


def read_mitsuba_xml(path, params=None):
    """The BSDFs of a Mitsuba 3 scene file as plugin dicts: ``{name: dict}`` in file order, named
    by their ``id`` (top-level ``<bsdf>``), else ``"<shape id>.bsdf"`` / ``"shape <i> (line n)"``
    for one declared inline in a shape. ``params``: values for ``$name`` (overriding <default>).
    Returns (bsdfs, folder of the file) -- relative image paths are relative to that folder."""
    path = Path(path)
    try:
        text = path.read_bytes()
    except FileNotFoundError:
        raise FileNotFoundError(f"from_mitsuba: scene file not found: {str(path)!r}") from None
    root = _parse(text, path)
    version = root.attrs.get("version", "")
    if version and not version.startswith("3") and not version.startswith("2"):
        raise MitsubaXMLError(f"{path}: scene version {version!r}: only Mitsuba 2/3 files (version 2.x / 3.x) are "
                              "read (Mitsuba 0.6 names such as intIOR are not upgraded)")
    r = _Reader(path, {})
    for c in root.children:
        if c.tag == "default":
            r.params.setdefault(r.attr(c, "name"), r.attr(c, "value", required=False) or "")
    r.params.update({k: str(v) for k, v in (params or {}).items()})
    out = {}
    shape_i = 0
    for c in root.children:
        if c.tag == "bsdf":
            d = r.obj(c)
            name = d.get("id") or f"bsdf (line {c.line})"
            out[name] = d
        elif c.tag == "texture" or (c.tag == "spectrum" and "type" in c.attrs):
            r.obj(c)
        elif c.tag == "shape":
            for s in c.children:
                if s.tag == "bsdf":
                    d = r.obj(s)
                    sid = c.attrs.get("id")
                    name = d.get("id") or (f"{sid}.bsdf" if sid else f"shape {shape_i} (line {c.line})")
                    out[name] = d
            shape_i += 1
        elif c.tag == "include":
            raise MitsubaXMLError(f"{r.where(c)}: <include> is not followed; read the included file itself")
    return out, os.fspath(path.parent.resolve())


def from_mitsuba_file(path, params=None, strict=False, progress=None):
    """``from_mitsuba(scene_file)``: ``{name: model}`` of the scene's BSDFs (see
    :func:`read_mitsuba_xml` for the names); one that cannot be converted is skipped with a
    ``MitsubaSkipWarning`` naming it, its line and the reason, or raises with ``strict=True``."""
    import warnings

    from .mitsuba import MitsubaSkipWarning, from_mitsuba

    if not isinstance(strict, (bool, np.bool_)):
        raise TypeError(f"strict: expected True or False, got {strict!r}")
    from .._progress import PROGRESS_DELAY, Progress, check_progress
    progress = check_progress(progress)
    bsdfs, folder = read_mitsuba_xml(path, params)
    out = {}
    with Progress(progress, len(bsdfs), "BSDFs", "from_mitsuba", delay=PROGRESS_DELAY) as prog:
        for name, d in bsdfs.items():
            try:
                out[name] = from_mitsuba(d, base_dir=folder)
            except (ValueError, NotImplementedError, FileNotFoundError, TypeError) as e:
                if strict:
                    raise
                w = MitsubaSkipWarning(f"from_mitsuba: {path}: skipped BSDF {name!r} (line {d.get(LINE_KEY)}): {e}")
                w.material, w.line, w.file, w.reason = name, d.get(LINE_KEY), os.fspath(path), str(e)
                warnings.warn(w, stacklevel=3)
            prog.advance()
    return out


# --------------------------------------------------------------------------------------- writing

_BSDF_KEYS_TEXTURE = ("bitmap", "checkerboard", "mesh_attribute")


def _xml_attr(s) -> str:
    return (str(s).replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;").replace(">", "&gt;"))


def _fmt_num(x) -> str:
    return repr(float(x))


def _xml_value(name, v, folder, texture_dir, indent, where):
    """One property or nested object of a plugin dict as XML lines."""
    pad = "  " * indent
    na = f' name="{_xml_attr(name)}"' if name is not None else ""
    if isinstance(v, dict):
        kind = v.get("type")
        if kind in ("rgb", "srgb") and set(v) <= {"type", "value", "color"}:
            val = np.broadcast_to(np.asarray(v.get("value", v.get("color")), np.float64).reshape(-1), (3,))
            return [f'{pad}<rgb{na} value="{", ".join(_fmt_num(x) for x in val)}"/>']
        if kind == "spectrum" and set(v) <= {"type", "value"} and np.ndim(v["value"]) == 0:
            return [f'{pad}<spectrum{na} value="{_fmt_num(v["value"])}"/>']
        tag = "texture" if kind in _BSDF_KEYS_TEXTURE else "bsdf"
        v = dict(v)
        if kind == "bitmap" and ("data" in v or "bitmap" in v):   # in memory: written as an EXR file
            from .. import _render_ext
            from .._values import digest
            from ._mitsuba_texture import parse_bitmap

            def fail(w, msg):
                raise ValueError(f"to_mitsuba_file: {where}: {msg}")
            bm = parse_bitmap({k: x for k, x in v.items() if k in ("type", "data", "bitmap", "raw")}, where, None, fail)
            px = bm.source
            if bm.encoding == "sRGB":
                from ..io import srgb_to_linear
                px = srgb_to_linear(px)
            v.pop("data", None), v.pop("bitmap", None)
            px = np.ascontiguousarray(px, dtype=np.float32)
            os.makedirs(texture_dir, exist_ok=True)
            path = os.path.join(texture_dir, f"bsdfkit-{digest(px)}.exr")
            if not os.path.exists(path):
                _render_ext.load().write_image(path, px)
            v["filename"], v["raw"] = path, True
        if kind == "bitmap" and isinstance(v.get("filename"), str):
            fn = os.path.abspath(v["filename"])
            rel = os.path.relpath(fn, folder)
            v["filename"] = fn if rel.startswith("..") else rel.replace(os.sep, "/")
        lines = [f'{pad}<{tag} type="{_xml_attr(kind)}"{na}>']
        for k, x in v.items():
            if k in ("type", LINE_KEY):
                continue
            lines += _xml_value(None if k.startswith("_arg_") else k, x, folder, texture_dir, indent + 1,
                                f"{where}.{k}")
        return lines + [f"{pad}</{tag}>"]
    if isinstance(v, (bool, np.bool_)):
        return [f'{pad}<boolean{na} value="{"true" if v else "false"}"/>']
    if isinstance(v, (int, np.integer)):
        return [f'{pad}<integer{na} value="{int(v)}"/>']
    if isinstance(v, (float, np.floating)):
        return [f'{pad}<float{na} value="{_fmt_num(v)}"/>']
    if isinstance(v, str):
        return [f'{pad}<string{na} value="{_xml_attr(v)}"/>']
    m = getattr(v, "matrix", None)
    if m is not None:   # a Mitsuba transform (to_uv)
        a = np.array(m, np.float64)
        if a.shape == (3, 3):
            b = np.eye(4)
            b[np.ix_([0, 1, 3], [0, 1, 3])] = a
            a = b
        return [f'{pad}<transform{na}>', f'{pad}  <matrix value="{" ".join(_fmt_num(x) for x in a.reshape(-1))}"/>',
                f"{pad}</transform>"]
    a = np.asarray(v, dtype=np.float64)
    if a.shape == (3,):
        return [f'{pad}<rgb{na} value="{", ".join(_fmt_num(x) for x in a)}"/>']
    raise ValueError(f"to_mitsuba_file: {where}: cannot write {type(v).__name__} {v!r} as Mitsuba XML"[:300])


def to_mitsuba_file(models, path, *, texture_dir=None, approximate=False):
    """Write models as a Mitsuba 3 scene file of ``<bsdf id=...>`` elements (``mi.load_file``
    parses it; ``from_mitsuba(path)`` reads it back): ``models`` is ``{id: model}`` (or one model,
    id ``"bsdf"``). Each is exported by its ``to_mitsuba`` (textured models: image files are
    referenced relative to the file when inside its folder, absolute otherwise; textures built
    from arrays are written as EXR files into ``texture_dir``, default the file's folder).
    Returns the path."""
    from ..models.base import BxDF
    if isinstance(models, BxDF):
        models = {"bsdf": models}
    if not isinstance(models, dict) or not all(isinstance(m, BxDF) for m in models.values()):
        raise TypeError("to_mitsuba_file: models: expected a bsdfkit model or a dict {id: model}")
    path = os.path.abspath(os.fspath(path))
    folder = os.path.dirname(path)
    texture_dir = os.path.abspath(os.fspath(texture_dir)) if texture_dir is not None else folder
    lines = ['<scene version="3.0.0">']
    for name, m in models.items():
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_.\-]*", name):
            raise ValueError(f"to_mitsuba_file: model id {name!r}: expected an XML-safe name (letters, digits, _ . -)")
        if getattr(m, "textures", None):
            from ._mitsuba_textured_export import textured_to_mitsuba
            d = textured_to_mitsuba(m, approximate, texture_dir, _plain=True)
        else:
            d = m.to_mitsuba(approximate=approximate)
        body = _xml_value(None, d, folder, texture_dir, 1, name)
        body[0] = body[0][:-1] + f' id="{_xml_attr(name)}">'
        lines += body
    lines.append("</scene>")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines) + "\n")
    return path
