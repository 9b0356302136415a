#!/usr/bin/env python3
"""Speed versus accuracy of every knob configuration, per model family.

    python bench/tradeoff.py            # N = 2^18 pairs per timing call; > 18 min with the stochastic layered family
    python bench/tradeoff.py --quick    # N = 2^15, one round: a smoke run (does not overwrite the costs)

Writes bench/TRADEOFF.md (per model: the full table, the Pareto front and the headline speedups of
bsdfkit.simplify at tol = 1e-2, 1e-3, 1e-4) and python/bsdfkit/tuning/_knob_costs.json (the cost table
bsdfkit.simplify ranks by; --costs-out to write it elsewhere, --quick writes none unless given).

Method
* One representative instance per cost family (bsdfkit.tuning.family: the class plus the
  structural variant that selects a compiled kernel), chosen so that every knob is reachable.
* Errors: bsdfkit.tuning.tradeoff (measure=False), i.e. the package's own definition (relative error of
  f |cos theta_i| with the albedo floor, p99 / max, directional-albedo error), seed 0.
* Throughput: the timed operation is eval with a preallocated out= (sample with preallocated
  outputs for models made only of delta lobes), on N uniform pairs, single-threaded by default
  (--threads): the knobs change per-element arithmetic, and one thread is what stays measurable
  on a shared 2-core machine (a 2-thread kernel waits for its slower thread whenever another
  process holds a core). Each configuration is timed right after the most accurate configuration
  of its family (best of --repeats each), in --rounds interleaved rounds; the cost of a
  configuration is its best time over the run divided by the reference's best time over the same
  run (same-run ratios; a load spike during one timing cannot set a ratio). Before each
  (reference, configuration) pair the bench waits (bounded) until other processes use less than
  0.3 cores.
* Headline: bsdfkit.simplify(model, tol, metric="p99", seed=0) ranked by the cost table written
  by this same run; the speedup shown is the measured one of the chosen configuration.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _host import QUIET, machine_info, wait_quiet  # noqa: E402  (same directory: same timing rules)

import bsdfkit as bk  # noqa: E402
from bsdfkit.tuning import best_time as _best_time, configurations, family, simplify, tradeoff  # noqa: E402
from bsdfkit.tuning.costs import _op, _timed_call, _timing_inputs, cost_deviations, knob_costs  # noqa: E402
from bsdfkit.tuning.report import _pareto_mask  # noqa: E402

SEED = 0
TOLS = (1e-2, 1e-3, 1e-4)


def representatives():
    """(label, model) per cost family, from the model registry: of the registered examples of a
    family (``model.cost_family()``), the one with the most reachable knobs (ties: the first)."""
    from bsdfkit.models import registry
    from bsdfkit.models.spec import parse_spec

    best = {}
    for cls, label, spec in registry.examples():
        m = parse_spec(spec)
        reach = sum(k.reachable for k in bk.knobs(m))
        fam = m.cost_family()
        if fam not in best or reach > best[fam][0]:
            best[fam] = (reach, f"{cls.__name__} {label}", m)
    return [(label, m) for _, label, m in best.values()]


def extra_models():
    """Further materials for the headline table only (ranked with the families' costs)."""
    ex = bk.filament.examples()
    return [
        ("Conductor Al, αx 0.4 αy 0.05 (anisotropic)", bk.Conductor.from_metal("Al", alpha_x=0.4, alpha_y=0.05)),
        ("Conductor Cu, α = 0.05", bk.Conductor.from_metal("Cu", alpha=0.05)),
        ("FilamentStandard defaults (plastic, reflectance 0.5)", ex["plastic (defaults)"]),
        ("FilamentStandard gold, rough", ex["gold, rough"]),
        ("FilamentStandard car paint (coat)", ex["car paint (clear coat over blue metal)"]),
        ("FilamentStandard satin (sheen)", ex["satin (sheen)"]),
        ("FilamentStandard clear_coat = 0.001, sheen 2e-4 (lobe dropping)",
         bk.FilamentStandard([0.8, 0.5, 0.3], clear_coat=0.001, sheen_color=2e-4, sheen_roughness=0.5)),
    ]


def measure_family(model, n, repeats, rounds, only=None, ref_n=None):
    """Best times per pair {config key: t / pairs}: every configuration timed right after the
    most accurate one, in `rounds` interleaved rounds; the reference's entry is its best over all
    its timings. only: time only the configurations whose key contains this text (and the
    reference); ref_n: pairs of the reference's timing call (default n; fewer bound a slow
    reference, e.g. the 64-sample random walk of a stochastic layered model)."""
    cfgs = configurations(model)
    if only:
        cfgs = [cfgs[0]] + [c for c in cfgs[1:] if only in c.key]
    op = _op(model)
    ref_n = ref_n or n
    inputs = _timing_inputs(model, n, SEED)
    calls = [_timed_call(c, op, inputs) for c in cfgs]
    if ref_n != n:
        calls[0] = _timed_call(cfgs[0], op, _timing_inputs(model, ref_n, SEED))
    best = {c.key: math.inf for c in cfgs}
    for _ in range(rounds):
        for c, call in zip(cfgs, calls):
            wait_quiet(max_wait=2.0)
            tr = _best_time(calls[0], repeats) / ref_n
            best[cfgs[0].key] = min(best[cfgs[0].key], tr)
            if call is not calls[0]:
                best[c.key] = min(best[c.key], _best_time(call, repeats) / n)
    return op, cfgs, best


def check(args) -> int:
    """--check: the shipped cost table against a fresh single-threaded timing of every family."""
    bk.set_num_threads(args.threads)
    n = args.n or 2**15
    shipped = knob_costs()
    measured = {}
    for label, model in representatives():
        fam = family(model)
        if args.families and fam not in args.families.split(","):
            continue
        _, cfgs, best = measure_family(model, n, args.repeats, args.rounds or 2, args.configs, args.ref_n)
        ref = best[cfgs[0].key]
        measured[fam] = {k: t / ref for k, t in best.items()}
    bad = cost_deviations(shipped, measured, tol=0.5)
    for fam, key, want, got in bad:
        print(f"STALE {fam} {key}: table {want:.3f}, measured {got:.3f} ({got / want:.2f}x)")
    print(f"{len(bad)} stale cost entr{'y' if len(bad) == 1 else 'ies'} of "
          f"{sum(len(v) for v in measured.values())} checked (tolerance 50 %)")
    return 1 if bad else 0


def fmt_e(x):
    return "0" if x == 0 else f"{x:.1e}"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="N = 2^15, 1 round, smaller error sets (smoke run)")
    ap.add_argument("--n", type=int, default=None, help="pairs per timing call (default 2^18; quick 2^15)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1,
                    help="threads of the timed kernels (default 1: per-element cost, robust to other processes "
                         "on a shared machine; the relative costs of compute-bound kernels do not depend on it)")
    ap.add_argument("--rounds", type=int, default=None, help="interleaved rounds (default 2; quick 1)")
    ap.add_argument("--out", default=None,
                    help="report path (default bench/TRADEOFF.md; with --families no report unless given)")
    ap.add_argument("--costs-out", default=None,
                    help="cost table path (default python/bsdfkit/tuning/_knob_costs.json; none with --quick)")
    ap.add_argument("--families", default=None,
                    help="comma-separated subset of family names (their cost-table entries are replaced, the others kept)")
    ap.add_argument("--configs", default=None,
                    help="time only the configurations whose key contains this text (and the reference), e.g. "
                         "method=analytic; the others keep no entry (bsdfkit.tuning falls back to the model's cost "
                         "model for them, where it has one); skips the error tables (no report)")
    ap.add_argument("--ref-n", type=int, default=None,
                    help="pairs of the reference's timing calls (default --n): a slow reference (the 64-sample "
                         "random walk of the stochastic layered models) timed on fewer pairs; costs are per pair")
    ap.add_argument("--check", action="store_true",
                    help="only re-time every family and compare with the shipped cost table: exit status 1 if an "
                         "entry is off by more than 50 %% (a kernel change made it stale); writes nothing")
    args = ap.parse_args()
    if args.check:
        return check(args)
    n = args.n or (2**15 if args.quick else 2**18)
    rounds = args.rounds or (1 if args.quick else 3)
    n_err = 4096 if args.quick else 8192
    costs_out = args.costs_out or (None if args.quick else str(HERE.parent / "python" / "bsdfkit" / "tuning" / "_knob_costs.json"))
    t_start = time.perf_counter()
    info = machine_info()
    bk.set_num_threads(args.threads)
    info["threads"] = bk.get_num_threads()
    try:
        info["uptime_start"] = open("/proc/loadavg").read().strip()
    except OSError:
        pass
    reps = representatives()
    if args.families:
        want = set(args.families.split(","))
        reps = [(l, m) for l, m in reps if family(m) in want]
    print(f"[tradeoff] {info['cpu']}, {info['threads']} threads, N = {n:,}, rounds {rounds}", flush=True)

    results, families = [], {}
    for label, m in reps:
        t0 = time.perf_counter()
        # errors (and DFG tables built); not with --configs (a subset: costs only, no report)
        table = None if args.configs else tradeoff(m, n=n_err, seed=SEED, measure=False)
        op, cfgs, best = measure_family(m, n, args.repeats, rounds, args.configs, args.ref_n)
        t_ref = best[cfgs[0].key]
        cost = {c.key: best[c.key] / t_ref for c in cfgs}
        families[family(m)] = {"op": op, "representative": repr(m), "label": label, "costs": cost,
                               "reference_rate_per_s": 1.0 / t_ref}
        if args.configs:
            families[family(m)]["timed"] = {"configs": args.configs, "n": n, "reference_n": args.ref_n or n}
            print(f"[tradeoff] {family(m):28s} " + "  ".join(f"{k}: {v:.4g}" for k, v in cost.items()
                                                          if k != cfgs[0].key), flush=True)
            continue
        rows = table.to_records()
        for r, c in zip(rows, cfgs):
            r["evals_per_s"] = 1.0 / best[c.key]
            r["speedup"] = t_ref / best[c.key]
        results.append({"label": label, "model": m, "family": family(m), "table": table, "rows": rows, "op": op})
        print(f"[tradeoff] {family(m):28s} {len(cfgs):4d} configurations  {time.perf_counter() - t0:6.1f} s",
              flush=True)

    info["load_avg_end"] = os.getloadavg()
    try:
        info["uptime_end"] = open("/proc/loadavg").read().strip()
    except OSError:
        pass
    info["quiet_wait"] = {"waited_s": QUIET["waited_s"], "max_busy_cores_other": max(QUIET["busy_samples"] or [0]),
                          "pairs_with_busy_gt_0.3": sum(b > 0.3 for b in QUIET["busy_samples"]),
                          "pairs": len(QUIET["busy_samples"])}
    cost_table = {"schema": 1, "generated_by": "bench/tradeoff.py", "date": info["date"],
                  "machine": {k: info.get(k) for k in ("cpu", "nproc", "simd", "threads", "platform")},
                  "settings": {"n": n, "repeats": args.repeats, "rounds": rounds, "seed": SEED},
                  "note": "cost = time of the configuration / time of the family's most accurate configuration, "
                          "timed back to back (op: eval with out=, or sample for delta-only models)",
                  "families": families}
    if costs_out and args.families and Path(costs_out).exists():
        # a subset re-timed: those families replace their entries, the others keep theirs
        merged = json.loads(Path(costs_out).read_text())
        for fam, entry in families.items():
            entry["date"] = info["date"]
        merged["families"].update(families)
        merged.setdefault("partial_updates", []).append({"date": info["date"], "families": sorted(families),
                                                         "machine": cost_table["machine"]})
        cost_table = merged
    if costs_out:
        Path(costs_out).write_text(json.dumps(cost_table, indent=1, sort_keys=False) + "\n")
        print(f"[tradeoff] wrote {costs_out}", flush=True)

    out = args.out or (None if args.families else str(HERE / "TRADEOFF.md"))
    if args.configs:
        out = None
    if out is None:
        print(f"[tradeoff] --families: report not written (give --out for one) "
              f"({time.perf_counter() - t_start:.0f} s)", flush=True)
        return 0
    # headline: simplify ranked by this run's table; measured speedup of the chosen configuration
    headline = []
    live = {r["family"]: {c.key: row for c, row in zip(r["table"].configs, r["rows"])} for r in results}
    for label, m in [(r["label"], r["model"]) for r in results] + extra_models():
        row = {"label": label, "family": family(m)}
        for tol in TOLS:
            mm, rep = simplify(m, tol, seed=SEED, n=n_err, costs=cost_table)
            key = next(c.key for c in configurations(m) if c.model == mm and c.dtype is rep.dtype)
            meas = live.get(family(m), {}).get(key) if any(r["model"] == m for r in results) else None
            row[tol] = {"config": _short(rep), "p99": rep.error["p99"], "expected": rep.expected_speedup,
                        "measured": None if meas is None else meas["speedup"]}
        headline.append(row)
    elapsed = time.perf_counter() - t_start
    write_md(out, info, results, headline, n, rounds, args.repeats, n_err, elapsed, costs_out)
    print(f"[tradeoff] wrote {out} ({elapsed:.0f} s)", flush=True)


def _short(rep):
    ch = [f"{k}={v}" for k, a, v, _ in rep.changes if v is not None]
    return ", ".join(ch) if ch else "unchanged"


def _fmt_speed(x):
    return "—" if x is None else f"{x:.2f}×"


def write_md(path, info, results, headline, n, rounds, repeats, n_err, elapsed, costs_out):
    L = []
    w = L.append
    w("# Speed versus accuracy: every knob configuration\n")
    w(f"Generated by `python bench/tradeoff.py` on {info['date']} (wall time {elapsed:.0f} s). "
      f"Timing: N = {n:,} pairs per call, {info['threads']} threads, best of {repeats} × {rounds} interleaved rounds, "
      f"each configuration right after its family's most accurate configuration; speedup = best time of the most "
      f"accurate configuration over the run / best time of the configuration. Errors: `bsdfkit.tradeoff` on "
      f"{n_err} direction pairs (seed {SEED}) — see `bsdfkit/tradeoff.py` for the definitions.\n")
    q = info["quiet_wait"]
    w(f"- CPU: {info['cpu']} (`nproc` = {info['nproc']}); `/proc/loadavg` at start `{info.get('uptime_start')}`, at "
      f"end `{info.get('uptime_end')}`; other processes used up to {q['max_busy_cores_other']:.2f} cores before a "
      f"timed pair ({q['pairs_with_busy_gt_0.3']} of {q['pairs']} pairs started with > 0.3 cores busy elsewhere, "
      f"after waiting up to 2 s each)")
    w(f"- Python {info['python']}, numpy {info['numpy']}, bsdfkit {info['bsdfkit']}")
    if costs_out:
        w(f"- Cost table written to `{os.path.relpath(costs_out, HERE.parent)}` (what `bsdfkit.simplify` ranks by)")
    w("")
    w("Columns: **speedup** = time of the most accurate configuration / time of this one, measured back to back "
      "in this run (> 1: faster); **max / p99** = relative error of f·|cos θi| (floor 1e-3 × mean albedo / π); "
      "**albedo** = largest absolute directional-albedo difference. float32 rows were run on float32 directions.\n")

    w("## Headline: `bsdfkit.simplify(model, tol)` (metric p99)\n")
    w("Speedup of the configuration simplify picks over the most accurate configuration: measured in this run "
      "(family representatives) / expected from the cost table (every model).\n")
    w("| model | tol 1e-2 | tol 1e-3 | tol 1e-4 |")
    w("|---|---|---|---|")
    for h in headline:
        cells = []
        for tol in TOLS:
            c = h[tol]
            sp = _fmt_speed(c["measured"]) if c["measured"] is not None else f"exp. {_fmt_speed(c['expected'])}"
            cells.append(f"**{sp}** ({c['config']}; p99 {fmt_e(c['p99'])})")
        w(f"| {h['label']} | " + " | ".join(cells) + " |")
    w("")

    for r in results:
        rows, op = r["rows"], r["op"]
        knob_cols = [k.name for k in r["table"].knobs if k.reachable and k.name != "precision"]
        w(f"## {r['label']} — `{r['family']}`\n")
        w(f"`{r['model']!r}`; timed op: `{op}`; {len(rows)} configurations; reference "
          f"{rows[0]['evals_per_s'] / 1e6:.1f} M/s.\n")
        thr = np.array([x["speedup"] for x in rows])
        err = np.array([x["p99_err"] for x in rows])
        on_front = _pareto_mask(err, thr)
        front = [i for i in np.argsort(err, kind="stable") if on_front[i]]
        w("**Pareto front** (measured speedup vs p99 error):\n")
        w("| configuration | dtype | speedup | max | p99 | albedo |")
        w("|---|---|--:|--:|--:|--:|")
        for i in front:
            x = rows[i]
            w(f"| {x['config']} | {x['dtype']} | {x['speedup']:.2f}× | {fmt_e(x['max_err'])} | "
              f"{fmt_e(x['p99_err'])} | {fmt_e(x['albedo_err'])} |")
        w("")
        w(f"<details><summary>Full table ({len(rows)} configurations)</summary>\n")
        w("| " + "".join(f"{k} | " for k in knob_cols) + "dtype | M/s | speedup | max | p99 | albedo |")
        w("|" + "---|" * len(knob_cols) + "---|--:|--:|--:|--:|--:|")
        for x in rows:
            w("| " + "".join(f"{x[k]} | " for k in knob_cols) + f"{x['dtype']} | {x['evals_per_s'] / 1e6:.1f} | "
              f"{x['speedup']:.2f}× | {fmt_e(x['max_err'])} | {fmt_e(x['p99_err'])} | {fmt_e(x['albedo_err'])} |")
        w("\n</details>\n")
    Path(path).write_text("\n".join(L) + "\n")


if __name__ == "__main__":
    sys.exit(main())
