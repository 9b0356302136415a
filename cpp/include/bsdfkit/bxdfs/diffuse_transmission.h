// Lambertian reflection plus Lambertian transmission (pbrt-v4 DiffuseTransmissionBxDF).
//   reflectance  R per channel, transmittance  T per channel, each in [0, 1]
// Symmetric: the transport mode does not change the value.
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/frame.h"
#include "../core/sampling.h"

namespace bsdfkit {

template <template <typename, int, typename> class M, typename F> struct ColourSpectral;  // batch_spectral.h

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
// N, Col: the colours' channel count and type (DiffuseParamsT).
template <typename S = double, int N = 3, typename Col = S> struct DiffuseTransmissionParamsT {
    std::array<Col, N> reflectance{Col(0.25), Col(0.25), Col(0.25)}, transmittance{Col(0.25), Col(0.25), Col(0.25)};
    template <class V> void fields(V &&v) {
        v("reflectance", reflectance);
        v("transmittance", transmittance);
    }
    template <int N2, typename Col2> using WithColours = DiffuseTransmissionParamsT<S, N2, Col2>;
};
using DiffuseTransmissionParams = DiffuseTransmissionParamsT<>;

// NC: channels (3 RGB; 4 in spectral mode, see DiffuseBxDF). The lobe choice uses the largest
// channel, as pbrt-v4's MaxComponentValue over the sampled wavelengths.
// C: the channel values' type, F; or Packet<F> for a spectral packet (a value per lane, and so
// per-lane lobe weights).
template <typename F, int NC = 3, typename C = F> struct DiffuseTransmissionBxDF {
    using Params = DiffuseTransmissionParamsT<param_t<F>, NC, colour_param_t<F, C>>;
    static constexpr const char *Name = "DiffuseTransmission";
    using Spectral = ColourSpectral<DiffuseTransmissionBxDF, F>;  // its spectral form (core/bxdf.h): the generic one
    static constexpr int GradColumns = 8;  // eval_grad columns at most
    Spectrum<C, NC> R, T;

    static DiffuseTransmissionBxDF make(const Params &p) {
        return {to_channels<C>(p.reflectance), to_channels<C>(p.transmittance)};
    }

    uint8_t flags() const {
        return uint8_t((R.is_black() ? Unset : DiffuseReflection) | (T.is_black() ? Unset : DiffuseTransmission));
    }

    // Runs on packets in the batch kernels (batch.h; core/simd.h): every method is a template
    // on the evaluation type V (F, or a packet of F). The lobe probabilities depend on the
    // parameters and sample_flags only, so their normalization is one scalar division per call
    // (LobeWeights); per element: f and pdf no division, sample 1 division (the concentric
    // map's ratio) and 1 square root.
    static constexpr bool Vectorized = true;

    template <typename V> Spectrum<V, NC> over_pi(const Spectrum<C, NC> &a) const {
        Spectrum<V, NC> r;
        for (int c = 0; c < NC; ++c) r[c] = V(a[c] * InvPi<F>);
        return r;
    }

    // f = R / pi on the side of wo, T / pi across the surface.
    template <typename V> Spectrum<V, NC> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode) const {
        return select(SameHemisphere(wo, wi), over_pi<V>(R), over_pi<V>(T));
    }

    // Lobe probabilities from the largest channel, restricted by sample_flags: pr, pt
    // unnormalized, the reflection threshold pr / (pr + pt) of ChooseFirstLobe, and the pdf
    // factors cr = pr / (pi (pr + pt)), ct likewise (0 when pr + pt = 0).
    // (Per lane when C is a packet.)
    struct LobeWeights {
        C pr, pt, first, cr, ct;
        Mask<C> any;
    };
    LobeWeights lobe_weights(uint8_t sample_flags) const {
        LobeWeights w;
        restrict_lobes(R.max_component(), T.max_component(), sample_flags, &w.pr, &w.pt);
        C sum = w.pr + w.pt;
        w.any = sum > C(0);
        C inv = select(w.any, C(1) / select(w.any, sum, C(1)), C(0));
        w.first = w.pr * inv;
        C k = InvPi<F> * inv;
        w.cr = w.pr * k;
        w.ct = w.pt * k;
        return w;
    }

    template <typename V>
    BSDFSample<V, NC> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode, uint8_t sample_flags) const {
        LobeWeights lw = lobe_weights(sample_flags);
        BSDFSample<V, NC> s;
        // ChooseFirstLobe (core/sampling.h) with its ratio computed once.
        Mask<V> reflect = Mask<V>(lw.pr > C(0)) & (Mask<V>(lw.pt <= C(0)) | (uc < V(lw.first)));
        Vec3<V> wi = SampleCosineHemisphere(u);
        // reflection stays on wo's side, transmission goes to the other side
        Mask<V> flip = (wo.z < V(0)) ^ !reflect;
        wi.z = select(flip, -wi.z, wi.z);
        s.wi = wi;
        s.pdf = AbsCosTheta(wi) * select(reflect, V(lw.cr), V(lw.ct));
        // The chosen lobe's f: f(wo, wi) wherever the sample survives (wi.z != 0, wo.z != 0).
        s.f = select(reflect, over_pi<V>(R), over_pi<V>(T));
        s.flags = lobe_flag<V>(DiffuseReflection, !reflect);
        s.valid = Mask<V>(lw.any);
        return s;
    }

    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        LobeWeights lw = lobe_weights(sample_flags);
        return AbsCosTheta(wi) * select(SameHemisphere(wo, wi), V(lw.cr), V(lw.ct));
    }

    void regularize() {}
};

} // namespace bsdfkit
