// The BSDF-level rules pbrt-v4 applies around every BxDF (pbrt-v4 BSDF::f / PDF / Sample_f):
// wo on the horizon scatters nothing, and samples with f = 0, pdf = 0 or wi on the horizon
// are discarded. Batch kernels and the generic albedo go through these, never the raw BxDF.
#pragma once
#include "bsdf_sample.h"
#include "frame.h"

namespace bsdfkit {

template <typename Model, typename F>
inline Spectrum<F> bsdf_f(const Model &m, const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode) {
    Spectrum<F> v = m.f(wo, wi, mode);
    return select(wo.z != F(0), v, Spectrum<F>(F(0)));
}

template <typename Model, typename F>
inline F bsdf_pdf(const Model &m, const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode, uint8_t sf) {
    F p = m.pdf(wo, wi, mode, sf);
    return wo.z != F(0) ? p : F(0);
}

template <typename Model, typename F>
inline BSDFSample<F> bsdf_sample(const Model &m, const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode,
                                 uint8_t sf) {
    BSDFSample<F> s = m.sample_f(wo, uc, u, mode, sf);
    bool ok = s.valid && wo.z != F(0) && (m.flags() & sf) != 0 && !s.f.is_black() && s.pdf > F(0) &&
              s.wi.z != F(0);
    // Every output of a rejected sample is a defined value, never a NaN from a dead branch.
    BSDFSample<F> r;
    r.f = select(ok, s.f, Spectrum<F>(F(0)));
    r.wi = select(ok, s.wi, Vec3<F>(0, 0, 0));
    r.pdf = ok ? s.pdf : F(0);
    r.flags = ok ? s.flags : uint8_t(Unset);
    r.eta = ok ? s.eta : F(1);
    r.pdf_is_proportional = ok && s.pdf_is_proportional;
    r.valid = ok;
    return r;
}

} // namespace bsdfkit
