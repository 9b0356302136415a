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
    cos_i = std::abs(cos_i);
    F sin2_t = (F(1) - sqr(cos_i)) / sqr(eta);
    bool tir = sin2_t >= F(1);
    F cos_t = safe_sqrt(F(1) - sin2_t);
    F r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    F r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    F fr = (sqr(r_parl) + sqr(r_perp)) / F(2);
    return tir ? F(1) : fr;
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
    F n = std::sqrt(cnorm(z));
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
    F a2pb2 = std::sqrt(t0 * t0 + F(4) * eta2 * k2); // a^2 + b^2
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

} // namespace bsdfkit
