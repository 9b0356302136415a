#!/usr/bin/env python3
"""Throughput and accuracy of the Filament models, one row per knob setting.

    python tools/perf/filament.py            # N = 1e6 directions, ~2-4 min
    python tools/perf/filament.py --quick    # N = 1e5, a smoke run

Writes tools/perf/results/FILAMENT.md (or --out-dir; the JSON goes beside it only with --out-dir).

Throughput: M elements/s of eval / pdf (preallocated out=) and of the compiled sample kernel
(preallocated outputs), float32 and float64, at the current thread count (bk.get_num_threads()),
each the best of several repeats. Every figure is also given relative to the foundation's rough
conductor (tools/perf/throughput.py's headline model: Cu, GGX alpha 0.3, separable masking) measured
back to back with it in the same round, so machine load cancels out of the ratio.

Accuracy: each knob setting against the default (Filament's desktop high quality, which is also
the most accurate setting: height-correlated V, energy compensation, f90 rule): the median and
p99 relative difference of f over importance-sampled pairs, and the largest difference of the
directional albedo over NoV in {1, 0.7, 0.4, 0.15, 0.05} (2^17 samples each). Knobs that change the
model rather than approximate it (diffuse, layering, IOR change, LUT size, min_roughness) are
listed the same way: the numbers say how far each choice moves the result.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

import bsdfkit as bk
from _machine import cpu_model, load  # bench/_host.py's
from bsdfkit.directions import random_directions

HERE = Path(__file__).resolve().parent / "results"
SEED = 20240611
CU_ETA = [0.201006, 0.923749, 1.102215]
CU_K = [3.913262, 2.453045, 2.142090]

BASE = dict(base_color=[0.8, 0.5, 0.3])  # roughness 0.5 (the default) unless stated
COAT = dict(clear_coat=1.0, clear_coat_roughness=0.3)


def configs():
    """(key, label, model, reference model or None): each knob row changes one thing of its
    reference, on a material where that knob matters."""
    S = bk.FilamentStandard
    base = S(**BASE)
    dark = S(**BASE, reflectance=0.1)               # f0 = 0.0016: the f90 rule gives f90 = 0.08
    smooth = S(**BASE, roughness=0.05)               # below the mobile clamp 0.089
    metal = S(1.0, metallic=1.0, roughness=0.5)
    coat = S(**BASE, metallic=0.5, **COAT)
    cloth = bk.FilamentCloth(0.5)
    return [
        ("std", "Standard, defaults (lambert, correlated, f90 rule, EC on, desktop), r 0.5", base, None),
        ("std_burley", "  diffuse='burley'", S(**BASE, diffuse="burley"), base),
        ("std_fast", "  visibility='fast'", S(**BASE, visibility="fast"), base),
        ("std_noec", "  energy_compensation=False", S(**BASE, energy_compensation=False), base),
        ("std_lut32", "  dfg_lut_size=32", S(**BASE, dfg_lut_size=32), base),
        ("std_lut256", "  dfg_lut_size=256", S(**BASE, dfg_lut_size=256), base),
        ("std_lowq", "  fast + f90 one + no EC + mobile (Filament LOW on mobile)",
         S(**BASE, visibility="fast", f90="one", energy_compensation=False, min_roughness="mobile"), base),
        ("dark_f90one", "  f90='one', on reflectance 0.1 (f0 0.0016)", S(**BASE, reflectance=0.1, f90="one"), dark),
        ("smooth_mobile", "  min_roughness='mobile', on roughness 0.05", S(**BASE, roughness=0.05, min_roughness="mobile"),
         smooth),
        ("metal", "Standard metal (base 1, metallic 1, r 0.5)", metal, None),
        ("metal_fast", "  visibility='fast'", S(1.0, metallic=1.0, roughness=0.5, visibility="fast"), metal),
        ("metal_noec", "  energy_compensation=False", S(1.0, metallic=1.0, roughness=0.5, energy_compensation=False),
         metal),
        ("aniso", "Standard + anisotropy 0.6", S(**BASE, anisotropy=0.6), base),
        ("coat", "Standard + clear coat (1, r_c 0.3), metallic 0.5", coat, None),
        ("coat_doc", "  clear_coat_layering='doc'", S(**BASE, metallic=0.5, **COAT, clear_coat_layering="doc"), coat),
        ("coat_noior", "  clear_coat_ior_change=False", S(**BASE, metallic=0.5, **COAT, clear_coat_ior_change=False),
         coat),
        ("sheen", "Standard + sheen (0.5, r_s 0.5)", S(**BASE, sheen_color=0.5, sheen_roughness=0.5), base),
        ("all", "Standard + anisotropy + coat + sheen",
         S(**BASE, metallic=0.5, anisotropy=0.6, sheen_color=0.5, sheen_roughness=0.5, **COAT), coat),
        ("cloth", "Cloth (base 0.5, sheen sqrt(base), r 0.5)", cloth, None),
        ("cloth_burley", "  diffuse='burley'", bk.FilamentCloth(0.5, diffuse="burley"), cloth),
        ("cloth_ss", "  subsurface_color=(0.4, 0.2, 0.1)", bk.FilamentCloth(0.5, subsurface_color=[0.4, 0.2, 0.1]),
         cloth),
    ]


from _machine import wait_quiet  # noqa: E402  (bench/_host.py's: same timing rules)
from bsdfkit.tuning import best_time as _timer  # noqa: E402


def best_time(fn, repeats=5):
    """Min over `repeats` of the mean time of back-to-back calls, each repeat >= 20 ms."""
    return _timer(fn, repeats=repeats, min_time=0.02, warmup=1)


def make_inputs(n):
    rng = np.random.default_rng(SEED)
    d = {"wo": random_directions(n, rng, upper=True), "wi": random_directions(n, rng, upper=True), "uc": rng.random(n), "u": rng.random((n, 2))}
    return {"float64": d, "float32": {k: v.astype(np.float32) for k, v in d.items()}}


def calls(m, d):
    n, dt = len(d["wo"]), d["wo"].dtype
    out3, out1 = np.empty((n, 3), dt), np.empty(n, dt)
    bufs = (np.empty((n, 3), dt), np.empty((n, 3), dt), np.empty(n, dt), np.empty(n, np.uint8), np.empty(n, dt),
            np.empty(n, bool), np.empty(n, bool))
    core = m._core
    return {"eval": lambda: m.eval(d["wo"], d["wi"], out=out3),
            "pdf": lambda: m.pdf(d["wo"], d["wi"], out=out1),
            "sample": lambda: core.sample(d["wo"], d["uc"], d["u"], 0, 3, bufs)}


def throughput(rows, inputs, repeats, rounds):
    """Best time of every (model, dtype, op), the conductor timed right before each one, over
    `rounds` interleaved rounds; ratio = best conductor time / best model time."""
    ref = bk.Conductor(CU_ETA, CU_K, alpha=0.3, masking="separable")
    ops = ("eval", "pdf", "sample")
    keys = [r[0] for r in rows]
    best = {k: {dt: {op: math.inf for op in ops} for dt in inputs} for k in keys + ["conductor"]}
    best_ref = {k: {dt: {op: math.inf for op in ops} for dt in inputs} for k in keys}
    busy = []
    for _ in range(rounds):
        for dt, d in inputs.items():
            cref = calls(ref, d)
            for key, label, m, _ in rows:
                busy.append(wait_quiet(max_wait=5.0))
                cm = calls(m, d)
                for op in ops:
                    t_ref = best_time(cref[op], repeats)
                    t = best_time(cm[op], repeats)
                    best_ref[key][dt][op] = min(best_ref[key][dt][op], t_ref)
                    best["conductor"][dt][op] = min(best["conductor"][dt][op], t_ref)
                    best[key][dt][op] = min(best[key][dt][op], t)
    res = {}
    for key in keys + ["conductor"]:
        res[key] = {dt: {op: len(inputs[dt]["wo"]) / best[key][dt][op] / 1e6 for op in ops} for dt in inputs}
        if key != "conductor":
            res[key]["ratio"] = {dt: {op: best_ref[key][dt][op] / best[key][dt][op] for op in ops} for dt in inputs}
    res["busy_cores_max"] = max(busy) if busy else 0.0
    return res


def accuracy(rows, n=200_000):
    rng = np.random.default_rng(SEED + 1)
    zs = np.array([1.0, 0.7, 0.4, 0.15, 0.05])
    wo_alb = bk.direction(np.arccos(zs), 0.3)
    out = {}
    ref_name = {}
    for key, label, m, r in rows:
        if r is None:
            ref_name[id(m)] = key
    for key, label, m, r in rows:
        if r is None:
            continue
        refkey = ref_name.get(id(r), "same material, default knobs")
        wo = bk.direction(np.arccos(rng.uniform(0.02, 1, n)), rng.uniform(0, 2 * np.pi, n))
        s = r.sample(wo, rng.random(n), rng.random((n, 2)))
        keep = s.valid
        f_ref = r.eval(wo[keep], s.wi[keep])
        f = m.eval(wo[keep], s.wi[keep])
        pos = f_ref > 1e-12
        rel = np.abs(f[pos] - f_ref[pos]) / f_ref[pos]
        a_ref = r.albedo(wo_alb, n_samples=1 << 17, seed=3)
        a = m.albedo(wo_alb, n_samples=1 << 17, seed=3)
        out[key] = {"ref": refkey, "f_rel_median": float(np.median(rel)), "f_rel_p99": float(np.quantile(rel, 0.99)),
                    "albedo_max_abs": float(np.max(np.abs(a - a_ref))),
                    "albedo_ref": a_ref[:, 0].round(4).tolist(), "albedo": a[:, 0].round(4).tolist()}
    return out


def lut_timing(sizes=(32, 64, 128, 256), samples=1024):
    from bsdfkit import _core
    t = {}
    for s in sizes:
        t0 = time.perf_counter()
        _core.filament_dfg_rows(s, samples, 0, s)
        t[s] = time.perf_counter() - t0
    return t


NOTE = ("Models with a sheen lobe (and the cloth model) evaluate D_Charlie with pow(), which has no vector form "
        "without -ffast-math: their kernels stay scalar. The standard model is compiled in four variants (with or "
        "without the clear-coat and sheen lobes); without sheen, eval (float32 and float64) and the float32 pdf "
        "loops vectorize (AVX2 gathers from the DFG table); sample stays scalar (sin/cos), as for every model.")


def write_markdown(path, info, rows, thr, acc, lut, args, n):
    L = []
    L.append("# Filament models: throughput and accuracy per knob setting\n")
    L.append(f"Generated by `python tools/perf/filament.py{' --quick' if args.quick else ''}` on {info['date']} "
             f"(wall time {info['elapsed_s']:.0f} s). N = {n:,} directions (wo, wi uniform on the upper "
             f"hemisphere), {info['threads']} threads, best of {args.repeats} repeats x {args.rounds} rounds.\n")
    L.append(f"- CPU: {info['cpu']} (`nproc` = {info['nproc']}); load average at start {info['load_start']}, "
             f"at end {info['load_end']}; other processes used up to {thr['busy_cores_max']:.1f} cores "
             f"before a measurement (waits of up to 5 s for < 0.3)\n- Python {info['python']}, numpy {info['numpy']}, bsdfkit {info['bsdfkit']}\n")
    L.append("## Throughput (M elements/s) and ratio to the rough conductor\n")
    L.append("Ratio = conductor time / model time, measured back to back in the same round (> 1: faster than "
             "the conductor). The conductor's own rates are the last row.\n")
    for dt in ("float32", "float64"):
        L.append(f"### {dt}\n")
        L.append("| setting | eval | pdf | sample | eval / cond | pdf / cond | sample / cond |")
        L.append("|---|--:|--:|--:|--:|--:|--:|")
        for key, label, _, _ in rows:
            r = thr[key]
            L.append(f"| {label} | {r[dt]['eval']:.1f} | {r[dt]['pdf']:.1f} | {r[dt]['sample']:.1f} | "
                     f"{r['ratio'][dt]['eval']:.2f}x | {r['ratio'][dt]['pdf']:.2f}x | {r['ratio'][dt]['sample']:.2f}x |")
        c = thr["conductor"][dt]
        L.append(f"| *Conductor Cu a=0.3 (separable)* | {c['eval']:.1f} | {c['pdf']:.1f} | {c['sample']:.1f} | 1 | 1 | 1 |\n")
    L.append("## Accuracy of each knob against its reference setting\n")
    L.append("f: relative difference over 2e5 pairs sampled from the reference model (wo with NoV in "
             "[0.02, 1]); albedo: largest absolute difference over NoV = 1, 0.7, 0.4, 0.15, 0.05 "
             "(first channel listed).\n")
    L.append("| setting | reference | f median | f p99 | albedo max abs diff | albedo (reference) | albedo |")
    L.append("|---|---|--:|--:|--:|---|---|")
    labels = {k: lab.strip() for k, lab, _, _ in rows}
    for key, a in acc.items():
        L.append(f"| {labels[key]} | {a['ref']} | {a['f_rel_median']:.2e} | {a['f_rel_p99']:.2e} | "
                 f"{a['albedo_max_abs']:.2e} | {a['albedo_ref']} | {a['albedo']} |")
    L.append("\n## DFG table build (C++, float64, 1024 samples per texel and strategy)\n")
    L.append("| size | seconds |\n|--:|--:|")
    for s, t in lut.items():
        L.append(f"| {s} | {t:.2f} |")
    L.append("\n" + NOTE + "\n")
    path.write_text("\n".join(L) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--n", type=int, default=None)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--out-dir", type=Path, default=HERE)
    args = ap.parse_args()
    n = args.n or (100_000 if args.quick else 1_000_000)
    t0 = time.perf_counter()
    info = {"date": _dt.datetime.now().astimezone().isoformat(timespec="seconds"), "nproc": os.cpu_count(),
            "threads": bk.get_num_threads(), "python": platform.python_version(), "numpy": np.__version__,
            "bsdfkit": bk.__version__, "load_start": list(load()), "cpu": cpu_model()}
    bk.filament.dfg_lut(128)  # build the shared table before timing
    rows = configs()
    inputs = make_inputs(n)
    print(f"[bench] throughput, N = {n:,}", flush=True)
    thr = throughput(rows, inputs, args.repeats, args.rounds)
    print("[bench] accuracy", flush=True)
    acc = accuracy(rows, n=min(n, 200_000))
    print("[bench] DFG table build", flush=True)
    lut = lut_timing() if not args.quick else lut_timing(sizes=(32, 64))
    info["load_end"] = [round(x, 2) for x in os.getloadavg()]
    info["elapsed_s"] = time.perf_counter() - t0
    args.out_dir.mkdir(parents=True, exist_ok=True)
    data = {"machine": info, "n": n, "throughput": thr, "accuracy": acc, "lut_seconds": lut,
            "labels": {k: lab for k, lab, _, _ in rows}}
    if args.out_dir != HERE:   # results/ keeps the report only (its retention rule)
        (args.out_dir / "filament.json").write_text(json.dumps(data, indent=1) + "\n")
    write_markdown(args.out_dir / "FILAMENT.md", info, rows, thr, acc, lut, args, n)
    print(f"[bench] wrote {args.out_dir / 'FILAMENT.md'} ({info['elapsed_s']:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
