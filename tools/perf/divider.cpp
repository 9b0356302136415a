// tools/perf/divider.cpp: the throughput of the vector divide and square root on the kernels' own
// packet type (core/simd.h Packet<F>, 16 lanes: Dr.Jit packets), built like the library
// (-O3 -march=native, no fast math). 12 independent chains keep the divider busy, so the time
// per operation is its reciprocal throughput. Prints JSON: elements per nanosecond (1 thread).
//
// `divider arith`: the host's arithmetic scaling probe instead. A fixed amount of multiply-add
// work (independent chains on the packet type, registers only: no memory traffic) timed on one
// thread, then on two threads at once (each the same amount, started together), best of 5.
// Prints JSON {"arith_1t": s, "arith_2t": s}: on two free cores the two times are equal; where
// the second vCPU shares a physical core with another (SMT sibling, another guest's work) the
// two-thread time is longer, and no kernel can scale better than 2 arith_1t / arith_2t.
#include <bsdfkit/core/simd.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <immintrin.h>
#include <sys/mman.h>
#include <thread>
using namespace bsdfkit;
template <typename F, bool Sqrt> double rate(long iters) {
    using P = Packet<F>;
    constexpr int K = 12;
    P x[K], a(F(1.0000001));
    for (int k = 0; k < K; ++k) x[k] = P(F(1 + 0.01 * k));
    auto t0 = std::chrono::steady_clock::now();
    for (long i = 0; i < iters; ++i) {
        for (int k = 0; k < K; ++k) {
            if constexpr (Sqrt) x[k] = drjit::sqrt(x[k]) * a; else x[k] = a / x[k];
        }
        for (int k = 0; k < K; ++k) asm volatile("" : : "m"(x[k]) : "memory");
    }
    double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    F s = 0;
    for (int k = 0; k < K; ++k) s += drjit::sum(x[k]);
    if (s == F(12345)) std::puts("");
    return double(iters) * K * kPacketWidth / t / 1e9;
}
// ~15 ms of independent multiply-add chains on one core of this host
__attribute__((noinline)) float arith_work(long iters) {
    using P = Packet<float>;
    constexpr int K = 10;
    P x[K], a(0.99999f), c(1e-6f);
    for (int k = 0; k < K; ++k) x[k] = P(1.f + 0.001f * float(k));
    for (long i = 0; i < iters; ++i) {
        for (int k = 0; k < K; ++k) x[k] = drjit::fmadd(x[k], a, c);
        for (int k = 0; k < K; ++k) asm volatile("" : : "m"(x[k]) : "memory");
    }
    float s = 0;
    for (int k = 0; k < K; ++k) s += drjit::sum(x[k]);
    return s;
}
int arith() {
    const long iters = 1500000;
    volatile float sink = arith_work(iters / 10); // warm-up
    double best1 = 1e30, best2 = 1e30;
    for (int r = 0; r < 5; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        sink = arith_work(iters);
        best1 = std::min(best1, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        std::atomic<int> ready{0};
        std::thread th([&] {
            ready.fetch_add(1);
            while (ready.load() < 2) {}
            volatile float s2 = arith_work(iters);
            (void)s2;
        });
        ready.fetch_add(1);
        while (ready.load() < 2) {}
        t0 = std::chrono::steady_clock::now();
        sink = arith_work(iters);
        th.join();
        best2 = std::min(best2, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    (void)sink;
    std::printf("{\"arith_1t\": %.6g, \"arith_2t\": %.6g}\n", best1, best2);
    return 0;
}
// `divider stream R W [zeros] [all]`: the memory bound of a kernel that reads R bytes and writes W
// bytes once per call. The element range in blocks, each reading its share of the R bytes (64-byte
// loads, OR-reduced) and writing its share of the W bytes, as the batch kernels move them
// ("fused"), or all reads and then all writes ("two passes"), each with plain stores and with
// streaming stores (no read for ownership; what the delta models' eval / pdf use, batch.h): the
// fastest of the four. The buffers are on 2 MB pages (as numpy's large arrays) and stay allocated
// and touched across passes, as a kernel's arrays between calls (at N = 1e6 they come near this
// host's L3: part of them stays cached between passes, for the kernels too). On 2 threads each
// takes half of the blocks (contiguous halves, as parallel_chunks' chunks), started together;
// every variant repeats its pass for >= 20 ms and keeps the best time per pass of 5 such runs.
// The bytes written are data (every 64-bit word non-zero, different on every line), as a kernel's
// outputs are; `zeros` writes zeros, as the delta lobes' eval / pdf do. The content matters on the
// Zen 4 host: its memory took streamed lines of zeros at 85-96 GB/s and lines of data at 27-30 GB/s
// (session 29, 36-512 MB, 1 and 2 threads; real eval outputs, half of them zero rows, 29.5 GB/s;
// a line with one non-zero word 55 GB/s), so a bound written in zeros was no bound for data.
// Prints JSON {"stream_1t": s, "stream_2t": s, "bytes_read", "bytes_written", "nonzero_words"}
// (seconds per pass; the bytes the blocks cover: R and W rounded up to whole lines; the 64-bit
// words of the written buffer that are non-zero after the passes); `all` also prints each
// variant's time to stderr.
struct StreamBufs {
    uint64_t *src, *dst;
    size_t nr, nw;  // 64-bit words (multiples of 8: whole 64-byte lines)
};
// On 2 MB pages where the kernel allows them, as numpy's large arrays are (numpy asks for
// transparent huge pages): the kernels' arrays then cost as few TLB misses as these buffers.
static uint64_t *alloc_lines(size_t words) {
    const size_t huge = size_t(1) << 21, bytes = (words * 8 + 64 + huge - 1) / huge * huge;
    void *p = nullptr;
    if (posix_memalign(&p, huge, bytes) != 0) std::abort();
    madvise(p, bytes, MADV_HUGEPAGE);
    std::memset(p, 1, bytes);  // touch the pages
    return static_cast<uint64_t *>(p);
}
constexpr size_t kStreamBlocks = 4096;
// 64-byte lines as one AVX-512 vector or two AVX2 vectors (an AVX2-only host builds this too)
#if defined(__AVX512F__)
using SV = __m512i;
static inline SV sv_load(const uint64_t *p) { return _mm512_load_si512(p); }
static inline SV sv_or(SV a, SV b) { return _mm512_or_si512(a, b); }
static inline SV sv_zero() { return _mm512_setzero_si512(); }
static inline void sv_store(uint64_t *p, SV v) { _mm512_store_si512(p, v); }
static inline void sv_stream(uint64_t *p, SV v) { _mm512_stream_si512(reinterpret_cast<SV *>(p), v); }
static inline uint64_t sv_reduce(SV v) { return uint64_t(_mm512_reduce_or_epi64(v)); }
// the data written at word j: non-zero odd words, different on every line
static inline SV sv_data(size_t j) {
    return _mm512_add_epi64(_mm512_set_epi64(0x3fd1e3779b97f4a7, 0x3fc2b7e151628aed, 0x3fe243f6a8885a31, 0x3fb7f4a7c15e3779,
                                             0x3fa9e3779b97f4a7, 0x3ff2b7e151628aed, 0x3f9243f6a8885a31, 0x3fe7f4a7c15e3779),
                            _mm512_set1_epi64((long long)(j << 1)));
}
#else
using SV = __m256i;
static inline SV sv_load(const uint64_t *p) { return _mm256_load_si256(reinterpret_cast<const SV *>(p)); }
static inline SV sv_or(SV a, SV b) { return _mm256_or_si256(a, b); }
static inline SV sv_zero() { return _mm256_setzero_si256(); }
static inline void sv_store(uint64_t *p, SV v) { _mm256_store_si256(reinterpret_cast<SV *>(p), v); }
static inline void sv_stream(uint64_t *p, SV v) { _mm256_stream_si256(reinterpret_cast<SV *>(p), v); }
static inline uint64_t sv_reduce(SV v) {
    alignas(32) uint64_t t[4];
    _mm256_store_si256(reinterpret_cast<SV *>(t), v);
    return t[0] | t[1] | t[2] | t[3];
}
static inline SV sv_data(size_t j) {
    return _mm256_add_epi64(_mm256_set_epi64x(0x3fd1e3779b97f4a7, 0x3fc2b7e151628aed, 0x3fe243f6a8885a31, 0x3fb7f4a7c15e3779),
                            _mm256_set1_epi64x((long long)(j << 1)));
}
#endif
constexpr size_t kSV = sizeof(SV) / 8;  // words per vector
// The words block k reads ([r0, r1) of src) and writes ([w0, w1) of dst): shares of whole lines.
struct BlockSpan {
    size_t r0, r1, w0, w1;
};
static inline BlockSpan block_span(const StreamBufs &b, size_t k) {
    BlockSpan s{b.nr * k / kStreamBlocks / 8 * 8, b.nr * (k + 1) / kStreamBlocks / 8 * 8,
                b.nw * k / kStreamBlocks / 8 * 8, b.nw * (k + 1) / kStreamBlocks / 8 * 8};
    if (k + 1 == kStreamBlocks) s.r1 = b.nr, s.w1 = b.nw;
    return s;
}
// Fused: each block reads its share and then writes its share (a kernel's pattern); else the
// range's reads first, then its writes (two passes, as numpy's reduce and fill).
template <bool NT, bool Fused, bool Zeros>
__attribute__((noinline)) uint64_t stream_part(const StreamBufs &b, size_t blk0, size_t blk1) {
    SV acc0 = sv_zero(), acc1 = acc0, zero = acc0;
    auto reads = [&](const BlockSpan &sp) {
        for (size_t i = sp.r0; i < sp.r1; i += 8) {  // whole lines of 8 words
            acc0 = sv_or(acc0, sv_load(b.src + i));
            if constexpr (kSV == 4) acc1 = sv_or(acc1, sv_load(b.src + i + 4));
        }
    };
    auto writes = [&](const BlockSpan &sp) {
        for (size_t j = sp.w0; j < sp.w1; j += kSV) {
            const SV v = Zeros ? zero : sv_data(j);
            if constexpr (NT) sv_stream(b.dst + j, v);
            else sv_store(b.dst + j, v);
        }
    };
    for (size_t k = blk0; k < blk1; ++k) {
        const BlockSpan sp = block_span(b, k);
        reads(sp);
        if constexpr (Fused) writes(sp);
    }
    if constexpr (!Fused)
        for (size_t k = blk0; k < blk1; ++k) writes(block_span(b, k));
    if constexpr (NT) _mm_sfence();
    return sv_reduce(sv_or(acc0, acc1));
}
template <bool NT, bool Fused, bool Zeros> double stream_time(const StreamBufs &b, int nt) {
    volatile uint64_t sink = 0;
    auto run_k = [&](size_t blk0, size_t blk1, long k) {
        uint64_t s = 0;
        for (long r = 0; r < k; ++r) s |= stream_part<NT, Fused, Zeros>(b, blk0, blk1);
        sink = sink | s;
    };
    auto t0 = std::chrono::steady_clock::now();
    run_k(0, kStreamBlocks, 1);
    double one = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const long k = std::max(1L, long(0.02 / std::max(one, 1e-7)));
    double best = 1e30;
    for (int r = 0; r < 5; ++r) {
        std::atomic<int> ready{0};
        std::thread th;
        if (nt == 2) {
            th = std::thread([&] {
                ready.fetch_add(1);
                while (ready.load() < 2) {}
                run_k(kStreamBlocks / 2, kStreamBlocks, k);
            });
        }
        ready.fetch_add(1);
        while (ready.load() < nt) {}
        t0 = std::chrono::steady_clock::now();
        run_k(0, nt == 2 ? kStreamBlocks / 2 : kStreamBlocks, k);
        if (nt == 2) th.join();
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / double(k));
    }
    return best;
}
template <bool Zeros> void stream_variants(const StreamBufs &b, int nt, double v[4]) {
    v[0] = stream_time<false, true, Zeros>(b, nt), v[1] = stream_time<true, true, Zeros>(b, nt);
    v[2] = stream_time<false, false, Zeros>(b, nt), v[3] = stream_time<true, false, Zeros>(b, nt);
}
int stream(long long rbytes, long long wbytes, bool zeros, bool verbose) {
    StreamBufs b;
    b.nr = size_t((rbytes + 63) / 64 * 8);
    b.nw = size_t((wbytes + 63) / 64 * 8);
    b.src = alloc_lines(b.nr);
    b.dst = alloc_lines(b.nw);
    // the opposite of what the passes write, so that nonzero_words shows they wrote every word
    std::memset(b.dst, zeros ? 1 : 0, b.nw * 8);
    // the blocks cover both buffers once, without gaps or overlaps (the words a pass moves)
    size_t words_r = 0, words_w = 0, next_r = 0, next_w = 0;
    for (size_t k = 0; k < kStreamBlocks; ++k) {
        const BlockSpan sp = block_span(b, k);
        if (sp.r0 != next_r || sp.w0 != next_w || sp.r1 < sp.r0 || sp.w1 < sp.w0) std::abort();
        words_r += sp.r1 - sp.r0, words_w += sp.w1 - sp.w0, next_r = sp.r1, next_w = sp.w1;
    }
    double t[2];
    for (int nt = 1; nt <= 2; ++nt) {
        double v[4];
        if (zeros) stream_variants<true>(b, nt, v);
        else stream_variants<false>(b, nt, v);
        if (verbose)  // `divider stream R W all`: each variant's time per pass
            std::fprintf(stderr, "%dT fused plain %.6g, fused streaming %.6g, two passes plain %.6g, two passes streaming %.6g\n",
                         nt, v[0], v[1], v[2], v[3]);
        t[nt - 1] = *std::min_element(v, v + 4);
    }
    size_t nonzero = 0;
    for (size_t j = 0; j < words_w; ++j) nonzero += b.dst[j] != 0;
    std::printf("{\"stream_1t\": %.6g, \"stream_2t\": %.6g, \"bytes_read\": %zu, \"bytes_written\": %zu, "
                "\"nonzero_words\": %zu}\n", t[0], t[1], words_r * 8, words_w * 8, nonzero);
    std::free(b.src);
    std::free(b.dst);
    return 0;
}
int main(int argc, char **argv) {
    if (argc > 1 && std::strcmp(argv[1], "arith") == 0) return arith();
    if (argc > 3 && std::strcmp(argv[1], "stream") == 0) {
        bool zeros = false, all = false;
        for (int a = 4; a < argc; ++a) {
            if (std::strcmp(argv[a], "zeros") == 0) zeros = true;
            else if (std::strcmp(argv[a], "all") == 0) all = true;
            else return std::fprintf(stderr, "divider stream: unknown option %s (zeros, all)\n", argv[a]), 2;
        }
        return stream(std::atoll(argv[2]), std::atoll(argv[3]), zeros, all);
    }
    const long n = 400000;
    double best[4] = {0, 0, 0, 0};
    for (int r = 0; r < 7; ++r) {
        double v[4] = {rate<float, false>(n), rate<float, true>(n), rate<double, false>(n), rate<double, true>(n)};
        for (int i = 0; i < 4; ++i) best[i] = v[i] > best[i] ? v[i] : best[i];
    }
    std::printf("{\"div_f32\": %.4f, \"sqrt_f32\": %.4f, \"div_f64\": %.4f, \"sqrt_f64\": %.4f}\n", best[0], best[1],
                best[2], best[3]);
}
