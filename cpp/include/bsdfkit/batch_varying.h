// Per-element parameters (issue 47): eval / pdf / sample / albedo of a model whose numeric
// parameters vary over the batch. Each varying field of the model's Params (core/bxdf.h: a double
// or an RGB std::array<double, 3>) comes as a plane of n values (float64, C order, n rows of 1 or 3),
// the Params walk (fields()) puts element i's values into a copy of the uniform Params, and the
// model of element i is Model::make(those Params): the model code is unchanged, and no second list
// of models or of their parameters exists.
//
// Runs: consecutive elements whose plane values are equal bit for bit share one model, built once,
// and run through the uniform kernels' own per-element code over the run: the packet code on
// lanes [i, j) (batch.h's padded tail for a run shorter than a packet), or the scalar code. Each
// element's result is therefore bit-identical to a call of the uniform model built from its
// parameters on the same inputs (a "loop of scalar models"), for any thread count, chunking and
// array position (tests/test_varying.py). A piecewise-constant map runs at the uniform rate; a map
// whose every element differs builds one model per element and runs one padded packet per element.
#pragma once
#include <array>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#include "batch.h"

namespace bsdfkit {

// One varying field: its index in the Params walk, its components (1 or 3) and n * comps values.
struct ParamPlane {
    int field = 0;
    int comps = 1;
    const double *data = nullptr;
};

// The uniform Params plus the planes (sorted by field index): element i's Params.
template <typename Params> struct VaryingParams {
    Params base;
    const ParamPlane *planes = nullptr;
    int nplanes = 0;

    Params at(int64_t i) const {
        Params p = base;
        int k = 0, j = 0;
        p.fields([&](const char *, auto &f) {
            using T = std::decay_t<decltype(f)>;
            if (j < nplanes && planes[j].field == k) {
                const double *d = planes[j].data + i * planes[j].comps;
                if constexpr (std::is_same_v<T, double>) f = d[0];
                else if constexpr (std::is_same_v<T, std::array<double, 3>>) f = {d[0], d[1], d[2]};
                ++j;
            }
            ++k;
        });
        return p;
    }
    // Whether elements a and b have the same parameters, bit for bit.
    bool same(int64_t a, int64_t b) const {
        for (int j = 0; j < nplanes; ++j) {
            const int c = planes[j].comps;
            if (std::memcmp(planes[j].data + a * c, planes[j].data + b * c, sizeof(double) * size_t(c)) != 0)
                return false;
        }
        return true;
    }
};

// fn(model, i, j) for each run [i, j) of equal parameters, over chunks of [0, n) on the pool.
// The model is built in Model's precision from element i's Params.
template <typename Model, typename Params, typename Fn>
inline bool varying_runs(const VaryingParams<Params> &vp, int64_t n, int nthreads, const Fn &fn) {
    return parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e;) {
            int64_t j = i + 1;
            while (j < e && vp.same(i, j)) ++j;
            const Model m = Model::make(vp.at(i));  // outside the FTZ scope, as the uniform model
            const DenormalsFlushedFor<Model> ftz;
            fn(m, i, j);
            i = j;
        }
    });
}

// eval (Eval) or pdf of n pairs, every array full length (rows): out n rows of 3 (eval) or n values.
template <bool Eval, typename Model, typename Params, typename F>
void varying_pair_batch(const VaryingParams<Params> &vp, const F *wo, const F *wi, int64_t n, TransportMode mode,
                        uint8_t sf, F *out, int nthreads, BadCounts &bad) {
    varying_runs<Model>(vp, n, nthreads, [&](const Model &m, int64_t b, int64_t e) {
        LocalModel<Model> mloc = m;
        int64_t bo = 0, bi = 0;
        if constexpr (is_vectorized<Model>::value) {
            for (int64_t i = b; i < e; i += kW<F>) {
                const int64_t cnt = std::min(kW<F>, e - i);
                Vec3<Packet<F>> o = load3_lanes<3>(wo, i, cnt), w = load3_lanes<3>(wi, i, cnt);
                count_not_unit_pair(o, w, &bo, &bi);
                if constexpr (Eval) store3_lanes(out, i, cnt, bsdf_f(mloc, o, w, mode));
                else store1_lanes(out, i, cnt, bsdf_pdf(mloc, o, w, mode, sf));
            }
        } else {
            for (int64_t i = b; i < e; ++i) {
                Vec3<F> o = load3<F, 3>(wo, i), w = load3<F, 3>(wi, i);
                bo += check_dir(&o);
                bi += check_dir(&w);
                if constexpr (Eval) {
                    Spectrum<F> v = bsdf_f(mloc, o, w, mode);
                    for (int c = 0; c < 3; ++c) out[3 * i + c] = v[c];
                } else {
                    out[i] = bsdf_pdf(mloc, o, w, mode, sf);
                }
            }
        }
        bad.wo += bo;
        bad.wi += bi;
    });
}

// sample of n elements (wo, uc, u full length), as sample_batch per run: the model's smooth or
// rough loop (has_split_sample), its lobe test (model_ok) per run.
template <typename Model, typename Params, typename F>
void varying_sample_batch(const VaryingParams<Params> &vp, const F *wo, const F *uc, const F *u, int64_t n,
                          TransportMode mode, uint8_t sf, const SampleOut<F> &out, int nthreads, BadCounts &bad) {
    varying_runs<Model>(vp, n, nthreads, [&](const Model &m, int64_t b, int64_t e) {
        LocalModel<Model> mloc = m;
        const bool model_ok = (m.flags() & sf) != 0;
        auto run = [&](const auto &sampler) {
            if constexpr (is_vectorized<Model>::value) {
                int64_t c[3] = {0, 0, 0};
                sample_chunk_packet<3, false>(mloc, sampler, model_ok, b, e, wo, uc, u, out.wi, out.f, out.pdf,
                                              out.eta, out.flags, out.valid, out.proportional, false, c);
                bad.wo += c[0];
                bad.uc += c[1];
                bad.u += c[2];
            } else {
                std::vector<F> stage(size_t(e - b));
                int64_t bo = 0;
                bad.uc += count_bad_uniforms(uc, b, e);
                bad.u += count_bad_uniforms(u, 2 * b, 2 * e);
                sample_chunk<3>(mloc, sampler, model_ok, b, e, wo, uc, u, out.wi, out.f, out.pdf, out.eta,
                                stage.data(), out.flags, out.valid, out.proportional, &bo);
                bad.wo += bo;
            }
        };
        if constexpr (has_split_sample<Model>::value) {
            if (m.is_smooth())
                run([mode, sf](const auto &mm, const auto &o, auto c, auto) { return mm.sample_smooth(o, c, mode, sf); });
            else
                run([mode, sf](const auto &mm, const auto &o, auto c, auto p) {
                    return mm.sample_rough(o, c, p, mode, sf);
                });
        } else {
            run([mode, sf](const auto &mm, const auto &o, auto c, auto p) { return mm.sample_f(o, c, p, mode, sf); });
        }
    });
}

// albedo of n_wo directions, element j's model from its parameters: albedo_batch's estimator
// (the same uniforms of (seed, j, sample index), the same blocks and sums).
template <typename Model, typename Params, typename F>
void varying_albedo_batch(const VaryingParams<Params> &vp, const F *wo, int64_t n_wo, int64_t n_samples,
                          uint64_t seed, TransportMode mode, F *out, int nthreads, BadCounts &bad) {
    albedo_batch_of([&](int64_t j) { return Model::make(vp.at(j)); }, wo, n_wo, n_samples, seed, mode, out, nthreads,
                    bad);
}

} // namespace bsdfkit
