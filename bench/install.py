"""What installing and starting bsdfkit costs (issue 52): a report script, not a timed test.

    python bench/install.py                      # import and first-use times, linked libraries
    python bench/install.py --build              # + a cold build of each target (CPU s, wall s, peak RSS)
    python bench/install.py --ab DIR_A DIR_B     # same-run kernel speed of two builds of _core

Import and first use: each figure is the median (and min) over fresh interpreters, ``import numpy``
measured the same way beside ``import bsdfkit``; first spectral eval is the first
``eval(..., wavelengths=...)`` of a process (the colour tables, the spectral kernel object), first
render / io the first call that loads the optional extension bsdfkit._render (Embree, OpenImageIO).

--build configures a scratch build directory (cold: ccache disabled) with the given CMake options
and times every compile and link with /usr/bin/time: CPU (user + sys) seconds, wall seconds and
peak RSS per translation unit, summed per target.

--ab DIR_A DIR_B: each DIR holds a bsdfkit package (python/bsdfkit with its built _core); the
kernels below run in alternating fresh processes, 1 thread, in cache-resident blocks, and the
report gives B / A throughput per kernel (e.g. A = the development build, B = LTO, or
B = a portable -march build against -march=native).

Machines of this kind are shared: quote ratios from one run, with the CPU and load printed.
"""
from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _host import cpu_model, load, simd_isa  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def _py(code, env=None, timeout=600):
    e = dict(os.environ, MPLBACKEND="Agg", **(env or {}))
    r = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, env=e,
                       timeout=timeout)
    if r.returncode != 0:
        raise RuntimeError(r.stderr[-2000:])
    return r.stdout


# ---------------------------------------------------------------- import and first use

_TIMED = {
    "import numpy": ("", "import numpy"),
    "import bsdfkit": ("import numpy", "import bsdfkit"),
    "first spectral eval (Conductor Cu, named spectra)": (
        "import numpy as np, bsdfkit as bk\n"
        "m = bk.Conductor.from_metal('Cu', roughness=0.3)\n"
        "wo, wi = bk.direction(0.5, 0.0), bk.hemisphere_grid(16, 32)\n"
        "lam = np.tile([450.0, 500.0, 550.0, 600.0], (wi.shape[0], 1))",
        "m.eval(wo, wi, wavelengths=lam)"),
    "first spectral eval (Diffuse RGB, uplifted)": (
        "import numpy as np, bsdfkit as bk\n"
        "m = bk.Diffuse([0.8, 0.4, 0.2])\n"
        "wo, wi = bk.direction(0.5, 0.0), bk.hemisphere_grid(16, 32)\n"
        "lam = np.tile([450.0, 500.0, 550.0, 600.0], (wi.shape[0], 1))",
        "m.eval(wo, wi, wavelengths=lam)"),
    "first render (16x16, 1 spp: loads bsdfkit._render)": (
        "import bsdfkit as bk\nm = bk.Diffuse(0.5)",
        "bk.render.preview(m, width=16, height=16, spp=1, progress=False)"),
    "first bk.io.write_image (EXR)": (
        "import numpy as np, bsdfkit as bk, tempfile, os\n"
        "p = os.path.join(tempfile.mkdtemp(), 'x.exr'); img = np.zeros((4, 4, 3), np.float32)",
        "bk.io.write_image(p, img)"),
}


def time_first_use(repeats):
    import bsdfkit
    # bytecode as pip writes it at install (PYTHONDONTWRITEBYTECODE would time the compiler instead)
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(Path(bsdfkit.__file__).parent)],
                   stdout=subprocess.DEVNULL, check=False)
    rows = {}
    for label, (setup, stmt) in _TIMED.items():
        code = (f"import time\n{setup}\nt0 = time.perf_counter()\n{stmt}\n"
                "print(time.perf_counter() - t0)\n"
                "import sys; print(int('colour' in sys.modules), int('bsdfkit._render' in sys.modules))")
        ts, flags = [], None
        for _ in range(repeats):
            out = _py(code).split()
            ts.append(float(out[0]))
            flags = out[1:]
        rows[label] = dict(median=statistics.median(ts), min=min(ts), colour_imported=flags[0] == "1",
                           render_loaded=flags[1] == "1")
    return rows


def linked_libraries():
    out = {}
    import importlib.util
    for mod in ("bsdfkit._core", "bsdfkit._render"):
        spec = importlib.util.find_spec(mod)
        if spec is None or not spec.origin:
            out[mod] = None
            continue
        ldd = subprocess.run(["ldd", spec.origin], capture_output=True, text=True).stdout
        out[mod] = dict(path=spec.origin, size_mb=round(os.path.getsize(spec.origin) / 2**20, 2),
                        libraries=sum(1 for line in ldd.splitlines() if "=>" in line or line.strip().startswith("/")))
    return out


# ---------------------------------------------------------------- cold build

_LAUNCHER = """#!/bin/sh
out=unknown; prev=""
for a in "$@"; do [ "$prev" = "-o" ] && out=$a; prev=$a; done
exec /usr/bin/time -f "%e %U %S %M $out" -a -o "$TIMING_LOG" "$@"
"""


def cold_build(cmake_args, jobs):
    import pybind11
    tmp = Path(tempfile.mkdtemp(prefix="bsdfkit-build-"))
    launcher = tmp / "timed.sh"
    launcher.write_text(_LAUNCHER)
    launcher.chmod(0o755)
    log = tmp / "timing.log"
    env = dict(os.environ, TIMING_LOG=str(log), CCACHE_DISABLE="1")
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(tmp / "b"), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                    f"-Dpybind11_DIR={pybind11.get_cmake_dir()}", f"-DCMAKE_CXX_COMPILER_LAUNCHER={launcher}",
                    f"-DCMAKE_CXX_LINKER_LAUNCHER={launcher}", *cmake_args], check=True, env=env,
                   stdout=subprocess.DEVNULL)
    subprocess.run(["ninja", "-C", str(tmp / "b"), f"-j{jobs}"], check=True, env=env, stdout=subprocess.DEVNULL)
    return parse_timing(log)


def parse_timing(log):
    """Rows of a launcher log: wall, user, sys, max RSS (KB), output path."""
    units = []
    for line in Path(log).read_text().splitlines():
        parts = line.split()
        if len(parts) != 5 or not parts[0].replace(".", "").isdigit():
            continue
        wall, user, sys_, rss, out = parts
        if "cmTC_" in out:   # CMake's configure-time try-compiles
            continue
        target = "_render" if "_render" in out else "_core"
        units.append(dict(output=out.split("CMakeFiles/")[-1], target=target, wall=float(wall),
                          cpu=float(user) + float(sys_), rss_mb=int(rss) / 1024))
    targets = {}
    for u in units:
        t = targets.setdefault(u["target"], dict(cpu=0.0, peak_rss_mb=0.0, units=0))
        t["cpu"] += u["cpu"]
        t["peak_rss_mb"] = max(t["peak_rss_mb"], u["rss_mb"])
        t["units"] += 1
    return dict(units=units, targets=targets)


# ---------------------------------------------------------------- same-run kernel A/B

_KERNELS = """
import time, json, numpy as np, bsdfkit as bk
bk.set_num_threads(1)
models = {"Diffuse": bk.Diffuse(0.5), "Conductor a=0.3": bk.Conductor.from_metal("Cu", roughness=0.3),
          "Dielectric a=0.2": bk.Dielectric(eta=1.5, alpha=0.2), "FilamentStandard": bk.FilamentStandard()}
rng = np.random.default_rng(1)
n = 1 << 16
wo = bk.direction(np.arccos(rng.random(n)), 2 * np.pi * rng.random(n))
wi = bk.direction(np.arccos(rng.random(n)), 2 * np.pi * rng.random(n))
uc, u = rng.random(n), rng.random((n, 2))
out = {}
for name, m in models.items():
    for op, fn in (("eval", lambda: m.eval(wo, wi)), ("sample", lambda: m.sample(wo, uc=uc, u=u))):
        fn()
        best = float("inf")
        for _ in range(7):
            t = time.perf_counter(); fn(); best = min(best, time.perf_counter() - t)
        out[f"{name} {op}"] = n / best
print(json.dumps(out))
"""


def kernel_ab(dir_a, dir_b, rounds):
    res = {"A": [], "B": []}
    for _ in range(rounds):
        for key, d in (("A", dir_a), ("B", dir_b)):
            res[key].append(json.loads(_py(_KERNELS, env=dict(PYTHONPATH=str(d)))))
    rows = {}
    for k in res["A"][0]:
        a = max(r[k] for r in res["A"])
        b = max(r[k] for r in res["B"])
        rows[k] = dict(a_meps=a / 1e6, b_meps=b / 1e6, ratio=b / a)
    return rows


# ---------------------------------------------------------------- report

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5, help="fresh interpreters per import / first-use figure")
    ap.add_argument("--build", action="store_true", help="also time a cold build (minutes)")
    ap.add_argument("--cmake-args", default="", help="extra CMake options of --build, e.g. '-DBSDFKIT_LTO=ON'")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--ab", nargs=2, metavar=("DIR_A", "DIR_B"), help="same-run kernel A/B of two builds")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--json", help="write the figures to this file too")
    args = ap.parse_args(argv)

    report = dict(machine=f"{cpu_model()} ({simd_isa()}), {os.cpu_count()} CPUs, load {load()[0]:.2f}")
    print(f"# bsdfkit install and start-up\n\nMachine: {report['machine']}\n")
    if args.ab:
        rows = kernel_ab(*args.ab, args.rounds)
        report["ab"] = dict(a=args.ab[0], b=args.ab[1], rows=rows)
        print(f"## Kernel A/B (1 thread, 65536 elements, best of 7 x {args.rounds} alternating processes)\n")
        print(f"A = {args.ab[0]}\nB = {args.ab[1]}\n")
        print("| kernel | A M/s | B M/s | B / A |\n|---|---:|---:|---:|")
        for k, r in rows.items():
            print(f"| {k} | {r['a_meps']:.1f} | {r['b_meps']:.1f} | {r['ratio']:.3f} |")
        print()
    else:
        libs = linked_libraries()
        report["libraries"] = libs
        print("## Compiled modules\n\n| module | size MB | linked libraries |\n|---|---:|---:|")
        for mod, v in libs.items():
            print(f"| {mod} | {v['size_mb'] if v else '-'} | {v['libraries'] if v else 'not built'} |")
        rows = time_first_use(args.repeats)
        report["first_use"] = rows
        print(f"\n## Import and first use (seconds; median / min of {args.repeats} fresh processes)\n")
        print("| step | median | min | imported colour-science | loaded _render |\n|---|---:|---:|:-:|:-:|")
        for k, r in rows.items():
            print(f"| {k} | {r['median']:.3f} | {r['min']:.3f} | {'yes' if r['colour_imported'] else 'no'} | "
                  f"{'yes' if r['render_loaded'] else 'no'} |")
    if args.build:
        b = cold_build(shlex.split(args.cmake_args), args.jobs)
        report["build"] = b
        print(f"\n## Cold build ({args.cmake_args or 'default options'}; -j{args.jobs}; ccache off)\n")
        print("| unit | CPU s | wall s | peak RSS MB |\n|---|---:|---:|---:|")
        for u in sorted(b["units"], key=lambda u: -u["cpu"]):
            print(f"| {u['output']} | {u['cpu']:.1f} | {u['wall']:.1f} | {u['rss_mb']:.0f} |")
        for t, v in b["targets"].items():
            print(f"| **{t}** ({v['units']} steps) | **{v['cpu']:.1f}** | | **{v['peak_rss_mb']:.0f}** |")
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    main()
