"""RGB versus spectral throughput of the models with a spectral kernel (issue 15): eval and sample,
float32 and float64, the same directions and uniforms; spectral calls get 4 wavelengths per pair
(pbrt-v4's visible sampling). Reported as the ratio spectral / RGB time per call (the machine is
shared: absolute rates are not headlines), median of REPEATS interleaved repetitions with the
spread (min..max of the per-repetition ratios), with the CPU model, the packet width of the RGB
kernels, the thread count and the load average. Writes bench/spectral.json and the table of
bench/SPECTRAL.md (between the markers).

    python bench/spectral.py [--n 400000] [--repeats 7] [--threads 2]
"""
import argparse
import json
import os
import re
import time
from pathlib import Path

import numpy as np

import bsdfkit as bk
from _machine import cpu_model, simd_isa  # same directory

HERE = Path(__file__).resolve().parent

MODELS = {
    "Diffuse": (lambda: bk.Diffuse((0.8, 0.3, 0.1)), lambda: bk.Diffuse(bk.Spectrum([360.0, 830.0], [0.2, 0.8]))),
    "DiffuseTransmission": (lambda: bk.DiffuseTransmission(0.5, 0.3),
                            lambda: bk.DiffuseTransmission(bk.Spectrum([360.0, 830.0], [0.2, 0.8]), 0.3)),
    "Conductor rough (exact)": (lambda: bk.Conductor.from_metal("Au", alpha=0.3),
                                lambda: bk.Conductor.from_metal("Au", alpha=0.3, spectral=True)),
    "Conductor rough (F82)": (lambda: bk.Conductor.from_metal("Au", alpha=0.3, fresnel="f82"),
                              lambda: bk.Conductor.from_metal("Au", alpha=0.3, fresnel="f82", spectral=True)),
    "Conductor smooth": (lambda: bk.Conductor.from_metal("Cu"), lambda: bk.Conductor.from_metal("Cu", spectral=True)),
    "Dielectric rough": (lambda: bk.Dielectric(1.5, alpha=0.3),
                         lambda: bk.Dielectric(bk.Spectrum.constant(1.5), alpha=0.3)),
    "Dielectric rough, dispersive": (lambda: bk.Dielectric(1.5, alpha=0.3),
                                     lambda: bk.Dielectric(bk.Spectrum.named("glass-BK7"), alpha=0.3)),
    "Dielectric smooth, dispersive": (lambda: bk.Dielectric(1.5), lambda: bk.Dielectric(bk.Spectrum.named("glass-BK7"))),
    "ThinDielectric, dispersive": (lambda: bk.ThinDielectric(1.5),
                                   lambda: bk.ThinDielectric(bk.Spectrum.named("glass-BK7"))),
}


def timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=400_000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    bk.set_num_threads(args.threads)
    rng = np.random.default_rng(0)
    n = args.n
    v = rng.normal(size=(2, n, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    lam = bk.sample_wavelengths(rng.random(n))[0]
    uc, u = rng.random(n), rng.random((n, 2))
    load_before = os.getloadavg()
    rows = []
    for name, (make_rgb, make_sp) in MODELS.items():
        m_rgb, m_sp = make_rgb(), make_sp()
        for dtype in (np.float32, np.float64):
            wo, wi = v[0].astype(dtype), v[1].astype(dtype)
            ucd, ud = uc.astype(dtype), u.astype(dtype)
            ops = {
                "eval": (lambda: m_rgb.eval(wo, wi), lambda: m_sp.eval(wo, wi, wavelengths=lam)),
                "sample": (lambda: m_rgb.sample(wo, ucd, ud), lambda: m_sp.sample(wo, ucd, ud, wavelengths=lam)),
            }
            for op, (f_rgb, f_sp) in ops.items():
                f_rgb(), f_sp()  # warm-up (uplift, caches, first touch)
                t_rgb, t_sp = [], []
                for _ in range(args.repeats):     # interleaved: load changes hit both
                    t_rgb.append(timed(f_rgb))
                    t_sp.append(timed(f_sp))
                ratios = np.array(t_sp) / np.array(t_rgb)
                rows.append({"model": name, "dtype": np.dtype(dtype).name, "op": op,
                             "rgb_s": float(np.median(t_rgb)), "spectral_s": float(np.median(t_sp)),
                             "ratio": float(np.median(ratios)), "ratio_min": float(ratios.min()),
                             "ratio_max": float(ratios.max())})
                print(f"{name:32s} {np.dtype(dtype).name:8s} {op:7s} spectral/RGB time {rows[-1]['ratio']:6.2f} "
                      f"({ratios.min():.2f}..{ratios.max():.2f})", flush=True)
    meta = {"cpu": cpu_model(), "simd": simd_isa(), "packet_width": 16, "threads": args.threads, "n": n,
            "repeats": args.repeats, "load_before": load_before, "load_after": os.getloadavg(),
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    (HERE / "spectral.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    lines = [f"CPU: {meta['cpu']} ({meta['simd']}; RGB kernels of Diffuse/Conductor/Dielectric on "
             f"{meta['packet_width']}-lane packets, the spectral kernels scalar), {args.threads} threads, "
             f"n = {n} pairs per call, {args.repeats} interleaved repetitions, load average "
             f"{load_before[0]:.1f} before / {meta['load_after'][0]:.1f} after ({meta['date']}).", "",
             "| model | dtype | op | spectral / RGB time (median) | spread (min..max) |", "|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['model']} | {r['dtype']} | {r['op']} | {r['ratio']:.2f} | "
                     f"{r['ratio_min']:.2f}..{r['ratio_max']:.2f} |")
    md = HERE / "SPECTRAL.md"
    text = md.read_text() if md.exists() else "<!-- table -->\n<!-- /table -->\n"
    text = re.sub(r"<!-- table -->.*<!-- /table -->", "<!-- table -->\n" + "\n".join(lines) + "\n<!-- /table -->",
                  text, flags=re.S)
    md.write_text(text)


if __name__ == "__main__":
    main()
