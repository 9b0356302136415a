#!/usr/bin/env python3
"""Measured materials (MERL tables, RGL tensor files): load time and memory, eval / pdf / sample
throughput against Mitsuba's `measured` plugin on the same file and the same arrays, tabulation
and round-trip errors per resolution, and the MERL sampler's efficiency.

    python bench/measured.py            # ~3-6 min on a loaded 2-core machine
    python bench/measured.py --quick    # smaller arrays and fewer resolutions

Writes bench/MEASURED.md and bench/measured.json (or --out-dir). Timings are taken on whatever
machine runs this, usually a loaded one: read the ratios (ours / Mitsuba measured back to back in
the same round), not the absolute numbers.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

import bsdfkit as bk
from bsdfkit.tuning.costs import best_time

HERE = Path(__file__).resolve().parent
LUM = np.array([0.2126, 0.7152, 0.0722])


def rss_mb() -> float:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def pairs(rng, n, zmin=0.15):
    v = rng.normal(size=(2, n, 3))
    v[..., 2] = np.abs(v[..., 2]) + zmin
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v[0], v[1]


def errors(model, ref, wo, wi):
    a, b = ref.eval(wo, wi) @ LUM, model.eval(wo, wi) @ LUM
    keep = a > 1e-2 * a.max()
    e = np.abs(b[keep] - a[keep]) / a[keep]
    return float(np.median(e)), float(np.quantile(e, 0.9)), float(np.quantile(e, 0.99))


def _clear_caches():
    from bsdfkit.models import measured as mm
    mm._TABLES.clear()
    mm._MEASURED.clear()


def load_rows(tmp, resolutions):
    """Cold loads (the shared-table caches cleared first). Table memory is computed from the
    sizes: float64 + float32 copies of every table, plus the CDFs of the sampled warps."""
    rows = []
    src = bk.Conductor.from_metal("Cu", alpha=0.2)
    p = bk.measured.write_merl(os.path.join(tmp, "cu_load.binary"), src)
    _clear_caches()
    r0 = rss_mb()
    t0 = time.perf_counter()
    m = bk.MERL.load(p, interpolation="linear")
    dt = time.perf_counter() - t0
    mem = (90 * 90 * 180 * 3 + 3 * 32 * 90 * 64) * 12 / 2**20
    rows.append(dict(kind="MERL (one table per interpolation knob)", size_mb=os.path.getsize(p) / 2**20,
                     load_s=dt, rss_mb=rss_mb() - r0, table_mb=mem))
    del m
    for N in resolutions:
        path = bk.measured.tabulate(src, resolution=N).save(os.path.join(tmp, f"cu{N}_rgb.bsdf"))
        _clear_caches()
        f = bk.measured.read_tensor(path)
        elems = sum(f[k].size for k in ("ndf", "sigma", "rgb")) + 2 * sum(f[k].size for k in ("vndf", "luminance"))
        r0 = rss_mb()
        t0 = time.perf_counter()
        m = bk.Measured.load(path)
        dt = time.perf_counter() - t0
        rows.append(dict(kind=f"tensor file, tabulate(resolution={N})", size_mb=os.path.getsize(path) / 2**20,
                         load_s=dt, rss_mb=rss_mb() - r0, table_mb=elems * 12 / 2**20))
        del m
    return rows


def mitsuba_timer(path, wo, wi, what):
    """A callable running Mitsuba's measured eval (or pdf, or sample) on the arrays (float32, llvm_ad_rgb)."""
    from bsdfkit.testing import mitsuba as ref
    mi, dr = ref._mi()
    bsdf = ref.load({"type": "measured", "filename": path})
    si = ref._make_si(wo.astype(np.float32))
    v = ref._v3(wi.astype(np.float32))
    ctx = mi.BSDFContext()
    n = len(wo)
    u = mi.Point2f(np.random.default_rng(1).random((n, 2), dtype=np.float32), flip_axes=True)

    def run():
        if what == "eval":
            r = bsdf.eval(ctx, si, v)
        elif what == "pdf":
            r = bsdf.pdf(ctx, si, v)
        else:
            r = bsdf.sample(ctx, si, mi.Float(0.5), u)
        dr.eval(r)
        dr.sync_thread()
    return run


def throughput(tmp, n, quick):
    rng = np.random.default_rng(3)
    src_iso = bk.Conductor.from_metal("Cu", alpha=0.25, masking="separable")
    tab = bk.measured.tabulate(src_iso, resolution=32)
    tpath = tab.save(os.path.join(tmp, "thr_rgb.bsdf"))
    meas = bk.Measured.load(tpath)
    mpath = bk.measured.write_merl(os.path.join(tmp, "thr.binary"), src_iso)
    models = [("Conductor Cu α=0.25 (analytic source)", src_iso), ("Measured (tensor, resolution 32)", meas),
              ("MERL nearest", bk.MERL(mpath)), ("MERL linear", bk.MERL(mpath, interpolation="linear"))]
    wo, wi = pairs(rng, n, zmin=0.05)
    u = rng.random((n, 2))
    uc = rng.random(n)
    rows = []
    for dt_name, dt in (("f32", np.float32), ("f64", np.float64)):
        a, b, uu, cc = wo.astype(dt), wi.astype(dt), u.astype(dt), uc.astype(dt)
        f_out, p_out = np.empty((n, 3), dt), np.empty(n, dt)
        for name, m in models:
            te = best_time(lambda: m.eval(a, b, out=f_out), repeats=3)
            tp = best_time(lambda: m.pdf(a, b, out=p_out), repeats=3)
            ts = best_time(lambda: m.sample(a, cc, uu), repeats=3)
            rows.append(dict(model=name, dtype=dt_name, eval=n / te / 1e6, pdf=n / tp / 1e6, sample=n / ts / 1e6))
    # Mitsuba measured on the same file and arrays, timed back to back with ours (float32)
    mit = {}
    for what in ("eval", "pdf", "sample"):
        run = mitsuba_timer(tpath, wo, wi, what)
        mit[what] = n / best_time(run, repeats=3) / 1e6
    a, b, uu, cc = wo.astype(np.float32), wi.astype(np.float32), u.astype(np.float32), uc.astype(np.float32)
    f_out, p_out = np.empty((n, 3), np.float32), np.empty(n, np.float32)
    ours = dict(eval=n / best_time(lambda: meas.eval(a, b, out=f_out), repeats=3) / 1e6,
                pdf=n / best_time(lambda: meas.pdf(a, b, out=p_out), repeats=3) / 1e6,
                sample=n / best_time(lambda: meas.sample(a, cc, uu), repeats=3) / 1e6)
    return rows, dict(mitsuba=mit, ours=ours, threads=bk.get_num_threads())


def tabulation(resolutions):
    rng = np.random.default_rng(5)
    wo, wi = pairs(rng, 40000)
    out = []
    for name, src in (("isotropic: Conductor Au α=0.3", bk.Conductor.from_metal("Au", alpha=0.3)),
                      ("anisotropic: Conductor Cu αx=0.15 αy=0.45", bk.Conductor.from_metal("Cu", alpha_x=0.15, alpha_y=0.45)),
                      ("FilamentStandard base 0.8,0.5,0.3 r=0.5", bk.FilamentStandard([0.8, 0.5, 0.3]))):
        for N in resolutions:
            t0 = time.perf_counter()
            t = bk.measured.tabulate(src, resolution=N)
            dt = time.perf_counter() - t0
            med, p90, p99 = errors(t, src, wo, wi)
            out.append(dict(model=name, resolution=N, size_kb=len(t._entry()[3]) / 1024, build_s=dt,
                            median=med, p90=p90, p99=p99))
    return out


def merl_rows(tmp):
    rng = np.random.default_rng(6)
    wo, wi = pairs(rng, 50000)
    rows, eff = [], []
    for name, src in (("Conductor Cu α=0.25", bk.Conductor.from_metal("Cu", alpha=0.25)),
                      ("Conductor Au α=0.08", bk.Conductor.from_metal("Au", alpha=0.08)),
                      ("FilamentStandard base 0.8,0.5,0.3 r=0.5", bk.FilamentStandard([0.8, 0.5, 0.3]))):
        p = bk.measured.write_merl(os.path.join(tmp, "rt.binary"), src)
        for interp in ("nearest", "linear"):
            m = bk.MERL(p, interpolation=interp)
            med, p90, p99 = errors(m, src, wo, wi)
            rows.append(dict(model=name, interpolation=interp, median=med, p90=p90, p99=p99))
        m = bk.MERL(p)
        for deg in (10, 45, 70, 85):
            w_o = bk.direction(np.radians(deg), 0.0)
            s = m.sample(w_o, n=200000, seed=2)
            w = s.weight @ LUM
            u = rng.random((200000, 2))
            r, ph = np.sqrt(u[:, 0]), 2 * np.pi * u[:, 1]
            wc = np.stack([r * np.cos(ph), r * np.sin(ph), np.sqrt(1 - u[:, 0])], 1)
            c = (m.eval(w_o, wc) @ LUM) * np.pi
            eff.append(dict(model=name, theta_o=deg, rv_tab=float(w.var() / w.mean() ** 2),
                            rv_cos=float(c.var() / c.mean() ** 2), albedo_tab=float(w.mean()), albedo_cos=float(c.mean())))
    return rows, eff


def write_md(res, path):
    L = []
    L.append("# Measured materials: MERL tables and RGL tensor files\n")
    L.append(f"`python bench/measured.py` on {res['machine']}, {res['date']}, {res['threads']} threads. "
             "The machine was shared and loaded: read the ratios, not the absolute throughputs.\n")
    L.append("## Tabulation error: `bk.measured.tabulate(model, resolution=N)` vs the model\n")
    L.append("Relative luminance error of f over 40 000 random pairs (cos > 0.15 both, f > 1 % of the max); "
             "every 2-D table is N x N, n_theta = max(6, N/4) incidence slices (anisotropic: 2 n_theta + 1 azimuths).\n")
    L.append("| source | N | file size | build time | median | p90 | p99 |\n|---|---:|---:|---:|---:|---:|---:|")
    for r in res["tabulation"]:
        L.append(f"| {r['model']} | {r['resolution']} | {r['size_kb']:.0f} kB | {r['build_s']:.1f} s | "
                 f"{r['median']:.4f} | {r['p90']:.4f} | {r['p99']:.4f} |")
    L.append("\n## MERL round trip: `write_merl(model)` -> `MERL.load` -> eval vs the model\n")
    L.append("| source | interpolation | median | p90 | p99 |\n|---|---|---:|---:|---:|")
    for r in res["merl"]:
        L.append(f"| {r['model']} | {r['interpolation']} | {r['median']:.4f} | {r['p90']:.4f} | {r['p99']:.4f} |")
    L.append("\n## MERL sampler efficiency\n")
    L.append("Relative variance Var[w]/E[w]^2 of the luminance weight w = f cos / pdf (200 000 samples): bsdfkit's "
             "tabulated half-vector sampler (32 θo tables x 90 θh rows x 64 φh columns, 10 % cosine) vs cosine "
             "sampling. Lower is better; the ratio is the factor in samples saved for the same variance.\n")
    L.append("| source (MERL nearest) | θo | tabulated | cosine | cosine / tabulated | albedo (tab, cos) |\n"
             "|---|---:|---:|---:|---:|---|")
    for r in res["merl_sampler"]:
        L.append(f"| {r['model']} | {r['theta_o']}° | {r['rv_tab']:.3f} | {r['rv_cos']:.3f} | "
                 f"{r['rv_cos'] / max(r['rv_tab'], 1e-12):.1f} | {r['albedo_tab']:.4f}, {r['albedo_cos']:.4f} |")
    L.append("\n## Load time and memory\n")
    L.append("Cold load (caches cleared) = read, validate, digest (SHA-256), build the shared tables (MERL: + the "
             "sampler; tensor: the warps' CDFs). Table memory is computed from the sizes (float64 and float32 copies); "
             "the RSS growth is the process's resident-set change (rough: freed buffers are reused).\n")
    L.append("| file | size | load | shared tables | RSS growth |\n|---|---:|---:|---:|---:|")
    for r in res["load"]:
        L.append(f"| {r['kind']} | {r['size_mb']:.2f} MB | {r['load_s'] * 1e3:.0f} ms | {r['table_mb']:.1f} MB | "
                 f"{r['rss_mb']:.0f} MB |")
    L.append(f"\n## Throughput (M elements/s, {res['n']} pairs)\n")
    L.append("| model | dtype | eval | pdf | sample |\n|---|---|---:|---:|---:|")
    for r in res["throughput"]:
        L.append(f"| {r['model']} | {r['dtype']} | {r['eval']:.1f} | {r['pdf']:.1f} | {r['sample']:.1f} |")
    mm = res["vs_mitsuba"]
    L.append("\n### Against Mitsuba `measured` on the same file and arrays (float32, llvm_ad_rgb, timed back to back)\n")
    L.append("| | ours | Mitsuba | ours / Mitsuba |\n|---|---:|---:|---:|")
    for k in ("eval", "pdf", "sample"):
        L.append(f"| {k} | {mm['ours'][k]:.1f} | {mm['mitsuba'][k]:.1f} | {mm['ours'][k] / mm['mitsuba'][k]:.2f} |")
    L.append("\nMitsuba's figure includes its JIT launch (kernels are cached after the first call) and its "
             "own threads; ours runs on `bk.get_num_threads()` threads.\n")
    Path(path).write_text("\n".join(L) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out-dir", default=str(HERE))
    args = ap.parse_args()
    n = 100_000 if args.quick else 1_000_000
    resolutions = (8, 16, 32) if args.quick else (8, 16, 32, 64)
    with tempfile.TemporaryDirectory() as tmp:
        res = dict(machine=f"{platform.machine()} {os.cpu_count()} cores", date=_dt.date.today().isoformat(),
                   threads=bk.get_num_threads(), n=n)
        res["tabulation"] = tabulation(resolutions)
        res["merl"], res["merl_sampler"] = merl_rows(tmp)
        res["load"] = load_rows(tmp, resolutions)
        res["throughput"], res["vs_mitsuba"] = throughput(tmp, n, args.quick)
    out = Path(args.out_dir)
    (out / "measured.json").write_text(json.dumps(res, indent=1))
    write_md(res, out / "MEASURED.md")
    print((out / "MEASURED.md").read_text())


if __name__ == "__main__":
    main()
