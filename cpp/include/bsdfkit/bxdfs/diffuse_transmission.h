// Lambertian reflection plus Lambertian transmission (pbrt-v4 DiffuseTransmissionBxDF).
//   reflectance  R per channel, transmittance  T per channel, each in [0, 1]
// Symmetric: the transport mode does not change the value.
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/frame.h"
#include "../core/sampling.h"

namespace bsdfkit {

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
template <typename S = double> struct DiffuseTransmissionParamsT {
    std::array<S, 3> reflectance{0.25, 0.25, 0.25}, transmittance{0.25, 0.25, 0.25};
    template <class V> void fields(V &&v) {
        v("reflectance", reflectance);
        v("transmittance", transmittance);
    }
};
using DiffuseTransmissionParams = DiffuseTransmissionParamsT<>;

// NC: channels (3 RGB; 4 in spectral mode, see DiffuseBxDF). The lobe choice uses the largest
// channel, as pbrt-v4's MaxComponentValue over the sampled wavelengths.
template <typename F, int NC = 3> struct DiffuseTransmissionBxDF {
    using Params = DiffuseTransmissionParamsT<param_t<F>>;
    static constexpr const char *Name = "DiffuseTransmission";
    Spectrum<F, NC> R, T;

    static DiffuseTransmissionBxDF make(const Params &p) {
        return {to_spectrum<F>(p.reflectance), to_spectrum<F>(p.transmittance)};
    }

    uint8_t flags() const {
        return uint8_t((R.is_black() ? Unset : DiffuseReflection) | (T.is_black() ? Unset : DiffuseTransmission));
    }

    Spectrum<F, NC> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const {
        return select(SameHemisphere(wo, wi), R * InvPi<F>, T * InvPi<F>);
    }

    // Lobe probabilities from the largest channel, restricted by sample_flags.
    void lobe_probs(uint8_t sample_flags, F *pr, F *pt) const {
        restrict_lobes(R.max_component(), T.max_component(), sample_flags, pr, pt);
    }

    BSDFSample<F, NC> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode,
                               uint8_t sample_flags) const {
        F pr, pt;
        lobe_probs(sample_flags, &pr, &pt);
        BSDFSample<F, NC> s;
        F sum = pr + pt;
        bool reflect = ChooseFirstLobe(uc, pr, pt);
        Vec3<F> wi = SampleCosineHemisphere(u);
        // reflection stays on wo's side, transmission goes to the other side (float selects, V2)
        F zo = wo.z < F(0) ? -wi.z : wi.z; // on wo's side
        wi.z = reflect ? zo : -zo;
        s.wi = wi;
        s.pdf = CosineHemispherePDF(AbsCosTheta(wi)) * (reflect ? pr : pt) / sum;
        s.f = f(wo, wi, mode);
        s.flags = lobe_flag(DiffuseReflection, !reflect);
        s.valid = sum > F(0);
        return s;
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        F pr, pt;
        lobe_probs(sample_flags, &pr, &pt);
        F sum = pr + pt;
        F p = CosineHemispherePDF(AbsCosTheta(wi)) * (SameHemisphere(wo, wi) ? pr : pt);
        return sum > F(0) ? p / sum : F(0);
    }

    void regularize() {}
};

} // namespace bsdfkit
