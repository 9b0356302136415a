// bench/divider.cpp: the throughput of the vector divide and square root on the kernels' own
// packet type (core/simd.h Packet<F>, 16 lanes: Dr.Jit packets), built like the library
// (-O3 -march=native, no fast math). 12 independent chains keep the divider busy, so the time
// per operation is its reciprocal throughput. Prints JSON: elements per nanosecond (1 thread).
#include <bsdfkit/core/simd.h>
#include <chrono>
#include <cstdio>
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
int main() {
    const long n = 400000;
    double best[4] = {0, 0, 0, 0};
    for (int r = 0; r < 7; ++r) {
        double v[4] = {rate<float, false>(n), rate<float, true>(n), rate<double, false>(n), rate<double, true>(n)};
        for (int i = 0; i < 4; ++i) best[i] = v[i] > best[i] ? v[i] : best[i];
    }
    std::printf("{\"div_f32\": %.4f, \"sqrt_f32\": %.4f, \"div_f64\": %.4f, \"sqrt_f64\": %.4f}\n", best[0], best[1],
                best[2], best[3]);
}
