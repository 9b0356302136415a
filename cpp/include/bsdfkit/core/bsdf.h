// The BSDF-level rules pbrt-v4 applies around every BxDF (pbrt-v4 BSDF::f / PDF / Sample_f):
// wo on the horizon scatters nothing, and samples with f = 0, pdf = 0 or wi on the horizon
// are discarded. Batch kernels and the generic albedo go through these, never the raw BxDF.
#pragma once
#include "bsdf_sample.h"
#include "frame.h"
#include "sampling.h"

namespace bsdfkit {

// Last line of defence at the degenerate limits (both cosines underflowing, G -> 0 against a
// vanishing Jacobian): a value that is not a finite non-negative number becomes 0. The
// models' own guards cover every regular case; tests compare those against references.
// Packets: finite_or_zero, and 0 where `zero` is set as well, in the same one blend with zero
// (core/simd.h not_finite_nonneg: the same lanes as the scalar compares).
template <typename F, std::enable_if_t<is_packet_v<F>, int> = 0> inline F finite_or_zero(F v, Mask<F> zero) {
    return drjit::select(zero | not_finite_nonneg(v), F(0), v);
}
template <typename F> inline F finite_or_zero(F v) {
    if constexpr (is_packet_v<F>) {
        return finite_or_zero(v, Mask<F>(false));
    } else {
        // Two float selects rather than one select on (a && b): GCC 12's vectorizer cannot handle
        // the boolean-valued COND_EXPRs that if-conversion makes of the && form.
        v = select(v >= F(0), v, F(0));
        return select(v <= F(std::numeric_limits<scalar_t<F>>::max()), v, F(0));
    }
}
template <typename F, int N> inline Spectrum<F, N> finite_or_zero(const Spectrum<F, N> &s) {
    Spectrum<F, N> r;
    for (int i = 0; i < N; ++i) r[i] = finite_or_zero(s[i]);
    return r;
}
// Mask forms (bitwise &/|, no short-circuit), so the checks vectorize in the sample kernels.
template <typename F, int N> inline Mask<F> nonzero_mask(const Spectrum<F, N> &s) {
    Mask<F> b = s[0] != F(0);
    for (int i = 1; i < N; ++i) b = b | (s[i] != F(0));
    return b;
}
template <typename F, int N> inline Mask<F> finite_nonneg_mask(const Spectrum<F, N> &s) {
    if constexpr (is_packet_v<F>) {
        Mask<F> bad = not_finite_nonneg(s[0]);
        for (int i = 1; i < N; ++i) bad = bad | not_finite_nonneg(s[i]);
        return !bad;
    }
    const F big(std::numeric_limits<scalar_t<F>>::max());
    Mask<F> ok = (s[0] >= F(0)) & (s[0] <= big);
    for (int i = 1; i < N; ++i) ok = ok & (s[i] >= F(0)) & (s[i] <= big);
    return ok;
}

// Whether a raw BxDF sample survives pbrt-v4's BSDF-level rules (the lobe-flag test against
// sample_flags aside, which the batch kernel hoists out of its loop).
template <typename F, int N> inline Mask<F> sample_accepted(const BSDFSample<F, N> &s, const Vec3<F> &wo) {
    if constexpr (is_packet_v<F>) {
        // The same lanes in fewer instructions (core/simd.h's class tests): pdf in (0, max], every
        // f channel finite and >= 0, and then "some channel != 0" as their sum > 0 (a sum of
        // non-negative values is > 0 iff one of them is; an overflow to +inf is > 0 as well;
        // -0 + -0 is -0; under DAZ a denormal channel is 0 to both forms). The class tests ignore
        // DAZ, the compares do not: they differ only on a denormal pdf under FTZ | DAZ (a
        // flush_denormals model, batch_policy.h), where FTZ flushes every computed value.
        Mask<F> bad = not_finite_positive(s.pdf);
        F sum = s.f[0];
        for (int c = 0; c < N; ++c) bad = bad | not_finite_nonneg(s.f[c]);
        for (int c = 1; c < N; ++c) sum = sum + s.f[c];
        return s.valid & (wo.z != F(0)) & (s.wi.z != F(0)) & !bad & (sum > F(0));
    } else {
        return s.valid & (wo.z != F(0)) & nonzero_mask(s.f) & (s.pdf > F(0)) & (s.wi.z != F(0)) &
               finite_nonneg_mask(s.f) & (s.pdf <= F(std::numeric_limits<scalar_t<F>>::max()));
    }
}

// The direction an invalid sample carries (with f = pdf = 0): the shading normal +z.
template <typename F> inline Vec3<F> kInvalidSampleWi() { return Vec3<F>(0, 0, 1); }

template <typename Model, typename F>
inline auto bsdf_f(const Model &m, const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode) {
    auto v = m.f(wo, wi, mode);  // Spectrum<F, N>: N = 3 (RGB) or 4 (spectral)
    if constexpr (is_packet_v<F>) {
        Mask<F> horizon = wo.z == F(0);
        for (int c = 0; c < decltype(v)::Size; ++c) v[c] = finite_or_zero(v[c], horizon);
        return v;
    } else {
        v = finite_or_zero(v);
        return select(wo.z != F(0), v, decltype(v)(F(0)));
    }
}

template <typename Model, typename F>
inline F bsdf_pdf(const Model &m, const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode, uint8_t sf) {
    F p = m.pdf(wo, wi, mode, sf);
    if constexpr (is_packet_v<F>) {
        return finite_or_zero(p, wo.z == F(0));
    } else {
        p = finite_or_zero(p);
        return select(wo.z != F(0), p, F(0));
    }
}

// pbrt-v4's BSDF-level rules on a BxDF's raw sample; model_ok: the model has a lobe in the
// requested sample flags. Every output of a rejected sample is a defined value, never a NaN from
// a dead branch; its direction is the normal (0, 0, 1), so that eval / pdf accept every sampled wi.
// F is a scalar or a packet (per lane; the spectral packet kernels, batch_spectral.h).
template <typename F, int N>
inline BSDFSample<F, N> accepted_sample(const BSDFSample<F, N> &s, const Vec3<F> &wo, bool model_ok) {
    Mask<F> ok = sample_accepted(s, wo) & Mask<F>(model_ok);
    BSDFSample<F, N> r;
    r.f = select(ok, s.f, decltype(s.f)(F(0)));
    r.wi = select(ok, s.wi, kInvalidSampleWi<F>());
    r.pdf = select(ok, s.pdf, F(0));
    if constexpr (is_packet_v<F>) r.flags = select(ok, s.flags, F(0));
    else r.flags = ok ? s.flags : uint8_t(Unset);
    r.eta = select(ok, s.eta, F(1));
    r.pdf_is_proportional = ok & s.pdf_is_proportional;
    r.valid = ok;
    return r;
}

template <typename Model, typename F>
inline auto bsdf_sample(const Model &m, const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode, uint8_t sf) {
    // Uniforms are documented on [0, 1] and used on [0, 1) (pbrt-v4's OneMinusEpsilon).
    auto s = m.sample_f(wo, clamp_uniform(uc), clamp_uniform(u), mode, sf);  // BSDFSample<F, N>
    return accepted_sample(s, wo, (m.flags() & sf) != 0);
}

} // namespace bsdfkit
