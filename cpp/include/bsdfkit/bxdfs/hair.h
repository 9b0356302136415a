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

template <typename F> struct HairFarFieldSpectral;  // its spectral form (batch_spectral.h / spectral/)

template <typename F> struct HairSpectral;  // its spectral form (batch_spectral.h / spectral/)

namespace hair {

inline constexpr int PMax = 3;

// The helpers are written on the evaluation type F (a scalar or a packet, core/simd.h): exp, log,
// asin and atan2 are unqualified, so scalars call libm (core/math.h) and packets Dr.Jit's vector
// forms (drjit/math.h, Cephes-derived, about 1 ulp). Where an exponent is finite by construction
// (beta_m, beta_n >= 0.01 bound 1 / v and 1 / s), exp_finite (core/simd.h) drops the packet exp's
// overflow / underflow selects: 4 of ~17 instructions, 10 exps per element (the same bits where
// the result is a normal float; T's exponent, -2 sigma_a len, is clamped at -104 first, as a huge
// sigma_a times len could reach -inf).

// Modified Bessel function of the first kind, order 0: sum_{i<10} x^{2i} / (4^i (i!)^2) (pbrt-v4 I0),
// by Horner's rule in x^2 (the coefficients are constants: 9 fused multiply-adds).
struct I0Coefficients {
    double c[10];
    constexpr I0Coefficients() : c{} {
        double t = 1;
        for (int i = 0; i < 10; ++i) {
            c[i] = t;
            t /= double(4 * (i + 1) * (i + 1));
        }
    }
};
inline constexpr I0Coefficients kI0{};
template <typename F> inline F I0(F x) {
    using S = scalar_t<F>;
    F x2 = x * x, val = F(S(kI0.c[9]));
    for (int i = 8; i >= 0; --i) val = mul_add(val, x2, F(S(kI0.c[i])));
    return val;
}

// Longitudinal scattering of d'Eon et al. 2011, eq. 7, in log space (pbrt-v4 Mp):
// Mp = exp(LogI0(a) - b + log_norm), a = cos_i cos_o / v, b = sin_i sin_o / v, with log_norm =
// -ln(2 v sinh(1/v)) for v > 0.1 and pbrt-v4's -1/v + 0.6931 + ln(1/(2v)) for v <= 0.1 (no overflow
// for small v). Written with one exp and no log: where a <= 12 (LogI0 = log I0, pbrt-v4 LogI0) it is
// I0(a) exp(log_norm - b); past 12, LogI0's asymptotic form a + (ln(1/a) - ln(2 pi) + 1/(8a)) / 2
// gives exp(a + 1/(16a) + log_norm - b) / sqrt(2 pi a), with 1/(16a) = (pi/8) r^2 for
// r = 1 / sqrt(2 pi a). The asymptotic terms are computed only for a packet with a lane past 12
// and serve only those lanes, so every lane's value is the same whatever its neighbours. No
// overflow: I0(12) < 2e4, exp(log_norm - b) <= 1 / (v (1 - exp(-2 / v))), about 1 / v + 1 / 2,
// and a - b + log_norm <= 1 / v + log_norm. (The TT lobe, v0 / 4, passes 12 on most pairs at
// beta_m = 0.3: its log, second exp and I0 were ~9 % of the eval kernel.)
template <typename F, typename S> inline F Mp(F cos_i, F cos_o, F sin_i, F sin_o, S inv_v, S log_norm) {
    using T = scalar_t<F>;
    F a = cos_i * cos_o * F(inv_v), b = sin_i * sin_o * F(inv_v);
    F arg = F(log_norm) - b;
    Mask<F> big = a > F(12);
    F pre = I0(min_(a, F(12)));
    if (any(big)) {
        F r = F(1) / sqrt(F(T(2) * Pi<T>) * max_(a, F(12)));
        pre = select(big, r, pre);
        arg = select(big, arg + mul_add(F(T(0.125) * Pi<T>), r * r, a), arg);
    }
    return pre * exp_finite(arg);
}

// Attenuation of each lobe (Marschner 2003 sec. 4.3; pbrt-v4 Ap): A0 = f, A1 = (1-f)^2 T,
// A2 = A1 T f, A3 = A2 f T / (1 - T f) (the geometric series of all p >= 3).
template <typename F, int NC, typename E>
inline void Ap(F cos_theta_o, E eta, F cos_gamma_o, const Spectrum<F, NC> &T, Spectrum<F, NC> ap[PMax + 1]) {
    F f = FrDielectric(cos_theta_o * cos_gamma_o, eta);
    ap[0] = Spectrum<F, NC>(f);
    ap[1] = T * sqr(F(1) - f);
    ap[2] = ap[1] * T * f;
    for (int c = 0; c < NC; ++c) {
        F den = F(1) - T[c] * f;
        Mask<F> ok = den > F(0);
        ap[3][c] = select(ok, ap[2][c] * f * T[c] / select(ok, den, F(1)), F(0));
    }
}

// Azimuth of the perfect (smooth) p-bounce path, Phi(p) = 2 p gamma_t - 2 gamma_o + p pi (pbrt-v4 Phi);
// p an integer, or per lane a float holding one.
template <typename F> inline F Phi(int p, F gamma_o, F gamma_t) {
    return F(2 * p) * gamma_t - F(2) * gamma_o + F(p) * Pi<scalar_t<F>>;
}
template <typename F> inline F Phi(F p, F gamma_o, F gamma_t) {
    return F(2) * p * gamma_t - F(2) * gamma_o + p * F(Pi<scalar_t<F>>);
}

// Logistic density of scale s (Chiang 2016 eq. 10), symmetric; inv_s = 1 / s.
template <typename F, typename S> inline F Logistic(F x, S inv_s) {
    F e = exp_finite(-abs(x) * F(inv_s));
    return e * F(inv_s) / sqr(F(1) + e);
}

// Wrap an angle into [-pi, pi].
template <typename F> inline F WrapPi(F x) {
    using S = scalar_t<F>;
    return mul_add(F(-S(2) * Pi<S>), floor((x + F(Pi<S>)) * F(Inv2Pi<S>)), x);
}

// Trimmed logistic on [-pi, pi] (Chiang 2016 eq. 11): Logistic / (CDF(pi) - CDF(-pi)).
template <typename F, typename P, typename S> inline F Np(F dphi, P p, S inv_s, S inv_trim, F gamma_o, F gamma_t) {
    return Logistic(WrapPi(dphi - Phi(p, gamma_o, gamma_t)), inv_s) * F(inv_trim);
}

// Inverse CDF of the trimmed logistic on [-pi, pi] (pbrt-v4 SampleTrimmedLogistic):
// -s ln(1/u - 1) = -s ln((1 - u) / u).
template <typename F, typename S> inline F SampleTrimmedLogistic(F u, S s, S cdf_lo, S cdf_hi) {
    using T = scalar_t<F>;
    u = lerp(u, F(cdf_lo), F(cdf_hi));
    F x = -F(s) * log((F(1) - u) / u);
    return clamp(x, F(-Pi<T>), F(Pi<T>));
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

// NC: colour channels (3: RGB; 4: the wavelengths of the spectral adapter, spectral/hair_spectral.h,
// whose lobe weights then average Ap over the 4 wavelengths as pbrt-v4's ApPDF does).
template <typename F, int NC = 3> struct HairBxDF {
    using Params = HairParams;
    static constexpr const char *Name = "Hair";
    using Spectral = HairSpectral<F>;  // its spectral form (core/bxdf.h)
    static constexpr int P = hair::PMax;

    // All derived at construction (in double).
    F h, eta, eta2, gamma_o, cos_gamma_o;
    Spectrum<F, NC> two_sigma_a;      // 2 sigma_a (the path length is 2 cos gamma_t / cos theta_t)
    F inv_v[P + 1], log_norm[P + 1];  // Mp per lobe
    F v[P + 1], exp_m2_over_v[P + 1]; // Mp sampling: cos = 1 + v ln(u + (1-u) e^{-2/v})
    F s, inv_trim, cdf_lo, cdf_hi;    // trimmed logistic
    F sin_tilt[P + 1], cos_tilt[P + 1];  // theta_o rotation per lobe: -2 alpha, alpha, 4 alpha, 0

    static HairBxDF make(const Params &p) {
        HairBxDF m = make_fibre(p);
        if constexpr (NC == 3)
            for (int c = 0; c < 3; ++c) m.two_sigma_a[c] = F(2 * p.sigma_a[size_t(c)]);
        return m;  // other NC: sigma_a 0 until set_sigma_a (the spectral adapter)
    }

    // Everything but sigma_a (zero): the spectral adapter sets sigma_a per element (set_sigma_a).
    static HairBxDF make_fibre(const Params &p) {
        HairBxDF m;
        m.set_h(p.h);
        m.eta = F(p.eta);
        m.eta2 = F(p.eta * p.eta);
        m.two_sigma_a = Spectrum<F, NC>(F(0));
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

    // sigma_a per channel (>= 0), as make() sets it: 2 sigma_a, exact in F.
    void set_sigma_a(const Spectrum<F, NC> &sigma_a) { two_sigma_a = sigma_a * F(2); }

    // The same fibre seen at offset h (the preview renderer sets h per curve hit): h, gamma_o = asin h
    // and cos gamma_o are the only members that depend on it.
    void set_h(double hh) {
        hh = clamp(hh, -1.0, 1.0);
        h = F(hh);
        gamma_o = F(std::asin(hh));
        cos_gamma_o = F(std::sqrt(std::max(0.0, 1.0 - hh * hh)));
    }

    uint8_t flags() const { return GlossyReflection; }

    // The model runs on packets in the batch kernels (batch.h): every method is written once on
    // the evaluation type V (F, or a packet of F; core/simd.h). The offset h and its angles are
    // passed as an Offset<V>, so that the far-field fibre can give every lane its own node.
    static constexpr bool Vectorized = true;
    // Every division is by a floored or masked value: the kernels may run with denormals flushed
    // (batch_policy.h).

    template <typename V> struct Offset {
        V h, gamma_o, cos_gamma_o;
    };
    template <typename V> Offset<V> offset() const { return {V(h), V(gamma_o), V(cos_gamma_o)}; }

    // Refraction geometry of wo (pbrt-v4 HairBxDF::f): gamma_t and the transmittance of one pass.
    // sin gamma_t = h / eta', eta' = sqrt(eta^2 - sin^2 theta_o) / cos theta_o (Bravais index);
    // T = exp(-sigma_a 2 cos gamma_t / cos theta_t) with cos theta_t = den / eta, den = sqrt(eta^2 -
    // sin^2 theta_o) floored at eta 1e-30 (cos theta_t > 0 unless eta == 1 at grazing): 1 division.
    template <typename V>
    void refracted(const Offset<V> &g, V sin_o, V cos_o, V *gamma_t, Spectrum<V, NC> *T) const {
        V inv_den = V(1) / max_(safe_sqrt(neg_mul_add(sin_o, sin_o, V(eta2))), V(F(1e-30) * eta));
        V sin_gt = clamp(g.h * cos_o * inv_den, V(-1), V(1));
        V cos_gt = safe_sqrt(neg_mul_add(sin_gt, sin_gt, V(1)));
        *gamma_t = asin(sin_gt);
        V len = cos_gt * V(eta) * inv_den;
        // the exponent is finite (exp_finite) but for a huge sigma_a times len: e^-104 is 0 in float
        for (int c = 0; c < NC; ++c) (*T)[c] = exp_finite(max_(-V(two_sigma_a[c]) * len, V(-104)));
    }

    // theta_o rotated by the lobe's cuticle tilt; cos is taken as |cos| (pbrt-v4).
    template <typename V, typename S> static void tilted(S st, S ct, V sin_o, V cos_o, V *sin_p, V *cos_p) {
        *sin_p = mul_add(sin_o, V(ct), cos_o * V(st));
        *cos_p = abs(mul_sub(cos_o, V(ct), sin_o * V(st)));
    }

    // Everything that depends on wo alone: theta_o, gamma_t, Ap and the lobe weights.
    template <typename V> struct Outgoing {
        V sin_o, cos_o, gamma_t;
        Spectrum<V, NC> ap[P + 1];
        V w[P + 1];
    };
    template <typename V> Outgoing<V> outgoing(const Offset<V> &g, const Vec3<V> &wo) const {
        Outgoing<V> o;
        o.sin_o = wo.x;
        o.cos_o = safe_sqrt(neg_mul_add(o.sin_o, o.sin_o, V(1)));
        Spectrum<V, NC> T;
        refracted(g, o.sin_o, o.cos_o, &o.gamma_t, &T);
        hair::Ap(o.cos_o, eta, g.cos_gamma_o, T, o.ap);
        weights(o.ap, o.w);
        return o;
    }

    // Mp Np of every lobe for wi at azimuth difference dphi (the p >= 3 lobe: Mp / (2 pi)).
    template <typename V>
    void lobes(const Offset<V> &g, const Outgoing<V> &o, const Vec3<V> &wi, V dphi, V mn[P + 1]) const {
        V sin_i = wi.x, cos_i = safe_sqrt(neg_mul_add(sin_i, sin_i, V(1)));
        F inv_s = F(1) / s;
        for (int p = 0; p < P; ++p) {
            V sp, cp;
            tilted(sin_tilt[p], cos_tilt[p], o.sin_o, o.cos_o, &sp, &cp);
            mn[p] = hair::Mp(cos_i, cp, sin_i, sp, inv_v[p], log_norm[p]) *
                    hair::Np(dphi, p, inv_s, inv_trim, g.gamma_o, o.gamma_t);
        }
        mn[P] = hair::Mp(cos_i, o.cos_o, sin_i, o.sin_o, inv_v[P], log_norm[P]) * V(Inv2Pi<scalar_t<V>>);
    }

    // Lobe-selection probabilities: averages of Ap over the NC channels (RGB, or the 4 sampled
    // wavelengths in spectral mode), normalised (pbrt-v4 ApPDF: SampledSpectrum::Average).
    template <typename V> static void weights(const Spectrum<V, NC> ap[P + 1], V w[P + 1]) {
        V sum = V(0);
        for (int p = 0; p <= P; ++p) sum += (w[p] = ap[p].average());
        V inv = select(sum > V(0), V(1) / select(sum > V(0), sum, V(1)), V(0));
        for (int p = 0; p <= P; ++p) w[p] *= inv;
    }

    // phi_i - phi_o from the (y, z) components: one atan2, in [-pi, pi] (pbrt-v4 takes two
    // atan2 and subtracts; Np wraps, so the values agree).
    template <typename V> static V delta_phi(const Vec3<V> &wo, const Vec3<V> &wi) {
        return atan2(wo.y * wi.z - wo.z * wi.y, wo.y * wi.y + wo.z * wi.z);
    }

    // sum_p Ap Mp Np / |cos theta_i| (divided where |cos| > 0, pbrt-v4) and sum_p w_p Mp Np.
    template <typename V>
    void f_pdf(const Offset<V> &g, const Vec3<V> &wo, const Vec3<V> &wi, V dphi, const Outgoing<V> &o,
               Spectrum<V, NC> *f, V *pdf) const {
        V mn[P + 1];
        lobes(g, o, wi, dphi, mn);
        Spectrum<V, NC> sum = o.ap[0] * mn[0];
        V p = o.w[0] * mn[0];
        for (int q = 1; q <= P; ++q) {
            for (int c = 0; c < NC; ++c) sum[c] = mul_add(o.ap[q][c], mn[q], sum[c]);
            p = mul_add(o.w[q], mn[q], p);
        }
        V c = AbsCosTheta(wi);
        if (f) *f = sum * (V(1) / select(c > V(0), c, V(1)));
        if (pdf) *pdf = p;
    }

    template <typename V> Spectrum<V, NC> f_at(const Offset<V> &g, const Vec3<V> &wo, const Vec3<V> &wi) const {
        Spectrum<V, NC> r;
        f_pdf<V>(g, wo, wi, delta_phi(wo, wi), outgoing(g, wo), &r, nullptr);
        return r;
    }
    template <typename V> V pdf_at(const Offset<V> &g, const Vec3<V> &wo, const Vec3<V> &wi) const {
        V r;
        f_pdf<V>(g, wo, wi, delta_phi(wo, wi), outgoing(g, wo), nullptr, &r);
        return r;
    }

    template <typename V> Spectrum<V, NC> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode) const {
        return f_at(offset<V>(), wo, wi);
    }

    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        // pbrt-v4's PDF ignores sample_flags; here it is 0 when reflection is excluded, as sample_f is.
        return select(Mask<V>((sample_flags & RT_Reflection) != 0), pdf_at(offset<V>(), wo, wi), V(0));
    }

    // Per-lane choice among four per-lobe constants (p a float holding 0..3).
    template <typename V> static V pick(V p, const F a[P + 1]) {
        return select(p == V(0), V(a[0]), select(p == V(1), V(a[1]), select(p == V(2), V(a[2]), V(a[3]))));
    }

    template <typename V>
    BSDFSample<V, NC> sample_at(const Offset<V> &g, const Vec3<V> &wo, V uc, Point2<V> u, uint8_t sample_flags) const {
        using S = scalar_t<V>;
        Outgoing<V> o = outgoing(g, wo);
        const V *w = o.w;
        // Choose the lobe p with probability w[p] and remap uc (pbrt-v4 SampleDiscrete).
        V c0 = w[0], c1 = c0 + w[1], c2 = c1 + w[2];
        V p = mask_to_float<V>(uc >= c0) + mask_to_float<V>(uc >= c1) + mask_to_float<V>(uc >= c2);
        V start = select(p == V(0), V(0), select(p == V(1), c0, select(p == V(2), c1, c2)));
        V wp = select(p == V(0), w[0], select(p == V(1), w[1], select(p == V(2), w[2], w[3])));
        V ur = min_((uc - start) / max_(wp, V(std::numeric_limits<S>::min())),
                    V(S(1) - std::numeric_limits<S>::epsilon() / 2));
        ur = max_(ur, V(0));
        V sp, cp;
        tilted(pick(p, sin_tilt), pick(p, cos_tilt), o.sin_o, o.cos_o, &sp, &cp);
        // Sample Mp (d'Eon 2011; pbrt-v4): cos = 1 + v ln(u0 + (1 - u0) e^{-2/v}), u0 >= 1e-5
        V cos_t = V(1) + pick(p, v) * log(max_(u.x, V(1e-5)) + (V(1) - u.x) * pick(p, exp_m2_over_v));
        V sin_t = safe_sqrt(V(1) - cos_t * cos_t);
        V sphi, cphi;
        sincos_(V(S(2) * Pi<S>) * u.y, &sphi, &cphi);
        V sin_i = -cos_t * sp + sin_t * cphi * cp;
        V cos_i = safe_sqrt(V(1) - sin_i * sin_i);
        // Sample Np: dphi = Phi(p) + trimmed logistic, or uniform for p >= 3
        V dphi_lobe = hair::Phi(p, g.gamma_o, o.gamma_t) + hair::SampleTrimmedLogistic(ur, s, cdf_lo, cdf_hi);
        V dphi = select(p < V(P), dphi_lobe, V(S(2) * Pi<S>) * ur);
        V sd, cd;
        sincos_(dphi, &sd, &cd);
        // rotate wo's azimuth (cos phi_o, sin phi_o) = (y, z) / r by dphi; phi_o = 0 on the axis
        V r2 = wo.y * wo.y + wo.z * wo.z;
        Mask<V> on_axis = !(r2 > V(0));
        V inv_r = V(1) / sqrt(select(on_axis, V(1), r2));
        V cpo = select(on_axis, V(1), wo.y * inv_r), spo = select(on_axis, V(0), wo.z * inv_r);
        Vec3<V> wi(sin_i, cos_i * (cpo * cd - spo * sd), cos_i * (spo * cd + cpo * sd));
        // f and the full mixture density (pbrt-v4), so sample_f agrees with f and pdf.
        BSDFSample<V, NC> out;
        f_pdf(g, wo, wi, dphi, o, &out.f, &out.pdf);
        out.wi = wi;
        out.flags = typename BSDFSample<V, NC>::Flags(GlossyReflection);
        out.valid = Mask<V>((sample_flags & RT_Reflection) != 0) & (out.pdf > V(0));
        return out;
    }

    template <typename V>
    BSDFSample<V, NC> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode, uint8_t sample_flags) const {
        return sample_at(offset<V>(), wo, uc, u, sample_flags);
    }

    void regularize() {}
};

// The far-field fibre: HairBxDF averaged over the offset h in [-1, 1] (a fibre seen whole, thinner
// than a pixel). (1/2) int f(h) dh is integrated in gamma = asin h, where the integrand is smooth:
// h = sin gamma, dh = cos gamma dgamma, by Gauss-Legendre with `nodes` points on (-pi/2, pi/2)
// (weights normalised to sum 1). Sampling picks node k with its weight, then samples HairBxDF(h_k);
// pdf is the same mixture, so sample_f, f and pdf agree exactly. Cost: `nodes` times HairBxDF. The
// nodes share every member of HairBxDF but h, gamma_o and cos gamma_o (HairBxDF::set_h).
template <typename F, int NC = 3> struct HairFarFieldBxDF {
    static constexpr int MaxNodes = 64;
    static constexpr const char *Name = "HairFarField";
    using Spectral = HairFarFieldSpectral<F>;  // its spectral form (core/bxdf.h)
    using Params = HairFarFieldParams;
    using Base = HairBxDF<F, NC>;
    Base base;
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
        m.base = Base::make(q);
        double x[MaxNodes], w[MaxNodes], wk[MaxNodes], wsum = 0;
        hair::GaussLegendre(m.n, x, w);
        for (int k = 0; k < m.n; ++k) {
            double gamma = x[k] * 1.5707963267948966;
            Base b = m.base;
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
    Base lobe(int k) const {
        Base b = base;
        b.h = node_h[k];
        b.gamma_o = node_gamma[k];
        b.cos_gamma_o = node_cos_gamma[k];
        return b;
    }

    uint8_t flags() const { return GlossyReflection; }

    // On packets too (batch.h): the node loop is uniform; sampling gives each lane its own node.
    static constexpr bool Vectorized = true;

    template <typename V> typename Base::template Offset<V> node(int k) const {
        return {V(node_h[k]), V(node_gamma[k]), V(node_cos_gamma[k])};
    }

    // sum_k weight_k (f_k, pdf_k): the azimuth difference is shared by the nodes.
    template <typename V> void f_pdf(const Vec3<V> &wo, const Vec3<V> &wi, Spectrum<V, NC> *f, V *pdf) const {
        V dphi = Base::delta_phi(wo, wi);
        Spectrum<V, NC> fs(V(0));
        V ps = V(0);
        for (int k = 0; k < n; ++k) {
            auto g = node<V>(k);
            Spectrum<V, NC> fk;
            V pk;
            base.f_pdf(g, wo, wi, dphi, base.outgoing(g, wo), f ? &fk : nullptr, pdf ? &pk : nullptr);
            if (f) fs = fs + fk * V(weight[k]);
            if (pdf) ps += pk * V(weight[k]);
        }
        if (f) *f = fs;
        if (pdf) *pdf = ps;
    }

    template <typename V> Spectrum<V, NC> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode) const {
        Spectrum<V, NC> r;
        f_pdf<V>(wo, wi, &r, nullptr);
        return r;
    }

    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        V r;
        f_pdf<V>(wo, wi, nullptr, &r);
        return select(Mask<V>((sample_flags & RT_Reflection) != 0), r, V(0));
    }

    template <typename V>
    BSDFSample<V, NC> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode, uint8_t sample_flags) const {
        using S = scalar_t<V>;
        // node k with probability weight[k]; uc remapped for the lobe choice inside node k
        V k = V(0);
        for (int j = 0; j < n - 1; ++j) k += mask_to_float<V>(uc >= V(cdf[j]));
        V start = select(k == V(0), V(0), gather_index(cdf, max_(k - V(1), V(0))));
        V ur = clamp((uc - start) / gather_index(weight, k), V(0), V(S(1) - std::numeric_limits<S>::epsilon() / 2));
        typename Base::template Offset<V> g{gather_index(node_h, k), gather_index(node_gamma, k),
                                            gather_index(node_cos_gamma, k)};
        BSDFSample<V, NC> s = base.sample_at(g, wo, ur, u, sample_flags);
        f_pdf<V>(wo, s.wi, &s.f, &s.pdf);
        s.pdf = select(Mask<V>((sample_flags & RT_Reflection) != 0), s.pdf, V(0));
        s.valid = s.valid & (s.pdf > V(0));
        return s;
    }

    void regularize() {}
};

} // namespace bsdfkit
