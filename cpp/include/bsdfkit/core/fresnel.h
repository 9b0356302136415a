// Fresnel reflectance for dielectric and conductor interfaces (unpolarised light).
#pragma once
#include "math.h"
#include "spectrum.h"

namespace bsdfkit {

// Exact dielectric Fresnel with inside flip and total internal reflection (pbrt-v4 FrDielectric).
template <typename F> inline F FrDielectric(F cos_i, F eta) {
    cos_i = clamp(cos_i, F(-1), F(1));
    bool inside = cos_i < F(0);
    eta = inside ? F(1) / eta : eta;
    cos_i = abs(cos_i);
    F sin2_t = (F(1) - sqr(cos_i)) / sqr(eta);
    bool tir = sin2_t >= F(1);
    F cos_t = safe_sqrt(F(1) - sin2_t);
    F r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    F r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    F fr = (sqr(r_parl) + sqr(r_perp)) / F(2);
    return tir ? F(1) : fr;
}

// FrDielectric's reflectance R and transmittance T = 1 - R, each from its own closed form
// (Born & Wolf: 1 - r^2 = 4 eta cos_i cos_t / (eta cos_i + cos_t)^2 per polarization), so
// that T keeps full relative precision where R -> 1 (near the critical angle) instead of
// losing it to the cancellation in 1 - R. One reciprocal serves both.
template <typename F> inline void FrDielectricRT(F cos_i, F eta, F *R, F *T) {
    cos_i = clamp(cos_i, F(-1), F(1));
    bool inside = cos_i < F(0);
    eta = inside ? F(1) / eta : eta;
    cos_i = abs(cos_i);
    F sin2_t = (F(1) - sqr(cos_i)) / sqr(eta);
    bool tir = sin2_t >= F(1);
    F cos_t = safe_sqrt(F(1) - sin2_t);
    F a = eta * cos_i + cos_t, b = cos_i + eta * cos_t;     // parallel / perpendicular denominators
    F a2 = sqr(a), b2 = sqr(b);
    F inv = F(1) / (F(2) * a2 * b2);
    F pa = eta * cos_i - cos_t, pb = cos_i - eta * cos_t;
    F r = (sqr(pa) * b2 + sqr(pb) * a2) * inv;
    F t = F(4) * eta * cos_i * cos_t * (a2 + b2) * inv;
    // a = b = 0 only at cos_i = 0 with cos_t = 0 (grazing TIR): then R = 1, T = 0.
    bool ok = (a2 * b2 > F(0)) & !tir;
    *R = ok ? r : F(1);
    *T = ok ? t : F(0);
}

// Minimal complex arithmetic in real form, so the conductor term vectorizes.
template <typename F> struct Cplx {
    F re, im;
};
template <typename F> inline Cplx<F> cmul(Cplx<F> a, Cplx<F> b) {
    return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re};
}
template <typename F> inline F cnorm(Cplx<F> a) { return a.re * a.re + a.im * a.im; }
// Principal square root: sqrt(a+ib) = (sqrt((|z|+a)/2), sign(b) sqrt((|z|-a)/2)).
template <typename F> inline Cplx<F> csqrt(Cplx<F> z) {
    F n = sqrt(cnorm(z));
    F re = safe_sqrt((n + z.re) * F(0.5));
    F im = safe_sqrt((n - z.re) * F(0.5));
    return {re, copysign1(im, z.im)};
}

// Complex Fresnel for a conductor with index eta + i k, unpolarised (Born & Wolf; the same
// value as pbrt-v4 FrComplex). Written in real arithmetic after Lagarde 2013, "Memo on Fresnel
// equations": two square roots and two divisions, which vectorizes and is half the cost of
// the complex-number form.
template <typename F> inline F FrComplex(F cos_i, F eta, F k) {
    cos_i = clamp(cos_i, F(0), F(1));
    F cos2 = cos_i * cos_i, sin2 = F(1) - cos2;
    F eta2 = eta * eta, k2 = k * k;
    F t0 = eta2 - k2 - sin2;
    F a2pb2 = sqrt(t0 * t0 + F(4) * eta2 * k2); // a^2 + b^2
    F a = safe_sqrt(F(0.5) * (a2pb2 + t0));
    F t1 = a2pb2 + cos2, t2 = F(2) * a * cos_i;
    F t3 = a2pb2 * cos2 + sin2 * sin2, t4 = t2 * sin2;
    // Both denominators vanish only for eta~ = 1 at grazing incidence, where F is 1.
    F rs = t1 + t2 > F(0) ? (t1 - t2) / (t1 + t2) : F(1);
    F rp_over_rs = t3 + t4 > F(0) ? (t3 - t4) / (t3 + t4) : F(1);
    return F(0.5) * (rs + rs * rp_over_rs);
}

template <typename F, int N>
inline Spectrum<F, N> FrComplex(F cos_i, const Spectrum<F, N> &eta, const Spectrum<F, N> &k) {
    Spectrum<F, N> r;
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
template <typename F, int N>
inline Spectrum<F, N> FrSchlick(F cos_i, const Spectrum<F, N> &f0) {
    F m = F(1) - clamp(cos_i, F(0), F(1));
    F m2 = m * m, m5 = m2 * m2 * m;
    Spectrum<F, N> r;
    for (int i = 0; i < N; ++i) r[i] = f0[i] + (F(1) - f0[i]) * m5;
    return r;
}

// F82-tint (Hoffman 2019, "Fresnel Equations Considered Harmful"; Kutz et al. 2021, Adobe
// Standard Material): F = F0 + (1 - F0)(1 - cos)^5 - a cos (1 - cos)^6, clamped to [0, 1]
// (the polynomial leaves [0, 1] for non-metallic eta + i k, e.g. eta ~ 1 with k ~ 0).
template <typename F, int N>
inline Spectrum<F, N> FrF82Tint(F cos_i, const Spectrum<F, N> &f0, const Spectrum<F, N> &a) {
    F c = clamp(cos_i, F(0), F(1));
    F m = F(1) - c;
    F m2 = m * m, m5 = m2 * m2 * m, cm6 = c * m5 * m;
    Spectrum<F, N> r;
    for (int i = 0; i < N; ++i) r[i] = clamp(f0[i] + (F(1) - f0[i]) * m5 - a[i] * cm6, F(0), F(1));
    return r;
}

} // namespace bsdfkit
