// Conductor: perfect mirror or Trowbridge-Reitz microfacet reflection with the complex
// Fresnel term (pbrt-v4 ConductorBxDF; Torrance & Sparrow 1967, Walter et al. 2007).
//   eta, k     real and imaginary index of refraction per channel (eta > 0, k >= 0)
//   mfd        anisotropic GGX; max(alpha) < 1e-3 makes the lobe a delta
// Two-sided: a wo below the surface sees the same conductor. Symmetric in wo and wi.
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"

namespace bsdfkit {

template <typename F> struct ConductorBxDF {
    TrowbridgeReitz<F> mfd;
    Spectrum<F> eta, k;

    uint8_t flags() const { return mfd.effectively_smooth() ? SpecularReflection : GlossyReflection; }

    // Torrance-Sparrow: f = D(wm) F(wo.wm) G(wo, wi) / (4 cos_o cos_i), wm = normalize(wo + wi).
    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const {
        F cos_o = AbsCosTheta(wo), cos_i = AbsCosTheta(wi);
        Vec3<F> wm = wi + wo;
        F len2 = length_squared(wm);
        F denom = F(4) * cos_o * cos_i;
        bool active = SameHemisphere(wo, wi) && !mfd.effectively_smooth() && len2 > F(0) && denom > F(0);
        wm = wm / std::sqrt(active ? len2 : F(1));
        F scale = mfd.D(wm) * mfd.G(wo, wi) / denom;
        Spectrum<F> fr = FrComplex(absdot(wo, wm), eta, k);
        return select(active, fr * scale, Spectrum<F>(F(0)));
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F /*uc*/, Point2<F> u, TransportMode mode,
                           uint8_t sample_flags) const {
        BSDFSample<F> s;
        bool allowed = (sample_flags & RT_Reflection) != 0;
        if (mfd.effectively_smooth()) {
            // Delta mirror: f = Fr / |cos_i|, discrete probability 1.
            s.wi = Vec3<F>(-wo.x, -wo.y, wo.z);
            F cos_i = DeltaAbsCos(s.wi);
            s.f = FrComplex(cos_i, eta, k) / cos_i;
            s.pdf = F(1);
            s.flags = SpecularReflection;
            s.valid = allowed && cos_i > F(0);
            return s;
        }
        // Sample a visible normal on wo's side and mirror wo about it.
        Vec3<F> wm = mfd.Sample_wm(wo, u);
        Vec3<F> wi = Reflect(wo, wm);
        F cos_o = AbsCosTheta(wo), cos_i = AbsCosTheta(wi);
        bool ok = allowed && SameHemisphere(wo, wi) && cos_o > F(0) && cos_i > F(0);
        F pdf = mfd.PDF(wo, wm) / (F(4) * absdot(wo, wm));
        Spectrum<F> fr = FrComplex(absdot(wo, wm), eta, k);
        s.f = fr * (mfd.D(wm) * mfd.G(wo, wi) / (F(4) * cos_o * cos_i));
        s.wi = wi;
        s.pdf = pdf;
        s.flags = GlossyReflection;
        s.valid = ok;
        return s;
    }

    // Visible-normal density mapped through the reflection Jacobian 1 / (4 |wo.wm|).
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        Vec3<F> wm = wo + wi;
        F len2 = length_squared(wm);
        bool active = (sample_flags & RT_Reflection) && SameHemisphere(wo, wi) &&
                      !mfd.effectively_smooth() && len2 > F(0);
        wm = face_forward(wm / std::sqrt(active ? len2 : F(1)), Vec3<F>(0, 0, 1));
        F p = mfd.PDF(wo, wm) / (F(4) * absdot(wo, wm));
        return active ? p : F(0);
    }

    void regularize() { mfd.regularize(); }
};

} // namespace bsdfkit
