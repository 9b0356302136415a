#!/usr/bin/env python3
"""The analytic layered method (method="analytic") against the converged random walk, and its cost.

    python tools/perf/layered_analytic.py          # ~2 min on 2 loaded cores

For every registered CoatedDiffuse / CoatedConductor example (stochastic ones; plus a smooth
coat over a smooth metal): relative RMS of f |cos wi| of the analytic method against the
converged walk (n_samples = 256, max_depth = 100) over N uniform pairs of the upper hemisphere,
with both MIS rules of the walk (pbrt-v4's, biased high with a rough coat, and the consistent
one), the walk's own residual noise (two converged realizations), and the analytic method's
speed relative to the walk with n_samples = 1 (eval, same arrays, back to back, best of 5,
3 rounds: median ratio and spread). Replaces the "Analytic method" section of bench/LAYERED.md
(bench/layered.py writes the rest of that file).
"""
from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")

import bsdfkit as bk  # noqa: E402
from _machine import cpu_model  # noqa: E402  (bench/_host.py's)
from bsdfkit.models import registry  # noqa: E402
from bsdfkit.models.spec import parse_spec  # noqa: E402
from bsdfkit.tuning.costs import best_time  # noqa: E402

HERE = Path(__file__).resolve().parents[2] / "bench"   # writes a section of bench/LAYERED.md
N = 1500
BEGIN, END = "<!-- analytic:begin -->", "<!-- analytic:end -->"


def dirs(rng, n):
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2])
    return v


def rel_rms(v, vr):
    return float(np.sqrt(np.mean((v - vr) ** 2) / np.mean(vr ** 2)))


def cases():
    out = []
    for cls, label, spec in registry.examples():
        m = parse_spec(spec)
        if cls in (bk.CoatedDiffuse, bk.CoatedConductor) and m.method == "stochastic":
            out.append((label, m))
    out.append(("lacquered gold, smooth coat + smooth metal", bk.CoatedConductor.from_metal("Au", thickness=0.05)))
    return out


def main():
    rng = np.random.default_rng(7)
    wo, wi = dirs(rng, N), dirs(rng, N)
    c = wi[:, 2:3]
    tw_o, tw_i = dirs(rng, 1 << 15), dirs(rng, 1 << 15)
    out_buf = np.empty((1 << 15, 3))
    rows = []
    for label, m in cases():
        p = dict(m._params)
        ana = type(m)(**{**p, "method": "analytic"})
        va = ana.eval(wo, wi) * c
        res = {}
        if not ana.flags & (bk.BxDFFlags.Diffuse | bk.BxDFFlags.Glossy):
            # only delta lobes: compare the albedo (sample weights) at 8 angles instead of eval
            wos = bk.direction(np.radians(np.linspace(0, 85, 8)), 0.3)
            aa = np.array([ana.sample(w, n=16, seed=1).weight.mean(0) for w in wos])
            for mis in ("pbrt", "consistent"):
                ws = [type(m)(**{**p, "max_depth": 100, "mis": mis}).sample(w, n=100_000, seed=s).weight.mean(0)
                      for s in (11, 12) for w in wos]
                a1, a2 = np.array(ws[:8]), np.array(ws[8:])
                res[mis] = (rel_rms(aa, a1), rel_rms(a2, a1) / np.sqrt(2), float(aa.sum() / a1.sum() - 1))
            label += " (albedo at 8 angles: all lobes are deltas)"
        for mis in ("pbrt", "consistent") if not res else ():
            ref = type(m)(**{**p, "n_samples": 256, "max_depth": 100, "mis": mis, "seed": 11})
            ref2 = type(m)(**{**p, "n_samples": 256, "max_depth": 100, "mis": mis, "seed": 12})
            vr, vr2 = ref.eval(wo, wi) * c, ref2.eval(wo, wi) * c
            res[mis] = (rel_rms(va, vr), rel_rms(vr2, vr) / np.sqrt(2), float(va.sum() / vr.sum() - 1))
        one = type(m)(**{**p, "n_samples": 1})
        ratios = []
        for _ in range(3):
            t1 = best_time(lambda: one.eval(tw_o, tw_i, out=out_buf))
            ta = best_time(lambda: ana.eval(tw_o, tw_i, out=out_buf))
            ratios.append(t1 / ta)
        rows.append((label, res, float(np.median(ratios)), float(max(ratios) / min(ratios))))
        print(label, res, ratios, flush=True)
    cpu = cpu_model()
    lines = [BEGIN, "", "## Analytic method (method=\"analytic\") vs the converged walk", "",
             f"{N} uniform pairs (upper hemisphere); converged walk: n_samples = 256, max_depth = 100. "
             "Relative RMS of f|cos| (non-delta part: eval), the walk's residual noise (two realizations / sqrt 2), "
             "and the relative difference of the totals (sum over pairs: the sign of the bias). Speed: analytic "
             "eval vs the walk with n_samples = 1 (max_depth as in the example), same 32768 pairs, back to back, "
             f"best of 5, median of 3 rounds (spread = max/min ratio); {cpu}, AVX2, "
             f"{bk.get_num_threads()} threads, loaded shared machine.", "",
             "| example | rel. RMS vs walk (pbrt MIS) | vs walk (consistent MIS) | walk noise | total bias (consistent) "
             "| speed vs n_samples=1 | spread |",
             "|---|---|---|---|---|---|---|"]
    for label, res, ratio, spread in rows:
        lines.append(f"| {label} | {res['pbrt'][0]:.3f} | {res['consistent'][0]:.3f} | {res['consistent'][1]:.4f} "
                     f"| {res['consistent'][2]:+.3f} | {ratio:.1f}x | {spread:.2f} |")
    lines += ["", "Where the bias comes from: no multiple scattering in the medium (lacquer, car paint), the rough "
              "coat's blurring of the base ignored (the base is seen through the macro normal), Fresnel at the macro "
              "normal, and the internal reflections summed with hemispherical averages. With a smooth coat over a "
              "Lambertian base and a thin clear layer the closed form is exact (tests/models/test_layered_analytic.py).",
              "", END]
    path = HERE / "LAYERED.md"
    text = path.read_text() if path.exists() else ""
    block = "\n".join(lines)
    if BEGIN in text:
        text = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda _: block, text, flags=re.S)
    else:
        text = text.rstrip("\n") + "\n\n" + block + "\n"
    path.write_text(text)
    print(block)


if __name__ == "__main__":
    main()
