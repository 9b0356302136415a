// Plastic: a Lambertian base under a dielectric coating, Mitsuba 3's `plastic` (alpha = 0,
// smooth coating) and `roughplastic` (GGX coating), two-sided (a wo below the surface sees the
// mirrored material, as Mitsuba's `twosided` adapter does).
//
//   reflectance           diffuse albedo R of the base, per channel in [0, 1]
//   specular_reflectance  Ks, a multiplier on the coating's reflection (1 = physical)
//   eta                   relative IOR of the coating (inside / outside), > 0 and != 1
//   alpha                 isotropic GGX alpha of the coating; < 1e-3 = smooth (delta) coating
//   nonlinear             internal-reflection sum with the base albedo inside (R / (1 - R Fdr),
//                         the seed's derivation) instead of Mitsuba's default 1 / (1 - Fdr)
//   masking               coating's G: separable G1 G1 (Mitsuba) or height-correlated (pbrt-v4)
//
// f = Ks Fr(wo.wh) D G / (4 cos_o cos_i)                                  (rough coating only)
//   + R / (1 - {Fdr | R Fdr}) * T(cos_o) T(cos_i) / (pi eta^2)          (Weidlich & Wilkie 2007,
//     Mitsuba's plastic.cpp / roughplastic.cpp), with
//   smooth: T = 1 - F(cos), Fdr = Mitsuba's fitted diffuse Fresnel reflectance of 1 / eta
//           (Egan & Hilgeman 1973 for eta < 1, d'Eon & Irving 2011 otherwise);
//   rough:  T(cos) = 64-entry table, linearly interpolated in cos, of the coating's directional
//           transmittance; Fdr = 2 * mean over the same 64 cosines of R_int(mu) mu, R_int the
//           coating's directional reflectance from inside. Both are integrated, as Mitsuba does,
//           with a Gauss-Legendre product rule over the unit square pushed through Mitsuba's GGX
//           visible-normal warp (32^2 nodes for eta > 1, 128^2 otherwise), cos floored at 1e-6.
//           Built once per (alpha, eta) and cached (PlasticTablesCached): in double for the
//           float/double models, on a 2-partial Dual for the gradient models (F = Dual, their
//           Params hold Duals: every derived quantity, the tables included, carries d/d theta).
// Lobe choice as Mitsuba: specular with probability p = w k / (w k + (1 - w)(1 - k)), where
// k = F(cos_o) (smooth) or 1 - T(cos_o) (rough) and w = mean(Ks) / (mean(R) + mean(Ks)).
// The rough specular lobe is sampled with Mitsuba's visible-normal warp (sample_visible_11,
// concentric-disk variant) so that samples coincide with Mitsuba's for the same uniforms.
#pragma once
#include <array>
#include <cstdint>
#include <mutex>
#include <vector>

#include "../core/bsdf_sample.h"
#include "../core/dual.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"

namespace bsdfkit {

template <typename F> struct PlasticSpectral;  // its spectral form (batch_spectral.h / spectral/)

// Mitsuba's MI_ROUGH_TRANSMITTANCE_RES: cosines at which the rough transmittance is tabulated.
inline constexpr int kPlasticTableRes = 64;

// Mitsuba's fresnel_diffuse_reflectance(eta): hemispherical average of F for light arriving
// from the side of relative IOR eta. eta < 1: Egan & Hilgeman 1973 fit; otherwise the
// polynomial in 1/eta of d'Eon & Irving 2011. S: double or a Dual (gradients, core/dual.h).
template <typename S> inline S FresnelDiffuseReflectanceT(const S &eta) {
    S ie = 1.0 / eta;
    if (eta < 1.0) return 0.0636 * ie + eta * (eta * -1.4399 + 0.7099) + 0.6681;
    return 0.919317 + ie * (-3.4793 + ie * (6.75335 + ie * (-7.80989 + ie * (4.98554 + ie * -1.36881))));
}
inline double FresnelDiffuseReflectance(double eta) { return FresnelDiffuseReflectanceT(eta); }

// Gauss-Legendre nodes and weights on [-1, 1]: roots of P_n by Newton's method from the
// Chebyshev guess, w = 2 / ((1 - x^2) P_n'(x)^2) (Abramowitz & Stegun 25.4.29).
inline void GaussLegendre(int n, double *x, double *w) {
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double z = -std::cos(Pi<double> * (i + 0.75) / (n + 0.5)), dp = 1;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1, p1 = z;  // P_0, P_1, then the three-term recurrence up to P_n
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            double pn = n == 1 ? z : p1, pm = n == 1 ? 1 : p0;
            dp = n * (z * pn - pm) / (z * z - 1);
            double step = pn / dp;
            z -= step;
            if (std::abs(step) <= 1e-16) break;
        }
        x[i] = z;
        x[n - 1 - i] = -z;
        w[i] = w[n - 1 - i] = 2 / ((1 - z * z) * dp * dp);
    }
}

// Mitsuba 3's GGX visible-normal sampler (MicrofacetDistribution::sample with sample_visible):
// stretch wo, draw a slope of the alpha = 1 distribution seen from cos(theta) with the
// concentric-disk projection (sample_visible_11), rotate, unstretch. The same density as
// pbrt-v4's Sample_wm (Heitz 2018), a different map from u to wm. wo.z > 0.
// VisibleSlope11: Heitz & d'Eon 2014 slope sampling, Mitsuba's "simpler and exact" disk variant:
// the slope is (sx, sy) / d (d > 0 on the visible side).
template <typename V> inline void VisibleSlope11(V cos_t, V sin_t, Point2<V> u, V *sx, V *sy, V *d) {
    Point2<V> p = SampleUniformDiskConcentric(u);
    V s = V(0.5) * (V(1) + cos_t);
    p.y = lerp(s, safe_sqrt(V(1) - p.x * p.x), p.y);
    V pz = safe_sqrt(V(1) - p.x * p.x - p.y * p.y);
    *d = sin_t * p.y + cos_t * pz;
    *sx = cos_t * p.y - sin_t * pz;
    *sy = p.x;
}
// Operation for operation as Mitsuba (normalized stretched wo, sin from cos, the slope divided by
// d): the rough coating's tables (RoughInterfaceAlbedo), whose derivatives in alpha and eta are
// checked against a Dr.Jit transcription of Mitsuba's code (tests/test_grad_plastic.py: a node
// that moves by a rounding can cross the integrand's total-internal-reflection kink).
template <typename V, typename A> inline Vec3<V> SampleVisibleGGXMitsuba(A alpha_, const Vec3<V> &wo, Point2<V> u) {
    using S = scalar_t<V>;
    V alpha(alpha_);
    Vec3<V> wp = normalize(Vec3<V>(alpha * wo.x, alpha * wo.y, wo.z));
    V sin2 = V(1) - wp.z * wp.z, inv_sin = V(1) / sqrt(select(sin2 > V(0), sin2, V(1)));
    Mask<V> pole = abs(sin2) <= V(S(2) * std::numeric_limits<S>::epsilon());
    V cos_phi = select(pole, V(1), clamp(wp.x * inv_sin, V(-1), V(1)));
    V sin_phi = select(pole, V(0), clamp(wp.y * inv_sin, V(-1), V(1)));
    V cos_t = wp.z, sin_t = safe_sqrt(V(1) - cos_t * cos_t), sx, sy, d;
    VisibleSlope11(cos_t, sin_t, u, &sx, &sy, &d);
    V norm = V(1) / d;
    sx = sx * norm;
    sy = sy * norm;
    V mx = (cos_phi * sx - sin_phi * sy) * alpha, my = (sin_phi * sx + cos_phi * sy) * alpha;
    return normalize(Vec3<V>(-mx, -my, V(1)));
}
// The same map for the sampler, written for a short critical path: with v the stretched wo and
// q = v.x^2 + v.y^2, cos theta = v.z / |v|, sin theta = sqrt(q) / |v| and (cos phi, sin phi) =
// (v.x, v.y) / sqrt(q) (no normalized wp: one root and division deep); the slope's 1 / d is a
// common factor of the direction (-slope, 1), so d scales its z instead; and the direction is
// returned unnormalized, |m|^2 in *len2_out.
template <typename V, typename A>
inline Vec3<V> SampleVisibleGGXMitsubaH(A alpha_, const Vec3<V> &wo, Point2<V> u, V *len2_out) {
    using S = scalar_t<V>;
    V alpha(alpha_);
    Vec3<V> v(alpha * wo.x, alpha * wo.y, wo.z);
    V q = v.x * v.x + v.y * v.y, len2 = q + v.z * v.z;
    V inv_len = V(1) / sqrt(len2), rq = sqrt(q), inv_rq = V(1) / select(q > V(0), rq, V(1));
    // Mitsuba's pole test |1 - cos^2| <= 2 eps on the normalized direction
    Mask<V> pole = q <= V(S(2) * std::numeric_limits<S>::epsilon()) * len2;
    V cos_phi = select(pole, V(1), clamp(v.x * inv_rq, V(-1), V(1)));
    V sin_phi = select(pole, V(0), clamp(v.y * inv_rq, V(-1), V(1)));
    V cos_t = v.z * inv_len, sin_t = rq * inv_len, sx, sy, d;
    VisibleSlope11(cos_t, sin_t, u, &sx, &sy, &d);
    V mx = (cos_phi * sx - sin_phi * sy) * alpha, my = (sin_phi * sx + cos_phi * sy) * alpha;
    Vec3<V> m(-mx, -my, d);
    *len2_out = dot(m, m);
    return m;
}

// Smith G1 of GGX with Mitsuba's back-facing rule (0 when v.m and v.z differ in sign).
template <typename S> inline S SmithG1Mitsuba(const S &alpha, const Vec3<S> &v, const Vec3<S> &m) {
    S xy = sqr(alpha * v.x) + sqr(alpha * v.y);
    S g = xy == 0.0 ? S(1.0) : 2.0 / (1.0 + sqrt(1.0 + xy / sqr(v.z)));
    return dot(v, m) * v.z <= 0.0 ? S(0.0) : g;
}

// Gauss-Legendre rule of Mitsuba's eval_transmittance / eval_reflectance: 32 nodes for eta > 1,
// 128 otherwise.
struct GLRule {
    int n;
    double x[128], w[128];
    explicit GLRule(double eta) : n(eta > 1 ? 32 : 128) { GaussLegendre(n, x, w); }
};

// Mitsuba's eval_transmittance / eval_reflectance: the directional transmittance (refract =
// true) or reflectance of a GGX dielectric interface for light arriving along w (w.z > 0) at
// relative IOR eta, by the Gauss-Legendre product rule over Mitsuba's visible-normal warp.
// S: double, or a Dual for the derivatives in alpha and eta of the rule as computed (its nodes
// are constants; the integrand's kinks - the horizon test, total internal reflection - are
// one-sided points of core/dual.h's list).
template <typename S>
inline S RoughInterfaceAlbedo(const S &alpha, const S &eta, const Vec3<double> &w_, bool refract, const GLRule &q) {
    Vec3<S> w(S(w_.x), S(w_.y), S(w_.z));
    S sum(0.0);
    for (int a = 0; a < q.n; ++a)
        for (int b = 0; b < q.n; ++b) {
            Point2<S> u{S(0.5 * q.x[b] + 0.5), S(0.5 * q.x[a] + 0.5)};
            Vec3<S> m = SampleVisibleGGXMitsuba(alpha, w, u);
            S c = dot(w, m), Fr = FrDielectric(c, eta), v;
            if (refract) {
                // Snell: the refracted direction through m (c > 0 here: visible normals)
                S cos_t = -safe_sqrt(1.0 - (1.0 - c * c) / sqr(eta));
                Vec3<S> wt_dir = m * (c / eta + cos_t) - w / eta;
                v = wt_dir.z * w.z >= 0.0 ? S(0.0) : SmithG1Mitsuba(alpha, wt_dir, m) * (1.0 - Fr);
            } else {
                Vec3<S> wr = Reflect(w, m);
                v = (wr.z <= 0.0 || w.z <= 0.0) ? S(0.0) : SmithG1Mitsuba(alpha, wr, m) * Fr;
            }
            sum += v * q.w[a] * q.w[b] * 0.25;
        }
    return sum;
}

// The rough coating's tables (Mitsuba roughplastic::parameters_changed) for the parameter type S
// of a model's Params: double, or the Dual of a gradient model (then T and fdr carry their
// derivatives in alpha and eta, chained to the Dual's partials).
template <typename S = double> struct PlasticTablesT {
    S T[kPlasticTableRes] = {};  // external transmittance at cos = max(1e-6, i / 63)
    S fdr = S(0.0);              // internal diffuse reflectance

    // The rule itself, on any S (double, or a Dual whose partials are those of alpha and eta).
    static PlasticTablesT integrate(const S &alpha, const S &eta) {
        PlasticTablesT t;
        double e = scalar_value(eta);
        GLRule qt(e), qr(1 / e);
        S refl(0.0);
        for (int i = 0; i < kPlasticTableRes; ++i) {
            double mu = std::max(1e-6, double(i) / (kPlasticTableRes - 1));
            Vec3<double> w(std::sqrt(1 - mu * mu), 0, mu);
            t.T[i] = RoughInterfaceAlbedo(alpha, eta, w, true, qt);
            refl += RoughInterfaceAlbedo(alpha, 1.0 / eta, w, false, qr) * mu;
        }
        t.fdr = 2.0 * refl / double(kPlasticTableRes);
        return t;
    }

    // Kept in a small cache per (alpha, eta), so the float and double models of one Plastic (and
    // a fit's models at one point) share one integration: S = double takes the double rule's
    // values; a Dual S the rule on a 2-partial Dual (d/d alpha, d/d eta; its values are the
    // double rule's, bit for bit), chained to S's own partials.
    static PlasticTablesT build(const S &alpha, const S &eta);

    static double scalar_value(const S &x) {
        if constexpr (is_dual<S>::value) return x.v;
        else return x;
    }
};
using PlasticTablesD2 = PlasticTablesT<Dual<double, 2>>;

// The tables of (alpha, eta), with their partials in (alpha, eta) if `partials` (else those are 0).
inline PlasticTablesD2 PlasticTablesCached(double alpha, double eta, bool partials) {
    using D2 = Dual<double, 2>;
    struct Entry {
        double alpha, eta;
        bool partials;
        PlasticTablesD2 t;
    };
    static std::mutex lock;
    static std::vector<Entry> cache;  // the last few (alpha, eta), newest at the back
    {
        std::lock_guard<std::mutex> g(lock);
        for (const Entry &e : cache)
            if (e.alpha == alpha && e.eta == eta && (e.partials || !partials)) return e.t;
    }
    PlasticTablesD2 t;
    if (partials) {
        t = PlasticTablesD2::integrate(D2::variable(alpha, 0), D2::variable(eta, 1));
    } else {
        PlasticTablesT<double> v = PlasticTablesT<double>::integrate(alpha, eta);
        for (int i = 0; i < kPlasticTableRes; ++i) t.T[i] = D2(v.T[i]);
        t.fdr = D2(v.fdr);
    }
    std::lock_guard<std::mutex> g(lock);
    if (cache.size() >= 8) cache.erase(cache.begin());
    cache.push_back(Entry{alpha, eta, partials, t});
    return t;
}

template <typename S> PlasticTablesT<S> PlasticTablesT<S>::build(const S &alpha, const S &eta) {
    constexpr bool dual = is_dual<S>::value;
    PlasticTablesD2 t2 = PlasticTablesCached(scalar_value(alpha), scalar_value(eta), dual);
    auto take = [&](const Dual<double, 2> &x) {
        if constexpr (dual) {
            S r(x.v);
            for (int k = 0; k < S::Size; ++k) r.d[k] = x.d[0] * alpha.d[k] + x.d[1] * eta.d[k];
            return r;
        } else {
            return S(x.v);
        }
    };
    PlasticTablesT t;
    for (int i = 0; i < kPlasticTableRes; ++i) t.T[i] = take(t2.T[i]);
    t.fdr = take(t2.fdr);
    return t;
}
using PlasticTables = PlasticTablesT<>;

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
template <typename S = double> struct PlasticParamsT {
    std::array<S, 3> reflectance{S(0.5), S(0.5), S(0.5)};
    S eta = S(1.49);
    S alpha = S(0.0);
    bool nonlinear = false;
    Masking masking = Masking::Correlated;
    std::array<S, 3> specular_reflectance{S(1.0), S(1.0), S(1.0)};

    template <class V> void fields(V &&v) {
        v("reflectance", reflectance);
        v("eta", eta);
        v("alpha", alpha);
        v("nonlinear", nonlinear);
        v("masking", masking);
        v("specular_reflectance", specular_reflectance);
    }
};
using PlasticParams = PlasticParamsT<>;

template <typename F> struct PlasticBxDF {
    using Params = PlasticParamsT<param_t<F>>;
    using S = param_t<F>;
    static constexpr const char *Name = "Plastic";
    using Spectral = PlasticSpectral<F>;  // its spectral form (core/bxdf.h)
    static constexpr int GradColumns = 8;  // eval_grad columns at most

    Spectrum<F> Ks{F(1)};
    Spectrum<F> diffuse{F(0)};  // R / (1 - {Fdr | R Fdr}) / (pi eta^2), the base's constant factor
    Spectrum<F> diffuse_tt{F(0)}; // diffuse 4 eta^2: the factor of trans_halves' product (smooth f)
    F eta = 1.49;
    F inv_eta2 = F(1) / (F(1.49) * F(1.49));  // 1 / eta^2 as FrDielectricRatioScaledAbove rounds it
    bool dense = true;          // eta > 1: no total internal reflection for light from outside
    F spec_weight = 0.5;        // w = mean(Ks) / (mean(R) + mean(Ks))
    Microfacet<F> mfd;
    bool smooth = true;
    bool has_diffuse = true;
    F table[kPlasticTableRes] = {};  // rough: T(cos) at cos = i / 63 (cos floored at 1e-6)
    F slope[kPlasticTableRes] = {};  // table[i + 1] - table[i]; slope[63] = 0

    static bool is_rough(const Params &p) { return !(p.alpha < kSmoothAlpha); }
    // the alpha floor 1e-4 (a zero derivative below it; core/dual.h)
    static S coat_alpha(const Params &p) { return is_rough(p) ? (p.alpha < kMinAlpha ? S(kMinAlpha) : p.alpha) : S(0.0); }
    static PlasticTablesT<S> tables(const Params &p) {
        return is_rough(p) ? PlasticTablesT<S>::build(coat_alpha(p), p.eta) : PlasticTablesT<S>{};
    }
    static PlasticBxDF make(const Params &p) { return make(p, tables(p)); }

    // S = a Dual (the gradient models): every derived quantity below is computed in S, so the
    // derivatives in R, Ks, eta and alpha flow through Fdr, the tables and the 1/(pi eta^2) factor.
    static PlasticBxDF make(const Params &p, const PlasticTablesT<S> &tab) {
        PlasticBxDF m;
        m.eta = F(p.eta);
        m.inv_eta2 = F(1) / (m.eta * m.eta);
        m.dense = m.eta > F(1);
        m.smooth = !is_rough(p);
        S a = coat_alpha(p);
        m.mfd = Microfacet<F>(F(a), F(a), p.masking);
        for (int i = 0; i < kPlasticTableRes; ++i) m.table[i] = F(tab.T[i]);
        for (int i = 0; i + 1 < kPlasticTableRes; ++i) m.slope[i] = m.table[i + 1] - m.table[i];
        m.slope[kPlasticTableRes - 1] = F(0);
        S fdr = m.smooth ? FresnelDiffuseReflectanceT(S(1.0 / p.eta)) : tab.fdr;
        S rmean(0.0), smean(0.0);
        m.has_diffuse = false;
        for (int c = 0; c < 3; ++c) {
            S R = p.reflectance[c];
            set_base(m, c, R / (1.0 - (p.nonlinear ? S(R * fdr) : fdr)), p.eta);
            m.Ks[c] = F(p.specular_reflectance[c]);
            rmean += R / 3.0;
            smean += p.specular_reflectance[c] / 3.0;
            m.has_diffuse = m.has_diffuse || R > 0.0;
        }
        // both means 0 is a black material; any split will do
        m.spec_weight = F(rmean + smean > 0.0 ? S(smean / (rmean + smean)) : S(0.5));
        return m;
    }

    // The base's factors of channel c from scale = R / (1 - {Fdr | R Fdr}) (also the spectral
    // adapter's, batch_spectral.h): diffuse = scale / (pi eta^2) and diffuse_tt, its 4 eta^2 multiple.
    static void set_base(PlasticBxDF &m, int c, const S &scale, const S &eta) {
        m.diffuse[c] = F(scale * InvPi<double> / (eta * eta));
        m.diffuse_tt[c] = F(scale * (4.0 * InvPi<double>));
    }

    uint8_t flags() const {
        uint8_t spec = smooth ? SpecularReflection : GlossyReflection;
        return has_diffuse ? uint8_t(spec | DiffuseReflection) : spec;
    }

    // The model runs on packets in the batch kernels (batch.h): every method is written once on
    // the evaluation type V (F, or a packet of F; core/simd.h). `smooth` is a per-model switch
    // (a uniform branch, the same for every lane).
    static constexpr bool Vectorized = true;

    // Mitsuba's lerp_gather: linear interpolation of the table at cos in [0, 1], as the entry
    // plus the fraction times its slope (one index for both reads; cos = 1 reads entry 63 and its
    // slope 0). Lanes the caller masks out (cos < 0 or NaN) read some entry (lookup64x2: packets
    // read the tables by permutations, float64 too; core/math.h has the measurements).
    template <typename V> V transmittance(V cos) const {
        V x = cos * V(kPlasticTableRes - 1);
        V fi = floor(x), t, d;
        static_assert(kPlasticTableRes == 64, "lookup64x2 reads 64-entry tables");
        lookup64x2(table, slope, fi, &t, &d);
        return mul_add(x - fi, d, t);
    }

    // Lobe-choice weights of the coating (ps) and the base (pd) for the coating's reflectance
    // k = r / (r + t) at wo (Mitsuba's prob_specular: p = ps / (ps + pd)); both ps = 0, pd = 1
    // when both vanish (a black material), so that p = 0.
    template <typename V> void lobe_weights(V r, V t, V *ps, V *pd) const {
        V a = r * V(spec_weight), b = t * V(F(1) - spec_weight);
        // 0 < w < 1 (both lobes present): a + b >= min(w, 1 - w) (r + t) > 0 for every lane the
        // caller keeps (r, t >= 0, not both 0), so the selects below change nothing
        if (spec_weight > F(0) && spec_weight < F(1)) {
            *ps = a;
            *pd = b;
            return;
        }
        Mask<V> some = a + b > V(0);
        *ps = select(some, a, V(0));
        *pd = select(some, b, V(1));
    }

    // The transmitted cosine for light from outside at sin^2 = sin2 of the incident angle, as
    // FrDielectricRatioScaledAbove computes it (|h| = 1); where eta > 1 (dense) its radicand is at
    // least 1 - 1 / eta^2 > 0 for every lane (sin2 <= 1), so no clamp. 1 square root.
    template <typename V> V cos_t(V sin2) const {
        V x = neg_mul_add(sin2, V(inv_eta2), V(1));
        return dense ? sqrt(x) : safe_sqrt(x);
    }
    // The Fresnel numerators and denominator (R = r / den, T = t / den; FrDielectricRatioScaledAbove's
    // at |h| = 1) at a cosine c > 0 from outside with sin2 = 1 - c^2 (or a sample's own sin^2:
    // the transmitted root then does not wait for c's), through cos_t.
    template <typename V> void ratio_above(V c, V sin2, V *r, V *t, V *den) const {
        V a2, b2;
        FrDielectricNumerators(c, cos_t(sin2), V(eta), &a2, &b2, r, t, den);
    }
    // Smooth coating: the transmittance T = 1 - F at a cosine c > 0 from outside (sin2 = 1 - c^2)
    // as T = 2 eta tq / dq, tq = c cos_t (a^2 + b^2), dq = a^2 b^2: FrDielectricNumerators' t and den
    // without their constant factors 4 eta and 2, which diffuse_tt holds. Lanes with c <= 0 are
    // masked by the caller. 1 square root.
    template <typename V> void trans_halves(V c, V sin2, V *tq, V *dq) const {
        V ct = cos_t(sin2), a2, b2, r, t, den; // r, t, den are dead code here
        FrDielectricNumerators(c, ct, V(eta), &a2, &b2, &r, &t, &den);
        *tq = c * ct * (a2 + b2);
        *dq = a2 * b2;
    }

    // What the rough coating's f and pdf share at (o, i): the half vector h = o + i, never
    // normalized (wm = h / |h|; every term below is written in h), its |h|^4, 1 / D and Smith's roots.
    template <typename V> struct Coat {
        Mask<V> ok;      // the coating lobe is non-zero here (D > 0, o + i != 0)
        V c_oh;          // o.wm |h|
        V len2, l4;      // |h|^2, |h|^4
        V dd;            // D_denom(wm) |h|^4 (D_denom with len2)
        V root_o, root_i;
    };
    template <typename V> Coat<V> coat(const Vec3<V> &o, const Vec3<V> &i) const {
        Coat<V> c;
        c.ok = Mask<V>(true);
        Vec3<V> h = reflection_half_vector_h(o, i, c.ok, &c.len2);
        c.l4 = sqr(c.len2);
        c.dd = mfd.D_denom(h, c.ok, c.len2);
        c.c_oh = dot(o, h);
        c.root_o = mfd.smith_root(o);
        c.root_i = mfd.smith_root(i);
        return c;
    }

    // Rough coating, o and i upper: diffuse T(cos_o) T(cos_i) (table) + Ks D F G / (4 cos_o cos_i)
    // as Ks r / (den D_denom(wm) G_denom) = Ks r |h|^4 / (den D_denom(h) G_denom) (the Fresnel
    // numerator over its denominator, both in h: FrDielectricRatioScaled; core/microfacet.h):
    // 1 division.
    // active: the lanes to keep (others 0; the two lobes' scalars are masked before the channels).
    template <typename V>
    Spectrum<V> f_rough(const Vec3<V> &o, const Vec3<V> &i, V T_o, const Coat<V> &c, Mask<V> active) const {
        V r, t, den;
        FrDielectricRatioScaledAbove(c.c_oh, c.len2, eta, &r, &t, &den); // o.h > 0 where c.ok
        V coat_v = r * c.l4 / (den * c.dd * mfd.G_denom(o.z, i.z, c.root_o, c.root_i));
        V base = select(active, T_o * transmittance(i.z), V(0));
        Spectrum<V> v = to_lanes<V>(diffuse) * base, ks = to_lanes<V>(Ks);
        V coat = select(c.ok & active, coat_v, V(0));
        for (int k = 0; k < Spectrum<V>::Size; ++k) v[k] = mul_add(ks[k], coat, v[k]);
        return v;
    }

    // Rough coating, o and i upper: the mixture density (1 - p) cos_i / pi + p / (D_denom(wm)
    // 2 (cos_o + root_o)) (visible normals through the reflection Jacobian), p = ps / (ps + pd),
    // over one common denominator x = D_denom(h) 2 (cos_o + root_o) = D_denom(wm) 2 (...) |h|^4:
    // 1 division.
    template <typename V> V pdf_rough(const Vec3<V> &o, const Vec3<V> &i, V T_o, const Coat<V> &c) const {
        V ps, pd;
        lobe_weights(V(1) - T_o, T_o, &ps, &pd);
        V x = select(c.ok, c.dd * mfd.reflection_pdf_denom(o.z, c.root_o), V(1));
        ps = select(c.ok, ps, V(0));
        return mul_add(pd * CosineHemispherePDF(i.z), x, ps * c.l4) / ((ps + pd) * x);
    }

    // Two-sided: o, i mirrored into wo's hemisphere (the sign s applies to wi as well). f and pdf
    // flip only z (mirror_z): every term they take of x and y is even in the pair's common sign
    // (|h|^2, D_denom's squares, o.h, Smith's roots), so the values are those of the full flip,
    // bit for bit; the sampler flips all of wo (its azimuth matters) and maps wi back.
    // The flip is a sign change (mulsign_: an exclusive or on packets, no multiplier); lanes with
    // wo.z = +-0 (which mulsign_ may flip or not) are masked: o.z > 0 fails there.
    template <typename V> static Vec3<V> mirror_z(const Vec3<V> &w, V z) { return Vec3<V>(w.x, w.y, mulsign_(w.z, z)); }
    template <typename V> static Vec3<V> flip(const Vec3<V> &w, V z) {
        return Vec3<V>(mulsign_(w.x, z), mulsign_(w.y, z), mulsign_(w.z, z));
    }
    template <typename V> Spectrum<V> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode) const {
        Vec3<V> o = mirror_z(wo, wo.z), i = mirror_z(wi, wo.z);
        Mask<V> active = (o.z > V(0)) & (i.z > V(0));
        Spectrum<V> v;
        if (smooth) {
            // diffuse T(cos_o) T(cos_i) = diffuse_tt tq_o tq_i / (dq_o dq_i): 1 division
            V tq_o, dq_o, tq_i, dq_i;
            trans_halves(o.z, neg_mul_add(o.z, o.z, V(1)), &tq_o, &dq_o);
            trans_halves(i.z, neg_mul_add(i.z, i.z, V(1)), &tq_i, &dq_i);
            v = to_lanes<V>(diffuse_tt) * select(active, tq_o * tq_i / (dq_o * dq_i), V(0));
        } else {
            v = f_rough(o, i, transmittance(o.z), coat(o, i), active);
        }
        return v; // the inactive lanes' scalars were zeroed before the channels (diffuse, Ks finite)
    }

    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        Vec3<V> o = mirror_z(wo, wo.z), i = mirror_z(wi, wo.z);
        Mask<V> active = (o.z > V(0)) & (i.z > V(0)) & Mask<V>((sample_flags & RT_Reflection) != 0);
        V p;
        if (smooth) {
            // the base's share pd / (ps + pd) of the cosine lobe (F's denominator cancels)
            V ro, to, den_o, ps, pd;
            ratio_above(o.z, neg_mul_add(o.z, o.z, V(1)), &ro, &to, &den_o);
            lobe_weights(ro, to, &ps, &pd);
            p = pd * (V(1) / (ps + pd)) * CosineHemispherePDF(i.z);
        } else {
            p = pdf_rough(o, i, transmittance(o.z), coat(o, i));
        }
        return select(active, p, V(0));
    }

    template <typename V>
    BSDFSample<V> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode, uint8_t sample_flags) const {
        BSDFSample<V> r;
        // wo flipped whole into the upper hemisphere (flip: the sign of wo.z on each component), the
        // sample flipped back
        Vec3<V> o = flip(wo, wo.z);
        V sin2_d;
        Vec3<V> wd = SampleCosineHemisphere(u, &sin2_d);
        Vec3<V> i;
        Mask<V> spec;
        if (smooth) {
            // delta reflection: f = Ks F / cos, discrete probability p; else the cosine lobe
            V ro, to, den_o, ps, pd;
            ratio_above(o.z, neg_mul_add(o.z, o.z, V(1)), &ro, &to, &den_o);
            lobe_weights(ro, to, &ps, &pd);
            V inv = V(1) / (ps + pd);
            V p_spec = ps * inv;
            spec = uc < p_spec;
            Vec3<V> ws(-o.x, -o.y, o.z);
            i = select(spec, ws, wd);
            // f = Ks ro / (den_o cos) (the mirror) or diffuse to ti / (den_o den_i) (the base): the
            // chosen lobe's quotient in one division
            V ri, ti, den_i;
            ratio_above(wd.z, sin2_d, &ri, &ti, &den_i); // ri is dead code here
            V q = select(spec, ro, to * ti) / (den_o * select(spec, DeltaAbsCos(ws), den_i));
            r.f = select(spec, to_lanes<V>(Ks), to_lanes<V>(diffuse)) * q;
            // as pdf(): the base's share times the cosine density
            r.pdf = select(spec, p_spec, pd * inv * CosineHemispherePDF(wd.z));
            r.flags = select_flag<V>(spec, SpecularReflection, DiffuseReflection);
        } else {
            V T_o = transmittance(o.z), ps, pd;
            lobe_weights(V(1) - T_o, T_o, &ps, &pd);
            spec = uc < ps / (ps + pd);
            // the mirror direction about the sampled normal m, |m| != 1
            V m2;
            Vec3<V> m = SampleVisibleGGXMitsubaH(mfd.alpha_x, o, u, &m2);
            Vec3<V> ws = reflect_about_h(o, m, dot(o, m), m2);
            i = select(spec, ws, wd);
            Coat<V> c = coat(o, i);
            r.f = f_rough(o, i, T_o, c, Mask<V>(true));
            r.pdf = pdf_rough(o, i, T_o, c);
            r.flags = select_flag<V>(spec, GlossyReflection, DiffuseReflection);
        }
        r.wi = flip(i, wo.z);
        r.eta = V(1);
        r.valid = (o.z > V(0)) & (i.z > V(0)) & (r.pdf > V(0)) & Mask<V>((sample_flags & RT_Reflection) != 0);
        return r;
    }

    // The tables belong to alpha: regularization would need them rebuilt, so it is a no-op.
    void regularize() {}
};

} // namespace bsdfkit
