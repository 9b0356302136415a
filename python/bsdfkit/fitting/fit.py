"""``bk.fit``: least-squares fit of a model family to a target, with the analytic Jacobian of
``eval_grad``."""
from __future__ import annotations

import html
import math
import time
from dataclasses import dataclass, field

import numpy as np

from .grad import _columns, differentiable_params

__all__ = ["FitReport", "fit"]

_LOSSES = ("log", "relative", "l2")
#: Residual floor of the "log" and "relative" losses and of the report's relative errors:
#: FLOOR_FRACTION * mean(target f |cos|) (as bsdfkit.tuning's errors).
FLOOR_FRACTION = 1e-3


@dataclass(frozen=True, eq=False)
class FitReport:
    """What ``bk.fit`` reached.

    Attributes
    ----------
    model : BxDF
        The fitted model.
    params : dict
        Fitted value per gradient column.
    init : dict
        The starting values of the best start.
    loss : str
        The loss name.
    cost : float
        Half the sum of squared residuals.
    rel_p50, rel_p90, rel_p99, rel_max : numpy.ndarray, shape (3,)
        Per-channel percentiles (and maximum) of |f - f_target| |cos| / max(f_target |cos|,
        floor) over the fitted pairs.
    albedo_error : float or None
        Max over the albedo directions and channels of |albedo - albedo_target| (Monte Carlo;
        ``None`` for raw-sample targets).
    nfev, njev : int
        Residual and Jacobian evaluations (all starts).
    time : float
        Seconds.
    starts : int
        Number of starting points.
    success, message : bool, str
        scipy's for the best start -- whether the optimizer converged, not whether the fit is
        good (a converged fit of the wrong family can have a p99 error of 0.8): judge the fit
        by rel_p99 / rel_max / albedo_error.
    n_pairs : int
        Direction pairs fitted.
    start_costs : tuple
        The final cost of every start.
    """

    model: object
    params: dict
    init: dict
    loss: str
    cost: float
    rel_p50: np.ndarray
    rel_p90: np.ndarray
    rel_p99: np.ndarray
    rel_max: np.ndarray
    albedo_error: float | None
    nfev: int
    njev: int
    time: float
    starts: int
    success: bool
    message: str
    n_pairs: int
    start_costs: tuple = field(default=())

    def _rows(self):
        rows = [("model", repr(self.model))]
        rows += [(f"  {k}", f"{v:.9g}  (start {self.init[k]:.6g})") for k, v in self.params.items()]
        rows += [("loss", f"{self.loss}, cost {self.cost:.4g} over {self.n_pairs} pairs x 3 channels"),
                 ("rel. error p50", _rgb_txt(self.rel_p50)), ("rel. error p90", _rgb_txt(self.rel_p90)),
                 ("rel. error p99", _rgb_txt(self.rel_p99)),
                 ("albedo error", "n/a (raw samples)" if self.albedo_error is None else f"{self.albedo_error:.3g}"),
                 ("evaluations", f"{self.nfev} residuals, {self.njev} Jacobians, {self.starts} start(s)"),
                 ("time", f"{self.time:.3g} s"),
                 ("optimizer", ("converged: " if self.success else "FAILED: ") + self.message
                  + " (convergence only; how well the family fits is the errors above)")]
        return rows

    def __repr__(self):
        w = max(len(k) for k, _ in self._rows())
        return "FitReport\n" + "\n".join(f"  {k:<{w}}  {v}" for k, v in self._rows())

    def _repr_html_(self):
        body = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th><td style='text-align:left'>"
                       f"<code>{html.escape(v)}</code></td></tr>" for k, v in self._rows())
        return f"<table><caption>bsdfkit fit</caption>{body}</table>"


def _rgb_txt(v):
    return ", ".join(f"{x:.3g}" for x in np.asarray(v))


def _target_samples(target, directions, n, seed):
    """(wo, wi, y = f |cos wi| (N, 3), target model or None)."""
    from ..models.base import BxDF
    if isinstance(target, BxDF):
        if directions is None:
            from ..tuning.errors import direction_set
            ds = direction_set(target, n=n, seed=seed, n_albedo=16)
            wo, wi = ds.wo, ds.wi
        else:
            if not isinstance(directions, (tuple, list)) or len(directions) != 2:
                raise TypeError("directions: expected None or a pair (wo, wi) of direction arrays")
            wo, wi = np.broadcast_arrays(np.asarray(directions[0], np.float64), np.asarray(directions[1], np.float64))
            wo, wi = wo.reshape(-1, 3), wi.reshape(-1, 3)
        f = target.eval(wo, wi).astype(np.float64)
        return wo, wi, f * np.abs(wi[:, 2:3]), target
    if isinstance(target, (tuple, list)) and len(target) == 3:
        if directions is not None:
            raise ValueError("directions: not used with raw samples (wo, wi, value); pass them in the target")
        wo, wi, v = (np.asarray(a, dtype=np.float64) for a in target)
        try:
            wo, wi = np.broadcast_arrays(wo, wi)
            v = np.broadcast_to(v, wo.shape)
        except ValueError:
            raise ValueError("target: wo, wi and value must broadcast to (N, 3)") from None
        wo, wi, v = wo.reshape(-1, 3), wi.reshape(-1, 3), v.reshape(-1, 3)
        if not (np.all(np.isfinite(v)) and np.all(v >= 0)):
            raise ValueError("target: values must be finite and >= 0")
        if len(wo) == 0:
            raise ValueError("target: no samples")
        return wo, wi, v * np.abs(wi[:, 2:3]), None
    raise TypeError("target: expected a bsdfkit model or raw samples (wo, wi, value)")


def _check_family(family, init):
    """TypeError unless ``family`` is a model class and ``init`` is None, a dict or a model of it;
    returns the parameters of such a model, else ``init`` itself."""
    from ..models.base import BxDF
    if not (isinstance(family, type) and issubclass(family, BxDF)):
        raise TypeError(f"family: expected a model class (e.g. bk.Conductor), got {family!r}")
    if isinstance(init, family):
        return dict(init._params)
    if isinstance(init, BxDF):
        raise TypeError(f"init: expected a {family.__name__} or a dict, got a {type(init).__name__}")
    return init


def _start_model(family, init, fixed):
    """The family's model at the starting point: its first registered example, then ``fixed``
    and ``init`` (a dict of parameter values, or a model of the family)."""
    from ..models.spec import example_model
    p = _check_family(family, init)
    if p is None or p is init:
        p = dict(example_model(family)._params)
    for name, d in (("fixed", fixed), ("init", init if isinstance(init, dict) else None)):
        if d is None:
            continue
        if not isinstance(d, dict):
            raise TypeError(f"{name}: expected a dict of parameter values")
        for k, v in d.items():
            if k.endswith("alpha") and k + "_x" in p and k + "_y" in p:
                p[k + "_x"] = p[k + "_y"] = v
            elif k not in p:
                raise ValueError(f"{name}: {family.__name__} has no parameter {k!r} ({', '.join(p)})")
            else:
                p[k] = v
    # a family with a differentiable method (the coated models' "analytic") fits with it unless told
    given = set(fixed or ()) | set(init if isinstance(init, dict) else ())
    if p.get("method") == "stochastic" and "method" not in given and not isinstance(init, family):
        p["method"] = "analytic"
    try:
        return family._from_params(p)
    except (TypeError, ValueError) as e:
        raise type(e)(f"init/fixed: {e}") from None


def _get(model, col):
    field_, ch = col[0]
    v = model._params[field_]
    return float(v if ch == -1 else np.asarray(v)[ch])


def _set(family, params, cols, x):
    p = dict(params)
    for col, v in zip(cols, x):
        for field_, ch in col:
            if ch == -1:
                p[field_] = float(v)
            else:
                a = np.array(p[field_], dtype=np.float64)
                a[ch] = v
                p[field_] = a
    return family._from_params(p)


def _bounds(family, names):
    ranges = getattr(family, "param_ranges", {})
    lo, hi = [], []
    for nm in names:
        base = nm + "_x" if nm.endswith("alpha") and nm + "_x" in ranges else nm.partition(".")[0]
        if base not in ranges:
            raise ValueError(f"params: {family.__name__} declares no fitting range for {nm!r}")
        a, b = ranges[base]
        lo.append(a)
        hi.append(b)
    return np.array(lo, float), np.array(hi, float)


def _one_blas_thread():
    """BLAS limited to one thread for the optimizer's small dense algebra (an SVD of a (3N, P)
    Jacobian, P <= 16): a threaded BLAS spinning on a busy machine made fits 4-7x slower
    (bench/FIT.md); results do not depend on it. Needs threadpoolctl (installed with the test
    and dask extras); without it, BLAS keeps its own setting."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        import contextlib
        return contextlib.nullcontext()
    return threadpool_limits(limits=1, user_api="blas")


def _residuals(loss, y_t, floor, w):
    """(r(y_m), dr/dy_m(y_m)) for the loss, elementwise on (N, 3)."""
    if loss == "l2":
        s = w / np.mean(y_t)
        return (lambda y: (y - y_t) * s), (lambda y: s)
    if loss == "relative":
        s = w / np.maximum(y_t, floor)
        return (lambda y: (y - y_t) * s), (lambda y: s)
    lt = np.log(y_t + floor)
    return (lambda y: w * (np.log(y + floor) - lt)), (lambda y: w / (y + floor))


def _start_params(m0, cols) -> dict:
    """The starting model's parameters for a fit of ``cols``: a parameter left to a default derived
    from others (None, e.g. FilamentCloth's sheen_color = sqrt(base_color)) takes its starting
    value, since eval_grad differentiates each field on its own; a fitted one still None raises."""
    base = dict(m0._params)
    for k, v in list(base.items()):
        if v is None and hasattr(m0, "effective_" + k):
            base[k] = np.asarray(getattr(m0, "effective_" + k), dtype=np.float64)
    for col in cols:
        for field, _ in col:
            if base[field] is None:
                raise ValueError(f"params: {field} is None in the starting model; give it in init")
    return base


def _family_setup(family, params, init, fixed, loss, starts):
    """Everything of ``fit``'s arguments that does not depend on the target, checked (ValueError
    naming the argument): (starting model, params, column names, columns, lower, upper bounds).
    ``fit_many`` calls it before it starts a cluster."""
    if loss not in _LOSSES:
        raise ValueError(f"loss: must be one of {_LOSSES}, got {loss!r}")
    if isinstance(starts, bool) or not isinstance(starts, int) or starts < 1:
        raise ValueError(f"starts: must be an integer >= 1, got {starts!r}")
    m0 = _start_model(family, init, fixed)
    if params is None:
        fixed_names = set(fixed or ())
        iso = [p for p in differentiable_params(m0) if p.endswith("alpha") and p + "_x" in m0._params]
        params = [p for p in differentiable_params(m0) if p not in fixed_names and p not in iso
                  and (m0._params.get(p, 0) is not None or hasattr(m0, "effective_" + p))
                  and not any(p in (a + "_x", a + "_y") and a in fixed_names for a in iso)]
    names, cols = _columns(m0, params)
    lo, hi = _bounds(family, names)
    return m0, params, names, cols, lo, hi


def fit(target, family, params=None, init=None, fixed=None, directions=None, loss="log", weights=None, *,
        starts=1, n=4096, seed=0, max_nfev=200, tol=1e-12, albedo=True):
    """Fit the model class ``family`` to ``target`` by least squares on f |cos theta_i|.

    Uses scipy.optimize.least_squares (trust-region reflective) with the analytic Jacobian
    (``eval_grad``). Bounds come from the family's validated parameter ranges
    (``param_ranges``). A parameter whose default is derived from others (FilamentCloth's
    sheen_color=None: sqrt(base_color)) starts from that value and is then fitted (or held, if
    not in ``params``) on its own.

    Parameters
    ----------
    target : BxDF or tuple
        A bsdfkit model (analytic or measured), evaluated on ``directions``, or raw samples
        ``(wo, wi, value)`` with value = f (cosine excluded), (N, 3).
    family : type
        A model class with a gradient kernel (see ``bsdfkit.fitting.differentiable_params``).
    params : sequence of str, optional
        The parameters to fit (``eval_grad`` names: RGB parameters fit per channel, "eta.g" one
        channel, "alpha" an isotropic alpha); default: every differentiable parameter not in
        ``fixed``.
    init : dict or BxDF, optional
        Starting values, or a model of the family; default: the family's first example.
    fixed : dict, optional
        Values (and knobs, e.g. ``{"masking": "separable"}``) held constant; default: the family's
        first example's.
    directions : tuple, optional
        A pair (wo, wi); default: the trade-off module's direction set of ``n`` pairs, stratified
        plus samples of the target's lobes, grazing angles included
        (``bsdfkit.tuning.errors.direction_set``). Not used with raw samples.
    loss : {"log", "relative", "l2"}, optional
        log(f cos + floor) differences (default: balances peak and tail), differences over
        max(target, floor), or differences over the target's mean.
    weights : array_like, shape (N,) or (N, 3), optional
        Residual weights.
    starts : int, optional
        Number of starting points: the given one plus starts - 1 drawn uniformly within the
        bounds, seeded by ``seed``; the best is kept.
    n : int, optional
        Pairs of the default direction set (default 4096).
    seed : int, optional
        Seed of the direction set and of the extra starts.
    max_nfev : int, optional
        Residual evaluations per start (scipy's ``max_nfev``, default 200).
    tol : float, optional
        scipy's ftol / xtol / gtol (default 1e-12).
    albedo : bool, optional
        Report the albedo error (``FitReport.albedo_error``; default True).

    Returns
    -------
    model : BxDF
        The fitted model of ``family``.
    report : FitReport
        What the fit reached (judge it by its errors, not by ``success``).

    Raises
    ------
    TypeError
        A ``family`` that is not a model class, a target of another kind, a bad ``init``.
    ValueError
        Unknown or non-differentiable parameter names, raw samples that do not broadcast or are
        negative, ``directions`` given with raw samples.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> target = bk.Conductor.from_metal("Cu", alpha=0.25)
    >>> m, report = bk.fit(target, bk.Conductor, params=["alpha"], init={"alpha": 0.5},
    ...                    fixed={"eta": target.eta, "k": target.k}, n=512)
    >>> round(m.alpha_x, 4), bool(report.rel_p99.max() < 1e-6)
    (0.25, True)
    """
    from scipy.optimize import least_squares
    t0 = time.perf_counter()
    m0, params, names, cols, lo, hi = _family_setup(family, params, init, fixed, loss, starts)
    wo, wi, y_t, target_model = _target_samples(target, directions, n, seed)
    cos_i = np.abs(wi[:, 2:3])
    floor = FLOOR_FRACTION * float(np.mean(y_t))
    if not floor > 0:
        raise ValueError("target: f |cos| is zero on every pair; nothing to fit")
    if weights is None:
        w = np.ones_like(y_t)
    else:
        wa = np.asarray(weights, np.float64)
        try:
            w = np.broadcast_to(wa[..., None] if wa.ndim == 1 else wa, y_t.shape)
        except ValueError:
            raise ValueError(f"weights: shape {wa.shape} does not match the {len(y_t)} direction pairs fitted "
                             f"(give (N,) or (N, 3) weights for the directions used)") from None
    if not (np.all(np.isfinite(w)) and np.all(w >= 0)):
        raise ValueError("weights: must be finite and >= 0")
    if not np.any(w > 0):
        raise ValueError("weights: all zero; nothing would be fitted")
    res_fn, dres_fn = _residuals(loss, y_t, floor, w)
    base = _start_params(m0, cols)
    m0 = family._from_params(base)
    x0 = np.clip(np.array([_get(m0, c) for c in cols]), lo, hi)
    cache = {}

    def evaluate(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            m = _set(family, base, cols, x)
            f, g = m.eval_grad(wo, wi, params)
            cache[key] = (f * cos_i, g * cos_i[..., None])
        return cache[key]

    def fun(x):
        y, _ = evaluate(x)
        return res_fn(y).ravel()

    def jac(x):
        y, g = evaluate(x)
        return (g * dres_fn(y)[..., None]).reshape(-1, len(x))

    rng = np.random.default_rng([seed, 0x666974])
    finite_hi = np.where(np.isfinite(hi), hi, np.maximum(lo, 0) + 4.0)
    x_starts = [x0] + [lo + (finite_hi - lo) * rng.random(len(x0)) for _ in range(starts - 1)]
    best, nfev, njev, costs = None, 0, 0, []
    for xs in x_starts:
        with _one_blas_thread():
            r = least_squares(fun, xs, jac=jac, bounds=(lo, hi), method="trf", x_scale="jac", max_nfev=max_nfev,
                              xtol=tol, ftol=tol, gtol=tol)
        nfev += int(r.nfev)
        njev += int(r.njev or 0)
        costs.append(float(r.cost))
        if best is None or r.cost < best[0].cost:
            best = (r, xs)
    r, xs = best
    model = _set(family, base, cols, r.x)
    y_m = model.eval(wo, wi) * cos_i
    rel = np.abs(y_m - y_t) / np.maximum(y_t, floor)
    alb = None
    if albedo and target_model is not None:
        from ..tuning.errors import ALBEDO_COS_THETA
        mu = np.asarray(ALBEDO_COS_THETA)
        a_wo = np.stack([np.sqrt(1 - mu * mu), np.zeros_like(mu), mu], axis=-1)
        alb = float(np.max(np.abs(model.albedo(a_wo, 1 << 16) - target_model.albedo(a_wo, 1 << 16))))
    rep = FitReport(model=model, params=dict(zip(names, map(float, r.x))), init=dict(zip(names, map(float, xs))),
                    loss=loss, cost=float(r.cost), rel_p50=np.percentile(rel, 50, axis=0),
                    rel_p90=np.percentile(rel, 90, axis=0), rel_p99=np.percentile(rel, 99, axis=0),
                    rel_max=rel.max(axis=0), albedo_error=alb, nfev=nfev, njev=njev, time=time.perf_counter() - t0, starts=len(x_starts),
                    success=bool(r.success), message=str(r.message), n_pairs=len(wo), start_costs=tuple(costs))
    return model, rep
