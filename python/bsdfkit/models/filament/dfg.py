"""Filament's material models: the DFG lookup table, the individual terms and the constants.

The models themselves are :class:`bsdfkit.FilamentStandard` and :class:`bsdfkit.FilamentCloth`.

The DFG table is computed by bsdfkit (in C++, double precision) rather than ported from
Filament's texture, cached per ``(size, samples)`` for the life of the process and on disk
under :func:`cache_dir` (keyed by size, samples and the digest of the compiled builder), so
only the first process on a machine pays the few seconds it takes::

    >>> import bsdfkit as bk
    >>> lut = bk.filament.dfg_lut(128)        # float64, read-only
    >>> lut.shape                             # lut[j, i]: (x, y, z) at roughness j / 127, NoV i / 127
    (128, 128, 3)

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

import hashlib
import math
import os
import sys
import tempfile
import threading
import time

import numpy as np

from ... import _core

__all__ = ["dfg_lut", "cache_dir", "term", "TERMS", "MIN_PERCEPTUAL_ROUGHNESS", "MIN_N_DOT_V", "DFG_LUT_SIZE",
           "DFG_LUT_SAMPLES"]

#: Filament's roughness clamps (``MIN_PERCEPTUAL_ROUGHNESS``; alpha floor = its square).
MIN_PERCEPTUAL_ROUGHNESS = {"desktop": 0.045, "mobile": 0.089}
#: ``MIN_N_DOT_V``: Filament clamps NoV to at least this value.
MIN_N_DOT_V = 1e-4
#: Filament's ``FILAMENT_DFG_LUT_SIZE`` default.
DFG_LUT_SIZE = 128
#: Quasi-Monte Carlo samples per texel and strategy used by the models (error <= 1.2e-4 for x, y
#: and <= 2.5e-4 for z against quadrature; see tests/models/test_filament_dfg.py).
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
    """The cached compiled table (``_core.FilamentDFG``) shared by every model of this size:
    from this process's cache, else from the on-disk cache (:func:`cache_dir`), else computed
    (and then written to the disk cache)."""
    size, samples = _check_size(size, samples)
    key = (size, samples)
    with _LOCK:
        t = _CACHE.get(key)
        if t is None:
            a = _load_cached(size, samples)
            if a is None:
                a = _build(size, samples, progress)
                _store_cached(size, samples, a)
            t = _core.FilamentDFG(a, samples)
            _CACHE[key] = t
    return t


#: Whether ``_build`` reports progress when ``progress=None``: None = only on an interactive
#: stderr for builds over 1 s; the CLI's ``-q`` sets False.
PROGRESS_DEFAULT = None


def cache_dir() -> str:
    """Directory of bsdfkit's on-disk cache: ``$BSDFKIT_CACHE_DIR`` if set, else the user cache
    directory (``$XDG_CACHE_HOME/bsdfkit`` or ``~/.cache/bsdfkit``; ``%LOCALAPPDATA%\\bsdfkit`` on
    Windows, ``~/Library/Caches/bsdfkit`` on macOS)."""
    d = os.environ.get("BSDFKIT_CACHE_DIR")
    if d:
        return d
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or os.path.expanduser("~\\AppData\\Local")
    elif sys.platform == "darwin":
        base = os.path.expanduser("~/Library/Caches")
    else:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    return os.path.join(base, "bsdfkit")


_BUILDER_DIGEST = None


def _builder_digest() -> str:
    """Content key of the code that computes the table: the SHA-256 of the compiled extension
    (a rebuilt or upgraded bsdfkit never reads a table an older builder wrote)."""
    global _BUILDER_DIGEST
    if _BUILDER_DIGEST is None:
        h = hashlib.sha256()
        with open(_core.__file__, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
        _BUILDER_DIGEST = h.hexdigest()[:16]
    return _BUILDER_DIGEST


def _cache_path(size, samples) -> str:
    return os.path.join(cache_dir(), f"filament-dfg-{size}x{size}-{samples}-{_builder_digest()}.npy")


def _load_cached(size, samples):
    """The table from the disk cache, or None (missing, unreadable or not a valid table)."""
    try:
        a = np.load(_cache_path(size, samples), allow_pickle=False)
    except Exception:   # any damage (tokenize.TokenError from a mangled header, a zip, ...) makes the
        return None     # cache invalid: computed again, never an error
    if not isinstance(a, np.ndarray) or a.shape != (size, size, 3) or a.dtype != np.float64 or not np.all(np.isfinite(a)):
        return None
    return a


def _store_cached(size, samples, a) -> None:
    """Writes the table atomically (temporary file + rename); a read-only or missing cache
    directory only means the next process computes it again."""
    path = _cache_path(size, samples)
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.save(fh, a, allow_pickle=False)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
    except OSError:
        pass


def _build(size, samples, progress):
    """Row chunks of the C++ builder; reports progress on stderr once it runs longer than 1 s
    (``progress=None``: only when stderr is a terminal, and never after the CLI's ``-q``),
    always (``True``) or never (``False``)."""
    if progress is None:
        progress = PROGRESS_DEFAULT
        if progress is None:
            progress = None if _stderr_is_tty() else False
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
            print(f"\rbsdfkit: computing the Filament DFG table ({size}x{size}, {samples} samples, "
                  f"cached in {cache_dir()}): {100 * r1 // size:3d}% ({elapsed:.1f} s)", end="", file=sys.stderr,
                  flush=True)
            shown = True
    if shown:
        print(file=sys.stderr, flush=True)
    return out


def _stderr_is_tty() -> bool:
    try:
        return sys.stderr is not None and sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def dfg_lut(size: int = DFG_LUT_SIZE, samples: int | None = None, *, progress=None) -> np.ndarray:
    """Filament's DFG table computed in float64: a read-only ``(size, size, 3)`` array.

    ``lut[j, i] = (x, y, z)`` at perceptual roughness ``j / (size - 1)`` and NoV
    ``i / (size - 1)`` (NoV = 1e-4 for i = 0; see the module docstring for the channels). ``samples`` quasi-Monte
    Carlo samples per texel (default :data:`DFG_LUT_SAMPLES`). Cached per ``(size, samples)`` in
    the process and on disk (:func:`cache_dir`); computing a table takes one to five seconds at
    128 (progress is printed on an interactive stderr when it takes longer than 1 s;
    ``progress=True/False`` forces it on/off).
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
