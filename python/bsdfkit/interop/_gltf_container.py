"""The glTF 2.0 container, read without a dependency (for :mod:`bsdfkit.interop.gltf`): a
``.gltf`` file is JSON with external or ``data:`` URI buffers and images; a ``.glb`` file is a
12-byte header (magic ``glTF``, version 2, length) and chunks (a JSON chunk, then an optional
``BIN`` chunk holding buffer 0) -- glTF 2.0 specification, "Binary glTF Layout". Also the images
(PNG / JPEG) and the checked reads of numbers and objects that name where a bad value is."""
from __future__ import annotations

import base64
import binascii
import io
import json
import math
import os
import struct
import urllib.parse

import numpy as np

_GLB_MAGIC, _CHUNK_JSON, _CHUNK_BIN = 0x46546C67, 0x4E4F534A, 0x004E4942
_PNG_MAGIC, _JPEG_MAGIC = b"\x89PNG\r\n\x1a\n", b"\xff\xd8\xff"
_MIME_SUFFIX = {"image/png": ".png", "image/jpeg": ".jpg"}


class _GltfError(ValueError):
    pass


# ---------------------------------------------------------------- container

def _read_container(path):
    """(the JSON document, the GLB BIN chunk or None)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF" or path.lower().endswith(".glb"):
        return _read_glb(data, path)
    return _parse_json(data, path), None


def _parse_json(data, where):
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise _GltfError(f"{where}: the glTF JSON is not UTF-8 (byte {e.start})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise _GltfError(f"{where}: not valid glTF JSON: {e.msg} at line {e.lineno} column {e.colno}") from None
    except RecursionError:
        raise _GltfError(f"{where}: not valid glTF JSON: nested too deeply") from None
    if not isinstance(doc, dict):
        raise _GltfError(f"{where}: a glTF document is a JSON object, got {type(doc).__name__}")
    asset = doc.get("asset")
    version = asset.get("version") if isinstance(asset, dict) else None
    if not isinstance(version, str) or version.split(".")[0] != "2":
        raise _GltfError(f"{where}: asset.version must be \"2.x\" (glTF 2.0), got {version!r}"
                         + (" (glTF 1.0 materials are techniques, not metallic-roughness)" if version == "1.0" else ""))
    return doc


def _read_glb(data, path):
    """A GLB container (glTF 2.0 spec, "Binary glTF Layout"): header, JSON chunk, optional BIN chunk."""
    if len(data) < 12:
        raise _GltfError(f"{path}: truncated GLB header ({len(data)} bytes, a header is 12)")
    magic, version, length = struct.unpack_from("<III", data, 0)
    if magic != _GLB_MAGIC:
        raise _GltfError(f"{path}: not a GLB file (magic {data[:4]!r}, expected b'glTF')")
    if version != 2:
        raise _GltfError(f"{path}: GLB container version {version}, only version 2 (glTF 2.0) is read")
    if length > len(data):
        raise _GltfError(f"{path}: truncated GLB: the header gives {length} bytes, the file has {len(data)}")
    pos, chunks = 12, []
    while pos + 8 <= length:
        clen, ctype = struct.unpack_from("<II", data, pos)
        if pos + 8 + clen > length:
            raise _GltfError(f"{path}: GLB chunk {len(chunks)} at byte {pos} runs past the end "
                             f"({clen} bytes from byte {pos + 8}, total length {length})")
        chunks.append((ctype, data[pos + 8:pos + 8 + clen]))
        pos += 8 + clen + (-clen) % 4 if clen % 4 else 8 + clen
    if not chunks or chunks[0][0] != _CHUNK_JSON:
        raise _GltfError(f"{path}: the first GLB chunk must be JSON (type 0x4E4F534A)"
                         + (f", got type {chunks[0][0]:#010x}" if chunks else ", the file has no chunk"))
    doc = _parse_json(chunks[0][1], f"{path} (GLB JSON chunk)")
    binary = chunks[1][1] if len(chunks) > 1 and chunks[1][0] == _CHUNK_BIN else None
    return doc, binary


def _data_uri(uri, where):
    """The bytes of a base64 ``data:`` URI (RFC 2397)."""
    head, sep, payload = uri.partition(",")
    if not sep or not head.endswith(";base64"):
        raise _GltfError(f"{where}: a data: URI must be base64 (\"data:<type>;base64,...\"), got {uri[:40]!r}")
    try:
        return base64.b64decode(payload, validate=True), head[5:-7]
    except (binascii.Error, ValueError) as e:
        raise _GltfError(f"{where}: bad base64 in the data: URI ({e})") from None


class _Doc:
    """A glTF document with lazy, cached buffer and image access."""

    def __init__(self, path):
        self.path = os.fspath(path)
        self.base = os.path.dirname(os.path.abspath(self.path))
        self.json, self.bin = _read_container(self.path)
        self._buffers, self._images = {}, {}

    def array(self, name):
        a = self.json.get(name, [])
        if not isinstance(a, list):
            raise _GltfError(f"{self.path}: {name} must be a JSON array, got {type(a).__name__}")
        return a

    def item(self, name, index, where):
        a = self.array(name)
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(a):
            raise _GltfError(f"{where}: {name}[{index!r}] does not exist (the file has {len(a)})")
        if not isinstance(a[index], dict):
            raise _GltfError(f"{where}: {name}[{index}] must be a JSON object")
        return a[index]

    def file(self, uri, what, where):
        """A relative URI (percent-decoded, relative to the glTF file) -> existing path."""
        if "://" in uri:
            raise _GltfError(f"{where}: {what} URI {uri!r}: only relative paths and data: URIs are read")
        p = os.path.join(self.base, urllib.parse.unquote(uri))
        if not os.path.isfile(p):
            raise FileNotFoundError(f"{where}: {what} file not found: {p}")
        return p

    def buffer(self, b, where):
        if b in self._buffers:
            return self._buffers[b]
        buf = self.item("buffers", b, where)
        uri, w = buf.get("uri"), f"{where} -> buffers[{b}]"
        if uri is None:
            if b != 0 or self.bin is None:
                raise _GltfError(f"{w} has no uri" + (" and the GLB file has no BIN chunk" if b == 0 else
                                                     " (only buffer 0 of a GLB file may omit it)"))
            data = self.bin
        elif not isinstance(uri, str):
            raise _GltfError(f"{w}: uri must be a string")
        elif uri.startswith("data:"):
            data = _data_uri(uri, w)[0]
        else:
            with open(self.file(uri, "buffer", w), "rb") as f:
                data = f.read()
        n = buf.get("byteLength")
        if isinstance(n, int) and not isinstance(n, bool) and len(data) < n:
            raise _GltfError(f"{w}: {len(data)} bytes, byteLength says {n}")
        self._buffers[b] = data
        return data

    def image(self, k, where):
        """Image ``k``: (a path, or a uint8 / uint16 array (H, W, C) decoded by Pillow, None), or
        (None, reason) for a format left out."""
        if k in self._images:
            return self._images[k]
        img = self.item("images", k, where)
        w = f"{where} -> images[{k}]"
        uri, mime = img.get("uri"), img.get("mimeType")
        if uri is not None:
            if not isinstance(uri, str):
                raise _GltfError(f"{w}: uri must be a string")
            if uri.startswith("data:"):
                data, mime = _data_uri(uri, w)
                out = _decode(data, mime, w)
            else:
                p = self.file(uri, "image", w)
                with open(p, "rb") as f:
                    head = f.read(8)
                if head[:8] != _PNG_MAGIC and head[:3] != _JPEG_MAGIC:
                    out = (None, f"{w}: image {os.path.basename(p)!r} is neither PNG nor JPEG (glTF 2.0's image formats)")
                else:
                    out = _open_image(p, w)
        elif "bufferView" in img:
            bv = self.item("bufferViews", img["bufferView"], w)
            off, n = bv.get("byteOffset", 0), bv.get("byteLength")
            if any(isinstance(x, bool) or not isinstance(x, int) or x < 0 for x in (off, n)):
                raise _GltfError(f"{w}: bufferViews[{img['bufferView']}]: byteOffset / byteLength must be "
                                 f"non-negative integers, got {off!r} / {n!r}")
            data = self.buffer(bv.get("buffer"), f"{w} -> bufferViews[{img['bufferView']}]")
            if off + n > len(data):
                raise _GltfError(f"{w}: bufferViews[{img['bufferView']}] (bytes {off} to {off + n}) runs past "
                                 f"the end of buffers[{bv.get('buffer')}] ({len(data)} bytes)")
            out = _decode(data[off:off + n], mime, w)
        else:
            raise _GltfError(f"{w}: an image needs a uri or a bufferView")
        self._images[k] = out
        return out


def _decode(data, mime, where):
    """Embedded PNG / JPEG bytes -> (an image array, None), or (None, reason) for another format."""
    if data[:8] != _PNG_MAGIC and data[:3] != _JPEG_MAGIC:
        if mime not in _MIME_SUFFIX and mime is not None:
            return None, f"{where}: embedded {mime} image (only PNG and JPEG are read)"
        raise _GltfError(f"{where}: embedded image data is neither PNG nor JPEG (mimeType {mime!r})")
    return _open_image(io.BytesIO(data), where)


def _open_image(src, where):
    """(path or array, None) of a PNG / JPEG file or stream. OpenImageIO reads PNGs with alpha
    premultiplied (associated), glTF's colours are not: images with alpha, and embedded ones, are
    decoded by Pillow (matplotlib's dependency) to uint8 / uint16 arrays, which bk.Texture scales
    to [0, 1]; other files go to bk.Texture by path (any bit depth). Pillow reads 16-bit RGB(A)
    PNGs as 8-bit (16-bit grey stays 16-bit): such images, with alpha or embedded, lose their low byte."""
    from PIL import Image
    try:
        with Image.open(src) as im:
            mode, alpha = im.mode, "A" in im.mode or "transparency" in im.info
            if isinstance(src, str) and not alpha:
                return src, None
            if mode in ("I;16", "I;16B", "I;16L"):
                return np.asarray(im, dtype=np.uint16), None
            if alpha:
                im = im.convert("LA" if mode in ("L", "LA", "I", "I;16") else "RGBA")
            elif mode not in ("L", "RGB"):
                im = im.convert("RGB")
            a = np.asarray(im)
    except (OSError, SyntaxError, ValueError) as e:   # Pillow: UnidentifiedImageError is an OSError
        raise _GltfError(f"{where}: cannot decode the image: {e}") from None
    return a, None


# ---------------------------------------------------------------- value checks

def _num(obj, key, default, where, lo=-math.inf, hi=math.inf):
    v = obj.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not lo <= v <= hi:
        raise _GltfError(f"{where}.{key}: expected a number in [{lo}, {hi}], got {v!r}")
    return float(v)


def _vec(obj, key, default, n, where, lo=0.0, hi=1.0):
    v = obj.get(key, default)
    if not isinstance(v, list) or len(v) != n or any(
            isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) or not lo <= x <= hi
            for x in v):
        raise _GltfError(f"{where}.{key}: expected {n} numbers in [{lo}, {hi}], got {v!r}")
    return np.array(v, dtype=np.float64)


def _obj(obj, key, where):
    v = obj.get(key, {})
    if not isinstance(v, dict):
        raise _GltfError(f"{where}.{key}: must be a JSON object, got {type(v).__name__}")
    return v
