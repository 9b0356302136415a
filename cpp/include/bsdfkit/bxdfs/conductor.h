// Conductor: perfect mirror or Trowbridge-Reitz microfacet reflection with a conductor Fresnel
// term (pbrt-v4 ConductorBxDF; Torrance & Sparrow 1967, Walter et al. 2007).
// Parameters (ConductorParams; Python: bsdfkit.Conductor)
//   eta, k     real and imaginary index of refraction per channel (eta > 0, k >= 0); default Cu
//   alpha_x, alpha_y, masking   anisotropic GGX; max(alpha) < 1e-3 makes the lobe a delta
//   FR         the Fresnel term, a compile-time knob (one loop per variant):
//              Exact    complex Fresnel of eta + i k (FrComplex)
//              Schlick  Schlick 1994 with the exact normal-incidence reflectance F0
//              F82      F82-tint (Hoffman 2019; Kutz et al. 2021): Schlick minus a
//                       mu (1 - mu)^6 term fitted to the exact value at mu = 1/7
// Two-sided: a wo below the surface sees the same conductor. Symmetric in wo and wi.
#pragma once
#include <cstdint>

#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"

namespace bsdfkit {

enum class ConductorFresnel : uint8_t { Exact = 0, Schlick = 1, F82 = 2 };

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
template <typename S = double> struct ConductorParamsT {
    std::array<S, 3> eta{0.201006, 0.923749, 1.102215}, k{3.913262, 2.453045, 2.142090};  // Cu (bk.METALS)
    S alpha_x = 0, alpha_y = 0;
    Masking masking = Masking::Correlated;
    template <class V> void fields(V &&v) {
        v("eta", eta);
        v("k", k);
        v("alpha_x", alpha_x);
        v("alpha_y", alpha_y);
        v("masking", masking);
    }
};
using ConductorParams = ConductorParamsT<>;

template <typename F, ConductorFresnel FR = ConductorFresnel::Exact> struct ConductorBxDF {
    using Params = ConductorParamsT<param_t<F>>;
    static constexpr const char *Name = FR == ConductorFresnel::Schlick ? "ConductorSchlick"
                                        : FR == ConductorFresnel::F82   ? "ConductorF82"
                                                                        : "Conductor";
    TrowbridgeReitz<F> mfd;
    Spectrum<F> eta, k;
    // Per-channel Schlick F0 and F82-tint a, computed in double at construction (unused by Exact);
    // for a Dual model in the Dual (param_t), so their derivatives reach eta and k.
    Spectrum<F> f0{F(0)}, f82_a{F(0)};

    ConductorBxDF() = default;
    ConductorBxDF(const TrowbridgeReitz<F> &mfd_, const Spectrum<F> &eta_, const Spectrum<F> &k_)
        : mfd(mfd_), eta(eta_), k(k_) {
        for (int i = 0; i < Spectrum<F>::Size; ++i) {
            f0[i] = F(ConductorF0(param_t<F>(eta[i]), param_t<F>(k[i])));
            f82_a[i] = F(ConductorF82A(param_t<F>(eta[i]), param_t<F>(k[i])));
        }
    }

    static ConductorBxDF make(const Params &p) {
        return ConductorBxDF(TrowbridgeReitz<F>(F(p.alpha_x), F(p.alpha_y), p.masking), to_spectrum<F>(p.eta),
                             to_spectrum<F>(p.k));
    }

    uint8_t flags() const { return mfd.effectively_smooth() ? SpecularReflection : GlossyReflection; }

    // The Fresnel reflectance at |wo.wm| = cos_i, per channel (the FR knob).
    Spectrum<F> fresnel(F cos_i) const {
        if constexpr (FR == ConductorFresnel::Schlick) return FrSchlick(cos_i, f0);
        else if constexpr (FR == ConductorFresnel::F82) return FrF82Tint(cos_i, f0, f82_a);
        else return FrComplex(cos_i, eta, k);
    }

    // Torrance-Sparrow: f = D(wm) F(wo.wm) G(wo, wi) / (4 cos_o cos_i), wm = normalize(wo + wi).
    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const {
        F cos_o = AbsCosTheta(wo), cos_i = AbsCosTheta(wi);
        F denom = F(4) * cos_o * cos_i;
        bool active = SameHemisphere(wo, wi) & !mfd.effectively_smooth() & (denom > F(0));
        Vec3<F> wm = reflection_half_vector(wi, wo, active);
        F scale = mfd.D(wm) * mfd.G(wo, wi) / denom;
        Spectrum<F> fr = fresnel(absdot(wo, wm));
        return select(active, fr * scale, Spectrum<F>(F(0)));
    }

    bool is_smooth() const { return mfd.effectively_smooth(); }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        return is_smooth() ? sample_smooth(wo, uc, mode, sample_flags) : sample_rough(wo, uc, u, mode, sample_flags);
    }

    // Delta mirror: f = Fr / |cos_i|, discrete probability 1.
    BSDFSample<F> sample_smooth(const Vec3<F> &wo, F /*uc*/, TransportMode, uint8_t sample_flags) const {
        BSDFSample<F> s;
        bool allowed = (sample_flags & RT_Reflection) != 0;
        s.wi = Vec3<F>(-wo.x, -wo.y, wo.z);
        F cos_i = DeltaAbsCos(s.wi);
        s.f = fresnel(cos_i) / cos_i;
        s.pdf = F(1);
        s.flags = SpecularReflection;
        s.valid = allowed; // cos_i >= the smallest normal number (DeltaAbsCos), even for a NaN wo
        return s;
    }

    // Sample a visible normal on wo's side and mirror wo about it.
    BSDFSample<F> sample_rough(const Vec3<F> &wo, F /*uc*/, Point2<F> u, TransportMode,
                               uint8_t sample_flags) const {
        BSDFSample<F> s;
        bool allowed = (sample_flags & RT_Reflection) != 0;
        Vec3<F> wm = mfd.Sample_wm(wo, u);
        Vec3<F> wi = Reflect(wo, wm);
        F cos_o = AbsCosTheta(wo), cos_i = AbsCosTheta(wi);
        bool ok = allowed & SameHemisphere(wo, wi) & (cos_o > F(0)) & (cos_i > F(0));
        F pdf = mfd.PDF(wo, wm) / (F(4) * absdot(wo, wm));
        Spectrum<F> fr = fresnel(absdot(wo, wm));
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
        bool active = SameHemisphere(wo, wi) & (len2 > F(0));
        wm = face_forward(wm / std::sqrt(active ? len2 : F(1)), Vec3<F>(0, 0, 1));
        F p = mfd.PDF(wo, wm) / (F(4) * absdot(wo, wm));
        p = keep_or_zero(active ? p : F(0), (sample_flags & RT_Reflection) != 0);
        return keep_or_zero(p, !mfd.effectively_smooth());
    }

    void regularize() { mfd.regularize(); }
};

// The Fresnel variants under their own names (the bindings and the renderer register each).
template <typename F> using ConductorSchlickBxDF = ConductorBxDF<F, ConductorFresnel::Schlick>;
template <typename F> using ConductorF82BxDF = ConductorBxDF<F, ConductorFresnel::F82>;

} // namespace bsdfkit
