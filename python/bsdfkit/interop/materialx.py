"""MaterialX documents -> bsdfkit models (:func:`from_materialx`): the ``gltf_pbr`` and
``UsdPreviewSurface`` shading models as :class:`bsdfkit.FilamentStandard`, with ``image`` /
``tiledimage`` nodes as ``bk.Texture`` values and ``normalmap`` nodes as ``bk.NormalMap``.

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

__all__ = ["MaterialXWarning", "from_materialx", "MATERIALX_SHADING_MODELS"]

#: Surface shader nodes read, and the ones refused with the reason.
MATERIALX_SHADING_MODELS = ("gltf_pbr", "UsdPreviewSurface")
_PENDING = {
    "standard_surface": "Autodesk Standard Surface layers specular over diffuse by albedo scaling and "
                        "uses Oren-Nayar diffuse and an F82-tint metal: no subset of its inputs is "
                        "FilamentStandard exactly; its successor OpenPBR is pending in bsdfkit",
    "open_pbr_surface": "bsdfkit has no OpenPBR Surface model yet (pending)",
}

#: MaterialX colour spaces (MaterialX spec, "Color Spaces") -> bk.Texture encoding.
_ENCODING = {"srgb_texture": "sRGB", "lin_rec709": "linear", "raw": "linear", "g22_rec709": "gamma 2.2",
             "none": "linear", "": "linear"}
_FILTER = {"closest": "nearest", "linear": "bilinear", "cubic": "bicubic"}
_WRAP = {"periodic": "periodic", "clamp": "clamp", "mirror": "mirror"}

_FLOAT_TYPES = {"float": 1, "integer": 1, "color3": 3, "vector3": 3, "vector2": 2, "color4": 4, "vector4": 4}


class MaterialXWarning(UserWarning):
    """Something of a MaterialX material that the bsdfkit model leaves out or approximates
    (emission, occlusion, displacement, glTF extensions without a FilamentStandard parameter,
    UsdPreviewSurface's tinted metal F90, ...): one warning per material, attributes ``file``,
    ``material`` and ``left_out`` (a tuple of one sentence per item). Turn it into an error with
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


def from_materialx(source, *, options=None) -> dict:
    """bsdfkit models for the materials of a MaterialX document: ``{name: model}`` in document
    order, each a :class:`~bsdfkit.FilamentStandard` (wrapped in ``bk.NormalMap`` / ``bk.Mask``
    where the material asks for them).

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

    ``standard_surface`` and ``open_pbr_surface`` are refused (no subset of Standard Surface's
    inputs is FilamentStandard exactly: it layers specular over diffuse by albedo scaling; OpenPBR
    is pending in bsdfkit).

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

    options = {} if options is None else dict(options)
    for k in options:
        if k not in _OPTIONS:
            raise TypeError(f"options: {k!r} is not a FilamentStandard option ({', '.join(_OPTIONS)})")
    text, path = _source(source)
    label = f"{path}: " if path is not None else ""
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
        for name, mat, sh in pairs:
            cat = sh.getCategory()
            if cat in _PENDING:
                r.fail(sh, f"{cat} is not read: {_PENDING[cat]}")
            r.require_def(sh)
            if cat == "UsdPreviewSurface":
                model, notes = _usd_preview_surface(r, sh, options)
            elif cat == "gltf_pbr":
                model, notes = _gltf_pbr(r, sh, options)
            else:
                r.fail(sh, f"shading model {cat!r} is not read: bsdfkit reads {', '.join(MATERIALX_SHADING_MODELS)}")
            out[name], notes_all[name] = model, notes
    except _MxError as e:
        raise ValueError(str(e)) from None
    for name, notes in notes_all.items():
        if notes:
            w = MaterialXWarning(f"from_materialx: {label}material {name!r}: left out: " + "; ".join(notes))
            w.file, w.material, w.left_out = path, name, tuple(notes)
            warnings.warn(w, stacklevel=2)
    return out
