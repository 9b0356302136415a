"""Cycles per packet of the batch kernels' own loops, and an A/B of two versions of the headers.

    python tools/perf/loop_ab.py                           # every model, eval / pdf / sample, N = 1e6
    python tools/perf/loop_ab.py --models diffuse,cond_r --ops pdf --threads 2
    python tools/perf/loop_ab.py --n 16384                 # in cache (L2): the arithmetic alone
    python tools/perf/loop_ab.py --base HEAD~1             # A = the headers of a revision, B = the tree's
    python tools/perf/loop_ab.py --aligned                 # outputs on 64-byte lines (streaming stores)
    python tools/perf/loop_ab.py --numpy-like              # arrays on 2 MB pages as throughput.py's (numpy's) are
    python tools/perf/loop_ab.py --march x86-64-v3         # an AVX2 build, on an AVX-512 host too
    python tools/perf/loop_ab.py --dtype float64           # the float64 kernels (16 lanes of double)
    python tools/perf/loop_ab.py --contract --ops eval,pdf # what the (N, 3) rows and the unit check cost

It writes a small C++ program that calls batch.h's eval_batch / pdf_batch / sample_batch (the
library's kernels, (N, 3) rows in and out, the unit and uniform checks included, no Python) on
fixed random unit directions and uniforms, and prints the best of `--reps` calls as TSC cycles per
packet of 16 elements; compiled with the library's flags (_machine.library_cxx: g++ -O3
-march=native -ffp-contract=off, Dr.Jit's packet headers). With --base it builds the same program
a second time against `git archive <rev> cpp/include` and runs the two binaries alternately
(`--rounds` times, fresh processes), printing the medians of A and B and their ratio: the way the
sessions measured a kernel change before spending a wheel build on it (session 20's prefetch and
sample-acceptance changes; CONTRIBUTING). TSC cycles tick at the nominal clock, not the core's:
compare figures of one run, not across hosts.

--contract adds, for eval and pdf, the same packet loop (the model code, bsdf_f / bsdf_pdf's
sanitizing, one thread, no chunking) in three variants beside the library's kernel: `rows-nocheck`
(the (N, 3) rows without the unit check), `planes` (three component planes, as an (N, 3)
Fortran-order array, with the check) and `planes-nocheck` (neither: Mitsuba's own setting, its
kernels read planes and check nothing). The differences are what the API's row layout and its
input contract cost per packet; the variants are measurement only, not library code paths.

The model `null` (NULL_MODEL: f = 1, pdf = 1, the mirror sample; the program checks those outputs)
computes nothing: the library's kernels on it take what the API's contract and the batch loops
cost alone. tools/perf/throughput.py times it beside every cell (its "contract bound"), through this
program with --numpy-like arrays and seconds per call (the program's 4th argument "s"; a 5th
picks a subset of the compiled ops).
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))
from _machine import library_cxx, summary  # noqa: E402

LANES = 16  # core/simd.h kPacketWidth
# key: C++ expression making the float32 model (its Params defaults but what is set here; --dtype
# float64 makes BxDF<double> instead)
MODELS = {
    "diffuse": "DiffuseBxDF<float>::make({})",
    "diffuse_t": "DiffuseTransmissionBxDF<float>::make({})",
    "plastic_s": "PlasticBxDF<float>::make({})",
    "plastic_r": "[] { PlasticParamsT<double> p; p.alpha = 0.3; return PlasticBxDF<float>::make(p); }()",
    "cond_s": "ConductorBxDF<float>::make({})",
    "cond_r": "[] { ConductorParamsT<double> p; p.alpha_x = p.alpha_y = 0.3; return ConductorBxDF<float>::make(p); }()",
    "diel_s": "DielectricBxDF<float>::make({})",
    "diel_r": "[] { DielectricParamsT<double> p; p.alpha_x = p.alpha_y = 0.3; return DielectricBxDF<float>::make(p); }()",
    "thin": "ThinDielectricBxDF<float>::make({})",
    "hair": "HairBxDF<float>::make({})",
    "nfresnel": "NormalizedFresnelBxDF<float>::make({})",
    # The API contract alone (NULL_MODEL below): not a library model.
    "null": "NullBxDF<float>::make({})",
}

# A model that computes nothing, so that the library's batch kernels on it time the API's contract
# alone: the (N, 3) rows read and written, the unit and uniform checks, bsdf_f / bsdf_pdf's
# sanitizing, bsdf_sample's acceptance rule and its seven outputs. f = 1 and pdf = 1 for every
# pair; sample: the mirror direction (-wo.x, -wo.y, wo.z), f = 1, pdf = 1, always valid. Every model
# pays this; throughput.py's contract bound is its rate (bench only, not a library model).
NULL_MODEL = r"""template <typename F> struct NullBxDF {
    struct Params {};
    static constexpr const char *Name = "Null";
    static NullBxDF make(const Params &) { return {}; }
    uint8_t flags() const { return DiffuseReflection; }
    static constexpr bool Vectorized = true;
    template <typename V> Spectrum<V> f(const Vec3<V> &, const Vec3<V> &, TransportMode) const {
        return Spectrum<V>(V(1));
    }
    template <typename V> V pdf(const Vec3<V> &, const Vec3<V> &, TransportMode, uint8_t) const { return V(1); }
    template <typename V> BSDFSample<V> sample_f(const Vec3<V> &wo, V, Point2<V>, TransportMode, uint8_t) const {
        BSDFSample<V> s;
        s.wi = Vec3<V>(-wo.x, -wo.y, wo.z);
        s.f = Spectrum<V>(V(1));
        s.pdf = V(1);
        s.flags = SpecularReflection;
        s.valid = Mask<V>(true);
        return s;
    }
    void regularize() {}
};
// Its line in the batch layer's policy table (batch_policy.h): streamed, as the light models.
template <typename F> struct bsdfkit::BatchPolicy<NullBxDF<F>> : bsdfkit::StreamAll {};
// The null model's outputs are what it defines (a wrong one: the harness timed something else).
template <class F> bool null_outputs_ok(const std::string &ops, int64_t n, const F *wo, const F *f, const F *pdf,
                                        const F *swi) {
    bool ok = true;
    for (int64_t i = 0; i < n; ++i) {
        if (ops.find("sample") != std::string::npos)
            ok &= swi[3 * i] == -wo[3 * i] && swi[3 * i + 1] == -wo[3 * i + 1] && swi[3 * i + 2] == wo[3 * i + 2] &&
                  f[3 * i] == F(1) && pdf[i] == F(1);
        else if (ops.find("pdf") != std::string::npos)
            ok &= pdf[i] == F(1);
        else
            ok &= f[3 * i] == F(1) && f[3 * i + 2] == F(1);
    }
    return ok;
}
"""
OPS = ("eval", "pdf", "sample")


DTYPES = {"float32": "float", "float64": "double"}

# --contract: the eval / pdf packet loop of batch.h's pair_packet_loop without its chunking,
# threads, prefetch and streaming, with or without the unit check, on rows or on planes. The check's
# count goes to a volatile sink, else the compiler drops it.
CONTRACT_LOOP = r"""volatile int64_t g_sink;
static bool g_differ = false;  // a variant's values differ from the library kernel's
template <bool Check, bool Planes, bool Pdf, class M, class T>
__attribute__((flatten)) void contract_loop(const M &m0, const T *wo, const T *wi, const T *wo_p, const T *wi_p, T *out, T *out_p) {
    using P = Packet<T>;
    const KernelOf_t<M> m = m0;
    int64_t bo = 0, bi = 0;
    for (int64_t i = 0; i < N; i += 16) {
        int64_t cnt = std::min<int64_t>(16, N - i);
        Vec3<P> o, w;
        if constexpr (Planes) {
            o = load3_planes(wo_p, N, i, cnt);
            w = load3_planes(wi_p, N, i, cnt);
        } else {
            o = load3_lanes<3>(wo, i, cnt);
            w = load3_lanes<3>(wi, i, cnt);
        }
        if constexpr (Check) count_not_unit_pair(o, w, &bo, &bi);
        if constexpr (Pdf) {
            store1_lanes(out, i, cnt, bsdf_pdf(m, o, w, TransportMode::Radiance, uint8_t(0xff)));
        } else {
            auto f = bsdf_f(m, o, w, TransportMode::Radiance);
            if constexpr (Planes) for (int c = 0; c < 3; ++c) store1_lanes(out_p + c * N, i, cnt, f[c]);
            else store3_lanes(out, i, cnt, f);
        }
    }
    g_sink = g_sink + bo + bi;
}
"""
CONTRACT_END = r"""    if (g_differ) std::printf("contract variants differ from the library's values\n");"""
CONTRACT_CALLS = r"""    Vec<F> wo_p(3 * N), wi_p(3 * N), f_p(3 * N);
    for (int64_t i = 0; i < N; ++i)
        for (int c = 0; c < 3; ++c) wo_p[c * N + i] = wo[3 * i + c], wi_p[c * N + i] = wi[3 * i + c];
    const F *a = wo.data(), *b = wi.data(), *ap = wo_p.data(), *bp = wi_p.data();
    // The variants run the library's model code on the same packets: their values must be the
    // library kernel's (still in f and pdf), bit for bit.
    bool same = true;
    if (ops.find("eval") != std::string::npos) {
        const Vec<F> lib(f.begin(), f.end());
        F *o = f.data(), *op = f_p.data();
        std::printf(" eval:rows-nocheck %.2f", best([&] { contract_loop<false, false, false>(m, a, b, ap, bp, o, op); }));
        std::printf(" eval:planes %.2f", best([&] { contract_loop<true, true, false>(m, a, b, ap, bp, o, op); }));
        std::printf(" eval:planes-nocheck %.2f", best([&] { contract_loop<false, true, false>(m, a, b, ap, bp, o, op); }));
        same &= std::memcmp(lib.data(), o, sizeof(F) * size_t(3 * N)) == 0;
        for (int64_t i = 0; i < N; ++i)
            for (int c = 0; c < 3; ++c) same &= std::memcmp(&lib[3 * i + c], &op[c * N + i], sizeof(F)) == 0;
    }
    if (ops.find("pdf") != std::string::npos) {
        const Vec<F> lib(pdf.begin(), pdf.end());
        F *o = pdf.data();
        std::printf(" pdf:rows-nocheck %.2f", best([&] { contract_loop<false, false, true>(m, a, b, ap, bp, o, o); }));
        same &= std::memcmp(lib.data(), o, sizeof(F) * size_t(N)) == 0;
        std::printf(" pdf:planes %.2f", best([&] { contract_loop<true, true, true>(m, a, b, ap, bp, o, o); }));
        std::printf(" pdf:planes-nocheck %.2f", best([&] { contract_loop<false, true, true>(m, a, b, ap, bp, o, o); }));
        same &= std::memcmp(lib.data(), o, sizeof(F) * size_t(N)) == 0;
    }
    if (!same) g_differ = true;
"""


def source(models, ops, aligned=False, dtype="float32", contract=False, numpy_like=False) -> str:
    """The C++ program; aligned: every array starts on a 64-byte line (as bsdfkit's own result
    arrays do, so a model that streams its outputs does so here; batch.h), else where std::vector
    puts it (16 bytes past a page for these sizes, as numpy's arrays); dtype: the models' and
    arrays' float type (float64: the 16-lane double packets of the float64 rows); contract: the
    eval / pdf loop variants of --contract (module docstring) besides the library's kernels."""
    ct = DTYPES[dtype]
    runs = "\n".join(f'    run("{k}", {MODELS[k].replace("BxDF<float>", f"BxDF<{ct}>")}, ops);' for k in models)
    alloc = "A64" if aligned else "std::allocator"
    # numpy_like: on 2 MB pages (madvise, as numpy asks for its large arrays), the inputs 16 bytes
    # past a page as numpy's, the outputs on a line as bsdfkit's result arrays (throughput.py's cells)
    vin, vout = ("Huge<T, 16>", "Huge<T, 0>") if numpy_like else (f"{alloc}<T>", f"{alloc}<T>")
    contract_loop, contract_calls = (CONTRACT_LOOP, CONTRACT_CALLS) if contract else ("", "")
    contract_end = CONTRACT_END if contract else ""
    return f"""#include <bsdfkit/bxdfs/all.h>
#include <bsdfkit/batch.h>
#include <x86intrin.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>
#include <sys/mman.h>
using namespace bsdfkit;
template <class T> struct A64 {{  // 64-byte aligned storage
    using value_type = T;
    A64() = default;
    template <class U> A64(const A64<U> &) {{}}
    T *allocate(size_t n) {{ return static_cast<T *>(std::aligned_alloc(64, (n * sizeof(T) + 63) / 64 * 64)); }}
    void deallocate(T *p, size_t) {{ std::free(p); }}
    template <class U> bool operator==(const A64<U> &) const {{ return true; }}
    template <class U> bool operator!=(const A64<U> &) const {{ return false; }}
}};
template <class T, size_t Off> struct Huge {{  // on 2 MB pages, Off bytes past a 2 MB boundary
    using value_type = T;
    template <class U> struct rebind {{ using other = Huge<U, Off>; }};
    Huge() = default;
    template <class U> Huge(const Huge<U, Off> &) {{}}
    T *allocate(size_t n) {{
        const size_t huge = size_t(1) << 21, bytes = (n * sizeof(T) + Off + huge - 1) / huge * huge;
        void *p = nullptr;
        if (posix_memalign(&p, huge, bytes) != 0) std::abort();
        madvise(p, bytes, MADV_HUGEPAGE);
        return reinterpret_cast<T *>(static_cast<char *>(p) + Off);
    }}
    void deallocate(T *p, size_t) {{ std::free(reinterpret_cast<char *>(p) - Off); }}
    template <class U> bool operator==(const Huge<U, Off> &) const {{ return true; }}
    template <class U> bool operator!=(const Huge<U, Off> &) const {{ return false; }}
}};
template <class T> using Vec = std::vector<T, {alloc}<T>>;
template <class T> using VecIn = std::vector<T, {vin}>;
template <class T> using VecOut = std::vector<T, {vout}>;
static int64_t N = 1000000;
static int g_threads = 1, g_reps = 20;
static bool g_seconds = false;  // argv[4] == "s": seconds per call (wall clock) instead of TSC per packet
template <class Fn> double best(Fn fn) {{
    double b = 1e300;
    for (int r = 0; r < g_reps; ++r) {{
        unsigned long long t0 = __rdtsc();
        auto c0 = std::chrono::steady_clock::now();
        fn();
        double tsc = double(__rdtsc() - t0);
        double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
        b = std::min(b, g_seconds ? sec : tsc);
    }}
    return g_seconds ? b : b / (double(N) / {LANES});
}}
{NULL_MODEL}{contract_loop}template <class Model> void run(const char *name, const Model &m, const std::string &ops) {{
    using F = {ct};
    std::mt19937 g(1);
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<F> ud(F(0), F(1));
    VecIn<F> wo(3 * N), wi(3 * N), uc(N), u(2 * N);
    VecOut<F> f(3 * N), swi(3 * N), pdf(N), eta(N);
    VecOut<uint8_t> flags(N);
    VecOut<char> valid(N), prop(N);
    for (int64_t i = 0; i < N; ++i) {{
        for (int side = 0; side < 2; ++side) {{
            double x = nd(g), y = nd(g), z = nd(g);
            if (side == 0) z = std::abs(z) + 0.05;  // wo above the surface
            double l = std::sqrt(x * x + y * y + z * z);
            F *w = side == 0 ? &wo[3 * i] : &wi[3 * i];
            w[0] = F(x / l), w[1] = F(y / l), w[2] = F(z / l);
        }}
        uc[i] = ud(g), u[2 * i] = ud(g), u[2 * i + 1] = ud(g);
    }}
    BadCounts bad;
    std::printf("%s", name);
    if (ops.find("eval") != std::string::npos)
        std::printf(" eval %.6g", best([&] {{ eval_batch<3, 3>(m, wo.data(), wi.data(), N, TransportMode::Radiance, f.data(), g_threads, bad); }}));
    if (ops.find("pdf") != std::string::npos)
        std::printf(" pdf %.6g", best([&] {{ pdf_batch<3, 3>(m, wo.data(), wi.data(), N, TransportMode::Radiance, 0xff, pdf.data(), g_threads, bad); }}));
{contract_calls}    if (ops.find("sample") != std::string::npos) {{
        SampleOut<F> so{{swi.data(), f.data(), pdf.data(), eta.data(), flags.data(), (bool *)valid.data(), (bool *)prop.data()}};
        std::printf(" sample %.6g", best([&] {{ sample_batch<3>(m, wo.data(), uc.data(), u.data(), N, TransportMode::Radiance, 0xff, so, g_threads, bad); }}));
    }}
    std::printf("\\n");
    if (bad.wo + bad.wi + bad.uc + bad.u != 0) std::printf("unexpected bad inputs\\n");
    if constexpr (std::is_same_v<Model, NullBxDF<F>>)
        if (!null_outputs_ok(ops, N, wo.data(), f.data(), pdf.data(), swi.data())) std::printf("null model: wrong outputs\\n");
{contract_end}
}}
int main(int argc, char **argv) {{
    if (argc > 1) N = std::atoll(argv[1]);
    if (argc > 2) g_threads = std::atoi(argv[2]);
    if (argc > 3) g_reps = std::atoi(argv[3]);
    if (argc > 4) g_seconds = std::string(argv[4]) == "s";
    std::string ops = "{",".join(ops)}";
    if (argc > 5) ops = argv[5];  // a subset of the compiled ops
{runs}
}}
"""


def build(src: Path, include_root: Path | None, out: Path, march: str = "native") -> None:
    """Compiles src with the library's flags (-march=march); include_root replaces cpp/include (a
    revision's headers)."""
    cmd = library_cxx(src, out, march=march, extra=["-pthread", "-fopenmp"])
    if include_root is not None:
        cmd = [c.replace(f"-I{ROOT / 'cpp' / 'include'}", f"-I{include_root}") for c in cmd]
    if subprocess.run(cmd).returncode != 0:
        which = "the working tree's" if include_root is None else "the --base revision's"
        sys.exit(f"loop_ab.py: g++ could not build the harness against {which} headers with -march={march} "
                 "(its message above; --march takes what g++ -march does, e.g. native, x86-64-v3, znver3)")


def parse(text: str) -> dict[tuple[str, str], float]:
    """{(model, op): cycles per packet} from the program's lines ("diffuse eval 26.61 pdf 18.40")."""
    res = {}
    for line in text.splitlines():
        parts = line.split()
        if not parts or parts[0] not in MODELS:
            continue
        for op, val in zip(parts[1::2], parts[2::2]):
            res[(parts[0], op)] = float(val)
    return res


def run(binary: Path, args) -> dict[tuple[str, str], float]:
    out = subprocess.run([str(binary), str(args.n), str(args.threads), str(args.reps)],
                         check=True, capture_output=True, text=True).stdout
    return parse(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", default=",".join(MODELS), help="comma-separated subset of: " + ", ".join(MODELS))
    ap.add_argument("--ops", default=",".join(OPS), help="comma-separated subset of: " + ", ".join(OPS))
    ap.add_argument("--n", type=int, default=1_000_000, help="elements per call (default 1e6; 16384 stays in L2)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--reps", type=int, default=20, help="calls per measurement, the best kept (default 20)")
    ap.add_argument("--base", default=None, help="a git revision: A/B its cpp/include (A) against the tree's (B)")
    ap.add_argument("--rounds", type=int, default=3, help="alternating runs of A and B with --base (default 3)")
    ap.add_argument("--keep", default=None, help="directory to keep the source and binaries in")
    ap.add_argument("--march", default="native",
                    help="g++ -march (default native; x86-64-v3: an AVX2 build on any AVX2 host; znver3 on AMD)")
    ap.add_argument("--dtype", default="float32", choices=sorted(DTYPES),
                    help="the kernels' float type (default float32; float64: the float64 rows)")
    ap.add_argument("--contract", action="store_true",
                    help="eval / pdf also without the unit check and on planes (see above); not with --base")
    ap.add_argument("--numpy-like", action="store_true",
                    help="arrays on 2 MB pages (madvise), inputs 16 bytes past a page as numpy's, outputs on a line "
                         "as bsdfkit's results: throughput.py's setting (its contract bound)")
    ap.add_argument("--aligned", action="store_true",
                    help="arrays on 64-byte lines, as bsdfkit's results (where stream_outputs models of batch_policy.h stream)")
    args = ap.parse_args(argv)
    models = [m for m in args.models.split(",") if m]
    ops = [o for o in args.ops.split(",") if o]
    for m in models:
        if m not in MODELS:
            ap.error(f"--models: unknown model {m!r} (known: {', '.join(MODELS)})")
    for o in ops:
        if o not in OPS:
            ap.error(f"--ops: unknown op {o!r} (known: {', '.join(OPS)})")
    if args.contract and args.base is not None:
        ap.error("--contract measures one tree's headers; leave out --base")
    if args.n < LANES or args.threads < 1 or args.reps < 1 or args.rounds < 1:
        ap.error(f"--n must be >= {LANES}; --threads, --reps and --rounds >= 1")

    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bsdfkit-loop-ab-"))
    work.mkdir(parents=True, exist_ok=True)
    src = work / "loops.cpp"
    src.write_text(source(models, ops, args.aligned, args.dtype, args.contract, args.numpy_like))
    b_bin = work / "loops_b"
    build(src, None, b_bin, args.march)
    print(f"# {summary()}; -march={args.march}; {args.dtype}; N = {args.n}, {args.threads} thread(s), best of {args.reps} calls; TSC cycles per packet of {LANES}")
    if args.base is None:
        res = run(b_bin, args)
        for (m, op), v in res.items():
            lib = res.get((m, op.split(":")[0])) if ":" in op else None
            share = f"  {lib / v:.2f}x the library kernel's speed" if lib else ""
            print(f"{m:10s} {op:22s} {v:8.2f}{share}")
        return 0

    base_inc = work / "base"
    base_inc.mkdir(exist_ok=True)
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.base, "cpp/include"], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(base_inc)], input=archive, check=True)
    a_bin = work / "loops_a"
    build(src, base_inc / "cpp" / "include", a_bin, args.march)
    a_runs, b_runs = [], []
    for _ in range(args.rounds):
        a_runs.append(run(a_bin, args))
        b_runs.append(run(b_bin, args))
    print(f"# A = {args.base}, B = the working tree; medians of {args.rounds} alternating runs")
    print(f"{'model':10s} {'op':7s} {'A':>8s} {'B':>8s}  A/B (> 1: B faster)")
    for key in a_runs[0]:
        a = statistics.median(r[key] for r in a_runs)
        b = statistics.median(r[key] for r in b_runs)
        print(f"{key[0]:10s} {key[1]:7s} {a:8.2f} {b:8.2f}  {a / b:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
