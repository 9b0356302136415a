"""Fixed per-call cost of the array API on the smallest input: one direction pair.

Users call ``m.eval(wo, wi)`` in Python loops and widgets, so the cost that does not scale with N
(argument checks, dtype choice, broadcasting, the call into _core, the GIL release) matters.
For each op (eval, pdf, sample with one uniform triple, albedo with 1 sample) this times a
million-ish back-to-back calls on one pair and reports the median over repeats in microseconds,
with the spread (max/min over repeats). Timings on a shared machine are noisy: the ratio against
``numpy.dot`` on the same 3-vectors (a copy-bound floor measured in the same run) is printed too.

``--large N`` (e.g. 1000000) also times the plain call against the compiled kernel with
preallocated outputs (``m._core.eval/pdf/sample(..., out arrays)``, inputs already rows) at N
pairs, interleaved repeat by repeat so load changes hit both alike, and prints the per-repeat
ratio plain / kernel (median and range): the wrapper's cost at large N (issue 17 item 3).

    python tools/perf/overhead.py [--repeats 7] [--model conductor] [--large 1000000] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np

import bsdfkit as bk
from _machine import cpu_model  # same directory
from bsdfkit.tuning.costs import time_repeats


def _per_call(fn, repeats: int, min_time: float = 0.05) -> list:
    """Per-call seconds of ``repeats`` repeats (the package's own timer, tuning.costs.time_repeats)."""
    return time_repeats(fn, repeats=repeats, min_time=min_time)


MODELS = {
    "conductor": lambda: bk.Conductor.from_metal("Cu", alpha=0.3),
    "dielectric": lambda: bk.Dielectric(eta=1.5, alpha=0.3),
    "diffuse": lambda: bk.Diffuse(0.5),
}


def _large(m, n: int, repeats: int) -> dict:
    """Plain call vs kernel with preallocated outputs at n pairs; per-repeat ratios."""
    rng = np.random.default_rng(1)
    wo = bk.direction(theta=np.arccos(rng.uniform(0.05, 1, n)), phi=rng.uniform(0, 2 * np.pi, n))
    wi = bk.direction(theta=np.arccos(rng.uniform(0.05, 1, n)), phi=rng.uniform(0, 2 * np.pi, n))
    uc, u = rng.random(n), rng.random((n, 2))
    core = m._core
    f, p = np.empty((n, 3)), np.empty(n)
    bufs = (np.empty((n, 3)), np.empty((n, 3)), np.empty(n), np.empty(n, np.uint8), np.empty(n), np.empty(n, bool),
            np.empty(n, bool))
    pairs = {
        "eval": (lambda: m.eval(wo, wi), lambda: core.eval(wo, wi, 0, f)),
        "pdf": (lambda: m.pdf(wo, wi), lambda: core.pdf(wo, wi, 0, 3, p)),
        "sample": (lambda: m.sample(wo, uc, u), lambda: core.sample(wo, uc, u, 0, 3, bufs)),
    }
    res = {}
    for name, (plain, kernel) in pairs.items():
        plain(), kernel()  # warm up (and fault in the preallocated outputs)
        tp, tk = [], []
        for _ in range(repeats):
            for fn, acc in ((plain, tp), (kernel, tk)):
                t0 = time.perf_counter()
                r = fn()
                acc.append(time.perf_counter() - t0)
                del r
        ratios = [a / b for a, b in zip(tp, tk)]
        res[name] = {"plain_ms": statistics.median(tp) * 1e3, "kernel_ms": statistics.median(tk) * 1e3,
                     "ratio_median": statistics.median(ratios), "ratio_min": min(ratios), "ratio_max": max(ratios)}
    return res


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--model", default="conductor", choices=sorted(MODELS))
    ap.add_argument("--large", type=int, default=0, help="also compare plain call vs kernel at this N")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    m = MODELS[a.model]()
    wo = bk.direction(theta=np.radians(40), phi=0.0)
    wi = bk.direction(theta=np.radians(30), phi=np.pi)
    uc, u = np.array(0.3), np.array([0.2, 0.7])
    ops = {
        "numpy.dot (floor)": lambda: np.dot(wo, wi),
        "eval": lambda: m.eval(wo, wi),
        "pdf": lambda: m.pdf(wo, wi),
        "sample": lambda: m.sample(wo, uc, u),
        "albedo (1 sample)": lambda: m.albedo(wo, n_samples=1),
    }
    res = {}
    print(f"bsdfkit {bk.__version__} ({bk.__file__}); model {m!r}; threads {bk.get_num_threads()}")
    print(f"CPU {cpu_model()}; load average {os.getloadavg()[0]:.1f} (shared machine: compare ratios)")
    print(f"{'op':20s} {'median µs':>10s} {'min µs':>8s} {'spread':>7s}")
    for name, fn in ops.items():
        ts = _per_call(fn, a.repeats)
        med, lo, hi = statistics.median(ts), min(ts), max(ts)
        res[name] = {"median_us": med * 1e6, "min_us": lo * 1e6, "spread": hi / lo}
        print(f"{name:20s} {med * 1e6:10.2f} {lo * 1e6:8.2f} {hi / lo:7.2f}")
    if a.large:
        print(f"\nN = {a.large}: plain call / kernel with preallocated outputs, {a.repeats} interleaved repeats")
        print(f"{'op':8s} {'plain ms':>9s} {'kernel ms':>9s} {'ratio':>6s} {'range':>12s}")
        big = _large(m, a.large, a.repeats)
        for name, r in big.items():
            print(f"{name:8s} {r['plain_ms']:9.2f} {r['kernel_ms']:9.2f} {r['ratio_median']:6.2f} "
                  f"{r['ratio_min']:5.2f}-{r['ratio_max']:5.2f}")
        res["large"] = {"n": a.large, **big}
        print(f"load average after: {os.getloadavg()[0]:.1f}")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=1)
    return res


if __name__ == "__main__":
    main()
