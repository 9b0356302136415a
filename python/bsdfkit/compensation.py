"""Energy-compensation tables: the directional albedo E(mu) of a model, or of a family of models over
a parameter grid, and its hemispherical average E_avg, each with its own error bound
(:func:`albedo_table`, :class:`AlbedoTable`).

These are the tables of Kulla & Conty 2017 ("Revisiting Physically Based Shading at Imageworks") and
Turquin 2019 ("Practical multiple scattering compensation for microfacet models"): E(mu) with
mu = cos theta_o, E_avg = 2 * integral_0^1 E(mu) mu dmu, tabulated over roughness (and eta for
dielectrics). They are computed with the model's own importance sampling (``BxDF.albedo``), so a
table is exactly as right as the model.

Errors. Each entry is the mean of ``replicas`` independent Monte Carlo estimates (independent seeds
of the counter-based generator); their spread gives the standard error ``E_se`` and the bound
``E_err = t * E_se`` (Student t quantile at ``confidence``, two-sided), so ``|E - E_true| <= E_err``
for about ``confidence`` of the entries. ``E_avg`` is an unbiased direct estimate (cosine-weighted
``wo``, no quadrature) with its own bound; ``E_avg_quad`` integrates the table itself (its
piecewise-linear interpolant in mu, clamped at the ends, as an engine's linear filtering reads it)
and ``E_avg_quad_err`` adds the Monte Carlo error propagated through the rule and the difference to
the same rule on every other mu point (the quadrature error). ``tol`` asks for enough samples:
sampling continues per entry until every ``E_err`` and ``E_avg_err`` is at most ``tol`` or
``max_samples`` is reached (then a RuntimeWarning and ``converged=False`` say what was reached).
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
import time
import warnings
from collections.abc import Mapping

import numpy as np

from ._enums import TransportMode
from .models.base import BxDF

__all__ = ["albedo_table", "AlbedoTable"]

#: Format tag and version of a saved table's JSON sidecar.
FORMAT = "bsdfkit-albedo-table"
FORMAT_VERSION = 1
#: Samples per compiled call at most (one call is ~0.1-0.5 s on one core): progress and Ctrl-C
#: are handled between calls.
_CALL_SAMPLES = 1 << 22
#: Samples per direction of the direct E_avg estimate (cosine-weighted wo).
_AVG_PER_DIR = 16
#: The direct E_avg estimate's first round: this many times an entry's samples.
_AVG_BUDGET = 4
_TEXEL_AXES = ("mu", "alpha", "roughness")


def _albedo(model, wo, n_samples, seed, mode):
    """One compiled albedo call (a module-level indirection: tests count the calls)."""
    return model.albedo(wo, n_samples=n_samples, seed=seed, mode=mode)


def _seed(*parts) -> int:
    """A 63-bit seed of the call's identity (independent streams per model, round and chunk)."""
    h = hashlib.blake2b(repr(parts).encode(), digest_size=8).digest()
    return int.from_bytes(h, "little") >> 1


def _check_int(v, name, lo, hi=None):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) or v < lo or (hi is not None and v > hi):
        rng = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
        raise ValueError(f"{name}: must be an integer {rng}, got {v!r}")
    return int(v)


def _axis_values(name, v):
    """The grid values of one axis: an int n on mu / alpha / roughness is n texel centres
    (i + 0.5) / n of (0, 1); anything else is an explicit 1-D array of finite, distinct values."""
    if isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)):
        if name not in _TEXEL_AXES:
            raise ValueError(f"grid: axis {name!r} takes explicit values (a 1-D array); an int (a count of texel "
                             f"centres in (0, 1)) is only for {', '.join(_TEXEL_AXES)}")
        n = _check_int(v, f"grid[{name!r}]", 3 if name == "mu" else 1, 1 << 16)
        return (np.arange(n) + 0.5) / n
    try:
        a = np.asarray(v, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"grid: axis {name!r} must be an int or a 1-D array of numbers, got {v!r}") from None
    if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError(f"grid: axis {name!r} must be a non-empty 1-D array of finite numbers, got shape {a.shape}")
    if np.unique(a).size != a.size:
        raise ValueError(f"grid: axis {name!r} repeats a value")
    if name == "mu":
        if a.size < 3 or np.any(np.diff(a) <= 0) or a[0] <= 0 or a[-1] > 1:
            raise ValueError("grid: axis 'mu' (cos theta_o) must hold at least 3 increasing values in (0, 1], "
                             f"got {a.tolist() if a.size <= 8 else a.shape}")
    return a


def _family(model, grid, params):
    """(axis names, {name: values}, the models over the non-mu axes in C order, their shape)."""
    if grid is None:
        grid = {"mu": 32}
    if not isinstance(grid, Mapping):
        raise ValueError(f"grid: expected a dict of axis name -> int or values, e.g. {{'mu': 32, 'alpha': 16}}, "
                         f"got {type(grid).__name__}")
    if "mu" not in grid:
        raise ValueError(f"grid: needs the 'mu' axis (cos theta_o), got axes {list(grid)}")
    names = [str(k) for k in grid]
    values = {k: _axis_values(k, grid[k]) for k in names}
    others = [k for k in names if k != "mu"]
    if isinstance(model, BxDF):
        if others:
            raise ValueError(f"grid: a fixed model takes only the 'mu' axis, got {others}; pass a callable "
                             f"(e.g. lambda alpha: ...) or a model class to vary a parameter")
        if params:
            raise ValueError("params: only with a model class (fixed keyword arguments of the family)")
        model._refuse_varying("albedo_table")
        return names, values, [model], ()
    if isinstance(model, type):
        if not issubclass(model, BxDF):
            raise TypeError(f"model: expected a bsdfkit model, a model class or a callable returning one, "
                            f"got the class {model.__name__}")
        cls, fixed = model, dict(params or {})
        both = sorted(set(fixed) & set(others))
        if both:
            raise ValueError(f"params: {both} are grid axes too")

        def build(**kw):
            return cls(**fixed, **kw)
    elif callable(model):
        if params:
            raise ValueError("params: only with a model class (a callable carries its own fixed arguments)")
        build = model
    else:
        raise TypeError(f"model: expected a bsdfkit model, a model class or a callable returning one, "
                        f"got {type(model).__name__}")
    shape = tuple(values[k].size for k in others)
    models = []
    for idx in np.ndindex(*shape):
        kw = {k: float(values[k][i]) for k, i in zip(others, idx)}
        try:
            m = build(**kw)
        except (TypeError, ValueError) as e:
            raise type(e)(f"grid: building the model at {kw} failed: {e}") from e
        if not isinstance(m, BxDF):
            raise TypeError(f"model: the callable returned {type(m).__name__} at {kw}, not a bsdfkit model")
        m._refuse_varying("albedo_table")
        models.append(m)
    return names, values, models, shape


class _Pool:
    """Pooled Monte Carlo statistics of entries from rounds of ``K`` replicas: totals of samples,
    of sample values and of the per-sample variance (weighted by its degrees of freedom)."""

    def __init__(self, shape):
        self.n = np.zeros(shape)
        self.s = np.zeros(shape + (3,))
        self.q = np.zeros(shape + (3,))
        self.dof = np.zeros(shape)

    def add(self, sel, reps, per_rep):
        """``reps`` (K, m, 3): K replica means of ``per_rep`` samples each, for entries ``sel``."""
        k = reps.shape[0]
        self.n[sel] += k * per_rep
        self.s[sel] += per_rep * reps.sum(0)
        self.q[sel] += (k - 1) * per_rep * reps.var(0, ddof=1)
        self.dof[sel] += k - 1

    def mean(self):
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.s / self.n[..., None]

    def se(self):
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.sqrt(self.q / self.dof[..., None] / self.n[..., None])


def _t(confidence, dof):
    from scipy.stats import t
    return t.ppf(0.5 + 0.5 * confidence, np.maximum(dof, 1))


def _quad_weights(mu):
    """Weights w with sum w_i E_i = 2 * integral_0^1 E(mu) mu dmu of E's piecewise-linear
    interpolant through (mu_i, E_i), constant below mu_0 and above mu_last (clamp to edge)."""
    w = np.zeros(mu.size)
    a, b = mu[:-1], mu[1:]
    np.add.at(w, np.arange(mu.size - 1), (b - a) * (b + 2 * a) / 3)     # integral of 2 mu (b - mu) / (b - a)
    np.add.at(w, np.arange(1, mu.size), (b - a) * (2 * b + a) / 3)      # integral of 2 mu (mu - a) / (b - a)
    w[0] += mu[0] ** 2
    w[-1] += 1 - mu[-1] ** 2
    return w


def _code_digest() -> str:
    from ._version import __version__
    from .models.filament.dfg import _builder_digest
    return f"{__version__}+{_builder_digest()}"


class AlbedoTable:
    """A directional-albedo table E over ``axes`` with its errors (:func:`albedo_table`).

    Attributes
    ----------
    E : numpy.ndarray
        Directional albedo, float64, axes in ``axes`` order (the grid's keys, then ``"channel"``
        when the table keeps RGB): ``E[..., i, ...]`` at ``wo = (sqrt(1 - mu_i^2), 0, mu_i)``.
    E_se, E_err : numpy.ndarray
        Its Monte Carlo standard error and bound (``confidence``, Student t), same shape.
    n_samples : numpy.ndarray of int
        Samples per entry (E's shape without the channel axis).
    E_avg, E_avg_se, E_avg_err : numpy.ndarray
        The direct (cosine-weighted, unbiased) estimate of 2 * integral E(mu) mu dmu, its standard
        error and bound: E's shape without the mu axis.
    E_avg_quad, E_avg_quad_err : numpy.ndarray
        The same integral of the table's own linear interpolant (what an engine integrating its
        table gets) and its bound: Monte Carlo (propagated) plus quadrature error (the rule against
        the rule on every other mu point).
    axes : tuple of str
        Axis names of ``E``.
    grid : dict of str to numpy.ndarray
        The values along each axis (``mu`` = cos theta_o).
    confidence, tol : float
        The bounds' confidence; the requested tolerance (None: none asked).
    converged : bool
        Whether every ``E_err`` and ``E_avg_err`` is at most ``tol`` (True without ``tol``).
    info : dict
        Models (repr), mode, seed, channel, replicas, bsdfkit version, cache key, seconds.
    """

    _ARRAYS = ("E", "E_se", "E_err", "n_samples", "E_avg", "E_avg_se", "E_avg_err", "E_avg_quad", "E_avg_quad_err")

    def __init__(self, arrays, axes, grid, confidence, tol, converged, info):
        for k in self._ARRAYS:
            setattr(self, k, arrays[k])
        self.axes, self.grid = tuple(axes), {k: np.asarray(v, np.float64) for k, v in grid.items()}
        self.confidence, self.tol, self.converged, self.info = confidence, tol, bool(converged), dict(info)

    def __repr__(self):
        shape = "x".join(str(s) for s in self.E.shape)
        return (f"<AlbedoTable {shape} axes={self.axes} max E_err={np.nanmax(self.E_err):.2g} "
                f"({self.confidence:.0%}) converged={self.converged}>")

    def report(self) -> str:
        """A few lines: shape, samples, the largest errors and where, E_avg's errors."""
        e = np.nan_to_num(self.E_err, nan=np.inf)
        i = np.unravel_index(int(np.argmax(e)), e.shape)
        where = ", ".join(f"{a}={self.grid[a][j]:.4g}" for a, j in zip(self.axes, i) if a in self.grid)
        lines = [f"albedo table {self.E.shape} over {self.axes}, {int(np.min(self.n_samples))}.."
                 f"{int(np.max(self.n_samples))} samples per entry",
                 f"E: largest error bound {float(np.max(e)):.3g} ({self.confidence:.0%}) at {where}",
                 f"E_avg: direct error bound <= {float(np.nanmax(self.E_avg_err)):.3g}; table quadrature "
                 f"error bound <= {float(np.nanmax(self.E_avg_quad_err)):.3g}"]
        if self.tol is not None:
            lines.append(f"tol {self.tol:g}: {'reached' if self.converged else 'NOT reached'}")
        return "\n".join(lines)

    # ---- export: <stem>.npy (E), <stem>.npz (everything), <stem>.json (layout)
    def layout(self) -> dict:
        """The JSON sidecar: what an engine needs to read ``<stem>.npy``."""
        mu_axis = self.axes.index("mu")
        return {
            "format": FORMAT, "format_version": FORMAT_VERSION,
            "axes": list(self.axes), "shape": list(self.E.shape),
            "grid": {k: v.tolist() for k, v in self.grid.items()},
            "entry": ("E = directional albedo, integral of f(wo, wi) |cos theta_i| dwi, at "
                      "wo = (sqrt(1 - mu^2), 0, mu) (local frame, z the normal); mu = cos theta_o; "
                      "other axes are the model's parameters"),
            "npy": "<stem>.npy: E, C order, axes as listed; <stem>_avg.npy: E_avg, axes as E_avg_axes",
            "E_avg": "2 * integral_0^1 E(mu) mu dmu: axes as E without 'mu' (direct Monte Carlo estimate)",
            "E_avg_axes": [a for i, a in enumerate(self.axes) if i != mu_axis],
            "E_avg_values": self.E_avg.tolist(), "E_avg_err": self.E_avg_err.tolist(),
            "max_E_err": float(np.nanmax(self.E_err)), "confidence": self.confidence,
            "tol": self.tol, "converged": self.converged, **self.info,
        }

    def save(self, path, dtype=np.float32) -> tuple:
        """Writes ``<stem>.npy`` (E in ``dtype``, default float32, for engines), ``<stem>_avg.npy``
        (E_avg likewise), ``<stem>.npz`` (every array in float64 and the grids as ``grid_<name>``)
        and ``<stem>.json`` (:meth:`layout`). ``path``: the stem, with or without ``.npy``.
        Returns the four paths."""
        stem = os.fspath(path)
        if stem.endswith(".npy"):
            stem = stem[:-4]
        paths = (stem + ".npy", stem + "_avg.npy", stem + ".npz", stem + ".json")
        np.save(paths[0], self.E.astype(dtype))
        np.save(paths[1], self.E_avg.astype(dtype))
        np.savez(paths[2], **{k: getattr(self, k) for k in self._ARRAYS},
                 **{f"grid_{k}": v for k, v in self.grid.items()})
        with open(paths[3], "w") as fh:
            json.dump(self.layout(), fh, indent=1)
        return paths

    @classmethod
    def load(cls, path) -> "AlbedoTable":
        """A table written by :meth:`save` (``path``: the stem, or any of its files)."""
        stem = os.fspath(path)
        for ext in ("_avg.npy", ".npy", ".npz", ".json"):
            if stem.endswith(ext):
                stem = stem[:-len(ext)]
        with open(stem + ".json") as fh:
            meta = json.load(fh)
        if meta.get("format") != FORMAT:
            raise ValueError(f"path: {stem}.json is not a bsdfkit albedo table")
        with np.load(stem + ".npz", allow_pickle=False) as z:
            arrays = {k: z[k] for k in cls._ARRAYS}
            grid = {k: z[f"grid_{k}"] for k in meta["grid"]}
        info = {k: meta[k] for k in ("models", "mode", "seed", "channel", "replicas", "bsdfkit", "key", "seconds")
                if k in meta}
        return cls(arrays, meta["axes"], grid, meta["confidence"], meta["tol"], meta["converged"], info)


def _cache_dir(cache):
    if cache is None or cache is False:
        return None
    if cache is True:
        from .models.filament.dfg import cache_dir
        return os.path.join(cache_dir(), "albedo-tables")
    try:
        return os.fspath(cache)
    except TypeError:
        raise TypeError(f"cache: expected True, False or a directory path, got {cache!r}") from None


def albedo_table(model, grid=None, *, params=None, n_samples: int = 1 << 16, tol=None, max_samples: int = 1 << 22,
                 seed: int = 0, mode=TransportMode.Radiance, channel="rgb", replicas: int = 32,
                 confidence: float = 0.95, cache=True, progress=None, interrupt: str = "raise") -> AlbedoTable:
    """Directional albedo E(mu) and its average E_avg over a parameter grid, with error bounds.

    Parameters
    ----------
    model : BxDF, model class or callable
        A model (the table is E(mu)); a model class, built as ``model(**params, **axis_values)`` at
        every grid point; or a callable of the non-``mu`` axes' values as keywords returning a model,
        e.g. ``lambda alpha: bk.Conductor(1.0, 1e4, alpha=alpha, fresnel="schlick")`` (a white
        metal). Models with per-element or textured parameters are refused.
    grid : dict, optional
        Axis name -> an int or 1-D values, in the output's axis order. ``"mu"`` (cos theta_o) is
        required: an int n is the n texel centres ``(i + 0.5) / n`` (default ``{"mu": 32}``), values
        must be increasing in (0, 1]. Other axes are the model's keyword arguments (``alpha``,
        ``eta``, ...); an int n on ``alpha`` / ``roughness`` is also n texel centres of (0, 1), any
        other axis takes explicit values.
    params : dict, optional
        With a model class: its fixed keyword arguments.
    n_samples : int, optional
        Importance samples per entry in the first round (default 65536), split into ``replicas``;
        the direct ``E_avg`` estimate takes four times as many per model.
    tol : float, optional
        Target of every error bound ``E_err`` and ``E_avg_err``: entries above it get more samples
        (estimated from their variance) up to ``max_samples`` each; if not reached, a RuntimeWarning
        says what was and ``converged`` is False.
    max_samples : int, optional
        Samples per entry at most with ``tol`` (default 2**22).
    seed : int, optional
        Seed of the generator (the table is deterministic for a given seed, at any thread count).
    mode : TransportMode or str, optional
        ``Radiance`` (default) or ``Importance``: a dielectric's transmission carries 1/eta^2 in
        radiance mode, so its white furnace (R + T = 1) holds in importance mode.
    channel : {"rgb", "mean", 0, 1, 2}, optional
        Keep the RGB channels (a last axis ``"channel"`` of 3), their mean, or one channel.
    replicas : int, optional
        Independent estimates per entry and round whose spread gives the standard error (default 32).
    confidence : float, optional
        Confidence of the error bounds (default 0.95).
    cache : bool or path, optional
        True (default): look the table up in, and store it to, ``<bsdfkit cache dir>/albedo-tables``
        (``$BSDFKIT_CACHE_DIR``, else ``$XDG_CACHE_HOME/bsdfkit`` or ``~/.cache/bsdfkit``), keyed by
        the content: every model's repr (parameters, table digests), the grid, the sampling options
        and the bsdfkit version and compiled-code digest. A path: that directory. False: no cache.
    progress : bool or callable, optional
        None (a line on stderr when it is a terminal, a bar in Jupyter), True, False, or a callable
        ``progress(done, total, stage)``.
    interrupt : {"raise", "return"}, optional
        On Ctrl-C: re-raise KeyboardInterrupt (with the partial table as its ``table`` attribute),
        or return the partial table (NaN where not computed, ``converged=False``) with a warning.

    Returns
    -------
    AlbedoTable
        ``E``, ``E_err``, ``E_avg``, ``E_avg_err``, ... (see :class:`AlbedoTable`); ``save(stem)``
        writes ``.npy`` + ``.npz`` + ``.json`` for engines.

    Raises
    ------
    ValueError
        A bad grid (no ``mu``, values out of range, an axis the fixed model cannot vary), a
        negative or zero ``tol``, a bad count or option, each naming the parameter.
    TypeError
        A ``model`` that is neither a model, a model class nor a callable returning a model.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> white = lambda alpha: bk.Conductor(1.0, 1e4, alpha=alpha, fresnel="schlick")   # F = 1
    >>> t = bk.albedo_table(white, grid={"alpha": 4, "mu": 8}, n_samples=4096, channel="mean", cache=False)
    >>> t.E.shape, t.E_avg.shape, t.axes            # E[alpha, mu]: mu is the fast (texture x) axis
    ((4, 8), (4,), ('alpha', 'mu'))
    >>> bool(t.E_avg[0] > t.E_avg[-1] > 0.4)         # rougher: more energy left to multiple scattering
    True
    """
    n_samples = _check_int(n_samples, "n_samples", 2)
    max_samples = _check_int(max_samples, "max_samples", 2)
    replicas = _check_int(replicas, "replicas", 2, 4096)
    seed = _check_int(seed, "seed", 0)
    if tol is not None:
        if isinstance(tol, (bool, np.bool_)) or not isinstance(tol, (int, float, np.floating, np.integer)) \
                or not math.isfinite(tol) or tol <= 0:
            raise ValueError(f"tol: must be a finite number > 0, got {tol!r}")
        tol = float(tol)
    if isinstance(confidence, (bool, np.bool_)) or not isinstance(confidence, (int, float, np.floating)) \
            or not 0 < confidence < 1:
        raise ValueError(f"confidence: must be in (0, 1), got {confidence!r}")
    if channel not in ("rgb", "mean", 0, 1, 2) or isinstance(channel, bool):
        raise ValueError(f"channel: must be 'rgb', 'mean', 0, 1 or 2, got {channel!r}")
    if interrupt not in ("raise", "return"):
        raise ValueError(f"interrupt: must be 'raise' or 'return', got {interrupt!r}")
    from ._progress import Progress, check_progress
    progress = check_progress(progress)
    mode_name = str(getattr(mode, "name", mode)).lower()
    if mode_name not in ("radiance", "importance"):
        raise ValueError(f"mode: must be 'radiance' or 'importance', got {mode!r}")
    mode = TransportMode.Radiance if mode_name == "radiance" else TransportMode.Importance
    names, values, models, shape = _family(model, grid, params)
    mu = values["mu"]
    key_src = {"models": [repr(m) for m in models], "grid": {k: values[k].tolist() for k in names},
               "n_samples": n_samples, "tol": tol, "max_samples": max_samples, "seed": seed, "mode": mode_name,
               "channel": channel, "replicas": replicas, "confidence": float(confidence), "code": _code_digest()}
    key = hashlib.sha256(json.dumps(key_src, sort_keys=True).encode()).hexdigest()[:32]
    cdir = _cache_dir(cache)
    if cdir is not None:
        try:
            table = AlbedoTable.load(os.path.join(cdir, f"albedo-table-{key}"))
        except Exception:   # missing or damaged: computed again
            table = None
        if table is not None:
            if not table.converged:
                warnings.warn(f"albedo_table (cached): tol={tol:g} not reached within max_samples={max_samples}:\n"
                              f"{table.report()}", RuntimeWarning, stacklevel=2)
            return table

    t0 = time.perf_counter()
    wo = np.stack([np.sqrt(np.maximum(0.0, 1 - mu * mu)), np.zeros_like(mu), mu], -1)
    nm, nmu, k = len(models), mu.size, replicas
    per_rep0 = max(1, -(-n_samples // k))
    pool, pavg = _Pool((nm, nmu)), _Pool((nm,))
    prog = Progress(progress, nm * (nmu + _AVG_BUDGET) * per_rep0 * k, "samples", "albedo_table")
    done = [0]
    models_done = 0

    def run(i, sel, per_rep, rnd):
        """Rounds of k replicas x per_rep samples for mu entries ``sel`` of model i (chunked calls)."""
        idx = np.flatnonzero(sel)
        chunk = max(1, _CALL_SAMPLES // max(1, idx.size * k))
        left, c = per_rep, 0
        while left > 0:
            s = min(chunk, left)
            w = np.ascontiguousarray(np.broadcast_to(wo[idx], (k, idx.size, 3)).reshape(-1, 3))
            reps = _albedo(models[i], w, s, _seed(seed, i, rnd, c, "E"), mode).reshape(k, idx.size, 3)
            pool.add((i, idx), reps, s)
            left, c = left - s, c + 1
            done[0] += s * k * idx.size
            prog(min(done[0], prog.total))

    def run_avg(i, per_rep, rnd):
        """Direct E_avg: k replicas of per_rep // 16 cosine-weighted directions x 16 samples, each
        replica's directions stratified in mu^2 (jittered: unbiased, and the replicas independent)."""
        dirs = max(1, per_rep // _AVG_PER_DIR)
        rng = np.random.default_rng(_seed(seed, i, rnd, "avg"))
        m = np.sqrt((np.arange(dirs) + rng.random((k, dirs))) / dirs)   # density 2 mu: cosine-weighted wo
        w = np.stack([np.sqrt(np.maximum(0.0, 1 - m * m)), np.zeros_like(m), m], -1).reshape(-1, 3)
        a = _albedo(models[i], w, _AVG_PER_DIR, _seed(seed, i, rnd, "avg"), mode).reshape(k, dirs, 3)
        pavg.add(i, a.mean(1), dirs * _AVG_PER_DIR)
        done[0] += dirs * _AVG_PER_DIR * k
        prog(min(done[0], prog.total))

    def bounds():
        e, se = pool.mean(), pool.se()
        ea, sea = pavg.mean(), pavg.se()
        return e, se, _t(confidence, pool.dof)[..., None] * se, ea, sea, _t(confidence, pavg.dof)[..., None] * sea

    interrupted = None
    try:
        for i in range(nm):
            run(i, np.ones(nmu, bool), per_rep0, 0)
            run_avg(i, _AVG_BUDGET * per_rep0, 0)
            rnd = 1
            while tol is not None:
                e, se, err, ea, sea, erra = (x[i] for x in bounds())
                need = (err.max(-1) > tol) & (pool.n[i] < max_samples)
                need_avg = erra.max() > tol and pavg.n[i] < max_samples
                if not need.any() and not need_avg:
                    break
                # samples to reach tol (error ~ 1/sqrt(n)), 10 % margin, at least double, within max
                if need.any():
                    target = np.max(pool.n[i][need] * (err.max(-1)[need] / tol) ** 2 * 1.1)
                    extra = min(max(target, 2 * pool.n[i][need].max()), max_samples) - pool.n[i][need].max()
                    if extra >= k:
                        prog.total += int(extra) * int(need.sum())
                        run(i, need, int(extra // k), rnd)
                if need_avg:
                    target = pavg.n[i] * (erra.max() / tol) ** 2 * 1.1
                    extra = min(max(target, 2 * pavg.n[i]), max_samples) - pavg.n[i]
                    if extra >= k * _AVG_PER_DIR:
                        prog.total += int(extra)
                        run_avg(i, int(extra // k), rnd)
                rnd += 1
                if rnd > 64:
                    break
            models_done += 1
    except KeyboardInterrupt as e:
        interrupted = e
    finally:
        prog.close()

    e, se, err, ea, sea, erra = bounds()
    if interrupted is not None:
        e[models_done:] = se[models_done:] = err[models_done:] = np.nan
        ea[models_done:] = sea[models_done:] = erra[models_done:] = np.nan
    # the table's own quadrature: linear rule on all mu points, and on every other one (plus the last)
    w_full = _quad_weights(mu)
    half = np.unique(np.r_[np.arange(0, nmu, 2), nmu - 1])
    w_half = np.zeros(nmu)
    w_half[half] = _quad_weights(mu[half])
    eq = np.einsum("j,ijc->ic", w_full, e)
    eq_mc = _t(confidence, pool.dof.min(1))[:, None] * np.sqrt(np.einsum("j,ijc->ic", w_full ** 2, se ** 2))
    eq_err = eq_mc + np.abs(eq - np.einsum("j,ijc->ic", w_half, e))

    def chan(a):
        if channel == "rgb":
            return a
        return a.mean(-1) if channel == "mean" else a[..., channel]

    def chan_err(a):   # the mean's error: at most the channels' largest
        return a if channel == "rgb" else (a.max(-1) if channel == "mean" else a[..., channel])

    mu_pos = names.index("mu")
    ch = ("channel",) if channel == "rgb" else ()

    def table_axes(a, has_mu=True):   # (models, [mu], [c]) -> grid order
        a = a.reshape(shape + a.shape[1:])
        if has_mu:
            a = np.moveaxis(a, len(shape), mu_pos)
        return np.ascontiguousarray(a)

    arrays = {
        "E": table_axes(chan(e)), "E_se": table_axes(chan_err(se)), "E_err": table_axes(chan_err(err)),
        "n_samples": table_axes(pool.n.astype(np.int64)),
        "E_avg": table_axes(chan(ea), False), "E_avg_se": table_axes(chan_err(sea), False),
        "E_avg_err": table_axes(chan_err(erra), False), "E_avg_quad": table_axes(chan(eq), False),
        "E_avg_quad_err": table_axes(chan_err(eq_err), False),
    }
    converged = interrupted is None and (tol is None or (np.nanmax(err) <= tol and np.nanmax(erra) <= tol))
    info = {"models": key_src["models"], "mode": mode_name, "seed": seed, "channel": channel, "replicas": replicas,
            "bsdfkit": key_src["code"], "key": key, "seconds": round(time.perf_counter() - t0, 3)}
    table = AlbedoTable(arrays, names + list(ch), values, float(confidence), tol, converged, info)
    if interrupted is not None:
        if interrupt == "raise":
            interrupted.table = table
            raise interrupted
        warnings.warn(f"albedo_table interrupted: returning {models_done} of {nm} models (NaN elsewhere)",
                      RuntimeWarning, stacklevel=2)
        return table
    if tol is not None and not converged:
        warnings.warn(f"albedo_table: tol={tol:g} not reached within max_samples={max_samples}:\n{table.report()}",
                      RuntimeWarning, stacklevel=2)
    if cdir is not None:
        _store(table, cdir, key)
    return table


def _store(table, cdir, key):
    """Writes the table to the cache atomically (a temporary directory, then renames); an unwritable
    cache only means the next call computes it again."""
    try:
        os.makedirs(cdir, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=cdir) as tmp:
            paths = table.save(os.path.join(tmp, "t"), dtype=np.float64)
            for p in paths:                                       # the JSON last: load reads it first
                os.replace(p, os.path.join(cdir, f"albedo-table-{key}" + os.path.basename(p)[1:]))
    except OSError:
        pass
