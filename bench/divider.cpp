// bench/divider.cpp: the throughput of the vector divide and square root on the kernels' own
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
#include <cstring>
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
int main(int argc, char **argv) {
    if (argc > 1 && std::strcmp(argv[1], "arith") == 0) return arith();
    const long n = 400000;
    double best[4] = {0, 0, 0, 0};
    for (int r = 0; r < 7; ++r) {
        double v[4] = {rate<float, false>(n), rate<float, true>(n), rate<double, false>(n), rate<double, true>(n)};
        for (int i = 0; i < 4; ++i) best[i] = v[i] > best[i] ? v[i] : best[i];
    }
    std::printf("{\"div_f32\": %.4f, \"sqrt_f32\": %.4f, \"div_f64\": %.4f, \"sqrt_f64\": %.4f}\n", best[0], best[1],
                best[2], best[3]);
}
