"""Per-call cost of the array API at n = 1 and for the README's idioms, beside Mitsuba 3's
scalar_rgb variant called from Python in the same process (issue 46's per-call targets).

    python bench/percall.py            # prints a markdown table (best and median of 7 rounds, us)

Mitsuba's scalar variant evaluates one direction pair per call, as these rows do; its figures
are the floor of a Python call into a compiled BSDF. Report the CPU beside the figures.
"""
from __future__ import annotations

import platform
import time

import numpy as np

import bsdfkit as bk


def _time(fn, reps: int, rounds: int = 7):
    runs = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(reps):
            fn()
        runs.append((time.perf_counter() - t0) / reps * 1e6)
    runs.sort()
    return runs[0], runs[len(runs) // 2]


def rows():
    m = bk.Conductor.from_metal("Cu", alpha=0.09)
    wo = bk.direction(theta=np.radians(40), phi=0.0)
    wi = bk.direction(theta=np.radians(30), phi=1.0)
    uc, u = np.array(0.5), np.array([0.3, 0.7])
    r = {
        "eval(wo, wi)": lambda: m.eval(wo, wi),
        "pdf(wo, wi)": lambda: m.pdf(wo, wi),
        "sample(wo, uc, u), 0-d uc": lambda: m.sample(wo, uc, u),
        "sample(wo, 0.5, u), Python float uc": lambda: m.sample(wo, 0.5, u),
        "sample(wo, n=1, seed=1)": lambda: m.sample(wo, n=1, seed=1),
        "albedo(wo, n_samples=64)": lambda: m.albedo(wo, 64),
        "eval(list, list)": lambda: m.eval([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
    }
    try:
        import mitsuba as mi
        mi.set_variant("scalar_rgb")
        b = mi.load_dict({"type": "roughconductor", "material": "Cu", "alpha": 0.09, "distribution": "ggx"})
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wo)
        ctx, wim = mi.BSDFContext(), mi.Vector3f(*wi)
        r["Mitsuba scalar_rgb eval"] = lambda: b.eval(ctx, si, wim)
        r["Mitsuba scalar_rgb pdf"] = lambda: b.pdf(ctx, si, wim)
        r["Mitsuba scalar_rgb sample"] = lambda: b.sample(ctx, si, 0.5, mi.Point2f(0.3, 0.7))
    except Exception as e:  # Mitsuba is a test dependency, not a runtime one
        print(f"(Mitsuba not available: {e})")
    return r


def main():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    print(f"Per-call cost, n = 1 (CPU: {cpu}; {bk.get_num_threads()} thread(s))\n")
    print("| call | best us | median us |\n|---|---:|---:|")
    for name, fn in rows().items():
        lo, med = _time(fn, 20000)
        print(f"| {name} | {lo:.2f} | {med:.2f} |")


if __name__ == "__main__":
    main()
