"""Static throughput of a packet kernel's loop with llvm-mca: cycles per packet and port pressure,
a figure no neighbour on a shared host can disturb.

    python tools/perf/mca.py cond_rough eval                 # -mcpu=sapphirerapids (an AVX-512 host)
    python tools/perf/mca.py diel_rough pdf --mcpu znver3    # the AMD Zen 3 model (build with -march=znver3)
    python tools/perf/mca.py diel_smooth sample --mcpu znver4 --mitsuba   # and Mitsuba's own kernel beside it
    python tools/perf/mca.py --list

It writes a small translation unit whose loop is batch.h's packet loop for one model and op
(rows of (N, 3) loaded and stored through batch.h's shuffles, bsdf_f / bsdf_pdf on Packet<float>
with a per-call local copy of the model), between llvm-mca region markers; compiles it with the
library's flags (g++ -O3 -march=<--march> -ffp-contract=off ...); takes the loop body from the
assembly by following the code from the begin marker to the end marker, through unconditional
jumps (GCC rotates the loop, so the end marker can come first in the text) and, at conditional
branches, along the longer side (a model's uniform switches, smooth vs rough, then take the costlier
one, the *_smooth keys the shorter, smooth one; --take picks the sides instead); and runs llvm-mca
on it. `sample` is the model's sampler alone (wo as rows, the uniforms as planes; f and wi stored as
rows, pdf and eta as planes), without the kernel's acceptance rule, uniform checks and byte outputs.

--mitsuba adds the same figures for Mitsuba's kernel of the same model and op (tools/perf/throughput.py's
plugin dictionary, variant llvm_ad_rgb): the LLVM IR Dr.Jit generated for it on this host, taken
from Dr.Jit's kernel history, compiled with llc for the target Dr.Jit chose, and its vectorized
loop. Mitsuba reads and writes planes and checks nothing, so the difference per packet is the model
code plus our (N, 3) rows (session 27, Zen 4: smooth Dielectric sample 123 vs 70 instructions, with
2 divisions and 1 square root each; rough Dielectric eval 166 vs 161, 1 vs 11 divisions; smooth
Conductor sample 121 vs 157, 3 vs 6 divisions).

Read the figures as a model of the core, not a measurement. llvm-mca 19's sapphirerapids model
issues 512-bit multiplies and FMAs on port 0 only and 512-bit additions on port 5, and leaves the
divider's occupancy out; icelake-server models the divider (vsqrtps zmm ~12 cycles). On this
project's Sapphire Rapids host 12 independent register chains of 512-bit multiplies took the same
time as 6 multiplies + 6 additions (session 18, 20000-iteration runs; longer runs of repeated
multiplies reach the denormals and slow down), so additions there do not run beside the multiplies
as the model's port 5 has them: the modelled port-0 bottleneck is not established. Use the tool to
compare two versions of a kernel under one model (instructions and modelled cycles per packet),
and confirm a gain with a timed A/B (CONTRIBUTING).
Needs llvm-mca (apt: llvm-19; /usr/lib/llvm-19/bin/llvm-mca) and drjit's headers; --mitsuba also
mitsuba and llc (llvm-19).
"""
from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

LANES = 16  # core/simd.h kPacketWidth (two ymm registers per packet on AVX2)
# key: (header, C++ model type); a model's smooth and rough cases share the loop, and loop_body
# follows the costlier side of its uniform branch (or the side --take names)
KERNELS = {
    "diffuse": ("diffuse.h", "DiffuseBxDF<float>"),
    "cond_rough": ("conductor.h", "ConductorBxDF<float>"),
    "diel_rough": ("dielectric.h", "DielectricBxDF<float>"),
    "plastic": ("plastic.h", "PlasticBxDF<float>"),
    "hair": ("hair.h", "HairBxDF<float>"),
    # the smooth lobes: the same loops, the shorter side of the model's uniform smooth / rough branch
    "cond_smooth": ("conductor.h", "ConductorBxDF<float>"),
    "diel_smooth": ("dielectric.h", "DielectricBxDF<float>"),
    "plastic_smooth": ("plastic.h", "PlasticBxDF<float>"),
    "thin": ("thin_dielectric.h", "ThinDielectricBxDF<float>"),
}
SHORTEST = {"cond_smooth", "diel_smooth", "plastic_smooth"}
# The tools/perf/throughput.py configuration of the same model (its Mitsuba plugin, for --mitsuba).
MITSUBA_KEY = {"diffuse": "diffuse", "cond_rough": "cond_rough", "diel_rough": "diel_rough", "plastic": "roughplastic",
               "hair": "hair", "cond_smooth": "cond_smooth", "diel_smooth": "diel_smooth",
               "plastic_smooth": "plastic", "thin": "thin"}
CALL = {
    "eval": "store3_lanes(out, i, kW<float>, bsdf_f(m, o, w, TransportMode::Radiance));",
    "pdf": "store1_lanes(out, i, kW<float>, bsdf_pdf(m, o, w, TransportMode::Radiance, 0xff));",
    # the model's sampler alone (no acceptance rule, uniform checks or byte outputs): uc and the
    # two u planes from `wi`, f and wi as rows, pdf and eta as planes
    "sample": "BSDFSample<P> s = m.sample_f(o, drjit::load<P>(wi + i), Point2<P>{drjit::load<P>(wi + n + i), "
              "drjit::load<P>(wi + 2 * n + i)}, TransportMode::Radiance, 0xff); store3_lanes(out, i, kW<float>, s.f); "
              "store3_lanes(out + 3 * n, i, kW<float>, s.wi); drjit::store(out + 6 * n + i, s.pdf); "
              "drjit::store(out + 7 * n + i, s.eta);",
}


def source(key, op):
    header, model = KERNELS[key]
    return f"""#include <bsdfkit/bxdfs/{header}>
#include <bsdfkit/batch.h>
using namespace bsdfkit;
using P = Packet<float>;
__attribute__((noinline, flatten)) void kernel(const {model} &m0, const float *__restrict wo,
                                               const float *__restrict wi, float *__restrict out, int64_t n) {{
    LocalModel<{model}> m = m0;
    for (int64_t i = 0; i < n; i += kW<float>) {{
        asm volatile("# LLVM-MCA-BEGIN loop");
        Vec3<P> o = load3_lanes<3>(wo, i, kW<float>), w = load3_lanes<3>(wi, i, kW<float>);
        (void)w;
        {CALL[op]}
        asm volatile("# LLVM-MCA-END");
    }}
}}
"""


def loop_body(asm: str, take=None, shortest=False):
    """The instructions from the begin marker to the end marker in execution order, through
    unconditional jumps. At a conditional branch: with `take` (a set of labels), the branch is taken
    iff its label is in it; without, both sides are followed and the longest path is returned (a
    model's uniform switches, e.g. smooth vs rough, then take their costlier side), or the shortest
    with `shortest` (the smooth lobes)."""
    lines = asm.split("\n")
    labels = {m.group(1): i for i, l in enumerate(lines) for m in [re.match(r"^(\.L\w+):", l)] if m}
    begin = next(i for i, l in enumerate(lines) if "LLVM-MCA-BEGIN" in l)
    memo, active = {}, set()

    def walk(i):
        # the longest instruction list from line i to the end marker
        if i in memo:
            return memo[i]
        if i in active:
            raise ValueError("a loop between the markers")
        active.add(i)
        body, j, steps = [], i, 0
        while True:
            steps += 1
            if steps > len(lines):  # jumps only, round and round
                raise ValueError("a loop between the markers")
            if j >= len(lines):
                raise ValueError("the end marker was not reached")
            s = lines[j].strip()
            if "LLVM-MCA-END" in s:
                break
            m = re.match(r"(j\w+)\s+(\.L\w+)$", s)
            if m:
                target = labels[m.group(2)] + 1
                if m.group(1) == "jmp" or (take is not None and m.group(2) in take):
                    j = target
                    continue
                if take is None:
                    a, b = walk(j + 1), walk(target)
                    body += a if (len(a) >= len(b)) != shortest else b
                    break
            elif s and not s.startswith((".", "#")) and not re.match(r"^\.L\w+:", s):
                body.append(s)
            j += 1
        active.discard(i)
        memo[i] = body
        return body

    return walk(begin + 1)


LLVM_LEAST = 17  # llvm-mca's znver4 model and llc for Dr.Jit 1.5's IR (llvm.maximum) need LLVM >= 17


def llvm_major(tool):
    """The LLVM major version `tool --version` prints, or None."""
    try:
        out = subprocess.run([tool, "--version"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    m = re.search(r"LLVM version (\d+)", out)
    return int(m.group(1)) if m else None


def find_llvm_tool(name):
    """`name` (llvm-mca, llc) of LLVM >= LLVM_LEAST: name-25 .. name-17 on PATH or in
    /usr/lib/llvm-N/bin, else the unversioned name if it is that new. An older unversioned tool
    (Debian 12's llvm-mca is LLVM 14, without -mcpu=znver4) is not taken: None then."""
    for v in range(25, LLVM_LEAST - 1, -1):
        for c in (f"{name}-{v}", f"/usr/lib/llvm-{v}/bin/{name}"):
            p = shutil.which(c) or (c if Path(c).exists() else None)
            if p:
                return p
    p = shutil.which(name)
    return p if p and (llvm_major(p) or 0) >= LLVM_LEAST else None


def mitsuba_loop(key, op, work):
    """Mitsuba's own kernel for the same model and op: the LLVM IR Dr.Jit generated for
    `bsdf.eval / pdf / sample` on this host (KernelHistory), compiled with llc (the IR carries
    Dr.Jit's target-cpu and features) and its loop body taken from the vectorized loop's label to
    the backward branch. Needs mitsuba, drjit and llc (apt: llvm-19)."""
    import numpy as np
    from throughput import CONFIG, _setup_drjit_env  # same directory: the bench's plugins and libLLVM choice
    _setup_drjit_env(None)
    import drjit as dr
    import mitsuba as mi
    mkey = MITSUBA_KEY[key]
    plugin = CONFIG[mkey][3]
    if plugin is None:
        sys.exit(f"{key}: no Mitsuba counterpart in tools/perf/throughput.py")
    mi.set_variant("llvm_ad_rgb")
    bsdf, ctx, n = mi.load_dict(plugin), mi.BSDFContext(), 4096
    rng = np.random.default_rng(1)
    v = rng.normal(size=(3, n)).astype(np.float32)
    v /= np.linalg.norm(v, axis=0)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(v)
    wo = mi.Vector3f(np.ascontiguousarray(v[::-1]))
    uc, u = mi.Float(rng.random(n, dtype=np.float32)), mi.Point2f(rng.random((2, n), dtype=np.float32))
    dr.eval(si, wo, uc, u)
    dr.sync_thread()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    if op == "sample":
        dr.eval(*bsdf.sample(ctx, si, uc, u))
    else:
        dr.eval(bsdf.eval(ctx, si, wo) if op == "eval" else bsdf.pdf(ctx, si, wo))
    dr.sync_thread()
    hist = dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, False)
    irs = [h["ir"] for h in hist if h.get("type") == dr.KernelType.JIT]
    if len(irs) != 1:
        sys.exit(f"expected one Mitsuba kernel, Dr.Jit ran {len(irs)}")
    ll, asm = work / "mitsuba.ll", work / "mitsuba.s"
    ll.write_text(irs[0].getvalue() if hasattr(irs[0], "getvalue") else str(irs[0]))
    llc = find_llvm_tool("llc")
    if not llc:
        sys.exit(f"llc of LLVM >= {LLVM_LEAST} not found (apt-get install llvm-19)")
    subprocess.run([llc, "-O3", str(ll), "-o", str(asm)], check=True)
    return llc_loop_body(asm.read_text())


def llc_loop_body(asm: str):
    """The instructions of a Dr.Jit kernel's loop in llc's assembly: from the label of the last
    backward conditional branch to that branch (Dr.Jit's kernels are one straight-line loop body)."""
    lines = asm.split("\n")
    labels = {m.group(1): k for k, l in enumerate(lines) for m in [re.match(r"^(\.L\w+):", l)] if m}
    back = [k for k, l in enumerate(lines)
            for m in [re.match(r"\s*j(?!mp)\w+\s+(\.L\w+)$", l)] if m and labels.get(m.group(1), k) < k]
    if not back:
        raise ValueError("no backward conditional branch: not a loop")
    end = back[-1]
    start = labels[re.match(r"\s*j\w+\s+(\.L\w+)$", lines[end]).group(1)]
    return [l.strip() for l in lines[start + 1:end + 1]
            if l.strip() and not l.strip().startswith((".", "#")) and not re.match(r"^\.L\w+:", l.strip())]


def summarize(label, ins, mca, mcpu, path):
    path.write_text("\n".join(ins) + "\n")
    out = subprocess.run([mca, f"-mcpu={mcpu}", "-iterations=300", "-instruction-info=false", str(path)],
                         check=True, capture_output=True, text=True).stdout
    cycles = int(re.search(r"Total Cycles:\s+(\d+)", out).group(1)) / 300
    names = dict(re.findall(r"\[(\d+)\]\s+-\s+(\S+)", out))
    ph = out.split("Resource pressure per iteration:")[1].split("\n")
    pressure = [float(x) if x != "-" else 0.0 for x in ph[2].split()]
    busiest = sorted(((p, names.get(str(k), str(k))) for k, p in enumerate(pressure)), reverse=True)[:3]
    count = lambda pat: sum(1 for x in ins if re.match(pat, x))
    print(f"{label}: {len(ins)} instructions per packet of {LANES} ({count(r'vdivp')} div, {count(r'vsqrtp')} sqrt, "
          f"{count(r'vcmp')} compares); llvm-mca -mcpu={mcpu}: {cycles:.1f} cycles per packet "
          f"({cycles / LANES:.2f} per element); busiest: " + ", ".join(f"{n} {p:.1f}" for p, n in busiest))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("key", nargs="?", choices=sorted(KERNELS))
    ap.add_argument("op", nargs="?", choices=sorted(CALL))
    ap.add_argument("--march", default="native", help="g++ -march (default native)")
    ap.add_argument("--mcpu", default="sapphirerapids", help="llvm-mca -mcpu (default sapphirerapids)")
    ap.add_argument("--take", default="", help="comma-separated labels of the conditional branches to take "
                    "(the others fall through); default: the longest path (the shortest for the *_smooth keys)")
    ap.add_argument("--mitsuba", action="store_true",
                    help="also Mitsuba's kernel for the same model and op (llvm_ad_rgb, this host's target)")
    ap.add_argument("--keep", help="directory to keep the source, assembly and loop body in")
    ap.add_argument("--list", action="store_true", help="list the kernels")
    args = ap.parse_args()
    if args.list or not args.key or not args.op:
        print("kernels:", ", ".join(sorted(KERNELS)), "- ops:", ", ".join(sorted(CALL)))
        return 0
    mca = find_llvm_tool("llvm-mca")
    if not mca:
        sys.exit(f"llvm-mca of LLVM >= {LLVM_LEAST} not found (apt-get install llvm-19)")
    from _machine import library_cxx  # same directory
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bsdfkit-mca-"))
    work.mkdir(parents=True, exist_ok=True)
    src, asm = work / "kernel.cpp", work / "kernel.s"
    src.write_text(source(args.key, args.op))
    subprocess.run(library_cxx(src, asm, march=args.march, extra=["-S"]), check=True)
    ins = loop_body(asm.read_text(), {t for t in args.take.split(",") if t} if args.take else None,
                    shortest=args.key in SHORTEST)
    summarize(f"{args.key} {args.op}", ins, mca, args.mcpu, work / "body.s")
    if args.mitsuba:
        summarize(f"Mitsuba {MITSUBA_KEY[args.key]} {args.op}", mitsuba_loop(args.key, args.op, work), mca, args.mcpu,
                  work / "mitsuba_body.s")
    if args.keep:
        print(f"kept in {work}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
