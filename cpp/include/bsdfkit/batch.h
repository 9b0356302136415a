// Array kernels: eval / pdf / sample / albedo of one model over N directions, chunked over a
// thread pool (OpenMP). Every element is computed by pure per-element code, so outputs are
// bit-identical for any thread count. Inner loops are written to auto-vectorize.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

#include "core/bsdf.h"
#include "core/rng.h"

namespace bsdfkit {

inline constexpr int64_t kChunk = 8192;

// Runs fn(begin, end) over fixed chunks of [0, n). Chunk boundaries never depend on the
// thread count, which keeps chunk-level reductions deterministic too.
template <typename Fn> inline void parallel_chunks(int64_t n, int nthreads, int64_t chunk, const Fn &fn) {
    int64_t nchunks = (n + chunk - 1) / chunk;
    if (nthreads <= 1 || nchunks <= 1) {
        for (int64_t c = 0; c < nchunks; ++c) fn(c * chunk, std::min(n, (c + 1) * chunk));
        return;
    }
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 1)
    for (int64_t c = 0; c < nchunks; ++c) fn(c * chunk, std::min(n, (c + 1) * chunk));
}

// A direction is accepted if it is finite and unit length to this tolerance on |w|^2.
template <typename F> inline constexpr F kUnitTol = F(1e-4);
template <typename F> inline int64_t not_unit(const Vec3<F> &w) {
    return !(std::abs(dot(w, w) - F(1)) <= kUnitTol<F>);
}

template <typename F, int S> inline Vec3<F> load3(const F *p, int64_t i) {
    return Vec3<F>(p[i * S], p[i * S + 1], p[i * S + 2]);
}

struct BadCounts {
    std::atomic<int64_t> wo{0}, wi{0};
};

// f(wo, wi) for N pairs; SO / SI are 3 for a full array, 0 for one broadcast direction.
template <int SO, int SI, typename Model, typename F>
void eval_batch(const Model &m, const F *wo, const F *wi, int64_t n, TransportMode mode, F *out, int nthreads,
                BadCounts &bad) {
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) __attribute__((flatten)) {
        int64_t bo = 0, bi = 0;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o = load3<F, SO>(wo, i), w = load3<F, SI>(wi, i);
            bo += not_unit(o);
            bi += not_unit(w);
            Spectrum<F> v = bsdf_f(m, o, w, mode);
            out[3 * i] = v[0];
            out[3 * i + 1] = v[1];
            out[3 * i + 2] = v[2];
        }
        bad.wo += bo;
        bad.wi += bi;
    });
}

template <int SO, int SI, typename Model, typename F>
void pdf_batch(const Model &m, const F *wo, const F *wi, int64_t n, TransportMode mode, uint8_t sf, F *out,
               int nthreads, BadCounts &bad) {
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) __attribute__((flatten)) {
        int64_t bo = 0, bi = 0;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o = load3<F, SO>(wo, i), w = load3<F, SI>(wi, i);
            bo += not_unit(o);
            bi += not_unit(w);
            out[i] = bsdf_pdf(m, o, w, mode, sf);
        }
        bad.wo += bo;
        bad.wi += bi;
    });
}

template <typename F> struct SampleOut {
    F *wi, *f, *pdf, *eta;
    uint8_t *flags;
    bool *valid, *proportional;
};

template <int SO, typename Model, typename F>
void sample_batch(const Model &m, const F *wo, const F *uc, const F *u, int64_t n, TransportMode mode, uint8_t sf,
                  const SampleOut<F> &out, int nthreads, BadCounts &bad) {
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) __attribute__((flatten)) {
        int64_t bo = 0;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o = load3<F, SO>(wo, i);
            bo += not_unit(o);
            BSDFSample<F> s = bsdf_sample(m, o, uc[i], Point2<F>{u[2 * i], u[2 * i + 1]}, mode, sf);
            for (int c = 0; c < 3; ++c) out.f[3 * i + c] = s.f[c];
            out.wi[3 * i] = s.wi.x;
            out.wi[3 * i + 1] = s.wi.y;
            out.wi[3 * i + 2] = s.wi.z;
            out.pdf[i] = s.pdf;
            out.eta[i] = s.eta;
            out.flags[i] = s.flags;
            out.valid[i] = s.valid;
            out.proportional[i] = s.pdf_is_proportional;
        }
        bad.wo += bo;
    });
}

// Directional albedo rho(wo) = E[f |cos wi| / pdf] (pbrt-v4 BxDF::rho), skipping pdf = 0
// samples (pbrt-v4 #313). Uniforms come from a counter hash of (seed, wo index, sample index),
// summed in fixed blocks and then in block order: deterministic for any thread count.
template <typename Model, typename F>
void albedo_batch(const Model &m, const F *wo, int64_t n_wo, int64_t n_samples, uint64_t seed, TransportMode mode,
                  F *out, int nthreads, BadCounts &bad) {
    const int64_t block = 4096;
    int64_t nblocks = (n_samples + block - 1) / block;
    std::vector<double> partial(size_t(n_wo * nblocks * 3), 0.0);
    parallel_chunks(n_wo * nblocks, nthreads, 1, [&](int64_t item, int64_t) {
        int64_t j = item / nblocks, blk = item % nblocks;
        Vec3<F> o = load3<F, 3>(wo, j);
        if (blk == 0) bad.wo += not_unit(o);
        int64_t s0 = blk * block, s1 = std::min(n_samples, s0 + block);
        double acc[3] = {0, 0, 0};
        for (int64_t k = s0; k < s1; ++k) {
            uint64_t h = hash3(seed, uint64_t(j), uint64_t(k));
            F uc = uniform_from_bits<F>(mix64(h ^ 1)), u0 = uniform_from_bits<F>(mix64(h ^ 2)),
              u1 = uniform_from_bits<F>(mix64(h ^ 3));
            BSDFSample<F> s = bsdf_sample(m, o, uc, Point2<F>{u0, u1}, mode, uint8_t(RT_All));
            F w = s.valid ? AbsCosTheta(s.wi) / s.pdf : F(0);
            for (int c = 0; c < 3; ++c) acc[c] += double(s.f[c] * w);
        }
        for (int c = 0; c < 3; ++c) partial[size_t(item * 3 + c)] = acc[c];
    });
    for (int64_t j = 0; j < n_wo; ++j)
        for (int c = 0; c < 3; ++c) {
            double sum = 0;
            for (int64_t blk = 0; blk < nblocks; ++blk) sum += partial[size_t((j * nblocks + blk) * 3 + c)];
            out[3 * j + c] = n_samples > 0 ? F(sum / double(n_samples)) : F(0);
        }
}

} // namespace bsdfkit
