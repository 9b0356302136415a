// Hair fibre scattering of Chiang, Bitterli, Tappan & Burley 2016, "A Practical and Controllable
// Hair and Fur Model for Production Path Tracing", as pbrt-v4 implements it (HairBxDF), after
// d'Eon et al. 2011 (Mp) and Marschner et al. 2003 (R, TT, TRT lobes).
//   h        offset across the fibre in [-1, 1] (where the ray from wo hits the cylinder)
//   eta      IOR of the fibre interior (>= 1; 1.55 for keratin)
//   sigma_a  absorption coefficient per RGB channel, per unit fibre *radius* (>= 0)
//   beta_m   longitudinal roughness in (0, 1]; beta_n azimuthal roughness in (0, 1]
//   alpha    cuticle scale tilt in degrees
// Frame (pbrt-v4): x is the fibre axis (sin theta = w.x), y and z span the normal plane with
// phi = atan2(w.z, w.y); z is the normal of the ribbon the curve is rendered as (the surface
// "normal" of the batch kernels; it only matters through f's division by |wi.z|).
// f is defined over the whole sphere: f = sum_p Mp Ap Np / |cos wi.z| (pbrt-v4 divides by the
// shading cosine so a renderer's |cos| cancels), p = 0 (R), 1 (TT), 2 (TRT), and one lobe for
// p >= 3 with uniform azimuth. TransportMode is ignored (pbrt-v4). The p loop has fixed length 4.
#pragma once
#include <array>

#include "../core/bsdf_sample.h"
#include "../core/fresnel.h"
#include "../core/frame.h"

namespace bsdfkit {

namespace hair {

inline constexpr int PMax = 3;

// Modified Bessel function of the first kind, order 0: sum_{i<10} x^{2i} / (4^i (i!)^2) (pbrt-v4 I0).
template <typename F> inline F I0(F x) {
    F x2 = x * x, val = F(0), term = F(1);
    for (int i = 0; i < 10; ++i) {
        val += term;
        term *= x2 / F(4 * (i + 1) * (i + 1));
    }
    return val;
}

// log I0(x); for x > 12 the asymptotic x + (ln(1/x) - ln(2 pi) + 1/(8x)) / 2 (pbrt-v4 LogI0).
template <typename F> inline F LogI0(F x) {
    F xs = min_(x, F(12)), xl = max_(x, F(12));
    F small = std::log(I0(xs));
    F large = xl + F(0.5) * (-std::log(F(2) * Pi<F> * xl) + F(1) / (F(8) * xl));
    return x > F(12) ? large : small;
}

// Longitudinal scattering of d'Eon et al. 2011, eq. 7, in log space (pbrt-v4 Mp):
// Mp = exp(LogI0(cos_i cos_o / v) - sin_i sin_o / v + log_norm), with log_norm = -ln(2 v sinh(1/v))
// for v > 0.1 and pbrt-v4's -1/v + 0.6931 + ln(1/(2v)) for v <= 0.1 (no overflow for small v).
template <typename F> inline F Mp(F cos_i, F cos_o, F sin_i, F sin_o, F inv_v, F log_norm) {
    F a = cos_i * cos_o * inv_v, b = sin_i * sin_o * inv_v;
    return std::exp(LogI0(a) - b + log_norm);
}

// Attenuation of each lobe (Marschner 2003 sec. 4.3; pbrt-v4 Ap): A0 = f, A1 = (1-f)^2 T,
// A2 = A1 T f, A3 = A2 f T / (1 - T f) (the geometric series of all p >= 3).
template <typename F>
inline void Ap(F cos_theta_o, F eta, F cos_gamma_o, const Spectrum<F> &T, Spectrum<F> ap[PMax + 1]) {
    F f = FrDielectric(cos_theta_o * cos_gamma_o, eta);
    ap[0] = Spectrum<F>(f);
    ap[1] = T * sqr(F(1) - f);
    ap[2] = ap[1] * T * f;
    for (int c = 0; c < Spectrum<F>::Size; ++c) {
        F den = F(1) - T[c] * f;
        ap[3][c] = den > F(0) ? ap[2][c] * f * T[c] / den : F(0);
    }
}

// Azimuth of the perfect (smooth) p-bounce path, Phi(p) = 2 p gamma_t - 2 gamma_o + p pi (pbrt-v4 Phi).
template <typename F> inline F Phi(int p, F gamma_o, F gamma_t) {
    return F(2 * p) * gamma_t - F(2) * gamma_o + F(p) * Pi<F>;
}

// Logistic density of scale s (Chiang 2016 eq. 10), symmetric.
template <typename F> inline F Logistic(F x, F s) {
    F e = std::exp(-std::abs(x) / s);
    return e / (s * sqr(F(1) + e));
}
template <typename F> inline F LogisticCDF(F x, F s) { return F(1) / (F(1) + std::exp(-x / s)); }

// Wrap an angle into [-pi, pi].
template <typename F> inline F WrapPi(F x) {
    return x - F(2) * Pi<F> * std::floor((x + Pi<F>) * Inv2Pi<F>);
}

// Trimmed logistic on [-pi, pi] (Chiang 2016 eq. 11): Logistic / (CDF(pi) - CDF(-pi)).
template <typename F> inline F Np(F dphi, int p, F s, F inv_trim, F gamma_o, F gamma_t) {
    return Logistic(WrapPi(dphi - Phi(p, gamma_o, gamma_t)), s) * inv_trim;
}

// Inverse CDF of the trimmed logistic on [-pi, pi] (pbrt-v4 SampleTrimmedLogistic).
template <typename F> inline F SampleTrimmedLogistic(F u, F s, F cdf_lo, F cdf_hi) {
    u = lerp(u, cdf_lo, cdf_hi);
    F x = -s * std::log(F(1) / u - F(1));
    return clamp(x, -Pi<F>, Pi<F>);
}

} // namespace hair

struct HairParams {
    double h = 0.0, eta = 1.55, beta_m = 0.3, beta_n = 0.3, alpha = 2.0;
    std::array<double, 3> sigma_a{0.0, 0.0, 0.0};
    template <class V> void fields(V &&v) {
        v("sigma_a", sigma_a); v("eta", eta); v("beta_m", beta_m); v("beta_n", beta_n);
        v("alpha", alpha); v("h", h);
    }
};

// The far-field fibre has no offset h (it integrates over it); `nodes` is the order of its
// Gauss-Legendre rule in gamma = asin h (1 .. HairFarFieldBxDF::MaxNodes; an accuracy knob).
struct HairFarFieldParams {
    double eta = 1.55, beta_m = 0.3, beta_n = 0.3, alpha = 2.0;
    std::array<double, 3> sigma_a{0.0, 0.0, 0.0};
    int nodes = 64;  // accurate default (bench/HAIR.md: 16 nodes miss 17 % of the peak at beta_n = 0.3); simplify lowers it
    template <class V> void fields(V &&v) {
        v("sigma_a", sigma_a); v("eta", eta); v("beta_m", beta_m); v("beta_n", beta_n);
        v("alpha", alpha); v("nodes", nodes);
    }
};

namespace hair {
// Gauss-Legendre nodes x and weights w of order n on [-1, 1]: Newton's iteration on the Legendre
// recurrence (n P_n = (2n - 1) x P_{n-1} - (n - 1) P_{n-2}) from Tricomi's initial guess
// cos(pi (i + 3/4) / (n + 1/2)); w = 2 / ((1 - x^2) P_n'(x)^2) (Abramowitz & Stegun 25.4.29).
inline void GaussLegendre(int n, double *x, double *w) {
    for (int i = 0; i < n; ++i) {
        double z = std::cos(3.14159265358979323846 * (i + 0.75) / (n + 0.5)), dp = 1;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1, p1 = 0;
            for (int j = 1; j <= n; ++j) {
                double p2 = p1;
                p1 = p0;
                p0 = ((2 * j - 1) * z * p1 - (j - 1) * p2) / j;
            }
            dp = n * (z * p0 - p1) / (z * z - 1);
            double dz = p0 / dp;
            z -= dz;
            if (std::abs(dz) < 1e-15) break;
        }
        x[i] = z;
        w[i] = 2 / ((1 - z * z) * dp * dp);
    }
}
} // namespace hair

template <typename F> struct HairBxDF {
    using Params = HairParams;
    static constexpr const char *Name = "Hair";
    static constexpr int P = hair::PMax;

    // All derived at construction (in double).
    F h, eta, eta2, gamma_o, cos_gamma_o;
    Spectrum<F> two_sigma_a;          // 2 sigma_a (the path length is 2 cos gamma_t / cos theta_t)
    F inv_v[P + 1], log_norm[P + 1];  // Mp per lobe
    F v[P + 1], exp_m2_over_v[P + 1]; // Mp sampling: cos = 1 + v ln(u + (1-u) e^{-2/v})
    F s, inv_trim, cdf_lo, cdf_hi;    // trimmed logistic
    F sin_tilt[P + 1], cos_tilt[P + 1];  // theta_o rotation per lobe: -2 alpha, alpha, 4 alpha, 0

    static HairBxDF make(const Params &p) {
        HairBxDF m;
        m.set_h(p.h);
        m.eta = F(p.eta);
        m.eta2 = F(p.eta * p.eta);
        for (int c = 0; c < 3; ++c) m.two_sigma_a[c] = F(2 * p.sigma_a[c]);
        // Longitudinal variance (Chiang 2016 eq. 7; pbrt-v4): v0, v0 / 4, 4 v0, 4 v0
        double b = p.beta_m;
        double v0 = sqr(0.726 * b + 0.812 * b * b + 3.7 * std::pow(b, 20));
        double vs[P + 1] = {v0, 0.25 * v0, 4 * v0, 4 * v0};
        for (int i = 0; i <= P; ++i) {
            double vi = vs[i];
            m.v[i] = F(vi);
            m.inv_v[i] = F(1 / vi);
            m.log_norm[i] = F(vi <= 0.1 ? -1 / vi + 0.6931 + std::log(1 / (2 * vi))
                                        : -std::log(2 * vi * std::sinh(1 / vi)));
            m.exp_m2_over_v[i] = F(std::exp(-2 / vi));
        }
        // Azimuthal logistic scale (Chiang 2016 eq. 8)
        double bn = p.beta_n;
        double s = std::sqrt(3.14159265358979323846 / 8) * (0.265 * bn + 1.194 * bn * bn + 5.372 * std::pow(bn, 22));
        double pi = 3.14159265358979323846;
        double lo = 1 / (1 + std::exp(pi / s)), hi = 1 / (1 + std::exp(-pi / s));
        m.s = F(s);
        m.cdf_lo = F(lo);
        m.cdf_hi = F(hi);
        m.inv_trim = F(1 / (hi - lo));
        // Cuticle tilt (Marschner 2003; pbrt-v4 sin2kAlpha by double-angle steps): R is shifted by
        // -2 alpha, TT by alpha, TRT by 4 alpha.
        double s1 = std::sin(p.alpha * pi / 180), c1 = std::sqrt(std::max(0.0, 1 - s1 * s1));
        double s2 = 2 * c1 * s1, c2 = c1 * c1 - s1 * s1;
        double s4 = 2 * c2 * s2, c4 = c2 * c2 - s2 * s2;
        double st[P + 1] = {-s2, s1, s4, 0.0}, ct[P + 1] = {c2, c1, c4, 1.0};
        for (int i = 0; i <= P; ++i) {
            m.sin_tilt[i] = F(st[i]);
            m.cos_tilt[i] = F(ct[i]);
        }
        return m;
    }

    // The same fibre seen at offset h (the preview renderer sets h per curve hit): h, gamma_o = asin h
    // and cos gamma_o are the only members that depend on it.
    void set_h(double hh) {
        hh = clamp(hh, -1.0, 1.0);
        h = F(hh);
        gamma_o = F(std::asin(hh));
        cos_gamma_o = F(std::sqrt(std::max(0.0, 1.0 - hh * hh)));
    }

    uint8_t flags() const { return GlossyReflection; }

    // Refraction geometry of wo (pbrt-v4 HairBxDF::f): gamma_t and the transmittance of one pass.
    void refracted(F sin_o, F cos_o, F *gamma_t, Spectrum<F> *T) const {
        F sin_t = sin_o / eta;
        F cos_t = safe_sqrt(F(1) - sin_t * sin_t);
        // sin gamma_t = h / eta', eta' = sqrt(eta^2 - sin^2 theta_o) / cos theta_o (Bravais index)
        F den = safe_sqrt(eta2 - sin_o * sin_o);
        F sin_gt = den > F(0) ? clamp(h * cos_o / den, F(-1), F(1)) : F(0);
        F cos_gt = safe_sqrt(F(1) - sin_gt * sin_gt);
        *gamma_t = std::asin(sin_gt);
        // T = exp(-sigma_a 2 cos gamma_t / cos theta_t); cos theta_t > 0 unless eta == 1 at grazing
        F len = cos_gt / max_(cos_t, F(1e-30));
        for (int c = 0; c < Spectrum<F>::Size; ++c) (*T)[c] = std::exp(-two_sigma_a[c] * len);
    }

    // theta_o rotated by the lobe's cuticle tilt; cos is taken as |cos| (pbrt-v4).
    void tilted(int p, F sin_o, F cos_o, F *sin_p, F *cos_p) const {
        *sin_p = sin_o * cos_tilt[p] + cos_o * sin_tilt[p];
        *cos_p = std::abs(cos_o * cos_tilt[p] - sin_o * sin_tilt[p]);
    }

    // Everything that depends on wo alone: theta_o, gamma_t, Ap and the lobe weights.
    struct Outgoing {
        F sin_o, cos_o, gamma_t;
        Spectrum<F> ap[P + 1];
        F w[P + 1];
    };
    Outgoing outgoing(const Vec3<F> &wo) const {
        Outgoing o;
        o.sin_o = wo.x;
        o.cos_o = safe_sqrt(F(1) - o.sin_o * o.sin_o);
        Spectrum<F> T;
        refracted(o.sin_o, o.cos_o, &o.gamma_t, &T);
        hair::Ap(o.cos_o, eta, cos_gamma_o, T, o.ap);
        weights(o.ap, o.w);
        return o;
    }

    // Mp Np of every lobe for wi at azimuth difference dphi (the p >= 3 lobe: Mp / (2 pi)).
    void lobes(const Outgoing &o, const Vec3<F> &wi, F dphi, F mn[P + 1]) const {
        F sin_i = wi.x, cos_i = safe_sqrt(F(1) - sin_i * sin_i);
        for (int p = 0; p < P; ++p) {
            F sp, cp;
            tilted(p, o.sin_o, o.cos_o, &sp, &cp);
            mn[p] = hair::Mp(cos_i, cp, sin_i, sp, inv_v[p], log_norm[p]) *
                    hair::Np(dphi, p, s, inv_trim, gamma_o, o.gamma_t);
        }
        mn[P] = hair::Mp(cos_i, o.cos_o, sin_i, o.sin_o, inv_v[P], log_norm[P]) * Inv2Pi<F>;
    }

    // Lobe-selection probabilities: spectral averages of Ap, normalised (pbrt-v4 ApPDF).
    static void weights(const Spectrum<F> ap[P + 1], F w[P + 1]) {
        F sum = F(0);
        for (int p = 0; p <= P; ++p) sum += (w[p] = ap[p].average());
        F inv = sum > F(0) ? F(1) / sum : F(0);
        for (int p = 0; p <= P; ++p) w[p] *= inv;
    }

    // phi_i - phi_o from the (y, z) components: one atan2, in [-pi, pi] (pbrt-v4 takes two
    // atan2 and subtracts; Np wraps, so the values agree).
    static F delta_phi(const Vec3<F> &wo, const Vec3<F> &wi) {
        return std::atan2(wo.y * wi.z - wo.z * wi.y, wo.y * wi.y + wo.z * wi.z);
    }

    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const {
        Outgoing o = outgoing(wo);
        F mn[P + 1];
        lobes(o, wi, delta_phi(wo, wi), mn);
        Spectrum<F> sum = o.ap[0] * mn[0];
        for (int p = 1; p <= P; ++p) sum = sum + o.ap[p] * mn[p];
        // divide by |cos theta_i| of the shading frame where it is not 0 (pbrt-v4)
        F c = AbsCosTheta(wi);
        return sum * (c > F(0) ? F(1) / c : F(1));
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        Outgoing o = outgoing(wo);
        F mn[P + 1];
        lobes(o, wi, delta_phi(wo, wi), mn);
        F sum = F(0);
        for (int p = 0; p <= P; ++p) sum += o.w[p] * mn[p];
        // pbrt-v4's PDF ignores sample_flags; here it is 0 when reflection is excluded, as sample_f is.
        return keep_or_zero(sum, (sample_flags & RT_Reflection) != 0);
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode, uint8_t sample_flags) const {
        Outgoing o = outgoing(wo);
        const F *w = o.w;
        F sin_o = o.sin_o, cos_o = o.cos_o, gamma_t = o.gamma_t;
        // Choose the lobe p with probability w[p] and remap uc (pbrt-v4 SampleDiscrete).
        F c0 = w[0], c1 = c0 + w[1], c2 = c1 + w[2];
        int p = int(uc >= c0) + int(uc >= c1) + int(uc >= c2);
        F start = p == 0 ? F(0) : (p == 1 ? c0 : (p == 2 ? c1 : c2));
        F wp = p == 0 ? w[0] : (p == 1 ? w[1] : (p == 2 ? w[2] : w[3]));
        F ur = min_((uc - start) / max_(wp, std::numeric_limits<F>::min()), F(1) - std::numeric_limits<F>::epsilon() / 2);
        ur = max_(ur, F(0));
        F sp, cp;
        tilted(p, sin_o, cos_o, &sp, &cp);
        // Sample Mp (d'Eon 2011; pbrt-v4): cos = 1 + v ln(u0 + (1 - u0) e^{-2/v}), u0 >= 1e-5
        F vp = v[p];
        F cos_t = F(1) + vp * std::log(max_(u.x, F(1e-5)) + (F(1) - u.x) * exp_m2_over_v[p]);
        F sin_t = safe_sqrt(F(1) - cos_t * cos_t);
        F sphi, cphi;
        sincos_(F(2) * Pi<F> * u.y, &sphi, &cphi);
        F sin_i = -cos_t * sp + sin_t * cphi * cp;
        F cos_i = safe_sqrt(F(1) - sin_i * sin_i);
        // Sample Np: dphi = Phi(p) + trimmed logistic, or uniform for p >= 3
        F dphi_lobe = hair::Phi(p, gamma_o, gamma_t) + hair::SampleTrimmedLogistic(ur, s, cdf_lo, cdf_hi);
        F dphi = p < P ? dphi_lobe : F(2) * Pi<F> * ur;
        F sd, cd;
        sincos_(dphi, &sd, &cd);
        // rotate wo's azimuth (cos phi_o, sin phi_o) = (y, z) / r by dphi; phi_o = 0 on the axis
        F r2 = wo.y * wo.y + wo.z * wo.z;
        bool on_axis = !(r2 > F(0));
        F inv_r = F(1) / std::sqrt(on_axis ? F(1) : r2);
        F cpo = on_axis ? F(1) : wo.y * inv_r, spo = on_axis ? F(0) : wo.z * inv_r;
        Vec3<F> wi(sin_i, cos_i * (cpo * cd - spo * sd), cos_i * (spo * cd + cpo * sd));
        // f and the full mixture density (pbrt-v4), so sample_f agrees with f and pdf.
        F mn[P + 1];
        lobes(o, wi, dphi, mn);
        Spectrum<F> fsum = o.ap[0] * mn[0];
        F pdf = w[0] * mn[0];
        for (int q = 1; q <= P; ++q) {
            fsum = fsum + o.ap[q] * mn[q];
            pdf += w[q] * mn[q];
        }
        F c = AbsCosTheta(wi);
        BSDFSample<F> out;
        out.wi = wi;
        out.f = fsum * (c > F(0) ? F(1) / c : F(1));
        out.pdf = pdf;
        out.flags = GlossyReflection;
        out.valid = ((sample_flags & RT_Reflection) != 0) & (pdf > F(0));
        return out;
    }

    void regularize() {}
};

// The far-field fibre: HairBxDF averaged over the offset h in [-1, 1] (a fibre seen whole, thinner
// than a pixel). (1/2) int f(h) dh is integrated in gamma = asin h, where the integrand is smooth:
// h = sin gamma, dh = cos gamma dgamma, by Gauss-Legendre with `nodes` points on (-pi/2, pi/2)
// (weights normalised to sum 1). Sampling picks node k with its weight, then samples HairBxDF(h_k);
// pdf is the same mixture, so sample_f, f and pdf agree exactly. Cost: `nodes` times HairBxDF. The
// nodes share every member of HairBxDF but h, gamma_o and cos gamma_o (HairBxDF::set_h).
template <typename F> struct HairFarFieldBxDF {
    static constexpr int MaxNodes = 64;
    static constexpr const char *Name = "HairFarField";
    using Params = HairFarFieldParams;
    HairBxDF<F> base;
    int n = 16;
    F node_h[MaxNodes], node_gamma[MaxNodes], node_cos_gamma[MaxNodes], weight[MaxNodes], cdf[MaxNodes];

    static HairFarFieldBxDF make(const Params &p) {
        HairFarFieldBxDF m;
        m.n = clamp(p.nodes, 1, MaxNodes);
        HairParams q;
        q.sigma_a = p.sigma_a;
        q.eta = p.eta;
        q.beta_m = p.beta_m;
        q.beta_n = p.beta_n;
        q.alpha = p.alpha;
        q.h = 0.0;
        m.base = HairBxDF<F>::make(q);
        double x[MaxNodes], w[MaxNodes], wk[MaxNodes], wsum = 0;
        hair::GaussLegendre(m.n, x, w);
        for (int k = 0; k < m.n; ++k) {
            double gamma = x[k] * 1.5707963267948966;
            HairBxDF<F> b = m.base;
            b.set_h(std::sin(gamma));
            m.node_h[k] = b.h;
            m.node_gamma[k] = b.gamma_o;
            m.node_cos_gamma[k] = b.cos_gamma_o;
            wk[k] = w[k] * std::cos(gamma);
            wsum += wk[k];
        }
        double c = 0;
        for (int k = 0; k < m.n; ++k) {
            m.weight[k] = F(wk[k] / wsum);
            c += wk[k] / wsum;
            m.cdf[k] = F(c);
        }
        m.cdf[m.n - 1] = F(1);
        for (int k = m.n; k < MaxNodes; ++k) m.node_h[k] = m.node_gamma[k] = m.node_cos_gamma[k] = m.weight[k] = m.cdf[k] = F(0);
        return m;
    }

    // The single-h fibre of node k.
    HairBxDF<F> lobe(int k) const {
        HairBxDF<F> b = base;
        b.h = node_h[k];
        b.gamma_o = node_gamma[k];
        b.cos_gamma_o = node_cos_gamma[k];
        return b;
    }

    uint8_t flags() const { return GlossyReflection; }

    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode) const {
        Spectrum<F> sum(F(0));
        for (int k = 0; k < n; ++k) sum = sum + lobe(k).f(wo, wi, mode) * weight[k];
        return sum;
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode, uint8_t sample_flags) const {
        F sum = F(0);
        for (int k = 0; k < n; ++k) sum += lobe(k).pdf(wo, wi, mode, sample_flags) * weight[k];
        return sum;
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        // node k with probability weight[k]; uc remapped for the lobe choice inside node k
        int k = 0;
        for (int j = 0; j < n - 1; ++j) k += int(uc >= cdf[j]);
        F start = k == 0 ? F(0) : cdf[k - 1];
        F ur = clamp((uc - start) / weight[k], F(0), F(1) - std::numeric_limits<F>::epsilon() / 2);
        BSDFSample<F> s = lobe(k).sample_f(wo, ur, u, mode, sample_flags);
        s.f = f(wo, s.wi, mode);
        s.pdf = pdf(wo, s.wi, mode, sample_flags);
        s.valid = s.valid & (s.pdf > F(0));
        return s;
    }

    void regularize() {}
};

} // namespace bsdfkit
