"""MaterialX documents -> bsdfkit models (:func:`from_materialx`): the ``gltf_pbr`` and
``UsdPreviewSurface`` shading models as :class:`bsdfkit.FilamentStandard`, ``open_pbr_surface``
as :class:`bsdfkit.OpenPBR` and ``standard_surface`` as OpenPBR through MaterialX's own translation
graph (``libraries/bxdf/translation/standard_surface_to_open_pbr.mtlx``, evaluated here on the
material's values), with ``image`` / ``tiledimage`` nodes as ``bk.Texture`` values and
``normalmap`` nodes as ``bk.NormalMap``.

The document is read, upgraded and traversed with MaterialX's own Python package (``materialx``
on PyPI, an optional dependency: ``pip install materialx``); the node definitions (input types
and defaults) are MaterialX's standard data libraries shipped with it. MaterialX keeps no source
lines, so the lines named in errors come from one pass of the standard library's expat parser
over the same text (element name paths -> line). ``gltf_pbr`` is glTF's metallic-roughness
material: it goes through :mod:`bsdfkit.interop.gltf`'s one mapping (``_material``).
"""
from __future__ import annotations

import math
import os
import warnings
import xml.parsers.expat

import numpy as np

from .._progress import PROGRESS_DELAY, Progress, check_progress

__all__ = ["MaterialXWarning", "from_materialx", "MATERIALX_SHADING_MODELS"]

#: Surface shader nodes read.
MATERIALX_SHADING_MODELS = ("gltf_pbr", "UsdPreviewSurface", "open_pbr_surface", "standard_surface")

#: MaterialX colour spaces (MaterialX spec, "Color Spaces") -> bk.Texture encoding.
_ENCODING = {"srgb_texture": "sRGB", "lin_rec709": "linear", "raw": "linear", "g22_rec709": "gamma 2.2",
             "none": "linear", "": "linear"}
_FILTER = {"closest": "nearest", "linear": "bilinear", "cubic": "bicubic"}
_WRAP = {"periodic": "periodic", "clamp": "clamp", "mirror": "mirror"}

_FLOAT_TYPES = {"float": 1, "integer": 1, "color3": 3, "vector3": 3, "vector2": 2, "color4": 4, "vector4": 4}


class MaterialXWarning(UserWarning):
    """Something of a MaterialX material that the bsdfkit model leaves out or approximates
    (emission, occlusion, displacement, glTF extensions without a FilamentStandard parameter,
    UsdPreviewSurface's tinted metal F90, OpenPBR inputs dropped by ``approximate=True``, ...): one
    warning per material, attributes ``file``, ``material`` and ``left_out`` (a tuple of one
    sentence per item). Turn it into an error with
    ``warnings.simplefilter("error", MaterialXWarning)``."""


class _MxError(ValueError):
    pass


def _import_materialx():
    try:
        import MaterialX as mx
    except ImportError:
        raise ImportError("bsdfkit.from_materialx needs the MaterialX Python package: pip install materialx "
                          "(or pip install 'bsdfkit[materialx]')") from None
    return mx


_LIBRARY = None


def _library(mx):
    """MaterialX's standard data libraries (node definitions), loaded once."""
    global _LIBRARY
    if _LIBRARY is None:
        lib = mx.createDocument()
        mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
        _LIBRARY = lib
    return _LIBRARY


# ---------------------------------------------------------------- source and lines

def _line_map(text, label):
    """{element name path: line} of a MaterialX document, the root's version string and line;
    malformed XML fails with expat's line and column."""
    lines, stack, root = {}, [], {}

    def start(tag, attrs):
        name = attrs.get("name") if root else None
        if not root:
            root.update(tag=tag, version=attrs.get("version"), line=p.CurrentLineNumber)
        elif name:
            lines.setdefault("/".join([n for n in stack if n] + [name]), p.CurrentLineNumber)
        stack.append(name)

    def end(tag):
        stack.pop()

    p = xml.parsers.expat.ParserCreate()
    p.StartElementHandler, p.EndElementHandler = start, end
    try:
        p.Parse(text, True)
    except xml.parsers.expat.ExpatError as e:
        raise _MxError(f"{label}not a well-formed MaterialX document: {xml.parsers.expat.errors.messages[e.code]} "
                       f"at line {e.lineno}, column {e.offset + 1}") from None
    if root.get("tag") != "materialx":
        raise _MxError(f"{label}not a MaterialX document: the root element is <{root.get('tag')}> "
                       f"(line {root.get('line')}), expected <materialx>")
    return lines, root


def _source(source):
    """(text, path or None) of from_materialx's argument."""
    if isinstance(source, (bytes, bytearray)):
        raise TypeError("source: expected MaterialX text (str) or a path (str or os.PathLike), got bytes "
                        "(decode the text first)")
    if isinstance(source, os.PathLike) or (isinstance(source, str) and "<" not in source):
        if not isinstance(source, os.PathLike) and not isinstance(source, str):
            raise TypeError(f"source: expected MaterialX text or a path, got {type(source).__name__}")
        path = os.fspath(source).strip() if isinstance(source, str) else os.fspath(source)
        if not os.path.isfile(path):
            raise FileNotFoundError(f"source: MaterialX file not found: {path}")
        try:
            with open(path, encoding="utf-8") as f:
                return f.read(), path
        except UnicodeDecodeError as e:
            raise ValueError(f"{path}: not a MaterialX document (not UTF-8 text at byte {e.start})") from None
    if not isinstance(source, str):
        raise TypeError(f"source: expected MaterialX text (str) or a path (str or os.PathLike), "
                        f"got {type(source).__name__}")
    return source, None


# ---------------------------------------------------------------- the reader

class _Reader:
    def __init__(self, mx, doc, lines, label, base):
        self.mx, self.doc, self.lines, self.label, self.base = mx, doc, lines, label, base
        self._textures, self._depth = {}, 0

    # -- where
    def line(self, elem):
        n = self.lines.get(elem.getNamePath())
        if n is not None:
            return f"line {n}"
        uri = elem.getActiveSourceUri()
        return f"in {uri}" if uri else "line ?"

    def require_def(self, node):
        """The node's definition; none: the input whose type matches no definition of the node, or
        "unknown node" (MaterialX matches a node to a definition by its output and input types)."""
        nd = node.getNodeDef()
        if nd is not None:
            return nd
        cat, typ = node.getCategory(), node.getType()
        defs = [d for d in self.doc.getMatchingNodeDefs(cat)]
        if not defs:
            self.fail(node, f"unknown node {cat!r}: no MaterialX node definition of it")
        same = [d for d in defs if d.getType() == typ] or defs
        for inp in node.getInputs():
            want = {d.getActiveInput(inp.getName()).getType() for d in same if d.getActiveInput(inp.getName())}
            if not want:
                self.fail(node, f"unknown input {inp.getName()!r} of a {cat} node", inp)
            if inp.getType() not in want:
                self.fail(node, f"type {inp.getType()}, the {cat} node definition says {' or '.join(sorted(want))}", inp)
        self.fail(node, f"type {typ}: no {cat} node definition has this output type "
                  f"({', '.join(sorted({d.getType() for d in defs}))})")

    def node_label(self, node):
        return f"node {node.getName()!r} ({node.getCategory()}, {self.line(node)})"

    def fail(self, node, msg, inp=None):
        what = self.node_label(node) if inp is None else \
            f"input {inp.getName()!r} ({self.line(inp)}) of {self.node_label(node)}"
        raise _MxError(f"{self.label}{what}: {msg}")

    # -- values
    def _parse(self, node, inp, typ, s):
        """A value string of type ``typ`` -> float, int, str or a float64 array."""
        if typ in ("string", "filename"):
            return s
        try:
            if typ == "integer":
                return int(s)
            if typ == "boolean":
                if s not in ("true", "false"):
                    raise ValueError
                return s == "true"
            parts = [float(x) for x in s.split(",")]
        except ValueError:
            self.fail(node, f"cannot read {s!r} as a {typ} value", inp)
        n = _FLOAT_TYPES.get(typ)
        if n is None:
            self.fail(node, f"type {typ} is not a value type bsdfkit reads", inp)
        if len(parts) != n or not all(math.isfinite(x) for x in parts):
            self.fail(node, f"expected {n} finite number(s) for a {typ} value, got {s!r}", inp)
        return parts[0] if n == 1 else np.array(parts, dtype=np.float64)

    def _constant_colour(self, node, inp, typ, v):
        """A constant colour in the input's colour space -> linear Rec.709 (MaterialX converts
        colour3/4 values to the working space, lin_rec709)."""
        cs = inp.getActiveColorSpace() if typ in ("color3", "color4") else ""
        if cs in ("", "lin_rec709", "raw", "none"):
            return v
        if cs == "srgb_texture":   # IEC 61966-2-1 decoding
            a = np.asarray(v, dtype=np.float64)
            return np.where(a <= 0.04045, a / 12.92, ((a + 0.055) / 1.055) ** 2.4)
        if cs == "g22_rec709":
            return np.sign(v) * np.abs(v) ** 2.2
        self.fail(node, f"colorspace {cs!r}: only srgb_texture, g22_rec709, lin_rec709 and raw are read "
                  "(other primaries need a colour-space conversion bsdfkit does not do)", inp)

    def value(self, node, name):
        """The value of input ``name`` of ``node``: ("const", value) or ("tex", texture, upstream node)."""
        nd = self.require_def(node)
        dinp = nd.getActiveInput(name)
        typ = dinp.getType()
        inp = node.getInput(name)
        if inp is None:
            s = dinp.getValueString()
            return ("const", self._parse(node, dinp, typ, s) if s else None)
        return self._input_value(node, inp, typ)

    def _input_value(self, node, inp, typ):
        if inp.getType() != typ:
            self.fail(node, f"type {inp.getType()}, the {node.getCategory()} node definition says {typ}", inp)
        if inp.hasInterfaceName():
            iface = inp.getInterfaceInput()
            if iface is None:
                self.fail(node, f"interfacename {inp.getInterfaceName()!r} names no input of the node graph", inp)
            return self._input_value(node, iface, typ)
        up = self._upstream(node, inp)
        if up is None:
            s = inp.getValueString()
            if not s:
                return ("const", None)
            return ("const", self._constant_colour(node, inp, typ, self._parse(node, inp, typ, s)))
        return self._node_value(node, inp, up, typ)

    def _upstream(self, node, inp):
        if inp.getNodeName() or inp.hasNodeGraphString() or inp.hasOutputString():
            out = inp.getConnectedOutput()
            up = out.getConnectedNode() if out is not None else inp.getConnectedNode()
            if up is None:
                target = inp.getNodeName() or inp.getNodeGraphString() or inp.getOutputString()
                self.fail(node, f"connected to {target!r}, which is not a node of the document "
                          "(or a node graph output without a node)", inp)
            return up
        return None

    def _node_value(self, node, inp, up, typ):
        cat = up.getCategory()
        if up.getType() != typ:
            self.fail(node, f"connected to {self.node_label(up)} of type {up.getType()}, the input is {typ}", inp)
        if cat in ("constant", "dot"):
            self.require_def(up)
            self._depth += 1
            if self._depth > 64:
                self.fail(up, "a chain of more than 64 dot / constant nodes (or a cycle)")
            try:
                return self.value(up, "value" if cat == "constant" else "in")
            finally:
                self._depth -= 1
        if cat in ("image", "tiledimage"):
            return ("tex", self.texture(up), up)
        if cat == "normalmap":
            return ("normalmap", up, up)
        self.require_def(up)
        self.fail(up, f"{cat!r} nodes are not read: only image, tiledimage, normalmap, constant and dot "
                  "nodes (and their node graphs) give a shading model's inputs; compute other graphs into an "
                  f"image (MaterialX's baketextures) (it feeds input {inp.getName()!r} of {self.node_label(node)})")

    # -- textures
    def texture(self, node):
        """bk.Texture of an ``image`` / ``tiledimage`` node (MaterialX spec, "Texture nodes")."""
        key = node.getNamePath()
        if key in self._textures:
            return self._textures[key]
        from ..textures import Texture

        self.require_def(node)
        typ = node.getType()
        if typ not in ("float", "color3", "vector3"):
            self.fail(node, f"type {typ}: image nodes of type float, color3 and vector3 are read")
        get = lambda n: self.value(node, n)   # noqa: E731
        for n in [i.getName() for i in node.getInputs()]:
            if node.getNodeDef().getActiveInput(n) is None:
                self.fail(node, f"unknown input {n!r} of a {node.getCategory()} node")
        # file: fileprefix applied (getResolvedValueString), relative to the document's directory
        finp = node.getInput("file")
        if finp is not None and finp.hasInterfaceName():
            finp = finp.getInterfaceInput() or finp
        if finp is None or not finp.getValueString():
            self.fail(node, "no file")
        if finp.getType() != "filename":
            self.fail(node, f"type {finp.getType()}, the node definition says filename", finp)
        name = finp.getResolvedValueString()
        path = os.path.normpath(name if os.path.isabs(name) else os.path.join(self.base, name))
        if not os.path.isfile(path):
            raise FileNotFoundError(f"{self.label}input 'file' ({self.line(finp)}) of {self.node_label(node)}: "
                                    f"image file not found: {path}")
        for n in ("layer", "framerange"):
            if node.getNodeDef().getActiveInput(n) is not None and get(n)[1]:
                self.fail(node, f"{n} {get(n)[1]!r}: layers and frame ranges are not read")
        tci = node.getInput("texcoord")
        while tci is not None and tci.hasInterfaceName():
            tci = tci.getInterfaceInput()
        up = self._upstream(node, tci) if tci is not None else None
        if up is not None:
            idx = self.value(up, "index")[1] if up.getCategory() == "texcoord" else None
            if idx != 0:
                self.fail(node, "texcoord: only the default uv set (a texcoord node with index 0) is read")
        filt = _FILTER.get(get("filtertype")[1])
        if filt is None:
            self.fail(node, f"filtertype {get('filtertype')[1]!r}: expected closest, linear or cubic")
        if node.getCategory() == "image":
            wrap = []
            for n in ("uaddressmode", "vaddressmode"):
                m = get(n)[1]
                if m == "constant":
                    d = get("default")[1]
                    if d is not None and np.any(np.asarray(d) != 0):
                        self.fail(node, f"{n} constant with a non-zero default {d}: only a zero default "
                                  "(bk.Texture's black wrap) is read")
                    wrap.append("black")
                elif m in _WRAP:
                    wrap.append(_WRAP[m])
                else:
                    self.fail(node, f"{n} {m!r}: expected constant, clamp, periodic or mirror")
            wrap = wrap[0] if wrap[0] == wrap[1] else tuple(wrap)
            su = sv = 1.0
            ou = ov = 0.0
        else:   # tiledimage: st = (uv uvtiling - uvoffset) / realworldimagesize realworldtilesize, periodic
            til, off = get("uvtiling")[1], get("uvoffset")[1]
            rwi, rwt = get("realworldimagesize")[1], get("realworldtilesize")[1]
            for n, v in (("uvtiling", til), ("uvoffset", off), ("realworldimagesize", rwi),
                         ("realworldtilesize", rwt)):
                if v is None:
                    self.fail(node, f"{n}: expected a constant vector2")
            if np.any(rwi == 0):
                self.fail(node, "realworldimagesize: must not be 0")
            su, sv = til * rwt / rwi
            ou, ov = 0.0 - off * rwt / rwi
            wrap = "periodic"
        # MaterialX's uv (0, 0) is the image's lower-left corner; bk.Texture's is the top-left
        transform = [[su, 0.0, ou], [0.0, -sv, 1.0 - ov]]
        # colour management applies to colour images only (float and vector data are never converted)
        cs = finp.getActiveColorSpace() if typ == "color3" else ""
        enc = _ENCODING.get(cs)
        if enc is None:
            self.fail(node, f"colorspace {cs!r} of its file: only srgb_texture, g22_rec709, lin_rec709 and raw are "
                      "read (other primaries need a colour-space conversion bsdfkit does not do)")
        try:
            t = Texture(path, filter=filt, wrap=wrap, encoding=enc, channel=0 if typ == "float" else None,
                        transform=transform)
        except FileNotFoundError:
            raise
        except (OSError, ValueError, TypeError) as e:
            self.fail(node, f"{path}: {e}")
        if typ != "float" and t.channels == 2:
            self.fail(node, f"{path}: a {typ} image node needs 1, 3 or 4 channels, the image has 2")
        self._textures[key] = t
        return t

    def normals(self, node, nm):
        """(texture, scale) of a ``normalmap`` node: its ``in`` an image read without colour
        conversion, n = normalize((2 in - 1) (scale, scale, 1)) (MaterialX stdlib ``normalmap``)."""
        for n in ("normal", "tangent", "bitangent"):
            if nm.getInput(n) is not None:
                self.fail(nm, f"input {n!r}: the normal map's frame is the shading frame; a connected or "
                          "given frame is not read")
        v = self.value(nm, "in")
        if v[0] != "tex":
            self.fail(nm, "input 'in': a normalmap node is read with an image / tiledimage node in 'in'")
        s = self.value(nm, "scale")
        if s[0] != "const" or not isinstance(s[1], float):
            self.fail(nm, "input 'scale': expected a constant float")
        return v[1], s[1]


# ---------------------------------------------------------------- shading models

def _check_inputs(r, node):
    nd = node.getNodeDef()
    for inp in node.getInputs():
        if nd.getActiveInput(inp.getName()) is None:
            r.fail(node, f"unknown input {inp.getName()!r} of a {node.getCategory()} node "
                   f"(node definition {nd.getName()})", inp)


def _const(r, node, name, lo=None, hi=None, textured=False, kind="float"):
    """An input's constant value (checked in [lo, hi]) or, with ``textured``, its texture."""
    v = r.value(node, name)
    if v[0] == "normalmap":
        r.fail(node, "a normalmap node only feeds a normal input", node.getInput(name))
    if v[0] == "tex":
        if not textured:
            r.fail(node, f"a texture (node {v[2].getName()!r}) where bsdfkit reads only a constant {kind}",
                   node.getInput(name))
        return v[1]
    x = v[1]
    if x is None:
        r.fail(node, f"input {name!r} has no value")
    if lo is not None and np.any((np.asarray(x) < lo) | (np.asarray(x) > hi)):
        r.fail(node, f"{x if np.isscalar(x) else list(x)} is outside [{lo}, {hi}]",
               node.getInput(name) or node.getNodeDef().getActiveInput(name))
    return x


def _is_tex(x):
    from ..textures import is_texture
    return is_texture(x)


def _changed(r, node, name, default):
    """Whether an input differs from ``default`` (a connection always does)."""
    v = r.value(node, name)
    return v[0] != "const" or (v[1] is not None and np.any(np.asarray(v[1]) != default))


def _usd_preview_surface(r, node, options):
    """(model, notes) of a UsdPreviewSurface node (UsdPreviewSurface spec 2.5 / MaterialX 2.6)."""
    from ..models import FilamentStandard, Mask
    from .gltf import _f0_to_reflectance, _value

    _check_inputs(r, node)
    notes = []
    inp = lambda n: node.getInput(n) or node.getNodeDef().getActiveInput(n)   # noqa: E731
    diffuse = _const(r, node, "diffuseColor", 0.0, 1.0, textured=True)
    rough = _const(r, node, "roughness", 0.0, 1.0, textured=True)
    metallic = _const(r, node, "metallic", 0.0, 1.0, textured=True)
    spec_wf = _const(r, node, "useSpecularWorkflow", 0, 1, kind="integer")
    ior = _const(r, node, "ior", 0.0, 1e30)
    clearcoat = _const(r, node, "clearcoat", 0.0, 1.0, textured=True)
    cc_rough = _const(r, node, "clearcoatRoughness", 0.0, 1.0, textured=True)
    opacity = _const(r, node, "opacity", 0.0, 1.0, textured=True)
    threshold = _const(r, node, "opacityThreshold", 0.0, 1.0)
    mode = _const(r, node, "opacityMode", 0, 1, kind="integer") if node.getNodeDef().getActiveInput("opacityMode") \
        else 0
    # the spec's dielectric F0 = ((1 - ior) / (1 + ior))^2; FilamentStandard f0 = 0.16 reflectance^2 <= 0.16
    f0 = ((1.0 - ior) / (1.0 + ior)) ** 2
    p = {"roughness": rough}   # "usually squared before use with GGX": alpha = roughness^2, as FilamentStandard's
    if spec_wf == 0:
        # metalness workflow: F0 = mix(F0(ior), diffuseColor, metallic), diffuse diffuseColor (1 - metallic):
        # FilamentStandard's f0 = 0.16 reflectance^2 (1 - metallic) + base_color metallic exactly
        if (_is_tex(metallic) or metallic < 1.0) and f0 > 0.16 + 1e-12:
            r.fail(node, f"ior {ior:g} gives a dielectric F0 ((1 - ior) / (1 + ior))^2 = {f0:.4g} above "
                   "FilamentStandard's 0.16 (reflectance 1: ior <= 2.333)", inp("ior"))
        p.update(base_color=diffuse, metallic=metallic, reflectance=float(_f0_to_reflectance(f0)))
        if _is_tex(metallic) or metallic > 0:
            if _is_tex(diffuse) or np.any(np.asarray(diffuse) != 1.0):
                notes.append("metallic: the spec's F90 = mix(white, diffuseColor, metallic) is not reproduced "
                             "(FilamentStandard's F90 is one grey value, its f90 option: 1 or Filament's rule)")
    else:
        # specular workflow: F0 = specularColor, F90 white, diffuse diffuseColor (not reduced)
        spec = _const(r, node, "specularColor", 0.0, 1.0, textured=True)
        black = not _is_tex(diffuse) and np.all(np.asarray(diffuse) == 0)
        if not _is_tex(spec) and np.ptp(spec) == 0 and spec[0] <= 0.16:
            p.update(base_color=diffuse, metallic=0.0, reflectance=float(_f0_to_reflectance(spec[0])))
        elif black:   # a black diffuse: FilamentStandard's metal has f0 = base_color and no diffuse
            p.update(base_color=spec, metallic=1.0)
        else:
            r.fail(node, "specular workflow: a tinted, textured or above-0.16 specularColor over a non-black "
                   "diffuseColor cannot be FilamentStandard (its F0 is a grey 0.16 reflectance^2 for a "
                   "non-metal, or the base colour, which is also the diffuse colour, for a metal); given "
                   f"{'a texture' if _is_tex(spec) else list(spec)}", inp("specularColor"))
    # clearcoat: "Second specular lobe amount. The color is white." with F0 from ior ("including the
    # clearcoat"); FilamentStandard's coat is IOR 1.5 (f0 0.04)
    if _is_tex(clearcoat) or clearcoat > 0:
        if abs(ior - 1.5) > 1e-9:
            r.fail(node, f"clearcoat > 0 with ior {ior:g}: the spec derives the clearcoat's F0 from ior, "
                   "FilamentStandard's coat is IOR 1.5", inp("ior"))
        p.update(clear_coat=clearcoat, clear_coat_roughness=cc_rough)
    # normal: a tangent-space normal in [-1, 1]
    nv = r.value(node, "normal")
    if nv[0] != "const" or nv[1] is None or np.any(nv[1] != np.array([0.0, 0.0, 1.0])):
        r.fail(node, "a normal other than the constant (0, 0, 1) is not read (UsdPreviewSurface takes a "
               "tangent-space normal already in [-1, 1]; gltf_pbr takes a normalmap node)", inp("normal"))
    for name, default, why in (("emissiveColor", 0.0, "emission: bsdfkit models only scatter"),
                               ("occlusion", 1.0, "ambient occlusion is a lighting approximation"),
                               ("displacement", 0.0, "displacement moves the geometry")):
        if _changed(r, node, name, default):
            notes.append(f"{name} ({why})")
    try:
        model = FilamentStandard(**p, **options)
    except (ValueError, TypeError) as e:
        r.fail(node, str(e))
    # opacity (MaterialX's UsdPreviewSurface graph): opacityThreshold > 0 cuts out where opacity < threshold;
    # opacityMode presence (1) takes opacity as coverage; transparent (0) makes it a transmission
    if threshold > 0:
        cut = _value("cutoff", opacity, None, np.array([1.0, threshold])) if _is_tex(opacity) else \
            float(opacity >= threshold)
        if _is_tex(cut) or cut < 1.0:
            model = Mask(model, cut)
    elif _is_tex(opacity) or opacity < 1.0:
        if mode != 1:
            r.fail(node, "opacity < 1 with opacityThreshold 0 and opacityMode transparent is a translucent "
                   "(transmitting) surface; FilamentStandard has no transmission (an opacityThreshold > 0 cut-out "
                   "or opacityMode presence (1) is read as bk.Mask)", inp("opacity"))
        model = Mask(model, opacity)
    return model, notes


class _GltfSlot:
    """A glTF textureInfo stand-in for interop.gltf._material: ``make(channel, encoding)`` gives the
    MaterialX texture feeding the input that channel stands for (the MaterialX image node decides
    the encoding), or 1.0 where that input is constant (the factor is then used alone)."""

    def __init__(self, by_channel, where):
        self.by_channel, self.where = by_channel, where

    def make(self, channel, encoding):
        return self.by_channel.get(channel, 1.0)


def _gltf_pbr(r, node, options):
    """(model, notes) of a gltf_pbr node: its inputs as a glTF material, mapped by interop.gltf."""
    from ._gltf_container import _GltfError
    from .gltf import _material

    _check_inputs(r, node)
    notes, slots = [], {}
    inp = lambda n: node.getInput(n) or node.getNodeDef().getActiveInput(n)   # noqa: E731

    def factor(name, default_tex, lo=0.0, hi=1.0, slot=None, channel=None):
        """The glTF factor of an input: the constant, or 1 with the texture in ``slot``."""
        x = _const(r, node, name, lo, hi, textured=slot is not None)
        if _is_tex(x):
            slots.setdefault(slot, {})[channel] = x
            return default_tex
        return x

    def info(slot):
        return {"_mx": _GltfSlot(slots[slot], slot)} if slot in slots else None

    pbr = {"baseColorFactor": list(np.append(factor("base_color", np.ones(3), slot="bc", channel="rgb"),
                                             factor("alpha", 1.0, slot="bc", channel=3))),
           "metallicFactor": factor("metallic", 1.0, slot="mr", channel=2),
           "roughnessFactor": factor("roughness", 1.0, slot="mr", channel=1)}
    mat = {"pbrMetallicRoughness": pbr, "extensions": {}}
    for key, slot in (("baseColorTexture", "bc"), ("metallicRoughnessTexture", "mr")):
        if info(slot):
            pbr[key] = info(slot)
    ext = mat["extensions"]
    ior = _const(r, node, "ior", 1.0, 1e30)
    if ior != 1.5:
        ext["KHR_materials_ior"] = {"ior": ior}
    sp = factor("specular", 1.0, slot="sp", channel=3)
    sc = factor("specular_color", np.ones(3), 0.0, 1e30, slot="sc", channel="rgb")
    if "sp" in slots or "sc" in slots or sp != 1.0 or np.any(sc != 1.0):
        ext["KHR_materials_specular"] = {"specularFactor": sp, "specularColorFactor": list(sc)}
        for key, slot in (("specularTexture", "sp"), ("specularColorTexture", "sc")):
            if info(slot):
                ext["KHR_materials_specular"][key] = info(slot)
    cc = factor("clearcoat", 1.0, slot="cc", channel=0)
    ccr = factor("clearcoat_roughness", 1.0, slot="ccr", channel=1)
    if "cc" in slots or cc > 0:
        e = ext["KHR_materials_clearcoat"] = {"clearcoatFactor": cc, "clearcoatRoughnessFactor": ccr}
        for key, slot in (("clearcoatTexture", "cc"), ("clearcoatRoughnessTexture", "ccr")):
            if info(slot):
                e[key] = info(slot)
        if r.value(node, "clearcoat_normal")[0] != "const":
            e["clearcoatNormalTexture"] = {}
    shc = factor("sheen_color", np.ones(3), slot="shc", channel="rgb")
    shr = factor("sheen_roughness", 1.0, slot="shr", channel=3)
    if "shc" in slots or np.any(shc > 0):
        e = ext["KHR_materials_sheen"] = {"sheenColorFactor": list(shc), "sheenRoughnessFactor": shr}
        for key, slot in (("sheenColorTexture", "shc"), ("sheenRoughnessTexture", "shr")):
            if info(slot):
                e[key] = info(slot)
    strength = _const(r, node, "anisotropy_strength", 0.0, 1.0)
    rot = _const(r, node, "anisotropy_rotation", -1e30, 1e30)
    if strength > 0:
        ext["KHR_materials_anisotropy"] = {"anisotropyStrength": strength, "anisotropyRotation": rot}
    if r.value(node, "tangent")[0] != "const":
        r.fail(node, "a connected tangent is not read (the models' tangent is the shading frame's x axis)",
               inp("tangent"))
    # inputs without a FilamentStandard parameter: glTF's extension notes, or our own
    for name, default, key in (("transmission", 0.0, "KHR_materials_transmission"),
                               ("iridescence", 0.0, "KHR_materials_iridescence"),
                               ("thickness", 0.0, "KHR_materials_volume"),
                               ("dispersion", 0.0, "KHR_materials_dispersion")):
        if _changed(r, node, name, default):
            ext[key] = {}
    for name, default, why in (("emissive", 0.0, "emission: bsdfkit models only scatter"),
                               ("occlusion", 1.0, "ambient occlusion is a lighting approximation")):
        if _changed(r, node, name, default):
            notes.append(f"{name} ({why})")
    nv = r.value(node, "normal")
    if nv[0] == "normalmap":
        tex, scale = r.normals(node, nv[1])
        mat["normalTexture"] = {"_mx": _GltfSlot({"rgb": tex}, "normal"), "scale": scale}
    elif nv[0] != "const":
        r.fail(node, "the normal must come from a normalmap node", inp("normal"))
    am = _const(r, node, "alpha_mode", 0, 2, kind="integer")
    mat["alphaMode"] = ("OPAQUE", "MASK", "BLEND")[int(am)]
    mat["alphaCutoff"] = _const(r, node, "alpha_cutoff", 0.0, 1.0)

    def ref(doc, obj, key, where, notes_):
        v = obj.get(key)
        return None if v is None else v.get("_mx")

    try:
        model, gnotes = _material(None, 0, mat, options, texture_ref=ref, where=f"gltf_pbr {node.getName()!r}")
    except _GltfError as e:
        r.fail(node, f"glTF mapping: {e}")
    return model, notes + [f"{n} [glTF mapping of gltf_pbr]" for n in gnotes]


# ---------------------------------------------------------------- OpenPBR Surface

#: open_pbr_surface inputs bk.OpenPBR models: its keyword parameters, the same names and defaults
#: (bk.OpenPBR checks their values; its errors are given the input's line here).
_OPBR_MODELLED = (
    "base_weight", "base_color", "base_metalness", "base_diffuse_roughness", "specular_weight", "specular_color",
    "specular_roughness", "specular_roughness_anisotropy", "specular_ior", "transmission_weight",
    "transmission_color", "subsurface_weight", "subsurface_color", "subsurface_scatter_anisotropy", "coat_weight",
    "coat_color", "coat_roughness", "coat_roughness_anisotropy", "coat_ior", "coat_darkening", "fuzz_weight",
    "fuzz_color", "fuzz_roughness", "thin_film_weight", "thin_film_thickness", "thin_film_ior",
    "geometry_thin_walled")
#: open_pbr_surface inputs bk.OpenPBR does not model: refused unless at their default (None: unset,
#: a geometric property), dropped with ``approximate=True``; why.
_OPBR_NOT_MODELLED = {
    "transmission_depth": (0.0, "no interior medium (volume absorption and scattering) behind the transmission"),
    "transmission_scatter": (0.0, "no interior medium (volume absorption and scattering) behind the transmission"),
    "transmission_scatter_anisotropy": (0.0, "no interior medium (volume absorption and scattering) behind the "
                                             "transmission"),
    "transmission_dispersion_scale": (0.0, "no dispersion: one IOR for every wavelength"),
    "emission_luminance": (0.0, "emission: bsdfkit models only scatter"),
    "geometry_coat_normal": (None, "the coat's shading frame is the call's normal= / tangent="),
    "geometry_tangent": (None, "the tangent is the shading frame's x axis (the call's tangent=)"),
    "geometry_coat_tangent": (None, "the coat's shading frame is the call's normal= / tangent="),
}
#: inputs that only act when another one is not at its default: Abbe number at dispersion scale 0,
#: emission colour at luminance 0 (OpenPBR spec); dropped (with a note) along with it.
_OPBR_DEPENDS = {"transmission_dispersion_abbe_number": ("transmission_dispersion_scale", 20.0),
                 "emission_color": ("emission_luminance", 1.0)}
#: ignored, as bk.OpenPBR v1 ignores them (its subsurface is a diffuse lobe, without a mean free path).
_OPBR_IGNORED = ("subsurface_radius", "subsurface_radius_scale")
_OPBR_READ = set(_OPBR_MODELLED) | set(_OPBR_NOT_MODELLED) | set(_OPBR_DEPENDS) | set(_OPBR_IGNORED) | \
    {"geometry_opacity", "geometry_normal"}


class _Opbr:
    """An open_pbr_surface input's value for :func:`_openpbr`: ``v`` a constant (float, bool or a
    float64 RGB), a bsdfkit texture, or ("normalmap", node); errors name ``inp`` (the input's
    element) or, when ``note`` is given, the standard_surface inputs it comes from."""

    def __init__(self, v, inp=None, note=None, authored=True):
        self.v, self.inp, self.note, self.authored = v, inp, note, authored


def _openpbr_inputs(r, node):
    """{open_pbr_surface input: _Opbr} of an open_pbr_surface node: every input of its node definition."""
    _check_inputs(r, node)
    out = {}
    for dinp in node.getNodeDef().getActiveInputs():
        name = dinp.getName()
        v = r.value(node, name)
        x = v[1] if v[0] in ("const", "tex") else ("normalmap", v[1])
        out[name] = _Opbr(x, node.getInput(name) or dinp, authored=node.getInput(name) is not None)
    return out


def _is_default(v, default):
    if isinstance(v, tuple) or _is_tex(v):
        return False
    if default is None or v is None:
        return v is None
    return bool(np.all(np.asarray(v, dtype=np.float64) == default))


def _openpbr(r, node, values, approximate, knobs=None):
    """(model, notes) of OpenPBR Surface inputs ``values`` ({name: _Opbr}) of ``node``: bk.OpenPBR,
    in bk.Mask for a geometry_opacity < 1, in bk.NormalMap for a geometry_normal from a normalmap node."""
    from ..models import Mask, NormalMap, OpenPBR
    from .gltf import GltfValue

    def fail(name, msg):
        o = values[name]
        if o.note:
            r.fail(node, f"{o.note}: {msg}")
        r.fail(node, msg, o.inp)

    def shown(v):
        if _is_tex(v):
            return "a texture"
        if isinstance(v, tuple):
            return f"a normalmap node ({v[1].getName()!r})"
        return f"{v:g}" if isinstance(v, float) else str(list(np.asarray(v).tolist()) if np.ndim(v) else v)

    notes, dropped = [], []
    for name in sorted(set(values) - _OPBR_READ):   # a newer node definition's input, given
        if values[name].authored and values[name].v is not None:
            fail(name, f"input {name!r} of open_pbr_surface is not one bk.OpenPBR reads")
    for name, (default, why) in _OPBR_NOT_MODELLED.items():
        o = values.get(name)
        if o is None or _is_default(o.v, default):
            continue
        if not approximate:
            fail(name, f"{name} = {shown(o.v)} is not modelled by bk.OpenPBR ({why}); from_materialx(..., "
                 "approximate=True) drops it with a warning")
        dropped.append(f"{name} = {shown(o.v)} ({why})")
        for dep, (master, dep_default) in _OPBR_DEPENDS.items():
            if master == name and dep in values and not _is_default(values[dep].v, dep_default):
                dropped.append(f"{dep} = {shown(values[dep].v)} (with {name})")
    kw = {}
    varying = getattr(OpenPBR, "varying_params", {}) or {}
    for name in _OPBR_MODELLED:
        o = values.get(name)
        if o is None or o.v is None:
            continue
        if isinstance(o.v, tuple):
            fail(name, "a normalmap node only feeds geometry_normal")
        if _is_tex(o.v) and name not in varying:
            fail(name, f"a texture for {name}: bk.OpenPBR takes no textures (no per-element parameters); "
                 "bake the material to constants or give one model per texel")
        kw[name] = o.v
    try:
        model = OpenPBR(**kw, **(knobs or {}))
    except (ValueError, TypeError) as e:   # named by its parameter: the input (the longest name it contains)
        named = sorted((k for k in kw if k in str(e)), key=len, reverse=True)
        if named:
            fail(named[0], f"bk.OpenPBR: {e}")
        r.fail(node, f"bk.OpenPBR: {e}")
    # geometry_normal (OpenPBR spec, "Normal maps"): a normalmap node -> bk.NormalMap, n = normalize((2 in - 1)
    # (scale, scale, 1)) (MaterialX stdlib normalmap), as gltf_pbr's normal
    o = values.get("geometry_normal")
    if o is not None and o.v is not None:
        if isinstance(o.v, tuple):
            tex, scale = r.normals(node, o.v[1])
            model = NormalMap(model, GltfValue("normal", tex, params=np.array([float(scale)])))
        elif not approximate:
            fail("geometry_normal", "the normal must come from a normalmap node (else the shading frame is the "
                 "call's normal=); from_materialx(..., approximate=True) drops it with a warning")
        else:
            dropped.append("geometry_normal (not from a normalmap node)")
    # geometry_opacity (OpenPBR spec, "Opacity / Transparency": mix(ambient medium, surface, geometry_opacity),
    # a presence weight) -> bk.Mask, whose rest passes straight through
    o = values.get("geometry_opacity")
    if o is not None and o.v is not None and (_is_tex(o.v) or isinstance(o.v, tuple) or o.v != 1.0):
        if isinstance(o.v, tuple):
            fail("geometry_opacity", "a normalmap node only feeds geometry_normal")
        if not _is_tex(o.v) and not 0.0 <= o.v <= 1.0:
            fail("geometry_opacity", f"{shown(o.v)} is outside [0, 1]")
        model = Mask(model, o.v)
    if dropped:
        notes.append("not modelled by bk.OpenPBR (approximate=True): " + "; ".join(dropped))
    return model, notes


# ---------------------------------------------------------------- standard_surface -> OpenPBR

#: standard_surface inputs MaterialX's translation graph (libraries/bxdf/translation/
#: standard_surface_to_open_pbr.mtlx) has no input for: refused unless at their default, dropped
#: with approximate=True; ``normal`` from a normalmap node is read as OpenPBR's geometry_normal.
_SS_UNTRANSLATED = {
    "specular_rotation": (0.0, "the anisotropy's rotation (rotate the call's tangent= instead)"),
    "coat_rotation": (0.0, "the coat anisotropy's rotation"),
    "transmission_extra_roughness": (0.0, "OpenPBR has no extra transmission roughness"),
    "coat_affect_color": (0.0, "Standard Surface's coat saturation of the base; OpenPBR has none"),
    "coat_normal": (None, "the coat's shading frame is the call's normal= / tangent="),
    "tangent": (None, "the tangent is the shading frame's x axis (the call's tangent=)"),
}
_TRANSLATION = "standard_surface_to_open_pbr_surface"
_TRANSLATION_FILE = "MaterialX's libraries/bxdf/translation/standard_surface_to_open_pbr.mtlx"


def _graph_value(r, node, ng, out, ss, cache, note):
    """The value of translation graph output ``out`` for standard_surface values ``ss`` (per
    interface input: a constant or a texture): the graph's stdlib nodes evaluated on constants
    (MaterialX stdlib semantics, libraries/stdlib/stdlib_defs.mtlx); a texture passes through
    dot / convert nodes, a multiplication by a constant, a conditional whose test is constant and
    a channel extraction (an image texture's channel)."""
    from .. import textures as tx
    from .gltf import GltfValue

    def typed(inp):
        s = inp.getValueString()
        return r._parse(node, inp, inp.getType(), s)

    def input_value(n, name):
        i = n.getInput(name)
        if i is None:
            i = n.getNodeDef().getActiveInput(name) if n.getNodeDef() is not None else None
            if i is None:
                r.fail(node, f"{_TRANSLATION_FILE}: node {n.getName()!r} ({n.getCategory()}) has no input {name!r}")
            return typed(i)
        if i.hasInterfaceName():
            return ss[i.getInterfaceName()]
        if i.getNodeName():
            return node_value(ng.getNode(i.getNodeName()))
        return typed(i)

    def tex_fail(n, name):
        r.fail(node, f"{note}: a texture reaches the {n.getCategory()} node {n.getName()!r} of {_TRANSLATION_FILE} "
               f"(input {name!r}); bsdfkit carries textures through its dot / convert / extract nodes, a product "
               "with a constant and a conditional on constants only")

    def node_value(n):
        key = n.getName()
        if key in cache:
            return cache[key]
        cat = n.getCategory()
        get = lambda k: input_value(n, k)   # noqa: E731
        if cat in ("dot", "convert"):
            v = get("in")
        elif cat == "multiply":
            a, b = get("in1"), get("in2")
            if _is_tex(a) and _is_tex(b):
                tex_fail(n, "in1")
            if _is_tex(b):
                a, b = b, a
            if _is_tex(a):
                f = np.asarray(b, dtype=np.float64)
                v = a if np.all(f == 1.0) else tx.Scale(a, float(f.reshape(-1)[0])) if np.ptp(f) == 0 else \
                    GltfValue("product", a, params=f)
            else:
                v = a * b
        elif cat == "mix":   # mix(bg, fg, mix) = bg (1 - mix) + fg mix
            fg, bg, m = get("fg"), get("bg"), get("mix")
            if _is_tex(m):
                tex_fail(n, "mix")
            if m in (0.0, 1.0):
                v = fg if m == 1.0 else bg
            elif _is_tex(fg) or _is_tex(bg):
                tex_fail(n, "fg" if _is_tex(fg) else "bg")
            else:
                v = bg * (1.0 - m) + fg * m
        elif cat in ("ifgreater", "ifequal"):   # in1 if value1 > (==) value2 else in2
            a, b = get("value1"), get("value2")
            if _is_tex(a) or _is_tex(b):
                tex_fail(n, "value1" if _is_tex(a) else "value2")
            v = get("in1") if (a > b if cat == "ifgreater" else a == b) else get("in2")
        elif cat == "dotproduct":
            a, b = get("in1"), get("in2")
            if _is_tex(a) or _is_tex(b):
                tex_fail(n, "in1" if _is_tex(a) else "in2")
            v = float(np.dot(a, b))
        elif cat == "power":
            a, b = get("in1"), get("in2")
            if _is_tex(a) or _is_tex(b):
                tex_fail(n, "in1" if _is_tex(a) else "in2")
            with np.errstate(invalid="ignore"):   # a negative base: nan, refused by bk.OpenPBR naming the input
                v = float(np.power(float(a), float(b)))
        elif cat == "extract":   # in[index]; of an image texture: its channel index
            a, k = get("in"), int(get("index"))
            if isinstance(a, tx.Texture) and a.channel is None:
                args = a._args()
                v = tx.Texture(args.pop("source"), **{**args, "channel": k})
            elif _is_tex(a):
                tex_fail(n, "in")
            else:
                v = float(np.asarray(a)[k])
        else:
            r.fail(node, f"{_TRANSLATION_FILE}: its {cat} node {n.getName()!r} is not one bsdfkit evaluates "
                   "(dot, convert, multiply, mix, ifgreater, ifequal, dotproduct, power, extract)")
        if isinstance(v, np.ndarray):
            v = v.astype(np.float64)
        cache[key] = v
        return v

    o = ng.getOutput(out)
    return node_value(ng.getNode(o.getNodeName()))


def _graph_sources(ng, out):
    """The interface (standard_surface) inputs upstream of translation graph output ``out``."""
    seen, names, todo = set(), set(), [ng.getNode(ng.getOutput(out).getNodeName())]
    while todo:
        n = todo.pop()
        if n is None or n.getName() in seen:
            continue
        seen.add(n.getName())
        for i in n.getInputs():
            if i.hasInterfaceName():
                names.add(i.getInterfaceName())
            elif i.getNodeName():
                todo.append(ng.getNode(i.getNodeName()))
    return sorted(names)


def _standard_surface(r, node, approximate, knobs=None):
    """(model, notes) of a standard_surface node: its inputs through MaterialX's own translation
    graph to OpenPBR Surface (the graph MaterialX's ShaderTranslator inserts), then :func:`_openpbr`."""
    _check_inputs(r, node)
    lib = r.doc.getDataLibrary() or r.doc
    defs = lib.getMatchingNodeDefs(_TRANSLATION)
    ng = defs[0].getImplementation() if defs else None
    if ng is None or not ng.isA(r.mx.NodeGraph):
        r.fail(node, f"the MaterialX package has no {_TRANSLATION} translation graph ({_TRANSLATION_FILE})")
    nd, snd = defs[0], node.getNodeDef()
    dropped = []
    for name, (default, why) in _SS_UNTRANSLATED.items():
        if snd.getActiveInput(name) is None:
            continue
        v = r.value(node, name)
        if _is_default(v[1] if v[0] in ("const", "tex") else ("normalmap", v[1]), default):
            continue
        if not approximate:
            r.fail(node, f"{name} is not carried to OpenPBR by {_TRANSLATION_FILE} ({why}); from_materialx(..., "
                   "approximate=True) drops it with a warning", node.getInput(name))
        dropped.append(f"{name} ({why})")
    # every translation input: the standard_surface's value (its own default when unset: MaterialX's
    # ShaderTranslator would leave an unset input to the translation node's default, which differs for
    # base 0.8 / base_color 1 against standard_surface's 1 / 0.8, the same product)
    ss = {}
    for dinp in nd.getActiveInputs():
        name = dinp.getName()
        if snd.getActiveInput(name) is None:   # not an input of this standard_surface version
            ss[name] = r._parse(node, dinp, dinp.getType(), dinp.getValueString())
            continue
        v = r.value(node, name)
        if v[0] == "normalmap":
            r.fail(node, "a normalmap node only feeds a normal input", node.getInput(name))
        ss[name] = v[1]
    cache, values = {}, {}
    for o in nd.getActiveOutputs():
        out = o.getName()
        name = out[:-4] if out.endswith("_out") else out
        src = ", ".join(f"{s!r}" + (f" ({r.line(node.getInput(s))})" if node.getInput(s) is not None else "")
                        for s in _graph_sources(ng, out))
        note = f"input(s) {src} -> OpenPBR {name} (through {_TRANSLATION_FILE})"
        values[name] = _Opbr(_graph_value(r, node, ng, out, ss, cache, note), None, note)
    # Standard Surface's normal (not in the translation graph) is OpenPBR's geometry_normal
    if snd.getActiveInput("normal") is not None:
        v = r.value(node, "normal")
        if v[0] == "normalmap" or v[1] is not None:
            values["geometry_normal"] = _Opbr(("normalmap", v[1]) if v[0] == "normalmap" else v[1],
                                              node.getInput("normal"))
    model, notes = _openpbr(r, node, values, approximate, knobs)
    if dropped:
        notes.append("not carried by MaterialX's standard_surface -> OpenPBR translation (approximate=True): "
                     + "; ".join(dropped))
    return model, notes


# ---------------------------------------------------------------- public

def _shader_nodes(r, mat):
    """The surface shader node of a ``surfacematerial`` (through node graph outputs)."""
    inp = mat.getInput("surfaceshader")
    if inp is None:
        r.fail(mat, "no surfaceshader input")
    up = r._upstream(mat, inp)
    if up is None:
        r.fail(mat, "its surfaceshader input is not connected to a shader node", inp)
    return up


def from_materialx(source, *, options=None, approximate=False, openpbr_options=None, progress=None) -> dict:
    """bsdfkit models for the materials of a MaterialX document: ``{name: model}`` in document
    order, each a :class:`~bsdfkit.FilamentStandard` (``gltf_pbr``, ``UsdPreviewSurface``) or a
    :class:`~bsdfkit.OpenPBR` (``open_pbr_surface``, ``standard_surface``), wrapped in
    ``bk.NormalMap`` / ``bk.Mask`` where the material asks for them.

    Needs the MaterialX Python package (``pip install materialx``), which reads, upgrades (older
    versions) and traverses the document; its standard libraries give each node's inputs, types
    and defaults.

    Parameters
    ----------
    source : str or os.PathLike
        A ``.mtlx`` file, or MaterialX XML text (a ``str`` containing ``<``). Image files are
        relative to the document's directory (the working directory for text), after the
        ``fileprefix`` in scope.
    options : dict, optional
        FilamentStandard's keyword-only knobs for every material, as :func:`bsdfkit.from_gltf`'s
        (default Filament's desktop shading). ``{"f90": "one"}`` gives the specifications' Schlick
        Fresnel to a white F90; ``{"energy_compensation": False}`` their single-scattering lobe.
        OpenPBR materials take ``openpbr_options`` instead.
    approximate : bool, default False
        For ``open_pbr_surface`` / ``standard_surface``: inputs bk.OpenPBR does not model, at
        values other than their defaults, are refused (ValueError naming the input, the node and
        their lines); with True they are left out, listed in one :class:`MaterialXWarning` per
        material.
    openpbr_options : dict, optional
        bk.OpenPBR's keyword-only knobs for every ``open_pbr_surface`` / ``standard_surface``
        material: ``{"compensation": "none"}`` (single-scattering GGX lobes) and / or
        ``{"layering": "reciprocal"}``; default bk.OpenPBR's (``"turquin"``, ``"albedo-scaling"``).
    progress : bool or callable, optional
        One bar over the materials converted (their images with them), as
        :func:`bsdfkit.from_pbrt`'s: None (default) shows it on an interactive stderr (a bar in
        Jupyter) once the import has run for a second.

    Returns
    -------
    dict
        ``{name: model}``: each ``surfacematerial`` by its name, following its ``surfaceshader``
        input (directly or through a node graph output) to the shading node. A document without
        ``surfacematerial`` nodes gives its top-level surface shader nodes by their names.

    Notes
    -----
    ``gltf_pbr`` is glTF's metallic-roughness material and goes through :func:`bsdfkit.from_gltf`'s
    mapping: base_color / alpha, metallic, roughness, ior, specular / specular_color, clearcoat /
    clearcoat_roughness, sheen_color / sheen_roughness, anisotropy_strength / _rotation, alpha_mode
    / alpha_cutoff, and ``normal`` from a ``normalmap`` node (``bk.NormalMap``). transmission,
    iridescence, thickness, dispersion, emissive and occlusion are left out with a note, as glTF's
    extensions are.

    ``UsdPreviewSurface`` (UsdPreviewSurface spec 2.5; MaterialX's 2.6 definition adds
    opacityMode): metalness workflow: ``base_color`` = diffuseColor, ``metallic``, ``roughness``
    (the spec squares it for GGX, as FilamentStandard), ``reflectance`` = sqrt(F0 / 0.16) with F0
    = ((1 - ior) / (1 + ior))^2 (refused above 0.16, ior > 2.333, unless metallic is 1); the
    spec's metal F90 = diffuseColor is not reproduced (noted). Specular workflow: a grey
    specularColor s <= 0.16 is ``reflectance`` = sqrt(s / 0.16); over a black diffuseColor any
    specularColor is a metal (``metallic`` 1, ``base_color`` = specularColor); anything else is
    refused naming specularColor. clearcoat / clearcoatRoughness -> ``clear_coat`` /
    ``clear_coat_roughness`` (refused unless ior is 1.5: the spec's coat takes its F0 from ior,
    FilamentStandard's is IOR 1.5). opacityThreshold > 0 -> ``bk.Mask`` of the cut-out (opacity
    >= threshold), opacityMode presence -> ``bk.Mask(opacity)``; opacity < 1 otherwise is a
    transmission and is refused. A normal other than (0, 0, 1) is refused. emissiveColor,
    occlusion and displacement are left out with a note.

    ``open_pbr_surface`` (OpenPBR Surface v1.1; MaterialX's node definition) is ``bk.OpenPBR``
    with the inputs as its keyword parameters (the same names and defaults; bk.OpenPBR checks the
    values). ``geometry_opacity`` < 1 is ``bk.Mask`` (the spec's presence mix with the ambient
    medium); ``geometry_normal`` from a ``normalmap`` node is ``bk.NormalMap``. Not modelled by
    bk.OpenPBR: transmission_depth, transmission_scatter, transmission_scatter_anisotropy (no
    interior medium), transmission_dispersion_scale (no dispersion), emission_luminance,
    geometry_tangent, geometry_coat_normal, geometry_coat_tangent and a geometry_normal not from a
    normalmap node: refused unless at their defaults, or dropped with ``approximate=True``
    (emission_color and transmission_dispersion_abbe_number act only with emission /
    dispersion, as the spec says, and go with them). subsurface_radius / subsurface_radius_scale
    are ignored (bk.OpenPBR's subsurface is a diffuse lobe). A texture on an input is refused
    naming it unless bk.OpenPBR takes that parameter per element (``varying_params``).

    ``standard_surface`` (Autodesk Standard Surface) goes through the translation graph MaterialX
    ships for it (``libraries/bxdf/translation/standard_surface_to_open_pbr.mtlx``, the one its
    ShaderTranslator inserts): its nodes (dot, mix, multiply, ifgreater, ifequal, dotproduct,
    power, extract, convert) are evaluated on the material's values, unset inputs at
    standard_surface's own defaults; the resulting OpenPBR inputs are read as above, errors naming
    the standard_surface inputs they come from. A texture passes through the graph's dot nodes, a
    product with a constant, a conditional on constants and a channel extraction (a textured
    ``opacity``: bk.Mask of the image's first channel), and is refused elsewhere (e.g.
    sheen_roughness, raised to the power 0.4). Standard Surface inputs the graph has no input for
    (specular_rotation, coat_rotation, transmission_extra_roughness, coat_affect_color,
    coat_normal, tangent) are refused unless at their defaults (dropped with ``approximate=True``);
    ``normal`` from a ``normalmap`` node is OpenPBR's geometry_normal.

    Inputs are constants (``colorspace`` srgb_texture / g22_rec709 colours converted to linear),
    ``constant`` / ``dot`` nodes, or ``image`` / ``tiledimage`` nodes (directly or as a node
    graph's outputs, with ``interfacename`` connections followed): a ``bk.Texture`` with
    ``filtertype`` closest / linear / cubic -> nearest / bilinear / bicubic, ``u/vaddressmode``
    periodic / clamp / mirror (constant with a zero default -> black), tiledimage's uvtiling /
    uvoffset / realworld sizes as the uv ``transform``, and the encoding of the file's colour
    space (MaterialX: colour images only; srgb_texture -> sRGB, lin_rec709 / raw / none ->
    linear, g22_rec709 -> gamma 2.2). MaterialX's uv (0, 0) is the image's lower-left corner:
    evaluate with ``uv=`` in MaterialX's convention (the textures flip v). Any other node (math,
    procedural, geometric) is refused naming it and its line.

    Raises
    ------
    ImportError
        The MaterialX package is not installed (with the pip command).
    FileNotFoundError
        The document or an image file (naming the path, the node and its line).
    ValueError
        Malformed XML (line and column), a version newer than the MaterialX package reads, an
        unknown node or input, a wrong type or value, or a construct bsdfkit does not represent,
        naming the node, the input and the line.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> mats = bk.from_materialx('''<?xml version="1.0"?>
    ... <materialx version="1.39">
    ...   <UsdPreviewSurface name="red_sh" type="surfaceshader">
    ...     <input name="diffuseColor" type="color3" value="0.8, 0.1, 0.1" />
    ...     <input name="roughness" type="float" value="0.4" />
    ...   </UsdPreviewSurface>
    ...   <surfacematerial name="red" type="material">
    ...     <input name="surfaceshader" type="surfaceshader" nodename="red_sh" />
    ...   </surfacematerial>
    ... </materialx>''')
    >>> mats["red"].roughness
    0.4
    """
    mx = _import_materialx()
    from .gltf import _OPTIONS

    if not isinstance(approximate, (bool, np.bool_)):
        raise TypeError(f"approximate: expected True or False, got {approximate!r}")
    options = {} if options is None else dict(options)
    for k in options:
        if k not in _OPTIONS:
            raise TypeError(f"options: {k!r} is not a FilamentStandard option ({', '.join(_OPTIONS)})")
    knobs = {} if openpbr_options is None else dict(openpbr_options)
    for k in knobs:
        if k not in ("compensation", "layering"):
            raise TypeError(f"openpbr_options: {k!r} is not a bk.OpenPBR knob (compensation, layering)")
    progress = check_progress(progress)
    text, path = _source(source)
    label = f"{path}: " if path is not None else ""
    prog = None
    try:
        lines, root = _line_map(text, label)
        version = root.get("version") or ""
        try:
            vt = tuple(int(x) for x in version.split("."))
        except ValueError:
            raise _MxError(f"{label}<materialx> (line {root['line']}): version {version!r} is not a MaterialX "
                           "version (major.minor)") from None
        if vt[:2] > tuple(mx.getVersionIntegers()[:2]):
            raise _MxError(f"{label}<materialx> (line {root['line']}): version {version} is newer than the "
                           f"MaterialX package reads ({mx.getVersionString()})")
        doc = mx.createDocument()
        try:
            if path is not None:
                mx.readFromXmlFile(doc, path)
            else:
                mx.readFromXmlString(doc, text)
        except Exception as e:   # MaterialX's ExceptionParseError / ExceptionFileMissing (xi:include)
            raise _MxError(f"{label}MaterialX cannot read the document: {e}") from None
        doc.setDataLibrary(_library(mx))
        cs = doc.getColorSpace()
        if cs not in ("", "lin_rec709"):
            raise _MxError(f"{label}<materialx> (line {root['line']}): colorspace {cs!r}: only lin_rec709 "
                           "(MaterialX's default working space) is read")
        base = os.path.dirname(os.path.abspath(path)) if path is not None else os.getcwd()
        r = _Reader(mx, doc, lines, label, base)
        pairs = [(m.getName(), m, _shader_nodes(r, m)) for m in doc.getMaterialNodes()]
        if not pairs:
            pairs = [(n.getName(), n, n) for n in doc.getNodes() if n.getType() == "surfaceshader"]
        out, notes_all = {}, {}
        prog = Progress(progress, len(pairs), "materials", "from_materialx", delay=PROGRESS_DELAY)
        for name, mat, sh in pairs:
            cat = sh.getCategory()
            r.require_def(sh)
            if cat == "UsdPreviewSurface":
                model, notes = _usd_preview_surface(r, sh, options)
            elif cat == "gltf_pbr":
                model, notes = _gltf_pbr(r, sh, options)
            elif cat == "open_pbr_surface":
                model, notes = _openpbr(r, sh, _openpbr_inputs(r, sh), approximate, knobs)
            elif cat == "standard_surface":
                model, notes = _standard_surface(r, sh, approximate, knobs)
            else:
                r.fail(sh, f"shading model {cat!r} is not read: bsdfkit reads {', '.join(MATERIALX_SHADING_MODELS)}")
            out[name], notes_all[name] = model, notes
            prog.advance()
    except _MxError as e:
        raise ValueError(str(e)) from None
    finally:
        if prog is not None:
            prog.close()
    for name, notes in notes_all.items():
        if notes:
            w = MaterialXWarning(f"from_materialx: {label}material {name!r}: left out: " + "; ".join(notes))
            w.file, w.material, w.left_out = path, name, tuple(notes)
            warnings.warn(w, stacklevel=2)
    return out
