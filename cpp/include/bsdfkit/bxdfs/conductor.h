// Conductor: perfect mirror or Trowbridge-Reitz microfacet reflection with a conductor Fresnel
// term (pbrt-v4 ConductorBxDF; Torrance & Sparrow 1967, Walter et al. 2007).
// Parameters (ConductorParams; Python: bsdfkit.Conductor)
//   eta, k     real and imaginary index of refraction per channel (eta > 0, k >= 0); default Cu
//   alpha_x, alpha_y, masking, distribution   anisotropic GGX or Beckmann; max(alpha) < 1e-3
//              makes the lobe a delta
//   sample_visible   sample visible normals (default) or D(wm) cos(wm) (Mitsuba 3's knob)
//   FR         the Fresnel term, a compile-time knob (one loop per variant):
//              Exact    complex Fresnel of eta + i k (FrComplex)
//              Schlick  Schlick 1994 with the exact normal-incidence reflectance F0
//              F82      F82-tint (Hoffman 2019; Kutz et al. 2021): Schlick minus a
//                       mu (1 - mu)^6 term fitted to the exact value at mu = 1/7
// Two-sided: a wo below the surface sees the same conductor. Symmetric in wo and wi.
#pragma once
#include <cstdint>

#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"

namespace bsdfkit {

enum class ConductorFresnel : uint8_t { Exact = 0, Schlick = 1, F82 = 2 };
template <typename F, ConductorFresnel FR> struct ConductorSpectralT;  // its spectral form (batch_spectral.h / spectral/)

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
template <typename S = double> struct ConductorParamsT {
    std::array<S, 3> eta{0.201006, 0.923749, 1.102215}, k{3.913262, 2.453045, 2.142090};  // Cu (bk.METALS)
    S alpha_x = 0, alpha_y = 0;
    Masking masking = Masking::Correlated;
    Distribution distribution = Distribution::GGX;
    bool sample_visible = true;
    template <class V> void fields(V &&v) {
        v("eta", eta);
        v("k", k);
        v("alpha_x", alpha_x);
        v("alpha_y", alpha_y);
        v("masking", masking);
        v("distribution", distribution);
        v("sample_visible", sample_visible);
    }
    // the microfacet distribution these fields describe
    template <typename F> Microfacet<F> microfacet() const {
        return Microfacet<F>(F(alpha_x), F(alpha_y), masking, distribution, sample_visible);
    }
};
using ConductorParams = ConductorParamsT<>;

// NC: channels (3 RGB; 4 in spectral mode: eta and k at the element's wavelengths, core/spectral.h).
// C: the channel values' type, F; or Packet<F> for a spectral packet (eta, k, f0, f82_a per lane,
// set field by field by batch_spectral.h; the constructor serves C = F).
// A: the alphas' type, F; or Packet<F> for per-lane parameters (make_lanes, per-element
// parameters: batch_varying.h), whose lanes may differ in smoothness (a lane mask, below).
template <typename F, ConductorFresnel FR = ConductorFresnel::Exact, int NC = 3, typename C = F, typename A = F>
struct ConductorBxDF {
    using Params = ConductorParamsT<param_t<F>>;
    static constexpr const char *Name = FR == ConductorFresnel::Schlick ? "ConductorSchlick"
                                        : FR == ConductorFresnel::F82   ? "ConductorF82"
                                                                        : "Conductor";
    using Spectral = ConductorSpectralT<F, FR>;  // its spectral form (core/bxdf.h)
    static constexpr int GradColumns = 8;  // eval_grad columns at most
    Microfacet<A> mfd;
    Spectrum<C, NC> eta, k;
    // Per-channel Schlick F0 and F82-tint a, computed in double at construction (unused by Exact);
    // for a Dual model in the Dual (param_t), so their derivatives reach eta and k.
    Spectrum<C, NC> f0{C(0)}, f82_a{C(0)};

    ConductorBxDF() = default;
    ConductorBxDF(const Microfacet<F> &mfd_, const Spectrum<F, NC> &eta_, const Spectrum<F, NC> &k_)
        : mfd(mfd_), eta(eta_), k(k_) {
        // Only the approximations read them (spectral mode builds a model per element: skip the
        // exact term's unused complex Fresnel at 1/7).
        if constexpr (FR != ConductorFresnel::Exact)
            for (int i = 0; i < NC; ++i) {
                f0[i] = F(ConductorF0(param_t<F>(eta[i]), param_t<F>(k[i])));
                f82_a[i] = F(ConductorF82A(param_t<F>(eta[i]), param_t<F>(k[i])));
            }
    }

    static ConductorBxDF make(const Params &p) {
        return ConductorBxDF(p.template microfacet<F>(), to_spectrum<F>(p.eta),
                             to_spectrum<F>(p.k));
    }

    // per-lane alphas: the union of the lanes' lobes
    uint8_t flags() const {
        const auto smooth = mfd.effectively_smooth();
        if constexpr (is_packet_v<A>)
            return uint8_t((any(smooth) ? SpecularReflection : 0) | (all(smooth) ? 0 : GlossyReflection));
        else return smooth ? SpecularReflection : GlossyReflection;
    }

    // The model of kPacketWidth elements, lane l built from p[l] as make(p[l]) builds it (the same
    // operations per lane: bit-identical values). The knobs (masking, distribution, sampling) are
    // lane 0's: every lane's are the same (per-element parameters vary only real and RGB fields).
    using Lanes = ConductorBxDF<F, FR, 3, Packet<F>, Packet<F>>;
    static Lanes make_lanes(const Params *p) {
        using P = Packet<F>;
        constexpr int W = int(kPacketWidth);
        alignas(64) F ax[W], ay[W], e[3][W], kk[3][W], f0[3][W], fa[3][W];
        for (int l = 0; l < W; ++l) {
            ax[l] = F(p[l].alpha_x);
            ay[l] = F(p[l].alpha_y);
            for (int c = 0; c < 3; ++c) {
                e[c][l] = F(p[l].eta[size_t(c)]);
                kk[c][l] = F(p[l].k[size_t(c)]);
                f0[c][l] = fa[c][l] = F(0);
                if constexpr (FR != ConductorFresnel::Exact) {  // as the constructor, from the F values
                    f0[c][l] = F(ConductorF0(param_t<F>(e[c][l]), param_t<F>(kk[c][l])));
                    fa[c][l] = F(ConductorF82A(param_t<F>(e[c][l]), param_t<F>(kk[c][l])));
                }
            }
        }
        Lanes m;
        m.mfd = Microfacet<P>(drjit::load_aligned<P>(ax), drjit::load_aligned<P>(ay), p[0].masking, p[0].distribution,
                              p[0].sample_visible);
        for (int c = 0; c < 3; ++c) {
            m.eta[c] = drjit::load_aligned<P>(e[c]);
            m.k[c] = drjit::load_aligned<P>(kk[c]);
            m.f0[c] = drjit::load_aligned<P>(f0[c]);
            m.f82_a[c] = drjit::load_aligned<P>(fa[c]);
        }
        return m;
    }

    // The model runs on packets in the batch kernels (batch.h): every method is written once on
    // the evaluation type V (F, or a packet of F; core/simd.h).
    static constexpr bool Vectorized = true;

    // The Fresnel reflectance at |wo.wm| = cos_i, per channel (the FR knob).
    template <typename V> Spectrum<V, NC> fresnel(V cos_i) const {
        if constexpr (FR == ConductorFresnel::Schlick) return FrSchlick(cos_i, f0);
        else if constexpr (FR == ConductorFresnel::F82) return FrF82Tint(cos_i, f0, f82_a);
        else return FrComplex(cos_i, eta, k);
    }

    // Fresnel / denom per channel with the fewest divisions: the exact term's own denominator
    // joins denom (one division per channel); the polynomial knobs share one reciprocal.
    template <typename V> Spectrum<V, NC> fresnel_over(V cos_i, V denom) const {
        return fresnel_over_scaled(cos_i, V(1), denom);
    }
    // The same with cos_i |h| = c and len2 = |h|^2 for a half vector h that was never normalized,
    // and denom_h = denom |h|^4 (D_denom with len2): F / denom = F |h|^4 / denom_h. The exact term
    // is homogeneous in h (FrComplexRatioScaled); the polynomial knobs need the cosine itself.
    template <typename V> Spectrum<V, NC> fresnel_over_scaled(V c, V len2, V denom_h) const {
        Spectrum<V, NC> r;
        V l4 = sqr(len2);
        if constexpr (FR == ConductorFresnel::Exact) {
            for (int ch = 0; ch < NC; ++ch) {
                V num, den;
                FrComplexRatioScaled(c, len2, eta[ch], k[ch], &num, &den);
                r[ch] = num * l4 / (den * denom_h);
            }
        } else {
            r = fresnel(c / sqrt(len2)) * (l4 / denom_h);
        }
        return r;
    }

    // Torrance-Sparrow: f = D(wm) F(wo.wm) G(wo, wi) / (4 cos_o cos_i), wm = h / |h|, h = wo + wi,
    // as F / (D_denom G_denom) (core/microfacet.h) written in h (D_denom with len2,
    // fresnel_over_scaled), so h is never normalized: Exact 3 divisions and 8 square roots per
    // element (3 + 0 and 2 + 6), Schlick / F82 2 and 3.
    template <typename V> Spectrum<V, NC> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode) const {
        // a delta lobe evaluates to 0: a per-model (uniform) branch; per-lane alphas: also per lane
        const auto smooth = mfd.effectively_smooth();
        if (all(smooth)) return Spectrum<V, NC>(V(0));
        V cos_o = AbsCosTheta(wo), cos_i = AbsCosTheta(wi);
        Mask<V> active = SameHemisphere(wo, wi);
        V len2;
        Vec3<V> h = reflection_half_vector_h(wo, wi, active, &len2);
        V denom = mfd.D_denom(h, active, len2) *
                  mfd.G_denom(cos_o, cos_i, mfd.smith_root(wo), mfd.smith_root(wi));
        Spectrum<V, NC> fr = fresnel_over_scaled(abs(dot(wo, h)), len2, denom);
        if constexpr (is_packet_v<A>) active &= !smooth;
        for (int c = 0; c < NC; ++c) fr[c] = zero_unless(active, fr[c]);
        return fr;
    }

    bool is_smooth() const { return mfd.effectively_smooth(); }

    template <typename V>
    BSDFSample<V, NC> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode mode, uint8_t sample_flags) const {
        if constexpr (is_packet_v<A>) {  // per-lane alphas: each lane's own case
            const Mask<V> smooth = mfd.effectively_smooth();
            if (all(smooth)) return sample_smooth(wo, uc, mode, sample_flags);
            if (none(smooth)) return sample_rough(wo, uc, u, mode, sample_flags);
            return select_sample(smooth, sample_smooth(wo, uc, mode, sample_flags),
                                 sample_rough(wo, uc, u, mode, sample_flags));
        } else {
            return is_smooth() ? sample_smooth(wo, uc, mode, sample_flags) : sample_rough(wo, uc, u, mode, sample_flags);
        }
    }

    // Delta mirror: f = Fr / |cos_i|, discrete probability 1.
    template <typename V>
    BSDFSample<V, NC> sample_smooth(const Vec3<V> &wo, V /*uc*/, TransportMode, uint8_t sample_flags) const {
        BSDFSample<V, NC> s;
        bool allowed = (sample_flags & RT_Reflection) != 0;
        s.wi = Vec3<V>(-wo.x, -wo.y, wo.z);
        V cos_i = DeltaAbsCos(s.wi);
        s.f = fresnel_over(cos_i, cos_i);
        s.pdf = V(1);
        s.flags = SpecularReflection;
        s.valid = Mask<V>(allowed); // cos_i >= the smallest normal number (DeltaAbsCos), even for a NaN wo
        return s;
    }

    // Sample a visible normal on wo's side and mirror wo about it. pdf = 1 / (D_denom P) with
    // P = 2 (cos_o + R_o), f = F / (D_denom G_denom) (core/microfacet.h). Written in the sampled
    // normal m = wm |m| unnormalized (Sample_wm_h), as f() is in h: the mirror direction
    // 2 (wo.m) m / |m|^2 - wo, D_denom(m) = D_denom(wm) |m|^4, fresnel_over_scaled.
    template <typename V>
    BSDFSample<V, NC> sample_rough(const Vec3<V> &wo, V /*uc*/, Point2<V> u, TransportMode, uint8_t sample_flags) const {
        BSDFSample<V, NC> s;
        V len2;
        Vec3<V> m = mfd.Sample_wm_h(wo, u, &len2);
        V wo_m = dot(wo, m);
        Vec3<V> wi = reflect_about_h(wo, m, wo_m, len2);
        V cos_o = AbsCosTheta(wo), cos_i = AbsCosTheta(wi);
        // SameHemisphere is strict: cos_o > 0 and cos_i > 0.
        Mask<V> active = Mask<V>((sample_flags & RT_Reflection) != 0) & SameHemisphere(wo, wi);
        V dd = mfd.D_denom(m, active, len2); // D = 0 there: f = pdf = 0, an invalid sample
        V root_o = mfd.smith_root(wo);
        s.pdf = select(active, sqr(len2) / (dd * mfd.pdf_denom(wo, m, cos_o, root_o)), V(0));
        s.f = fresnel_over_scaled(abs(wo_m), len2, dd * mfd.G_denom(cos_o, cos_i, root_o, mfd.smith_root(wi)));
        s.wi = wi;
        s.flags = GlossyReflection;
        s.valid = active;
        return s;
    }

    // Visible-normal density mapped through the reflection Jacobian 1 / (4 |wo.wm|):
    // G1(wo) D(wm) / (4 cos_o) = 1 / (D_denom(wm) 2 (cos_o + R_o)) = |h|^4 / (D_denom(h) 2 (cos_o
    // + R_o)) with h = wo + wi never normalized (D_denom with len2). 1 division, 1 square root.
    template <typename V>
    V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        const auto smooth = mfd.effectively_smooth();
        if (all(smooth)) return V(0); // a delta lobe (as f)
        Mask<V> active = SameHemisphere(wo, wi) &
                         Mask<V>((sample_flags & RT_Reflection) != 0);
        if constexpr (is_packet_v<A>) active &= !smooth;
        V len2;
        Vec3<V> h = reflection_half_vector_h(wo, wi, active, &len2);
        V dd = mfd.D_denom(h, active, len2);
        V p = sqr(len2) / (dd * mfd.pdf_denom(wo, h, AbsCosTheta(wo), mfd.smith_root(wo)));
        return select(active, p, V(0));
    }

    void regularize() { mfd.regularize(); }
};

// The Fresnel variants under their own names (the bindings and the renderer register each).
template <typename F> using ConductorSchlickBxDF = ConductorBxDF<F, ConductorFresnel::Schlick>;
template <typename F> using ConductorF82BxDF = ConductorBxDF<F, ConductorFresnel::F82>;

} // namespace bsdfkit
