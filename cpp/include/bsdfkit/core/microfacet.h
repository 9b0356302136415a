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

template <typename F> struct TrowbridgeReitz {
    F alpha_x = 0, alpha_y = 0;
    Masking masking = Masking::Correlated;

    TrowbridgeReitz() = default;
    TrowbridgeReitz(F ax, F ay, Masking m) : alpha_x(ax), alpha_y(ay), masking(m) {
        if (!effectively_smooth()) {
            alpha_x = max_(alpha_x, F(kMinAlpha));
            alpha_y = max_(alpha_y, F(kMinAlpha));
        }
    }

    bool effectively_smooth() const { return max_(alpha_x, alpha_y) < F(kSmoothAlpha); }

    // Normal distribution D(wm) (Trowbridge & Reitz 1975; anisotropic form, Heitz 2014 eq. 85).
    F D(const Vec3<F> &wm) const {
        F cos2 = Cos2Theta(wm), sin2 = Sin2Theta(wm);
        F cos4 = cos2 * cos2;
        // e = tan^2(theta) (cos^2 phi / ax^2 + sin^2 phi / ay^2), written without phi
        F e = (sqr(wm.x / alpha_x) + sqr(wm.y / alpha_y)) / cos2;
        F d = F(1) / (Pi<F> * alpha_x * alpha_y * cos4 * sqr(F(1) + e));
        // tan^2 = inf on the horizon and tiny cos^4 both mean D = 0 (pbrt-v4 safeguards)
        return (cos4 < F(1e-16) || !(sin2 / cos2 < std::numeric_limits<F>::infinity())) ? F(0) : d;
    }

    // Smith auxiliary function Lambda(w) (Heitz 2014 eq. 86).
    F Lambda(const Vec3<F> &w) const {
        F cos2 = Cos2Theta(w);
        // alpha^2 tan^2 theta along phi, written without phi
        F a2t2 = (sqr(w.x * alpha_x) + sqr(w.y * alpha_y)) / cos2;
        // A horizon direction (or tan^2 overflowing) gives Lambda = inf, so G1 = G = 0: the
        // limit of a fully masked direction. pbrt-v4 returns 0 here and relies on callers
        // excluding cos = 0; returning inf keeps f finite for cos down to the underflow limit.
        return (sqrt(F(1) + a2t2) - F(1)) / F(2);
    }

    F G1(const Vec3<F> &w) const { return F(1) / (F(1) + Lambda(w)); }

    // Masking-shadowing for the pair, per the knob.
    F G(const Vec3<F> &wo, const Vec3<F> &wi) const {
        F lo = Lambda(wo), li = Lambda(wi);
        return masking == Masking::Correlated ? F(1) / (F(1) + lo + li)
                                              : F(1) / ((F(1) + lo) * (F(1) + li));
    }

    // Distribution of visible normals D_w(wm) = G1(w) max(0, w.wm) D(wm) / cos(w) (Heitz 2014 eq. 2).
    F D(const Vec3<F> &w, const Vec3<F> &wm) const {
        return safe_div(G1(w) * absdot(w, wm) * D(wm), AbsCosTheta(w));
    }
    F PDF(const Vec3<F> &w, const Vec3<F> &wm) const { return D(w, wm); }

    // Visible-normal sampling, hemisphere variant (Heitz 2018; pbrt-v4 Sample_wm).
    Vec3<F> Sample_wm(const Vec3<F> &w, Point2<F> u) const {
        Vec3<F> wh = normalize(Vec3<F>(alpha_x * w.x, alpha_y * w.y, w.z));
        wh = wh.z < F(0) ? -wh : wh;
        bool pole = wh.z >= F(0.99999);
        Vec3<F> t1 = pole ? Vec3<F>(1, 0, 0) : normalize(cross(Vec3<F>(0, 0, 1), wh));
        Vec3<F> t2 = cross(wh, t1);
        Point2<F> p = SampleUniformDiskPolar(u);
        F h = std::sqrt(max_(F(0), F(1) - sqr(p.x)));
        p.y = lerp((F(1) + wh.z) / F(2), h, p.y);
        F pz = std::sqrt(max_(F(0), F(1) - sqr(p.x) - sqr(p.y)));
        Vec3<F> nh = p.x * t1 + p.y * t2 + pz * wh;
        return normalize(Vec3<F>(alpha_x * nh.x, alpha_y * nh.y, max_(F(1e-6), nh.z)));
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
