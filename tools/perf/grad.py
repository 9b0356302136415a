"""Cost of eval_grad relative to eval (float64), per model and number of gradient columns.

eval_grad runs the model's f with a dual number of K partials (K = 4, 8 or 16, the smallest that
holds the requested columns; core/dual.h), in scalar code (the dual number's partial loops do not
vectorize across elements as the float64 eval loop does). Rough Plastic's eval_grad also rebuilds
its model from dual parameters, whose coat tables (in alpha and eta) come from a per-(alpha, eta)
cache after the first call: the repeats time the cached case, as a fit's Jacobian after its
residual at the same point would not (see GRAD.md for the integration's own cost). Reported: the time of eval_grad over
the time of eval (float64) on the same N pairs, and that ratio per gradient column. Timings on a
shared machine: ratios within one run, median of repeats with the spread (max/min).

    python tools/perf/grad.py [--n 65536] [--repeats 5] [--threads 1] [--json /tmp/grad.json]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics

import numpy as np

import bsdfkit as bk
from _machine import cpu_model  # bench/_host.py's
from bsdfkit.tuning.costs import time_repeats

CASES = {
    "Diffuse / reflectance (3)": (lambda: bk.Diffuse((0.8, 0.5, 0.2)), ("reflectance",)),
    "Conductor / alpha (1)": (lambda: bk.Conductor.from_metal("Cu", alpha=0.3), ("alpha",)),
    "Conductor / eta, k, alpha (7)": (lambda: bk.Conductor.from_metal("Cu", alpha=0.3), ("eta", "k", "alpha")),
    "Conductor / all (8)": (lambda: bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.1), None),
    "Dielectric / all (3)": (lambda: bk.Dielectric(1.5, alpha=0.3), None),
    "FilamentStandard / base, metallic, roughness, reflectance (6)":
        (lambda: bk.FilamentStandard((0.8, 0.5, 0.3), roughness=0.5), ("base_color", "metallic", "roughness",
                                                                       "reflectance")),
    "FilamentStandard / all (13)": (lambda: bk.FilamentStandard((0.8, 0.5, 0.3), roughness=0.5, clear_coat=0.5,
                                                                 sheen_color=0.3), None),
    "FilamentCloth / base, sheen, roughness (7)":
        (lambda: bk.FilamentCloth((0.35, 0.1, 0.1), sheen_color=(0.8, 0.5, 0.5), roughness=0.5),
         ("base_color", "sheen_color", "roughness")),
    "CoatedDiffuse analytic / reflectance, eta, alpha, thickness (6)":
        (lambda: bk.CoatedDiffuse((0.6, 0.35, 0.15), alpha=0.05, method="analytic"),
         ("reflectance", "eta", "alpha", "thickness")),
    "CoatedDiffuse analytic, medium / all (11)":
        (lambda: bk.CoatedDiffuse(0.2, albedo=0.8, thickness=0.2, g=0.3, alpha=0.1, method="analytic"), None),
    "CoatedConductor analytic / metal eta, k, alphas (8)":
        (lambda: bk.CoatedConductor.from_metal("Cu", conductor_alpha=0.3, interface_alpha=0.05, method="analytic"),
         ("conductor_eta", "conductor_k", "conductor_alpha", "interface_alpha")),
    "Plastic smooth / reflectance, eta (4)": (lambda: bk.Plastic((0.8, 0.1, 0.1), eta=1.49), ("reflectance", "eta")),
    "Plastic rough / all (8)": (lambda: bk.Plastic((0.8, 0.1, 0.1), alpha=0.2, specular_reflectance=0.9), None),
}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=65536)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--json", default=None)
    ap.add_argument("--only", default=None, help="run only the cases whose name contains this text")
    a = ap.parse_args(argv)
    bk.set_num_threads(a.threads)
    rng = np.random.default_rng(0)
    wo = rng.normal(size=(a.n, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = rng.normal(size=(a.n, 3))
    wi[:, 2] = np.abs(wi[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    print(f"bsdfkit {bk.__version__}; {cpu_model()}; {os.cpu_count()} cpus, threads {a.threads}; load {os.getloadavg()}")
    print(f"N = {a.n} pairs, float64; ratio = eval_grad time / eval time (median of {a.repeats}, spread max/min)")
    print(f"{'case':62s} {'P':>3s} {'ratio':>7s} {'/column':>8s} {'spread':>7s}")
    res = {}
    for name, (make, params) in CASES.items():
        if a.only and a.only not in name:
            continue
        m = make()
        P = len(bk.fitting.grad_columns(m, params))
        t_e = time_repeats(lambda: m.eval(wo, wi), repeats=a.repeats, min_time=0.05)
        t_g = time_repeats(lambda: m.eval_grad(wo, wi, params), repeats=a.repeats, min_time=0.05)
        ratio = statistics.median(t_g) / statistics.median(t_e)
        spr = max(max(t_g) / min(t_g), max(t_e) / min(t_e))
        res[name] = {"columns": P, "ratio": ratio, "ratio_per_column": ratio / P, "spread": spr,
                     "eval_ns_per_pair": statistics.median(t_e) / a.n * 1e9}
        print(f"{name:62s} {P:3d} {ratio:7.1f} {ratio / P:8.2f} {spr:7.2f}")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"cpu": cpu_model(), "n": a.n, "threads": a.threads, "results": res}, fh, indent=1)
    return res


if __name__ == "__main__":
    main()
