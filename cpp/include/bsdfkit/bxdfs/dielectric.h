// Dielectric interface: smooth (delta) or Trowbridge-Reitz rough reflection and transmission
// (pbrt-v4 DielectricBxDF; Walter et al. 2007 "Microfacet models for refraction").
// Parameters (DielectricParams; Python: bsdfkit.Dielectric)
//   eta                  relative IOR inside / outside (> 0; < 1 means the outside is denser)
//   alpha_x, alpha_y, masking   anisotropic GGX; max(alpha) < 1e-3 (or eta == 1) makes both lobes deltas
// wo may lie on either side. In Radiance mode transmitted radiance is scaled by 1/etap^2,
// in Importance mode it is not (Veach 1997 ch. 5), so f is not symmetric for transmission.
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"

namespace bsdfkit {

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
template <typename S = double> struct DielectricParamsT {
    S eta = 1.5, alpha_x = 0, alpha_y = 0;
    Masking masking = Masking::Correlated;
    template <class V> void fields(V &&v) {
        v("eta", eta);
        v("alpha_x", alpha_x);
        v("alpha_y", alpha_y);
        v("masking", masking);
    }
};
using DielectricParams = DielectricParamsT<>;

template <typename F> struct DielectricBxDF {
    using Params = DielectricParamsT<param_t<F>>;
    static constexpr const char *Name = "Dielectric";
    F eta;
    TrowbridgeReitz<F> mfd;

    static DielectricBxDF make(const Params &p) {
        return {F(p.eta), TrowbridgeReitz<F>(F(p.alpha_x), F(p.alpha_y), p.masking)};
    }

    // Bitwise | (not ||): a short-circuit here becomes control flow in every batch loop.
    bool is_smooth() const { return (eta == F(1)) | mfd.effectively_smooth(); }

    uint8_t flags() const {
        uint8_t f = eta == F(1) ? Transmission : (Reflection | Transmission);
        return uint8_t(f | (mfd.effectively_smooth() ? Specular : Glossy));
    }

    // Lobe probabilities restricted by sample_flags.
    static void lobe_probs(F R, F T, uint8_t sample_flags, F *pr, F *pt) { restrict_lobes(R, T, sample_flags, pr, pt); }

    // Generalized half vector of a pair, facing +z, and the relative IOR etap along wi.
    // Returns false where pbrt-v4 returns 0: a horizon direction, a degenerate half vector,
    // or a back-facing microfacet.
    // *len2 = |wi etap + wo|^2, from which the transmission Jacobian's denominator follows
    // without cancellation: (wi.wm + wo.wm / etap)^2 = (h.wm / etap)^2 = |h|^2 / etap^2.
    bool half_vector(const Vec3<F> &wo, const Vec3<F> &wi, Vec3<F> *wm, F *etap, F *len2_out) const {
        F cos_o = CosTheta(wo), cos_i = CosTheta(wi);
        bool reflect = cos_i * cos_o > F(0);
        F eta_side = cos_o > F(0) ? eta : F(1) / eta;
        *etap = reflect ? F(1) : eta_side;
        Vec3<F> h = wi * *etap + wo;
        F len2 = length_squared(h);
        *len2_out = len2;
        bool ok = (cos_i != F(0)) & (cos_o != F(0)) & (len2 > F(0));
        F inv_len = F(1) / sqrt(ok ? len2 : F(1));
        F sgn = h.z < F(0) ? -inv_len : inv_len; // normalize and face +z in one scale
        h = h * sgn;
        *wm = h;
        // Discard back-facing microfacets (Walter 2007 sec. 5.1)
        ok = ok & (dot(h, wi) * cos_i >= F(0)) & (dot(h, wo) * cos_o >= F(0));
        return ok;
    }

    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode) const {
        // Delta lobes evaluate to 0: folded into the mask (no early return).
        Vec3<F> wm;
        F etap, len2;
        bool ok = half_vector(wo, wi, &wm, &etap, &len2) & !is_smooth();
        bool reflect = CosTheta(wi) * CosTheta(wo) > F(0);
        F cos_o = CosTheta(wo), cos_i = CosTheta(wi);
        F Fr, Ft;
        FrDielectricRT(dot(wo, wm), eta, &Fr, &Ft); // Ft = 1 - Fr without cancellation
        F dg = mfd.D(wm) * mfd.G(wo, wi);
        F cc = abs(cos_i * cos_o);
        // Reflection: D G F / |4 cos_i cos_o|
        F fr = dg * Fr / (F(4) * cc);
        // Transmission (Walter 2007 eq. 21): D G (1 - F) |wi.wm wo.wm| / (|cos_i cos_o| (wi.wm + wo.wm/etap)^2),
        // the squared sum being |h|^2 / etap^2 (half_vector); Radiance mode divides by etap^2,
        // which cancels the etap^2 of that denominator.
        F ft = dg * Ft * abs(dot(wi, wm) * dot(wo, wm)) / (len2 * cc);
        ft = mode == TransportMode::Radiance ? ft : ft * sqr(etap);
        F v = reflect ? fr : ft;
        return Spectrum<F>(ok ? v : F(0));
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode,
                           uint8_t sample_flags) const {
        return is_smooth() ? sample_smooth(wo, uc, mode, sample_flags)
                           : sample_rough(wo, uc, u, mode, sample_flags);
    }

    BSDFSample<F> sample_smooth(const Vec3<F> &wo, F uc, TransportMode mode, uint8_t sample_flags) const {
        BSDFSample<F> s;
        // eta == 1 is a pure pass-through; force R = 0 rather than trusting rounding.
        F R = keep_or_zero(FrDielectric(CosTheta(wo), eta), eta != F(1)), pr, pt;
        lobe_probs(R, F(1) - R, sample_flags, &pr, &pt);
        bool reflect = ChooseFirstLobe(uc, pr, pt);
        // Specular reflection about +z, or refraction through the flat interface.
        Vec3<F> wr(-wo.x, -wo.y, wo.z), wt;
        F etap;
        bool refr_ok = Refract(wo, Vec3<F>(0, 0, 1), eta, &etap, &wt);
        s.wi = reflect ? wr : wt;
        F cos_i = DeltaAbsCos(s.wi);
        F ft = (F(1) - R) / cos_i;
        ft = mode == TransportMode::Radiance ? ft / sqr(etap) : ft;
        s.f = Spectrum<F>(reflect ? R / cos_i : ft);
        s.pdf = (reflect ? pr : pt) / (pr + pt);
        s.flags = lobe_flag(SpecularReflection, !reflect);
        s.eta = reflect ? F(1) : etap;
        // cos_i > 0 always holds (DeltaAbsCos).
        s.valid = ((pr + pt) > F(0)) & (reflect | refr_ok);
        return s;
    }

    BSDFSample<F> sample_rough(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode,
                               uint8_t sample_flags) const {
        BSDFSample<F> s;
        Vec3<F> wm = mfd.Sample_wm(wo, u);
        F R, T, pr, pt;
        FrDielectricRT(dot(wo, wm), eta, &R, &T);
        lobe_probs(R, T, sample_flags, &pr, &pt);
        bool reflect = ChooseFirstLobe(uc, pr, pt);
        F cos_o = CosTheta(wo);
        F pdf_wm = mfd.PDF(wo, wm);

        // Reflection about the sampled normal.
        Vec3<F> wr = Reflect(wo, wm);
        F pdf_r = pdf_wm / (F(4) * absdot(wo, wm)) * pr / (pr + pt);
        F f_r = mfd.D(wm) * mfd.G(wo, wr) * R / std::abs(F(4) * CosTheta(wr) * cos_o);
        bool ok_r = SameHemisphere(wo, wr);

        // Refraction through the sampled normal, with the half-vector Jacobian.
        Vec3<F> wt;
        F etap;
        bool ok_t = Refract(wo, wm, eta, &etap, &wt);
        // wt.z == 0 is left to the BSDF-level check on wi.z (bsdf_sample; rule V5, core/math.h).
        ok_t = ok_t & !SameHemisphere(wo, wt);
        F denom = sqr(dot(wt, wm) + dot(wo, wm) / etap);
        F dwm_dwi = absdot(wt, wm) / denom;
        F pdf_t = pdf_wm * dwm_dwi * pt / (pr + pt);
        F f_t = T * mfd.D(wm) * mfd.G(wo, wt) *
                std::abs(dot(wt, wm) * dot(wo, wm) / (CosTheta(wt) * cos_o * denom));
        f_t = mode == TransportMode::Radiance ? f_t / sqr(etap) : f_t;

        s.wi = reflect ? wr : wt;
        s.f = Spectrum<F>(reflect ? f_r : f_t);
        // The chosen lobe's validity is folded into its pdf (0 = invalid; rule V2, core/math.h).
        pdf_r = ok_r ? pdf_r : F(0);
        pdf_t = ok_t ? pdf_t : F(0);
        s.pdf = reflect ? pdf_r : pdf_t;
        s.flags = lobe_flag(GlossyReflection, !reflect);
        s.eta = reflect ? F(1) : etap;
        s.valid = ((pr + pt) > F(0)) & (cos_o != F(0)) & (s.pdf > F(0));
        return s;
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        Vec3<F> wm;
        F etap, len2;
        bool ok = half_vector(wo, wi, &wm, &etap, &len2) & !is_smooth();
        bool reflect = CosTheta(wi) * CosTheta(wo) > F(0);
        F R, T, pr, pt;
        FrDielectricRT(dot(wo, wm), eta, &R, &T);
        lobe_probs(R, T, sample_flags, &pr, &pt);
        F pdf_wm = mfd.PDF(wo, wm);
        F p_r = pdf_wm / (F(4) * absdot(wo, wm)) * pr;
        // dwm/dwi = |wi.wm| / (wi.wm + wo.wm/etap)^2 = |wi.wm| etap^2 / |h|^2 (half_vector)
        F p_t = pdf_wm * absdot(wi, wm) * sqr(etap) / len2 * pt;
        F p = (reflect ? p_r : p_t) / (pr + pt);
        ok &= ((pr + pt) > F(0)); // len2 > 0 is in half_vector's ok
        return ok ? p : F(0);
    }

    void regularize() { mfd.regularize(); }
};

} // namespace bsdfkit
