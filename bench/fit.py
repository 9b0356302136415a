"""bk.fit wall time per family and target size, and bk.fit_many scaling from 1 to 2 Dask workers.

Part 1: each family is fitted to a target of its own family (parameters perturbed for the
start) on n = 512, 2048, 8192 direction pairs; reported: wall time of bk.fit (median of repeats
and spread max/min), residual and Jacobian evaluations, the reached p99 relative error.
Part 2: the same list of targets (Conductor fits to MERL-like analytic metals) through
bk.fit_many on a LocalCluster of 1 and then 2 worker processes (threads_per_worker=1, bsdfkit
kernels at 1 thread per task), cluster start excluded; reported: wall time of each and the ratio
t(1) / t(2), plus the in-process serial time of the same fits (the copy bound: what one worker
would take without Dask's overhead). Times are from a shared machine: ratios within one run.

    python bench/fit.py [--repeats 3] [--targets 16] [--pairs 8192] [--skip-families] [--json bench/fit.json]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np

import bsdfkit as bk
from _host import cpu_model  # same directory

FAMILIES = {
    "Diffuse": (lambda: bk.Diffuse((0.7, 0.4, 0.2)), {"reflectance": (0.5, 0.5, 0.5)}, None),
    "Conductor": (lambda: bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.15),
                  {"eta": (0.4, 0.8, 1.0), "k": (3.0, 2.0, 2.0), "alpha_x": 0.2, "alpha_y": 0.2}, None),
    "Dielectric": (lambda: bk.Dielectric(1.45, alpha=0.25), {"eta": 1.3, "alpha_x": 0.2, "alpha_y": 0.2}, None),
    "FilamentStandard": (lambda: bk.FilamentStandard((0.7, 0.4, 0.2), metallic=0.3, roughness=0.45,
                                                     reflectance=0.6),
                         {"base_color": (0.5, 0.5, 0.5), "metallic": 0.5, "roughness": 0.6, "reflectance": 0.5},
                         ("base_color", "metallic", "roughness", "reflectance")),
    "FilamentCloth": (lambda: bk.FilamentCloth((0.35, 0.1, 0.1), sheen_color=(0.8, 0.5, 0.5), roughness=0.5),
                      {"base_color": (0.5, 0.5, 0.5), "sheen_color": (0.5, 0.5, 0.5), "roughness": 0.7},
                      ("base_color", "sheen_color", "roughness")),
    "CoatedDiffuse (analytic)": (lambda: bk.CoatedDiffuse((0.6, 0.35, 0.15), alpha=0.08, thickness=0.05,
                                                          method="analytic"),
                                 {"reflectance": (0.5, 0.5, 0.5), "eta": 1.4, "alpha": 0.15, "thickness": 0.02},
                                 ("reflectance", "eta", "alpha", "thickness")),
    "CoatedConductor (analytic)": (lambda: bk.CoatedConductor.from_metal("Cu", conductor_alpha=0.3,
                                                                         interface_alpha=0.05, method="analytic"),
                                   {"conductor_eta": (0.3, 0.8, 1.2), "conductor_k": (3.0, 2.5, 2.0),
                                    "conductor_alpha": 0.2, "interface_alpha": 0.1},
                                   ("conductor_eta", "conductor_k", "conductor_alpha", "interface_alpha")),
}
SIZES = (512, 2048, 8192)


def bench_families(repeats):
    res = {}
    print(f"{'family':28s} {'n':>6s} {'time s':>8s} {'spread':>7s} {'nfev':>5s} {'njev':>5s} {'p99 err':>9s}")
    for name, (make, init, params) in FAMILIES.items():
        target = make()
        for n in SIZES:
            ts, rep = [], None
            for _ in range(repeats):
                t0 = time.perf_counter()
                _, rep = bk.fit(target, type(target), params=params, init=init, n=n, albedo=False,
                                fixed={"method": "analytic"} if "method" in target._params else None)
                ts.append(time.perf_counter() - t0)
            med = statistics.median(ts)
            res[f"{name} / {n}"] = {"family": name, "n": n, "time_s": med, "spread": max(ts) / min(ts),
                                   "nfev": rep.nfev, "njev": rep.njev, "p99": float(np.max(rep.rel_p99)),
                                   "columns": len(rep.params)}
            print(f"{name:28s} {n:6d} {med:8.3f} {max(ts) / min(ts):7.2f} {rep.nfev:5d} {rep.njev:5d} "
                  f"{float(np.max(rep.rel_p99)):9.2e}")
    return res


def _targets(k):
    metals = ("Cu", "Au", "Ag", "Al", "Cr")
    return [bk.Conductor.from_metal(metals[i % 5], alpha=0.1 + 0.05 * i) for i in range(k)]


def bench_fit_many(n_targets, repeats, n_pairs):
    from distributed import Client, LocalCluster
    targets = _targets(n_targets)
    kw = dict(params=("eta", "k", "alpha"), n=n_pairs, albedo=False, init={"alpha": 0.4})
    bk.set_num_threads(1)
    ts_serial = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for t in targets:
            bk.fit(t, bk.Conductor, **kw)
        ts_serial.append(time.perf_counter() - t0)
    out = {"targets": n_targets, "n_pairs": n_pairs, "serial_in_process_s": statistics.median(ts_serial),
           "serial_spread": max(ts_serial) / min(ts_serial)}
    for nw in (1, 2):
        with LocalCluster(n_workers=nw, processes=True, threads_per_worker=1, dashboard_address=None) as cl, \
                Client(cl) as c:
            bk.fit_many(targets[:nw], bk.Conductor, client=c, **kw)   # warm the workers (imports, tables)
            ts = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                r = bk.fit_many(targets, bk.Conductor, client=c, **kw)
                ts.append(time.perf_counter() - t0)
                assert not r.errors, r.errors
        out[f"workers_{nw}_s"] = statistics.median(ts)
        out[f"workers_{nw}_spread"] = max(ts) / min(ts)
    out["speedup_1_to_2"] = out["workers_1_s"] / out["workers_2_s"]
    out["overhead_1_worker_vs_serial"] = out["workers_1_s"] / out["serial_in_process_s"]
    print(f"fit_many, {n_targets} Conductor targets (n={n_pairs}): serial in-process {out['serial_in_process_s']:.2f} s, "
          f"1 worker {out['workers_1_s']:.2f} s, 2 workers {out['workers_2_s']:.2f} s, "
          f"speedup {out['speedup_1_to_2']:.2f}x (spreads {out['workers_1_spread']:.2f}, {out['workers_2_spread']:.2f})")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--targets", type=int, default=16)
    ap.add_argument("--pairs", type=int, default=8192, help="direction pairs per fit_many target")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--skip-families", action="store_true")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    bk.set_num_threads(a.threads)
    print(f"bsdfkit {bk.__version__}; {cpu_model()}; {os.cpu_count()} cpus, threads {a.threads}; load {os.getloadavg()}")
    out = {"cpu": cpu_model(), "threads": a.threads, "load_start": os.getloadavg()}
    if not a.skip_families:
        out["families"] = bench_families(a.repeats)
    out["fit_many"] = bench_fit_many(a.targets, a.repeats, a.pairs)
    out["load_end"] = os.getloadavg()
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)
    return out


if __name__ == "__main__":
    main()
