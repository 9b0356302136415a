#!/usr/bin/env python3
"""Preview renderer speed: bsdfkit.render vs Mitsuba 3's ``path`` integrator (llvm_ad_rgb).

    python bench/render.py            # 256 x 256, 64 spp, 1 and 2 threads, ~1-2 min
    python bench/render.py --quick    # 128 x 128, 16 spp

Scene: the demo gallery of the first measurement (``render.gallery_scene`` of the eight models in
``MODELS``: one sphere each on the checkerboard ground under the procedural sky; the demo's own list
has since grown models Mitsuba has no plugin for, so the bench keeps this fixed list), rendered by
both at the same resolution, spp and depth (ours max_depth 8 = Mitsuba max_depth 9). The Mitsuba scene comes from
``bsdfkit.testing.mitsuba_scene`` (same camera, sphere placement, envmap resampled at
Mitsuba's texel positions, checkerboard ground). DiffuseTransmission has no Mitsuba plugin:
Mitsuba renders that sphere as a two-sided diffuse of the same reflectance + transmittance
(noted in the report); everything else is the same model.

Timed:
  time-to-image  wall time from the scene description to the float image in numpy: ours =
                 scene/BVH build + path tracing; Mitsuba = load_dict + render + copy, first
                 call (includes its JIT compilation: "cold") and the best later call with the
                 kernel cached in memory ("warm").
  paths/s        width * height * spp / path-tracing time (warm for Mitsuba).
  rays/s         ours only: camera + bounce + shadow rays counted by the renderer.
Mitsuba runs in a subprocess per thread count (its own thread pool, dr.set_thread_count);
rounds of ours and Mitsuba's alternate so load drift on a shared machine biases neither.
Writes bench/RENDER.md and bench/render.json (or --out-dir).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


# The models of the demo gallery when the renderer was first measured against Mitsuba (all have
# a Mitsuba plugin but DiffuseTransmission, see mitsuba_bsdf).
MODELS = ['Diffuse(0.8)', 'DiffuseTransmission(0.5, 0.4)', 'Conductor.from_metal("Au", alpha=0.2)',
          'Conductor.from_metal("Cu", alpha=0)', 'Conductor.from_metal("Al", alpha_x=0.4, alpha_y=0.1)',
          'Dielectric(1.5, alpha=0.2)', 'Dielectric(1.5)', 'ThinDielectric(1.5)']


def build_scene():
    import bsdfkit as bk
    from bsdfkit import render as R
    models = [eval(m, {}, vars(bk)) for m in MODELS]
    return R.gallery_scene(models), list(MODELS)


def machine_info():
    """CPU model, SIMD width of the build machine and of our packets, cores, Python."""
    cpu, flags = platform.processor() or platform.machine(), set()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name") and cpu in ("", platform.machine()):
                    cpu = line.split(":", 1)[1].strip()
                if line.startswith("flags"):
                    flags = set(line.split(":", 1)[1].split())
    except OSError:
        pass
    isa = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "SSE"
    bits = {"AVX-512": 512, "AVX2": 256, "SSE": 128}[isa]
    return {"cpu": cpu, "isa": isa, "vector_bits": bits, "float_lanes_per_register": bits // 32,
            "packet_lanes": 16, "cores": os.cpu_count(), "python": platform.python_version()}


def mitsuba_bsdf(model):
    from bsdfkit.testing import mitsuba as ref
    if type(model).__name__ == "DiffuseTransmission":
        r = np.clip(np.asarray(model.reflectance) + np.asarray(model.transmittance), 0, 1)
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": r.tolist()}}}
    return ref.to_mitsuba(model)


def mitsuba_worker(args):
    """Subprocess: render the Mitsuba scene `rounds` times, print JSON timings, save the image."""
    from bsdfkit.testing import mitsuba as ref
    from bsdfkit.testing.mitsuba_scene import to_mitsuba_scene
    ref.variant()
    import drjit as dr
    import mitsuba as mi
    dr.set_thread_count(args.threads)
    scene, _ = build_scene()
    times = []
    t0 = time.perf_counter()
    msc = mi.load_dict(to_mitsuba_scene(scene, width=args.width, height=args.height, spp=args.spp,
                                        max_depth=args.max_depth, bsdf_fn=mitsuba_bsdf))
    t_load = time.perf_counter() - t0
    img = None
    for r in range(args.rounds):
        sys.stdin.readline()          # wait for our turn (interleaved rounds)
        t1 = time.perf_counter()
        img = np.array(mi.render(msc, seed=r, spp=args.spp))
        times.append(time.perf_counter() - t1)
        print(json.dumps({"round": r, "seconds": times[-1]}), flush=True)
    np.save(args.image, img)
    print(json.dumps({"done": True, "load": t_load, "times": times}), flush=True)


def ours_round(scene, args, seed):
    from bsdfkit import render as R
    t0 = time.perf_counter()
    img, st = R.render(scene, width=args.width, height=args.height, spp=args.spp, max_depth=args.max_depth,
                       seed=seed, progress=False, return_stats=True)
    return img, time.perf_counter() - t0, st


def run(args):
    import bsdfkit as bk
    scene, names = build_scene()
    results = {"width": args.width, "height": args.height, "spp": args.spp, "max_depth": args.max_depth,
               "machine": machine_info(),
               "threads": {}}
    tmp = tempfile.mkdtemp(prefix="bsdfkit-bench-")
    paths = args.width * args.height * args.spp
    for threads in (1, 2):
        bk.set_num_threads(threads)
        mi_img = os.path.join(tmp, f"mi{threads}.npy")
        cmd = [sys.executable, __file__, "--worker", "--threads", str(threads), "--image", mi_img,
               "--rounds", str(args.rounds), "--width", str(args.width), "--height", str(args.height),
               "--spp", str(args.spp), "--max-depth", str(args.max_depth)]
        load_start = os.getloadavg()[0]
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        ours_t, ours_tti, mi_t = [], [], []
        st = img = None
        for r in range(args.rounds):
            img, tti, st = ours_round(scene, args, seed=r)
            ours_t.append(st["seconds"])
            ours_tti.append(tti)
            proc.stdin.write("\n")
            proc.stdin.flush()
            mi_t.append(json.loads(proc.stdout.readline())["seconds"])
        proc.stdin.close()
        final = json.loads(proc.stdout.readline())
        proc.wait()
        mimg = np.load(mi_img)
        load_end = os.getloadavg()[0]
        # per round: Mitsuba's time / ours in the same round (the first Mitsuba round compiles)
        ratios = [m / o for m, o in zip(mi_t[1:], ours_t[1:])] or [mi_t[0] / ours_t[0]]
        cold = final["load"] + final["times"][0]
        warm_render = min(final["times"][1:]) if len(final["times"]) > 1 else final["times"][0]
        warm = final["load"] + warm_render
        best_ours = min(ours_t)
        rel = float(np.abs(img.mean() - mimg.mean()) / mimg.mean())
        results["threads"][threads] = {
            "ours_render_s": best_ours, "ours_time_to_image_s": min(ours_tti),
            "ours_rays_per_s": st["rays"] / best_ours, "ours_paths_per_s": paths / best_ours,
            "ours_rays": st["rays"],
            "mitsuba_load_s": final["load"], "mitsuba_first_render_s": final["times"][0],
            "mitsuba_render_s": warm_render, "mitsuba_time_to_image_cold_s": cold,
            "mitsuba_time_to_image_warm_s": warm, "mitsuba_paths_per_s": paths / warm_render,
            "speedup_render": warm_render / best_ours, "speedup_time_to_image_warm": warm / min(ours_tti),
            "speedup_time_to_image_cold": cold / min(ours_tti),
            "image_mean_ours": float(img.mean()), "image_mean_mitsuba": float(mimg.mean()),
            "image_mean_rel_diff": rel,
            "round_ratios": ratios, "ratio_median": float(np.median(ratios)),
            "ratio_min": float(min(ratios)), "ratio_max": float(max(ratios)),
            "ours_render_all_s": ours_t, "mitsuba_render_all_s": mi_t,
            "load_start": load_start, "load_end": load_end,
        }
        print(json.dumps({threads: results["threads"][threads]}, indent=1), flush=True)
        if threads == 2 and args.out_dir:
            from bsdfkit.io import write_image
            write_image(os.path.join(args.out_dir, "render_ours.png"), img)
            write_image(os.path.join(args.out_dir, "render_mitsuba.png"), mimg)
    results["configs"] = names
    results["rounds"] = args.rounds
    return results


NOTES = """
## Reading the figures

* The goal was >= 1.5x Mitsuba; the renderer is at about 0.8x (Mitsuba's `path` integrator is
  faster by ~1.25x on this scene, at 1 and at 2 threads alike).
* Mitsuba's "cold" time-to-image includes `load_dict` and the first render; its compiled kernels
  are cached on disk by Dr.Jit, so after the first run on a machine "cold" is nearly "warm"
  (the very first compilation adds a few seconds).
* The image means differ by ~1-2 %: the sun of the procedural sky is a few texels wide and the
  two renderers' texel grids sample it at different places (Mitsuba's rows sit at y / (H - 1),
  ours at (y + 0.5) / H), and Mitsuba draws the DiffuseTransmission sphere as a diffuse one.
  The pixel-exact comparison is tests/test_render_mitsuba.py (smooth analytic environment
  sampled on each grid; agreement to 0.01-0.05 % of the image mean).
* Ray counts are ours (camera + bounce + shadow rays); Mitsuba's Russian roulette starts at depth
  5 (ours after the second bounce), so it traces somewhat more rays per path: paths/s is the
  like-for-like throughput.

## Where the time goes (perf, 1 thread, this scene)

Embree ~30 % (16-wide packets of each bounce's rays and of the shadow rays), environment lookups
and sampling ~10 % after the software prefetch pass (they were ~40 % of the shading time before:
the alias table and texels miss the cache), model code (sample_f / f / pdf through the
`std::variant`) ~10 %, and the rest is scalar per-path glue (frames, normalisations, RNG,
Russian roulette, queues). Steps taken: wavefront per 16 x 16 tile and sample index with Embree
`rtcIntersect16` / `rtcOccluded16` (+15-20 %), O(1) alias-table environment sampling in 16-byte
entries (binary searches were 35 % of the shading time), a 256 x 128 procedural sky (fits L2,
+15 %), prefetching the texels and alias entries of a whole bounce, Cephes-style sin/cos/atan2
(libm was ~10 %). What Mitsuba has and we do not: its megakernel evaluates 16 paths per AVX-512
instruction stream for all shading; reaching it (and 1.5x) needs the shading of a bounce to run
SIMD over the wavefront too (hits sorted by material, SoA arrays, the per-element model code in
vectorised loops as in batch.h).
"""


def write_report(res, out_dir):
    out_dir = Path(out_dir)
    (out_dir / "render.json").write_text(json.dumps(res, indent=1))
    w, h, spp = res["width"], res["height"], res["spp"]
    lines = ["# Preview renderer speed: bsdfkit.render vs Mitsuba 3 `path` (llvm_ad_rgb)", "",
             f"Scene: the demo gallery ({len(res['configs'])} spheres, one per demo configuration, on the "
             f"checkerboard ground under the procedural sky), {w} x {h} pixels, {spp} spp, max_depth "
             f"{res['max_depth']} (Mitsuba {res['max_depth'] + 1}), box filter, independent sampler. "
             f"Machine: {res['machine']['cpu']}, {res['machine']['cores']} cores, {res['machine']['isa']} "
             f"({res['machine']['vector_bits']}-bit vectors; our shading packets: {res['machine']['packet_lanes']} "
             f"float lanes), Python {res['machine']['python']}. Best of {res.get('rounds', '?')} interleaved rounds "
             "(`python bench/render.py`); the spread column is the per-round ratio (Mitsuba's time over ours in the "
             "same round, its compiling first round left out): median [min, max].", "",
             "| threads | ours: render | ours: time-to-image | ours: Mrays/s | ours: Mpaths/s | Mitsuba: render (warm) "
             "| Mitsuba: time-to-image cold / warm | Mitsuba: Mpaths/s | speed ratio (render) | per-round ratio median [min, max] "
             "| ratio time-to-image warm / cold | load (1 min) start / end |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for t, r in sorted(res["threads"].items()):
        lines.append(f"| {t} | {r['ours_render_s']:.3f} s | {r['ours_time_to_image_s']:.3f} s | "
                     f"{r['ours_rays_per_s'] / 1e6:.2f} | {r['ours_paths_per_s'] / 1e6:.2f} | {r['mitsuba_render_s']:.3f} s | "
                     f"{r['mitsuba_time_to_image_cold_s']:.2f} / {r['mitsuba_time_to_image_warm_s']:.3f} s | "
                     f"{r['mitsuba_paths_per_s'] / 1e6:.2f} | **{r['speedup_render']:.2f}x** | "
                     f"{r['ratio_median']:.2f}x [{r['ratio_min']:.2f}, {r['ratio_max']:.2f}] | "
                     f"{r['speedup_time_to_image_warm']:.2f}x / {r['speedup_time_to_image_cold']:.2f}x | "
                     f"{r['load_start']:.1f} / {r['load_end']:.1f} |")
    lines += ["", "Speed ratio = Mitsuba time / our time (> 1: we are faster). Image means (sanity check, the "
              "scenes differ only where noted): " + ", ".join(
                  f"{t} threads: ours {r['image_mean_ours']:.4f} vs Mitsuba {r['image_mean_mitsuba']:.4f} "
                  f"({100 * r['image_mean_rel_diff']:.1f} %)" for t, r in sorted(res["threads"].items())) + ".", ""]
    lines += NOTES.splitlines()
    (out_dir / "RENDER.md").write_text("\n".join(lines) + "\n")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true")
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--height", type=int, default=256)
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--max-depth", type=int, default=8)
    p.add_argument("--rounds", type=int, default=4)
    p.add_argument("--out-dir", default=str(HERE))
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--threads", type=int, default=2, help=argparse.SUPPRESS)
    p.add_argument("--image", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.quick:
        args.width = args.height = 128
        args.spp = 16
        args.rounds = 3
    if args.worker:
        mitsuba_worker(args)
        return
    res = run(args)
    if args.out_dir:
        write_report(res, args.out_dir)
        print(f"wrote {Path(args.out_dir) / 'RENDER.md'}")


if __name__ == "__main__":
    main()
