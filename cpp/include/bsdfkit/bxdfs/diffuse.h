// Lambertian reflection, two-sided (pbrt-v4 DiffuseBxDF).
//   R  reflectance per channel, in [0, 1]
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/frame.h"
#include "../core/sampling.h"

namespace bsdfkit {

template <typename F> struct DiffuseBxDF {
    Spectrum<F> R;

    uint8_t flags() const { return R.is_black() ? Unset : DiffuseReflection; }

    // f = R / pi on the side of wo, 0 across the surface.
    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const {
        return select(SameHemisphere(wo, wi), R * InvPi<F>, Spectrum<F>(F(0)));
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F /*uc*/, Point2<F> u, TransportMode mode,
                           uint8_t sample_flags) const {
        BSDFSample<F> s;
        Vec3<F> wi = SampleCosineHemisphere(u);
        wi.z = wo.z < F(0) ? -wi.z : wi.z; // two-sided: sample wo's side
        s.wi = wi;
        s.pdf = CosineHemispherePDF(AbsCosTheta(wi));
        s.f = f(wo, wi, mode);
        s.flags = DiffuseReflection;
        s.valid = (sample_flags & RT_Reflection) != 0;
        return s;
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        bool ok = (sample_flags & RT_Reflection) && SameHemisphere(wo, wi);
        return ok ? CosineHemispherePDF(AbsCosTheta(wi)) : F(0);
    }

    void regularize() {}
};

} // namespace bsdfkit
