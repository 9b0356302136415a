#!/usr/bin/env python3
"""Layered family benchmark: CoatedDiffuse / CoatedConductor cost and noise versus n_samples,
sample throughput, and Plastic against Mitsuba 3's plastic / roughplastic on the same arrays.

    python bench/layered.py            # ~2 min on 2 loaded cores
    python bench/layered.py --quick

Writes bench/LAYERED.md and bench/layered.json. The machine this runs on is shared and
loaded: absolute rates are not comparable between runs; the ratios (bsdfkit / Mitsuba measured
back to back in the same process on the same arrays, and cost relative to n_samples = 1) are
the figures to read.

Error measure of the layered knobs: relative RMS of f |cos wi| against a converged reference
(n_samples = 256, max_depth = 100) over a fixed set of direction pairs: noise and bias
(truncation by max_depth) together; the noise part alone is the RMS over seeds of the same
configuration, reported separately.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")

import bsdfkit as bk  # noqa: E402
from bsdfkit.directions import random_directions  # noqa: E402
from bsdfkit.tuning.costs import best_time  # noqa: E402

HERE = Path(__file__).resolve().parent


def dirs(rng, n, upper=True):
    return random_directions(n, rng, upper=upper)


def layered_rows(n, quick):
    rng = np.random.default_rng(1)
    wo, wi = dirs(rng, n), dirs(rng, n)
    m_ref = dict(max_depth=100)
    configs = {
        "CoatedDiffuse rough coat + medium": dict(cls=bk.CoatedDiffuse, kw=dict(reflectance=[0.6, 0.35, 0.15], alpha=0.1,
                                                                                  albedo=0.5, thickness=0.2, g=0.3)),
        "CoatedConductor (car paint)": dict(cls=bk.CoatedConductor, kw=dict(conductor_eta=bk.METALS["Cu"][0],
                                                                          conductor_k=bk.METALS["Cu"][1],
                                                                          conductor_alpha=0.3, interface_alpha=0.05,
                                                                          albedo=[0.5, 0.1, 0.1], thickness=0.1)),
    }
    rows = []
    ns_list = (1, 2, 4, 8, 16) if quick else (1, 2, 4, 8, 16, 32, 64)
    for name, c in configs.items():
        cls, kw = c["cls"], c["kw"]
        nref = 2000
        ref = cls(**kw, n_samples=64 if quick else 256, **m_ref).eval(wo[:nref], wi[:nref]) * np.abs(wi[:nref, 2:3])
        scale = np.sqrt(np.mean(ref ** 2))
        base = None
        for ns in ns_list:
            m = cls(**kw, n_samples=ns)
            out = np.empty((n, 3))
            t = best_time(lambda: m.eval(wo, wi, out=out), repeats=3)
            rate = n / t
            base = base or rate
            fc = [cls(**kw, n_samples=ns, seed=s).eval(wo[:nref], wi[:nref]) * np.abs(wi[:nref, 2:3]) for s in range(4)]
            err = np.mean([np.sqrt(np.mean((f - ref) ** 2)) for f in fc]) / scale
            noise = np.sqrt(np.mean(np.var(np.stack(fc), axis=0, ddof=1))) / scale
            rows.append(dict(model=name, n_samples=ns, evals_per_s=rate, cost_vs_1=base / rate, rel_rms_err=err,
                             rel_rms_noise=noise))
        m = cls(**kw)
        uc, u = rng.random(n), rng.random((n, 2))
        t = best_time(lambda: m.sample(wo, uc, u), repeats=3)
        rows.append(dict(model=name, n_samples="sample()", evals_per_s=n / t, cost_vs_1=base / (n / t),
                         rel_rms_err=float("nan"), rel_rms_noise=float("nan")))
        for md in (1, 2, 5, 10, 20, 50):
            mm = cls(**kw, n_samples=1, max_depth=md)
            t = best_time(lambda: mm.eval(wo, wi), repeats=3)
            fc = [cls(**kw, n_samples=16, max_depth=md, seed=s).eval(wo[:nref], wi[:nref]) * np.abs(wi[:nref, 2:3])
                  for s in range(2)]
            bias = np.sqrt(np.mean((np.mean(fc, 0) - ref) ** 2)) / scale
            rows.append(dict(model=name, n_samples=f"max_depth={md}", evals_per_s=n / t, cost_vs_1=base / (n / t),
                             rel_rms_err=bias, rel_rms_noise=float("nan")))
    return rows


def plastic_rows(n):
    from bsdfkit.testing import mitsuba as ref
    mi, dr = ref._mi()
    rng = np.random.default_rng(2)
    wo32 = dirs(rng, n).astype(np.float32)
    wi32 = dirs(rng, n).astype(np.float32)
    uc32, u32 = rng.random(n).astype(np.float32), rng.random((n, 2)).astype(np.float32)
    rows = []
    for name, m in (("plastic", bk.Plastic(0.5, 1.49, masking="separable")),
                    ("roughplastic a=0.2", bk.Plastic(0.5, 1.49, alpha=0.2, masking="separable"))):
        bsdf = ref.load(m)
        si = ref._make_si(wo32)
        wi_mi = ref._v3(wi32)
        ctx = mi.BSDFContext()
        ucm, um = mi.Float(uc32), mi.Point2f(u32, flip_axes=True)
        dr.eval(si, wi_mi, ucm, um)

        def mi_eval():
            v, p = bsdf.eval_pdf(ctx, si, wi_mi)
            dr.eval(v, p)
            dr.sync_thread()

        def mi_sample():
            bs, w = bsdf.sample(ctx, si, ucm, um)
            dr.eval(bs, w)
            dr.sync_thread()

        for dt, wo_, wi_, uc_, u_ in (("f32", wo32, wi32, uc32, u32),
                                      ("f64", wo32.astype(np.float64), wi32.astype(np.float64),
                                       uc32.astype(np.float64), u32.astype(np.float64))):
            out = np.empty((n, 3), wo_.dtype)
            pout = np.empty(n, wo_.dtype)

            def ours_eval():
                m.eval(wo_, wi_, out=out)
                m.pdf(wo_, wi_, out=pout)

            t_o = best_time(ours_eval, repeats=5)
            t_m = best_time(mi_eval, repeats=5)
            t_os = best_time(lambda: m.sample(wo_, uc_, u_), repeats=5)
            t_ms = best_time(mi_sample, repeats=5)
            rows.append(dict(model=name, dtype=dt, eval_pdf_ratio=t_m / t_o, sample_ratio=t_ms / t_os,
                             ours_eval_pdf_per_s=n / t_o, mitsuba_eval_pdf_per_s=n / t_m))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out-dir", default=str(HERE))
    a = ap.parse_args()
    n = 20_000 if a.quick else 100_000
    lay = layered_rows(n, a.quick)
    pla = plastic_rows(200_000 if a.quick else 1_000_000)
    out = Path(a.out_dir)
    meta = dict(date=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"), threads=bk.get_num_threads(),
                n_layered=n, note="shared, loaded 2-core machine: read ratios, not absolute rates")
    (out / "layered.json").write_text(json.dumps(dict(meta=meta, layered=lay, plastic=pla), indent=1, default=str))
    L = ["# Layered family and Plastic: cost, noise, and Plastic vs Mitsuba", "",
         f"{meta['date']}, {meta['threads']} threads. **The machine is shared and loaded: absolute rates are not "
         "comparable between runs; read the ratios** (cost relative to n_samples = 1 measured in the same run; "
         "bsdfkit / Mitsuba measured back to back in one process on the same arrays).", "",
         "## CoatedDiffuse / CoatedConductor: eval cost and error vs n_samples and max_depth", "",
         "Error: relative RMS of f|cos| against a converged reference (n_samples = 256, max_depth = 100) over 2000 "
         "random pairs; *noise*: RMS over 4 seeds of the same configuration. max_depth rows: bias only (16 samples, "
         "2 seeds averaged, so a residual noise floor remains).", "",
         "| model | n_samples | evals/s | cost vs n=1 | rel. RMS error | rel. RMS noise |", "|---|---|---|---|---|---|"]
    for r in lay:
        L.append(f"| {r['model']} | {r['n_samples']} | {r['evals_per_s']:.3g} | {r['cost_vs_1']:.2f} | "
                 f"{r['rel_rms_err']:.3g} | {r['rel_rms_noise']:.3g} |")
    L += ["", "## Plastic vs Mitsuba 3 (llvm_ad_rgb) on the same arrays", "",
          "Ratios > 1: bsdfkit faster. eval+pdf: bsdfkit's eval and pdf (two calls, out= preallocated) against "
          "Mitsuba's eval_pdf (one call, inputs already Dr.Jit arrays). sample: bsdfkit's sample() (Python "
          "validation and output allocation included) against Mitsuba's sample (kernel only). Mitsuba computes in "
          "float32 for both rows.", "",
          "| plugin | dtype | eval+pdf ratio | sample ratio | bsdfkit eval+pdf /s | Mitsuba eval_pdf /s |",
          "|---|---|---|---|---|---|"]
    for r in pla:
        L.append(f"| {r['model']} | {r['dtype']} | {r['eval_pdf_ratio']:.2f} | {r['sample_ratio']:.2f} | "
                 f"{r['ours_eval_pdf_per_s']:.3g} | {r['mitsuba_eval_pdf_per_s']:.3g} |")
    (out / "LAYERED.md").write_text("\n".join(L) + "\n")
    print("\n".join(L))


if __name__ == "__main__":
    main()
