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
// Lobe choice as Mitsuba: specular with probability p = w k / (w k + (1 - w)(1 - k)), where
// k = F(cos_o) (smooth) or 1 - T(cos_o) (rough) and w = mean(Ks) / (mean(R) + mean(Ks)).
// The rough specular lobe is sampled with Mitsuba's visible-normal warp (sample_visible_11,
// concentric-disk variant) so that samples coincide with Mitsuba's for the same uniforms.
#pragma once
#include <array>
#include <cstdint>

#include "../core/bsdf_sample.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"

namespace bsdfkit {

// Mitsuba's MI_ROUGH_TRANSMITTANCE_RES: cosines at which the rough transmittance is tabulated.
inline constexpr int kPlasticTableRes = 64;

// Mitsuba's fresnel_diffuse_reflectance(eta): hemispherical average of F for light arriving
// from the side of relative IOR eta. eta < 1: Egan & Hilgeman 1973 fit; otherwise the
// polynomial in 1/eta of d'Eon & Irving 2011.
inline double FresnelDiffuseReflectance(double eta) {
    double ie = 1.0 / eta;
    if (eta < 1.0) return 0.0636 * ie + eta * (eta * -1.4399 + 0.7099) + 0.6681;
    return 0.919317 + ie * (-3.4793 + ie * (6.75335 + ie * (-7.80989 + ie * (4.98554 + ie * -1.36881))));
}

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
template <typename F> inline Vec3<F> SampleVisibleGGXMitsuba(F alpha, const Vec3<F> &wo, Point2<F> u) {
    Vec3<F> wp = normalize(Vec3<F>(alpha * wo.x, alpha * wo.y, wo.z));
    F sin2 = F(1) - wp.z * wp.z, inv_sin = F(1) / std::sqrt(sin2 > F(0) ? sin2 : F(1));
    bool pole = std::abs(sin2) <= F(2) * std::numeric_limits<F>::epsilon();
    F cos_phi = pole ? F(1) : clamp(wp.x * inv_sin, F(-1), F(1));
    F sin_phi = pole ? F(0) : clamp(wp.y * inv_sin, F(-1), F(1));
    F cos_t = wp.z, sin_t = safe_sqrt(F(1) - cos_t * cos_t);
    // Heitz & d'Eon 2014 slope sampling, Mitsuba's "simpler and exact" disk variant
    Point2<F> p = SampleUniformDiskConcentric(u);
    F s = F(0.5) * (F(1) + cos_t);
    p.y = lerp(s, safe_sqrt(F(1) - p.x * p.x), p.y);
    F pz = safe_sqrt(F(1) - p.x * p.x - p.y * p.y);
    F norm = F(1) / (sin_t * p.y + cos_t * pz);
    F sx = (cos_t * p.y - sin_t * pz) * norm, sy = p.x * norm;
    F mx = (cos_phi * sx - sin_phi * sy) * alpha, my = (sin_phi * sx + cos_phi * sy) * alpha;
    return normalize(Vec3<F>(-mx, -my, F(1)));
}

// Smith G1 of GGX with Mitsuba's back-facing rule (0 when v.m and v.z differ in sign).
inline double SmithG1Mitsuba(double alpha, const Vec3<double> &v, const Vec3<double> &m) {
    double xy = sqr(alpha * v.x) + sqr(alpha * v.y);
    double g = xy == 0 ? 1.0 : 2.0 / (1.0 + std::sqrt(1.0 + xy / sqr(v.z)));
    return dot(v, m) * v.z <= 0 ? 0.0 : g;
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
inline double RoughInterfaceAlbedo(double alpha, double eta, const Vec3<double> &w, bool refract, const GLRule &q) {
    double sum = 0;
    for (int a = 0; a < q.n; ++a)
        for (int b = 0; b < q.n; ++b) {
            Point2<double> u{0.5 * q.x[b] + 0.5, 0.5 * q.x[a] + 0.5};
            Vec3<double> m = SampleVisibleGGXMitsuba(alpha, w, u);
            double c = dot(w, m), Fr = FrDielectric(c, eta), v;
            if (refract) {
                // Snell: the refracted direction through m (c > 0 here: visible normals)
                double cos_t = -safe_sqrt(1 - (1 - c * c) / sqr(eta));
                Vec3<double> wt_dir = m * (c / eta + cos_t) - w / eta;
                v = wt_dir.z * w.z >= 0 ? 0.0 : SmithG1Mitsuba(alpha, wt_dir, m) * (1 - Fr);
            } else {
                Vec3<double> wr = Reflect(w, m);
                v = (wr.z <= 0 || w.z <= 0) ? 0.0 : SmithG1Mitsuba(alpha, wr, m) * Fr;
            }
            sum += v * q.w[a] * q.w[b] * 0.25;
        }
    return sum;
}

// The rough coating's tables (Mitsuba roughplastic::parameters_changed), built once per
// (alpha, eta) in double and shared by the float and double models.
struct PlasticTables {
    double T[kPlasticTableRes] = {};  // external transmittance at cos = max(1e-6, i / 63)
    double fdr = 0;                   // internal diffuse reflectance

    static PlasticTables build(double alpha, double eta) {
        PlasticTables t;
        GLRule qt(eta), qr(1 / eta);
        double refl = 0;
        for (int i = 0; i < kPlasticTableRes; ++i) {
            double mu = std::max(1e-6, double(i) / (kPlasticTableRes - 1));
            Vec3<double> w(std::sqrt(1 - mu * mu), 0, mu);
            t.T[i] = RoughInterfaceAlbedo(alpha, eta, w, true, qt);
            refl += RoughInterfaceAlbedo(alpha, 1 / eta, w, false, qr) * mu;
        }
        t.fdr = 2 * refl / kPlasticTableRes;
        return t;
    }
};

struct PlasticParams {
    std::array<double, 3> reflectance{0.5, 0.5, 0.5};
    double eta = 1.49;
    double alpha = 0;
    bool nonlinear = false;
    Masking masking = Masking::Correlated;
    std::array<double, 3> specular_reflectance{1, 1, 1};

    template <class V> void fields(V &&v) {
        v("reflectance", reflectance);
        v("eta", eta);
        v("alpha", alpha);
        v("nonlinear", nonlinear);
        v("masking", masking);
        v("specular_reflectance", specular_reflectance);
    }
};

template <typename F> struct PlasticBxDF {
    using Params = PlasticParams;
    static constexpr const char *Name = "Plastic";

    Spectrum<F> Ks{F(1)};
    Spectrum<F> diffuse{F(0)};  // R / (1 - {Fdr | R Fdr}) / (pi eta^2), the base's constant factor
    F eta = 1.49;
    F spec_weight = 0.5;        // w = mean(Ks) / (mean(R) + mean(Ks))
    TrowbridgeReitz<F> mfd;
    bool smooth = true;
    bool has_diffuse = true;
    F table[kPlasticTableRes] = {};  // rough: T(cos) at cos = i / 63 (cos floored at 1e-6)

    static bool is_rough(const Params &p) { return !(p.alpha < kSmoothAlpha); }
    static double coat_alpha(const Params &p) { return is_rough(p) ? std::max(p.alpha, kMinAlpha) : 0.0; }
    static PlasticTables tables(const Params &p) {
        return is_rough(p) ? PlasticTables::build(coat_alpha(p), p.eta) : PlasticTables{};
    }
    static PlasticBxDF make(const Params &p) { return make(p, tables(p)); }

    static PlasticBxDF make(const Params &p, const PlasticTables &tab) {
        PlasticBxDF m;
        m.eta = F(p.eta);
        m.smooth = !is_rough(p);
        double a = coat_alpha(p);
        m.mfd = TrowbridgeReitz<F>(F(a), F(a), p.masking);
        for (int i = 0; i < kPlasticTableRes; ++i) m.table[i] = F(tab.T[i]);
        double fdr = m.smooth ? FresnelDiffuseReflectance(1 / p.eta) : tab.fdr;
        double rmean = 0, smean = 0;
        m.has_diffuse = false;
        for (int c = 0; c < 3; ++c) {
            double R = p.reflectance[c];
            double scale = R / (1 - (p.nonlinear ? R * fdr : fdr));
            m.diffuse[c] = F(scale * InvPi<double> / (p.eta * p.eta));
            m.Ks[c] = F(p.specular_reflectance[c]);
            rmean += R / 3;
            smean += p.specular_reflectance[c] / 3;
            m.has_diffuse = m.has_diffuse || R > 0;
        }
        // both means 0 is a black material; any split will do
        m.spec_weight = F(rmean + smean > 0 ? smean / (rmean + smean) : 0.5);
        return m;
    }

    uint8_t flags() const {
        uint8_t spec = smooth ? SpecularReflection : GlossyReflection;
        return has_diffuse ? uint8_t(spec | DiffuseReflection) : spec;
    }

    // Mitsuba's lerp_gather: linear interpolation of the table at cos in [0, 1].
    F transmittance(F cos) const {
        F x = cos * F(kPlasticTableRes - 1);
        F fi = min_(std::floor(x), F(kPlasticTableRes - 2));
        int i = int(fi);
        return lerp(x - fi, table[i], table[i + 1]);
    }
    // Coating transmittance T(cos) of the outside direction.
    F coat_T(F cos) const { return smooth ? F(1) - FrDielectric(cos, eta) : transmittance(cos); }

    // Probability of picking the coating's lobe for wo (Mitsuba's prob_specular).
    F prob_specular(F k) const {
        F ps = k * spec_weight, pd = (F(1) - k) * (F(1) - spec_weight);
        F sum = ps + pd;
        return sum > F(0) ? ps / sum : F(0);
    }

    // Rough coating: Torrance-Sparrow reflection D F G / (4 cos_o cos_i) (o, i upper).
    Spectrum<F> f_coat(const Vec3<F> &o, const Vec3<F> &i) const {
        Vec3<F> wh = normalize(o + i);
        F val = mfd.D(wh) * FrDielectric(dot(o, wh), eta) * mfd.G(o, i) / (F(4) * o.z * i.z);
        return Ks * val;
    }

    // Density of the mixture for o, i in the upper hemisphere (rough: both lobes).
    F pdf_upper(const Vec3<F> &o, const Vec3<F> &i, F T_o) const {
        F p_spec = prob_specular(F(1) - T_o);
        F p = (F(1) - p_spec) * CosineHemispherePDF(i.z);
        if (!smooth) {
            Vec3<F> wh = normalize(o + i);
            p += p_spec * mfd.PDF(o, wh) / (F(4) * dot(o, wh));
        }
        return p;
    }

    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const {
        F s = wo.z < F(0) ? F(-1) : F(1);  // two-sided: mirror both into wo's hemisphere
        Vec3<F> o = wo * s, i = wi * s;
        bool active = (o.z > F(0)) & (i.z > F(0));
        F T_o = coat_T(o.z), T_i = coat_T(i.z);
        Spectrum<F> v = diffuse * (T_o * T_i);
        if (!smooth) v = v + f_coat(o, i);
        return select(active, v, Spectrum<F>(F(0)));
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        F s = wo.z < F(0) ? F(-1) : F(1);
        Vec3<F> o = wo * s, i = wi * s;
        bool active = (o.z > F(0)) & (i.z > F(0)) & ((sample_flags & RT_Reflection) != 0);
        F p = pdf_upper(o, i, coat_T(o.z));
        return active ? p : F(0);
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        BSDFSample<F> r;
        F s = wo.z < F(0) ? F(-1) : F(1);
        Vec3<F> o = wo * s;
        F T_o = coat_T(o.z);
        F p_spec = prob_specular(F(1) - T_o);
        bool spec = uc < p_spec;
        Vec3<F> wd = SampleCosineHemisphere(u);
        Vec3<F> i;
        if (smooth) {
            // delta reflection: f = Ks F / cos, discrete probability p_spec
            Vec3<F> ws(-o.x, -o.y, o.z);
            i = spec ? ws : wd;
            F cos_s = DeltaAbsCos(ws);
            Spectrum<F> fs = Ks * ((F(1) - T_o) / cos_s);
            Spectrum<F> fd = diffuse * (T_o * coat_T(wd.z));
            r.f = select(spec, fs, fd);
            r.pdf = spec ? p_spec : (F(1) - p_spec) * CosineHemispherePDF(wd.z);
            r.flags = spec ? uint8_t(SpecularReflection) : uint8_t(DiffuseReflection);
        } else {
            Vec3<F> ws = Reflect(o, SampleVisibleGGXMitsuba(mfd.alpha_x, o, u));
            i = spec ? ws : wd;
            r.f = f(o, i, mode);
            r.pdf = pdf_upper(o, i, T_o);
            r.flags = spec ? uint8_t(GlossyReflection) : uint8_t(DiffuseReflection);
        }
        r.wi = i * s;
        r.eta = F(1);
        r.valid = (o.z > F(0)) & (i.z > F(0)) & (r.pdf > F(0)) & ((sample_flags & RT_Reflection) != 0);
        return r;
    }

    // The tables belong to alpha: regularization would need them rebuilt, so it is a no-op.
    void regularize() {}
};

} // namespace bsdfkit
