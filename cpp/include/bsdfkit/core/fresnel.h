// Fresnel reflectance for dielectric and conductor interfaces (unpolarised light).
#pragma once
#include "frame.h"
#include "math.h"
#include "spectrum.h"

namespace bsdfkit {

// Exact dielectric Fresnel reflectance R and transmittance T = 1 - R, unpolarised, with the
// inside flip and total internal reflection (pbrt-v4 FrDielectric). Each from its own closed
// form (Born & Wolf: 1 - r^2 = 4 eta cos_i cos_t / (eta cos_i + cos_t)^2 per polarization), so
// that T keeps full relative precision where R -> 1 (near the critical angle) instead of
// losing it to the cancellation in 1 - R. One reciprocal of eta and one of the shared
// denominator 2 a^2 b^2 serve both. eta is a scalar or V. FrDielectricRatio gives the two
// numerators over that denominator (R = r / den, T = t / den; den = 1 where R = 1, T = 0), for
// callers that fold den into a division of their own.
// The Fresnel formulas themselves, from cos_i, cos_t >= 0 (both times the same length) and the
// relative IOR eta on the incident side: the squared parallel / perpendicular denominators
// a^2 = (eta cos_i + cos_t)^2, b^2 = (cos_i + eta cos_t)^2, and R = r / den, T = t / den.
template <typename F> inline void FrDielectricNumerators(F cos_i, F cos_t, F eta, F *a2, F *b2, F *r, F *t, F *den) {
    F a = mul_add(eta, cos_i, cos_t), b = mul_add(eta, cos_t, cos_i);
    *a2 = sqr(a);
    *b2 = sqr(b);
    F pa = mul_sub(eta, cos_i, cos_t), pb = neg_mul_add(eta, cos_t, cos_i);
    *den = F(2) * *a2 * *b2;
    *r = mul_add(sqr(pa), *b2, sqr(pb) * *a2);
    *t = F(4) * eta * cos_i * cos_t * (*a2 + *b2);
}
// FrDielectricRatioScaled takes the cosine times a length, c = cos_i |h|, and len2 = |h|^2 (a
// half vector h that was never normalized): a, b, the numerators and den all scale by |h|^4, so
// the ratios R and T do not change and the caller saves the normalization's root and division.
// cos_t_out (optional): the transmitted cosine times |h| (>= 0; 0 under total internal
// reflection), what Refract's homogeneous form needs.
template <typename F, typename E>
inline void FrDielectricRatioScaled(F cos_i, F len2, E eta_, F *r_num, F *t_num, F *den, F *cos_t_out = nullptr) {
    F eta, inv_etap;
    RelativeEta(cos_i, eta_, &eta, &inv_etap);
    cos_i = abs(cos_i);
    // len2 sin^2 of the transmitted angle; cos^2 <= 1 (rounding past |h| clamped, a NaN kept)
    F c2 = sqr(cos_i);
    F sin2_t = (len2 - min_(len2, c2)) * sqr(inv_etap);  // min_: select(c2 > len2, len2, c2)
    Mask<F> tir = sin2_t >= len2;
    F cos_t = safe_sqrt(len2 - sin2_t);
    if (cos_t_out) *cos_t_out = cos_t;
    F a2, b2, r, t, d;
    FrDielectricNumerators(cos_i, cos_t, eta, &a2, &b2, &r, &t, &d);
    // a = b = 0 only at cos_i = 0 with cos_t = 0 (grazing TIR): then R = 1, T = 0.
    Mask<F> ok = (a2 * b2 > F(0)) & !tir;
    *den = select(ok, d, F(1));
    *r_num = select(ok, r, F(1));
    *t_num = select(ok, t, F(0));
}
template <typename F, typename E>
inline void FrDielectricRatio(F cos_i, E eta, F *r_num, F *t_num, F *den, F *cos_t_out = nullptr) {
    FrDielectricRatioScaled(clamp(cos_i, F(-1), F(1)), F(1), eta, r_num, t_num, den, cos_t_out);
}
// FrDielectricRatioScaled for light arriving from outside, cos_i > 0 (a caller's mask drops the
// other lanes), and eta a scalar (or a per-lane packet: one division per packet): the same
// formulas with the inside flip, the clamp and the masks folded away. Past the critical angle
// (eta < 1) cos_t = 0 gives t = 0 and r = den (R = 1) by the formulas themselves, and cos_i > 0
// keeps den > 0; a cos_i a rounding past |h| (or past 1 for a direction of length 1 within the
// unit tolerance) makes cos_t a rounding past it, not a NaN. 1 square root.
template <typename F, typename E>
inline void FrDielectricRatioScaledAbove(F cos_i, F len2, E eta, F *r_num, F *t_num, F *den) {
    const E inv_eta2 = E(1) / (eta * eta); // a scalar division for a scalar eta
    F sin2_i = neg_mul_add(cos_i, cos_i, len2); // len2 sin^2 of the incident angle
    F cos_t = safe_sqrt(neg_mul_add(sin2_i, F(inv_eta2), len2)), a2, b2;
    FrDielectricNumerators(cos_i, cos_t, F(eta), &a2, &b2, r_num, t_num, den);
}

template <typename F, typename E> inline void FrDielectricRT(F cos_i, E eta, F *R, F *T) {
    F r, t, den;
    FrDielectricRatio(cos_i, eta, &r, &t, &den);
    F inv = F(1) / den;
    *R = r * inv;
    *T = t * inv;
}

// The reflectance alone: FrDielectricRT's R.
template <typename F, typename E> inline F FrDielectric(F cos_i, E eta) {
    F R, T;
    FrDielectricRT(cos_i, eta, &R, &T);
    return R;
}

// Minimal complex arithmetic in real form, so the conductor term vectorizes.
template <typename F> struct Cplx {
    F re, im;
};
template <typename F> inline Cplx<F> cmul(Cplx<F> a, Cplx<F> b) {
    return {mul_sub(a.re, b.re, a.im * b.im), mul_add(a.re, b.im, a.im * b.re)};
}
template <typename F> inline F cnorm(Cplx<F> a) { return mul_add(a.re, a.re, a.im * a.im); }
// Principal square root: sqrt(a+ib) = (sqrt((|z|+a)/2), sign(b) sqrt((|z|-a)/2)).
template <typename F> inline Cplx<F> csqrt(Cplx<F> z) {
    F n = sqrt(cnorm(z));
    F re = safe_sqrt((n + z.re) * F(0.5));
    F im = safe_sqrt((n - z.re) * F(0.5));
    return {re, copysign1(im, z.im)};
}

// Complex Fresnel for a conductor with index eta + i k, unpolarised (Born & Wolf; the same
// value as pbrt-v4 FrComplex), in real arithmetic after Lagarde 2013, "Memo on Fresnel
// equations": Rs = (t1 - t2) / (t1 + t2), Rp = Rs (t3 - t4) / (t3 + t4), so that
// F = (Rs + Rp) / 2 = (t1 - t2) t3 / ((t1 + t2)(t3 + t4)) as num / den with ONE division.
// FrComplexRatio returns num and den so that a kernel can fold den into its own single
// division. Two square roots (|z| = a^2 + b^2 and 2a = sqrt(2 (|z| + t0))); eta and k are
// scalars or V.
// FrComplexRatioScaled takes c = cos_i |h| >= 0 and len2 = |h|^2 for a half vector h that was
// never normalized: t0, |z|, t1, t2 scale by |h|^2, t3, t4 by |h|^4, so num and den both by
// |h|^6 and F does not change (as FrDielectricRatioScaled).
template <typename F, typename E> inline void FrComplexRatioScaled(F c, F len2, E eta, E k, F *num, F *den) {
    F cos2 = sqr(c);
    cos2 = min_(len2, cos2); // cos^2 <= 1 (rounding past |h|; a NaN kept): select(cos2 > len2, len2, cos2)
    F sin2 = len2 - cos2;
    E eta2 = eta * eta, k2 = k * k;
    F t0 = F(eta2 - k2) * len2 - sin2;
    F a2pb2 = sqrt(t0 * t0 + F(E(4) * eta2 * k2) * sqr(len2)); // a^2 + b^2
    F t2 = safe_sqrt(F(2) * (a2pb2 + t0)) * c;                  // 2 a cos_i
    F t1 = a2pb2 + cos2;
    F t3 = a2pb2 * cos2 + sin2 * sin2, t4 = t2 * sin2;
    // den = 0 only for eta~ = 1 at grazing incidence, where F = 1.
    F d = (t1 + t2) * (t3 + t4);
    Mask<F> ok = d > F(0);
    *num = select(ok, (t1 - t2) * t3, F(1));
    *den = select(ok, d, F(1));
}
template <typename F, typename E> inline void FrComplexRatio(F cos_i, E eta, E k, F *num, F *den) {
    FrComplexRatioScaled(clamp(cos_i, F(0), F(1)), F(1), eta, k, num, den);
}
template <typename F, typename E> inline F FrComplex(F cos_i, E eta, E k) {
    F num, den;
    FrComplexRatio(cos_i, eta, k, &num, &den);
    return num / den;
}

template <typename V, typename F, int N>
inline Spectrum<V, N> FrComplex(V cos_i, const Spectrum<F, N> &eta, const Spectrum<F, N> &k) {
    Spectrum<V, N> r;
    for (int i = 0; i < N; ++i) r[i] = FrComplex(cos_i, eta[i], k[i]);
    return r;
}

// ---- Approximations of the conductor term (the Conductor 'fresnel' knob)

// F82-tint's fitting cosine, mu_bar = 1/7 (theta ~ 81.79 deg), where mu (1 - mu)^6 peaks.
inline constexpr double kF82Cos = 1.0 / 7.0;

// Normal-incidence reflectance of eta + i k: F0 = ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2).
// T is double (models compute it at construction in double) or a Dual (core/dual.h).
template <typename T> inline T ConductorF0(T eta, T k) {
    return (sqr(eta - T(1)) + k * k) / (sqr(eta + T(1)) + k * k);
}

// F82-tint coefficient a (Kutz et al. 2021 eq. for a, with the tinted target replaced by the
// exact Fresnel): a = (Schlick(mu_bar) - F_exact(mu_bar)) / (mu_bar (1 - mu_bar)^6).
template <typename T> inline T ConductorF82A(T eta, T k) {
    T f0 = ConductorF0(eta, k);
    double m = 1.0 - kF82Cos;
    T schlick = f0 + (T(1) - f0) * T(m * m * m * m * m);
    return (schlick - FrComplex(T(kF82Cos), eta, k)) / T(kF82Cos * (m * m * m * m * m * m));
}

// Schlick 1994: F = F0 + (1 - F0)(1 - cos)^5, per channel.
template <typename V, typename F, int N>
inline Spectrum<V, N> FrSchlick(V cos_i, const Spectrum<F, N> &f0) {
    V m = V(1) - clamp(cos_i, V(0), V(1));
    V m2 = m * m, m5 = m2 * m2 * m;
    Spectrum<V, N> r;
    for (int i = 0; i < N; ++i) r[i] = V(f0[i]) + V(F(1) - f0[i]) * m5;
    return r;
}

// F82-tint (Hoffman 2019, "Fresnel Equations Considered Harmful"; Kutz et al. 2021, Adobe
// Standard Material): F = F0 + (1 - F0)(1 - cos)^5 - a cos (1 - cos)^6, clamped to [0, 1]
// (the polynomial leaves [0, 1] for non-metallic eta + i k, e.g. eta ~ 1 with k ~ 0).
template <typename V, typename F, int N>
inline Spectrum<V, N> FrF82Tint(V cos_i, const Spectrum<F, N> &f0, const Spectrum<F, N> &a) {
    V c = clamp(cos_i, V(0), V(1));
    V m = V(1) - c;
    V m2 = m * m, m5 = m2 * m2 * m, cm6 = c * m5 * m;
    Spectrum<V, N> r;
    for (int i = 0; i < N; ++i) r[i] = clamp(V(f0[i]) + V(F(1) - f0[i]) * m5 - V(a[i]) * cm6, V(0), V(1));
    return r;
}

} // namespace bsdfkit
