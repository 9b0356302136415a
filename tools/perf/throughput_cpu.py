#!/usr/bin/env python3
"""Kernel-to-kernel throughput in CPU time, for a LOADED machine: bsdfkit's array kernels (one thread) and
Mitsuba 3 llvm_ad_rgb's (dr.set_thread_count(1)), each timed by the CPU time its process consumed
(time.process_time, all threads), so that time spent descheduled by other processes does not count.
Cache and memory-bandwidth contention still do: give the results as ratios from one run.

    python tools/perf/throughput_cpu.py --python /work/venv/main/bin/python --python /work/venv/perf/bin/python

runs Mitsuba once and bsdfkit under each given interpreter (e.g. two installs), interleaved, --rounds times,
and prints a Markdown table of M elements per CPU-second with each bsdfkit column's ratio to Mitsuba
(median over rounds, with the min-max spread). Same inputs, models and calls as tools/perf/throughput.py.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import throughput as T  # noqa: E402  (inputs, model configs, Mitsuba harness)
from _machine import cpu_model, simd_flags  # noqa: E402

KEYS = ["diffuse", "cond_rough", "diel_rough"]


def cpu_best(fn, repeats=5, min_cpu=0.05):
    """Min over repeats of the process CPU time per call (calls batched to >= min_cpu)."""
    fn()
    t0 = time.process_time()
    fn()
    one = max(time.process_time() - t0, 1e-6)
    inner = max(1, int(min_cpu / one))
    best = float("inf")
    for _ in range(repeats):
        t0 = time.process_time()
        for _ in range(inner):
            fn()
        best = min(best, (time.process_time() - t0) / inner)
    return best


def side_bk(n, keys, ops, dtypes, threads=1):
    import bsdfkit as bk
    bk.set_num_threads(threads)
    inputs = T.make_inputs(n)
    res = {}
    for key in keys:
        m = T.bk_model(key)
        for op in ops:
            for dt in dtypes:
                kern = T.bk_calls(m, op, inputs[dt], T.CONFIG[key][2])["kernel"]  # out= / preallocated outputs
                res[f"{key}/{op}/{dt}"] = cpu_best(kern)
    return {"results": res, "bsdfkit": bk.__file__}


def side_mi(n, keys, ops, llvm, threads=1):
    mi = T._MiLLVM(llvm)
    mi.set_inputs(n, T.checksum(T.make_inputs(n)))
    mi.dr.set_thread_count(threads)
    res = {}
    for key in keys:
        if T.CONFIG[key][3] is None:  # no Mitsuba counterpart
            continue
        for op in ops:
            res[f"{key}/{op}/float32"] = cpu_best(mi.kernel_fn(n, key, op))
    return {"results": res, "info": mi.info()}


def run_side(python, side, args):
    cmd = [python, __file__, "--_side", side, "--n", str(args.n), "--models", ",".join(args.keys),
           "--threads", str(args.threads)]
    if args.llvm:
        cmd += ["--llvm", args.llvm]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--python", action="append", default=None, help="interpreter with a bsdfkit install (repeatable)")
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--models", default=",".join(KEYS))
    ap.add_argument("--llvm", default=None)
    ap.add_argument("--threads", type=int, default=1, help="threads of both sides (rates stay per CPU-second)")
    ap.add_argument("--_side", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    args.keys = args.models.split(",")
    ops, dtypes = T.OPS, T.DTYPES
    if args._side == "bk":
        print(json.dumps(side_bk(args.n, args.keys, ops, dtypes, args.threads)))
        return
    if args._side == "mi":
        T._setup_drjit_env(args.llvm)
        print(json.dumps(side_mi(args.n, args.keys, ops, args.llvm, args.threads)))
        return
    pythons = args.python or [sys.executable]
    load0 = os.getloadavg()
    runs = {p: [] for p in ["mitsuba"] + pythons}
    files = {}
    for r in range(args.rounds):
        runs["mitsuba"].append(run_side(sys.executable, "mi", args)["results"])
        for p in pythons:
            out = run_side(p, "bk", args)
            files[p] = out["bsdfkit"]
            runs[p].append(out["results"])
        sys.stderr.write(f"[cpu-bench] round {r + 1}/{args.rounds} done\n")
    load1 = os.getloadavg()
    cpu, simd = cpu_model(), ", ".join(f for f in simd_flags() if f != "avx512vl")
    print(f"CPU: {cpu}; SIMD {simd}; {platform.platform()}; load average {load0[0]:.1f} at start, {load1[0]:.1f} at end")
    print(f"N = {args.n:,}, {args.threads} thread(s) each, rates in M elements per CPU-second, median of "
          f"{args.rounds} rounds [min-max]; ratio = bsdfkit / Mitsuba llvm_ad_rgb kernel (float32 Mitsuba kernel for "
          f"both dtypes); last column: the last install / the first, same dtype (rows without Mitsuba: —).")
    for i, p in enumerate(pythons):
        print(f"- bk{i}: {files[p]}")
    last = len(pythons) - 1
    hdr = ("| model | op | dtype | Mitsuba | " + " | ".join(f"bk{i} | bk{i}/Mi" for i in range(len(pythons))) +
           (f" | bk{last}/bk0" if last else "") + " |")
    print(hdr)
    print("|" + "---|" * (3 + 1 + 2 * len(pythons) + (1 if last else 0)))

    def stats(vals):
        v = np.array(vals)
        return np.median(v), v.min(), v.max()

    for key in args.keys:
        has_mi = T.CONFIG[key][3] is not None
        for op in ops:
            for dt in dtypes:
                mi_rates = [args.n / r[f"{key}/{op}/float32"] / 1e6 for r in runs["mitsuba"]] if has_mi else None
                cells = [f"{T.CONFIG[key][1]}", op, dt, f"{stats(mi_rates)[0]:.0f}" if has_mi else "—"]
                per = []
                for p in pythons:
                    rates = [args.n / r[f"{key}/{op}/{dt}"] / 1e6 for r in runs[p]]
                    per.append(rates)
                    bm, _, _ = stats(rates)
                    cells.append(f"{bm:.0f}")
                    if has_mi:
                        rm, rlo, rhi = stats([a / b for a, b in zip(rates, mi_rates)])
                        cells.append(f"{rm:.2f}× [{rlo:.2f}–{rhi:.2f}]")
                    else:
                        cells.append("—")
                if last:
                    rm, rlo, rhi = stats([a / b for a, b in zip(per[last], per[0])])
                    cells.append(f"{rm:.2f}× [{rlo:.2f}–{rhi:.2f}]")
                print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
