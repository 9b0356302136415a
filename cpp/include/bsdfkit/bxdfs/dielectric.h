// Dielectric interface: smooth (delta) or Trowbridge-Reitz rough reflection and transmission
// (pbrt-v4 DielectricBxDF; Walter et al. 2007 "Microfacet models for refraction").
// Parameters (DielectricParams; Python: bsdfkit.Dielectric)
//   eta                  relative IOR inside / outside (> 0; < 1 means the outside is denser)
//   alpha_x, alpha_y, masking, distribution   anisotropic GGX or Beckmann; max(alpha) < 1e-3 (or
//                        eta == 1) makes both lobes deltas
//   sample_visible       sample visible normals (default) or D(wm) cos(wm) (Mitsuba 3's knob)
// wo may lie on either side. In Radiance mode transmitted radiance is scaled by 1/etap^2,
// in Importance mode it is not (Veach 1997 ch. 5), so f is not symmetric for transmission.
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"

namespace bsdfkit {

template <typename F> struct DielectricSpectral;  // its spectral form (batch_spectral.h / spectral/)

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
template <typename S = double> struct DielectricParamsT {
    S eta = 1.5, alpha_x = 0, alpha_y = 0;
    Masking masking = Masking::Correlated;
    Distribution distribution = Distribution::GGX;
    bool sample_visible = true;
    template <class V> void fields(V &&v) {
        v("eta", eta);
        v("alpha_x", alpha_x);
        v("alpha_y", alpha_y);
        v("masking", masking);
        v("distribution", distribution);
        v("sample_visible", sample_visible);
    }
    // the microfacet distribution these fields describe
    template <typename F> Microfacet<F> microfacet() const {
        return Microfacet<F>(F(alpha_x), F(alpha_y), masking, distribution, sample_visible);
    }
};
using DielectricParams = DielectricParamsT<>;

// Eta: eta's type, F; or Packet<F> for a dispersive glass on a spectral packet (eta per lane,
// never 1: batch_spectral.h keeps a glass whose eta(lambda) reaches 1 on the scalar path).
template <typename F, typename Eta = F> struct DielectricBxDF {
    using Params = DielectricParamsT<param_t<F>>;
    static constexpr const char *Name = "Dielectric";
    using Spectral = DielectricSpectral<F>;  // its spectral form (core/bxdf.h)
    static constexpr int GradColumns = 4;  // eval_grad columns at most
    Eta eta;
    Microfacet<F> mfd;

    static DielectricBxDF make(const Params &p) {
        return {F(p.eta), p.template microfacet<F>()};
    }

    // Bitwise | (not ||): a short-circuit here becomes control flow in every batch loop.
    bool is_smooth() const { return (!not_index_matched()) | mfd.effectively_smooth(); }
    bool not_index_matched() const {
        if constexpr (is_packet_v<Eta>) return true; // a per-lane eta is never 1 (above)
        else return eta != F(1);
    }

    uint8_t flags() const {
        uint8_t f = eta == F(1) ? Transmission : (Reflection | Transmission);
        return uint8_t(f | (mfd.effectively_smooth() ? Specular : Glossy));
    }

    // Runs on packets in the batch kernels (batch.h): every method is written once on the
    // evaluation type V (F, or a packet of F; core/simd.h).
    static constexpr bool Vectorized = true;

    // The distribution D(wm) cos(wm) sampling draws from (the `visible = false` knob): the model's,
    // widened by 1.2 - 0.2 sqrt|cos_o| (Walter et al. 2007 sec. 5.3, as Mitsuba 3's
    // roughdielectric), which lowers the sampling weights of grazing wo. Per lane: a packet of alphas.
    template <typename V> Microfacet<V> widened(V cos_o) const {
        V s = V(1.2) - V(0.2) * sqrt(abs(cos_o));
        return Microfacet<V>(V(mfd.alpha_x) * s, V(mfd.alpha_y) * s, mfd.masking, mfd.distribution, false);
    }

    // Lobe probabilities restricted by sample_flags.
    template <typename V> static void lobe_probs(V R, V T, uint8_t sample_flags, V *pr, V *pt) {
        restrict_lobes(R, T, sample_flags, pr, pt);
    }

    // Generalized half vector h = wi etap + wo of a pair, turned to face +z but NOT normalized
    // (wm = h / |h|), *len2 = |h|^2, and the relative IOR etap along wi. Every term of f and
    // pdf is homogeneous in h (FrDielectricRatioScaled, D_denom with len2), so the
    // normalization's root and division are never needed. Returns false where pbrt-v4 returns
    // 0: a horizon direction, a degenerate half vector, or a back-facing microfacet.
    template <typename V>
    Mask<V> half_vector(const Vec3<V> &wo, const Vec3<V> &wi, Vec3<V> *h_out, V *etap, V *len2_out) const {
        V cos_o = CosTheta(wo), cos_i = CosTheta(wi);
        Mask<V> reflect = cos_i * cos_o > V(0);
        V eta_side = select(cos_o > V(0), V(eta), V(F(1) / eta));
        *etap = select(reflect, V(1), eta_side);
        Vec3<V> h(mul_add(wi.x, *etap, wo.x), mul_add(wi.y, *etap, wo.y), mul_add(wi.z, *etap, wo.z));
        V len2 = length_squared(h);
        *len2_out = len2;
        Mask<V> ok = (cos_i != V(0)) & (cos_o != V(0)) & (len2 > V(0));
        h = select(h.z < V(0), -h, h);
        *h_out = h;
        // Discard back-facing microfacets (Walter 2007 sec. 5.1)
        ok = ok & (dot(h, wi) * cos_i >= V(0)) & (dot(h, wo) * cos_o >= V(0));
        return ok;
    }

    // With wm = h / |h|, L = |h|^2 and every term written in h (half_vector): reflection
    // D G F / |4 cos_i cos_o| = F / (D_denom(wm) G_denom) = r L^2 / (den D_denom(h) G_denom);
    // transmission (Walter 2007 eq. 21) D G (1 - F) |wi.wm wo.wm| / (|cos_i cos_o|
    // (wi.wm + wo.wm/etap)^2) = 4 (1 - F) |wi.wm wo.wm| etap^2 / (D_denom(wm) G_denom L)
    // = 4 t |wi.h wo.h| etap^2 / (den D_denom(h) G_denom) (core/microfacet.h), Radiance mode
    // dividing by etap^2, which cancels it. r, t, den: FrDielectricRatioScaled's numerators and
    // denominator at wo.h. 1 division and 3 square roots per element in all.
    template <typename V> Spectrum<V> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode mode) const {
        // Delta lobes evaluate to 0: a per-model (uniform) branch, not a lane mask.
        if (is_smooth()) return Spectrum<V>(V(0));
        Vec3<V> h;
        V etap, len2;
        Mask<V> active = half_vector(wo, wi, &h, &etap, &len2);
        V cos_o = CosTheta(wo), cos_i = CosTheta(wi);
        Mask<V> reflect = cos_i * cos_o > V(0);
        V r, t, den;
        V wo_h = dot(wo, h);
        FrDielectricRatioScaled(wo_h, len2, eta, &r, &t, &den); // t = (1 - F) den without cancellation
        V dg = mfd.D_denom(h, active, len2) *
               mfd.G_denom(abs(cos_o), abs(cos_i), mfd.smith_root(wo), mfd.smith_root(wi));
        V ft = V(4) * t * abs(dot(wi, h) * wo_h);
        ft = mode == TransportMode::Radiance ? ft : ft * sqr(etap);
        V v = select(reflect, r * sqr(len2), ft) / (den * dg);
        return Spectrum<V>(zero_unless(active, v));
    }

    template <typename V>
    BSDFSample<V> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode mode, uint8_t sample_flags) const {
        return is_smooth() ? sample_smooth(wo, uc, mode, sample_flags) : sample_rough(wo, uc, u, mode, sample_flags);
    }

    // 2 divisions (f, pdf; neither on the path to the lobe choice), 1 square root. The lobe
    // probabilities are FrDielectricRatio's numerators r : t (= R : T), its denominator joins
    // f's division (as sample_rough).
    template <typename V>
    BSDFSample<V> sample_smooth(const Vec3<V> &wo, V uc, TransportMode mode, uint8_t sample_flags) const {
        BSDFSample<V> s;
        V r, t, den, pr, pt, cos_t;
        // R = r / den, T = t / den; cos_t the transmitted cosine (0 under total internal reflection)
        FrDielectricRatio(CosTheta(wo), eta, &r, &t, &den, &cos_t);
        // eta == 1 is a pure pass-through: R = 0, T = 1 exactly rather than trusting rounding
        if (!not_index_matched()) {
            r = V(0);
            t = den;
        }
        lobe_probs(r, t, sample_flags, &pr, &pt);
        Mask<V> reflect = ChooseFirstLobe(uc, pr, pt);
        // Specular reflection about +z, or refraction through the flat interface.
        // (Refract's direction through n = +z from the Fresnel term's cos_t: one square root for both;
        // Refract's total internal reflection test sin2_t >= 1 is cos_t == 0, as its safe_sqrt)
        Vec3<V> wr(-wo.x, -wo.y, wo.z);
        V etap, inv_etap;
        Vec3<V> wt = RefractScaled(wo, Vec3<V>(V(0), V(0), V(1)), CosTheta(wo), V(1), cos_t, eta, &etap, &inv_etap);
        Mask<V> refr_ok = cos_t > V(0);
        s.wi = select(reflect, wr, wt);
        V cos_i = DeltaAbsCos(s.wi);
        V ft = mode == TransportMode::Radiance ? t * sqr(inv_etap) : t;
        s.f = Spectrum<V>(select(reflect, r, ft) / (den * cos_i));
        s.pdf = select(reflect, pr, pt) / (pr + pt);
        s.flags = lobe_flag<V>(SpecularReflection, !reflect);
        s.eta = select(reflect, V(1), etap);
        // cos_i > 0 always holds (DeltaAbsCos).
        s.valid = ((pr + pt) > V(0)) & (reflect | refr_ok);
        return s;
    }

    // Only the chosen lobe's value is computed. pdf = G1(wo) D / (4 cos_o) = 1 / (D_denom P)
    // for reflection, times 4 |wo.wm| |wi.wm| / (wi.wm + wo.wm / etap)^2 for transmission
    // (the half-vector Jacobian), P = 2 (cos_o + R_o); f as in f(). The lobe probabilities are
    // FrDielectricRatio's numerators r : t (= R : T), its denominator joins f's division.
    // Written in the sampled normal m = wm |m| unnormalized (Sample_wm_h), as f() is in h:
    // FrDielectricRatioScaled at wo.m with |m|^2 (its numerators and denominator scale alike),
    // D_denom(m) = D_denom(wm) |m|^4, the Jacobian's ratio is of degree 0 in m, the mirror
    // direction is 2 (wo.m) m / |m|^2 - wo and the refracted one -wo / etap + (|wo.m| / etap -
    // cos_t |m|) n / |m|^2 (n = +-m toward wo; cos_t |m| from the Fresnel term): 3 divisions
    // (|m|^2, f, pdf), 6 square roots per element.
    template <typename V>
    BSDFSample<V> sample_rough(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode mode, uint8_t sample_flags) const {
        BSDFSample<V> s;
        V len2;
        Vec3<V> m = mfd.visible ? mfd.Sample_wm_h(wo, u, &len2) : widened(CosTheta(wo)).Sample_wm_h(wo, u, &len2);
        V wo_m = dot(wo, m);
        V r, t, den, pr, pt, cos_t;
        FrDielectricRatioScaled(wo_m, len2, eta, &r, &t, &den, &cos_t); // R = r / den, T = t / den
        lobe_probs(r, t, sample_flags, &pr, &pt);
        Mask<V> reflect = ChooseFirstLobe(uc, pr, pt);
        V cos_o = CosTheta(wo), inv_len2 = V(1) / len2;

        // Reflection about the sampled normal, or refraction through it (in m's units).
        Vec3<V> wr = m * (V(2) * wo_m * inv_len2) - wo; // reflect_about_h, the reciprocal shared with wt
        V etap, inv_etap;
        Vec3<V> wt = RefractScaled(wo, m, wo_m, inv_len2, cos_t, eta, &etap, &inv_etap);
        Mask<V> ok_t = cos_t > V(0); // not total internal reflection (nor a grazing wo.m = 0)
        // wt.z == 0 is left to the BSDF-level check on wi.z (bsdf_sample).
        Mask<V> ok = (reflect & SameHemisphere(wo, wr)) | ((!reflect) & ok_t & (!SameHemisphere(wo, wt)));
        ok &= ((pr + pt) > V(0)) & (cos_o != V(0));
        if (!mfd.visible) ok &= wo_m * cos_o > V(0);  // a normal facing away from wo (D cos sampling)
        Vec3<V> wi = select(reflect, wr, wt);

        V abs_o = abs(cos_o), root_o = mfd.smith_root(wo), l4 = sqr(len2);
        V dd = mfd.D_denom(m, ok, len2); // D_denom(wm) |m|^4
        V dd_pdf = dd;  // the sampled distribution's (widened without visible normals)
        if (!mfd.visible) {
            Mask<V> ok_w = ok;
            dd_pdf = widened(cos_o).D_denom(m, ok_w, len2);
        }
        // Transmission: 4 |wo.m| |wi.m| / (wi.m + wo.m / etap)^2; reflection: 1.
        V wi_m = dot(wi, m);
        V jac_num = select(reflect, V(1), V(4) * abs(wo_m * wi_m));
        V jac_den = select(reflect, V(1), sqr(wi_m + wo_m * inv_etap));
        V ft = mode == TransportMode::Radiance ? t * sqr(inv_etap) : t;
        s.pdf = select(ok, select(reflect, pr, pt) * jac_num * l4 /
                               (dd_pdf * mfd.pdf_denom(wo, m, abs_o, root_o) * jac_den * (pr + pt)), V(0));
        V gd = mfd.G_denom(abs_o, AbsCosTheta(wi), root_o, mfd.smith_root(wi));
        s.f = Spectrum<V>(select(reflect, r, ft) * jac_num * l4 / (den * dd * gd * jac_den));
        s.wi = wi;
        s.flags = lobe_flag<V>(GlossyReflection, !reflect);
        s.eta = select(reflect, V(1), etap);
        s.valid = ok & (s.pdf > V(0));
        return s;
    }

    // Reflection pr / (D_denom(wm) P (pr + pt)) = pr L^2 / (D_denom(h) P (pr + pt));
    // transmission 4 |wo.wm| |wi.wm| etap^2 pt / (D_denom(wm) P L (pr + pt)) =
    // 4 |wo.h| |wi.h| etap^2 pt / (D_denom(h) P (pr + pt)), P = 2 (cos_o + R_o), h and L as in f.
    // The lobe probabilities are a ratio, so FrDielectricRatioScaled's numerators serve without
    // its denominator: 1 division, 2 square roots.
    template <typename V>
    V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        if (is_smooth()) return V(0); // delta lobes (as f)
        Vec3<V> h;
        V etap, len2;
        Mask<V> ok = half_vector(wo, wi, &h, &etap, &len2);
        Mask<V> reflect = CosTheta(wi) * CosTheta(wo) > V(0);
        V r, t, den, pr, pt;
        V wo_h = dot(wo, h);
        FrDielectricRatioScaled(wo_h, len2, eta, &r, &t, &den); // R : T = r : t
        lobe_probs(r, t, sample_flags, &pr, &pt);
        V dd = mfd.visible ? mfd.D_denom(h, ok, len2) : widened(CosTheta(wo)).D_denom(h, ok, len2);
        V num = select(reflect, pr * sqr(len2), V(4) * abs(wo_h * dot(wi, h)) * sqr(etap) * pt);
        V dn = dd * mfd.pdf_denom(wo, h, AbsCosTheta(wo), mfd.smith_root(wo)) * (pr + pt);
        ok &= ((pr + pt) > V(0)); // len2 > 0 is in half_vector's ok
        return zero_unless(ok, num / dn);
    }

    void regularize() { mfd.regularize(); }
};

} // namespace bsdfkit
