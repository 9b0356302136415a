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

// Complex Fresnel for a conductor with index eta + i k (pbrt-v4 FrComplex; Born & Wolf).
template <typename F> inline F FrComplex(F cos_i, F eta, F k) {
    cos_i = clamp(cos_i, F(0), F(1));
    F sin2_i = F(1) - sqr(cos_i);
    // eta~^2 and sin^2(theta_t) = sin^2(theta_i) / eta~^2
    Cplx<F> e2{sqr(eta) - sqr(k), F(2) * eta * k};
    F inv_n = F(1) / cnorm(e2);
    Cplx<F> sin2_t{sin2_i * e2.re * inv_n, -sin2_i * e2.im * inv_n};
    Cplx<F> cos_t = csqrt(Cplx<F>{F(1) - sin2_t.re, -sin2_t.im});
    Cplx<F> ec{eta * cos_i, k * cos_i};           // eta~ cos_i
    Cplx<F> ect = cmul(Cplx<F>{eta, k}, cos_t);   // eta~ cos_t
    // r_parl = (eta~ cos_i - cos_t) / (eta~ cos_i + cos_t); r_perp = (cos_i - eta~ cos_t) / (cos_i + eta~ cos_t)
    F num_parl = cnorm(Cplx<F>{ec.re - cos_t.re, ec.im - cos_t.im});
    F den_parl = cnorm(Cplx<F>{ec.re + cos_t.re, ec.im + cos_t.im});
    F num_perp = cnorm(Cplx<F>{cos_i - ect.re, -ect.im});
    F den_perp = cnorm(Cplx<F>{cos_i + ect.re, ect.im});
    // Both denominators vanish only for eta~ = 1 at grazing incidence, where F is 1.
    F r_parl = den_parl > F(0) ? num_parl / den_parl : F(1);
    F r_perp = den_perp > F(0) ? num_perp / den_perp : F(1);
    return (r_parl + r_perp) / F(2);
}

template <typename F, int N>
inline Spectrum<F, N> FrComplex(F cos_i, const Spectrum<F, N> &eta, const Spectrum<F, N> &k) {
    Spectrum<F, N> r;
    for (int i = 0; i < N; ++i) r[i] = FrComplex(cos_i, eta[i], k[i]);
    return r;
}

} // namespace bsdfkit
