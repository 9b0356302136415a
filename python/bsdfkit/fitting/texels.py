"""``bk.fit_texels``: per-texel parameters fitted from observations, vectorized across texels.

One batched Levenberg-Marquardt run for all texels: each iteration is one ``eval_grad`` call on
the (texels, pairs) batch of the still-active texels, with their parameters as per-element arrays
(shape (T, 1), RGB (T, 1, 3)), then per-texel normal equations solved with numpy's batched
``linalg.solve`` on (T, P, P), per-texel damping (Nielsen's update) and the family's
``param_ranges`` as bounds (a step that crosses a bound goes 90 % of the way to it; a parameter at
a bound whose descent direction points outwards is held for that step). Each texel's iterations
depend on its own data only, so splitting the texels into chunks
(``chunk=``, or Dask tasks with ``client=``) gives bit-identical results.

Residuals are those of ``bk.fit`` on raw samples, per texel: on y = f |cos wi| with the floor
1e-3 mean(y_target) of that texel; "linear" is ``bk.fit``'s "l2".
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .fit import FLOOR_FRACTION, _check_family, _family_setup, _one_blas_thread, _start_params

__all__ = ["TexelFit", "fit_texels"]

_LOSSES = {"log": "log", "linear": "l2", "relative": "relative"}


@dataclass(frozen=True, eq=False)
class TexelFit:
    """What ``bk.fit_texels`` reached, per texel. Made by :func:`fit_texels`, not by hand.

    Attributes
    ----------
    model : BxDF
        One model of the family whose fitted parameters are per-element arrays of shape (T,)
        (RGB: (T, 3)); evaluate it with directions of shape (T, 3), or (T, M, 3) after
        reshaping the arrays to (T, 1).
    columns : tuple of str
        The fitted columns (``bsdfkit.fitting.grad_columns`` names).
    x, stderr : numpy.ndarray, shape (T, P)
        Fitted value and standard error per texel and column: sqrt of the diagonal of
        s^2 (J^T J)^-1, s^2 = SSR / (n_obs - P), J the residuals' Jacobian at the solution (inf
        where J^T J is singular, nan where n_obs <= P).
    covariance : numpy.ndarray, shape (T, P, P)
        s^2 (J^T J)^-1 per texel.
    params, errors : dict
        Fitted values and standard errors by the names fitted: (T,) per real, (T, 3) per RGB
        parameter.
    rms : numpy.ndarray, shape (T,)
        Residual RMS per texel, sqrt(SSR / n_obs), in the loss's units (log: about the relative
        error).
    cost : numpy.ndarray, shape (T,)
        SSR / 2 per texel.
    converged : numpy.ndarray of bool, shape (T,)
        The texel met a tolerance (cost, step or gradient) within ``max_iter`` iterations.
    iterations : numpy.ndarray of int, shape (T,)
        Levenberg-Marquardt iterations per texel.
    n_obs : numpy.ndarray of int, shape (T,)
        Residuals with a non-zero weight per texel (pairs x 3 channels).
    loss : str
        The loss name.
    time : float
        Seconds.
    """

    model: object
    columns: tuple
    x: np.ndarray
    stderr: np.ndarray
    covariance: np.ndarray
    params: dict
    errors: dict
    rms: np.ndarray
    cost: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    n_obs: np.ndarray
    loss: str
    time: float

    def summary(self) -> str:
        """A few lines: texels, convergence, iterations, residual RMS and the parameters'
        median values and standard errors.

        Returns
        -------
        str
            The summary text.
        """
        T = len(self.rms)
        lines = [f"fit_texels: {type(self.model).__name__}, {T} texels x {len(self.columns)} columns, "
                 f"loss {self.loss}, {self.time:.3g} s",
                 f"  converged   {int(np.sum(self.converged))}/{T}; iterations median "
                 f"{np.median(self.iterations) if T else 0:g}, max {np.max(self.iterations) if T else 0}",
                 f"  rms         median {np.median(self.rms) if T else np.nan:.3g}, p99 "
                 f"{np.percentile(self.rms, 99) if T else np.nan:.3g}"]
        w = max([11] + [len(c) for c in self.columns])
        lines = [lines[0]] + [ln[:2] + ln[2:].split(" ", 1)[0].ljust(w) + " " + ln[2:].split(" ", 1)[1].lstrip()
                              for ln in lines[1:]]
        for j, c in enumerate(self.columns):
            if T:
                lines.append(f"  {c:<{w}} median {np.median(self.x[:, j]):.6g}, median s.e. "
                             f"{np.median(self.stderr[:, j]):.3g}")
        return "\n".join(lines)

    def __repr__(self):
        return self.summary()


def _per_texel(v, n, T, arg, name):
    """``v`` as a per-texel array (T,) / (T, 3), or None when it is uniform."""
    if isinstance(v, np.ndarray) or isinstance(v, (list, tuple)):
        a = np.asarray(v)
        if a.dtype.kind not in "fiub":
            return None
        uniform = () if n == 1 else (3,)
        if a.shape == uniform:
            return None
        want = (T,) if n == 1 else (T, 3)
        if a.shape != want:
            raise ValueError(f"{arg}: {name!r} must be uniform {uniform} or per texel {want}, got shape {a.shape}")
        return a.astype(np.float64)
    return None


def _split(d, arg, family, T):
    """(uniform part, {field: per-texel array}) of an init/fixed dict."""
    if d is None:
        return None, {}
    if not isinstance(d, dict):
        raise TypeError(f"{arg}: expected a dict of parameter values")
    vp = getattr(family, "varying_params", {})
    uni, tex = {}, {}
    for k, v in d.items():
        fields = [k + "_x", k + "_y"] if k not in vp and k + "_x" in vp and k + "_y" in vp else [k]
        n = vp.get(fields[0], 1)
        a = _per_texel(v, n, T, arg, k)
        if a is None:
            uni[k] = v
            continue
        if fields[0] not in vp:
            raise ValueError(f"{arg}: {family.__name__}'s {k!r} does not vary per element; give one value "
                             f"(varying: {', '.join(vp) or 'none'})")
        uni[k] = a[0]   # a valid value standing for the texels' (checked per texel when the model is built)
        for f in fields:
            tex[f] = a
    return uni, tex


def _prepare(family, wo, wi, values, params, init, fixed, loss, weights):
    """Everything checked before any work: (setup, arrays)."""
    if loss not in _LOSSES:
        raise ValueError(f"loss: must be one of {tuple(_LOSSES)}, got {loss!r}")
    arrs = []
    for nm, a in (("wo", wo), ("wi", wi), ("values", values)):
        try:
            a = np.asarray(a, dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"{nm}: expected a real array") from None
        if a.ndim < 1 or a.shape[-1] != 3:
            raise ValueError(f"{nm}: expected shape (T, M, 3) (or broadcastable), got {a.shape}")
        arrs.append(a)
    wo, wi, values = arrs
    if values.ndim != 3:
        raise ValueError(f"values: expected shape (T, M, 3) (texels, pairs, RGB), got {values.shape}")
    try:
        shape = np.broadcast_shapes(wo.shape, wi.shape, values.shape)
    except ValueError:
        raise ValueError(f"wo, wi, values: shapes {wo.shape}, {wi.shape}, {values.shape} do not broadcast "
                         "to (T, M, 3)") from None
    if shape != values.shape:
        raise ValueError(f"wo, wi: shapes {wo.shape}, {wi.shape} must broadcast to values' {values.shape}")
    T, M = shape[:2]
    wo, wi = np.broadcast_to(wo, shape), np.broadcast_to(wi, shape)
    for nm, a in (("wo", wo), ("wi", wi)):
        bad = ~(np.isfinite(a).all(-1) & (np.abs(np.einsum("...i,...i", a, a) - 1) <= 1e-4))
        if bad.any():
            i = np.unravel_index(np.argmax(bad), bad.shape)
            raise ValueError(f"{nm}: {int(bad.sum())} direction(s) are not finite unit vectors, first at "
                             f"index {tuple(map(int, i))} (|w|^2 must equal 1 within 1e-4)")
    if not np.all(np.isfinite(values)) or np.any(values < 0):
        i = np.unravel_index(np.argmax(~(np.isfinite(values) & (values >= 0))), values.shape)
        raise ValueError(f"values: must be finite and >= 0; first bad entry at index {tuple(map(int, i))}")
    if weights is None:
        w = np.ones(shape)
    else:
        wa = np.asarray(weights, np.float64)
        try:
            w = np.broadcast_to(wa[..., None] if wa.ndim == 2 else wa, shape)
        except ValueError:
            raise ValueError(f"weights: shape {wa.shape} does not broadcast to (T, M) or (T, M, 3) = {shape}") from None
        if not (np.all(np.isfinite(w)) and np.all(w >= 0)):
            raise ValueError("weights: must be finite and >= 0")
    init = _check_family(family, init)
    init_u, init_t = _split(init, "init", family, T)
    fixed_u, fixed_t = _split(fixed, "fixed", family, T)
    m0, params, names, cols, lo, hi = _family_setup(family, params, init_u, fixed_u, _LOSSES[loss], 1)
    vp = getattr(family, "varying_params", {})
    for nm, col in zip(names, cols):
        for field, _ in col:
            if field not in vp:
                raise ValueError(f"params: {nm!r} does not vary per element in {family.__name__} "
                                 f"(varying: {', '.join(vp) or 'none'})")
    fitted = {f for col in cols for f, _ in col}
    both = fitted & set(fixed_t)
    if both:
        raise ValueError(f"fixed: {', '.join(sorted(both))} also fitted (params)")
    for k, v in init_t.items():   # a per-texel start of a parameter not fitted: held per texel
        if k not in fitted:
            fixed_t.setdefault(k, v)
    base = _start_params(m0, cols)
    x0 = np.empty((T, len(cols)))
    for j, col in enumerate(cols):
        field, ch = col[0]
        src = init_t.get(field)
        if src is None:
            v = np.asarray(base[field], np.float64)
            x0[:, j] = v if ch == -1 else v[ch]
        else:
            x0[:, j] = src if ch == -1 else src[:, ch]
    x0 = np.clip(x0, lo, hi)
    setup = dict(family=family, base=base, params=list(params), names=tuple(names), cols=cols, lo=lo, hi=hi,
                 fixed_t=fixed_t, loss=_LOSSES[loss], vp=vp)
    return setup, (wo, wi, values, w, x0)


def _model(setup, x, fixed_t, per_texel_shape):
    """The family's model with the columns ``x`` (T, P) and the per-texel fixed fields, each
    per-element array reshaped by ``per_texel_shape`` ((T, 1) inside the fit, (T,) for the
    result)."""
    p = dict(setup["base"])
    vp = setup["vp"]
    T = len(x)
    arrays = {}
    for field, a in fixed_t.items():
        arrays[field] = np.array(a, dtype=np.float64)
    for j, col in enumerate(setup["cols"]):
        for field, ch in col:
            if ch == -1:
                arrays[field] = x[:, j].copy()
            else:
                if field not in arrays:
                    arrays[field] = np.array(np.broadcast_to(np.asarray(p[field], np.float64), (T, 3)))
                arrays[field][:, ch] = x[:, j]
    for field, a in arrays.items():
        p[field] = a.reshape(per_texel_shape + ((3,) if vp[field] == 3 else ()))
    return setup["family"]._from_params(p)


def _fit_block(setup, wo, wi, values, w, x0, fixed_t, max_iter, tol):
    """Batched Levenberg-Marquardt on one block of texels, x0 (T, S, P): S starts per texel, the
    lowest final cost kept; returns the raw per-texel arrays."""
    T, S = x0.shape[:2]
    if S > 1:
        rep = lambda a: np.repeat(a, S, axis=0)  # noqa: E731
        out = _fit_block(setup, rep(wo), rep(wi), rep(values), rep(np.broadcast_to(w, values.shape)),
                         x0.reshape(T * S, 1, -1), {k: rep(v) for k, v in fixed_t.items()}, max_iter, tol)
        best = np.argmin(out["cost"].reshape(T, S), axis=1)   # the first of equal costs
        pick = np.arange(T) * S + best
        res = {k: v[pick] for k, v in out.items()}
        res["iterations"] = out["iterations"].reshape(T, S).sum(axis=1)
        return res
    x0 = x0[:, 0]
    T, M = values.shape[:2]
    P = x0.shape[1]
    lo, hi = setup["lo"], setup["hi"]
    cos_i = np.abs(wi[..., 2:3])
    y_t = values * cos_i
    mean = np.mean(y_t.reshape(T, -1), axis=1)[:, None, None]
    floor = FLOOR_FRACTION * mean
    loss = setup["loss"]

    def residuals(y, idx):
        """(r, dr/dy) of bk.fit's losses (fit._residuals), per texel, for the texels idx."""
        yt, wt, fl = y_t[idx], w[idx], floor[idx]
        if loss == "log":
            return wt * (np.log(y + fl) - np.log(yt + fl)), wt / (y + fl)
        s = wt / (mean[idx] if loss == "l2" else np.maximum(yt, fl))
        return (y - yt) * s, s

    def evaluate(idx, x):
        """(r (n, 3M), J (n, 3M, P), finite (n,)) for the texels idx (indices or a slice) at x (n, P)."""
        m = _model(setup, x, {k: v[idx] for k, v in fixed_t.items()}, (len(x), 1))
        f, g = m.eval_grad(wo[idx], wi[idx], setup["params"])
        c = cos_i[idx]
        r, d = residuals(f * c, idx)
        J = g * (c * d)[..., None]
        r, J = r.reshape(len(x), -1), J.reshape(len(x), -1, P)
        ok = np.isfinite(r).all(1) & np.isfinite(J).all((1, 2))
        return r, J, ok

    x = x0.copy()
    all_idx = np.arange(T)
    r, J, ok = evaluate(slice(None), x)
    if not ok.all():
        i = int(np.argmax(~ok))
        raise ValueError(f"fit_texels: the model is not finite at the starting point of texel {i}; give init")
    cost = 0.5 * np.einsum("tn,tn->t", r, r)
    lam = np.full(T, 1e-3)
    nu = np.full(T, 2.0)
    done = np.zeros(T, bool)
    conv = np.zeros(T, bool)
    iters = np.zeros(T, int)
    eye = np.eye(P)
    for _ in range(max_iter):
        act = all_idx[~done]
        if len(act) == 0:
            break
        Ja, ra, xa = J[act], r[act], x[act]
        A = np.matmul(Ja.transpose(0, 2, 1), Ja)
        g = np.matmul(Ja.transpose(0, 2, 1), ra[..., None])[..., 0]
        # bounds: a parameter at a bound whose descent direction points outwards is held
        held = ((xa <= lo) & (g > 0)) | ((xa >= hi) & (g < 0))
        gp = np.where(held, 0.0, g)
        gnorm = np.max(np.abs(gp), axis=1)
        small_g = gnorm <= tol * np.maximum(1.0, 2 * cost[act])
        dA = np.einsum("tii->ti", A)
        D = np.maximum(dA, 1e-12 * np.maximum(dA.max(axis=1, keepdims=True), np.finfo(float).tiny))
        Ad = A + (lam[act][:, None] * D)[..., None] * eye
        Ad = np.where(held[:, :, None] | held[:, None, :], 0.0, Ad) + held[:, :, None] * eye
        step = np.linalg.solve(Ad, -gp[..., None])[..., 0]
        # a step crossing a bound goes 90 % of the way to it, coordinate by coordinate (landing on
        # the bound stalls where the derivative vanishes there, e.g. a conductor's d f / d k at
        # k = 0); a parameter already at its bound stays there
        xn = xa + step
        xn = np.where(xn < lo, np.where(xa > lo, xa + 0.9 * (lo - xa), lo), xn)
        xn = np.where(xn > hi, np.where(xa < hi, xa + 0.9 * (hi - xa), hi), xn)
        dx = xn - xa
        rn, Jn, okn = evaluate(act, xn)
        cn = np.where(okn, 0.5 * np.einsum("tn,tn->t", rn, rn), np.inf)
        pred = -(np.einsum("tp,tp->t", dx, g) + 0.5 * np.einsum("tp,tpq,tq->t", dx, A, dx))
        ca = cost[act]
        rho = np.where(pred > 0, (ca - cn) / np.where(pred > 0, pred, 1.0), -1.0)
        accept = okn & (cn < ca) & (rho > 1e-4)
        iters[act] += 1
        xnorm = np.linalg.norm(xa, axis=1)
        small_dx = np.linalg.norm(dx, axis=1) <= tol * (tol + xnorm)
        small_f = accept & ((ca - cn) <= tol * ca)
        # update the accepted texels
        ia = act[accept]
        x[ia], r[ia], J[ia], cost[ia] = xn[accept], rn[accept], Jn[accept], cn[accept]
        ra_ = rho[accept]
        lam[ia] *= np.maximum(1 / 3, 1 - (2 * ra_ - 1) ** 3)
        nu[ia] = 2.0
        ir = act[~accept]
        lam[ir] *= nu[ir]
        nu[ir] *= 2
        stop = small_g | small_f | small_dx | (cost[act] == 0)
        conv[act[stop]] = True
        done[act[stop | (lam[act] > 1e16)]] = True
    # standard errors from J at the solution: cov = s^2 (J^T J)^-1, s^2 = SSR / (n_obs - P)
    A = np.matmul(J.transpose(0, 2, 1), J)
    ev, V = np.linalg.eigh(A)
    big = ev.max(axis=1, keepdims=True) * (P * np.finfo(float).eps)
    inv_ev = np.where(ev > big, 1.0 / np.where(ev > big, ev, 1.0), np.inf)
    n_obs = np.count_nonzero(np.broadcast_to(w, values.shape).reshape(T, -1) > 0, axis=1)
    dof = n_obs - P
    s2 = np.where(dof > 0, 2 * cost / np.maximum(dof, 1), np.nan)
    with np.errstate(invalid="ignore"):
        cov = np.einsum("tij,tj,tkj->tik", V, np.where(np.isinf(inv_ev), 0.0, inv_ev), V) * s2[:, None, None]
        var = np.einsum("tii->ti", cov).copy()
        # a column along an eigenvector without information (eigenvalue ~0) has no finite error
        var[(np.isinf(inv_ev)[:, None, :] & (np.abs(V) > 1e-12)).any(axis=2)] = np.inf
        se = np.sqrt(var)
    rms = np.sqrt(2 * cost / np.maximum(n_obs, 1))
    return dict(x=x, stderr=se, covariance=cov, rms=rms, cost=cost, converged=conv, iterations=iters,
                n_obs=n_obs)


_KEYS = ("x", "stderr", "covariance", "rms", "cost", "converged", "iterations", "n_obs")


def _chunk_task(setup, wo, wi, values, w, x0, fixed_t, max_iter, tol, kernel_threads):
    """Runs on a Dask worker: one block of texels."""
    if kernel_threads is not None:
        from ..threads import set_num_threads
        set_num_threads(kernel_threads)
    with _one_blas_thread():
        return _fit_block(setup, wo, wi, values, w, x0, fixed_t, max_iter, tol)


def fit_texels(family, wo, wi, values, params=None, init=None, fixed=None, loss="log", weights=None, *,
               starts=1, seed=0, max_iter=100, tol=1e-10, chunk=None, client=None, kernel_threads=1) -> TexelFit:
    """Fit per-texel parameters of ``family`` to observations, all texels at once.

    A batched Levenberg-Marquardt: each iteration is one ``eval_grad`` call on the (T, M) batch
    of the texels still iterating, their parameters as per-element arrays, then per-texel normal
    equations (numpy's batched ``linalg.solve``), per-texel damping and the family's
    ``param_ranges`` as bounds. Residuals as ``bk.fit``'s on raw samples, per texel (on
    f |cos wi|; the "log" loss floors at 1e-3 of the texel's mean). Standard errors from the
    Jacobian at the solution: cov = s^2 (J^T J)^-1, s^2 = SSR / (n_obs - P), per texel; with the
    "log" loss they suit multiplicative noise of constant relative size. Chunks (``chunk=``,
    ``client=``) give bit-identical results.

    Parameters
    ----------
    family : type
        A model class with a gradient kernel whose fitted parameters vary per element
        (``varying_params``), e.g. ``bk.Diffuse``, ``bk.Conductor``, ``bk.FilamentStandard``.
    wo, wi : array_like, shape (T, M, 3)
        Unit directions of the observations, local frame (broadcastable to ``values``' shape).
    values : array_like, shape (T, M, 3)
        Observed f (cosine excluded), T texels x M pairs x RGB; finite and >= 0.
    params : sequence of str, optional
        The parameters to fit (``bsdfkit.fitting.grad_columns`` names: "base_color", "alpha",
        "eta.g", ...); default: every differentiable parameter not in ``fixed``.
    init : dict or BxDF, optional
        Starting values: uniform values, or per texel (T,) / RGB (T, 3); default: the family's
        first example.
    fixed : dict, optional
        Values held (uniform, or per texel (T,) / (T, 3)) and knobs.
    loss : {"log", "linear", "relative"}, optional
        log(y + floor) differences (default), differences over the texel's mean (``bk.fit``'s
        "l2"), or over max(y, floor); y = f |cos wi|.
    weights : array_like, shape (T, M) or (T, M, 3), optional
        Residual weights (0 drops an observation).
    starts : int, optional
        Starting points per texel: the given one plus ``starts - 1`` drawn uniformly within the
        bounds (seeded by ``seed``, per texel, independent of chunking); the lowest cost is
        kept. Several starts cost that many times the time and escape local minima at the
        bounds (e.g. a Conductor's eta, k per channel).
    seed : int, optional
        Seed of the extra starts.
    max_iter : int, optional
        Iterations per texel and start (default 100).
    tol : float, optional
        Relative cost, step and gradient tolerances (default 1e-10).
    chunk : int, optional
        Texels per block (default: all in one; 4096 with ``client``).
    client : dask.distributed.Client or str, optional
        Fit the blocks as Dask tasks on this client (or scheduler address), concatenated in order.
    kernel_threads : int or None, optional
        bsdfkit threads in each Dask task (default 1; None keeps the worker's setting).

    Returns
    -------
    TexelFit
        The fitted model (per-element arrays of shape (T,) / (T, 3)), per-texel parameters,
        standard errors, covariance, residual RMS, convergence flags; ``summary()``.

    Raises
    ------
    ValueError
        Shapes that are not (T, M, 3), directions that are not unit vectors, negative or
        non-finite values, bad weights, unknown or non-varying parameter names, per-texel init /
        fixed arrays of another shape, a bad loss, ``max_iter``, ``tol`` or ``chunk``.
    TypeError
        A ``family`` that is not a model class, a bad ``client``.

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> rho = np.array([[0.2, 0.3, 0.4], [0.6, 0.5, 0.1]])           # 2 texels
    >>> wo = np.broadcast_to(bk.direction(0.3, 0.0), (2, 4, 3))
    >>> wi = np.broadcast_to(bk.direction(np.array([0.1, 0.4, 0.7, 1.0]), 1.0), (2, 4, 3))
    >>> res = bk.fit_texels(bk.Diffuse, wo, wi, np.broadcast_to(rho[:, None] / np.pi, (2, 4, 3)))
    >>> np.round(res.params["reflectance"], 6).tolist(), bool(res.converged.all())
    ([[0.2, 0.3, 0.4], [0.6, 0.5, 0.1]], True)
    """
    t0 = time.perf_counter()
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter: must be an integer >= 1, got {max_iter!r}")
    if not (isinstance(tol, (int, float)) and 0 <= tol < 1):
        raise ValueError(f"tol: must be a number in [0, 1), got {tol!r}")
    if chunk is not None and (isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1):
        raise ValueError(f"chunk: must be an integer >= 1, got {chunk!r}")
    if kernel_threads is not None and (isinstance(kernel_threads, bool) or not isinstance(kernel_threads, int)
                                       or kernel_threads < 1):
        raise ValueError(f"kernel_threads: must be an integer >= 1 or None, got {kernel_threads!r}")
    if isinstance(starts, bool) or not isinstance(starts, (int, np.integer)) or starts < 1:
        raise ValueError(f"starts: must be an integer >= 1, got {starts!r}")
    setup, (wo, wi, values, w, x0) = _prepare(family, wo, wi, values, params, init, fixed, loss, weights)
    T = values.shape[0]
    lo, hi = setup["lo"], setup["hi"]
    finite_hi = np.where(np.isfinite(hi), hi, np.maximum(lo, 0) + 4.0)
    rng = np.random.default_rng([seed, 0x746578])
    extra = lo + (finite_hi - lo) * rng.random((T, starts - 1, len(lo)))
    x0 = np.concatenate([x0[:, None], extra], axis=1)
    fixed_t = setup["fixed_t"]
    if client is not None:
        from distributed import Client
        if not isinstance(client, (Client, str)):
            raise TypeError(f"client: expected a dask.distributed.Client, a scheduler address or None, got "
                            f"{type(client).__name__}")
    step = T if chunk is None and client is None else (chunk or 4096)
    blocks = [slice(a, min(a + step, T)) for a in range(0, T, max(step, 1))]
    args = [(setup, wo[b], wi[b], values[b], w[b], x0[b], {k: v[b] for k, v in fixed_t.items()})
            for b in blocks]
    if client is None:
        with _one_blas_thread():
            outs = [_fit_block(*a, max_iter, tol) for a in args]
    else:
        from distributed import Client
        own = None
        if isinstance(client, str):
            client = own = Client(client)
        try:
            futs = [client.submit(_chunk_task, *a, max_iter, tol, kernel_threads, pure=False) for a in args]
            outs = client.gather(futs)
        finally:
            if own is not None:
                own.close()
    P = x0.shape[1]
    if outs:
        res = {k: np.concatenate([o[k] for o in outs]) for k in _KEYS}
    else:
        res = dict(x=np.empty((0, P)), stderr=np.empty((0, P)), covariance=np.empty((0, P, P)), rms=np.empty(0),
                   cost=np.empty(0), converged=np.empty(0, bool), iterations=np.empty(0, int), n_obs=np.empty(0, int))
    model = _model(setup, res["x"], fixed_t, (T,)) if T else None
    pv, pe = {}, {}
    names = setup["names"]
    for p in setup["params"]:
        idx = [j for j, n in enumerate(names) if n == p or n.partition(".")[0] == p]
        if len(idx) == 1:
            pv[p], pe[p] = res["x"][:, idx[0]].copy(), res["stderr"][:, idx[0]].copy()
        else:
            pv[p], pe[p] = res["x"][:, idx].copy(), res["stderr"][:, idx].copy()
    return TexelFit(model=model, columns=names, x=res["x"], stderr=res["stderr"], covariance=res["covariance"],
                    params=pv, errors=pe, rms=res["rms"], cost=res["cost"], converged=res["converged"],
                    iterations=res["iterations"], n_obs=res["n_obs"], loss=loss, time=time.perf_counter() - t0)
