"""pbrt-v4 materials -> bsdfkit models (``from_pbrt``), following pbrt-v4's ``src/pbrt/materials.cpp``."""
from __future__ import annotations

import math
import os
import warnings

import numpy as np

from ..._progress import PROGRESS_DELAY, Progress, check_progress
from ...models import (CoatedConductor, CoatedDiffuse, Conductor, Dielectric, Diffuse, DiffuseTransmission,
                       ThinDielectric, roughness_to_alpha)
from ...textures import Scale
from .parser import _PBRT_SHADING, PbrtSkipWarning, _context, _PbrtError, _scene_source, parse_pbrt_materials
from .mix import resolve_mixes
from .shading import shading
from .textures import float_value, is_texture, lookup_op, spectrum_value
from .values import (_bool_param, _check_texture, _eta_param, _float_param, _int_param, _pfail, _pfail_param,
                     _spectrum_param, scene_file)

_PBRT_SUPPORTED = ("diffuse", "diffusetransmission", "conductor", "dielectric", "thindielectric",
                   "coateddiffuse", "coatedconductor", "hair", "measured", "mix")

#: pbrt-v4 material types with no BSDF: ``interface`` (and ``none`` / ``""``) mark a boundary
#: between participating media that rays pass through unchanged; skipped with their own reason.
_PBRT_NO_BSDF = ("interface", "none", "")

_PBRT_UNSUPPORTED = ("subsurface",)

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
    "measured": ("filename",),
}


def _layer_kwargs(rec, ctx):
    """pbrt-v4 LayeredBxDF parameters of coateddiffuse / coatedconductor (materials.cpp): albedo
    clamped to [0, 1] and g to [-1, 1] per lookup; thickness, albedo and g may be textures."""
    albedo = spectrum_value(rec, "albedo", albedo=True, ctx=ctx)
    g = lookup_op("clamp", float_value(rec, "g", 0.0, ctx), (-1.0, 1.0))
    return dict(thickness=float_value(rec, "thickness", 0.01, ctx), albedo=0.0 if albedo is None else albedo,
                g=g, max_depth=_int_param(rec, "maxdepth", 10), n_samples=_int_param(rec, "nsamples", 1))


def _alphas(rec, ctx, prefix=""):
    """(alpha_x, alpha_y): uroughness / vroughness, default roughness [0], each a float or a float
    texture; with remaproughness [true] alpha = sqrt(roughness), per lookup for a texture."""
    r = float_value(rec, prefix + "roughness", 0.0, ctx)
    u = float_value(rec, prefix + "uroughness", r, ctx)
    v = float_value(rec, prefix + "vroughness", r, ctx)
    for val, n in ((u, "uroughness"), (v, "vroughness")):
        if not is_texture(val) and not (math.isfinite(val) and val >= 0):
            _pfail(rec, f"{prefix + n if prefix + n in rec.params else prefix + 'roughness'} must be finite "
                   f"and >= 0, got {val}")
    if _bool_param(rec, "remaproughness", True):
        return tuple(lookup_op("remap_roughness", x) if is_texture(x) else roughness_to_alpha(x) for x in (u, v))
    return u, v


def _pbrt_bxdf(rec, ctx=None):
    ctx = ctx or {}
    mtype = rec.type
    if mtype in _PBRT_NO_BSDF:
        _pfail(rec, f"{mtype or 'empty'!r} material: no BSDF (pbrt-v4: a boundary between participating media that "
               "rays pass through unchanged); nothing to model")
    if mtype not in _PBRT_SUPPORTED:
        kind = "unsupported" if mtype in _PBRT_UNSUPPORTED else "unknown"
        _pfail(rec, f"{kind} material type {mtype!r}; supported: {', '.join(_PBRT_SUPPORTED)}")
    if mtype == "mix":
        _pfail(rec, "a mix material needs the scene's other materials: use from_pbrt")
    allowed = _PBRT_PARAMS[mtype] + _PBRT_SHADING
    for p in rec.params.values():
        if p.name not in allowed:
            _pfail_param(rec, p, f"not a parameter of pbrt-v4's {mtype} material; it takes "
                         + ", ".join(_PBRT_PARAMS[mtype] + _PBRT_SHADING))
    try:
        model = _base_model(rec, ctx)
    except _PbrtError:
        raise
    except (ValueError, TypeError) as e:
        _pfail(rec, str(e))
    return shading(rec, model, ctx)


def _base_model(rec, ctx):
    mtype = rec.type
    if mtype == "diffuse":
        r = spectrum_value(rec, "reflectance", albedo=True, ctx=ctx)
        return Diffuse(0.5 if r is None else r)
    if mtype == "diffusetransmission":
        # pbrt-v4 DiffuseTransmissionMaterial: clamp(scale * texture, 0, 1) per lookup
        r = spectrum_value(rec, "reflectance", albedo=True, ctx=ctx)
        t = spectrum_value(rec, "transmittance", albedo=True, ctx=ctx)
        s = _float_param(rec, "scale", 1.0)
        r = np.full(3, 0.25) if r is None else r
        t = np.full(3, 0.25) if t is None else t
        return DiffuseTransmission(*(lookup_op("clamp01", Scale(x, s)) if is_texture(x) else np.clip(s * x, 0, 1)
                                     for x in (r, t)))
    if mtype == "conductor":
        ax, ay = _alphas(rec, ctx)
        refl = _conductor_parts(rec, "reflectance", "eta", "k", ctx)
        if refl is not None:
            if is_texture(refl) or is_texture(ax) or is_texture(ay):
                return Conductor(1.0, lookup_op("conductor_k", refl),
                                 alpha_x=ax, alpha_y=ay, masking="correlated")
            return Conductor.from_reflectance(refl, alpha_x=ax, alpha_y=ay, masking="correlated")
        eta = spectrum_value(rec, "eta", albedo=False, ctx=ctx)
        k = spectrum_value(rec, "k", albedo=False, ctx=ctx)
        eta = _default_copper("eta", ctx) if eta is None else eta
        k = _default_copper("k", ctx) if k is None else k
        return Conductor(eta, k, alpha_x=ax, alpha_y=ay, masking="correlated")
    if mtype == "dielectric":
        ax, ay = _alphas(rec, ctx)
        return Dielectric(_eta_param(rec, ctx=ctx), alpha_x=ax, alpha_y=ay, masking="correlated")
    if mtype == "coateddiffuse":
        ax, ay = _alphas(rec, ctx)
        r = spectrum_value(rec, "reflectance", albedo=True, ctx=ctx)
        return CoatedDiffuse(0.5 if r is None else r, eta=_eta_param(rec), alpha_x=ax, alpha_y=ay,
                             **_layer_kwargs(rec, ctx))
    if mtype == "coatedconductor":
        iax, iay = _alphas(rec, ctx, "interface.")
        cax, cay = _alphas(rec, ctx, "conductor.")
        kw = dict(conductor_alpha_x=cax, conductor_alpha_y=cay, interface_eta=_eta_param(rec, param="interface.eta"),
                  interface_alpha_x=iax, interface_alpha_y=iay, **_layer_kwargs(rec, ctx))
        refl = _conductor_parts(rec, "reflectance", "conductor.eta", "conductor.k", ctx)
        if refl is not None:
            if any(is_texture(v) for v in kw.values()) or is_texture(refl):
                return CoatedConductor(1.0, lookup_op("conductor_k", refl), **kw)
            return CoatedConductor.from_reflectance(refl, **kw)
        eta = spectrum_value(rec, "conductor.eta", albedo=False, ctx=ctx)
        k = spectrum_value(rec, "conductor.k", albedo=False, ctx=ctx)
        eta = _default_copper("eta", ctx) if eta is None else eta
        k = _default_copper("k", ctx) if k is None else k
        return CoatedConductor(eta, k, **kw)
    if mtype == "hair":
        return _pbrt_hair(rec, ctx)
    if mtype == "measured":
        return _measured(rec, ctx)
    return ThinDielectric(_eta_param(rec, ctx=ctx))


def _conductor_parts(rec, refl_name, eta_name, k_name, ctx):
    """The reflectance (a [0, 1] clamp of its texture) if given, after checking that eta / k are not
    given too (pbrt-v4 refuses both); None without one."""
    refl = spectrum_value(rec, refl_name, albedo=True, ctx=ctx)
    if refl is not None and (eta_name in rec.params or k_name in rec.params):
        which = f'"{eta_name}"/"{k_name}"'
        _pfail(rec, f"give either \"{refl_name}\" or {which}, not both (pbrt-v4 refuses it)")
    return refl


def _default_copper(part, ctx):
    """pbrt-v4's default conductor: metal-Cu-eta / metal-Cu-k, from the named-spectra table."""
    from ...spectral.spectrum import Spectrum
    s = Spectrum.named(f"metal-Cu-{part}")
    return s if ctx.get("spectral") else np.asarray(s.to_rgb("unbounded", illuminant=None), dtype=np.float64)


def _pbrt_hair(rec, ctx):
    """pbrt-v4 ``HairMaterial``: sigma_a, else reflectance, else eumelanin/pheomelanin (each
    ignored when an earlier one is given, as pbrt-v4 warns and does); neither -> eumelanin 1.3.
    beta_m / beta_n clamped to [0.01, 1] and reflectance to [0, 1] as pbrt-v4's material does.
    sigma_a, eta, beta_m, beta_n and alpha may be textures; reflectance and the melanins not yet
    (their conversion to sigma_a is not a per-lookup operation here)."""
    from ...models.hair import Hair, sigma_a_from_concentration, sigma_a_from_reflectance

    bm = lookup_op("clamp", float_value(rec, "beta_m", 0.3, ctx), (0.01, 1.0))
    bn = lookup_op("clamp", float_value(rec, "beta_n", 0.3, ctx), (0.01, 1.0))
    kw = dict(eta=float_value(rec, "eta", 1.55, ctx), beta_m=bm, beta_n=bn, alpha=float_value(rec, "alpha", 2.0, ctx),
              h=0.0)
    sigma_a = spectrum_value(rec, "sigma_a", albedo=False, ctx=ctx)
    if sigma_a is None:
        p = rec.params.get("reflectance")
        if p is not None:
            _check_texture(rec, p)
            if is_texture(bn):
                _pfail_param(rec, p, "a hair reflectance with a textured beta_n is not supported")
            c = _spectrum_param(rec, "reflectance", albedo=False)
            sigma_a = sigma_a_from_reflectance(np.clip(c, 0.0, 1.0), bn)
        else:
            for n in ("eumelanin", "pheomelanin"):
                if n in rec.params:
                    _check_texture(rec, rec.params[n])
            ce = _float_param(rec, "eumelanin", None)
            cp = _float_param(rec, "pheomelanin", None)
            if ce is None and cp is None:
                ce = 1.3
            sigma_a = sigma_a_from_concentration(ce or 0.0, cp or 0.0)
    return Hair(sigma_a=sigma_a, **kw)


def _measured(rec, ctx):
    """pbrt-v4 ``measured``: ``"string filename"``, an RGL tensor file (``.bsdf``) relative to the
    scene file's directory -> ``bk.Measured``."""
    from ...models.measured import Measured

    p = rec.params.get("filename")
    if p is None or p.type != "string" or len(p.values) != 1 or not isinstance(p.values[0], str) or not p.values[0]:
        _pfail(rec, "needs a \"string filename\" naming an RGL tensor file (.bsdf)")
    full = scene_file(rec, p, p.values[0], ctx, lambda f: f"no measured BSDF file {f!r}")
    try:
        return Measured(full)
    except (OSError, ValueError) as e:
        _pfail_param(rec, p, f"{full!r}: {e}")


def from_pbrt(source, *, skip_unsupported: bool = False, skip_missing_includes: bool = False,
              spectral: bool = False, progress=None) -> dict:
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
      [0.5] (a float or a float texture, clamped to [0, 1]) -> ``Mix(first, second, amount,
      method="stochastic")`` (pbrt-v4 MixMaterial: the second material with probability amount,
      per shading point). Mixes of mixes are refused past 64 levels or 1,024 materials counted
      once per path (``bk.Mix`` evaluates every path; pbrt-v4 picks one).
    * ``measured``: filename (an RGL ``.bsdf`` tensor file, relative to the scene file's
      directory) -> ``bk.Measured``.
    * ``interface`` (and ``none``): no BSDF (a boundary between media): skipped with that reason.
      ``subsurface`` is unsupported.

    Every material also takes ``"string normalmap"`` -> ``bk.NormalMap`` of the image (read
    linearly, bilinear with repeat wrap at (u, 1 - v), normals normalize(2 rgb - 1) turned to the
    outside) and ``"texture displacement"`` -> ``bk.BumpMap`` whose gradient is pbrt-v4
    BumpMap()'s forward difference (step (|du/dx| + |du/dy|) / 2 with uv derivatives, else 0.0005),
    both with ``flip_invalid_normals=False, shadowing=False`` (pbrt-v4 has neither); a normal map
    wins over a displacement, as in pbrt-v4, and a constant displacement tilts nothing
    (``PbrtMaterial.ignored``). bk.BumpMap takes the local frame's x and y axes as dp/du, dp/dv
    (pbrt scales the gradient by the mesh's |dp/du|, which a material alone does not have).

    Textures: ``Texture "name" "float" | "spectrum" "class" params`` of the classes
    ``imagemap`` (filename relative to the scene file's directory; filter point / bilinear /
    trilinear / ewa (OpenImageIO's anisotropic filter); wrap repeat / black / clamp; encoding
    [sRGB for .png files, linear otherwise]; scale; invert), ``constant``, ``scale``, ``mix`` and
    2-D ``checkerboard``, with the uv mapping (uscale, vscale, udelta, vdelta; pbrt's v runs up
    the image: the texture's ``transform`` is [[su, 0, du], [0, -sv, 1 - dv]]) become
    ``bk.Texture`` / ``bsdfkit.textures`` textures, converted once per scene. A parameter
    ``"texture <p>" "<name>"`` takes the float or spectrum texture of that name wherever pbrt-v4
    takes a texture: reflectance, transmittance, eta / k of conductors, (u|v)roughness,
    thickness, albedo, g, a mix's amount, hair's sigma_a / eta / beta_m / beta_n / alpha. The
    model is then textured (``bsdfkit.models.textured``: evaluate with ``uv=``), and pbrt-v4's
    per-lookup arithmetic is applied to the looked-up values (:class:`~bsdfkit.interop.pbrt.textures.PbrtLookup`:
    reflectances and albedos clamped to [0, 1], g to [-1, 1], beta to [0.01, 1], alpha =
    sqrt(roughness) with remaproughness, a conductor's k = 2 sqrt(r) / sqrt(1 - r) of a
    reflectance texture with eta 1). A float texture of an RGB image reads channel 0, a spectrum
    texture of an RGBA image its RGB. Other classes (ptex, marble, fbm, wrinkled, windy, dots,
    bilerp, directionmix), 3-D checkerboards, other mappings and the octahedralsphere wrap are
    refused naming the class and the Texture statement's line, as are undefined textures and
    cycles; a missing image names its path and the line.

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
    stay RGB / scalar).

    Parameters
    ----------
    source : str or os.PathLike
        Scene text, or the path of a scene file (above).
    skip_unsupported : bool, optional
        Leave out materials that cannot be converted (unsupported types or textures, missing
        images, unknown spectra) instead of raising, with one :class:`PbrtSkipWarning` per material naming it,
        its line and the reason (its ``material``, ``line`` and ``reason`` attributes carry
        them); malformed text still raises.
    skip_missing_includes : bool, optional
        Skip an ``Include`` / ``Import`` of a missing file, with a
        :class:`PbrtMissingIncludeWarning`.
    spectral : bool, optional
        Keep named and file spectra of metal eta / k and dielectric eta as ``bsdfkit.Spectrum``.
    progress : bool or callable, optional
        One bar for the whole import: the characters read (includes too), then the materials
        converted (their image textures with them). None (default): on stderr when it is a
        terminal (a bar in Jupyter), once the import has run for a second; True, False, or a
        callable ``progress(done, total, stage)``. Ctrl-C stops the import with ``KeyboardInterrupt``.

    Returns
    -------
    dict
        ``{name: BxDF}`` in file order.

    Raises
    ------
    ValueError
        Naming the material, its line and the parameter for unsupported types (subsurface,
        interface, ...), unsupported or undefined textures (naming the texture and its line),
        missing images, unknown parameters, bad values, and malformed text (with the line).
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
    progress = check_progress(progress)
    text, path = _scene_source(source)
    prog = Progress(progress, len(text), "reading the scene (characters)", "from_pbrt", delay=PROGRESS_DELAY)
    try:
        base = None if path is None else os.path.dirname(os.path.abspath(path))
        records = parse_pbrt_materials(text, path=path, skip_missing_includes=skip_missing_includes, _progress=prog)
        prog.begin("materials", len(records))
        return _convert_all(records, base, skip_unsupported, spectral, prog)
    finally:
        prog.close()


def _convert_all(records, base, skip_unsupported, spectral, prog):
    out = {}

    def skip(rec, e):
        if not skip_unsupported:
            raise e
        w = PbrtSkipWarning(f"from_pbrt: skipped {e}" + (f" [in {rec.file}]" if rec.file else ""))
        w.material, w.line, w.file, w.reason = rec.name, rec.line, rec.file, str(e)
        warnings.warn(w, stacklevel=4)
    ctx = _context(records[0].textures if records else {}, spectral, base)   # textures converted once per scene
    for rec in records:
        if rec.type != "mix":   # a mix needs the others: resolved below (mix.py)
            try:
                out[rec.name] = _pbrt_bxdf(rec, ctx)
            except _PbrtError as e:
                skip(rec, e)
        prog.advance()
    resolve_mixes([r for r in records if r.type == "mix"], out, _pfail, _pfail_param,
                  lambda rec, name, default: float_value(rec, name, default, ctx), skip)
    return {rec.name: out[rec.name] for rec in records if rec.name in out}   # file order

