"""Measured -> analytic: the cheapest model family that fits a target within a tolerance
(``bk.simplify(model, tol, families=(...))`` calls :func:`simplify_families`)."""
from __future__ import annotations

import html
import math
from dataclasses import dataclass

import numpy as np

from ..tuning.errors import FLOOR_FRACTION
from .fit import fit

__all__ = ["FamilyFit", "FamilySimplifyReport", "simplify_families"]

_METRICS = ("p99", "max", "albedo")


@dataclass(frozen=True, eq=False)
class FamilyFit:
    """One family's fit: the fitted model, its FitReport, the error in the chosen metric and
    its cost (seconds per float64 eval of the fitted model's configuration, from the shipped
    cost table; inf when the table has no entry for its cost family).

    error is the larger of ``error_target_pairs`` (on the fitted pairs: stratified and
    importance-sampled from the target) and ``error_own_pairs`` (on pairs importance-sampled from
    the fitted model itself: where it puts its energy, so that a lobe the target does not have
    is seen; None for raw-sample targets, which cannot be evaluated there). dropped: optional
    lobes of the fit (e.g. ``clear_coat``) set to 0 because the data does not support them (the
    fit without them has no larger error)."""

    family: str
    model: object
    report: object
    error: float
    cost: float
    ok: bool
    error_target_pairs: float = math.nan
    error_own_pairs: float | None = None
    dropped: tuple = ()


@dataclass(frozen=True, eq=False)
class FamilySimplifyReport:
    """What every family reached (``fits``, cheapest first) and which one was chosen.

    Attributes
    ----------
    tol : float
        The tolerance asked for.
    metric : str
        The error metric.
    fits : tuple of FamilyFit
        One fit per family, cheapest first: its model, errors (on the target's pairs and on the
        fit's own), the lobes it dropped, whether it is within tol, its cost.
    chosen : FamilyFit or None
        The cheapest fit within tol (None: none is).
    """

    tol: float
    metric: str
    fits: tuple
    chosen: FamilyFit | None

    def _rows(self):
        return [(f.family + (" <- chosen" if f is self.chosen else ""), f"{f.error:.3g}",
                 f"{f.error_target_pairs:.3g}", "n/a" if f.error_own_pairs is None else f"{f.error_own_pairs:.3g}",
                 ", ".join(f.dropped) or "-", "yes" if f.ok else "no",
                 "n/a" if not math.isfinite(f.cost) else f"{f.cost * 1e9:.3g}", f"{f.report.time:.2g}")
                for f in self.fits]

    def _head(self):
        return ("family", f"{self.metric} error", "on target's pairs", "on fit's own pairs", "lobes dropped",
                f"<= {self.tol:g}", "ns/eval", "fit s")

    def __repr__(self):
        head = self._head()
        rows = [head] + self._rows()
        w = [max(len(r[i]) for r in rows) for i in range(len(head))]
        lines = ["  ".join(c.ljust(w[i]) for i, c in enumerate(r)) for r in rows]
        pick = "none within tol" if self.chosen is None else repr(self.chosen.model)
        return f"FamilySimplifyReport (tol {self.tol:g}, metric {self.metric})\n" + "\n".join(lines) + f"\nchosen: {pick}"

    def _repr_html_(self):
        head = self._head()
        th = "".join(f"<th>{html.escape(h)}</th>" for h in head)
        body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in self._rows())
        return f"<table><caption>bsdfkit simplify: families</caption><tr>{th}</tr>{body}</table>"


def _own_key(model) -> str:
    """The cost-table key of ``model``'s own knob settings in float64 (as tuning.configurations
    keys it: a moot knob takes its first setting's label)."""
    from ..tuning.configs import _index_of, _specs
    p = model._params
    parts = []
    for s in _specs(model):
        i = 0 if s.param is None or s.moot(p) is not None else _index_of(s.settings, p[s.param])
        parts.append(f"{s.name}={s.labels[i]}")
    return ";".join(parts)


def _cost(model, costs):
    """Seconds per float64 eval of ``model``: its cost family's reference rate times the cost of
    the model's own configuration (1 when the table has no entry for it; inf without a family)."""
    from ..tuning.configs import family
    from ..tuning.costs import knob_costs
    table = knob_costs() if costs is None else costs
    fam = table.get("families", {}).get(family(model), {})
    rate = fam.get("reference_rate_per_s")
    if not rate:
        return math.inf
    return float(fam.get("costs", {}).get(_own_key(model), 1.0)) / rate


def _rel_error(y, y_t, floor, metric):
    """p99 (max over channels of the per-channel 99th percentile, as FitReport.rel_p99) or max of
    |y - y_t| / max(y_t, floor)."""
    if len(y_t) == 0:
        return 0.0
    rel = np.abs(y - y_t) / np.maximum(y_t, floor)
    return float(np.max(np.percentile(rel, 99, axis=0))) if metric == "p99" else float(np.max(rel))


#: Pairs importance-sampled from each fitted model to measure it where it puts its energy.
OWN_PAIRS = 4096
#: A fitted optional lobe is kept only if dropping it raises the error by more than this fraction
#: (a coat-less FilamentStandard's MERL table: the spurious coat lowers the p99 by 0.5 %; a real
#: coat of 0.8 by a factor 7).
LOBE_SUPPORT = 0.05


def _own_pairs_error(target, model, floor, metric, seed, n=OWN_PAIRS):
    """The error on pairs importance-sampled from ``model`` (stratified wo, cos theta_o >= 1e-3):
    a lobe the target lacks (a narrow clear coat) is hit by the model's own samples, not by
    the target's."""
    from ..tuning.errors import MIN_COS, _dirs, _lhs
    rng = np.random.default_rng([seed, 0x6f776e])
    h = _lhs(rng, n, 4)
    wo = _dirs(MIN_COS + (1 - MIN_COS) * h[:, 0], 2 * np.pi * h[:, 1])
    s = model.sample(wo, np.ascontiguousarray(h[:, 2]), rng.random((n, 2)))
    from .._enums import BxDFFlags
    ok = s.valid & ((s.flags & int(BxDFFlags.Specular)) == 0) & (np.abs(s.wi[:, 2]) > MIN_COS)
    wo, wi = wo[ok], s.wi[ok]
    cos = np.abs(wi[:, 2:3])
    return _rel_error(model.eval(wo, wi) * cos, target.eval(wo, wi) * cos, floor, metric)


def _lobe_variants(model):
    """``[(dropped lobe names, model)]``: the model, and the model with each subset of its optional
    lobes (Filament's clear coat, sheen: the registry's lobe knobs) set to their 'drop' value."""
    from itertools import combinations

    from ..tuning.configs import _specs
    lobes = [s for s in _specs(model, "all") if s.lobe and s.moot(model._params) is None and len(s.settings) > 1]
    out = [((), model)]
    for k in range(1, len(lobes) + 1):
        for sub in combinations(lobes, k):
            p = dict(model._params)
            for s in sub:
                p[s.param] = s.settings[-1]
            out.append((tuple(s.name for s in sub), type(model)._from_params(p)))
    return out


def simplify_families(target, tol, families, metric="p99", directions=None, seed=0, costs=None, **fit_kwargs):
    """Fit every class of ``families`` to ``target`` (``bk.fit``, several starts) and return the
    cheapest fitted model whose error meets ``tol``.

    An optional lobe of the fit (FilamentStandard's clear coat, sheen) is dropped when the fit
    without it has no larger error (``FamilyFit.dropped``): the data must support every lobe the
    answer has. Cost: the shipped cost table's float64 time per eval of the fitted model's
    configuration (its cost family's reference rate and the configuration's relative cost).

    Parameters
    ----------
    target : BxDF
        The model to replace (typically a measured one).
    tol : float
        The tolerance, in the unit of ``metric``.
    families : sequence of type
        Model classes with a gradient kernel.
    metric : {"p99", "max", "albedo"}, optional
        ``"p99"`` / ``"max"`` (max over channels of the relative error of f |cos|, the larger of
        its values on the fitted pairs and on pairs importance-sampled from the fitted model
        itself, :data:`OWN_PAIRS` of them: a lobe the target does not have is measured where the
        fit puts it) or ``"albedo"`` (absolute directional-albedo error).
    directions : tuple, optional
        A pair (wo, wi) to fit and measure on (default: ``bk.fit``'s).
    seed : int, optional
        Seed of the directions and starts.
    costs : dict, optional
        A cost table to rank by instead of the shipped one.
    **fit_kwargs
        Passed to ``bk.fit`` (``n``, ``starts``, ``loss``, ...).

    Returns
    -------
    model : BxDF or None
        The cheapest fit within tol (None if none is).
    report : FamilySimplifyReport
        Every family's fit and errors.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m, report = bk.fitting.simplify_families(bk.Conductor.from_metal("Cu", alpha=0.25), 0.05,
    ...                                          (bk.Diffuse, bk.Conductor), n=512)
    >>> type(m).__name__, round(m.alpha_x, 3)
    ('Conductor', 0.25)
    """
    if metric not in _METRICS:
        raise ValueError(f"metric: must be one of {_METRICS}, got {metric!r}")
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol >= 0:
        raise ValueError(f"tol: must be a number >= 0, got {tol!r}")
    if isinstance(families, type) or not families:
        raise TypeError("families: expected a non-empty sequence of model classes")
    kw = {"starts": 3, "seed": seed, **fit_kwargs}
    from ..models.base import BxDF
    from .fit import _target_samples
    model_target = isinstance(target, BxDF)
    fits = []
    for fam in families:
        m, rep = fit(target, fam, directions=directions, **kw)
        if metric == "albedo":
            err = math.inf if rep.albedo_error is None else rep.albedo_error
            fits.append(FamilyFit(fam.__name__, m, rep, err, _cost(m, costs), err <= tol, err))
            continue
        wo, wi, y_t, _ = _target_samples(target, directions, kw.get("n", 4096), seed)
        floor = FLOOR_FRACTION * float(np.mean(y_t))
        variants = []
        for dropped, cand in _lobe_variants(m):
            e_t = _rel_error(cand.eval(wo, wi) * np.abs(wi[:, 2:3]), y_t, floor, metric)
            e_o = _own_pairs_error(target, cand, floor, metric, seed) if model_target else None
            variants.append((max(e_t, e_o or 0.0), dropped, cand, e_t, e_o))
        # a lobe stays only if the data supports it: the fit without it would be worse by more
        # than LOBE_SUPPORT (relative); of the variants that close to the best, the fewest lobes
        e_best = min(v[0] for v in variants)
        err, dropped, cand, e_t, e_o = min((v for v in variants if v[0] <= e_best * (1 + LOBE_SUPPORT)),
                                           key=lambda v: (-len(v[1]), v[0]))
        fits.append(FamilyFit(fam.__name__, cand, rep, err, _cost(cand, costs), err <= tol, e_t, e_o, dropped))
    fits.sort(key=lambda f: (f.cost, f.error))
    chosen = next((f for f in fits if f.ok), None)
    return (None if chosen is None else chosen.model), FamilySimplifyReport(float(tol), metric, tuple(fits), chosen)
