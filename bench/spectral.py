"""RGB versus spectral throughput of the models with a spectral kernel (issue 15): eval and sample,
float32 and float64, the same directions and uniforms; spectral calls get 4 wavelengths per pair
(pbrt-v4's visible sampling). Reported as the ratio spectral / RGB time per call (the machine is
shared: absolute rates are not headlines), median of REPEATS interleaved repetitions with the
spread (min..max of the per-repetition ratios), with the CPU model, the packet width of the RGB
kernels, the thread count and the load average. Each row also times the scalar per-element
spectral path (the ``_core`` entry with ``packets=False``: the path before the packet kernels,
outputs allocated as the Python layer does) in the same repetitions, so "before / after" is one run. Writes bench/spectral.json, the table of
bench/SPECTRAL.md (between the markers) and the spectral / RGB cost ratios of the tuning registry's
``color`` knob (python/bsdfkit/tuning/_color_costs.json, per cost family, dtype and op).

``--errors``: instead, the RGB-versus-spectral error table per material (the ``color`` knob's
error, bsdfkit.tuning: f |cos| of RGB mode against spectral mode integrated to linear sRGB under
a D65 white furnace, per direction pair and as directional albedo), bench/SPECTRAL.md between
the ``errors`` markers and bench/spectral_errors.json.

    python bench/spectral.py [--n 400000] [--repeats 7] [--threads 2]
    python bench/spectral.py --errors [--pairs 8192]
"""
import argparse
import json
import os
import re
import time
from pathlib import Path

import numpy as np

import bsdfkit as bk
from bsdfkit.models._spectral import _spectral_core
from _host import cpu_model, simd_isa  # same directory

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
    # session 6: the split-channel adapters (batch_spectral.h)
    "Plastic rough": (lambda: bk.Plastic((0.8, 0.3, 0.1), alpha=0.2),
                      lambda: bk.Plastic(bk.Spectrum([360.0, 830.0], [0.2, 0.8]), alpha=0.2)),
    "Plastic smooth": (lambda: bk.Plastic((0.8, 0.3, 0.1)), lambda: bk.Plastic(bk.Spectrum([360.0, 830.0], [0.2, 0.8]))),
    "NormalizedFresnel, BK7": (lambda: bk.NormalizedFresnel(1.5),
                               lambda: bk.NormalizedFresnel(bk.Spectrum.named("glass-BK7"))),
    "FilamentStandard": (lambda: bk.FilamentStandard((0.8, 0.3, 0.1), roughness=0.4),
                         lambda: bk.FilamentStandard(bk.Spectrum([360.0, 830.0], [0.2, 0.8]), roughness=0.4)),
    "FilamentStandard coat+sheen": (
        lambda: bk.FilamentStandard((0.8, 0.3, 0.1), clear_coat=0.5, sheen_color=0.5, sheen_roughness=0.4),
        lambda: bk.FilamentStandard(bk.Spectrum([360.0, 830.0], [0.2, 0.8]), clear_coat=0.5, sheen_color=0.5,
                                    sheen_roughness=0.4)),
    "CoatedDiffuse analytic": (lambda: bk.CoatedDiffuse((0.8, 0.3, 0.1), alpha=0.1, method="analytic"),
                               lambda: bk.CoatedDiffuse(bk.Spectrum([360.0, 830.0], [0.2, 0.8]), alpha=0.1,
                                                        method="analytic")),
    "CoatedConductor analytic, Au": (
        lambda: bk.CoatedConductor.from_metal("Au", conductor_alpha=0.3, interface_alpha=0.05, method="analytic"),
        lambda: bk.CoatedConductor(bk.Spectrum.named("mitsuba-Au-eta"), bk.Spectrum.named("mitsuba-Au-k"),
                                   conductor_alpha=0.3, interface_alpha=0.05, method="analytic")),
    # session 7: Hair (sigma_a(lambda); spectral/hair_spectral.h) and FilamentCloth (split channels)
    "Hair (h 0.3)": (lambda: bk.Hair([0.3, 0.9, 2.2], h=0.3),
                     lambda: bk.Hair(bk.Spectrum([360.0, 830.0], [2.0, 0.3]), h=0.3)),
    "Hair far field (16 nodes)": (lambda: bk.Hair([0.3, 0.9, 2.2], h=None, nodes=16),
                                  lambda: bk.Hair(bk.Spectrum([360.0, 830.0], [2.0, 0.3]), h=None, nodes=16)),
    "FilamentCloth subsurface": (
        lambda: bk.FilamentCloth((0.35, 0.02, 0.08), subsurface_color=(0.3, 0.05, 0.05), roughness=0.35),
        lambda: bk.FilamentCloth(bk.Spectrum([360.0, 830.0], [0.2, 0.8]), subsurface_color=(0.3, 0.05, 0.05),
                                 roughness=0.35)),
    # session 7 (measspec): the measured models (one model: RGB mode reads its RGB / projected
    # table, spectral mode its spectra or uplifted bins) and the stochastic coated walk
    "Measured, spectral file": (lambda: _spectral_tensor(), lambda: _spectral_tensor()),
    "MERL nearest, Cu": (lambda: bk.MERL.from_metal("Cu"), lambda: bk.MERL.from_metal("Cu")),
    "MERL linear, Cu": (lambda: bk.MERL.from_metal("Cu", interpolation="linear"),
                        lambda: bk.MERL.from_metal("Cu", interpolation="linear")),
    "CoatedDiffuse walk, medium": (
        lambda: bk.CoatedDiffuse((0.8, 0.3, 0.1), alpha=0.1, albedo=(0.7, 0.5, 0.3), thickness=0.2),
        lambda: bk.CoatedDiffuse(bk.Spectrum([360.0, 830.0], [0.2, 0.8]), alpha=0.1,
                                 albedo=bk.Spectrum([360.0, 830.0], [0.3, 0.7]), thickness=0.2)),
    "CoatedConductor walk, Au": (
        lambda: bk.CoatedConductor.from_metal("Au", conductor_alpha=0.3, interface_alpha=0.05),
        lambda: bk.CoatedConductor(bk.Spectrum.named("mitsuba-Au-eta"), bk.Spectrum.named("mitsuba-Au-k"),
                                   conductor_alpha=0.3, interface_alpha=0.05)),
}


def _spectral_tensor(_cache={}):
    """A spectral RGL tensor file (the tabulated rough gold's luminance times a reflectance peak
    moving with the sample-space position; 26 wavelengths over 360-1000 nm), written once."""
    if "m" not in _cache:
        import tempfile
        from bsdfkit.models import measured as mm
        tab = bk.measured.tabulate(bk.Conductor.from_metal("Au", alpha=0.3), resolution=32, n_theta=8)
        f = {k: np.array(v) for k, v in tab.fields.items()}
        rgb = f.pop("rgb")
        lum = np.einsum("c,ptcyx->ptyx", [0.2126, 0.7152, 0.0722], rgb)
        wl = np.concatenate([np.linspace(360, 700, 18), np.linspace(720, 1000, 8)])
        y = np.linspace(0, 1, rgb.shape[-1])[:, None]
        peak = 0.15 + 0.7 * np.exp(-0.5 * ((wl[:, None, None] - (430 + 250 * y)) / 45.0) ** 2)
        f["spectra"] = (lum[:, :, None] * peak[None, None]).astype(np.float32)
        f["wavelengths"] = wl.astype(np.float32)
        _cache["m"] = bk.Measured(mm.write_tensor(os.path.join(tempfile.mkdtemp(), "au_spec.bsdf"), f))
    return _cache["m"]


def _au(**kw):
    return bk.Conductor.from_metal("Au", spectral=True, **kw)


#: Materials of the RGB-versus-spectral error table (spectral parameters: measured metal and glass
#: data, sampled reflectance spectra).
R_SPEC = bk.Spectrum([360.0, 430.5, 520.0, 610.0, 700.0, 830.0], [0.05, 0.31, 0.62, 0.40, 0.90, 0.83])
MATERIALS = {
    "Au, rough (alpha 0.3)": lambda: _au(alpha=0.3),
    "Au, mirror": lambda: _au(),
    "Cu, rough (alpha 0.3)": lambda: bk.Conductor.from_metal("Cu", spectral=True, alpha=0.3),
    "Ag, rough (alpha 0.3)": lambda: bk.Conductor.from_metal("Ag", spectral=True, alpha=0.3),
    "Al, rough (alpha 0.3)": lambda: bk.Conductor.from_metal("Al", spectral=True, alpha=0.3),
    "Cr, rough (alpha 0.3)": lambda: bk.Conductor.from_metal("Cr", spectral=True, alpha=0.3),
    "BK7 glass, rough (alpha 0.3)": lambda: bk.Dielectric(bk.Spectrum.named("glass-BK7"), alpha=0.3),
    "diffuse, sampled spectrum": lambda: bk.Diffuse(R_SPEC),
    "plastic, sampled spectrum, alpha 0.2": lambda: bk.Plastic(R_SPEC, alpha=0.2),
    "Filament, spectral base colour": lambda: bk.FilamentStandard(R_SPEC, roughness=0.4),
    "Filament metal, spectral base colour": lambda: bk.FilamentStandard(R_SPEC, metallic=1.0, roughness=0.4),
    "coated Au (analytic)": lambda: bk.CoatedConductor(bk.Spectrum.named("mitsuba-Au-eta"),
                                                       bk.Spectrum.named("mitsuba-Au-k"), conductor_alpha=0.3,
                                                       interface_alpha=0.05, method="analytic"),
    "NormalizedFresnel, BK7": lambda: bk.NormalizedFresnel(bk.Spectrum.named("glass-BK7")),
}


def errors_table(pairs):
    """RGB mode against spectral mode per material (float64, every other knob as given): the
    ``color`` knob's two configurations only, measured as bsdfkit.tuning measures every knob."""
    from bsdfkit.tuning.configs import Config
    from bsdfkit.tuning.errors import (FLOOR_FRACTION, _Prepared, _values, direction_set, relative_error,
                                       relative_rms)
    rows = []
    for name, make in MATERIALS.items():
        m = make()
        t0 = time.perf_counter()
        ds = direction_set(m, pairs, 0, n_albedo=2048)
        prep = _Prepared(m, ds)
        cfg = lambda c: Config({"color": c}, {"color": 0}, m, np.float64, c)   # noqa: E731
        v_ref, a_ref = _values(cfg("spectral"), prep)
        v, a = _values(cfg("rgb"), prep)
        floor = FLOOR_FRACTION * float(np.mean(np.abs(a_ref))) / np.pi
        e = relative_error(v_ref, v, floor)
        # grazing: pairs with both cosines below 0.2
        graze = (np.abs(np.concatenate([ds.wo, ds.delta_wo])[:, 2]) < 0.2)
        row = {"material": name, "max_err": float(e.max()), "p99_err": float(np.quantile(e, 0.99)),
               "rms_err": relative_rms(v_ref, v), "albedo_err": float(np.max(np.abs(a - a_ref))),
               "albedo_ref_max": float(np.max(a_ref)),
               "grazing_p99_err": float(np.quantile(e[graze], 0.99)) if graze.any() else None,
               "normal_albedo_err": [float(x) for x in a[0] - a_ref[0]],
               "seconds": time.perf_counter() - t0}
        rows.append(row)
        print(f"{name:40s} p99 {row['p99_err']:.2e} max {row['max_err']:.2e} rms {row['rms_err']:.2e} "
              f"albedo {row['albedo_err']:.2e} ({row['seconds']:.0f} s)", flush=True)
    return rows


def _sample_outputs(n, dtype):
    """The spectral sample's output arrays (wi, f, pdf, flags, eta, valid, pdf_is_proportional, terminated)."""
    return (np.empty((n, 3), dtype), np.empty((n, 4), dtype), np.empty(n, dtype), np.empty(n, np.uint8),
            np.empty(n, dtype), np.empty(n, bool), np.empty(n, bool), np.empty(n, bool))


def timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=400_000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--errors", action="store_true", help="the RGB-versus-spectral error table instead")
    ap.add_argument("--pairs", type=int, default=8192)
    args = ap.parse_args()
    bk.set_num_threads(args.threads)
    if args.errors:
        return write_errors(errors_table(args.pairs), args.pairs)
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
            core = _spectral_core(m_sp)
            ops = {
                "eval": (lambda: m_rgb.eval(wo, wi), lambda: m_sp.eval(wo, wi, wavelengths=lam),
                         lambda: core.eval(wo, wi, lam, 0, np.empty((n, 4), dtype), packets=False)),
                "sample": (lambda: m_rgb.sample(wo, ucd, ud), lambda: m_sp.sample(wo, ucd, ud, wavelengths=lam),
                           lambda: core.sample(wo, ucd, ud, lam, 0, 3, *_sample_outputs(n, dtype), packets=False)),
            }
            for op, (f_rgb, f_sp, f_scalar) in ops.items():
                f_rgb(), f_sp(), f_scalar()  # warm-up (uplift, caches, first touch)
                t_rgb, t_sp, t_sc = [], [], []
                for _ in range(args.repeats):     # interleaved: load changes hit all three
                    t_rgb.append(timed(f_rgb))
                    t_sp.append(timed(f_sp))
                    t_sc.append(timed(f_scalar))
                ratios = np.array(t_sp) / np.array(t_rgb)
                ratios_sc = np.array(t_sc) / np.array(t_rgb)
                rows.append({"model": name, "dtype": np.dtype(dtype).name, "op": op,
                             "rgb_s": float(np.median(t_rgb)), "spectral_s": float(np.median(t_sp)),
                             "ratio": float(np.median(ratios)), "ratio_min": float(ratios.min()),
                             "ratio_max": float(ratios.max()), "scalar_s": float(np.median(t_sc)),
                             "ratio_scalar": float(np.median(ratios_sc)), "ratio_scalar_min": float(ratios_sc.min()),
                             "ratio_scalar_max": float(ratios_sc.max())})
                print(f"{name:32s} {np.dtype(dtype).name:8s} {op:7s} spectral/RGB time {rows[-1]['ratio']:6.2f} "
                      f"({ratios.min():.2f}..{ratios.max():.2f}); scalar path {rows[-1]['ratio_scalar']:6.2f} "
                      f"({ratios_sc.min():.2f}..{ratios_sc.max():.2f})", flush=True)
    meta = {"cpu": cpu_model(), "simd": simd_isa(), "packet_width": 16, "threads": args.threads, "n": n,
            "repeats": args.repeats, "load_before": load_before, "load_after": os.getloadavg(),
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    (HERE / "spectral.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    lines = [f"CPU: {meta['cpu']} ({meta['simd']}; {meta['packet_width']}-lane packets), {args.threads} threads, "
             f"n = {n} pairs per call, {args.repeats} interleaved repetitions, load average "
             f"{load_before[0]:.1f} before / {meta['load_after'][0]:.1f} after ({meta['date']}). "
             "Spectral: the kernel `wavelengths=` runs (packets for the pbrt-core models); scalar path: the "
             "per-element loop (`packets=False`, the spectral kernels before the packet path).", "",
             "| model | dtype | op | spectral / RGB time (median) | spread (min..max) | scalar path / RGB | spread |",
             "|---|---|---|--:|---|--:|---|"]
    for r in rows:
        lines.append(f"| {r['model']} | {r['dtype']} | {r['op']} | {r['ratio']:.2f} | "
                     f"{r['ratio_min']:.2f}..{r['ratio_max']:.2f} | {r['ratio_scalar']:.2f} | "
                     f"{r['ratio_scalar_min']:.2f}..{r['ratio_scalar_max']:.2f} |")
    md = HERE / "SPECTRAL.md"
    text = md.read_text() if md.exists() else "<!-- table -->\n<!-- /table -->\n"
    text = re.sub(r"<!-- table -->.*<!-- /table -->", "<!-- table -->\n" + "\n".join(lines) + "\n<!-- /table -->",
                  text, flags=re.S)
    md.write_text(text)
    write_color_costs(rows, meta)


def write_color_costs(rows, meta):
    """The ``color`` knob's cost table: spectral / RGB time per cost family, dtype and op (the
    spectral model's family), and their median as the default for unmeasured families."""
    fams = {}
    for r in rows:
        fam = MODELS[r["model"]][1]().cost_family()
        fams.setdefault(fam, {}).setdefault(r["dtype"], {})[r["op"]] = round(r["ratio"], 3)
    out = {"meta": {k: meta[k] for k in ("cpu", "simd", "threads", "n", "repeats", "load_before", "date")},
           "note": "spectral / RGB time of the same call (bench/spectral.py); median of interleaved repetitions",
           "families": fams, "default": round(float(np.median([r["ratio"] for r in rows])), 3)}
    path = HERE.parent / "python" / "bsdfkit" / "tuning" / "_color_costs.json"
    path.write_text(json.dumps(out, indent=1) + "\n")


def write_errors(rows, pairs):
    (HERE / "spectral_errors.json").write_text(json.dumps({"pairs": pairs, "rows": rows}, indent=1))
    lines = [f"bsdfkit {bk.__version__}, {pairs} direction pairs per material (tuning's default set: half "
             "stratified, half samples of the spectral model) plus 6 x 2048 albedo samples; float64.", "",
             "| material | p99 rel. error f cos | p99 at grazing wo (cos < 0.2) | max rel. error | rel. RMS | "
             "albedo abs. error, max over wo (max albedo) |", "|---|--:|--:|--:|--:|--:|"]
    for r in rows:
        g = "—" if r["grazing_p99_err"] is None else f"{r['grazing_p99_err']:.2e}"
        lines.append(f"| {r['material']} | {r['p99_err']:.2e} | {g} | {r['max_err']:.2e} | {r['rms_err']:.2e} | "
                     f"{r['albedo_err']:.2e} ({r['albedo_ref_max']:.2f}) |")
    md = HERE / "SPECTRAL.md"
    text = md.read_text()
    if "<!-- errors -->" not in text:
        text += "\n<!-- errors -->\n<!-- /errors -->\n"
    text = re.sub(r"<!-- errors -->.*<!-- /errors -->", "<!-- errors -->\n" + "\n".join(lines) + "\n<!-- /errors -->",
                  text, flags=re.S)
    md.write_text(text)


if __name__ == "__main__":
    main()
