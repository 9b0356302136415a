"""Values of pbrt-v4 material parameters: rgb, float, spectra (named, pairs, files), eta, ints and bools."""
from __future__ import annotations

import os
import re

import numpy as np

from ..spectra import spectrum_to_rgb
from .parser import _PbrtError

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

def _label(rec, line):
    """``pbrt material 'm' (conductor, line 3`` / ``pbrt texture 't' (float imagemap, line 2 of f.pbrt``."""
    if rec.kind == "texture":
        where = f" of {os.path.basename(rec.file)}" if rec.file else ""
        return f"pbrt texture {rec.name!r} ({rec.type} {rec.cls}, line {line}{where}"
    return f"pbrt material {rec.name!r} ({rec.type}, line {line}"


def _pfail(rec, msg):
    raise _PbrtError(f"{_label(rec, rec.line)}): {msg}")


def _pfail_param(rec, p, msg):
    raise _PbrtError(f"{_label(rec, p.line)}): parameter {p.name!r}: {msg}")


def _check_texture(rec, p):
    """A texture reference where pbrt-v4 takes only a value (dielectric eta, maxdepth, ...)."""
    if p.type == "texture":
        tex = p.values[0] if p.values else "?"
        _pfail_param(rec, p, f"is a texture ({tex!r}); pbrt-v4's {rec.type} {rec.kind} takes only a constant value "
                     "for it")


def _numbers(rec, p):
    if not all(isinstance(v, float) for v in p.values) or not p.values:
        _pfail_param(rec, p, f"expected numbers for a {p.type!r} parameter, got {list(p.values)!r}")
    return np.array(p.values, dtype=np.float64)


def _named_metal(rec, p, name, part, ctx):
    """eta or k of a named metal spectrum: the table of ``bsdfkit.Spectrum.named`` (pbrt-v4's
    ``metal-<X>-eta/k``, also Mitsuba's ``mitsuba-<X>-...`` and ``jc-<X>-...``), kept as a
    Spectrum (``spectral=True``) or projected to RGB as ``Conductor`` projects a spectral eta / k
    (CIE 1931 to linear sRGB, no illuminant)."""
    from ...spectral.spectrum import Spectrum

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


def scene_file(rec, p, name, ctx, missing) -> str:
    """The file ``name`` of parameter ``p``, relative to the scene file's directory (pbrt-v4's
    search directory; the working directory for text), normalised; a missing file fails with
    ``missing(path)`` and the line."""
    base = ctx.get("base") or os.getcwd()
    full = os.path.normpath(name if os.path.isabs(name) else os.path.join(base, name))
    if not os.path.isfile(full):
        _pfail_param(rec, p, missing(full))
    return full


def _spectrum_file(rec, p, name, ctx, *, albedo):
    """A spectrum given by file name (pbrt-v4: a string that is not a named spectrum), relative to
    the scene file's directory (pbrt-v4's search directory; the working directory for text)."""
    from ...spectral.spectrum import Spectrum

    full = scene_file(rec, p, name, ctx, lambda f: f"{name!r} is neither a named spectrum "
                      f"(bsdfkit.Spectrum.names()) nor a spectrum file (no file {f!r})")
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
            from ...spectral.spectrum import Spectrum
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
    from ...spectral.spectrum import Spectrum

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
            full = scene_file(rec, p, name, ctx, lambda f: f"{name!r} is neither a named glass "
                              f"({', '.join(PBRT_GLASS_ETA)}) nor a spectrum file (no file {f!r})")
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


