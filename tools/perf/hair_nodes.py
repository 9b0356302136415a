#!/usr/bin/env python3
"""Error and cost of the far-field fibre's quadrature order (Hair(h=None, nodes=N)).

    python tools/perf/hair_nodes.py            # prints a markdown table (bench/HAIR.md, "Far field")

Error: bsdfkit.tuning's definition (relative error of f |cos theta_i| per pair and channel with the
albedo floor; p99 and max over the default direction set, n = 8192, seed 0) against the 64-node
rule, per azimuthal roughness beta_n (beta_m = 0.3, alpha = 2, pbrt-v4's brown sigma_a), plus the
error relative to the peak of f |cos| over that set. Cost: eval time of N nodes over one
single-h eval (h = 0.3), 1 thread, float32 and float64, best of 5, timed back to back on the same
arrays (a ratio from one run on a shared, loaded machine).
"""
from __future__ import annotations

import os
import platform
import time

import numpy as np

import bsdfkit as bk
from _machine import cpu_model  # bench/_host.py's
from bsdfkit.tuning import direction_set

NODES = (64, 32, 16, 8, 4)
BETA_N = (0.1, 0.2, 0.3, 0.5)


def best(fn, repeats=5):
    t = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return min(t)


def main():
    bk.set_num_threads(1)
    cpu = cpu_model()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {cpu}, {platform.machine()}, "
          f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs\n")
    print("| beta_n | " + " | ".join(f"{n} nodes p99 / max / max of peak" for n in NODES[1:]) + " |")
    print("|---|" + "---|" * (len(NODES) - 1))
    for bn in BETA_N:
        ref = bk.Hair(h=None, beta_n=bn, nodes=64)
        ds = direction_set(ref, n=8192, seed=0)
        wo, wi = ds.wo, ds.wi
        cos = np.abs(wi[..., 2:3])
        vref = ref.eval(wo, wi) * cos
        t = bk.tradeoff(ref, n=8192, seed=0, measure=False)
        rec = {(r["nodes"], r["dtype"]): r for r in t.to_records()}
        cells = []
        for n in NODES[1:]:
            v = bk.Hair(h=None, beta_n=bn, nodes=n).eval(wo, wi) * cos
            peak = np.abs(v - vref).max() / vref.max()
            r = rec[(str(n), "float64")]
            cells.append(f"{r['p99_err']:.1e} / {r['max_err']:.1e} / {peak:.1e}")
        print(f"| {bn} | " + " | ".join(cells) + " |")
    print()
    rng = np.random.default_rng(0)
    n = 100_000
    for dt in (np.float32, np.float64):
        v = rng.standard_normal((2, n, 3))
        v /= np.linalg.norm(v, axis=-1, keepdims=True)
        wo, wi = v[0].astype(dt), v[1].astype(dt)
        out = np.empty((n, 3), dt)
        one = bk.Hair(h=0.3)
        t1 = best(lambda: one.eval(wo, wi, out=out))
        cells = []
        for k in NODES:
            m = bk.Hair(h=None, nodes=k)
            cells.append(f"{k}: {best(lambda: m.eval(wo, wi, out=out)) / t1:.1f}x")
        print(f"eval cost vs one h, {np.dtype(dt).name}: " + ", ".join(cells))


if __name__ == "__main__":
    main()
