"""The argument checks of the whole package, in one place: the wording of every error a user
sees for a bad argument (the parameter's name first), shared by the models, the array door's
Python side, the plots, the renderer and the trade-off tools. No imports from the rest of the
package but the enums, so that any module can use it without an import cycle."""
from __future__ import annotations

import math
import numbers

import numpy as np

from ._enums import ReflTrans, TransportMode

__all__ = ["check_int", "check_real", "check_rgb", "check_array", "check_mode", "check_sample_flags", "bad_message",
           "raise_bad"]


def check_int(x, name: str, lo: int, hi: int | None = None) -> int:
    """An integer (numpy's too; not a bool) in [lo, hi]: TypeError for another type, ValueError
    out of range, both naming ``name``."""
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        raise TypeError(f"{name}: expected an integer, got {type(x).__name__}")
    if x < lo:
        raise ValueError(f"{name}: must be >= {lo}, got {x}")
    if hi is not None and x > hi:
        raise ValueError(f"{name}: must be <= {hi}, got {x}")
    return int(x)


def check_array(x, name: str, tail: tuple = (), *, lo=None, hi=None, lo_open=False):
    """A per-element parameter: a read-only float64 array of trailing shape ``tail`` whose entries
    are finite and within the bounds, or, when it has no element axis (shape ``tail``), a float
    (``tail == ()``) or that float64 array. Wrong types raise TypeError, bad entries ValueError
    naming ``name`` and the first bad index."""
    try:
        a = np.asarray(x)
    except Exception as e:
        raise TypeError(f"{name}: cannot be converted to a numeric array ({e})") from None
    if a.dtype.kind not in "fiu" or a.dtype == np.bool_:
        raise TypeError(f"{name}: expected real numbers, got {type(x).__name__} of dtype {a.dtype}")
    if a.ndim < len(tail) or a.shape[a.ndim - len(tail):] != tail:
        raise ValueError(f"{name}: expected trailing shape {tail}, got {a.shape}")
    a = a.astype(np.float64)
    items = a.reshape((-1,) + tail)
    flat = items.reshape(len(items), -1)
    bad = ~np.isfinite(flat).all(1)
    what = "not finite"
    if not bad.any() and lo is not None:
        bad = ~(flat > lo if lo_open else flat >= lo).all(1)
        what = f"{'<=' if lo_open else '<'} {lo}"
    if not bad.any() and hi is not None:
        bad = ~(flat <= hi).all(1)
        what = f"> {hi}"
    if bad.any():
        i = int(np.argmax(bad))
        idx = np.unravel_index(i, a.shape[:a.ndim - len(tail)]) if a.ndim > len(tail) else ()
        rng = "" if lo is None and hi is None else (
            f" and {'>' if lo_open else '>='} {lo}" if hi is None else
            f" and in {'(' if lo_open else '['}{lo if lo is not None else '-inf'}, {hi}]")
        raise ValueError(f"{name}: entries must be finite{rng}; the first bad one, at index "
                         f"{tuple(int(j) for j in idx)}, is {what}: {items[i].tolist()}")
    if a.ndim == len(tail) and not tail:
        return float(a)
    a.setflags(write=False)
    return a


def _is_elements(x, ndim: int) -> bool:
    """Whether x is array-like with more than ``ndim`` axes (an element axis), not a scalar / RGB."""
    if isinstance(x, (np.ndarray, list, tuple)):
        return np.ndim(x) > ndim
    return False


def check_real(x, name: str, *, lo=None, hi=None, lo_open=False, varying=False):
    """A finite real number within the bounds (``lo_open``: strictly above lo). ``varying``: an
    array of them is accepted too (a per-element parameter, ``check_array``)."""
    if varying and _is_elements(x, 0):
        return check_array(x, name, lo=lo, hi=hi, lo_open=lo_open)
    if isinstance(x, bool) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name}: expected a real number, got {type(x).__name__}")
    v = float(x)
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {v}")
    if lo is not None and (v <= lo if lo_open else v < lo):
        raise ValueError(f"{name}: must be {'>' if lo_open else '>='} {lo}, got {v}")
    if hi is not None and v > hi:
        raise ValueError(f"{name}: must be <= {hi}, got {v}")
    return v


def check_rgb(x, name: str, *, lo=None, hi=None, lo_open=False, varying=False) -> np.ndarray:
    """A number (grey) or 3 numbers (RGB), finite and within the bounds per channel: a read-only
    float64 (3,) array. ``varying``: an array of shape (..., 3) is accepted too (an RGB value per
    element, ``check_array``)."""
    if varying and _is_elements(x, 1):
        return check_array(x, name, (3,), lo=lo, hi=hi, lo_open=lo_open)
    a = np.asarray(x)
    if a.dtype.kind not in "fiu":
        raise TypeError(f"{name}: expected a number or 3 numbers (RGB), got dtype {a.dtype}")
    if a.ndim == 0:
        a = np.repeat(a, 3)
    if a.shape != (3,):
        raise ValueError(f"{name}: expected a number or 3 numbers (RGB), got shape {a.shape}")
    a = a.astype(np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: must be finite, got {a.tolist()}")
    if lo is not None and np.any(a <= lo if lo_open else a < lo):
        raise ValueError(f"{name}: every channel must be {'>' if lo_open else '>='} {lo}, got {a.tolist()}")
    if hi is not None and np.any(a > hi):
        raise ValueError(f"{name}: every channel must be <= {hi}, got {a.tolist()}")
    a.setflags(write=False)
    return a


def check_mode(mode) -> int:
    """A TransportMode (or its name) as its integer."""
    if isinstance(mode, str) and mode.capitalize() in TransportMode.__members__:
        return int(TransportMode[mode.capitalize()])
    try:
        return int(TransportMode(mode))
    except (ValueError, TypeError):
        raise ValueError(f"mode: must be a TransportMode, got {mode!r}") from None


def check_sample_flags(sf) -> int:
    """A ReflTrans as its integer (0..All)."""
    try:
        v = int(ReflTrans(sf))
    except (ValueError, TypeError):
        raise ValueError(f"sample_flags: must be a ReflTrans, got {sf!r}") from None
    if not 0 <= int(sf) <= int(ReflTrans.All):  # IntFlag takes -1 as ~0, i.e. All
        raise ValueError(f"sample_flags: must be a ReflTrans (0..{int(ReflTrans.All)}), got {sf!r}")
    return v


def bad_message(name: str, count: int) -> str:
    """The words of cpp/bindings/bind_model.h bad_message (the compiled fast path raises those)."""
    if name in ("uc", "u"):
        return f"{name}: {count} sample value(s) are outside [0, 1] or NaN (uniforms must lie in [0, 1])"
    return (f"{name}: {count} direction(s) are not finite unit vectors "
            "(|w|^2 must equal 1 within 1e-4; normalize them first)")


def raise_bad(name: str, count: int) -> None:
    """ValueError naming ``name`` when the kernels counted ``count`` > 0 bad inputs."""
    if count:
        raise ValueError(bad_message(name, count))
