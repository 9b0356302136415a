// Thin dielectric slab: specular reflection plus straight-through transmission, summing the
// inter-reflections inside the slab without absorption (pbrt-v4 ThinDielectricBxDF).
//   eta   relative IOR of the slab (> 0)
// The ray leaves into the medium it came from, so the sample's eta is 1 and no 1/eta^2 applies.
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/fresnel.h"
#include "../core/sampling.h"

namespace bsdfkit {

struct ThinDielectricParams {
    double eta = 1.5;
    template <class V> void fields(V &&v) { v("eta", eta); }
};

template <typename F> struct ThinDielectricBxDF {
    using Params = ThinDielectricParams;
    static constexpr const char *Name = "ThinDielectric";
    F eta;

    static ThinDielectricBxDF make(const Params &p) { return {F(p.eta)}; }

    uint8_t flags() const { return Reflection | Transmission | Specular; }

    Spectrum<F> f(const Vec3<F> &, const Vec3<F> &, TransportMode) const { return Spectrum<F>(F(0)); }

    // The slab's reflectance at |cos| = cos_o: the geometric series of inter-reflections,
    // R' = R + T^2 R / (1 - R^2) (pbrt-v4 ThinDielectricBxDF). Also used per wavelength in
    // spectral mode (batch_spectral.h).
    static F slab_reflectance(F cos_o, F eta) {
        F R = FrDielectric(cos_o, eta);
        F T = F(1) - R;
        return R < F(1) ? R + sqr(T) * R / (F(1) - sqr(R)) : R;
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F>, TransportMode, uint8_t sample_flags) const {
        BSDFSample<F> s;
        F Rs = slab_reflectance(AbsCosTheta(wo), eta);
        F pr, pt;
        restrict_lobes(Rs, F(1) - Rs, sample_flags, &pr, &pt);
        bool reflect = ChooseFirstLobe(uc, pr, pt);
        s.wi = Vec3<F>(-wo.x, -wo.y, reflect ? wo.z : -wo.z);
        F cos_i = DeltaAbsCos(s.wi);
        s.f = Spectrum<F>((reflect ? Rs : F(1) - Rs) / cos_i);
        s.pdf = (reflect ? pr : pt) / (pr + pt);
        s.flags = lobe_flag(SpecularReflection, !reflect);
        s.eta = F(1);
        // cos_i > 0 always holds (DeltaAbsCos).
        s.valid = (pr + pt) > F(0);
        return s;
    }

    F pdf(const Vec3<F> &, const Vec3<F> &, TransportMode, uint8_t) const { return F(0); }

    void regularize() {}
};

} // namespace bsdfkit
