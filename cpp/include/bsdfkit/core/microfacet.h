// Anisotropic Trowbridge-Reitz (GGX) microfacet distribution with visible-normal sampling.
// Heitz 2014 "Understanding the masking-shadowing function"; Heitz 2018 "Sampling the GGX
// distribution of visible normals"; safeguards as in pbrt-v4's TrowbridgeReitzDistribution.
#pragma once
#include <array>

#include "frame.h"
#include "sampling.h"

namespace bsdfkit {

// Masking-shadowing knob: height-correlated Smith (pbrt-v4, default) or the separable
// product G1(wo) G1(wi) (Mitsuba 3, Walter 2007).
enum class Masking : uint8_t { Correlated = 0, Separable = 1 };
inline constexpr std::array<const char *, 2> enum_names(Masking) { return {"correlated", "separable"}; }

// Below this max(alpha) a microfacet lobe is treated as a delta (pbrt-v4 EffectivelySmooth).
inline constexpr double kSmoothAlpha = 1e-3;
// Floor for each alpha of a rough lobe: one zero axis would divide by zero in D (pbrt-v4 #283).
inline constexpr double kMinAlpha = 1e-4;

// F: the alphas' type, a scalar; or a packet for per-lane alphas (per-element parameters,
// batch_varying.h), where effectively_smooth() is a lane mask and the floor applies per lane.
template <typename F> struct TrowbridgeReitz {
    F alpha_x = 0, alpha_y = 0;
    Masking masking = Masking::Correlated;

    TrowbridgeReitz() = default;
    TrowbridgeReitz(F ax, F ay, Masking m) : alpha_x(ax), alpha_y(ay), masking(m) {
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

    // Normal distribution D(wm) (Trowbridge & Reitz 1975; anisotropic form, Heitz 2014 eq. 85).
    template <typename V> V D(const Vec3<V> &wm) const {
        V cos2 = Cos2Theta(wm), sin2 = Sin2Theta(wm);
        V cos4 = cos2 * cos2;
        // e = tan^2(theta) (cos^2 phi / ax^2 + sin^2 phi / ay^2), written without phi
        V e = (sqr(wm.x / alpha_x) + sqr(wm.y / alpha_y)) / cos2;
        V d = V(1) / (V(Pi<scalar_t<V>>) * alpha_x * alpha_y * cos4 * sqr(V(1) + e));
        // tan^2 = inf on the horizon and tiny cos^4 both mean D = 0 (pbrt-v4 safeguards)
        return select((cos4 < V(1e-16)) | !(sin2 / cos2 < V(std::numeric_limits<scalar_t<V>>::infinity())), V(0), d);
    }

    // Smith auxiliary function Lambda(w) (Heitz 2014 eq. 86).
    template <typename V> V Lambda(const Vec3<V> &w) const {
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

    // Distribution of visible normals D_w(wm) = G1(w) max(0, w.wm) D(wm) / cos(w) (Heitz 2014 eq. 2).
    template <typename V> V D(const Vec3<V> &w, const Vec3<V> &wm) const {
        return safe_div(G1(w) * absdot(w, wm) * D(wm), AbsCosTheta(w));
    }
    template <typename V> V PDF(const Vec3<V> &w, const Vec3<V> &wm) const { return D(w, wm); }

    // ---- The same terms as shared denominators, for kernels with the fewest divides and
    // square roots (one reciprocal per quantity; the caller combines them into one divide).

    // 1 / D(wm) for a unit wm: pi ax ay (cos^2 + (x/ax)^2 + (y/ay)^2)^2 (eq. 85 with
    // cos^4 (1 + tan^2 (...))^2 expanded; no phi, no tan). `active &=` D's safeguard (D = 0
    // where cos^4 < 1e-16, which includes the horizon).
    // With len2 = |h|^2 for an h that was never normalized (wm = h / |h|), the same expression
    // in h is D_denom(wm) |h|^4: the caller saves the normalization's root and division.
    template <typename V> V D_denom(const Vec3<V> &wm, Mask<V> &active, V len2 = V(1)) const {
        using S = scalar_t<V>;
        V cos2 = Cos2Theta(wm);
        active &= cos2 * cos2 >= V(1e-16) * sqr(len2);
        V qx = wm.x * V(S(1) / alpha_x), qy = wm.y * V(S(1) / alpha_y);
        V q = mul_add(qx, qx, mul_add(qy, qy, cos2));
        return V(Pi<S> * alpha_x * alpha_y) * sqr(q);
    }
    // |cos| sqrt(1 + alpha^2 tan^2) = sqrt(cos^2 + (ax x)^2 + (ay y)^2), so that
    // 1 + Lambda(w) = (|cos| + root) / (2 |cos|) (eq. 86): finite down to cos = 0.
    template <typename V> V smith_root(const Vec3<V> &w) const {
        V ax = w.x * alpha_x, ay = w.y * alpha_y;
        return sqrt(mul_add(ax, ax, mul_add(ay, ay, Cos2Theta(w))));
    }
    // G(wo, wi) / (4 cos_o cos_i) = 1 / G_denom: height-correlated 2 (cos_i R_o + cos_o R_i),
    // separable (cos_o + R_o)(cos_i + R_i), with R = smith_root.
    template <typename V> V G_denom(V cos_o, V cos_i, V root_o, V root_i) const {
        return masking == Masking::Correlated ? V(2) * mul_add(cos_i, root_o, cos_o * root_i)
                                              : (cos_o + root_o) * (cos_i + root_i);
    }
    // PDF(w, wm) / (4 |w.wm|) = G1(w) D(wm) / (4 |cos|) = 1 / (2 (|cos| + R) / D): the
    // reflection pdf's denominator without D, 2 (|cos| + R).
    template <typename V> V reflection_pdf_denom(V cos_o, V root_o) const { return V(2) * (cos_o + root_o); }

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
    template <typename V> Vec3<V> Sample_wm(const Vec3<V> &w, Point2<V> u) const {
        V len2;
        Vec3<V> m = Sample_wm_h(w, u, &len2);
        return m / sqrt(len2);
    }
    template <typename V> Vec3<V> Sample_wm_h(const Vec3<V> &w, Point2<V> u, V *len2) const {
        using S = scalar_t<V>;
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
