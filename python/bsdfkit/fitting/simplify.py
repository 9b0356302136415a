"""Measured -> analytic: the cheapest model family that fits a target within a tolerance
(``bk.simplify(model, tol, families=(...))`` calls :func:`simplify_families`)."""
from __future__ import annotations

import html
import math
from dataclasses import dataclass

import numpy as np

from .fit import fit

__all__ = ["FamilyFit", "FamilySimplifyReport", "simplify_families"]

_METRICS = ("p99", "max", "albedo")


@dataclass(frozen=True, eq=False)
class FamilyFit:
    """One family's fit: the fitted model, its FitReport, the error in the chosen metric and
    its cost (seconds per float64 eval of the fitted model's configuration, from the shipped
    cost table; inf when the table has no entry for its cost family)."""

    family: str
    model: object
    report: object
    error: float
    cost: float
    ok: bool


@dataclass(frozen=True, eq=False)
class FamilySimplifyReport:
    """What every family reached (``fits``, cheapest first) and which one was chosen (None:
    none within tol)."""

    tol: float
    metric: str
    fits: tuple
    chosen: FamilyFit | None

    def _rows(self):
        return [(f.family + (" <- chosen" if f is self.chosen else ""), f"{f.error:.3g}", "yes" if f.ok else "no",
                 "n/a" if not math.isfinite(f.cost) else f"{f.cost * 1e9:.3g}", f"{f.report.time:.2g}")
                for f in self.fits]

    def __repr__(self):
        head = ("family", f"{self.metric} error", f"<= {self.tol:g}", "ns/eval", "fit s")
        rows = [head] + self._rows()
        w = [max(len(r[i]) for r in rows) for i in range(len(head))]
        lines = ["  ".join(c.ljust(w[i]) for i, c in enumerate(r)) for r in rows]
        pick = "none within tol" if self.chosen is None else repr(self.chosen.model)
        return f"FamilySimplifyReport (tol {self.tol:g}, metric {self.metric})\n" + "\n".join(lines) + f"\nchosen: {pick}"

    def _repr_html_(self):
        head = ("family", f"{self.metric} error", f"<= {self.tol:g}", "ns/eval", "fit s")
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


def simplify_families(target, tol, families, metric="p99", directions=None, seed=0, costs=None, **fit_kwargs):
    """Fit every class of ``families`` to ``target`` (``bk.fit``, several starts) and return
    ``(model, FamilySimplifyReport)``: the cheapest fitted model whose error meets ``tol``
    (None if none does). metric: ``"p99"`` / ``"max"`` (max over channels of the relative error
    of f |cos| on the fitted pairs) or ``"albedo"`` (absolute directional-albedo error). Cost:
    the shipped cost table's float64 time per eval of the fitted model's configuration (its cost
    family's reference rate and the configuration's relative cost)."""
    if metric not in _METRICS:
        raise ValueError(f"metric: must be one of {_METRICS}, got {metric!r}")
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol >= 0:
        raise ValueError(f"tol: must be a number >= 0, got {tol!r}")
    if isinstance(families, type) or not families:
        raise TypeError("families: expected a non-empty sequence of model classes")
    kw = {"starts": 3, "seed": seed, **fit_kwargs}
    fits = []
    for fam in families:
        m, rep = fit(target, fam, directions=directions, **kw)
        err = {"p99": float(np.max(rep.rel_p99)), "max": float(np.max(rep.rel_max)),
               "albedo": math.inf if rep.albedo_error is None else rep.albedo_error}[metric]
        fits.append(FamilyFit(fam.__name__, m, rep, err, _cost(m, costs), err <= tol))
    fits.sort(key=lambda f: (f.cost, f.error))
    chosen = next((f for f in fits if f.ok), None)
    return (None if chosen is None else chosen.model), FamilySimplifyReport(float(tol), metric, tuple(fits), chosen)
