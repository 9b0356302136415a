"""RGB -> smooth spectrum, Jakob & Hanika 2019 ("A Low-Dimensional Function Space for Efficient
Spectral Upsampling"), the way pbrt-v4 uses it.

A reflectance is s(c0 lambda^2 + c1 lambda + c2) with the sigmoid s(x) = 1/2 + x / (2 sqrt(1 + x^2))
(lambda in nm). The coefficients of every sRGB colour come from a table of res^3 x 3 entries
per "largest channel" (pbrt-v4's ``RGBToSpectrumTable``, res = 64): the largest channel z on a
smoothstep(smoothstep(.)) grid, the other two divided by z on a uniform grid, trilinearly
interpolated. Greys use the closed form (0, 0, (c - 1/2) / sqrt(c (1 - c))) (a constant c).

The table is fitted here, by a vectorized Newton iteration with step halving (3 residuals,
3 unknowns; the paper's Gauss-Newton) on the CIELAB difference between the target and the spectrum's colour under D65 (paper, Sec. 4), with
the "pbrt" projection of :mod:`.colorimetry` (so constant c -> grey c), continuing from slice to
slice of z as the paper's optimizer does. It is generated at first use (about a minute of CPU,
measured 65 s; progress on stderr) and cached under the user cache directory
(``$BSDFKIT_CACHE_DIR``, else ``$XDG_CACHE_HOME/bsdfkit``, else ``~/.cache/bsdfkit``) keyed by a
hash of everything it depends on. Why not at build time: the build is CMake-only (no numpy or
colour-science at build time), and a content-keyed cache regenerates exactly when the CMFs,
matrix or algorithm change.

pbrt-v4's three RGB spectrum kinds (``RGBAlbedoSpectrum``, ``RGBUnboundedSpectrum``,
``RGBIlluminantSpectrum``): see :func:`rgb_coefficients`.
"""
from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from . import colorimetry

__all__ = ["RES", "sigmoid", "eval_coefficients", "rgb_coefficients", "reflectance_coefficients", "refine",
           "table", "fit_table", "z_nodes", "cache_path"]

#: Table resolution per axis (pbrt-v4's ``RGBToSpectrumTable::res``).
RES = 64
_ALGO_VERSION = "bsdfkit-rgb2spec-1"   # bump when the fit changes
_TOL = 1e-5                           # CIELAB residual at which a fit stops
_MAX_ITERS = 60
_LAMBDA0, _LAMBDA_SPAN = colorimetry.LAMBDA_MIN, colorimetry.LAMBDA_MAX - colorimetry.LAMBDA_MIN


def sigmoid(x):
    """s(x) = 1/2 + x / (2 sqrt(1 + x^2)), with s(+-inf) = 1, 0 (Jakob & Hanika 2019, Eq. 3)."""
    x = np.asarray(x, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        s = 0.5 + 0.5 * x / np.hypot(1.0, x)            # hypot: no overflow for huge |x|
    return np.where(np.isinf(x), (x > 0).astype(np.float64), s)


def eval_coefficients(coeffs, wavelengths):
    """s(c0 lambda^2 + c1 lambda + c2) for coefficients (..., 3) (nm units) and wavelengths (nm),
    broadcasting coeffs[..., 0] against wavelengths."""
    c = np.asarray(coeffs, dtype=np.float64)
    lam = np.asarray(wavelengths, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        x = (c[..., 0] * lam + c[..., 1]) * lam + c[..., 2]
    # c2 = +-inf (closed form of black / white) gives inf + finite = inf: no NaN.
    return sigmoid(x)


def z_nodes(res: int = RES) -> np.ndarray:
    """The largest-channel grid: smoothstep(smoothstep(k / (res - 1))) (Jakob & Hanika 2019, Sec. 4)."""
    k = np.arange(res) / (res - 1.0)
    s = k * k * (3.0 - 2.0 * k)
    return s * s * (3.0 - 2.0 * s)


# --------------------------------------------------------------------------- the fit
def _lab_f(t):
    d = 6.0 / 29.0
    return np.where(t > d ** 3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0)


def _lab_df(t):
    d = 6.0 / 29.0
    return np.where(t > d ** 3, 1.0 / (3.0 * np.cbrt(np.maximum(t, d ** 3)) ** 2), 1.0 / (3 * d * d))


def _lab(xyz, white):
    f = _lab_f(xyz / white)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1)


def _lab_jacobian(xyz, white):
    """d Lab / d XYZ (..., 3, 3)."""
    g = _lab_df(xyz / white) / white
    z = np.zeros_like(g[..., 0])
    rows = [[z, 116 * g[..., 1], z], [500 * g[..., 0], -500 * g[..., 1], z], [z, 200 * g[..., 1], -200 * g[..., 2]]]
    return np.stack([np.stack(r, -1) for r in rows], -2)


class _Problem:
    """The projection used by the fit: XYZ = s(B c) @ W on the 1000-point grid, B = [t^2, t, 1]
    with t = (lambda - 360) / 470."""

    def __init__(self):
        w, W = colorimetry.grid_weights(illuminant="D65", normalization="pbrt")
        t = (w - _LAMBDA0) / _LAMBDA_SPAN
        self.B = np.stack([t * t, t, np.ones_like(t)], 0)            # (3, n)
        self.W = W                                                    # (n, 3)
        self.white = np.ones(self.W.shape[0]) @ W                     # XYZ of a constant 1
        self.WB = [W * self.B[k][:, None] for k in range(3)]          # (n, 3) each

    def xyz(self, c):
        return sigmoid(c @ self.B) @ self.W

    def xyz_and_jacobian(self, c):
        x = c @ self.B
        q = 1.0 / np.sqrt(1.0 + x * x)
        s = 0.5 + 0.5 * x * q
        ds = 0.5 * q * q * q                                          # s'(x)
        xyz = s @ self.W
        J = np.stack([ds @ self.WB[k] for k in range(3)], -1)         # (m, 3 xyz, 3 coeffs)
        return xyz, J


def _solve_slice(prob, target_xyz, c, tol=_TOL, max_iters=_MAX_ITERS, stats=None):
    """Newton with step halving on the CIELAB residual for m problems at once; c (m, 3) is the
    starting point and is updated in place. Returns the final residual norms."""
    target = _lab(target_xyz, prob.white)
    xyz, J = prob.xyz_and_jacobian(c)
    r = target - _lab(xyz, prob.white)
    err = np.linalg.norm(r, axis=-1)
    active = np.nonzero(err > tol)[0]
    step_scale = np.ones(c.shape[0])
    for it in range(max_iters):
        if active.size == 0:
            break
        if stats is not None:
            stats.append(active.size)
        Jl = _lab_jacobian(xyz[active], prob.white) @ J[active]
        with np.errstate(all="ignore"):
            det = np.linalg.det(Jl)
            ok = np.isfinite(det) & (np.abs(det) > 1e-300)
            step = np.zeros((active.size, 3))
            if np.any(ok):
                step[ok] = np.linalg.solve(Jl[ok], r[active][ok][..., None])[..., 0]
        step = np.where(np.isfinite(step), step, 0.0)
        cand = c[active] + step_scale[active, None] * step
        xyz_c, J_c = prob.xyz_and_jacobian(cand)
        r_c = target[active] - _lab(xyz_c, prob.white)
        e_c = np.linalg.norm(r_c, axis=-1)
        better = e_c < err[active]
        acc = active[better]
        c[acc], xyz[acc], J[acc], r[acc], err[acc] = cand[better], xyz_c[better], J_c[better], r_c[better], e_c[better]
        # A rejected step is retried at half length from the same point (at most 8 times).
        step_scale[acc] = 1.0
        rej = active[~better]
        step_scale[rej] *= 0.5
        active = np.concatenate([acc[err[acc] > tol], rej[step_scale[rej] > 2.0 ** -8]])
    return err


def _slice_targets(res, z):
    """Linear sRGB targets (3 * res * res, 3) of one z slice: for l = largest channel, rgb[l] = z,
    rgb[(l + 1) % 3] = x z, rgb[(l + 2) % 3] = y z, x and y uniform in [0, 1] (x fastest)."""
    u = np.arange(res) / (res - 1.0)
    y, x = np.meshgrid(u, u, indexing="ij")
    out = np.empty((3, res, res, 3))
    for l in range(3):
        out[l, :, :, l] = z
        out[l, :, :, (l + 1) % 3] = x * z
        out[l, :, :, (l + 2) % 3] = y * z
    return out.reshape(-1, 3)


def _to_nm(c):
    """Coefficients in t = (lambda - 360) / 470 -> coefficients in lambda (nm)."""
    a, b = _LAMBDA0, 1.0 / _LAMBDA_SPAN
    return np.stack([c[..., 0] * b * b, c[..., 1] * b - 2 * c[..., 0] * a * b * b,
                     c[..., 0] * a * a * b * b - c[..., 1] * a * b + c[..., 2]], -1)


def fit_table(res: int = RES, *, progress=None):
    """Fit the sRGB table: coefficients (3, res z, res y, res x, 3) in nm units, and the final
    CIELAB residual of every entry (3, res, res, res). ``progress(done, total)`` per z slice."""
    prob = _problem()
    zs = z_nodes(res)
    coeffs = np.zeros((res, 3 * res * res, 3))
    resid = np.zeros((res, 3 * res * res))
    start = res // 5                                                  # the paper's starting slice
    order = list(range(start, res)) + list(range(start - 1, -1, -1))
    c = np.zeros((3 * res * res, 3))
    for n, zi in enumerate(order):
        if zi == start - 1:
            c = coeffs[start].copy()                                  # continue downwards from the start
        rgb = _slice_targets(res, zs[zi])
        target = np.maximum(rgb @ colorimetry.SRGB_TO_XYZ.T, 1e-12)   # black: Lab of ~0, not -inf
        resid[zi] = _solve_slice(prob, target, c)
        coeffs[zi] = c
        if progress is not None:
            progress(n + 1, res)
    table_ = _to_nm(coeffs).reshape(res, 3, res, res, 3).transpose(1, 0, 2, 3, 4)
    return np.ascontiguousarray(table_), np.ascontiguousarray(resid.reshape(res, 3, res, res).transpose(1, 0, 2, 3))


def _content_key(res):
    w, W = colorimetry.grid_weights(illuminant="D65", normalization="pbrt")
    h = hashlib.sha256()
    for part in (_ALGO_VERSION, repr((res, _TOL, _MAX_ITERS)), w.tobytes(), W.tobytes(),
                 colorimetry.XYZ_TO_SRGB.tobytes()):
        h.update(part if isinstance(part, bytes) else part.encode())
    return h.hexdigest()[:20]


def cache_path(res: int = RES) -> Path:
    """Where the fitted table of resolution ``res`` is cached."""
    base = os.environ.get("BSDFKIT_CACHE_DIR")
    if not base:
        base = os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"),
                            "bsdfkit")
    return Path(base) / f"rgb2spec_srgb_res{res}_{_content_key(res)}.npz"


def _stderr_progress():
    t0 = time.perf_counter()

    def report(done, total):
        if done == 1 or done == total or done % 8 == 0:
            print(f"bsdfkit: fitting the sRGB -> spectrum table (Jakob & Hanika 2019, {total}^3): "
                  f"{done}/{total} slices, {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return report


def _load(path, res):
    try:
        with np.load(path, allow_pickle=False) as f:
            t = f["coeffs"]
    except Exception:   # any damage (zipfile.BadZipFile, a bad CRC, tokenize.TokenError from a mangled
        return None     # .npy header, ...) makes the cache invalid: fitted again, never an error
    if not isinstance(t, np.ndarray) or t.shape != (3, res, res, res, 3) or t.dtype.kind != "f" \
            or not np.all(np.isfinite(t)):
        return None
    return t


@contextlib.contextmanager
def _fit_lock(path):
    """An exclusive lock beside the cache file, so parallel processes (pytest-xdist workers) fit
    the table once; a no-op where fcntl or the directory is unavailable."""
    try:
        import fcntl
        path.parent.mkdir(parents=True, exist_ok=True)
        f = open(path.with_suffix(".lock"), "w")
    except (ImportError, OSError):
        yield
        return
    with f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


@functools.lru_cache(maxsize=None)
def table(res: int = RES):
    """The fitted table (3, res, res, res, 3) float64, read-only: from the cache, else fitted
    now (progress on stderr) and cached. The z nodes are :func:`z_nodes`."""
    path = cache_path(res)
    t = _load(path, res)
    if t is None:
        with _fit_lock(path):
            t = _load(path, res)             # another process may have fitted it meanwhile
            if t is None:
                t, resid = fit_table(res, progress=_stderr_progress())
                try:
                    path.parent.mkdir(parents=True, exist_ok=True)
                    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz.tmp")
                    with os.fdopen(fd, "wb") as f:
                        np.savez(f, coeffs=t, residual=resid)
                    os.replace(tmp, path)
                except OSError as e:         # read-only home: keep the table in memory only
                    print(f"bsdfkit: could not cache the RGB -> spectrum table at {path}: {e}", file=sys.stderr)
    t.setflags(write=False)
    return t


def _lookup(rgb, res=RES):
    """Trilinear table lookup (pbrt-v4 ``RGBToSpectrumTable::operator()``) for rgb (m, 3) in
    [0, 1], not grey. Returns coefficients (m, 3)."""
    tab = table(res)
    zs = z_nodes(res)
    m = rgb.shape[0]
    ar = np.arange(m)
    l = np.argmax(rgb, axis=1)
    z = rgb[ar, l]
    x = rgb[ar, (l + 1) % 3] * (res - 1) / z
    y = rgb[ar, (l + 2) % 3] * (res - 1) / z
    zi = np.clip(np.searchsorted(zs, z, side="right") - 1, 0, res - 2)
    dz = (z - zs[zi]) / (zs[zi + 1] - zs[zi])
    xi = np.minimum(x.astype(np.int64), res - 2)
    yi = np.minimum(y.astype(np.int64), res - 2)
    dx, dy = (x - xi)[:, None], (y - yi)[:, None]
    dz = dz[:, None]

    def co(a, b, c):
        return tab[l, zi + a, yi + b, xi + c]
    return ((1 - dz) * ((1 - dy) * ((1 - dx) * co(0, 0, 0) + dx * co(0, 0, 1))
                        + dy * ((1 - dx) * co(0, 1, 0) + dx * co(0, 1, 1)))
            + dz * ((1 - dy) * ((1 - dx) * co(1, 0, 0) + dx * co(1, 0, 1))
                    + dy * ((1 - dx) * co(1, 1, 0) + dx * co(1, 1, 1))))


def _to_unit(c):
    """Coefficients in lambda (nm) -> coefficients in t = (lambda - 360) / 470 (inverse of _to_nm)."""
    a, L = _LAMBDA0, _LAMBDA_SPAN
    return np.stack([c[..., 0] * L * L, (c[..., 1] + 2 * c[..., 0] * a) * L,
                     (c[..., 0] * a + c[..., 1]) * a + c[..., 2]], -1)


@functools.lru_cache(maxsize=1)
def _problem():
    return _Problem()


def refine(rgb, coeffs, tol: float = 1e-7) -> np.ndarray:
    """Newton-polish table coefficients (m, 3) (nm units) for the exact colours rgb (m, 3) (not
    grey): a few steps of the fit itself, so the round trip is exact to the fit tolerance
    instead of the table's interpolation error (<= 4e-3 near the gamut boundary)."""
    prob = _problem()
    c = _to_unit(np.asarray(coeffs, dtype=np.float64).reshape(-1, 3)).copy()
    target = np.maximum(np.asarray(rgb, dtype=np.float64).reshape(-1, 3) @ colorimetry.SRGB_TO_XYZ.T, 1e-12)
    _solve_slice(prob, target, c, tol=tol)
    return _to_nm(c)


def reflectance_coefficients(rgb, *, exact: bool = False) -> np.ndarray:
    """Sigmoid coefficients (..., 3) (nm units) of linear sRGB reflectances rgb (..., 3) in [0, 1]
    (pbrt-v4 ``RGBAlbedoSpectrum``). Greys (r == g == b) use the closed form; 0 and 1 give
    c2 = -inf / +inf (the spectra 0 and 1). ``exact``: polish the table lookup with
    :func:`refine` (bsdfkit's default for parameter values; pbrt-v4 uses the lookup as is)."""
    a = np.asarray(rgb, dtype=np.float64)
    flat = a.reshape(-1, 3)
    out = np.zeros(flat.shape)
    grey = (flat[:, 0] == flat[:, 1]) & (flat[:, 1] == flat[:, 2])
    g = flat[grey, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        out[grey, 2] = np.where(g <= 0, -np.inf, np.where(g >= 1, np.inf, (g - 0.5) / np.sqrt(g * (1 - g))))
    if np.any(~grey):
        out[~grey] = _lookup(flat[~grey])
        if exact:
            out[~grey] = refine(flat[~grey], out[~grey])
    return out.reshape(a.shape)


def rgb_coefficients(rgb, kind: str = "reflectance", *, exact: bool = False):
    """(coefficients (..., 3), scale (...,)) of the spectrum of rgb: value(lambda) =
    scale * s(poly(lambda)) [* D65(lambda) normalised to unit luminance for "illuminant"].

    * ``"reflectance"`` (pbrt-v4 ``RGBAlbedoSpectrum``): rgb in [0, 1], scale 1.
    * ``"unbounded"`` (``RGBUnboundedSpectrum``): rgb >= 0; m = max(rgb), scale = 2 m, the
      coefficients of rgb / scale (so the sigmoid stays in its middle range).
    * ``"illuminant"`` (``RGBIlluminantSpectrum``): as unbounded, times the illuminant.

    ``exact``: see :func:`reflectance_coefficients`.
    """
    a = np.asarray(rgb, dtype=np.float64)
    if kind == "reflectance":
        return reflectance_coefficients(a, exact=exact), np.ones(a.shape[:-1])
    if kind in ("unbounded", "illuminant"):
        scale = 2.0 * a.max(axis=-1)
        safe = np.where(scale > 0, scale, 1.0)[..., None]
        c = reflectance_coefficients(np.where(scale[..., None] > 0, a / safe, 0.0), exact=exact)
        return c, scale
    raise ValueError(f"kind: expected 'reflectance', 'unbounded' or 'illuminant', got {kind!r}")
