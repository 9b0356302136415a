// Result of sampling a BxDF. `valid` replaces pbrt-v4's optional<> so that batch
// loops stay branch-free: an invalid sample has f = 0, pdf = 0.
#pragma once
#include "flags.h"
#include "spectrum.h"

namespace bsdfkit {

// For a packet F, `flags` holds each lane's BxDFFlags as a float (see lobe_flag) and the bools
// are lane masks. N: channels of f (3 RGB; 4 in spectral mode, one per wavelength, core/spectral.h).
template <typename F, int N = 3> struct BSDFSample {
    using Flags = std::conditional_t<is_packet_v<F>, F, uint8_t>;
    Spectrum<F, N> f{F(0)};
    Vec3<F> wi{F(0), F(0), F(0)};
    F pdf = F(0);
    Flags flags = Flags(Unset);
    F eta = F(1);
    Mask<F> pdf_is_proportional = Mask<F>(false);
    Mask<F> valid = Mask<F>(false);

    bool is_reflection() const { return flags & Reflection; }
    bool is_transmission() const { return flags & Transmission; }
    bool is_specular() const { return flags & Specular; }
};

template <typename F> inline BSDFSample<F> invalid_sample() { return BSDFSample<F>{}; }

// The flag of a two-lobe model's sample: `reflection` (e.g. SpecularReflection) or its
// transmission twin (= reflection + 1), by arithmetic (rule V2, core/math.h).
static_assert(DiffuseTransmission == DiffuseReflection + 1 && GlossyTransmission == GlossyReflection + 1 &&
              SpecularTransmission == SpecularReflection + 1);
inline uint8_t lobe_flag(BxDFFlags reflection, bool transmit) { return uint8_t(reflection + int(transmit)); }
// Per lane: a where m is set, else b (two samples of a per-lane model, e.g. a conductor whose
// lanes differ in smoothness; batch_varying.h).
template <typename V, int N>
inline BSDFSample<V, N> select_sample(const Mask<V> &m, const BSDFSample<V, N> &a, const BSDFSample<V, N> &b) {
    BSDFSample<V, N> r;
    r.f = select(m, a.f, b.f);
    r.wi = select(m, a.wi, b.wi);
    r.pdf = select(m, a.pdf, b.pdf);
    r.flags = select(m, a.flags, b.flags);
    r.eta = select(m, a.eta, b.eta);
    r.pdf_is_proportional = (m & a.pdf_is_proportional) | (!m & b.pdf_is_proportional);
    r.valid = (m & a.valid) | (!m & b.valid);
    return r;
}

// The same per lane, for an evaluation type V (lobe_flag<V>(GlossyReflection, !reflect)).
template <typename V> inline typename BSDFSample<V>::Flags lobe_flag(BxDFFlags reflection, const Mask<V> &transmit) {
    if constexpr (is_packet_v<V>) return V(scalar_t<V>(reflection)) + mask_to_float<V>(transmit);
    else return lobe_flag(reflection, transmit);
}

// The flag of a sample that took lobe `a` where m is set, else lobe `b` (per lane for packets).
template <typename V>
inline typename BSDFSample<V>::Flags select_flag(const Mask<V> &m, BxDFFlags a, BxDFFlags b) {
    if constexpr (is_packet_v<V>) return select(m, V(scalar_t<V>(a)), V(scalar_t<V>(b)));
    else return m ? uint8_t(a) : uint8_t(b);
}

// A model's per-channel parameter (Spectrum<F>) as a spectrum of the evaluation type V.
template <typename V, typename F, int N> inline Spectrum<V, N> to_lanes(const Spectrum<F, N> &s) {
    Spectrum<V, N> r;
    for (int c = 0; c < N; ++c) r[c] = V(s[c]);
    return r;
}

// Lobe weights restricted to the lobes sample_flags allows (pbrt-v4's `if (!(sampleFlags &
// Reflection)) pr = 0;`), as bit masks (rule V3, core/math.h).
template <typename F> inline void restrict_lobes(F r, F t, uint8_t sample_flags, F *pr, F *pt) {
    *pr = keep_or_zero(r, (sample_flags & RT_Reflection) != 0);
    *pt = keep_or_zero(t, (sample_flags & RT_Transmission) != 0);
}

} // namespace bsdfkit
