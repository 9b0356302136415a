"""glTF 2.0 materials -> bsdfkit models (:func:`from_gltf`): the metallic-roughness material and
its ``KHR_materials_*`` extensions as :class:`bsdfkit.FilamentStandard`, Filament's model of it.

The container is read without a dependency (``_gltf_container``: ``.gltf`` JSON with external or
``data:`` URI buffers and images, ``.glb`` binary chunks). Only what materials use is read: the ``materials``,
``textures``, ``samplers``, ``images`` and, for images stored in buffers, the ``bufferViews``
and ``buffers`` they name (a buffer holding only geometry is never opened). A glTF library
(pygltflib) would add a dependency for this much parsing and still leave the errors, the image
decoding and every material rule to this module.
"""
from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field

import numpy as np

from .._progress import PROGRESS_DELAY, Progress, check_progress
from ..textures import TextureBase, is_texture
from ._gltf_container import _GltfError, _Doc, _num, _vec, _obj

__all__ = ["GltfMaterial", "GltfWarning", "GltfValue", "read_gltf_materials", "from_gltf", "GLTF_SUPPORTED_EXTENSIONS"]


#: Material extensions mapped onto FilamentStandard parameters (what each sets: see from_gltf).
GLTF_SUPPORTED_EXTENSIONS = ("KHR_materials_clearcoat", "KHR_materials_sheen", "KHR_materials_anisotropy",
                             "KHR_materials_ior", "KHR_materials_specular", "KHR_materials_emissive_strength",
                             "KHR_texture_transform")

#: Why known extensions that have no FilamentStandard parameter are left out.
_UNSUPPORTED_WHY = {
    "KHR_materials_transmission": "no transmission in FilamentStandard",
    "KHR_materials_volume": "no volume (transmission) in FilamentStandard",
    "KHR_materials_diffuse_transmission": "no transmission in FilamentStandard",
    "KHR_materials_dispersion": "no transmission (dispersion) in FilamentStandard",
    "KHR_materials_iridescence": "no thin-film iridescence in FilamentStandard",
    "KHR_materials_unlit": "an unlit material is no BSDF; the metallic-roughness fallback is used",
    "KHR_materials_pbrSpecularGlossiness": "the archived specular-glossiness model; the metallic-roughness "
                                           "parameters are used",
    "KHR_materials_variants": "material variants are a scene feature",
}

# sampler enums (glTF 2.0 Properties Reference, "sampler")
_NEAREST, _LINEAR = 9728, 9729
_MIN_TRILINEAR = (9986, 9987)          # NEAREST_MIPMAP_LINEAR, LINEAR_MIPMAP_LINEAR
_MIN_ALL = (9728, 9729, 9984, 9985, 9986, 9987)
_WRAP = {33071: "clamp", 33648: "mirror", 10497: "periodic"}


#: FilamentStandard's keyword-only knobs that ``options=`` may set.
_OPTIONS = ("diffuse", "visibility", "f90", "energy_compensation", "min_roughness", "clear_coat_layering",
            "clear_coat_ior_change", "dfg_lut_size")


class GltfWarning(UserWarning):
    """Something of a glTF material that the bsdfkit model leaves out (occlusion, emission, an
    extension without a FilamentStandard parameter, a texture on a second uv set, ...): one
    warning per material, attributes ``file``, ``material`` (its index), ``name`` and
    ``left_out`` (a tuple of one sentence per item)."""


@dataclass(frozen=True)
class GltfMaterial:
    """One converted glTF material: ``index`` in the file's ``materials``, the ``name`` used as
    its key (the material's ``name``, ``"material#<index>"`` without one, ``"<name>
    (material#<index>)"`` for a repeated one), the ``model`` and what it leaves out
    (``left_out``: one sentence per item, naming the glTF property)."""

    index: int
    name: str
    model: object = field(repr=False)
    left_out: tuple = ()


# ---------------------------------------------------------------- textures

def _sampler_args(doc, texture, where):
    """bk.Texture's filter and wrap of a glTF sampler (an absent one: repeat, filtering ours:
    bilinear; glTF 2.0 spec, "Samplers")."""
    if "sampler" not in texture:
        return "bilinear", "periodic"
    s = doc.item("samplers", texture["sampler"], where)
    w = f"{where}: samplers[{texture['sampler']}]"
    mag, mn = s.get("magFilter"), s.get("minFilter")
    if mag not in (None, _NEAREST, _LINEAR):
        raise _GltfError(f"{w}.magFilter: expected 9728 or 9729, got {mag!r}")
    if mn is not None and mn not in _MIN_ALL:
        raise _GltfError(f"{w}.minFilter: expected one of {', '.join(map(str, _MIN_ALL))}, got {mn!r}")
    wrap = []
    for key in ("wrapS", "wrapT"):
        v = s.get(key, 10497)
        if v not in _WRAP:
            raise _GltfError(f"{w}.{key}: expected 33071 (clamp), 33648 (mirror) or 10497 (repeat), got {v!r}")
        wrap.append(_WRAP[v])
    # magnification chooses between texels (no uv derivatives: every lookup magnifies); a mipmapped
    # minification filter with a linear level blend is trilinear once derivatives are given
    if mn in _MIN_TRILINEAR and mag != _NEAREST:
        filt = "trilinear"
    elif mag == _NEAREST and mn in (None, _NEAREST, 9984, 9986):
        filt = "nearest"
    else:
        filt = "bilinear"
    return filt, (wrap[0] if wrap[0] == wrap[1] else tuple(wrap))


def _uv_transform(info, where):
    """KHR_texture_transform -> a (2, 3) uv matrix, or None. uv' = T R S uv with the extension's
    offset, rotation (counter-clockwise in uv) and scale: u' = sx c u + sy s v + ox,
    v' = -sx s u + sy c v + oy (KHR_texture_transform README, its example; as CesiumGltf)."""
    ext = _obj(info, "extensions", where).get("KHR_texture_transform")
    if ext is None:
        return None
    if not isinstance(ext, dict):
        raise _GltfError(f"{where}.extensions.KHR_texture_transform: must be a JSON object")
    w = f"{where}.KHR_texture_transform"
    ox, oy = _vec(ext, "offset", [0.0, 0.0], 2, w, -1e30, 1e30)
    sx, sy = _vec(ext, "scale", [1.0, 1.0], 2, w, -1e30, 1e30)
    r = _num(ext, "rotation", 0.0, w)
    c, s = math.cos(r), math.sin(r)
    return np.array([[sx * c, sy * s, ox], [-sx * s, sy * c, oy]])


class _Tex:
    """A resolved glTF texture reference: the image (path or array), sampler and uv transform;
    ``make(channel, encoding)`` builds the bk.Texture."""

    def __init__(self, source, filt, wrap, transform, where):
        self.source, self.filter, self.wrap, self.transform, self.where = source, filt, wrap, transform, where
        self.channels = None

    def make(self, channel, encoding):
        """The bk texture of ``channel`` (an int; "rgb" for an RGB value), or 1.0 where the image
        lacks the channel: the alpha of an image without one (opaque). A grey (+ alpha) image's
        R, G and B are its grey channel, its alpha the second channel."""
        kw = dict(filter=self.filter, wrap=self.wrap, transform=self.transform, encoding=encoding)
        if self.channels is None:   # (a linear probe of a file reads nothing but its header)
            self.channels = self.source.shape[2] if isinstance(self.source, np.ndarray) else \
                self._texture(encoding="linear").channels
        n = self.channels
        if channel == "rgb":   # 1 (replicated), 3 or 4 channels (RGBA: the first three) make an RGB value
            return self._texture(channel=0 if n == 2 else None, **kw)
        if channel == 3 and n in (1, 3):
            return 1.0
        if n <= 2:
            channel = 1 if channel == 3 else 0
        return self._texture(channel=channel, **kw)

    def _texture(self, **kw):
        from ..textures import Texture
        try:
            return Texture(self.source, **kw)
        except FileNotFoundError:
            raise
        except (OSError, ValueError) as e:
            raise _GltfError(f"{self.where}: {e}") from None


def _texture_ref(doc, mat, key, where, notes):
    """The ``key`` textureInfo of ``mat`` as a _Tex, or None (absent, or left out with a note)."""
    info = mat.get(key)
    if info is None:
        return None
    w = f"{where}.{key}"
    if not isinstance(info, dict):
        raise _GltfError(f"{w}: must be a JSON object (a textureInfo)")
    tc = info.get("texCoord", 0)
    ext = _obj(info, "extensions", w).get("KHR_texture_transform")
    if isinstance(ext, dict) and "texCoord" in ext:
        tc = ext["texCoord"]
    if isinstance(tc, bool) or not isinstance(tc, int) or tc < 0:
        raise _GltfError(f"{w}.texCoord: expected a non-negative integer, got {tc!r}")
    if tc != 0:
        notes.append(f"{key} (uses TEXCOORD_{tc}; the models take one uv set, TEXCOORD_0: the factor alone is used)")
        return None
    t = info.get("index")
    texture = doc.item("textures", t, w)
    wt = f"{w} -> textures[{t}]"
    if "source" not in texture:
        exts = sorted(_obj(texture, "extensions", wt))
        notes.append(f"{key} (textures[{t}] has no PNG/JPEG source"
                     + (f", only {', '.join(exts)}" if exts else "") + ": the factor alone is used)")
        return None
    source, why = doc.image(texture["source"], wt)
    if source is None:
        notes.append(f"{key} ({why}: the factor alone is used)")
        return None
    filt, wrap = _sampler_args(doc, texture, wt)
    return _Tex(source, filt, wrap, _uv_transform(info, w), wt)


# ---------------------------------------------------------------- derived values

def _product(factor, tex, channel, encoding):
    """factor x texture (a bk texture), or the factor when there is no texture."""
    if tex is None:
        return factor
    t = tex.make(channel, encoding)
    if not _is_texture(t):
        return factor * t
    f = np.asarray(factor, dtype=np.float64)
    if np.all(f == 1.0):
        return t
    if f.ndim == 0:
        from .. import textures as tx
        return tx.Scale(t, float(f))
    return GltfValue("product", t, params=f)


def _f0_to_reflectance(f0):
    """FilamentStandard's dielectric f0 = 0.16 reflectance^2 -> reflectance."""
    return np.sqrt(np.minimum(np.asarray(f0, dtype=np.float64), 0.16) / 0.16)


# ---------------------------------------------------------------- materials

def _material(doc, i, mat, options, *, texture_ref=_texture_ref, where=None):
    """(model, notes) of materials[i]. Shared with ``interop.materialx`` (its ``gltf_pbr`` node is
    this material): ``texture_ref(doc, obj, key, where, notes)`` resolves a textureInfo (an object
    whose ``make(channel, encoding)`` gives the bk texture of a channel, or None) and ``where``
    prefixes error messages."""
    from ..models import FilamentStandard, Mask, NormalMap, TwoSided
    where = f"materials[{i}]" if where is None else where
    notes = []
    pbr = _obj(mat, "pbrMetallicRoughness", where)
    wp = f"{where}.pbrMetallicRoughness"
    exts = _obj(mat, "extensions", where)
    for name in exts:
        if name not in GLTF_SUPPORTED_EXTENSIONS:
            notes.append(f"{name} ({_UNSUPPORTED_WHY.get(name, 'not a FilamentStandard parameter')})")
    for name, e in exts.items():
        if not isinstance(e, dict):
            raise _GltfError(f"{where}.extensions.{name}: must be a JSON object")

    # core metallic-roughness (glTF 2.0 spec, "Metallic-Roughness Material"): factor x texture,
    # base colour sRGB-decoded, metalness = B and roughness = G of metallicRoughnessTexture, linear
    bcf = _vec(pbr, "baseColorFactor", [1.0, 1.0, 1.0, 1.0], 4, wp)
    bct = texture_ref(doc, pbr, "baseColorTexture", wp, notes)
    metal = _num(pbr, "metallicFactor", 1.0, wp, 0.0, 1.0)
    rough = _num(pbr, "roughnessFactor", 1.0, wp, 0.0, 1.0)
    mrt = texture_ref(doc, pbr, "metallicRoughnessTexture", wp, notes)
    p = {"base_color": _product(bcf[:3], bct, "rgb", "sRGB"),
         "metallic": _product(metal, mrt, 2, "linear")}
    # glTF roughness is perceptual: alpha = roughness^2 (glTF 2.0 spec, Appendix B "Microfacet
    # Surfaces"), which is FilamentStandard's roughness (alpha = roughness^2): passed as it is
    rough_v = _product(rough, mrt, 1, "linear")

    # dielectric f0: KHR_materials_ior f0 = ((ior - 1) / (ior + 1))^2, times KHR_materials_specular's
    # min(f0 specularColor, 1) specular; FilamentStandard f0 = 0.16 reflectance^2
    ior = 1.5
    if "KHR_materials_ior" in exts:
        ior = _num(exts["KHR_materials_ior"], "ior", 1.5, f"{where}.extensions.KHR_materials_ior", 0.0)
        if 0 < ior < 1:
            raise _GltfError(f"{where}.extensions.KHR_materials_ior.ior: must be 0 or >= 1, got {ior}")
    f0 = 1.0 if ior == 0 else ((ior - 1) / (ior + 1)) ** 2   # ior 0: the extension's "infinite IOR" mode
    spec_tex = spec_col_tex = None
    if "KHR_materials_specular" in exts:
        e, w = exts["KHR_materials_specular"], f"{where}.extensions.KHR_materials_specular"
        spec = _num(e, "specularFactor", 1.0, w, 0.0, 1.0)
        col = _vec(e, "specularColorFactor", [1.0, 1.0, 1.0], 3, w, 0.0, 1e30)
        spec_tex = texture_ref(doc, e, "specularTexture", w, notes)
        spec_col_tex = texture_ref(doc, e, "specularColorTexture", w, notes)
        if np.ptp(col) > 0 or spec_col_tex is not None:
            notes.append("KHR_materials_specular specularColor tint (FilamentStandard's reflectance is one "
                         "number: the largest channel is used)")
        if spec != 1.0 or spec_tex is not None:
            notes.append("KHR_materials_specular f90 = specularFactor (FilamentStandard keeps its own f90 rule; "
                         "f0 is scaled as the extension says)")
        f0_c = min(f0 * float(np.max(col)), 1.0)
    else:
        spec, f0_c = 1.0, f0
    if f0_c * spec > 0.16 and spec_tex is None and spec_col_tex is None:
        notes.append(f"dielectric f0 {f0_c * spec:.4g} (ior {ior:g}) above FilamentStandard's 0.16 "
                     "(reflectance 1): clamped")
    if spec_tex is None and spec_col_tex is None:
        p["reflectance"] = float(_f0_to_reflectance(f0_c * spec))
    else:
        p["reflectance"] = _derived_reflectance(f0, spec, spec_tex, np.max(col) if spec_col_tex is None else col,
                                                spec_col_tex)

    # KHR_materials_clearcoat: clearcoat = factor x R, clearcoatRoughness = factor x G (linear;
    # perceptual, alpha = r^2, as FilamentStandard's clear_coat_roughness); the coat is IOR 1.5 in both
    if "KHR_materials_clearcoat" in exts:
        e, w = exts["KHR_materials_clearcoat"], f"{where}.extensions.KHR_materials_clearcoat"
        cc = _num(e, "clearcoatFactor", 0.0, w, 0.0, 1.0)
        if cc > 0:
            p["clear_coat"] = _product(cc, texture_ref(doc, e, "clearcoatTexture", w, notes), 0, "linear")
            p["clear_coat_roughness"] = _product(_num(e, "clearcoatRoughnessFactor", 0.0, w, 0.0, 1.0),
                                                 texture_ref(doc, e, "clearcoatRoughnessTexture", w, notes),
                                                 1, "linear")
            if "clearcoatNormalTexture" in e:
                notes.append("KHR_materials_clearcoat clearcoatNormalTexture (FilamentStandard's coat shares "
                             "the base's shading normal)")

    # KHR_materials_sheen: sheenColor = factor x RGB (sRGB), sheenRoughness = factor x A (linear,
    # perceptual: alpha = r^2 as in Filament)
    if "KHR_materials_sheen" in exts:
        e, w = exts["KHR_materials_sheen"], f"{where}.extensions.KHR_materials_sheen"
        col = _vec(e, "sheenColorFactor", [0.0, 0.0, 0.0], 3, w)
        if np.any(col > 0):
            p["sheen_color"] = _product(col, texture_ref(doc, e, "sheenColorTexture", w, notes), "rgb", "sRGB")
            p["sheen_roughness"] = _product(_num(e, "sheenRoughnessFactor", 0.0, w, 0.0, 1.0),
                                            texture_ref(doc, e, "sheenRoughnessTexture", w, notes), 3, "linear")

    # KHR_materials_anisotropy: alpha_t = mix(alpha, 1, strength^2) along the tangent, alpha_b = alpha.
    # FilamentStandard: alpha_t = a (1 + k), alpha_b = a (1 - k) with a = roughness^2, so
    # roughness = sqrt((alpha_t + alpha_b) / 2) and k = (alpha_t - alpha_b) / (alpha_t + alpha_b)
    # give both alphas exactly; a rotation of 90 degrees (mod 180) swaps the axes (k -> -k)
    p["roughness"] = rough_v
    if "KHR_materials_anisotropy" in exts:
        e, w = exts["KHR_materials_anisotropy"], f"{where}.extensions.KHR_materials_anisotropy"
        strength = _num(e, "anisotropyStrength", 0.0, w, 0.0, 1.0)
        rot = _num(e, "anisotropyRotation", 0.0, w)
        quarter = rot / (math.pi / 2)
        if "anisotropyTexture" in e:
            notes.append("KHR_materials_anisotropy (anisotropyTexture: per-texel directions need a rotated "
                         "tangent frame per element; the material is imported isotropic)")
        elif strength > 0 and abs(quarter - round(quarter)) > 1e-9:
            notes.append(f"KHR_materials_anisotropy (anisotropyRotation {rot:g} rad is not a multiple of 90 "
                         "degrees: FilamentStandard's anisotropy follows the tangent or bitangent; imported isotropic)")
        elif strength > 0:
            sign = -1.0 if round(quarter) % 2 else 1.0
            p["roughness"], p["anisotropy"] = _anisotropic(rough_v, strength, sign)

    # occlusion and emission: not part of a BSDF
    if "occlusionTexture" in mat:
        notes.append("occlusionTexture (ambient occlusion is a lighting approximation, not part of the BSDF)")
    emf = _vec(mat, "emissiveFactor", [0.0, 0.0, 0.0], 3, where)
    if np.any(emf > 0) or "emissiveTexture" in mat:
        notes.append("emissiveFactor / emissiveTexture" + (" / KHR_materials_emissive_strength"
                     if "KHR_materials_emissive_strength" in exts else "") + " (emission: bsdfkit models only scatter)")

    try:
        model = FilamentStandard(**p, **options)
    except (ValueError, TypeError) as e:
        raise _GltfError(f"{where}: {e}") from None

    # normalTexture: n = normalize((2 rgb - 1) (scale, scale, 1)) (glTF 2.0 spec, "Additional Textures")
    nt = texture_ref(doc, mat, "normalTexture", where, notes)
    if nt is not None:
        scale = _num(mat["normalTexture"], "scale", 1.0, f"{where}.normalTexture")
        model = NormalMap(model, _normal_texture(nt, scale))

    ds = mat.get("doubleSided", False)
    if not isinstance(ds, bool):
        raise _GltfError(f"{where}.doubleSided: expected true or false, got {ds!r}")
    if ds:
        model = TwoSided(model)
    # alpha coverage (glTF 2.0 spec, "Alpha Coverage"): alpha = baseColorFactor.a x baseColorTexture.a (linear)
    mode = mat.get("alphaMode", "OPAQUE")
    if mode not in ("OPAQUE", "MASK", "BLEND"):
        raise _GltfError(f"{where}.alphaMode: expected \"OPAQUE\", \"MASK\" or \"BLEND\", got {mode!r}")
    if mode != "OPAQUE":
        cutoff = _num(mat, "alphaCutoff", 0.5, where, 0.0) if mode == "MASK" else None
        opacity = _opacity(bcf[3], bct, cutoff)
        if not (np.isscalar(opacity) and opacity == 1.0):
            model = Mask(model, opacity)
    return model, notes


def _derived_reflectance(f0, spec, spec_tex, col, col_tex):
    """Textured KHR_materials_specular: reflectance = sqrt(min(f0 max(specularColor), 1) specular / 0.16)."""
    s_in = spec_tex.make(3, "linear") if spec_tex is not None else None
    c_in = col_tex.make("rgb", "sRGB") if col_tex is not None else None
    s_in, c_in = (None if not _is_texture(x) else x for x in (s_in, c_in))
    p = np.concatenate([[f0, spec], np.broadcast_to(np.asarray(col, dtype=np.float64), (3,))])
    return _value("reflectance", s_in, c_in, p)


def _anisotropic(rough, strength, sign):
    """(roughness, anisotropy) of FilamentStandard for KHR_materials_anisotropy (see _material)."""
    t = rough if _is_texture(rough) else None
    p = np.array([strength, sign] + ([] if t is not None else [rough]), dtype=np.float64)
    return _value("aniso_roughness", t, None, p), _value("aniso_k", t, None, p)


def _normal_texture(tex, scale):
    """n = normalize((2 rgb - 1) (scale, scale, 1)) of the normal texture (linear)."""
    return GltfValue("normal", tex.make("rgb", "linear"), params=np.array([float(scale)]))


def _opacity(factor, tex, cutoff):
    if tex is None:
        return factor if cutoff is None else float(factor >= cutoff)
    if cutoff is None:
        return _product(factor, tex, 3, "linear")
    t = tex.make(3, "linear")
    return _value("cutoff", t if _is_texture(t) else None, None, np.array([factor * (1.0 if _is_texture(t) else t),
                                                                            cutoff]))


def _is_texture(x):
    return is_texture(x)


# the derived values, per element after each input texture's own filtering: (a, b, params) -> (..., C)
def _f_product(a, b, p):
    a = a if a.shape[-1] != 4 else a[..., :3]
    return a * p


def _f_normal(a, b, p):
    n = (2 * a[..., :3] - 1) * np.array([p[0], p[0], 1.0])
    # blue <= 0.5 is invalid in glTF: such a normal is raised to just above the surface (z = 1e-4 |xy|)
    n[..., 2] = np.maximum(n[..., 2], 1e-4 * np.sqrt(n[..., 0] ** 2 + n[..., 1] ** 2) + 1e-300)
    return n / np.sqrt(n[..., 0] ** 2 + n[..., 1] ** 2 + n[..., 2] ** 2)[..., None]


def _aniso(a, p):
    r = a[..., 0] if a is not None else np.asarray(p[2])
    al = r * r
    at = al + (1 - al) * p[0] ** 2
    tot = at + al
    k = np.divide(at - al, tot, out=np.zeros_like(tot), where=tot > 0)
    return np.sqrt(tot / 2), p[1] * k + 0.0


def _f_aniso_roughness(a, b, p):
    return _aniso(a, p)[0][..., None]


def _f_aniso_k(a, b, p):
    return _aniso(a, p)[1][..., None]


def _f_reflectance(a, b, p):
    s = p[1] * (a[..., 0] if a is not None else 1.0)
    c = np.max(p[2:5] * (b[..., :3] if b is not None else 1.0), axis=-1)
    return _f0_to_reflectance(np.minimum(p[0] * c, 1.0) * s)[..., None]


def _f_cutoff(a, b, p):
    v = a[..., 0] * p[0] if a is not None else np.asarray(p[0])
    return (v >= p[1]).astype(np.float64)[..., None]


_KINDS = {"product": (_f_product, 3), "normal": (_f_normal, 3), "aniso_roughness": (_f_aniso_roughness, 1),
          "aniso_k": (_f_aniso_k, 1), "reflectance": (_f_reflectance, 1), "cutoff": (_f_cutoff, 1)}


def _value(kind, a, b, params):
    """A GltfValue, or its value (a float) when neither input is a texture."""
    if a is None and b is None:
        return float(np.asarray(_KINDS[kind][0](None, None, params)).reshape(-1)[0])
    return GltfValue(kind, a, b, params)


class GltfValue(TextureBase):
    """A glTF material value derived from textures, per element after their own filtering:
    ``kind`` is "product" (a texture times an RGB factor), "normal" (normalize((2 rgb - 1)
    (scale, scale, 1))), "aniso_roughness" / "aniso_k" (KHR_materials_anisotropy as
    FilamentStandard's roughness / anisotropy), "reflectance" (KHR_materials_specular /
    _ior) or "cutoff" (alphaMode MASK); ``a``, ``b`` the input textures (or None),
    ``params`` the factors."""

    def __init__(self, kind, a=None, b=None, params=None):
        if kind not in _KINDS:
            raise ValueError(f"kind: expected one of {list(_KINDS)}, got {kind!r}")
        p = np.array([] if params is None else params, dtype=np.float64).reshape(-1)
        p.setflags(write=False)
        for k, v in (("kind", kind), ("a", a), ("b", b), ("params", p), ("channels", _KINDS[kind][1])):
            object.__setattr__(self, k, v)

    def _args(self):
        return {"kind": self.kind, "a": self.a, "b": self.b, "params": self.params}

    def _lookup(self, uv, dx, dy):
        va = None if self.a is None else self.a._lookup(uv, dx, dy)
        vb = None if self.b is None else self.b._lookup(uv, dx, dy)
        return np.asarray(_KINDS[self.kind][0](va, vb, self.params), dtype=np.float64)


# ---------------------------------------------------------------- public

def read_gltf_materials(path, *, options=None, progress=None) -> list:
    """The materials of a glTF 2.0 file as :class:`GltfMaterial` records (model and what it leaves
    out), in file order, without warnings. Arguments, conversion and errors: :func:`from_gltf`."""
    if isinstance(path, (bytes, bytearray)) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: expected the path of a .gltf or .glb file (str or os.PathLike), got {type(path).__name__}")
    options = {} if options is None else dict(options)
    for k in options:
        if k not in _OPTIONS:
            raise TypeError(f"options: {k!r} is not a FilamentStandard option ({', '.join(_OPTIONS)})")
    progress = check_progress(progress)
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"path: glTF file not found: {path}")
    prog = None
    try:
        doc = _Doc(path)
        out, seen = [], set()
        mats = doc.array("materials")
        prog = Progress(progress, len(mats), "materials", "from_gltf", delay=PROGRESS_DELAY)
        for i, mat in enumerate(mats):
            if not isinstance(mat, dict):
                raise _GltfError(f"materials[{i}]: must be a JSON object")
            name = mat.get("name")
            name = name if isinstance(name, str) and name else f"material#{i}"
            if name in seen:
                name = f"{name} (material#{i})"
            seen.add(name)
            try:
                model, notes = _material(doc, i, mat, options)
            except _GltfError as e:
                msg = str(e)
                raise _GltfError(msg if msg.startswith(f"materials[{i}]") else f"materials[{i}] ({name!r}): {msg}") \
                    from None
            out.append(GltfMaterial(i, name, model, tuple(notes)))
            prog.advance()
        return out
    except _GltfError as e:
        msg = str(e)
        raise ValueError(msg if msg.startswith(path) else f"{path}: {msg}") from None
    except FileNotFoundError as e:
        raise FileNotFoundError(f"{path}: {e}") from None
    finally:
        if prog is not None:
            prog.close()


def from_gltf(path, *, options=None, progress=None) -> dict:
    """bsdfkit models for the materials of a glTF 2.0 file (``.gltf`` or ``.glb``): ``{name:
    model}`` in file order, each a :class:`~bsdfkit.FilamentStandard` (Filament's model is glTF's
    metallic-roughness), wrapped in ``NormalMap`` / ``Mask`` / ``TwoSided`` where the material
    asks for them.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.gltf`` file (JSON; buffers and images as files relative to it or as base64 ``data:``
        URIs) or a ``.glb`` file (GLB container; images in buffer views of its BIN chunk).
        Detected by the content (GLB magic ``glTF``), not by the extension.
    options : dict, optional
        FilamentStandard's keyword-only knobs for every material (``diffuse``, ``f90``,
        ``energy_compensation``, ``min_roughness``, ...); default Filament's desktop shading.
        ``{"f90": "one"}`` gives glTF's reference Fresnel (f90 = 1).
    progress : bool or callable, optional
        One bar over the materials converted (their images with them), as
        :func:`bsdfkit.from_pbrt`'s: None (default) shows it on an interactive stderr (a bar in
        Jupyter) once the import has run for a second.

    Returns
    -------
    dict
        ``{name: model}``: a material's ``name``; ``"material#<i>"`` without one, ``"<name>
        (material#<i>)"`` for a repeated name.

    Notes
    -----
    Mapping (glTF 2.0 spec "Metallic-Roughness Material", "Additional Textures", "Alpha Coverage"):

    * ``base_color`` = baseColorFactor.rgb x baseColorTexture (sRGB-decoded); ``metallic`` =
      metallicFactor x B and ``roughness`` = roughnessFactor x G of metallicRoughnessTexture
      (linear). glTF's roughness is perceptual (alpha = roughness^2), as FilamentStandard's.
    * ``reflectance`` = sqrt(f0 / 0.16) with the dielectric f0 = ((ior - 1) / (ior + 1))^2
      (``KHR_materials_ior``, default 1.5: f0 0.04, reflectance 0.5), times
      ``KHR_materials_specular``'s min(f0 specularColor, 1) specular; a tinted specularColor
      uses its largest channel, and the extension's f90 = specular is not reproduced (both
      noted); f0 above 0.16 is clamped (noted).
    * ``KHR_materials_clearcoat`` -> ``clear_coat`` (factor x R), ``clear_coat_roughness``
      (factor x G); its clearcoatNormalTexture is left out (noted).
    * ``KHR_materials_sheen`` -> ``sheen_color`` (factor x sRGB RGB), ``sheen_roughness``
      (factor x A).
    * ``KHR_materials_anisotropy``: the extension's alpha_t = mix(alpha, 1, strength^2),
      alpha_b = alpha become ``roughness`` = sqrt((alpha_t + alpha_b) / 2) and ``anisotropy`` =
      (alpha_t - alpha_b) / (alpha_t + alpha_b), FilamentStandard's pair with the same alphas;
      anisotropyRotation must be a multiple of 90 degrees and anisotropyTexture (per-texel
      directions) is not read: otherwise the material is imported isotropic (noted).
    * normalTexture -> ``bk.NormalMap`` with n = normalize((2 rgb - 1) (scale, scale, 1));
      doubleSided -> ``bk.TwoSided``; alphaMode ``BLEND`` -> ``bk.Mask`` (outermost) with opacity = baseColorFactor.a x texture alpha,
      ``MASK`` -> opacity 1 where alpha >= alphaCutoff else 0.
    * Left out, with one :class:`GltfWarning` per material naming each item: occlusionTexture (a
      lighting approximation), emission (emissiveFactor / emissiveTexture /
      ``KHR_materials_emissive_strength``), extensions without a FilamentStandard parameter
      (``KHR_materials_transmission``, ``_volume``, ``_iridescence``, ``_dispersion``,
      ``_diffuse_transmission``, ``_unlit``, ...), textures on a uv set other than TEXCOORD_0 and
      textures that are not PNG / JPEG (the factor is used alone).
    * Textures: ``bk.Texture`` with the sampler's wrapS / wrapT (33071 clamp, 33648 mirror, 10497
      repeat) and filter (magFilter NEAREST -> ``"nearest"``; a ``*_MIPMAP_LINEAR`` minFilter ->
      ``"trilinear"``; otherwise ``"bilinear"``), and ``KHR_texture_transform`` as the texture's
      uv ``transform``. Lookups at ``uv=`` use glTF's convention: (0, 0) is the image's top-left.
      Images with alpha and embedded images are decoded by Pillow (OpenImageIO would premultiply
      a PNG's colour by its alpha; glTF's is not premultiplied), at 8 bits (16 for grey); other
      image files are read by bk.Texture at their own bit depth. A grey image's R, G and B are its
      grey value. Derived values (base colour x factor, scaled normals, anisotropy over a
      roughness map, specular, alpha cutoff) are :class:`GltfValue` textures, computed per
      element from their inputs' filtered values.

    Raises
    ------
    FileNotFoundError
        The glTF file, or a buffer or image file a material needs (naming the path, the
        material and the texture / image / buffer index).
    ValueError
        A truncated or corrupt GLB container or JSON, a glTF that is not 2.x, a bad value or
        index (naming the material and the property), an undecodable embedded image.

    Examples
    --------
    >>> import json, bsdfkit as bk
    >>> _ = open("gold.gltf", "w").write(json.dumps({"asset": {"version": "2.0"}, "materials": [
    ...     {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1, 0.766, 0.336, 1],
    ...      "metallicFactor": 1, "roughnessFactor": 0.3}}]}))
    >>> bk.from_gltf("gold.gltf")["gold"].roughness
    0.3
    """
    recs = read_gltf_materials(path, options=options, progress=progress)
    for r in recs:
        if r.left_out:
            w = GltfWarning(f"from_gltf: {os.fspath(path)}: materials[{r.index}] {r.name!r}: left out: "
                            + "; ".join(r.left_out))
            w.file, w.material, w.name, w.left_out = os.fspath(path), r.index, r.name, r.left_out
            warnings.warn(w, stacklevel=2)
    return {r.name: r.model for r in recs}
