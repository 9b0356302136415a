// Local shading frame helpers (z is the normal), named as in pbrt-v4.
#pragma once
#include "math.h"

namespace bsdfkit {

template <typename F> inline F CosTheta(const Vec3<F> &w) { return w.z; }
template <typename F> inline F Cos2Theta(const Vec3<F> &w) { return w.z * w.z; }
template <typename F> inline F AbsCosTheta(const Vec3<F> &w) { return abs(w.z); }
template <typename F> inline F Sin2Theta(const Vec3<F> &w) { return max_(F(0), F(1) - Cos2Theta(w)); }
template <typename F> inline F SinTheta(const Vec3<F> &w) { return sqrt(Sin2Theta(w)); }
// +inf on the horizon; callers test for it (pbrt-v4 D and Lambda).
template <typename F> inline F Tan2Theta(const Vec3<F> &w) { return Sin2Theta(w) / Cos2Theta(w); }
template <typename F> inline F CosPhi(const Vec3<F> &w) {
    F s = SinTheta(w);
    return select(s == F(0), F(1), clamp(w.x / s, F(-1), F(1)));
}
template <typename F> inline F SinPhi(const Vec3<F> &w) {
    F s = SinTheta(w);
    return select(s == F(0), F(0), clamp(w.y / s, F(-1), F(1)));
}
// |cos theta| for a delta lobe's f = F / |cos|: floored at the smallest normal number so a
// denormal cosine cannot overflow f to inf (the lobe's weight f |cos| / pdf stays <= F).
template <typename F> inline F DeltaAbsCos(const Vec3<F> &w) {
    return max_(AbsCosTheta(w), F(std::numeric_limits<scalar_t<F>>::min()));
}
// Strict: a direction on the horizon is in neither hemisphere.
template <typename F> inline Mask<F> SameHemisphere(const Vec3<F> &a, const Vec3<F> &b) { return a.z * b.z > F(0); }

// The reflection half vector h = wo + wi NOT normalized (wm = h / |h|) and *len2 = |h|^2, for
// kernels written in h (D_denom with len2, the ...Scaled Fresnel ratios). `active &= (h != 0)`.
template <typename F>
inline Vec3<F> reflection_half_vector_h(const Vec3<F> &wo, const Vec3<F> &wi, Mask<F> &active, F *len2) {
    Vec3<F> h = wo + wi;
    *len2 = length_squared(h);
    active &= *len2 > F(0);
    return h;
}

// The mirror of wo about a normal m that was never normalized (|m|^2 = len2, wo_m = wo.m):
// 2 (wo.wm) wm - wo = 2 (wo.m) m / |m|^2 - wo (the samplers' reflection about Sample_wm_h's m).
template <typename F> inline Vec3<F> reflect_about_h(const Vec3<F> &wo, const Vec3<F> &m, F wo_m, F len2) {
    return m * (F(2) * wo_m / len2) - wo;
}

// The reflection half vector normalize(wo + wi) (Walter 2007 eq. 13). `active &= (wo + wi != 0)`;
// where it ends up false the result is wo + wi unnormalized, for the caller's mask to discard.
template <typename F> inline Vec3<F> reflection_half_vector(const Vec3<F> &wo, const Vec3<F> &wi, Mask<F> &active) {
    F len2;
    Vec3<F> h = reflection_half_vector_h(wo, wi, active, &len2);
    return h / sqrt(select(active, len2, F(1)));
}

// Mirror wo about n (pbrt-v4 Reflect).
template <typename F> inline Vec3<F> Reflect(const Vec3<F> &wo, const Vec3<F> &n) {
    return -wo + F(2) * dot(wo, n) * n;
}

// The relative IOR seen from the side of a direction with cosine c to the normal (pbrt-v4's
// flip): etap = eta above (c >= 0), 1 / eta below, and its reciprocal; one scalar division for a
// scalar eta. Returns c < 0.
template <typename F, typename E> inline Mask<F> RelativeEta(F c, E eta_, F *etap, F *inv_etap) {
    Mask<F> inside = c < F(0);
    F eta(eta_), inv_eta = F(E(1) / eta_);
    *inv_etap = select(inside, eta, inv_eta);
    *etap = select(inside, inv_eta, eta);
    return inside;
}

// Refraction through the normal m scaled by |m| (wm = m / |m|: a unit normal, or an unnormalized
// sampled one) when the transmitted cosine is known in m's units, cos_t_m = cos_t |m| (e.g.
// FrDielectricRatioScaled's): wt = -wi / etap + (|wi.m| / etap - cos_t_m) n / |m|^2, n = m turned
// toward wi (pbrt-v4 Refract's direction; wi below m inverts eta). wi_m = wi . m, inv_len2 =
// 1 / |m|^2. No square root; total internal reflection is the caller's (no cos_t_m).
template <typename F, typename E>
inline Vec3<F> RefractScaled(const Vec3<F> &wi, const Vec3<F> &m, F wi_m, F inv_len2, F cos_t_m, E eta_, F *etap,
                             F *inv_etap) {
    Mask<F> inside = RelativeEta(wi_m, eta_, etap, inv_etap);
    Vec3<F> n = select(inside, -m, m);
    return -wi * *inv_etap + n * ((abs(wi_m) * *inv_etap - cos_t_m) * inv_len2);
}

// Refraction of wi about the unit n with relative IOR eta (inside/outside); handles wi below n by
// inverting eta. Returns false on total internal reflection (pbrt-v4 Refract). eta is a scalar
// or V; one reciprocal of eta serves the whole formula.
template <typename F, typename E>
inline Mask<F> Refract(const Vec3<F> &wi, const Vec3<F> &n, E eta_, F *etap, Vec3<F> *wt, F *inv_etap_out = nullptr) {
    F cos_i = dot(n, wi), etap_, inv_etap;
    RelativeEta(cos_i, eta_, &etap_, &inv_etap);  // as RefractScaled (the same values)
    F sin2_i = max_(F(0), F(1) - sqr(cos_i));
    F sin2_t = sin2_i * sqr(inv_etap);
    Mask<F> tir = sin2_t >= F(1);
    F cos_t = safe_sqrt(F(1) - sin2_t);
    *wt = RefractScaled(wi, n, cos_i, F(1), cos_t, eta_, etap, &inv_etap);
    if (inv_etap_out) *inv_etap_out = inv_etap;
    return !tir;
}

} // namespace bsdfkit
