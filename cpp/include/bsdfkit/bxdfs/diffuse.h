// Lambertian reflection, two-sided (pbrt-v4 DiffuseBxDF).
//   reflectance  R per channel, in [0, 1]
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/frame.h"
#include "../core/sampling.h"

namespace bsdfkit {

template <template <typename, int, typename> class M, typename F> struct ColourSpectral;  // batch_spectral.h

// S: the parameters' scalar type, double (core/math.h param_t; a Dual for gradients, core/dual.h).
// N, Col: the colours' channel count and type (4 and double or Packet<double> in spectral mode,
// core/math.h colour_param_t; the generic spectral form ColourSpectral rebinds them).
template <typename S = double, int N = 3, typename Col = S> struct DiffuseParamsT {
    std::array<Col, N> reflectance{Col(0.5), Col(0.5), Col(0.5)};
    template <class V> void fields(V &&v) { v("reflectance", reflectance); }
    template <int N2, typename Col2> using WithColours = DiffuseParamsT<S, N2, Col2>;
};
using DiffuseParams = DiffuseParamsT<>;

// NC: channels (3 RGB; 4 in spectral mode, one per wavelength, built per element from the
// parameters evaluated at that element's wavelengths: core/spectral.h, batch_spectral.h).
// C: the channel values' type, F; or Packet<F> for a spectral packet (a value per lane).
template <typename F, int NC = 3, typename C = F> struct DiffuseBxDF {
    using Params = DiffuseParamsT<param_t<F>, NC, colour_param_t<F, C>>;
    static constexpr const char *Name = "Diffuse";
    using Spectral = ColourSpectral<DiffuseBxDF, F>;  // its spectral form (core/bxdf.h): the generic one
    static constexpr int GradColumns = 4;  // eval_grad columns at most
    Spectrum<C, NC> R;

    static DiffuseBxDF make(const Params &p) { return {to_channels<C>(p.reflectance)}; }

    uint8_t flags() const { return R.is_black() ? Unset : DiffuseReflection; }

    // Runs on packets in the batch kernels (batch.h; core/simd.h). No divisions or square
    // roots in f and pdf; sample: 1 division (the concentric map's ratio) and 1 square root.
    static constexpr bool Vectorized = true;

    template <typename V> Spectrum<V, NC> R_over_pi() const {
        Spectrum<V, NC> r;
        for (int c = 0; c < NC; ++c) r[c] = V(R[c] * InvPi<F>);
        return r;
    }

    // f = R / pi on the side of wo, 0 across the surface.
    template <typename V> Spectrum<V, NC> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode) const {
        return select(SameHemisphere(wo, wi), R_over_pi<V>(), Spectrum<V, NC>(V(0)));
    }

    template <typename V>
    BSDFSample<V, NC> sample_f(const Vec3<V> &wo, V /*uc*/, Point2<V> u, TransportMode /*mode*/,
                               uint8_t sample_flags) const {
        BSDFSample<V, NC> s;
        Vec3<V> wi = SampleCosineHemisphere(u);
        wi.z = select(wo.z < V(0), -wi.z, wi.z); // two-sided: sample wo's side
        s.wi = wi;
        // wi is on wo's side unless one of them lies on the horizon: folded into the pdf
        // (0 = invalid).
        s.pdf = select(SameHemisphere(wo, wi), CosineHemispherePDF(AbsCosTheta(wi)), V(0));
        s.f = R_over_pi<V>();
        s.flags = DiffuseReflection;
        s.valid = Mask<V>((sample_flags & RT_Reflection) != 0) & (s.pdf > V(0));
        return s;
    }

    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        V p = select(SameHemisphere(wo, wi), CosineHemispherePDF(AbsCosTheta(wi)), V(0));
        return keep_or_zero(p, (sample_flags & RT_Reflection) != 0);
    }

    void regularize() {}
};

} // namespace bsdfkit
