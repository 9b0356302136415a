// EON: the energy-preserving Oren-Nayar diffuse BRDF (Portsmouth, Kutz & Hill, "EON: A Practical
// Energy-Preserving Rough Diffuse BRDF", JCGT 14(1), 2025; OpenPBR Surface 1.1's base diffuse
// lobe, MaterialX oren_nayar_diffuse_bsdf with energy_compensation). Two-sided.
//   reflectance  rho per channel, in [0, 1]
//   roughness    r in [0, 1] (OpenPBR base_diffuse_roughness, the paper's sigma); r = 0: Lambert
// f = f_FON (Fujii's Oren-Nayar, single scattering) + f_ms (the multiple-scattering lobe that makes
// a white surface's albedo exactly 1). Sampling: the paper's mixture of a uniform hemisphere and
// a clipped linearly transformed cosine (CLTC) lobe; pdf() is that mixture's density.
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/frame.h"
#include "../core/sampling.h"

namespace bsdfkit {

template <template <typename, int, typename> class M, typename F> struct ColourSpectral;  // batch_spectral.h

// S: the parameters' scalar type (core/math.h param_t; a Dual for gradients); N, Col: the colour's
// channel count and type (DiffuseParamsT).
template <typename S = double, int N = 3, typename Col = S> struct EONParamsT {
    std::array<Col, N> reflectance{Col(0.5), Col(0.5), Col(0.5)};
    S roughness = 0;
    template <class V> void fields(V &&v) {
        v("reflectance", reflectance);
        v("roughness", roughness);
    }
    template <int N2, typename Col2> using WithColours = EONParamsT<S, N2, Col2>;
};
using EONParams = EONParamsT<>;

// Fujii's constants ([P] constant1_FON / constant2_FON): c1 = 1/2 - 2/(3 pi), c2 = 2/3 - 28/(15 pi).
inline constexpr double kFujiiC1 = 0.5 - 2.0 / (3.0 * 3.14159265358979323846);
inline constexpr double kFujiiC2 = 2.0 / 3.0 - 28.0 / (15.0 * 3.14159265358979323846);

// Fujii's s / t (OpenPBR FON_brdf footnote): s = wi.wo - mu_i mu_o, t = max(mu_i, mu_o) where s > 0, else 1.
template <typename V> inline V FujiiSOverT(V s, V mu_i, V mu_o) { return select(s > V(0), s / max_(mu_i, mu_o), s); }

// G(mu) of the FON directional albedo E(mu) = A (1 + r G(mu) / pi) ([P] E_FON_exact), with
// (S / mu)(1 - S^3) written S mu (1 + S + S^2) / (1 + S), S = sqrt(1 - mu^2): no division by mu,
// G(0) = pi/2 - 2/3, G(1) = 0.
template <typename V> inline V FONAlbedoG(V mu) {
    V s = safe_sqrt(V(1) - mu * mu);
    return s * (acos(min_(mu, V(1))) - s * mu) + V(2.0 / 3.0) * (s * mu * (V(1) + s + s * s) / (V(1) + s) - s);
}

// 1 - E(mu) over r A: c1 - G(mu) / pi, in [0, c1] (the cancellation-free form of [P] f_EON's 1 - E).
template <typename V> inline V FONAlbedoDeficit(V mu) {
    return V(kFujiiC1) - FONAlbedoG(mu) * V(0.31830988618379067154);
}

// The CLTC lobe's matrix M = [[a, 0, b], [0, c, 0], [d, 0, 1]] at mu = cos theta_o ([P] ltc_coeffs,
// rational fits). d is clamped to <= 0 (the fit crosses 0 at mu = 0.99989; the clipped disk of
// CLTCSample assumes d <= 0, so the lobe stays in the upper hemisphere).
template <typename V> struct LTCCoefficients {
    V a, b, c, d;
};
template <typename V> inline LTCCoefficients<V> EONLTCCoefficients(V mu, V r) {
    LTCCoefficients<V> m;
    m.a = V(1) + r * (V(0.303392) + (V(-0.518982) + V(0.111709) * mu) * mu + (V(-0.276266) + V(0.335918) * mu) * r);
    m.b = r * (V(-1.16407) + V(1.15859) * mu + (V(0.150815) - V(0.150105) * mu) * r) / (mu * mu * mu - V(1.43545));
    m.c = V(1) + (V(0.20013) + (V(-0.506373) + V(0.261777) * mu) * mu) * r;
    V d = r * (V(0.540852) + (V(-1.01625) + V(0.475392) * mu) * mu) / (V(-1.0743) + mu * (V(0.0725628) + mu));
    m.d = min_(d, V(0));
    return m;
}

// The probability of the uniform component ([P] sample_EON): r^0.1 times a cubic in mu.
template <typename V> inline V EONUniformProbability(V mu, V r_pow01) {
    return r_pow01 * (V(0.162925) + mu * (V(-0.372058) + mu * (V(0.538233) - V(0.290822) * mu)));
}

// The clipped disk's scale sc = (1 + vz) / 2, vz = 1 / sqrt(d^2 + 1) ([P] cltc_sample / cltc_pdf).
template <typename V> inline V CLTCScale(V d) { return V(0.5) * (V(1) + V(1) / sqrt(d * d + V(1))); }

// The CLTC density of l = (lx, ly, lz) in the LTC frame ([P] cltc_pdf): with h = adj(M) l,
// pdf = (det M / |h|^2)^2 max(h.z, 0) / (pi sc).
template <typename V> inline V CLTCPdf(const LTCCoefficients<V> &m, V lx, V ly, V lz) {
    V hx = m.c * (lx - m.b * lz), hy = (m.a - m.b * m.d) * ly, hz = m.c * (m.a * lz - m.d * lx);
    V det = m.c * (m.a - m.b * m.d);
    V h2 = hx * hx + hy * hy + hz * hz;
    V q = det / h2;
    return q * q * max_(hz, V(0)) / (V(3.14159265358979323846) * CLTCScale(m.d));
}

// A CLTC sample in the LTC frame ([P] cltc_sample): a point of the unit disk mapped affinely onto
// the disk clipped at the horizon of M, lifted to the hemisphere (cosine-distributed), then M wh
// normalized.
template <typename V> inline Vec3<V> CLTCSample(const LTCCoefficients<V> &m, Point2<V> u) {
    V R = sqrt(u.x), sp, cp;
    sincos_(V(2 * 3.14159265358979323846) * u.y, &sp, &cp);
    V x = R * cp, y = R * sp;
    V sc = CLTCScale(m.d);
    x = -((V(1) - sc) * safe_sqrt(V(1) - y * y) + sc * x);
    V z = safe_sqrt(V(1) - x * x - y * y);
    Vec3<V> v(m.a * x + m.b * z, m.c * y, m.d * x + z);
    V inv = V(1) / sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return {v.x * inv, v.y * inv, v.z * inv};
}

// NC: channels (3 RGB; 4 in spectral mode, the generic form ColourSpectral). C: the channel
// values' type, F or Packet<F> (a spectral packet).
template <typename F, int NC = 3, typename C = F> struct EONBxDF {
    using Params = EONParamsT<param_t<F>, NC, colour_param_t<F, C>>;
    static constexpr const char *Name = "EON";
    using Spectral = ColourSpectral<EONBxDF, F>;  // its spectral form (core/bxdf.h): the generic one
    static constexpr int GradColumns = 4;         // eval_grad columns at most
    Spectrum<C, NC> R_over_pi, ms_over_pi;  // rho / pi; rho_ms r A / (pi (c1 - c2))
    F r = F(0), A = F(1), r_pow01 = F(0);   // roughness, A = 1 / (1 + c1 r), r^0.1

    // rho_ms = rho^2 Eavg / (1 - rho (1 - Eavg)), Eavg = A (1 + c2 r) ([P] f_EON; OpenPBR EON_comp).
    template <typename T, typename P> static T MultipleScatterAlbedo(T rho, P eavg) {
        return rho * rho * eavg / (T(1) - rho * (T(1) - eavg));
    }

    static EONBxDF make(const Params &p) {
        using P = param_t<F>;
        P rr = p.roughness, a = P(1) / (P(1) + P(kFujiiC1) * rr), eavg = a * (P(1) + P(kFujiiC2) * rr);
        P k = rr * a / (P(kFujiiC1 - kFujiiC2)) * P(0.31830988618379067154);
        EONBxDF m;
        m.r = F(rr);
        m.A = F(a);
        m.r_pow01 = F(pow(rr, P(0.1)));
        for (int i = 0; i < NC; ++i) {
            auto rho = p.reflectance[size_t(i)];
            m.R_over_pi[i] = C(rho * P(0.31830988618379067154));
            m.ms_over_pi[i] = C(MultipleScatterAlbedo(rho, eavg) * k);
        }
        return m;
    }

    uint8_t flags() const { return R_over_pi.is_black() ? Unset : DiffuseReflection; }

    // Runs on packets in the batch kernels (batch.h; core/simd.h).
    static constexpr bool Vectorized = true;

    // f = f_FON + f_ms on wo's side ([P] f_EON): rho/pi A (1 + r s/t) + rho_ms r A / (pi (c1 - c2))
    // (c1 - G(mu_o)/pi)(c1 - G(mu_i)/pi); 0 across the surface.
    template <typename V> Spectrum<V, NC> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode) const {
        Mask<V> active = SameHemisphere(wo, wi);
        V mu_o = abs(wo.z), mu_i = abs(wi.z);
        V ss = V(A) * (V(1) + V(r) * FujiiSOverT(wo.x * wi.x + wo.y * wi.y, mu_i, mu_o));
        V ms = FONAlbedoDeficit(mu_o) * FONAlbedoDeficit(mu_i);
        Spectrum<V, NC> v;
        for (int c = 0; c < NC; ++c) v[c] = select(active, V(R_over_pi[c]) * ss + V(ms_over_pi[c]) * ms, V(0));
        return v;
    }

    // The sampler's density on wo's side, both hemispheres folded to the upper one:
    // P_u / (2 pi) + (1 - P_u) pdf_CLTC ([P] pdf_EON).
    template <typename V> V pdf_folded(const Vec3<V> &wo, const Vec3<V> &wi) const {
        V mu = abs(wo.z), pu = EONUniformProbability(mu, V(r_pow01));
        LTCCoefficients<V> m = EONLTCCoefficients(mu, V(r));
        // the LTC frame: X along wo's azimuth (x if wo is the normal), Y = z x X
        V len2 = wo.x * wo.x + wo.y * wo.y;
        Mask<V> az = len2 > V(0);
        V inv = V(1) / sqrt(select(az, len2, V(1)));
        V xx = select(az, wo.x * inv, V(1)), xy = select(az, wo.y * inv, V(0));
        V lx = wi.x * xx + wi.y * xy, ly = wi.y * xx - wi.x * xy, lz = abs(wi.z);
        return pu * V(0.15915494309189533577) + (V(1) - pu) * CLTCPdf(m, lx, ly, lz);
    }

    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        V p = select(SameHemisphere(wo, wi), pdf_folded(wo, wi), V(0));
        return keep_or_zero(p, (sample_flags & RT_Reflection) != 0);
    }

    template <typename V>
    BSDFSample<V, NC> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode mode, uint8_t sample_flags) const {
        V mu = abs(wo.z);
        Mask<V> uniform = uc < EONUniformProbability(mu, V(r_pow01));
        // uniform on the hemisphere: z = u1, phi = 2 pi u2 ([P] uniform_lobe_sample)
        V su, cu, ru = safe_sqrt(V(1) - u.x * u.x);
        sincos_(V(2 * 3.14159265358979323846) * u.y, &su, &cu);
        Vec3<V> wu(ru * cu, ru * su, u.x);
        // the CLTC sample, from the LTC frame to the local one
        LTCCoefficients<V> m = EONLTCCoefficients(mu, V(r));
        Vec3<V> l = CLTCSample(m, u);
        V len2 = wo.x * wo.x + wo.y * wo.y;
        Mask<V> az = len2 > V(0);
        V inv = V(1) / sqrt(select(az, len2, V(1)));
        V xx = select(az, wo.x * inv, V(1)), xy = select(az, wo.y * inv, V(0));
        Vec3<V> wi(select(uniform, wu.x, l.x * xx - l.y * xy), select(uniform, wu.y, l.x * xy + l.y * xx),
                   select(uniform, wu.z, l.z));
        wi.z = select(wo.z < V(0), -wi.z, wi.z);  // two-sided: sample wo's side
        BSDFSample<V, NC> s;
        s.wi = wi;
        s.pdf = select(SameHemisphere(wo, wi), pdf_folded(wo, wi), V(0));
        s.f = f(wo, wi, mode);
        s.flags = DiffuseReflection;
        s.valid = Mask<V>((sample_flags & RT_Reflection) != 0) & (s.pdf > V(0));
        return s;
    }

    void regularize() {}
};

} // namespace bsdfkit
