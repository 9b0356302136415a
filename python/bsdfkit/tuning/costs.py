"""Costs: the shipped per-knob cost table and live timing of configurations."""
from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from ..directions import random_directions
from .errors import _all_delta, _is_transmissive
from .configs import Config, family

__all__ = ["knob_costs", "color_costs", "color_ratio", "SPECTRAL_KEY", "COST_RESOLUTION", "best_time", "time_repeats", "spread", "SPREAD_WARN", "cost_deviations"]


_COSTS_CACHE: dict = {}


def knob_costs(path=None) -> dict:
    """The shipped cost table (``bsdfkit/tuning/_knob_costs.json``, written by ``bench/tradeoff.py``).

    Parameters
    ----------
    path : str or os.PathLike, optional
        Read another file (not cached).

    Returns
    -------
    dict
        ``{"families": {family: {"op": ..., "costs": {config key: time / time of the most
        accurate}}}, ...}``; ``{}`` when it is missing.
    """
    if path is None:
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_knob_costs.json")
        if path in _COSTS_CACHE:
            return _COSTS_CACHE[path]
        cache = True
    else:
        cache = False
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except FileNotFoundError:
        data = {}
    if cache:
        _COSTS_CACHE[path] = data
    return data


def _check_costs(costs) -> dict:
    if costs is None:
        return knob_costs()
    if not isinstance(costs, dict):
        raise TypeError(f"costs: expected a cost table dict (see knob_costs()), got {type(costs).__name__}")
    return costs


#: Suffix of a spectral-mode configuration's cost key (configs._key).
SPECTRAL_KEY = ";color=spectral"


def color_costs(path=None) -> dict:
    """The shipped spectral-mode cost table (``bsdfkit/tuning/_color_costs.json``, written by
    ``bench/spectral.py``): ``{"families": {family: {dtype: {"eval": r, "sample": r}}}, "default": r}``
    with r = spectral time / RGB time of the same call; ``{}`` when missing."""
    if path is None:
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_color_costs.json")
    if path not in _COSTS_CACHE:
        _COSTS_CACHE[path] = knob_costs(path)
    return _COSTS_CACHE[path]


def color_ratio(model, dtype, op: str) -> float | None:
    """Spectral / RGB time of ``op`` for ``model``'s family at ``dtype`` (the table's median over
    families when the family was not measured; None without a table)."""
    t = color_costs()
    if not t:
        return None
    row = t.get("families", {}).get(family(model), {}).get(np.dtype(dtype).name, {})
    r = row.get(op)
    return float(r) if r is not None else t.get("default")


def _costs_for(model, configs, costs):
    fam = costs.get("families", {}).get(family(model))
    op = fam.get("op", "eval") if fam else _op(model)
    table = (fam or {}).get("costs", {})

    def rgb_key(c):
        return c.key[:-len(SPECTRAL_KEY)] if c.key.endswith(SPECTRAL_KEY) else c.key

    def spectral(c, base):
        # a spectral-mode configuration: the RGB configuration's cost times the measured ratio
        if base is None or not c.spectral:
            return base
        r = color_ratio(model, c.dtype, op)
        return None if r is None else base * r
    if hasattr(model, "relative_cost") and any(rgb_key(c) not in table for c in configs):
        # a family whose cost follows its knobs (the stochastic layered models: linear in
        # n_samples): the measured entry where the table has one (bench/tradeoff.py --configs
        # times only some, e.g. the analytic method against the reference walk), else the
        # model's own cost model, relative to configs[0]
        c0 = model.relative_cost(configs[0].model._params, configs[0].dtype)
        return [spectral(c, table[rgb_key(c)] if rgb_key(c) in table
                         else model.relative_cost(c.model._params, c.dtype) / c0) for c in configs]
    return [spectral(c, table.get(rgb_key(c))) for c in configs]


#: Relative cost differences below this are measurement noise of the cost table: among the
#: candidates within (1 + COST_RESOLUTION) x the cheapest cost, simplify takes the one that drops
#: the most lobes, then the one that changes the fewest knobs of the input (so that simplifying
#: a simplified model returns it unchanged, rather than trading knobs at equal cost on float32
#: rounding noise in the errors), then the most accurate.
COST_RESOLUTION = 0.05


def _n_changes(c, ref):
    """Knobs whose setting differs between two configurations (moot ones not counted)."""
    return sum(1 for k, lab in c.labels.items()
               if lab is not None and ref.labels.get(k) is not None and c.index[k] != ref.index[k])


def _pick(cands, costs, configs, err, ref):
    """Index of the chosen candidate and how it was ranked (see :func:`simplify`); ref: the
    input's configuration (ties in cost go to the fewest changes from it)."""
    if all(c is None for c in costs):
        def rank(i):   # most knobs at cheaper settings; ties: the most lobes dropped, then the closest
            r = configs[i].registry_rank
            return (r[0], -sum(v == "drop" for v in configs[i].labels.values()), err[i], r[1])
        return min(cands, key=rank), "registry order (no cost table for this family)"
    c = {i: 1.0 if costs[i] is None else float(costs[i]) for i in cands}
    cmin = min(c.values())
    near = [i for i in cands if c[i] <= cmin * (1 + COST_RESOLUTION)]
    drops = {i: sum(v == "drop" for v in configs[i].labels.values()) for i in near}
    moved = {i: _n_changes(configs[i], ref) for i in near}
    best = min(near, key=lambda i: (-drops[i], moved[i], err[i], configs[i].registry_rank))
    return best, "cost table" + (" (this configuration is missing: assumed as costly as the most accurate)"
                                 if costs[best] is None else "")


def time_repeats(fn, repeats=5, min_time=0.005, warmup=1) -> list:
    """Per-call times of ``repeats`` repeats, each the mean of ``inner`` back-to-back calls of
    ``fn`` after ``warmup`` calls; ``inner`` is chosen so that one repeat takes >= ``min_time``
    seconds."""
    for _ in range(warmup):
        fn()
    t0 = time.perf_counter()
    fn()
    dt = time.perf_counter() - t0
    inner = max(1, int(math.ceil(min_time / max(dt, 1e-9)))) if dt < min_time else 1
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        out.append((time.perf_counter() - t0) / inner)
    return out


def best_time(fn, repeats=5, min_time=0.005, warmup=1):
    """Min over ``repeats`` of the mean time of ``inner`` back-to-back calls of ``fn`` after
    ``warmup`` calls (:func:`time_repeats`). Also the timer of ``tools/perf/throughput.py`` and
    ``tools/perf/filament.py``.

    Parameters
    ----------
    fn : callable
        Called without arguments.
    repeats : int, optional
        Repeats; the best is kept.
    min_time : float, optional
        Seconds one repeat lasts at least (``inner`` is chosen for it).
    warmup : int, optional
        Calls before timing.

    Returns
    -------
    float
        Seconds per call.

    Examples
    --------
    >>> from bsdfkit.tuning import best_time
    >>> best_time(lambda: sum(range(100)), repeats=2, min_time=1e-4) > 0
    True
    """
    return min(time_repeats(fn, repeats, min_time, warmup))


def spread(times) -> float:
    """Timing spread of repeats: median / min (1 on a quiet machine; a load spike or a stalled
    thread makes it large)."""
    t = sorted(times)
    return float(np.median(t) / t[0]) if t and t[0] > 0 else math.inf


#: Above this spread (median / min of the repeats) a live timing is reported as unreliable.
SPREAD_WARN = 1.5


def cost_deviations(shipped: dict, measured: dict, tol: float = 0.5) -> list:
    """Entries of a cost table that a fresh measurement contradicts: ``[(family, config key,
    table cost, measured cost)]`` for every entry present in both whose measured relative cost
    differs from the table's by more than ``tol`` (0.5: a factor outside [1/1.5, 1.5]).
    ``shipped``: a :func:`knob_costs` table; ``measured``: ``{family: {config key: cost}}``
    (``bench/tradeoff.py --check`` measures it)."""
    out = []
    fams = shipped.get("families", {})
    for fam, costs in measured.items():
        table = fams.get(fam, {}).get("costs", {})
        for key, got in costs.items():
            want = table.get(key)
            if want is None or not want > 0 or not got > 0:
                continue
            r = got / want
            if r > 1 + tol or r < 1 / (1 + tol):
                out.append((fam, key, float(want), float(got)))
    return out


def _timing_inputs(model, n, seed):
    rng = np.random.default_rng([seed, 0x74696d65])
    d = {"wo": random_directions(n, rng, upper=True),
         "wi": random_directions(n, rng, upper=not _is_transmissive(model)), "uc": rng.random(n),
         "u": rng.random((n, 2))}
    return {"float64": d, "float32": {k: v.astype(np.float32) for k, v in d.items()}}


def _timed_call(cfg: Config, op: str, inputs):
    d = inputs["float64" if cfg.dtype is np.float64 else "float32"]
    n, dt, m = len(d["wo"]), d["wo"].dtype, cfg.model
    if cfg.spectral:   # spectral mode: 4 wavelengths per pair (pbrt-v4's visible sampling)
        from ..spectral import sample_wavelengths
        lam = sample_wavelengths(np.random.default_rng(n).random(n))[0]
        if op == "eval":
            return lambda: m.eval(d["wo"], d["wi"], wavelengths=lam)
        return lambda: m.sample(d["wo"], d["uc"], d["u"], wavelengths=lam)
    if op == "eval":
        out = np.empty((n, 3), dt)
        return lambda: m.eval(d["wo"], d["wi"], out=out)
    bufs = (np.empty((n, 3), dt), np.empty((n, 3), dt), np.empty(n, dt), np.empty(n, np.uint8), np.empty(n, dt),
            np.empty(n, bool), np.empty(n, bool))
    core = m._core
    return lambda: core.sample(d["wo"], d["uc"], d["u"], 0, 3, bufs)


def _op(model) -> str:
    return "sample" if _all_delta(model) else "eval"


#: Wall time (s) the live timing of tradeoff aims at when n_timing is left to its default.
TIMING_BUDGET_S = 15.0
#: Fewest pairs per timed call the budget may reduce n_timing to.
MIN_AUTO_TIMING = 64


def _budgeted_n_timing(configs, op, n_timing, repeats, rounds, seed, budget=TIMING_BUDGET_S):
    """n_timing reduced so that timing every configuration (each call beside a reference call,
    ``repeats`` + 2 calls each, ``rounds`` times) stays within ``budget`` seconds, estimated
    from one call of the most accurate (slowest) configuration; at least MIN_AUTO_TIMING."""
    inputs = _timing_inputs(configs[0].model, n_timing, seed)
    call = _timed_call(configs[0], op, inputs)
    call()
    t0 = time.perf_counter()
    call()
    t = time.perf_counter() - t0
    est = t * len(configs) * 2 * (repeats + 2) * rounds
    if est <= budget:
        return n_timing
    return max(MIN_AUTO_TIMING, int(n_timing * budget / est))


#: Shortest repeat (s) of a budgeted timing (time_repeats' min_time; 5 ms otherwise): 340
#: configurations x 2 x 5 repeats of >= 5 ms alone would take 17 s.
BUDGET_MIN_TIME = 0.001


def _measure(configs, op, n_timing, repeats, rounds, seed, progress=False, min_time=0.005):
    """Live throughput: every configuration timed right after the most accurate one (``repeats``
    repeats each), in ``rounds`` interleaved rounds; returns (evals/s, speedup, spread) lists,
    speedup = smallest reference time of the run / smallest time of the configuration (a load
    spike during one reference timing then cannot inflate a ratio), spread = the larger of the
    configuration's and the reference's :func:`spread` over all its repeats."""
    inputs = _timing_inputs(configs[0].model, n_timing, seed)
    calls = [_timed_call(c, op, inputs) for c in configs]
    ref_times = []
    times = [[] for _ in configs]
    from .._progress import Progress
    prog = Progress(progress, rounds * len(calls), "timing configuration")
    try:
        for r in range(rounds):
            for i, call in enumerate(calls):
                ref_times += time_repeats(calls[0], repeats, min_time)
                if i:
                    times[i] += time_repeats(call, repeats, min_time)
                prog(r * len(calls) + i + 1)
    finally:
        prog.close()
    times[0] = ref_times
    t = [min(x) for x in times]
    t_ref = t[0]
    s_ref = spread(ref_times)
    spreads = [max(s_ref, spread(x)) for x in times]
    return [n_timing / x for x in t], [t_ref / x for x in t], spreads


def _threads():
    from .. import _core
    return _core.get_num_threads()
