"""Spectral mode of the array API (issue 15; docs/SPECTRAL.md): ``wavelengths=`` in ``eval``,
``pdf``, ``sample`` and ``albedo``, and model parameters given as :class:`bsdfkit.Spectrum`.

* Parameters: a model field may be a ``Spectrum`` (sampled, named, constant, uplifted RGB) or an
  RGB / scalar value. In spectral mode each becomes a ``_core.SpectralParam``: an RGB colour
  through the Jakob & Hanika 2019 uplift (the sigmoid coefficients, ``Spectrum.from_rgb``'s
  polished fit; greys exactly constant), a sampled spectrum as its piecewise-linear nodes over
  [360, 830] nm (exact; a per-nm index finds the segment), a constant as itself. In RGB mode a spectrum is projected (:func:`rgb_of`, :func:`scalar_of`).
* Calls: wavelengths (..., 4) in nm, finite and in [360, 830], broadcast with the directions'
  leading axes; ``f`` and ``albedo`` become (..., 4), ``pdf`` stays (...), ``sample`` adds
  ``terminated``. The kernels: ``cpp/include/bsdfkit/batch_spectral.h``.
"""
from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from .. import _core
from .._arrays import (MAX_ALBEDO_SAMPLES, as_dirs, broadcast_batch, check_int, check_out, flatten_to, kernel_dtype,
                       sample_uniforms)
from ..spectral.spectrum import Spectrum

__all__ = ["LAMBDA_MIN", "LAMBDA_MAX", "DENSE_WAVELENGTHS", "check_wavelengths", "spectral_param", "spectral_mean",
           "spectral_max", "rgb_of",
           "scalar_of", "spectrum_or_rgb", "spectrum_or_scalar", "fmt_param", "is_dispersive", "eval", "pdf",
           "sample", "albedo"]

LAMBDA_MIN, LAMBDA_MAX = 360.0, 830.0
#: The 1 nm grid of the kernels' spectral tables (pbrt-v4 DenselySampledSpectrum's range).
DENSE_WAVELENGTHS = np.arange(360.0, 831.0)
DENSE_WAVELENGTHS.setflags(write=False)
#: RGB-mode eta of a dispersive dielectric: its value here (pbrt-v4 RGB renders have no dispersion).
RGB_ETA_WAVELENGTH = 550.0

def spectral_classes() -> tuple:
    """The registered model classes with a spectral form, read from ``_core``: a compiled model
    ``X`` has one when ``_core.XSpectral`` exists (core/bxdf.h ``Spectral``), and it belongs to
    the registered class whose name is the longest prefix of ``X`` (``ConductorF82`` to
    ``Conductor``, ``MERLLinear`` to ``MERL``). No hand-kept list. Some of them have it for some
    parameters only (``_has_spectral_kernel``, e.g. Measured: spectral tensor files)."""
    from . import registry
    names = [c.__name__ for c in registry.classes()]
    found = set()
    for core_name in _core.model_names():
        if hasattr(_core, core_name + "Spectral"):
            owners = [n for n in names if core_name.startswith(n)]
            if owners:
                found.add(max(owners, key=len))
    return tuple(c for c in registry.classes() if c.__name__ in found)


def spectral_model_names() -> str:
    """The registered models with a spectral form (:func:`spectral_classes`), comma-separated."""
    return ", ".join(c.__name__ for c in spectral_classes())


# ------------------------------------------------------------------------------- parameters

def _check_spectrum(s: Spectrum, name: str, lo, hi, lo_open):
    v = s(DENSE_WAVELENGTHS)
    if s.kind == "sampled":
        inside = (s.wavelengths >= LAMBDA_MIN) & (s.wavelengths <= LAMBDA_MAX)
        v = np.concatenate([v, s.values[inside]])
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: the spectrum must be finite over [360, 830] nm")
    if lo is not None and np.any(v <= lo if lo_open else v < lo):
        raise ValueError(f"{name}: the spectrum must be {'>' if lo_open else '>='} {lo} over [360, 830] nm, "
                         f"got min {v.min():.6g}")
    if hi is not None and np.any(v > hi):
        raise ValueError(f"{name}: the spectrum must be <= {hi} over [360, 830] nm, got max {v.max():.6g}")
    return s


def spectrum_or_rgb(x, name: str, *, lo=None, hi=None, lo_open=False, varying=False):
    """A validated Spectrum (bounds checked over [360, 830] nm) or RGB value (base._rgb; with
    ``varying``, also an RGB value per element)."""
    if isinstance(x, Spectrum):
        return _check_spectrum(x, name, lo, hi, lo_open)
    from .._validate import check_rgb as _rgb
    return _rgb(x, name, lo=lo, hi=hi, lo_open=lo_open, varying=varying)


def spectrum_or_scalar(x, name: str, *, lo=None, hi=None, lo_open=False, varying=False):
    """A validated Spectrum or real number (base._scalar; with ``varying``, also one per element)."""
    if isinstance(x, Spectrum):
        return _check_spectrum(x, name, lo, hi, lo_open)
    from .._validate import check_real as _scalar
    return _scalar(x, name, lo=lo, hi=hi, lo_open=lo_open, varying=varying)


def rgb_of(v, kind: str) -> np.ndarray:
    """RGB-mode value of a parameter: an RGB array as is; a Spectrum projected to linear sRGB:
    ``kind="reflectance"`` under D65 (Mitsuba's rule for spectra in scene dicts), ``"unbounded"``
    (eta, k) without an illuminant (Mitsuba's projection of its IOR presets, how ``METALS`` was
    made), floored at 1e-4 so that an eta stays positive. A constant spectrum is its value."""
    if not isinstance(v, Spectrum):
        return v
    if v.is_constant:   # a constant is that value in every channel (as a Mitsuba uniform spectrum), not
        return np.full(3, float(v(np.float64(550.0))))   # its projection (D65 white is (0.999, 0.999, 0.999))
    if kind == "reflectance":
        return v.to_rgb("reflectance", "D65")
    return np.maximum(v.to_rgb("unbounded", None), 1e-4)


def scalar_of(v) -> float:
    """RGB-mode value of a scalar parameter (a dielectric's eta): the number, or the spectrum at
    550 nm (pbrt-v4 RGB renders have no dispersion; ``interop.PBRT_GLASS_ETA`` is the same rule)."""
    if isinstance(v, Spectrum):
        return float(v(np.float64(RGB_ETA_WAVELENGTH)))
    return v if isinstance(v, np.ndarray) else float(v)   # an array: per-element values


def is_dispersive(v) -> bool:
    """A non-constant spectrum of eta: the dielectric disperses light."""
    return isinstance(v, Spectrum) and not v.is_constant


def fmt_param(v) -> str:
    """Short text of a parameter for ``describe``: a spectrum by its name or kind."""
    if isinstance(v, Spectrum):
        if v.name is not None:
            return v.name
        if v.kind == "constant":
            return f"{float(v(np.float64(550.0))):.3g}"
        return f"{v.kind} spectrum"
    from .base import fmt_value
    return fmt_value(v)


def spectral_mean(v, kind: str) -> float:
    """Mean of a parameter over [360, 830] nm in spectral mode (Mitsuba's ``Texture::mean()`` of its
    spectral variants): a piecewise-linear spectrum's exact integral over its nodes (trapezoids),
    an uplifted RGB or other smooth spectrum by trapezoids on the 1 nm grid, a constant itself."""
    if isinstance(v, Spectrum) and v.kind == "sampled":
        lam = v.wavelengths
        inner = lam[(lam > LAMBDA_MIN) & (lam < LAMBDA_MAX)]
        x = np.concatenate([[LAMBDA_MIN], inner, [LAMBDA_MAX]])
    else:
        x = DENSE_WAVELENGTHS
    y = spectral_param(v, kind)(np.ascontiguousarray(x, dtype=np.float64))
    return float(np.sum((y[1:] + y[:-1]) * np.diff(x)) * 0.5 / (LAMBDA_MAX - LAMBDA_MIN))


def spectral_max(v, kind: str) -> float:
    """Largest value of a parameter in spectral mode (over the 1 nm grid and a table's nodes)."""
    x = DENSE_WAVELENGTHS
    if isinstance(v, Spectrum) and v.kind == "sampled":
        x = np.concatenate([x, np.clip(v.wavelengths, LAMBDA_MIN, LAMBDA_MAX)])
    return float(np.max(spectral_param(v, kind)(np.ascontiguousarray(x, dtype=np.float64))))


def spectral_param(v, kind: str) -> "_core.SpectralParam":
    """The kernel form of one parameter (see the module docstring). kind: the uplift of an RGB
    value, "reflectance" (bounded, pbrt-v4 RGBAlbedoSpectrum) or "unbounded" (eta, k)."""
    SP = _core.SpectralParam
    if isinstance(v, Spectrum):
        if v.kind == "constant":
            return SP.constant(float(v(np.float64(550.0))))
        if v.kind == "rgb" and v._data[1] != "illuminant":
            c, scale = v._data[2], v._data[3]
            return SP.sigmoid(float(c[0]), float(c[1]), float(c[2]), float(scale))
        if v.is_constant:
            return SP.constant(float(v(np.float64(550.0))))
        if v.kind == "sampled":   # its nodes inside (360, 830) plus its values at 360 and 830 nm
            lam = v.wavelengths
            inner = lam[(lam > LAMBDA_MIN) & (lam < LAMBDA_MAX)]
            nodes = np.concatenate([[LAMBDA_MIN], inner, [LAMBDA_MAX]])
            return SP.table(nodes, v(nodes))
        return SP.table(DENSE_WAVELENGTHS, np.ascontiguousarray(v(DENSE_WAVELENGTHS)))  # blackbody, illuminant
    a = np.asarray(v, dtype=np.float64)
    if a.ndim == 0 or np.all(a == a.flat[0]):
        return SP.constant(float(a.flat[0]))       # a grey uplifts to exactly that constant
    from ..spectral import uplift
    c, scale = uplift.rgb_coefficients(a, kind, exact=True)
    return SP.sigmoid(float(c[0]), float(c[1]), float(c[2]), float(scale))


_CACHE: "OrderedDict" = OrderedDict()
_CACHE_SIZE = 256


def _spectral_core(model):
    """The model's ``_core.<Model>Spectral`` (built once per distinct model: the RGB uplift
    polishes each colour, ~1-15 ms). Models without a spectral form (``_has_spectral_kernel()``
    false) raise NotImplementedError."""
    if not model._has_spectral_kernel():
        reason = getattr(model, "_no_spectral_reason", None)
        if reason is not None:
            raise NotImplementedError(reason())
        raise NotImplementedError(
            f"wavelengths: spectral mode is not implemented for {type(model).__name__} yet "
            f"(models with wavelengths=: {spectral_model_names()}); call without wavelengths= for RGB")
    key = (type(model), model._key())
    core = _CACHE.get(key)
    if core is None:
        core = model._make_spectral_core()
        _CACHE[key] = core
        if len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    else:
        _CACHE.move_to_end(key)
    return core


# ------------------------------------------------------------------------------- arguments

def check_wavelengths(x) -> np.ndarray:
    """``wavelengths`` as a real array with last axis 4 (nm). Their values (finite, in [360, 830])
    are checked by the kernels, which count the bad ones in the same pass (no extra numpy pass over
    the array); the count raises a ValueError naming ``wavelengths`` (_raise_counts)."""
    try:
        a = np.asarray(x)
    except Exception as e:
        raise TypeError(f"wavelengths: cannot be converted to a numeric array ({e})") from None
    if a.dtype.kind not in "fiu" or a.dtype == np.bool_:
        raise TypeError(f"wavelengths: expected real numbers (nm), got dtype {a.dtype}")
    if a.ndim == 0 or a.shape[-1] != 4:
        raise ValueError(f"wavelengths: expected an array with last axis of length 4 (pbrt-v4's 4 wavelengths "
                         f"per sample, e.g. from bsdfkit.sample_wavelengths), got shape {a.shape}")
    return a


def _raise_counts(counts, names):
    for name, c in zip(names, counts):
        if not c:
            continue
        if name == "wavelengths":
            raise ValueError(f"wavelengths: {c} row(s) of 4 hold values that are not finite or outside [360, 830] nm")
        from .._validate import raise_bad as _raise_bad
        _raise_bad(name, c)


def _mode_sf(mode, sample_flags=None):
    from .._validate import check_mode as _mode, check_sample_flags as _sflags
    return _mode(mode), (None if sample_flags is None else _sflags(sample_flags))


def eval(model, wo, wi, wavelengths, mode, out):
    core = _spectral_core(model)
    wo, wi, lam = as_dirs(wo, "wo"), as_dirs(wi, "wi"), check_wavelengths(wavelengths)
    batch = broadcast_batch(("wo", "wi", "wavelengths"), wo.shape[:-1], wi.shape[:-1], lam.shape[:-1])
    dtype = kernel_dtype(wo, wi)
    md, _ = _mode_sf(mode)
    out = check_out(out, batch + (4,), dtype)
    if out.size:
        _raise_counts(core.eval(flatten_to(wo, batch, (3,), dtype), flatten_to(wi, batch, (3,), dtype),
                                flatten_to(lam, batch, (4,), np.float64), md, out.reshape(-1, 4)),
                      ("wo", "wi", "wavelengths"))
    return out


def pdf(model, wo, wi, wavelengths, mode, sample_flags, out):
    core = _spectral_core(model)
    wo, wi, lam = as_dirs(wo, "wo"), as_dirs(wi, "wi"), check_wavelengths(wavelengths)
    batch = broadcast_batch(("wo", "wi", "wavelengths"), wo.shape[:-1], wi.shape[:-1], lam.shape[:-1])
    dtype = kernel_dtype(wo, wi)
    md, sf = _mode_sf(mode, sample_flags)
    out = check_out(out, batch, dtype)
    if out.size:
        _raise_counts(core.pdf(flatten_to(wo, batch, (3,), dtype), flatten_to(wi, batch, (3,), dtype),
                               flatten_to(lam, batch, (4,), np.float64), md, sf, out.reshape(-1)),
                      ("wo", "wi", "wavelengths"))
    return out


def sample(model, wo, uc, u, n, seed, wavelengths, mode, sample_flags, out):
    from .base import SampleResult, _sample_result
    core = _spectral_core(model)
    wo, lam = as_dirs(wo, "wo"), check_wavelengths(wavelengths)
    uc, u, dtype, batch = sample_uniforms(wo, uc, u, n, seed, ("wavelengths",), (lam.shape[:-1],))
    md, sf = _mode_sf(mode, sample_flags)
    if out is not None:
        raise ValueError("out: not supported with wavelengths= (spectral sample results are allocated)")
    m = math.prod(batch)
    res = _sample_result((np.empty(batch + (3,), dtype), np.empty(batch + (4,), dtype), np.empty(batch, dtype),
                          np.empty(batch, np.uint8), np.empty(batch, dtype), np.empty(batch, bool),
                          np.empty(batch, bool)))
    res.__dict__["terminated"] = np.empty(batch, bool)
    if m:
        ucf = np.ascontiguousarray(np.broadcast_to(uc, batch), dtype=dtype).reshape(-1)
        uf = np.ascontiguousarray(np.broadcast_to(u, batch + (2,)), dtype=dtype).reshape(-1, 2)
        _raise_counts(core.sample(flatten_to(wo, batch, (3,), dtype), ucf, uf, flatten_to(lam, batch, (4,), np.float64),
                                  md, sf, res.wi.reshape(-1, 3), res.f.reshape(-1, 4), res.pdf.reshape(-1),
                                  res.flags.reshape(-1), res.eta.reshape(-1), res.valid.reshape(-1),
                                  res.pdf_is_proportional.reshape(-1), res.terminated.reshape(-1)),
                      ("wo", "uc", "u", "wavelengths"))
    assert isinstance(res, SampleResult)
    return res


def albedo(model, wo, wavelengths, n_samples, seed, mode):
    core = _spectral_core(model)
    wo, lam = as_dirs(wo, "wo"), check_wavelengths(wavelengths)
    n_samples = check_int(n_samples, "n_samples", 1, MAX_ALBEDO_SAMPLES)
    seed = check_int(seed, "seed", 0)
    batch = broadcast_batch(("wo", "wavelengths"), wo.shape[:-1], lam.shape[:-1])
    dtype = kernel_dtype(wo)
    md, _ = _mode_sf(mode)
    out = np.empty(batch + (4,), dtype)
    if out.size:
        wof = np.ascontiguousarray(np.broadcast_to(wo, batch + (3,)), dtype=dtype).reshape(-1, 3)
        _raise_counts(core.albedo(wof, flatten_to(lam, batch, (4,), np.float64), n_samples, seed & 0xFFFFFFFFFFFFFFFF,
                                  md, out.reshape(-1, 4)), ("wo", "wavelengths"))
    return out
