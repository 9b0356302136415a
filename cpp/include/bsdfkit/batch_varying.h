// Per-element parameters (issue 47): eval / pdf / sample / albedo of a model whose numeric
// parameters vary over the batch. Each varying field of the model's Params (core/bxdf.h: a double
// or an RGB std::array<double, 3>) comes as a plane of n values (float64, C order, n rows of 1 or 3),
// the Params walk (fields()) puts element i's values into a copy of the uniform Params, and the
// model of element i is Model::make(those Params): the model code is unchanged, and no second list
// of models or of their parameters exists.
//
// Runs: consecutive elements whose plane values are equal bit for bit share one model, built once,
// and run through the uniform kernels' own per-element code over the run: the packet code on
// lanes [i, j) (batch.h's padded tail for a run shorter than a packet), or the scalar code. A model
// with make_lanes (below; ConductorBxDF) instead takes a run shorter than a packet as a packet of
// per-lane parameters: one model whose lanes are the elements' own. Each element's result is
// therefore bit-identical to a call of the uniform model built from its parameters on the same
// inputs (a "loop of scalar models"), for any thread count, chunking and array position
// (tests/test_varying.py). A piecewise-constant map runs at the uniform rate; a map whose every
// element differs runs at the lane models' rate (make_lanes), or builds one model per element and
// runs one padded packet per element (the others).
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

// Whether a model builds a model of per-lane parameters (core/bxdf.h, optional):
//   static Lanes make_lanes(const Params *p)   lane l from p[l] (kPacketWidth of them), the same
//                                              operations per lane as make(p[l]), so each lane's
//                                              values are those of the uniform model's packet code.
template <typename M, typename = void> struct has_make_lanes : std::false_type {};
template <typename M>
struct has_make_lanes<M, std::void_t<decltype(M::make_lanes(std::declval<const typename M::Params *>()))>>
    : std::bool_constant<is_vectorized<M>::value> {};

// Over chunks of [0, n) on the pool: run(model, i, j) for each run [i, j) of equal parameters (the
// model built from element i's Params), or, for a model with make_lanes, lanes(lane model, i, cnt)
// for a packet of cnt elements starting a run shorter than a packet (each lane its own
// parameters; lanes past cnt repeat lane 0's). Either way each element gets its own model's values.
template <typename Model, typename Params, typename F, typename Run, typename Lanes>
inline bool varying_chunks(const VaryingParams<Params> &vp, int64_t n, int nthreads, const Run &run,
                           const Lanes &lanes) {
    return parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e;) {
            int64_t j = i + 1;
            while (j < e && j - i < kW<F> && vp.same(i, j)) ++j;
            if constexpr (has_make_lanes<Model>::value) {
                if (j - i < kW<F>) {
                    const int64_t cnt = std::min(kW<F>, e - i);
                    Params ps[kPacketWidth];
                    for (int64_t l = 0; l < int64_t(kPacketWidth); ++l) ps[l] = vp.at(l < cnt ? i + l : i);
                    const auto lm = Model::make_lanes(ps);
                    const DenormalsFlushedFor<Model> ftz;
                    lanes(lm, i, cnt);
                    i += cnt;
                    continue;
                }
            }
            while (j < e && vp.same(i, j)) ++j;
            const Model m = Model::make(vp.at(i));  // outside the FTZ scope, as the uniform model
            const DenormalsFlushedFor<Model> ftz;
            run(m, i, j);
            i = j;
        }
    });
}

// eval (Eval) or pdf of n pairs, every array full length (rows): out n rows of 3 (eval) or n values.
template <bool Eval, typename Model, typename Params, typename F>
void varying_pair_batch(const VaryingParams<Params> &vp, const F *wo, const F *wi, int64_t n, TransportMode mode,
                        uint8_t sf, F *out, int nthreads, BadCounts &bad) {
    // the packets of [b, e) through model mm (a run's model, or a lane model over one packet)
    auto packets = [&](const auto &mm, int64_t b, int64_t e) {
        int64_t bo = 0, bi = 0;
        for (int64_t i = b; i < e; i += kW<F>) {
            const int64_t cnt = std::min(kW<F>, e - i);
            Vec3<Packet<F>> o = load3_lanes<3>(wo, i, cnt), w = load3_lanes<3>(wi, i, cnt);
            count_not_unit_pair(o, w, &bo, &bi);
            if constexpr (Eval) store3_lanes(out, i, cnt, bsdf_f(mm, o, w, mode));
            else store1_lanes(out, i, cnt, bsdf_pdf(mm, o, w, mode, sf));
        }
        bad.wo += bo;
        bad.wi += bi;
    };
    auto run = [&](const Model &m, int64_t b, int64_t e) {
        LocalModel<Model> mloc = m;
        if constexpr (is_vectorized<Model>::value) {
            packets(mloc, b, e);
        } else {
            int64_t bo = 0, bi = 0;
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
            bad.wo += bo;
            bad.wi += bi;
        }
    };
    auto lanes = [&](const auto &lm, int64_t i, int64_t cnt) { packets(lm, i, i + cnt); };
    varying_chunks<Model, Params, F>(vp, n, nthreads, run, lanes);
}

// sample of n elements (wo, uc, u full length), as sample_batch per run: the model's smooth or
// rough loop (has_split_sample), its lobe test (model_ok) per run; a lane model's sample_f and
// its lanes' lobes (make_lanes: the same lobes in every lane's sample flags test).
template <typename Model, typename Params, typename F>
void varying_sample_batch(const VaryingParams<Params> &vp, const F *wo, const F *uc, const F *u, int64_t n,
                          TransportMode mode, uint8_t sf, const SampleOut<F> &out, int nthreads, BadCounts &bad) {
    auto chunk_packets = [&](const auto &mm, const auto &sampler, bool model_ok, int64_t b, int64_t e) {
        int64_t c[3] = {0, 0, 0};
        sample_chunk_packet<3, false>(mm, sampler, model_ok, b, e, wo, uc, u, out.wi, out.f, out.pdf, out.eta,
                                      out.flags, out.valid, out.proportional, false, c);
        bad.wo += c[0];
        bad.uc += c[1];
        bad.u += c[2];
    };
    auto run = [&](const Model &m, int64_t b, int64_t e) {
        LocalModel<Model> mloc = m;
        const bool model_ok = (m.flags() & sf) != 0;
        auto go = [&](const auto &sampler) {
            if constexpr (is_vectorized<Model>::value) {
                chunk_packets(mloc, sampler, model_ok, b, e);
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
                go([mode, sf](const auto &mm, const auto &o, auto c, auto) { return mm.sample_smooth(o, c, mode, sf); });
            else
                go([mode, sf](const auto &mm, const auto &o, auto c, auto p) {
                    return mm.sample_rough(o, c, p, mode, sf);
                });
        } else {
            go([mode, sf](const auto &mm, const auto &o, auto c, auto p) { return mm.sample_f(o, c, p, mode, sf); });
        }
    };
    auto lanes = [&](const auto &lm, int64_t i, int64_t cnt) {
        chunk_packets(lm, [mode, sf](const auto &mm, const auto &o, auto c, auto p) { return mm.sample_f(o, c, p, mode, sf); },
                      (lm.flags() & sf) != 0, i, i + cnt);
    };
    varying_chunks<Model, Params, F>(vp, n, nthreads, run, lanes);
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
