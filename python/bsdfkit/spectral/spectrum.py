"""``Spectrum``: an immutable spectral value (a function of wavelength in nm) for model parameters."""
from __future__ import annotations

import numpy as np

from .._arrays import check_real
from . import colorimetry, named as _named, uplift

__all__ = ["Spectrum"]

_RGB_KINDS = ("reflectance", "unbounded", "illuminant")
# Planck's law constants (CODATA 2018, exact SI values).
_C = 299792458.0
_H = 6.62607015e-34
_KB = 1.380649e-23
_WIEN = 2.897771955e-3       # Wien's displacement constant b, m K


def _array_1d(x, name):
    try:
        a = np.asarray(x)
    except Exception as e:  # ragged nested sequences and the like
        raise ValueError(f"{name}: expected a 1-D sequence of numbers ({e})") from None
    if a.dtype.kind not in "fiu" or a.dtype == np.bool_:
        raise TypeError(f"{name}: expected real numbers, got dtype {a.dtype}")
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"{name}: expected a non-empty 1-D sequence, got shape {a.shape}")
    a = a.astype(np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: must be finite, got {a.tolist()}")
    a.setflags(write=False)
    return a


def _planck(lam_nm, T):
    """Spectral radiance of a black body, W / (m^2 sr m) (Planck's law)."""
    l = lam_nm * 1e-9
    with np.errstate(over="ignore"):
        return (2 * _H * _C * _C) / (l ** 5 * np.expm1((_H * _C) / (l * _KB * T)))


def _planck_ratio_log(lam_nm, T):
    """Planck's law over its peak value, B(lam, T) / B(lam_max, T), in logarithms: the form for
    temperatures where the direct ratio over- or underflows (T near 0 or beyond ~1e30 K), where it
    tends to 0 across the visible range. lam_max = b / T (Wien), so x_max = hc / (lam_max k T)
    does not depend on T."""
    l = lam_nm * 1e-9
    with np.errstate(divide="ignore", over="ignore"):
        x = (_H * _C) / (l * _KB * T)  # inf where l k T underflows (T near 0): the value is 0 there
    x_max = (_H * _C) / (_WIEN * _KB)

    def log_expm1(y):
        with np.errstate(divide="ignore", over="ignore"):
            return np.where(y > 30, y + np.log1p(-np.exp(-np.minimum(y, 700.0))), np.log(np.expm1(np.minimum(y, 30.0))))

    with np.errstate(divide="ignore"):
        r = 5 * (np.log(_WIEN / T) - np.log(l)) + log_expm1(np.float64(x_max)) - log_expm1(x)
    return np.exp(r)


class Spectrum:
    """A spectrum: a function of wavelength (nm) given as

    * ``Spectrum(wavelengths, values)``: samples, piecewise linear in between, and outside the
      samples the nearest end value (pbrt-v4 extends tabulated spectra this way over its
      [360, 830] nm range, ``PiecewiseLinearSpectrum::FromInterleaved``);
    * ``Spectrum.constant(c)``; ``Spectrum.blackbody(T)`` (Planck, normalised to 1 at its peak as
      pbrt-v4's ``BlackbodySpectrum``);
    * ``Spectrum.named(name)``: pbrt-v4's and Mitsuba's measured metal eta/k and glass IOR
      spectra (``Spectrum.names()``);
    * ``Spectrum.from_rgb(rgb, kind)``: a linear sRGB colour uplifted to a smooth spectrum
      (Jakob & Hanika 2019, pbrt-v4's three kinds; see ``bsdfkit.spectral.uplift``).

    Immutable, compares and hashes by value (a named spectrum equals the same samples given
    directly), pickles, and ``eval(repr(s)) == s`` with ``Spectrum`` in scope. ``s(lambda)``
    evaluates at any finite positive wavelengths (float64, same shape); :meth:`to_rgb` projects
    to linear sRGB as Mitsuba 3 does.

    Parameters
    ----------
    wavelengths : array_like, 1-D
        Sample wavelengths in nm, > 0 and strictly increasing.
    values : array_like, 1-D
        One value per wavelength.

    Raises
    ------
    ValueError
        Mismatched lengths, a wavelength <= 0, duplicate or decreasing wavelengths (named).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> s = bk.Spectrum([400, 500, 600], [0.25, 0.5, 1.0])
    >>> s([450, 700]).tolist()   # linear in between, the end value outside
    [0.375, 1.0]
    >>> round(float(bk.Spectrum.named("glass-BK7")(550.0)), 4)
    1.5185
    """

    __slots__ = ("_kind", "_data", "_name")

    def __init__(self, wavelengths, values):
        lam = _array_1d(wavelengths, "wavelengths")
        val = _array_1d(values, "values")
        if lam.shape != val.shape:
            raise ValueError(f"values: expected one value per wavelength ({lam.size}), got {val.size}")
        if np.any(lam <= 0):
            raise ValueError(f"wavelengths: must be > 0 nm, got {lam.tolist()}")
        d = np.diff(lam)
        if np.any(d == 0):
            raise ValueError(f"wavelengths: duplicate wavelength {lam[1:][d == 0][0]!r} nm")
        if np.any(d < 0):
            raise ValueError(f"wavelengths: must be increasing, got {lam.tolist()}")
        self._set("sampled", (lam, val), None)

    def _set(self, kind, data, name):
        object.__setattr__(self, "_kind", kind)
        object.__setattr__(self, "_data", data)
        object.__setattr__(self, "_name", name)

    @classmethod
    def _make(cls, kind, data, name=None):
        s = object.__new__(cls)
        s._set(kind, data, name)
        return s

    # ------------------------------------------------------------------ constructors
    @classmethod
    def constant(cls, value) -> "Spectrum":
        """The same value at every wavelength."""
        return cls._make("constant", (check_real(value, "value"),))

    @classmethod
    def blackbody(cls, T) -> "Spectrum":
        """Planck's law at temperature ``T`` (kelvin, > 0), divided by its value at the peak
        wavelength (Wien), so the maximum is 1 (pbrt-v4 ``BlackbodySpectrum``)."""
        t = check_real(T, "T")
        if t <= 0:
            raise ValueError(f"T: must be > 0 K, got {t}")
        return cls._make("blackbody", (t,))

    @classmethod
    def named(cls, name: str) -> "Spectrum":
        """A named spectrum of pbrt-v4 (``metal-Cu-eta``, ``glass-BK7`` ...) or Mitsuba 3
        (``mitsuba-Cr-k`` ...); ``Spectrum.names()`` lists them."""
        lam, val, _ = _named.data(name)
        return cls._make("sampled", (lam, val), name)

    @staticmethod
    def names() -> tuple:
        """Every name :meth:`named` accepts."""
        return _named.names()

    @classmethod
    def from_rgb(cls, rgb, kind: str = "reflectance", *, exact: bool = True) -> "Spectrum":
        """A linear sRGB colour as a smooth spectrum (Jakob & Hanika 2019, as pbrt-v4):

        * ``"reflectance"`` (pbrt-v4 ``RGBAlbedoSpectrum``): rgb in [0, 1]; values in [0, 1].
        * ``"unbounded"`` (``RGBUnboundedSpectrum``, for eta, k, absorption): rgb >= 0.
        * ``"illuminant"`` (``RGBIlluminantSpectrum``, for lights): rgb >= 0; the unbounded
          spectrum times D65 normalised to unit luminance.

        exact: polish the table's coefficients with a few Newton steps so that the spectrum
        projects back to ``rgb`` (pbrt-v4's projection) within 1e-6 instead of the trilinear
        table lookup's error (median 2e-4, up to 4e-3 near the gamut boundary); False gives
        pbrt-v4's lookup as is. The first use fits (or loads from the cache) the table.
        """
        if not isinstance(exact, (bool, np.bool_)):
            raise TypeError(f"exact: expected True or False, got {exact!r}")
        if kind not in _RGB_KINDS:
            raise ValueError(f"kind: expected one of {', '.join(map(repr, _RGB_KINDS))}, got {kind!r}")
        a = np.asarray(rgb)
        if a.dtype.kind not in "fiu" or a.dtype == np.bool_:
            raise TypeError(f"rgb: expected 3 real numbers, got dtype {a.dtype}")
        if a.ndim == 0:
            a = np.repeat(a, 3)
        if a.shape != (3,):
            raise ValueError(f"rgb: expected a number or 3 numbers, got shape {a.shape}")
        a = a.astype(np.float64)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"rgb: must be finite, got {a.tolist()}")
        if np.any(a < 0):
            raise ValueError(f"rgb: every channel must be >= 0, got {a.tolist()}")
        if kind == "reflectance" and np.any(a > 1):
            raise ValueError(f"rgb: a reflectance must be in [0, 1], got {a.tolist()} (use kind='unbounded')")
        a.setflags(write=False)
        coeffs, scale = uplift.rgb_coefficients(a, kind, exact=bool(exact))
        coeffs.setflags(write=False)
        return cls._make("rgb", (a, kind, coeffs, float(scale), bool(exact)))

    # ------------------------------------------------------------------ properties
    @property
    def kind(self) -> str:
        """"sampled", "constant", "blackbody" or "rgb"."""
        return self._kind

    @property
    def name(self):
        """The name a named spectrum was made from, else None."""
        return self._name

    @property
    def wavelengths(self):
        """Sample wavelengths (nm) of a sampled spectrum (read-only), else None."""
        return self._data[0] if self._kind == "sampled" else None

    @property
    def values(self):
        """Sample values of a sampled spectrum (read-only), else None."""
        return self._data[1] if self._kind == "sampled" else None

    @property
    def rgb(self):
        """The colour a ``from_rgb`` spectrum was made from (read-only), else None."""
        return self._data[0] if self._kind == "rgb" else None

    @property
    def is_constant(self) -> bool:
        """True if the value does not depend on wavelength (no dispersion)."""
        if self._kind == "constant":
            return True
        if self._kind == "sampled":
            return bool(np.all(self._data[1] == self._data[1][0]))
        return False

    # ------------------------------------------------------------------ evaluation
    def __call__(self, wavelengths) -> np.ndarray:
        """Values at ``wavelengths`` (nm; finite, > 0; any shape), float64 of the same shape."""
        lam = np.asarray(wavelengths)
        if lam.dtype.kind not in "fiu" or lam.dtype == np.bool_:
            raise TypeError(f"wavelengths: expected real numbers, got dtype {lam.dtype}")
        lam = lam.astype(np.float64)
        if not np.all(np.isfinite(lam)):
            raise ValueError("wavelengths: must be finite")
        if np.any(lam <= 0):
            raise ValueError(f"wavelengths: must be > 0 nm, got min {lam.min()}")
        return self._eval(lam)

    def _eval(self, lam):
        k, d = self._kind, self._data
        if k == "sampled":
            return np.interp(lam, d[0], d[1])      # constant beyond the ends (pbrt's extension)
        if k == "constant":
            return np.full(lam.shape, d[0])
        if k == "blackbody":
            T = d[0]
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                v = _planck(lam, T) / _planck(np.float64(_WIEN / T * 1e9), T)
            bad = ~np.isfinite(v)
            if np.any(bad):  # extreme T (the peak's radiance or a term over- or underflows): in logs
                v = np.where(bad, _planck_ratio_log(np.asarray(lam, np.float64), T), v)
            return v
        rgb, kind, coeffs, scale, _ = d
        v = scale * uplift.eval_coefficients(coeffs, lam)
        if kind == "illuminant":
            v = v * _d65_unit(lam)
        return v

    def to_rgb(self, kind: str = "reflectance", illuminant="D65", *, normalization: str = "mitsuba") -> np.ndarray:
        """Linear sRGB (BT.709 primaries) of this spectrum, as Mitsuba 3's RGB variants project
        spectra (``bsdfkit.spectral.colorimetry``): float64 (3,).

        kind: ``"reflectance"`` (weighted by ``illuminant``, clipped to [0, 1]), ``"unbounded"``
        (weighted by ``illuminant``, clamped at 0; eta, k) or ``"illuminant"`` (emitted light:
        never weighted, clamped at 0). illuminant: "D65" (Mitsuba's rule for spectra in scene
        dicts) or None (Mitsuba's rule for its IOR presets, ``bsdfkit.METALS``).
        normalization: "mitsuba" (Mitsuba's grid and constants; a constant 1 gives 0.9989 grey)
        or "pbrt" (pbrt-v4's 1 nm sum; a constant c gives grey c; the uplift is fitted for it).

        Sampled spectra are projected as Mitsuba does ``spectrum_list_to_srgb``: 0 outside their
        samples (which differs from ``s(lambda)`` only for data not covering [360, 830] nm).
        """
        if kind not in _RGB_KINDS:
            raise ValueError(f"kind: expected one of {', '.join(map(repr, _RGB_KINDS))}, got {kind!r}")
        if illuminant not in ("D65", None):
            raise ValueError(f"illuminant: expected 'D65' or None, got {illuminant!r}")
        weight = None if kind == "illuminant" else illuminant
        w, W = colorimetry.grid_weights(illuminant=weight, normalization=normalization)
        if self._kind == "sampled":
            lam, val = self._data
            keep = (w >= lam[0]) & (w <= lam[-1])
            v = np.where(keep, np.interp(w, lam, val), 0.0)
        else:
            v = self._eval(w)
        rgb = colorimetry.xyz_to_srgb(v @ W)
        return np.clip(rgb, 0.0, 1.0) if kind == "reflectance" else np.maximum(rgb, 0.0)

    # ------------------------------------------------------------------ value semantics
    def _key(self):
        k, d = self._kind, self._data
        if k == "sampled":
            return (k, tuple(d[0].tolist()), tuple(d[1].tolist()))
        if k == "rgb":
            return (k, tuple(d[0].tolist()), d[1], d[4])
        return (k,) + d

    def __eq__(self, other):
        if not isinstance(other, Spectrum):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash(("Spectrum",) + self._key())

    def __setattr__(self, k, v):
        raise AttributeError("Spectrum is immutable; build a new one instead")

    def __delattr__(self, k):
        raise AttributeError("Spectrum is immutable")

    def __repr__(self):
        k, d = self._kind, self._data
        if k == "sampled":
            if self._name is not None:
                return f"Spectrum.named({self._name!r})"
            return f"Spectrum({d[0].tolist()!r}, {d[1].tolist()!r})"
        if k == "constant":
            return f"Spectrum.constant({d[0]!r})"
        if k == "blackbody":
            return f"Spectrum.blackbody({d[0]!r})"
        extra = "" if d[4] else ", exact=False"
        return f"Spectrum.from_rgb({d[0].tolist()!r}, kind={d[1]!r}{extra})"

    def __reduce__(self):
        k, d = self._kind, self._data
        if k == "sampled":
            if self._name is not None:
                return (_named_spectrum, (self._name,))
            return (Spectrum, (np.array(d[0]), np.array(d[1])))
        if k == "constant":
            return (_constant_spectrum, d)
        if k == "blackbody":
            return (_blackbody_spectrum, d)
        return (_rgb_spectrum, (np.array(d[0]), d[1], d[4]))


def _named_spectrum(name):
    return Spectrum.named(name)


def _constant_spectrum(c):
    return Spectrum.constant(c)


def _blackbody_spectrum(T):
    return Spectrum.blackbody(T)


def _rgb_spectrum(rgb, kind, exact=True):
    return Spectrum.from_rgb(rgb, kind, exact=exact)


def _d65_unit(lam):
    """D65 scaled to luminance Y = 1 under the "pbrt" projection."""
    return colorimetry.d65(lam) * colorimetry._grid("pbrt")[4]
