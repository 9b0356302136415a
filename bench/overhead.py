"""Fixed per-call cost of the array API on the smallest input: one direction pair.

Users call ``m.eval(wo, wi)`` in Python loops and widgets, so the cost that does not scale with N
(argument checks, dtype choice, broadcasting, the call into _core, the GIL release) matters.
For each op (eval, pdf, sample with one uniform triple, albedo with 1 sample) this times a
million-ish back-to-back calls on one pair and reports the median over repeats in microseconds,
with the spread (max/min over repeats). Timings on a shared machine are noisy: the ratio against
``numpy.dot`` on the same 3-vectors (a copy-bound floor measured in the same run) is printed too.

    python bench/overhead.py [--repeats 7] [--model conductor] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np

import bsdfkit as bk


def _per_call(fn, repeats: int, min_time: float = 0.05) -> list:
    fn()
    inner = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        dt = time.perf_counter() - t0
        if dt >= min_time:
            break
        inner *= 2
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        out.append((time.perf_counter() - t0) / inner)
    return out


MODELS = {
    "conductor": lambda: bk.Conductor.from_metal("Cu", alpha=0.3),
    "dielectric": lambda: bk.Dielectric(eta=1.5, alpha=0.3),
    "diffuse": lambda: bk.Diffuse(0.5),
}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--model", default="conductor", choices=sorted(MODELS))
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
    print(f"{'op':20s} {'median µs':>10s} {'min µs':>8s} {'spread':>7s}")
    for name, fn in ops.items():
        ts = _per_call(fn, a.repeats)
        med, lo, hi = statistics.median(ts), min(ts), max(ts)
        res[name] = {"median_us": med * 1e6, "min_us": lo * 1e6, "spread": hi / lo}
        print(f"{name:20s} {med * 1e6:10.2f} {lo * 1e6:8.2f} {hi / lo:7.2f}")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=1)
    return res


if __name__ == "__main__":
    main()
