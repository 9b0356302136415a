// Anisotropic microfacet distributions with visible-normal sampling: Trowbridge-Reitz (GGX) and
// Beckmann. Heitz 2014 "Understanding the masking-shadowing function"; Heitz 2018 "Sampling the
// GGX distribution of visible normals"; safeguards as in pbrt-v4's TrowbridgeReitzDistribution;
// Beckmann's terms as Walter et al. 2007 and its visible normals as Jakob 2014.
#pragma once
#include <array>

#include "frame.h"
#include "sampling.h"

namespace bsdfkit {

// Masking-shadowing knob: height-correlated Smith (pbrt-v4, default) or the separable
// product G1(wo) G1(wi) (Mitsuba 3, Walter 2007).
enum class Masking : uint8_t { Correlated = 0, Separable = 1 };
inline constexpr std::array<const char *, 2> enum_names(Masking) { return {"correlated", "separable"}; }

// Distribution knob: Trowbridge-Reitz / GGX (pbrt-v4's only one, the default) or Beckmann
// (Beckmann & Spizzichino 1963; Mitsuba 3's default for roughconductor / roughdielectric).
enum class Distribution : uint8_t { GGX = 0, Beckmann = 1 };
inline constexpr std::array<const char *, 2> enum_names(Distribution) { return {"ggx", "beckmann"}; }

// Below this max(alpha) a microfacet lobe is treated as a delta (pbrt-v4 EffectivelySmooth).
inline constexpr double kSmoothAlpha = 1e-3;
// Floor for each alpha of a rough lobe: one zero axis would divide by zero in D (pbrt-v4 #283).
inline constexpr double kMinAlpha = 1e-4;

// F: the alphas' type, a scalar; or a packet for per-lane alphas (per-element parameters,
// batch_varying.h), where effectively_smooth() is a lane mask and the floor applies per lane.
// The knobs (masking, distribution, visible) are uniform: every lane's are the same.
template <typename F> struct Microfacet {
    F alpha_x = 0, alpha_y = 0;
    Masking masking = Masking::Correlated;
    Distribution distribution = Distribution::GGX;
    // Sample the distribution of visible normals (Heitz & d'Eon 2014; the default) or D(wm) cos(wm)
    // (Walter et al. 2007; Mitsuba 3's sample_visible = false): a sampling knob, f is the same.
    bool visible = true;

    Microfacet() = default;
    Microfacet(F ax, F ay, Masking m, Distribution d = Distribution::GGX, bool vis = true)
        : alpha_x(ax), alpha_y(ay), masking(m), distribution(d), visible(vis) {
        if constexpr (is_packet_v<F>) {
            const Mask<F> rough = !effectively_smooth();
            alpha_x = select(rough, max_(alpha_x, F(kMinAlpha)), alpha_x);
            alpha_y = select(rough, max_(alpha_y, F(kMinAlpha)), alpha_y);
        } else if (!effectively_smooth()) {
            alpha_x = max_(alpha_x, F(kMinAlpha));
            alpha_y = max_(alpha_y, F(kMinAlpha));
        }
    }

    // bool; a lane mask for per-lane alphas
    auto effectively_smooth() const { return max_(alpha_x, alpha_y) < F(kSmoothAlpha); }
    bool beckmann() const { return distribution == Distribution::Beckmann; }

    // Normal distribution D(wm): Trowbridge & Reitz 1975 (anisotropic form, Heitz 2014 eq. 85),
    // or Beckmann exp(-e) / (pi ax ay cos^4) (Walter 2007 eq. 25), with e as below.
    template <typename V> V D(const Vec3<V> &wm) const {
        V cos2 = Cos2Theta(wm), sin2 = Sin2Theta(wm);
        V cos4 = cos2 * cos2;
        // e = tan^2(theta) (cos^2 phi / ax^2 + sin^2 phi / ay^2), written without phi
        V e = (sqr(wm.x / alpha_x) + sqr(wm.y / alpha_y)) / cos2;
        V d = beckmann() ? exp_f64libm(-e) / (V(Pi<scalar_t<V>>) * alpha_x * alpha_y * cos4)
                         : V(1) / (V(Pi<scalar_t<V>>) * alpha_x * alpha_y * cos4 * sqr(V(1) + e));
        // tan^2 = inf on the horizon and tiny cos^4 both mean D = 0 (pbrt-v4 safeguards)
        return select((cos4 < V(1e-16)) | !(sin2 / cos2 < V(std::numeric_limits<scalar_t<V>>::infinity())), V(0), d);
    }

    // Smith auxiliary function Lambda(w): GGX exactly (Heitz 2014 eq. 86); Beckmann by Walter
    // 2007's rational fit (eq. 27, as pbrt-v3 and Mitsuba 3): with a = 1 / (alpha tan theta),
    // (1 - 1.259 a + 0.396 a^2) / (3.535 a + 2.181 a^2) for a < 1.6, else 0.
    template <typename V> V Lambda(const Vec3<V> &w) const {
        if (beckmann()) {
            V c = AbsCosTheta(w), root = smith_root(w);
            return (root - c) / (V(2) * c);  // root = |cos| (1 + 2 Lambda)
        }
        V cos2 = Cos2Theta(w);
        // alpha^2 tan^2 theta along phi, written without phi
        V a2t2 = (sqr(w.x * alpha_x) + sqr(w.y * alpha_y)) / cos2;
        // A horizon direction (or tan^2 overflowing) gives Lambda = inf, so G1 = G = 0: the
        // limit of a fully masked direction. pbrt-v4 returns 0 here and relies on callers
        // excluding cos = 0; returning inf keeps f finite for cos down to the underflow limit.
        return (sqrt(V(1) + a2t2) - V(1)) / V(2);
    }

    template <typename V> V G1(const Vec3<V> &w) const { return V(1) / (V(1) + Lambda(w)); }

    // Masking-shadowing for the pair, per the knob.
    template <typename V> V G(const Vec3<V> &wo, const Vec3<V> &wi) const {
        V lo = Lambda(wo), li = Lambda(wi);
        return masking == Masking::Correlated ? V(1) / (V(1) + lo + li) : V(1) / ((V(1) + lo) * (V(1) + li));
    }

    // Distribution of visible normals D_w(wm) = G1(w) max(0, w.wm) D(wm) / cos(w) (Heitz 2014 eq. 2),
    // with the exact G1 that normalizes it (Beckmann: visible_root, not Walter's fit).
    template <typename V> V D(const Vec3<V> &w, const Vec3<V> &wm) const {
        V c = AbsCosTheta(w), g1 = beckmann() ? V(2) * c / (c + visible_root(w)) : G1(w);
        return safe_div(g1 * absdot(w, wm) * D(wm), c);
    }
    // The sampling density of wm (the `visible` knob): D_w(wm), or D(wm) |cos(wm)|.
    template <typename V> V PDF(const Vec3<V> &w, const Vec3<V> &wm) const {
        return visible ? D(w, wm) : D(wm) * AbsCosTheta(wm);
    }

    // ---- The same terms as shared denominators, for kernels with the fewest divides and
    // square roots (one reciprocal per quantity; the caller combines them into one divide).

    // 1 / D(wm) for a unit wm: GGX pi ax ay (cos^2 + (x/ax)^2 + (y/ay)^2)^2 (eq. 85 with
    // cos^4 (1 + tan^2 (...))^2 expanded; no phi, no tan); Beckmann pi ax ay cos^4 exp(e).
    // `active &=` D's safeguard (D = 0 where cos^4 < 1e-16, which includes the horizon).
    // With len2 = |h|^2 for an h that was never normalized (wm = h / |h|), the same expression
    // in h is D_denom(wm) |h|^4: the caller saves the normalization's root and division.
    template <typename V> V D_denom(const Vec3<V> &wm, Mask<V> &active, V len2 = V(1)) const {
        using S = scalar_t<V>;
        V cos2 = Cos2Theta(wm);
        active &= cos2 * cos2 >= V(1e-16) * sqr(len2);
        V qx = wm.x * V(S(1) / alpha_x), qy = wm.y * V(S(1) / alpha_y);
        if (beckmann()) {  // e is of degree 0 in h, cos^4 |h|^4 = h.z^4
            V e = mul_add(qx, qx, qy * qy) / cos2;
            return V(Pi<S> * alpha_x * alpha_y) * sqr(cos2) * exp_f64libm(e);
        }
        V q = mul_add(qx, qx, mul_add(qy, qy, cos2));
        return V(Pi<S> * alpha_x * alpha_y) * sqr(q);
    }
    // R(w) = |cos| (1 + 2 Lambda(w)), so that 1 + Lambda(w) = (|cos| + R) / (2 |cos|): finite
    // down to cos = 0. GGX: |cos| sqrt(1 + alpha^2 tan^2) = sqrt(cos^2 + (ax x)^2 + (ay y)^2)
    // (eq. 86). Beckmann: with s = sqrt((ax x)^2 + (ay y)^2) = |cos| / a, Walter's fit multiplied
    // through by s^2 / |cos|: (2 s^2 + 1.017 |cos| s + 2.973 cos^2) / (3.535 s + 2.181 |cos|)
    // where |cos| < 1.6 s, else |cos| (Lambda = 0).
    template <typename V> V smith_root(const Vec3<V> &w) const {
        V ax = w.x * alpha_x, ay = w.y * alpha_y;
        if (beckmann()) {
            V s2 = mul_add(ax, ax, ay * ay), s = sqrt(s2), c = AbsCosTheta(w);
            V r = mul_add(V(2), s2, c * mul_add(V(1.017), s, V(2.973) * c)) / mul_add(V(3.535), s, V(2.181) * c);
            return select(c < V(1.6) * s, r, c);
        }
        return sqrt(mul_add(ax, ax, mul_add(ay, ay, Cos2Theta(w))));
    }
    // smith_root with the exact Smith Lambda, the normalization of the visible normals that
    // Sample_wm draws: GGX's is exact already; Beckmann's (Walter 2007 eq. 26: Lambda = (erf(a) - 1)
    // / 2 + exp(-a^2) / (2 a sqrt(pi))) is |cos| erf(a) + s exp(-a^2) / sqrt(pi), a = |cos| / s.
    // Walter's fit in smith_root is up to 0.31 % off in G1: a pdf from it would not integrate to 1.
    template <typename V> V visible_root(const Vec3<V> &w) const {
        if (!beckmann()) return smith_root(w);
        using S = scalar_t<V>;
        V ax = w.x * alpha_x, ay = w.y * alpha_y;
        V s = sqrt(mul_add(ax, ax, ay * ay)), c = AbsCosTheta(w);
        Mask<V> normal = s <= V(0);
        V a = c / select(normal, V(1), s);
        V r = mul_add(c, erf(a), s * exp(-sqr(a)) * V(InvSqrtPi<S>));
        return select(normal, c, r);
    }
    // G(wo, wi) / (4 cos_o cos_i) = 1 / G_denom: height-correlated 2 (cos_i R_o + cos_o R_i),
    // separable (cos_o + R_o)(cos_i + R_i), with R = smith_root.
    template <typename V> V G_denom(V cos_o, V cos_i, V root_o, V root_i) const {
        return masking == Masking::Correlated ? V(2) * mul_add(cos_i, root_o, cos_o * root_i)
                                              : (cos_o + root_o) * (cos_i + root_i);
    }
    // PDF(w, wm) / (4 |w.wm|) = G1(w) D(wm) / (4 |cos|) = 1 / (2 (|cos| + R) / D): the
    // reflection pdf's denominator without D, 2 (|cos| + R), for visible-normal sampling.
    template <typename V> V reflection_pdf_denom(V cos_o, V root_o) const { return V(2) * (cos_o + root_o); }
    // The same per the `visible` knob, for an h = wm |h| never normalized: D(wm) |cos(wm)| /
    // (4 |wo.wm|) = 1 / (D_denom 4 |wo.h| / |h.z|) without visible normals. A Beckmann pdf
    // normalizes by the exact G1 (visible_root): it is the density Sample_wm draws from.
    // root_o: smith_root(wo) (Beckmann's visible normals take visible_root instead).
    template <typename V> V pdf_denom(const Vec3<V> &wo, const Vec3<V> &h, V cos_o, V root_o) const {
        if (visible) return reflection_pdf_denom(cos_o, beckmann() ? visible_root(wo) : root_o);
        return V(4) * abs(dot(wo, h)) / abs(h.z);
    }

    // Visible-normal sampling by spherical caps (Dupuy & Benyoub 2023, "Sampling Visible GGX
    // Normals with Spherical Caps"): in the stretched configuration the visible normals of the
    // unit direction wh are h = c + wh with c uniform on the cap z > -wh.z of the unit sphere;
    // unstretched and normalized, h is distributed as D_w (the same density as Heitz 2018's
    // hemisphere method, pbrt-v4 Sample_wm, with 2 square roots and a division fewer).
    // 1 - z = u.x (1 + wh.z) = a exactly, so sin^2 = a (2 - a) without cancellation at the pole.
    // Written in units of L = |v|, v the stretched w (wh = v / L), so that wh is never formed
    // (no division on the sampler's critical path): b = a L = u.x (L + v.z), sin L = sqrt(b (2 L -
    // b)), and h L = (sin L cos phi + v.x, sin L sin phi + v.y, (L - b) + v.z), whose unstretched
    // direction is the same (h.z's floor 1e-6 becomes 1e-6 L).
    // Sample_wm_h: the sampled normal unnormalized (wm = m / |m|), |m|^2 in *len2, for callers
    // that write their terms homogeneous in it (Conductor, Dielectric: no root and division).
    // Beckmann and the `visible = false` knob: Sample_wm_slopes (below).
    template <typename V> Vec3<V> Sample_wm(const Vec3<V> &w, Point2<V> u) const {
        V len2;
        Vec3<V> m = Sample_wm_h(w, u, &len2);
        return m / sqrt(len2);
    }
    template <typename V> Vec3<V> Sample_wm_h(const Vec3<V> &w, Point2<V> u, V *len2) const {
        using S = scalar_t<V>;
        if (beckmann() || !visible) return Sample_wm_slopes(w, u, len2);
        Vec3<V> v(alpha_x * w.x, alpha_y * w.y, w.z);
        v = select(v.z < V(0), -v, v);
        V L = sqrt(dot(v, v));
        V b = u.x * (L + v.z);
        V sin_l = sqrt(max_(V(0), b * (V(2) * L - b))), sp, cp;
        sincos_(V(2 * Pi<S>) * u.y, &sp, &cp);
        Vec3<V> h(sin_l * cp + v.x, sin_l * sp + v.y, (L - b) + v.z);
        Vec3<V> m(alpha_x * h.x, alpha_y * h.y, max_(V(1e-6) * L, h.z));
        *len2 = dot(m, m);
        return m;
    }

    // Sampling through microfacet slopes (Heitz & d'Eon 2014): a slope (x, y) of the unit-alpha
    // distribution, stretched by (ax, ay), is the normal m = (-ax x, -ay y, 1) (|m|^2 in *len2).
    // Without visible normals (either distribution), the slope is drawn from P22 itself, so m has
    // density D(wm) cos(wm): GGX |slope|^2 = u / (1 - u), Beckmann -log(1 - u) (Walter 2007 eqs.
    // 28, 35). Beckmann's visible normals: in the configuration stretched and rotated so that w
    // lies at (theta, phi = 0), x from Jakob 2014's inversion (BeckmannVisibleSlope11), y Gaussian.
    template <typename V> Vec3<V> Sample_wm_slopes(const Vec3<V> &w, Point2<V> u, V *len2) const {
        using S = scalar_t<V>;
        V x, y;
        if (!visible) {
            V s2 = beckmann() ? -log(V(1) - u.x) : u.x / (V(1) - u.x), s = sqrt(s2), sp, cp;
            sincos_(V(2 * Pi<S>) * u.y, &sp, &cp);
            x = s * cp;
            y = s * sp;
        } else {
            Vec3<V> v(alpha_x * w.x, alpha_y * w.y, w.z);
            v = select(v.z < V(0), -v, v);
            V r2 = mul_add(v.x, v.x, v.y * v.y), r = sqrt(r2);
            Mask<V> pole = r2 <= V(0);
            V inv_r = V(1) / select(pole, V(1), r);
            V cos_phi = select(pole, V(1), v.x * inv_r), sin_phi = select(pole, V(0), v.y * inv_r);
            V x1, y1;
            BeckmannVisibleSlope11(v.z, r, u, &x1, &y1);
            x = mul_sub(cos_phi, x1, sin_phi * y1);
            y = mul_add(sin_phi, x1, cos_phi * y1);
        }
        Vec3<V> m(-alpha_x * x, -alpha_y * y, V(1));
        *len2 = dot(m, m);
        return m;
    }

    // The unit-alpha Beckmann slopes visible from a direction at polar angle theta with
    // tan(theta) = r / z (Jakob 2014, "An improved visible normal sampling routine for the
    // Beckmann distribution"). The visible x-slope density (1 - x tan) exp(-x^2) on x < cot has,
    // in b = erf(x), the CDF C(b) = k (1 + b + tan / sqrt(pi) exp(-x^2)), k = 1 / (1 + erf(cot) +
    // tan / sqrt(pi) exp(-cot^2)), and dC/db = k (1 - x tan). C(b) = u.x is solved by three
    // Newton steps kept inside a bisection bracket [-1, erf(cot)], from the first guess b = erf(cot)
    // - (1 + erf(cot)) (1 - u.x)^p, p a cubic in theta (the fit and safeguards of Mitsuba 3's
    // MicrofacetDistribution::sample_visible_11). y = erfinv(2 u.y - 1) is independent.
    template <typename V> static void BeckmannVisibleSlope11(V z, V r, Point2<V> u, V *x, V *y) {
        using S = scalar_t<V>;
        const V inv_sqrt_pi = V(InvSqrtPi<S>);
        V ux = max_(u.x, V(1e-6)), uy = max_(u.y, V(1e-6));
        Mask<V> pole = r <= V(0);
        V tan_t = select(pole, V(0), r / z), cot_t = select(pole, V(0), z / r);  // pole: tan 0, cot inf
        V hi = select(pole, V(1), erf(cot_t)), lo = V(-1);
        V theta = acos(z / sqrt(mul_add(r, r, z * z)));
        V p = mul_add(theta, mul_add(theta, mul_add(theta, V(-0.0594), V(0.4265)), V(-0.876)), V(1));
        V b = hi - (V(1) + hi) * pow(V(1) - ux, p);
        V k = V(1) / (V(1) + hi + select(pole, V(0), tan_t * inv_sqrt_pi * exp(-sqr(cot_t))));
        Mask<V> done = Mask<V>(false);
        for (int it = 0; it < 3; ++it) {
            b = select((b >= lo) & (b <= hi), b, V(0.5) * (lo + hi));
            V xb = drjit::erfinv(b);
            V value = k * (V(1) + b + tan_t * inv_sqrt_pi * exp(-sqr(xb))) - ux;
            V deriv = k * (V(1) - xb * tan_t);
            done |= abs(value) < V(1e-5);
            hi = select(done | !(value > V(0)), hi, b);
            lo = select(done | (value > V(0)), lo, b);
            b = select(done, b, b - value / deriv);
        }
        b = select((b >= lo) & (b <= hi), b, V(0.5) * (lo + hi));
        *x = drjit::erfinv(b);
        *y = drjit::erfinv(mul_sub(V(2), uy, V(1)));
    }

    // Roughen near-specular lobes for path regularization (pbrt-v4 Regularize).
    void regularize() {
        if (alpha_x < F(0.3)) alpha_x = clamp(F(2) * alpha_x, F(0.1), F(0.3));
        if (alpha_y < F(0.3)) alpha_y = clamp(F(2) * alpha_y, F(0.1), F(0.3));
    }
};

// pbrt-v4 RoughnessToAlpha: alpha = sqrt(roughness). pbrt-v4 #479 notes r^2 would be the
// perceptually linear choice; kept for compatibility with pbrt scenes.
template <typename F> inline F RoughnessToAlpha(F r) { return sqrt(r); }

} // namespace bsdfkit
