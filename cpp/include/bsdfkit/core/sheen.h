// Zeltner, Burley & Chiang 2022, "Practical Multiple-Scattering Sheen Using Linearly Transformed
// Cosines" (SIGGRAPH 2022 talk): the sheen (OpenPBR "fuzz") lobe as an LTC fit of a volumetric
// microflake layer's multiple-scattering reflectance.
//
// What it computes, for a white sheen of roughness r in the local shading frame (z = normal,
// wo = view direction, wi = light direction, both unit and pointing away from the surface):
//   R(mu_o, r)       the layer's directional albedo (the paper's fitted R; albedo()),
//   D_ltc(wi)        the LTC lobe, a normalized density over the upper hemisphere of wi (pdf()):
//                      D_ltc(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3
//                    with D_o the clamped cosine z / pi and (in the frame where wo has azimuth 0)
//                      M^-1 = [[a, 0, b], [0, a, 0], [0, 0, 1]],  a = aInv(mu_o, r), b = bInv(mu_o, r),
//                    so D_ltc(w) = w.z a^2 / (pi |M^-1 w|^4) (|w| = 1; M^-1 keeps z, so the upper
//                    hemisphere maps onto itself and the integral over it is exactly 1),
//   f(wo, wi)        = R D_ltc(wi) / wi.z, the BRDF WITHOUT the cosine (eval()),
//   sample()         wi = M w_c / |M w_c| for a cosine-distributed w_c; its density is D_ltc.
// Fits (facts carried over): the directional albedo's Gaussian fit and the rational fits of the
// LTC coefficients aInv, bInv are those of the authors' code (github.com/tizian/ltc-sheen) as
// transcribed in MaterialX libraries/pbrlib/genglsl/lib/mx_microfacet_sheen.glsl
// (mx_zeltner_sheen_dir_albedo, mx_zeltner_sheen_ltc_aInv, mx_zeltner_sheen_ltc_bInv).
//
// Conventions and edge cases:
// - mu_o = cos_o is clamped to [0, 1]; r to [0.01, 1] (the range the fits were made on; at r = 0
//   the LTC degenerates, a = 0, and the albedo fit divides 0 by 0). The albedo is clamped to [0, 1].
// - The LTC frame: x along wo's tangential part (wo in the x-z plane), y = z x x. For wo along the
//   normal (wo.x = wo.y = 0) the lobe is rotationally symmetric (bInv = 0 at mu_o = 1 by the fit's
//   sqrt(1 - mu_o) factor) and the frame is the shading frame itself.
// - eval() and pdf() are 0 for wi.z <= 0 or wo.z <= 0. make() takes cos_o separately (the caller
//   passes wo.z); eval/pdf/sample take wo only for its azimuth.
// - sample() returns a direction with z >= 0 (z = 0 only from u on the disk's rim).
#pragma once
#include "frame.h"
#include "math.h"
#include "sampling.h"

namespace bsdfkit {

template <typename F> struct ZeltnerSheen {
    F mu;    // clamped cos_o
    F r;     // clamped roughness
    F a_inv; // LTC inverse-matrix coefficients (a = aInv, b = bInv)
    F b_inv;
    F R;     // directional albedo

    // Zeltner et al. 2022's fits (tizian/ltc-sheen; MaterialX mx_microfacet_sheen.glsl), x = mu_o, y = r.
    static F fit_albedo(F x, F y) {
        F s = y * mul_add(F(1.58491), y, F(0.0206607)) / (F(0.0379424) + y * (F(1.32227) + y));
        F m = y * (F(-0.193854) + y * (F(-1.14885) + y * (F(1.7932) - F(0.95943) * y * y))) / (F(0.046391) + y);
        F o = y * (F(0.000654023) + (F(-0.0207818) + F(0.119681) * y) * y) / (F(1.26264) + y * (F(-1.92021) + y));
        F t = (x - m) / s;
        // 1 / sqrt(2 pi) = InvSqrtPi / sqrt(2)
        return exp(F(-0.5) * t * t) * F(InvSqrtPi<scalar_t<F>> * 0.70710678118654752440) / s + o;
    }
    static F fit_a_inv(F x, F y) {
        return (F(2.58126) * x + F(0.813703) * y) * y / (F(1) + F(0.310327) * x * x + F(2.60994) * x * y);
    }
    static F fit_b_inv(F x, F y) {
        return safe_sqrt(F(1) - x) * (y - F(1)) * y * y * y /
               (F(0.0000254053) + F(1.71228) * x - F(1.71506) * x * y + F(1.34174) * y * y);
    }

    static ZeltnerSheen make(F cos_o, F roughness) {
        ZeltnerSheen s;
        s.mu = clamp(cos_o, F(0), F(1));
        s.r = clamp(roughness, F(0.01), F(1));
        s.a_inv = fit_a_inv(s.mu, s.r);
        s.b_inv = fit_b_inv(s.mu, s.r);
        s.R = clamp(fit_albedo(s.mu, s.r), F(0), F(1));
        return s;
    }

    F albedo() const { return R; }

    // cos and sin of wo's azimuth; (1, 0) when wo is along the normal.
    static void azimuth(const Vec3<F> &wo, F *c, F *s) {
        F l2 = mul_add(wo.x, wo.x, wo.y * wo.y);
        Mask<F> ok = l2 > F(0);
        F inv = F(1) / sqrt(select(ok, l2, F(1)));
        *c = select(ok, wo.x * inv, F(1));
        *s = select(ok, wo.y * inv, F(0));
    }

    // a^2 / (pi |M^-1 w|^4) for a unit w in the shading frame: D_ltc(w) / w.z (w.z > 0).
    F d_over_cos(const Vec3<F> &wo, const Vec3<F> &w) const {
        F c, s;
        azimuth(wo, &c, &s);
        F lx = mul_add(c, w.x, s * w.y), ly = neg_mul_add(s, w.x, c * w.y); // w in the LTC frame
        F ox = mul_add(a_inv, lx, b_inv * w.z), oy = a_inv * ly;           // M^-1 w
        F l2 = mul_add(ox, ox, mul_add(oy, oy, w.z * w.z));
        return sqr(a_inv / l2) * F(InvPi<scalar_t<F>>);
    }

    F eval(const Vec3<F> &wo, const Vec3<F> &wi) const {
        Mask<F> ok = (wo.z > F(0)) & (wi.z > F(0));
        return select(ok, R * d_over_cos(wo, wi), F(0));
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi) const {
        Mask<F> ok = (wo.z > F(0)) & (wi.z > F(0));
        return select(ok, wi.z * d_over_cos(wo, wi), F(0));
    }

    Vec3<F> sample(const Vec3<F> &wo, Point2<F> u) const {
        Vec3<F> wc = SampleCosineHemisphere(u);
        // M w_c with M = [[1/a, 0, -b/a], [0, 1/a, 0], [0, 0, 1]]
        F ia = F(1) / a_inv;
        F lx = neg_mul_add(b_inv, wc.z, wc.x) * ia, ly = wc.y * ia;
        Vec3<F> w = normalize(Vec3<F>(lx, ly, wc.z));
        F c, s;
        azimuth(wo, &c, &s);
        return Vec3<F>(neg_mul_add(s, w.y, c * w.x), mul_add(s, w.x, c * w.y), w.z);
    }
};

} // namespace bsdfkit
