"""Per-element parameters (issue 47): eval throughput of a model whose parameters are arrays,
against the same model with uniform parameters and against Mitsuba 3 reading the same values from
``bitmap`` textures at each element's uv (nearest lookups), end to end (numpy in, numpy out).

Rows, float32, N pairs (default 1e6):
- uniform: the model with scalar parameters (the reference rate);
- varying, all distinct: every element has its own values (one model built per element);
- varying, runs of 64: the values change every 64 elements (piecewise-constant maps: one model
  per run, the packet code over the run);
- Mitsuba bitmap: ``llvm_ad_rgb``, the parameters as bitmap textures, uv per element, the
  directions and uv converted from numpy and f converted back (eval / |cos|) inside the timing.

Reported as time ratios measured in the same run (the machine is shared), median of REPEATS
interleaved repetitions with the min..max spread, the CPU model and the load written beside.
Writes bench/varying.json and the table of bench/VARYING.md.

    python bench/varying.py [--n 1000000] [--repeats 5]
"""
import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

import bsdfkit as bk
from _host import cpu_model, simd_isa  # same directory

HERE = Path(__file__).resolve().parent


def _dirs(rng, n):
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


def _models(rng, n, H, W):
    runs = np.repeat(np.arange(n // 64 + 1), 64)[:n]
    alpha, eta, k = rng.uniform(0.05, 0.6, n), rng.uniform(0.2, 2.5, (n, 3)), rng.uniform(0.5, 4, (n, 3))
    bc, r, mt = rng.uniform(0, 1, (n, 3)), rng.uniform(0.05, 1, n), rng.uniform(0, 1, n)
    f32 = lambda a: a.astype(np.float32).astype(np.float64)  # noqa: E731  (the bitmaps hold float32)
    alpha, eta, k, bc, r, mt = map(f32, (alpha, eta, k, bc, r, mt))

    def bitmap(v):
        import mitsuba as mi
        ch = 1 if v.ndim == 1 else 3
        return {"type": "bitmap", "data": mi.TensorXf(v.astype(np.float32).reshape(H, W, ch)),
                "filter_type": "nearest", "raw": True}

    return {
        "Conductor rough (alpha, eta, k)": dict(
            uniform=bk.Conductor(eta[0], k[0], alpha=alpha[0], masking="separable"),
            distinct=bk.Conductor(eta, k, alpha=alpha, masking="separable"),
            runs=bk.Conductor(eta[runs], k[runs], alpha=alpha[runs], masking="separable"),
            mitsuba=lambda: {"type": "roughconductor", "distribution": "ggx", "eta": bitmap(eta), "k": bitmap(k),
                             "alpha": bitmap(alpha)}),
        "FilamentStandard (base_color, roughness, metallic)": dict(
            uniform=bk.FilamentStandard(bc[0], roughness=r[0], metallic=mt[0]),
            distinct=bk.FilamentStandard(bc, roughness=r, metallic=mt),
            runs=bk.FilamentStandard(bc[runs], roughness=r[runs], metallic=mt[runs]),
            mitsuba=None),  # Mitsuba has no Filament model: the row times bsdfkit only
    }


def _mitsuba_eval(d, wo, wi, uv):
    import drjit as dr
    import mitsuba as mi
    bsdf = mi.load_dict(d)

    def run():
        n = len(wo)
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(np.ascontiguousarray(wo), flip_axes=True)
        si.sh_frame = mi.Frame3f(mi.Normal3f(0, 0, 1))
        si.uv = mi.Point2f(uv[:, 0], uv[:, 1])
        val = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(np.ascontiguousarray(wi), flip_axes=True))
        v = val.numpy().T if hasattr(val, "numpy") else np.asarray(val).T
        return v / np.abs(wi[:, 2:3])
    return run


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    W = 1000
    H = (args.n + W - 1) // W
    n = H * W
    rng = np.random.default_rng(1)
    wo, wi = _dirs(rng, n), _dirs(rng, n)
    r, c = np.divmod(np.arange(n), W)
    uv = np.stack([(c + 0.5) / W, (r + 0.5) / H], axis=1).astype(np.float32)
    have_mi = True
    try:
        import mitsuba as mi
        mi.set_variant("llvm_ad_rgb")
    except Exception:
        have_mi = False
    rows = []
    for name, ms in _models(rng, n, H, W).items():
        calls = {k: (lambda m=ms[k]: m.eval(wo, wi)) for k in ("uniform", "distinct", "runs")}
        if have_mi and ms["mitsuba"] is not None:
            calls["mitsuba"] = _mitsuba_eval(ms["mitsuba"](), wo, wi, uv)
        for f in calls.values():   # warm up (and JIT-compile Mitsuba's kernel)
            f()
        times = {k: [] for k in calls}
        for _ in range(args.repeats):
            for k, f in calls.items():
                t = time.perf_counter()
                f()
                times[k].append(time.perf_counter() - t)
        t = {k: np.array(v) for k, v in times.items()}
        row = {"model": name, "n": n, "ms": {k: float(np.median(v) * 1e3) for k, v in t.items()}}
        for k in ("distinct", "runs"):
            ratio = t["uniform"] / t[k]
            row[f"{k}_vs_uniform"] = [float(np.median(ratio)), float(ratio.min()), float(ratio.max())]
            if "mitsuba" in t:
                ratio = t["mitsuba"] / t[k]
                row[f"{k}_vs_mitsuba"] = [float(np.median(ratio)), float(ratio.min()), float(ratio.max())]
        rows.append(row)
        print(json.dumps(row))
    host = dict(cpu=cpu_model(), simd=simd_isa(), threads=bk.get_num_threads(), load=os.getloadavg()[0],
                date=time.strftime("%Y-%m-%d"))
    (HERE / "varying.json").write_text(json.dumps(dict(host=host, rows=rows), indent=1) + "\n")
    lines = ["# Per-element parameters: eval throughput", "",
             f"Host: {host['cpu']} ({host['simd']}), {host['threads']} threads, load {host['load']:.1f}, "
             f"{host['date']}; float32, N = {n}, median of {args.repeats} interleaved repetitions (min..max). "
             "Ratios > 1: the varying call is faster than the other.", "",
             "| model | varying / uniform rate, all distinct | runs of 64 | vs Mitsuba bitmap, all distinct | runs of 64 |",
             "|---|---|---|---|---|"]

    def fmt(v):
        return "-" if v is None else f"{v[0]:.2f} ({v[1]:.2f}..{v[2]:.2f})"
    for row in rows:
        lines.append(f"| {row['model']} | {fmt(row.get('distinct_vs_uniform'))} | {fmt(row.get('runs_vs_uniform'))} | "
                     f"{fmt(row.get('distinct_vs_mitsuba'))} | {fmt(row.get('runs_vs_mitsuba'))} |")
    (HERE / "VARYING.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
