// Normalized-Fresnel exit lobe of a subsurface (BSSRDF) boundary (pbrt-v4 NormalizedFresnelBxDF;
// d'Eon & Irving 2011, "A quantized-diffusion model", eq. for S_w; Jensen et al. 2001).
//   eta   relative IOR of the boundary, inside / outside (> 0)
// f = (1 - Fr(cos wi, eta)) / (c pi), c = 1 - 2 FresnelMoment1(1 / eta), on wo's side; cos wi is
// signed (pbrt-v4), so below the surface Fr uses 1 / eta. Radiance mode multiplies by eta^2
// (pbrt-v4's adjoint correction). The normalisation makes the Importance-mode albedo 1 for wo
// above the surface: pbrt-v4's FresnelMoment1(x) fits int_0^1 Fr(mu, 1/x) mu dmu (checked by
// quadrature in the tests), so c = 1 - 2 int_0^1 Fr(mu, eta) mu dmu. Cosine-weighted sampling.
#pragma once
#include <array>

#include "../core/bsdf_sample.h"
#include "../core/fresnel.h"
#include "../core/frame.h"
#include "../core/sampling.h"

namespace bsdfkit {

template <typename F> struct NormalizedFresnelSpectral;  // its spectral form (batch_spectral.h / spectral/)

// pbrt-v4 FresnelMoment1: polynomial fit of the first Fresnel moment, int_0^1 Fr(mu, 1/eta) mu dmu.
// T: double, or a packet of double (per lane, spectral mode: batch_spectral.h).
template <typename T> inline T FresnelMoment1(T eta) {
    T e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    T below = T(0.45966) - T(1.73965) * eta + T(3.37668) * e2 - T(3.904945) * e3 + T(2.49277) * e4 - T(0.68441) * e5;
    T above = T(-4.61686) + T(11.1136) * eta - T(10.4646) * e2 + T(5.11455) * e3 - T(1.27198) * e4 + T(0.12746) * e5;
    return select(eta < T(1), below, above);
}

struct NormalizedFresnelParams {
    double eta = 1.33;
    template <class V> void fields(V &&v) { v("eta", eta); }
};

// C: the parameters' type, F; or Packet<F> for spectral packets (eta(lambda) per lane: lanes()).
template <typename F, typename C = F> struct NormalizedFresnelBxDF {
    using Params = NormalizedFresnelParams;
    static constexpr const char *Name = "NormalizedFresnel";
    using Spectral = NormalizedFresnelSpectral<F>;  // its spectral form (core/bxdf.h)

    C eta;
    C inv_c_pi;  // 1 / (c pi)
    C eta2;      // Radiance-mode factor

    static NormalizedFresnelBxDF make(const Params &p) { return from_eta(p.eta); }
    // From eta in double (D: double, or a packet of double giving C = Packet<F>).
    template <typename D> static NormalizedFresnelBxDF from_eta(const D &e) {
        D c = D(1.0) - D(2.0) * FresnelMoment1(D(1.0) / e);
        return {C(e), C(D(1.0) / (c * D(3.14159265358979323846))), C(e * e)};
    }

    uint8_t flags() const { return DiffuseReflection; }

    // The model runs on packets in the batch kernels (batch.h): every method is written once on
    // the evaluation type V (F, or a packet of F; core/simd.h).
    static constexpr bool Vectorized = true;

    // (1 - Fr) / (c pi) [eta^2] as the Fresnel transmittance's numerator over its denominator
    // (core/fresnel.h FrDielectricRatio): 1 division.
    template <typename V> Spectrum<V> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode mode) const {
        V r, t, den;
        FrDielectricRatio(CosTheta(wi), eta, &r, &t, &den);
        C scale = mode == TransportMode::Radiance ? inv_c_pi * eta2 : inv_c_pi;
        return Spectrum<V>(select(SameHemisphere(wo, wi), t * V(scale) / den, V(0)));
    }

    template <typename V>
    BSDFSample<V> sample_f(const Vec3<V> &wo, V /*uc*/, Point2<V> u, TransportMode mode, uint8_t sample_flags) const {
        BSDFSample<V> s;
        Vec3<V> wi = SampleCosineHemisphere(u);
        wi.z = select(wo.z < V(0), -wi.z, wi.z);  // wo's side
        s.wi = wi;
        s.pdf = select(SameHemisphere(wo, wi), CosineHemispherePDF(AbsCosTheta(wi)), V(0));
        s.f = f(wo, wi, mode);
        s.flags = typename BSDFSample<V>::Flags(DiffuseReflection);
        s.valid = Mask<V>((sample_flags & RT_Reflection) != 0) & (s.pdf > V(0));
        return s;
    }

    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        Mask<V> ok = SameHemisphere(wo, wi) & Mask<V>((sample_flags & RT_Reflection) != 0);
        return select(ok, CosineHemispherePDF(AbsCosTheta(wi)), V(0));
    }

    void regularize() {}
};

} // namespace bsdfkit
