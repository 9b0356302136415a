// Lambertian reflection, two-sided (pbrt-v4 DiffuseBxDF).
//   reflectance  R per channel, in [0, 1]
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/frame.h"
#include "../core/sampling.h"

namespace bsdfkit {

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
template <typename S = double> struct DiffuseParamsT {
    std::array<S, 3> reflectance{0.5, 0.5, 0.5};
    template <class V> void fields(V &&v) { v("reflectance", reflectance); }
};
using DiffuseParams = DiffuseParamsT<>;

template <typename F> struct DiffuseBxDF {
    using Params = DiffuseParamsT<param_t<F>>;
    static constexpr const char *Name = "Diffuse";
    Spectrum<F> R;

    static DiffuseBxDF make(const Params &p) { return {to_spectrum<F>(p.reflectance)}; }

    uint8_t flags() const { return R.is_black() ? Unset : DiffuseReflection; }

    // f = R / pi on the side of wo, 0 across the surface.
    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const {
        return select(SameHemisphere(wo, wi), R * InvPi<F>, Spectrum<F>(F(0)));
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F /*uc*/, Point2<F> u, TransportMode /*mode*/,
                           uint8_t sample_flags) const {
        BSDFSample<F> s;
        Vec3<F> wi = SampleCosineHemisphere(u);
        wi.z = wo.z < F(0) ? -wi.z : wi.z; // two-sided: sample wo's side
        s.wi = wi;
        // wi is on wo's side unless one of them lies on the horizon: folded into the pdf
        // (0 = invalid; rules V2, V5 of core/math.h).
        s.pdf = SameHemisphere(wo, wi) ? CosineHemispherePDF(AbsCosTheta(wi)) : F(0);
        s.f = R * InvPi<F>;
        s.flags = DiffuseReflection;
        s.valid = ((sample_flags & RT_Reflection) != 0) & (s.pdf > F(0));
        return s;
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        F p = SameHemisphere(wo, wi) ? CosineHemispherePDF(AbsCosTheta(wi)) : F(0);
        return keep_or_zero(p, (sample_flags & RT_Reflection) != 0);
    }

    void regularize() {}
};

} // namespace bsdfkit
