"""Reports: :func:`tradeoff` (every configuration, its error and speed) and :func:`simplify`."""
from __future__ import annotations

import html as _html
import math
import numbers
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..models import BxDF
from .._progress import check_progress
from .costs import BUDGET_MIN_TIME, SPREAD_WARN, _budgeted_n_timing, _check_costs, _costs_for, _measure, _op, _pick, _threads
from .errors import STOCHASTIC_N, _Evaluation, _check_int, is_stochastic
from .configs import _check_allow, _check_model, _knobs_from, _label, _specs, family

__all__ = ["METRICS", "METRIC_DESCRIPTIONS", "Table", "tradeoff", "SimplifyReport", "simplify",
           "ToleranceNotMetWarning"]


#: Error metrics accepted by :func:`simplify` and :func:`pareto`, and their Table columns.
METRICS = {"max": "max_err", "p99": "p99_err", "albedo": "albedo_err", "rms": "rms_err"}

#: What each metric measures (named in reports and the CLI; definitions in the module docstring).
METRIC_DESCRIPTIONS = {
    "p99": "99th percentile of the relative error of f·|cos θi|",
    "max": "largest relative error of f·|cos θi|",
    "albedo": "largest absolute error of the directional albedo",
    "rms": "relative RMS of f·|cos θi| against the converged walk (noise and bias)",
}


class ToleranceNotMetWarning(UserWarning):
    """:func:`simplify` found no configuration within the tolerance; the report's
    ``within_tol`` is False and it returned the most accurate configuration."""


def _pareto_mask(err, thr) -> np.ndarray:
    """True where no other point has error <= and throughput >= with one of them strict."""
    err, thr = np.asarray(err, float), np.asarray(thr, float)
    mask = np.ones(len(err), bool)
    for i in range(len(err)):
        dom = (err <= err[i]) & (thr >= thr[i]) & ((err < err[i]) | (thr > thr[i]))
        mask[i] = not dom.any()
    return mask


def _fmt_cell(v, col):
    if v is None:
        return "—"
    if isinstance(v, (bool, np.bool_)):
        return "✓" if v else ""
    if col == "evals_per_s":
        return f"{v / 1e6:.1f}M"
    if col in ("speedup", "expected_speedup"):
        return f"{v:.2f}×"
    if col == "spread":
        return f"{v:.2f}" + ("!" if v > SPREAD_WARN else "")
    if isinstance(v, float):
        return "0" if v == 0 else f"{v:.2e}"
    return str(v)


class Table:
    """Result of :func:`tradeoff`: one row per reachable configuration, the most accurate first.

    Columns: ``config`` (what differs from the most accurate configuration), one column per
    reachable knob, ``dtype``, ``op`` (timed operation: eval, or sample for delta-only models),
    ``evals_per_s`` and ``speedup`` (live, this run, ratio to the most accurate configuration
    timed back to back; ``None`` with ``measure=False``), ``spread`` (median / min of the repeats
    of that row and the reference, 1 on a quiet machine; marked ``!`` above ``SPREAD_WARN``, and
    :func:`tradeoff` warns), ``expected_speedup`` (from the shipped
    cost table, ``None`` if the configuration is not in it), ``max_err``, ``p99_err``,
    ``albedo_err`` (see the module docstring) and ``pareto`` (on the front of throughput vs
    p99 error; throughput = live speedup, else expected speedup).

    Renders as text (``str``), Markdown and HTML (Jupyter); ``to_records()`` (list of dicts),
    ``to_dict()`` (dict of columns) and ``to_pandas()`` (needs pandas). ``table[i]`` is a row,
    ``table["p99_err"]`` a column, ``table.configs[i]`` the :class:`Config` (``.model``,
    ``.dtype``). Attributes: model, reference (the most accurate model, or tradeoff's
    ``reference=``), external_reference (that model, else None), knobs, floor,
    reference_albedo, directions (the :class:`DirectionSet`), seed, family, measured. Tables
    are made by :func:`tradeoff`, not by hand.

    Parameters
    ----------
    model : BxDF
        The model :func:`tradeoff` was given.
    evaluation : object
        The errors of every configuration (internal).
    rates, speedups, expected, spreads : sequence or None
        Per configuration: measured throughput, live and expected speedup, timing spread.
    info : dict
        What the run used (``n_timing``, thread count, ...).
    """

    def __init__(self, model, evaluation: _Evaluation, rates, speedups, expected, info, spreads=None):
        self.model = model
        self.configs = evaluation.configs
        self.reference = evaluation.reference.model
        #: the ``reference=`` model given to tradeoff (None: the most accurate configuration)
        self.external_reference = None if evaluation.reference in evaluation.configs else self.reference
        self.knobs = _knobs_from(model, self.configs)
        self.floor = evaluation.floor
        self.reference_albedo = evaluation.reference_albedo
        self.directions = evaluation.directions
        self.family = family(model)
        self.measured = rates is not None
        self.info = info
        self.seed = info.get("seed")
        #: stochastic models: errors against the converged reference (``converged``), the front on rms_err
        self.stochastic = evaluation.stochastic
        self.converged = evaluation.converged
        self.reference_noise = evaluation.reference_noise
        self.metric = "rms" if self.stochastic else "p99"
        noise = ["noise", "bias"] if self.stochastic else []
        self.columns = (["config"] + [k.name for k in self.knobs if k.reachable and k.name != "precision"] +
                        ["dtype", "op", "evals_per_s", "speedup", "spread", "expected_speedup", "max_err", "p99_err",
                         "albedo_err", "rms_err"] + noise + ["pareto"])
        op = _op(model)
        rows = []
        for i, (c, e) in enumerate(zip(self.configs, evaluation.errors)):
            r = {"config": c.describe()}
            for k in self.knobs:
                if k.reachable and k.name != "precision":
                    r[k.name] = c.labels[k.name] if c.labels[k.name] is not None else "(moot)"
            r.update(dtype=c.labels["precision"], op=op,
                     evals_per_s=None if rates is None else rates[i],
                     speedup=None if speedups is None else speedups[i],
                     spread=None if spreads is None else spreads[i],
                     expected_speedup=None if expected[i] is None else 1.0 / expected[i],
                     **{k: v for k, v in e.items() if k in self.columns})
            rows.append(r)
        thr = [r["speedup"] if r["speedup"] is not None else (r["expected_speedup"] or 1.0) for r in rows]
        for r, p in zip(rows, _pareto_mask([r[METRICS[self.metric]] for r in rows], thr)):
            r["pareto"] = bool(p)
        self._rows = rows

    # --- access
    def __len__(self):
        return len(self._rows)

    def __iter__(self):
        return iter(self.to_records())

    def __getitem__(self, i):
        if isinstance(i, str):
            if i not in self.columns:
                raise KeyError(f"column {i!r}; columns: {', '.join(self.columns)}")
            return [r[i] for r in self._rows]
        return dict(self._rows[i])

    def to_records(self) -> list:
        """Rows as a list of dicts (column -> value)."""
        return [dict(r) for r in self._rows]

    def to_dict(self) -> dict:
        """Columns as a dict of lists."""
        return {c: [r[c] for r in self._rows] for c in self.columns}

    def to_pandas(self):
        """The table as a ``pandas.DataFrame`` (raises ImportError naming pandas when it is not
        installed: pandas is optional; ``to_records()`` / ``to_dict()`` need nothing)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Table.to_pandas() needs pandas, which is not installed (pip install pandas); "
                              "Table.to_records() and Table.to_dict() work without it") from None
        return pd.DataFrame(self.to_records(), columns=self.columns)

    def pareto_front(self, metric="p99") -> list:
        """Row indices on the Pareto front of throughput (live speedup, else expected) against
        the given error metric, sorted by error."""
        col = _check_metric(metric)
        thr = [r["speedup"] if r["speedup"] is not None else (r["expected_speedup"] or 1.0) for r in self._rows]
        err = [r[col] for r in self._rows]
        idx = [i for i, p in enumerate(_pareto_mask(err, thr)) if p]
        return sorted(idx, key=lambda i: (err[i], -thr[i]))

    # --- rendering
    def _title(self) -> str:
        from ..models.describe import describe
        m = "live" if self.measured else "not measured"
        vs = ("the converged walk (n_samples=256, max_depth=100; rms_err = noise + bias)" if self.converged is not None
              else "the most accurate" if self.external_reference is None else describe(self.external_reference))
        return (f"{describe(self.model)} — {len(self)} configurations ({self.family}); errors vs {vs} "
                f"on {len(self.directions)} direction pairs (seed {self.seed}), floor {self.floor:.2e}; "
                f"throughput {m}")

    def _cells(self):
        return [[_fmt_cell(r[c], c) for c in self.columns] for r in self._rows]

    def __str__(self):
        cells = self._cells()
        w = [max(len(c), *(len(row[j]) for row in cells)) for j, c in enumerate(self.columns)]
        lines = [self._title(), "  ".join(c.ljust(w[j]) for j, c in enumerate(self.columns)),
                 "  ".join("-" * x for x in w)]
        lines += ["  ".join(v.ljust(w[j]) for j, v in enumerate(row)) for row in cells]
        return "\n".join(lines)

    def __repr__(self):
        return f"<bsdfkit.tradeoff.Table: {len(self)} configurations of {type(self.model).__name__}>"

    def _repr_markdown_(self):
        cells = self._cells()
        lines = [f"**{self._title()}**", "", "| " + " | ".join(self.columns) + " |",
                 "|" + "|".join("---" for _ in self.columns) + "|"]
        for r, row in zip(self._rows, cells):
            row = [f"**{v}**" if r["pareto"] and v else v for v in row]
            lines.append("| " + " | ".join(v.replace("|", "\\|") for v in row) + " |")
        return "\n".join(lines)

    def _repr_html_(self):
        esc = _html.escape
        head = "".join(f"<th>{esc(c)}</th>" for c in self.columns)
        body = []
        for r, row in zip(self._rows, self._cells()):
            style = ' style="font-weight:bold"' if r["pareto"] else ""
            body.append(f"<tr{style}>" + "".join(f"<td>{esc(v)}</td>" for v in row) + "</tr>")
        return (f"<div><p>{esc(self._title())} (bold: Pareto front)</p><table><thead><tr>{head}</tr></thead>"
                f"<tbody>{''.join(body)}</tbody></table></div>")


def _check_metric(metric) -> str:
    if not isinstance(metric, str) or metric not in METRICS:
        raise ValueError(f"metric: must be one of {', '.join(map(repr, METRICS))}, got {metric!r}")
    return METRICS[metric]


def _check_tol(tol) -> float:
    if isinstance(tol, bool) or not isinstance(tol, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"tol: expected a real number, got {type(tol).__name__}")
    t = float(tol)
    if math.isnan(t) or t < 0:
        raise ValueError(f"tol: must be a number >= 0 (inf allowed), got {t}")
    return t


def _stochastic_defaults(sto, n, n_albedo, ref_sto=False):
    """Default sizes: stochastic models (every eval a random walk) get smaller sets. The albedo
    set keeps 4096 samples per wo when the reference is stochastic: then every configuration's
    albedo is the mean of its own sampling weights (one walk per sample, not an eval of
    n_samples walks; see ``errors._Prepared``), and 64 samples would leave ~5 % noise."""
    n = (STOCHASTIC_N if sto else 8192) if n is None else n
    n_albedo = (64 if sto and not ref_sto else 4096) if n_albedo is None else n_albedo
    return n, n_albedo


def tradeoff(model, directions=None, n: int | None = None, seed: int = 0, *, n_albedo: int | None = None,
             measure: bool = True, n_timing: int | None = None, repeats: int = 5, rounds: int = 1,
             costs: dict | None = None, reference=None, progress=None) -> Table:
    """Throughput and error of every reachable knob configuration of ``model``.

    Errors: ``max_err`` / ``p99_err`` (relative error of f |cos theta_i|) and ``albedo_err``
    against the most accurate configuration (definitions in the module docstring). float32
    configurations are run on float32 directions.

    Throughput (``measure=True``): each configuration's ``eval`` (``sample`` for models made only
    of delta lobes) on ``n_timing`` pairs with a preallocated ``out=``, timed back to back with
    the most accurate configuration, best of ``repeats`` (over ``rounds`` rounds), at the current
    ``bsdfkit.set_num_threads``; ``speedup`` is that same-run ratio. With ``n_timing`` left to
    its default (65536 pairs, 4096 for stochastic models) it is reduced, down to 64, so that the
    timing takes about ``TIMING_BUDGET_S`` (15 s) at most, estimated from one call of the most
    accurate configuration, and its repeats then last >= 1 ms instead of 5 ms
    (``Table.info["n_timing"]`` says what was used); pass ``n_timing=`` for a fixed size. Ctrl-C
    stops between two calls (KeyboardInterrupt). ``expected_speedup`` is what the shipped cost
    table predicts (the number :func:`simplify` ranks by; see the module docstring for why
    simplify does not use the live figure). DFG tables are built before timing.

    Stochastic models (``model.exact_eval`` False: CoatedDiffuse, CoatedConductor): the errors are
    against the *converged* reference (the most accurate configuration with n_samples = 256,
    max_depth = 100, another realization), ``rms_err`` is the relative RMS of f |cos theta_i|
    (``sqrt(mean((v - v_ref)^2) / mean(v_ref^2))`` over pairs and channels), split into ``noise``
    (the RMS difference of two realizations of the configuration / sqrt 2) and ``bias``
    (``sqrt(rms_err^2 - noise^2 - reference_noise^2)``, clamped at 0); ``Table.reference_noise``
    is the converged reference's own noise (two realizations), included in rms_err. The Pareto
    front is on rms_err. Defaults there: n = 512 pairs, n_timing = 4096, n_albedo = 4096 (each
    configuration's albedo is the mean of its own sampling weights: the walk's sample pdf is only
    proportional to the density; 64 when only the configurations are stochastic).

    Parameters
    ----------
    model : BxDF
        The model whose configurations are compared.
    directions : DirectionSet or tuple, optional
        ``None`` (the default set, :func:`direction_set` with ``n`` rows and ``seed``), a
        :class:`DirectionSet`, or a pair ``(wo, wi)`` of direction arrays (float64 unit vectors;
        delta lobes, which ``eval`` cannot reach, are then sampled at those ``wo``).
    n : int, optional
        Rows of the default direction set (8192; 512 for stochastic models).
    seed : int, optional
        Seed of the default direction set (default 0).
    n_albedo : int, optional
        Samples per wo of the albedo error (4096; see above for stochastic models).
    measure : bool, optional
        Time every configuration (default True); False: errors only (``speedup`` is None).
    n_timing : int, optional
        Direction pairs per timed call (default: chosen as above).
    repeats, rounds : int, optional
        Timing repeats (best of, default 5) and rounds (default 1).
    costs : dict, optional
        A cost table in the :func:`knob_costs` format to use instead of the shipped one.
    reference : BxDF, optional
        Another model to measure the errors against instead of the most accurate configuration
        (called in float64; e.g. a ``bk.Custom`` wrapping your own formula, or a measured
        material): every configuration of ``model`` is compared with it on the same directions
        (drawn from ``model``; the albedo from the reference's own samples). It must have specular
        (delta) lobes exactly when ``model`` has.
    progress : bool or callable, optional
        None (a progress line on stderr when it is a terminal, a bar in Jupyter), True, False, or a
        callable ``progress(done, total, stage)``.

    Returns
    -------
    Table
        One row per reachable configuration, the most accurate first.

    Raises
    ------
    ValueError
        A bad argument (named); a reference whose delta lobes differ from the model's.
    TypeError
        An argument of the wrong type, or a model that is not a bsdfkit model.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> t = bk.tradeoff(bk.Conductor.from_metal("Cu", alpha=0.3), n=256, n_albedo=64, measure=False)
    >>> t[0]["config"], len(t) > 1
    ('most accurate', True)
    """
    _check_model(model)
    progress = check_progress(progress)
    sto = _any_stochastic(model)
    auto_timing = n_timing is None
    from .configs import configurations
    ref_sto = is_stochastic(configurations(model)[0].model if reference is None else reference)
    n, n_albedo = _stochastic_defaults(sto, n, n_albedo, ref_sto)
    if n_timing is None:
        n_timing = 4096 if sto else 65536
    n, seed, n_albedo = _check_int(n, "n", 16), _check_int(seed, "seed", 0), _check_int(n_albedo, "n_albedo", 16)
    n_timing, repeats, rounds = (_check_int(n_timing, "n_timing", 1), _check_int(repeats, "repeats", 1),
                                 _check_int(rounds, "rounds", 1))
    if reference is not None:
        _check_model(reference, "reference")
    ev = _Evaluation(model, directions, n, seed, n_albedo, reference="accurate" if reference is None else reference,
                     progress=progress)
    rates = speedups = spreads = None
    if measure:
        min_time = 0.005
        if auto_timing:   # the default stays within TIMING_BUDGET_S of live timing (690 s for CoatedDiffuse before)
            n_auto = _budgeted_n_timing(ev.configs, _op(model), n_timing, repeats, rounds, seed)
            if n_auto < n_timing:
                n_timing, min_time = n_auto, BUDGET_MIN_TIME
        rates, speedups, spreads = _measure(ev.configs, _op(model), n_timing, repeats, rounds, seed, progress,
                                            min_time)
        worst = max(spreads)
        if worst > SPREAD_WARN:
            warnings.warn(f"tradeoff: live timings are noisy (spread median/min of repeats up to {worst:.2f}x, "
                          f"above {SPREAD_WARN}): the machine is busy and the speedup column is unreliable; "
                          "rerun with more repeats= / rounds= on a quiet machine, or rank by expected_speedup",
                          RuntimeWarning, stacklevel=2)
    costs = _check_costs(costs)
    expected = _costs_for(model, ev.configs, costs)
    info = {"seed": seed, "n": n, "n_albedo": n_albedo, "n_timing": n_timing, "repeats": repeats, "rounds": rounds,
            "threads": _threads(), "cost_table": costs.get("machine")}
    return Table(model, ev, rates, speedups, expected, info, spreads)


def _any_stochastic(model) -> bool:
    """The model or one of its configurations is stochastic (then errors are RMS vs converged)."""
    from .configs import configurations
    return is_stochastic(model) or any(is_stochastic(c.model) for c in configurations(model))


@dataclass
class SimplifyReport:
    """What :func:`simplify` chose and why (``summary()`` says it in words).

    Attributes
    ----------
    input_model : BxDF
        The model given to simplify.
    model : BxDF
        The simplified model.
    dtype : type
        ``np.float32`` or ``np.float64``, the precision to call it with (feed directions of that
        dtype).
    config : dict
        ``{knob: label}`` of every reachable knob (precision included).
    changes : list
        ``[(parameter, input value, output value, reason)]`` for every constructor parameter that
        differs between the input and the output model, and ``("precision", "float64",
        "float32", ...)`` when float32 was chosen -- an empty list means the input comes back
        unchanged.
    kept : list
        ``[(knob, reason)]`` for approximation knobs left at the input's setting although a
        cheaper one exists.
    error : dict
        ``{"max": ..., "p99": ..., "albedo": ...}`` of the chosen configuration against the input
        model called in float64 (``reference``).
    tol : float
        The tolerance.
    metric : str
        The metric the tolerance applies to.
    expected_speedup : float or None
        Against the most accurate configuration simplify considered, from the cost table
        (``None`` when the configuration is not in it).
    speedup_vs_input : float or None
        The same against the input model's own configuration (float64 calls), when both are in
        the table.
    ranked_by : str
        ``"cost table"`` or ``"registry order"``.
    reference : BxDF
        What the errors are measured against.
    description : str
        The chosen configuration in words.
    n_configurations, n_within_tol : int
        Configurations measured, and how many met the tolerance.
    seed : int
        Seed of the direction set.
    floor : float
        The relative-error floor.
    notes : list of str
        Remarks (e.g. the n_samples that would reach a missed tolerance).
    fixed : list
        ``[(knob, value)]``, the modelling choices kept as given (not named in ``allow``).
    allow : tuple
        The modelling knobs simplify was allowed to change.
    within_tol : bool
        False when no configuration met the tolerance.
    """

    input_model: BxDF
    model: BxDF
    dtype: type
    config: dict
    changes: list
    kept: list
    error: dict
    tol: float
    metric: str
    expected_speedup: float | None
    speedup_vs_input: float | None
    ranked_by: str
    reference: BxDF
    description: str
    n_configurations: int
    n_within_tol: int
    seed: int
    floor: float
    notes: list = field(default_factory=list)
    fixed: list = field(default_factory=list)
    allow: tuple = ()
    #: True when the returned configuration's error is <= tol. False only when no configuration
    #: is (stochastic models with a tol below what n_samples = 64 reaches): then the most accurate
    #: configuration is returned, ``n_within_tol`` is 0 and simplify warns (ToleranceNotMetWarning).
    within_tol: bool = True

    @property
    def unchanged(self) -> bool:
        """True when the output model equals the input (the precision may still be float32)."""
        return self.model == self.input_model

    @property
    def metric_description(self) -> str:
        """What ``metric`` measures, e.g. "99th percentile of the relative error of f·|cos θi|"."""
        return METRIC_DESCRIPTIONS.get(self.metric, self.metric)

    def summary(self) -> str:
        """One line: chosen configuration, error against the input (the metric named), whether it
        meets tol, and the expected speedup. A missed tolerance starts with "TOLERANCE NOT MET"."""
        ch = "unchanged" if not self.changes else ", ".join(f"{k}={b}" for k, a, b, _ in self.changes)
        sp = "unknown" if self.speedup_vs_input is None else f"{self.speedup_vs_input:.2f}×" + (
            " (slower)" if self.speedup_vs_input < 1 else "")
        e = self.error[self.metric]
        metric = f"{self.metric} error ({self.metric_description}) vs input {e:.2e}"
        if self.within_tol:
            return (f"{ch} | {metric} <= tol {self.tol:g} | expected speedup over the input {sp} | "
                    f"dtype {np.dtype(self.dtype).name}")
        return (f"TOLERANCE NOT MET: no configuration within tol {self.tol:g}; returned the most accurate, "
                f"{ch} | {metric} > tol {self.tol:g} | expected speedup over the input {sp} | "
                f"dtype {np.dtype(self.dtype).name}")

    def __str__(self):
        L = [f"simplify({self.input_model.describe()}, tol={self.tol:g}, metric={self.metric!r}, seed={self.seed}"
             + (f", allow={self.allow!r}" if self.allow else "") + ")",
             f"  chosen: {self.summary()}",
             f"  errors vs the input model (float64): max {self.error['max']:.2e}, p99 {self.error['p99']:.2e}, "
             f"albedo {self.error['albedo']:.2e} (floor {self.floor:.1e})",
             f"  {self.n_within_tol} of {self.n_configurations} configurations within tol; ranked by "
             f"{self.ranked_by}"]
        if not self.within_tol:
            L.insert(1, f"  TOLERANCE NOT MET: the returned model's {self.metric} error {self.error[self.metric]:.2e} "
                        f"> tol {self.tol:g}")
        if self.expected_speedup is not None:
            L.append(f"  expected speedup over the most accurate configuration: {self.expected_speedup:.2f}×")
        if not self.changes:
            L.append("  parameters: unchanged")
        for k, a, b, why in self.changes:
            L.append(f"  - {k}: {a} -> {b}: {why}")
        for k, why in self.kept:
            L.append(f"  - {k} kept: {why}")
        for k, v in self.fixed:
            L.append(f"  - {k}={v} kept: a modelling choice (pass allow=({k!r},) to let simplify change it)")
        L += [f"  note: {x}" for x in self.notes]
        L.append(f"  model: {self.model!r}, call with {np.dtype(self.dtype).name} directions")
        return "\n".join(L)

    def _repr_markdown_(self):
        return "```\n" + str(self) + "\n```"


def _input_label(model, spec) -> str:
    if spec.name == "precision":
        return "float64"
    v = model._params[spec.param]
    if spec.lobe:
        return "keep"
    return _label(v)


def _param_text(v) -> str:
    if isinstance(v, np.ndarray):
        return _label(v)
    return repr(v) if isinstance(v, str) else str(v)


def _same_value(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return a is not None and b is not None and np.array_equal(np.asarray(a), np.asarray(b))
    return type(a) is type(b) and a == b


def simplify(model, tol, metric: str | None = None, directions=None, seed: int = 0, *, n: int | None = None,
             n_albedo: int | None = None, costs: dict | None = None, allow=(), margin: float | None = None,
             families=None, progress=None, n_texels: int = 16):
    """The cheapest configuration of ``model`` whose error against ``model`` itself (called in
    float64) is <= ``tol``.

    A textured model (``bk.Texture`` parameters) is measured at ``n_texels`` texels (uv on a
    jittered grid; each texel's model against itself) and gets the cheapest configuration within
    tol at every one of them; a lobe whose texture is negligible there is dropped
    (``bsdfkit.tuning.textured``).

    The reference is the user's model as given. Approximation knobs (precision, Schlick/F82
    versus exact Fresnel, Filament's fast visibility, DFG table size, dropping a negligible lobe)
    may move in either direction; modelling knobs (masking, Lambert versus Burley, f90 rule, energy
    compensation, ...: which material it is) keep the input's setting unless named in ``allow``,
    e.g. ``allow=("diffuse",)``. Every parameter that differs between input and output is listed
    in ``report.changes`` (empty: the model comes back unchanged). Errors are measured on
    ``directions``; float32 configurations on float32 directions, so ``report.dtype`` is the
    precision to call the result with. A lobe whose removal stays within ``tol`` is dropped (a
    FilamentStandard with clear_coat 0.001 gets clear_coat 0 and the compiled variant without the
    coat).

    "Cheapest" is ranked by the shipped cost table (bench/tradeoff.py), not by a timing taken
    now, so the result is deterministic for a given seed: among the configurations within tol
    that cost at most (1 + ``COST_RESOLUTION``) x the cheapest one, the one dropping the most
    lobes, then the one changing the fewest knobs of the input (so a simplified model simplifies
    to itself), then the one closest to the input; configurations missing from the table count as
    costing as much as the most accurate one, and a family without a table is ranked by registry
    order (most knobs at cheaper settings). ``tol = 0`` returns the input unchanged (float64).

    A model with a non-constant ``bsdfkit.Spectrum`` parameter also has the ``color`` knob
    (``"spectral"``, the reference, or ``"rgb"``; a property of the call like precision): its error
    is RGB mode's f |cos| against spectral mode's, both in linear sRGB under a D65 white furnace
    (``bsdfkit.tuning.errors.color_weights``); ``report.config["color"]`` says which mode to call.

    Stochastic models (``model.exact_eval`` False: CoatedDiffuse, CoatedConductor): the reference
    is the input's converged walk (n_samples = 256, max_depth = 100, another realization), the
    default metric is ``"rms"`` (relative RMS of f |cos theta_i|, noise and bias together; see
    :func:`tradeoff`) with ``margin`` 0.8 (an RMS over hundreds of pairs is a stable statistic),
    and the default set is 512 pairs. The input itself is a candidate only if its own error is
    within tol; when no configuration is (tol below what n_samples = 64 reaches), the most
    accurate configuration is returned, ``report.within_tol`` is False, ``report.n_within_tol``
    is 0, ``summary()`` starts with "TOLERANCE NOT MET", ``notes`` extrapolates the n_samples that
    would reach it, and a :class:`ToleranceNotMetWarning` is issued. The answer to "how many samples
    does this car paint need for 2 % error" is ``report.config["n_samples"]``, with its measured
    error in ``report.error["rms"]``. Caveat: the relative RMS is normalized by mean(v_ref^2),
    which a pair on a narrow coat highlight (alpha <~ 0.05; deterministic and 1e3 x brighter)
    dominates when the set happens to contain one: for such materials the figure varies by a
    factor of several between direction sets (car paint, alpha 0.02: 0.07 on simplify's 512
    stratified pairs, 0.009 on 400 uniform pairs with one highlight pair, same n_samples = 64).

    Parameters
    ----------
    model : BxDF
        The model to simplify (the reference).
    tol : float
        The tolerance, >= 0 (inf allowed), in the unit of ``metric``.
    metric : {"p99", "max", "albedo", "rms"}, optional
        ``"p99"`` (the default for deterministic models: the 99th percentile of the relative
        error of f |cos theta_i|), ``"max"`` (its maximum), ``"albedo"`` (absolute
        directional-albedo error) or ``"rms"`` (the default for stochastic models, above);
        definitions in the module docstring, one-line descriptions in ``METRIC_DESCRIPTIONS``;
        ``report.metric`` names the one used.
    directions : DirectionSet or tuple, optional
        As :func:`tradeoff`'s (default: :func:`direction_set` of ``n`` rows drawn with ``seed``).
    seed : int, optional
        Seed of the default direction set.
    n, n_albedo : int, optional
        Rows of the default direction set and albedo samples per wo, as :func:`tradeoff`'s.
    costs : dict, optional
        A cost table in the :func:`knob_costs` format (e.g. ``bench/tradeoff.py`` run on another
        machine) to rank by instead of the shipped one.
    allow : tuple of str, optional
        Modelling knobs that may change (default none).
    margin : float, optional
        A configuration is accepted when its error on the measuring direction set is
        <= ``margin * tol`` (default 0.5; 0.8 for ``"rms"``), in (0, 1]. The p99 (or max) over a
        few thousand directions is itself an estimate: an error measured at 0.94 tol was seen at
        1.55 tol on another direction set (a Filament sheen + coat material with fast visibility),
        so the factor keeps the error on directions simplify never saw within ``tol``.
        ``margin=1`` accepts up to tol exactly.
    families : sequence of type, optional
        Model classes (e.g. ``(bk.Diffuse, bk.Conductor, bk.FilamentStandard)``): instead of
        configurations of ``model``, fit each family to it and return the cheapest fitted model
        within ``tol`` (``bsdfkit.fitting.simplify_families``: measured -> analytic).
    progress : bool or callable, optional
        As in :func:`tradeoff` (one step per configuration measured).
    n_texels : int, optional
        A textured model: the number of texels measured (default 16).

    Returns
    -------
    model : BxDF
        The simplified model (call it with ``report.dtype`` directions).
    report : SimplifyReport
        What was chosen, its measured error, the changes, and whether ``tol`` was met.

    Raises
    ------
    ValueError
        A bad ``tol``, ``metric`` or ``margin`` (named).
    TypeError
        A ``tol`` that is not a real number.

    Warns
    -----
    ToleranceNotMetWarning
        When no configuration meets ``tol``.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m, report = bk.simplify(bk.Conductor.from_metal("Cu", alpha=0.3), 0.02, n=512, n_albedo=64)
    >>> report.within_tol, report.metric, report.dtype.__name__
    (True, 'p99', 'float32')
    """
    if families is not None:  # measured -> analytic (bsdfkit.fitting; one hook)
        from ..fitting.simplify import simplify_families
        return simplify_families(model, tol, families, metric="p99" if metric is None else metric, directions=directions, seed=seed, costs=costs,
                                 **({} if n is None else {"n": n}))
    from ..models.textured import Textured
    textured = isinstance(model, Textured)
    probe = model.at([0.5, 0.5]) if textured else model   # one texel: the model's knobs and defaults
    if not textured:
        _check_model(model)
    tol = _check_tol(tol)
    sto = _any_stochastic(probe)
    if metric is None:
        metric = "rms" if sto else "p99"
    if margin is None:
        margin = 0.8 if metric == "rms" else 0.5
    n, n_albedo = _stochastic_defaults(sto, n, n_albedo, is_stochastic(probe))
    col = _check_metric(metric)
    allowed = _check_allow(probe, allow)
    seed, n, n_albedo = _check_int(seed, "seed", 0), _check_int(n, "n", 16), _check_int(n_albedo, "n_albedo", 16)
    table = _check_costs(costs)
    if isinstance(margin, bool) or not isinstance(margin, (int, float)) or not 0 < margin <= 1:
        raise ValueError(f"margin: must be a number in (0, 1], got {margin!r}")
    if textured:
        from .textured import simplify_textured
        return simplify_textured(model, tol, metric, col, margin, directions, seed, n, n_albedo, allow, costs,
                                 check_progress(progress), _check_int(n_texels, "n_texels", 1))
    ev = _Evaluation(model, directions, n, seed, n_albedo, allow=allowed, reference="input",
                     progress=check_progress(progress), what="simplify")
    costs = _costs_for(model, ev.configs, table)
    ref_i = next(i for i, c in enumerate(ev.configs) if c is ev.reference)
    cands = [i for i, e in enumerate(ev.errors) if e[col] <= margin * tol] if tol > 0 else [ref_i]
    none_within = not cands
    if none_within:   # stochastic input: even the most accurate configuration misses tol
        cands = [0]   # configurations()[0]: every knob at its most accurate setting
    best, ranked_by = _pick(cands, costs, ev.configs, [e[col] for e in ev.errors], ev.reference)
    cfg, err = ev.configs[best], ev.errors[best]
    # explanations: each knob's error alone (the input with only that knob changed)
    single = {}
    for i, c in enumerate(ev.configs):
        r = ev.reference   # moot knobs (label None) are not changes
        diff = {k: c.labels[k] for k in c.labels if c.labels[k] is not None and r.labels[k] is not None
                and c.index[k] != r.index[k]}
        if len(diff) == 1:
            (k, lab), = diff.items()
            single[(k, lab)] = ev.errors[i][col]
    specs = _specs(model, allowed)
    knob_of = {s.param: s for s in specs if s.param is not None}
    changes, kept, notes = [], [], []
    for k, before in model._params.items():
        after = cfg.model._params[k]
        if _same_value(before, after):
            continue
        s = knob_of.get(k)
        lab = cfg.labels.get(s.name) if s is not None else None
        alone = single.get((s.name, lab)) if s is not None else None
        why = (f"{metric} error of this change alone {alone:.2e} <= {margin:g} tol" if alone is not None
               else "part of the cheapest configuration within tol")
        if s is not None and s.lobe:
            why += "; the model gets the compiled variant without this lobe"
        if s is not None and s.kind == "modelling":
            why += " (modelling choice, allowed)"
        changes.append((k, _param_text(before), _param_text(after), why))
    if cfg.dtype is np.float32:
        alone = single.get(("precision", "float32"))
        changes.append(("precision", "float64", "float32",
                        f"{metric} error of float32 alone {alone:.2e} <= {margin:g} tol" if alone is not None
                        else "part of the cheapest configuration within tol"))
    if cfg.spectral != ev.reference.spectral and "color" in cfg.labels:
        # the colour mode is a property of the call, like precision: say which mode to call in
        alone = single.get(("color", cfg.labels["color"]))
        changes.append(("color", ev.reference.labels["color"], cfg.labels["color"],
                        f"{metric} error of {cfg.labels['color']} mode alone {alone:.2e} <= {margin:g} tol "
                        "(linear sRGB under a D65 white furnace)" if alone is not None
                        else "part of the cheapest configuration within tol"))
    for s in specs:
        lab = cfg.labels[s.name]
        if lab is None or s.name == "precision" or len(s.settings) < 2:
            continue
        i_in = ev.reference.index[s.name]
        if cfg.index[s.name] == i_in and i_in < len(s.settings) - 1:
            errs = [(lab2, single[(s.name, lab2)]) for lab2 in s.labels[i_in + 1:] if (s.name, lab2) in single]
            if errs:
                lab2, e2 = min(errs, key=lambda t: t[1])
                kept.append((s.name, f"cheaper {lab2!r} alone has {metric} error {e2:.2e}" +
                             (f" > {margin:g} tol" if e2 > margin * tol else " (within tol, but not in the cheapest configuration)")))
    fixed = [(d.name, _param_text(model._params[d.keyword])) for d in type(model).knobs
             if d.kind == "modelling" and d.name not in allowed]
    if tol == 0:
        notes.append("tol = 0: the input, unchanged")
    if none_within:
        notes.append(f"no configuration has {metric} error <= {margin:g} tol; the most accurate one is returned "
                     f"({metric} error {err[col]:.2e})")
        ns = cfg.model._params.get("n_samples")
        if metric == "rms" and err.get("noise") and ns:
            room = (margin * tol) ** 2 - (err["bias"] or 0.0) ** 2 - (ev.reference_noise or 0.0) ** 2
            if room > 0:
                need = int(math.ceil(ns * err["noise"] ** 2 / room))
                notes.append(f"noise falls as 1/sqrt(n_samples): about n_samples={need} would reach {margin:g} tol "
                             f"(extrapolated from noise {err['noise']:.2e} at n_samples={ns}; not measured)")
            else:
                notes.append("the bias plus the reference's own noise already exceed the tolerance: more samples "
                             "alone do not reach it")
    if ev.converged is not None:
        notes.append(f"errors against the converged walk (n_samples=256, max_depth=100): {metric} "
                     f"{err[col]:.2e} = noise {err['noise']:.2e} + bias {err['bias']:.2e} + the reference's own "
                     f"noise {ev.reference_noise:.2e} (in quadrature)")
    ref_cost = costs[0]
    exp = None if costs[best] is None or ref_cost is None else ref_cost / costs[best]
    vs_in = None
    if costs[ref_i] is not None and costs[best] is not None:
        vs_in = costs[ref_i] / costs[best]
    report = SimplifyReport(
        input_model=model, model=cfg.model, dtype=cfg.dtype, config=dict(cfg.labels), changes=changes, kept=kept,
        error=_error_dict(err, ev.stochastic or metric == "rms", ev.stochastic), tol=tol, metric=metric, expected_speedup=exp,
        speedup_vs_input=vs_in, ranked_by=ranked_by, reference=model, description=cfg.describe(),
        n_configurations=len(ev.configs), n_within_tol=0 if none_within else len(cands), seed=seed,
        floor=ev.floor, notes=notes, fixed=fixed, allow=tuple(sorted(allowed)), within_tol=bool(err[col] <= tol))
    if not report.within_tol:
        warnings.warn(f"simplify: tolerance not met: no configuration of {model.describe()} has {metric} error "
                      f"<= {tol:g}; the most accurate one is returned with {metric} error {err[col]:.2e} "
                      "(report.within_tol is False)", ToleranceNotMetWarning, stacklevel=2)
    return cfg.model, report


def _error_dict(err, with_rms, with_noise) -> dict:
    out = {k: err[v] for k, v in METRICS.items() if k != "rms" or with_rms}
    if with_noise:
        out.update(noise=err["noise"], bias=err["bias"])
    return out


def _input_config(model, configs):
    """Index of the configuration equal to the input model called in float64, if reachable."""
    for i, c in enumerate(configs):
        if c.dtype is np.float64 and c.model == model:
            return i
    return None
