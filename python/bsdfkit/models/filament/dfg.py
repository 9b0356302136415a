"""Filament's material models: the DFG lookup table, the individual terms and the constants.

The models themselves are :class:`bsdfkit.FilamentStandard` and :class:`bsdfkit.FilamentCloth`.

The DFG table is computed by bsdfkit (in C++, double precision) rather than ported from
Filament's texture, and cached per ``(size, samples)`` for the life of the process::

    >>> import bsdfkit as bk
    >>> lut = bk.filament.dfg_lut(128)        # (128, 128, 3) float64, read-only
    >>> lut[j, i]                             # (x, y, z) at roughness j / 127, NoV i / 127

Channels, with alpha = r**2 (r the perceptual roughness) and v at angle acos(NoV) from the normal:

* ``x = integral of D V (1 - VoH)^5 <NoL> dl`` and ``y = integral of D V <NoL> dl`` (GGX, height-
  correlated V): Filament's multiscatter DFG; ``(1 - f0) x + f0 y`` is the albedo of the Schlick
  GGX lobe with f90 = 1 and ``y`` the E of the energy compensation ``1 + f0 (1/y - 1)``.
* ``z = integral of D_Charlie V_Neubelt <NoL> dl``: the cloth/sheen albedo used by the sheen
  scaling ``1 - max(sheen_color) z``.

Rows are roughness and columns NoV on a grid that includes both end points, ``k / (size - 1)``
(column 0 is evaluated at NoV = MIN_N_DOT_V = 1e-4; row 0 holds the alpha -> 0 limits
x = (1 - NoV)^5, y = 1, z = 0); models interpolate bilinearly. This layout is ours: Filament's
texture holds texel centres (with a one-texel roughness shift) and ``textureLod`` clamps within
half a texel of 0 and 1, which alone leaves the energy-compensated white metal 1.4 % dark at
roughness 1 (size 128).
"""
from __future__ import annotations

import math
import sys
import threading
import time

import numpy as np

from ... import _core

__all__ = ["dfg_lut", "term", "TERMS", "MIN_PERCEPTUAL_ROUGHNESS", "MIN_N_DOT_V", "DFG_LUT_SIZE",
           "DFG_LUT_SAMPLES"]

#: Filament's roughness clamps (``MIN_PERCEPTUAL_ROUGHNESS``; alpha floor = its square).
MIN_PERCEPTUAL_ROUGHNESS = {"desktop": 0.045, "mobile": 0.089}
#: ``MIN_N_DOT_V``: Filament clamps NoV to at least this value.
MIN_N_DOT_V = 1e-4
#: Filament's ``FILAMENT_DFG_LUT_SIZE`` default.
DFG_LUT_SIZE = 128
#: Quasi-Monte Carlo samples per texel and strategy used by the models (error <= 1.2e-4 for x, y
#: and <= 2.5e-4 for z against quadrature; see tests/test_filament_dfg.py).
DFG_LUT_SAMPLES = 1024

#: Names accepted by :func:`term` and their arguments.
TERMS = {
    "D_GGX": ("alpha_t", "alpha_b", "hx", "hy", "hz"),
    "D_Charlie": ("alpha", "NoH"),
    "D_Ashikhmin": ("alpha", "NoH"),
    "V_SmithGGXCorrelated": ("alpha", "NoV", "NoL"),
    "V_SmithGGXCorrelated_Fast": ("alpha", "NoV", "NoL"),
    "V_SmithGGXCorrelated_Anisotropic": ("alpha_t", "alpha_b", "ToV", "BoV", "ToL", "BoL", "NoV", "NoL"),
    "V_Kelemen": ("LoH",),
    "V_Neubelt": ("NoV", "NoL"),
    "F_Schlick": ("f0", "f90", "VoH"),
    "Fd_Lambert": ("any",),
    "Fd_Burley": ("alpha", "NoV", "NoL", "LoH"),
    "Fd_Wrap": ("NoL", "w"),
    "f0ClearCoatToSurface": ("f0",),
}

_CACHE: dict = {}
_LOCK = threading.Lock()


def _check_size(size, samples):
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or not 2 <= size <= 4096:
        raise ValueError(f"size: must be an integer in [2, 4096], got {size!r}")
    if samples is None:
        samples = DFG_LUT_SAMPLES
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not 2 <= samples <= 1 << 24:
        raise ValueError(f"samples: must be an integer in [2, 2**24], got {samples!r}")
    return int(size), int(samples)


def _table(size=DFG_LUT_SIZE, samples=None, progress=None):
    """The cached compiled table (``_core.FilamentDFG``) shared by every model of this size."""
    size, samples = _check_size(size, samples)
    key = (size, samples)
    with _LOCK:
        t = _CACHE.get(key)
        if t is None:
            t = _core.FilamentDFG(_build(size, samples, progress), samples)
            _CACHE[key] = t
    return t


def _build(size, samples, progress):
    """Row chunks of the C++ builder; reports progress on stderr once it runs longer than 1 s
    (``progress=None``), always (``True``) or never (``False``)."""
    out = np.empty((size, size, 3))
    t0 = time.perf_counter()
    step = max(1, math.ceil(size / 32))
    shown = False
    last = -1.0
    for r0 in range(0, size, step):
        r1 = min(size, r0 + step)
        out[r0:r1] = _core.filament_dfg_rows(size, samples, r0, r1)
        elapsed = time.perf_counter() - t0
        due = r1 == size or elapsed - last >= 0.25
        if due and (progress or (progress is None and elapsed > 1.0)):
            last = elapsed
            print(f"\rbsdfkit: computing the Filament DFG table ({size}x{size}, {samples} samples): "
                  f"{100 * r1 // size:3d}% ({elapsed:.1f} s)", end="", file=sys.stderr, flush=True)
            shown = True
    if shown:
        print(file=sys.stderr, flush=True)
    return out


def dfg_lut(size: int = DFG_LUT_SIZE, samples: int | None = None, *, progress=None) -> np.ndarray:
    """Filament's DFG table computed in float64: a read-only ``(size, size, 3)`` array.

    ``lut[j, i] = (x, y, z)`` at perceptual roughness ``j / (size - 1)`` and NoV
    ``i / (size - 1)`` (NoV = 1e-4 for i = 0; see the module docstring for the channels). ``samples`` quasi-Monte
    Carlo samples per texel (default :data:`DFG_LUT_SAMPLES`). Cached per ``(size, samples)``;
    the first call for a size takes one to three seconds at 128 (progress is printed on stderr when
    it takes longer than that; ``progress=True/False`` forces it on/off).
    """
    a = _table(size, samples, progress).array()
    a.setflags(write=False)
    return a


def term(name: str, *args, dtype=np.float64) -> np.ndarray:
    """Evaluates one Filament term of the C++ core elementwise (arguments broadcast).

    ``name`` is one of :data:`TERMS` (Filament's shader names: ``D_GGX``, ``V_Kelemen``, ...;
    ``D_GGX`` takes the half vector in the local frame and covers ``D_GGX_Anisotropic``).
    ``dtype`` float64 or float32 selects the kernel precision. Meant for term-by-term checks;
    the models call the same functions.
    """
    if name not in TERMS:
        raise ValueError(f"name: unknown Filament term {name!r}; known: {', '.join(TERMS)}")
    if len(args) != len(TERMS[name]):
        raise ValueError(f"{name}: expects {len(TERMS[name])} arguments {TERMS[name]}, got {len(args)}")
    dtype = np.dtype(dtype)
    if dtype not in (np.float32, np.float64):
        raise TypeError(f"dtype: must be float32 or float64, got {dtype}")
    arrs = np.broadcast_arrays(*[np.asarray(a, dtype=dtype) for a in args])
    shape = arrs[0].shape
    flat = [np.ascontiguousarray(a, dtype=dtype).reshape(-1) for a in arrs]
    if flat[0].size == 0:
        return np.zeros(shape, dtype)
    return _core.filament_term(name, flat).reshape(shape)
