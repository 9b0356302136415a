"""Static throughput of a packet kernel's loop with llvm-mca: cycles per packet and port pressure,
a figure no neighbour on a shared host can disturb.

    python bench/mca.py cond_rough eval                 # -mcpu=sapphirerapids (an AVX-512 host)
    python bench/mca.py diel_rough pdf --mcpu znver3    # the AMD Zen 3 model (build with -march=znver3)
    python bench/mca.py --list

It writes a small translation unit whose loop is batch.h's packet loop for one model and op
(rows of (N, 3) loaded and stored through batch.h's shuffles, bsdf_f / bsdf_pdf on Packet<float>
with a per-call local copy of the model), between llvm-mca region markers; compiles it with the
library's flags (g++ -O3 -march=<--march> -ffp-contract=off ...); takes the loop body from the
assembly by following the code from the begin marker to the end marker, through unconditional
jumps (GCC rotates the loop, so the end marker can come first in the text) and, at conditional
branches, along the longer side (a model's uniform switches, smooth vs rough, then take the costlier
one; --take picks the sides instead); and runs llvm-mca on it.

Read the figures as a model of the core, not a measurement. llvm-mca 19's sapphirerapids model
issues 512-bit multiplies and FMAs on port 0 only and 512-bit additions on port 5, and leaves the
divider's occupancy out; icelake-server models the divider (vsqrtps zmm ~12 cycles). On this
project's Sapphire Rapids host 12 independent register chains of 512-bit multiplies took the same
time as 6 multiplies + 6 additions (session 18, 20000-iteration runs; longer runs of repeated
multiplies reach the denormals and slow down), so additions there do not run beside the multiplies
as the model's port 5 has them: the modelled port-0 bottleneck is not established. Use the tool to
compare two versions of a kernel under one model (instructions and modelled cycles per packet),
and confirm a gain with a timed A/B (CONTRIBUTING).
Needs llvm-mca (apt: llvm-19; /usr/lib/llvm-19/bin/llvm-mca) and drjit's headers.
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
}
CALL = {
    "eval": "store3_lanes(out, i, kW<float>, bsdf_f(m, o, w, TransportMode::Radiance));",
    "pdf": "store1_lanes(out, i, kW<float>, bsdf_pdf(m, o, w, TransportMode::Radiance, 0xff));",
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
        {CALL[op]}
        asm volatile("# LLVM-MCA-END");
    }}
}}
"""


def loop_body(asm: str, take=None):
    """The instructions from the begin marker to the end marker in execution order, through
    unconditional jumps. At a conditional branch: with `take` (a set of labels), the branch is taken
    iff its label is in it; without, both sides are followed and the longest path is returned (a
    model's uniform switches, e.g. smooth vs rough, then take their costlier side)."""
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
                    body += a if len(a) >= len(b) else b
                    break
            elif s and not s.startswith((".", "#")) and not re.match(r"^\.L\w+:", s):
                body.append(s)
            j += 1
        active.discard(i)
        memo[i] = body
        return body

    return walk(begin + 1)


def find_mca():
    for c in ("llvm-mca-19", "/usr/lib/llvm-19/bin/llvm-mca", "llvm-mca"):
        p = shutil.which(c) or (c if Path(c).exists() else None)
        if p:
            return p
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("key", nargs="?", choices=sorted(KERNELS))
    ap.add_argument("op", nargs="?", choices=sorted(CALL))
    ap.add_argument("--march", default="native", help="g++ -march (default native)")
    ap.add_argument("--mcpu", default="sapphirerapids", help="llvm-mca -mcpu (default sapphirerapids)")
    ap.add_argument("--take", default="", help="comma-separated labels of the conditional branches to take "
                    "(the others fall through); default: the longest path")
    ap.add_argument("--keep", help="directory to keep the source, assembly and loop body in")
    ap.add_argument("--list", action="store_true", help="list the kernels")
    args = ap.parse_args()
    if args.list or not args.key or not args.op:
        print("kernels:", ", ".join(sorted(KERNELS)), "- ops:", ", ".join(sorted(CALL)))
        return 0
    mca = find_mca()
    if not mca:
        sys.exit("llvm-mca not found (apt-get install llvm-19)")
    from _machine import library_cxx  # same directory
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bsdfkit-mca-"))
    work.mkdir(parents=True, exist_ok=True)
    src, asm, body = work / "kernel.cpp", work / "kernel.s", work / "body.s"
    src.write_text(source(args.key, args.op))
    subprocess.run(library_cxx(src, asm, march=args.march, extra=["-S"]), check=True)
    ins = loop_body(asm.read_text(), {t for t in args.take.split(",") if t} if args.take else None)
    body.write_text("\n".join(ins) + "\n")
    out = subprocess.run([mca, f"-mcpu={args.mcpu}", "-iterations=300", "-instruction-info=false", str(body)],
                         check=True, capture_output=True, text=True).stdout
    cycles = int(re.search(r"Total Cycles:\s+(\d+)", out).group(1)) / 300
    names = dict(re.findall(r"\[(\d+)\]\s+-\s+(\S+)", out))
    ph = out.split("Resource pressure per iteration:")[1].split("\n")
    pressure = [float(x) if x != "-" else 0.0 for x in ph[2].split()]
    busiest = sorted(((p, names.get(str(k), str(k))) for k, p in enumerate(pressure)), reverse=True)[:3]
    print(f"{args.key} {args.op}: {len(ins)} instructions per packet of {LANES}; llvm-mca -mcpu={args.mcpu}: "
          f"{cycles:.1f} cycles per packet ({cycles / LANES:.2f} per element); busiest: "
          + ", ".join(f"{n} {p:.1f}" for p, n in busiest))
    if args.keep:
        print(f"kept in {work}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
