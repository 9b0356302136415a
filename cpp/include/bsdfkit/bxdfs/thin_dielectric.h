// Thin dielectric slab: specular reflection plus straight-through transmission, summing the
// inter-reflections inside the slab without absorption (pbrt-v4 ThinDielectricBxDF).
//   eta   relative IOR of the slab (> 0)
// The ray leaves into the medium it came from, so the sample's eta is 1 and no 1/eta^2 applies.
#pragma once
#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/fresnel.h"
#include "../core/sampling.h"

namespace bsdfkit {

template <typename F> struct ThinDielectricSpectral;  // its spectral form (batch_spectral.h / spectral/)

struct ThinDielectricParams {
    double eta = 1.5;
    template <class V> void fields(V &&v) { v("eta", eta); }
};

// Eta: eta's type, F; or Packet<F> for a dispersive slab on a spectral packet (eta per lane).
template <typename F, typename Eta = F> struct ThinDielectricBxDF {
    using Params = ThinDielectricParams;
    static constexpr const char *Name = "ThinDielectric";
    using Spectral = ThinDielectricSpectral<F>;  // its spectral form (core/bxdf.h)
    Eta eta;

    static ThinDielectricBxDF make(const Params &p) { return {F(p.eta)}; }

    uint8_t flags() const { return Reflection | Transmission | Specular; }

    // Runs on packets in the batch kernels (batch.h; core/simd.h): every method is a template
    // on the evaluation type V (F, or a packet of F). sample: 2 divisions, 1 square root.
    static constexpr bool Vectorized = true;

    // Delta lobes only: f and pdf are 0 for every given pair (pbrt-v4).
    template <typename V> Spectrum<V> f(const Vec3<V> &, const Vec3<V> &, TransportMode) const {
        return Spectrum<V>(V(0));
    }
    template <typename V> V pdf(const Vec3<V> &, const Vec3<V> &, TransportMode, uint8_t) const { return V(0); }

    // The slab's reflectance R' and transmittance T' = 1 - R' at |cos| = cos_o as numerators
    // over one denominator: R' = rs / den, T' = ts / den. The geometric series of
    // inter-reflections R' = R + T^2 R / (1 - R^2) (pbrt-v4 ThinDielectricBxDF) with T = 1 - R
    // is 2 R / (1 + R), and T' = (1 - R) / (1 + R); with the interface's R = r / d, T = t / d
    // (FrDielectricRatio, r + t = d) they are 2 r / (d + r) and t / (d + r). T' from t keeps
    // full relative precision where R -> 1; no division here (eta is a scalar: the index-matched
    // test is uniform). R = 1 (grazing, or total internal
    // reflection for eta < 1) gives r = d: R' = 1, T' = 0.
    template <typename V, typename E> static void slab_ratio(V cos_o, E eta, V *rs, V *ts, V *den) {
        V r, t, d;
        FrDielectricRatio(cos_o, eta, &r, &t, &d);
        slab_terms(r, t, d, eta, rs, ts, den);
    }
    // The slab's numerators from the interface's r, t over d (R = r / d, T = t / d).
    template <typename V, typename E> static void slab_terms(V r, V t, V d, E eta, V *rs, V *ts, V *den) {
        *rs = r + r;
        *ts = t;
        // index-matched: r = 0, T' = 1 exactly (t = d only to rounding); per lane for a packet eta
        if constexpr (is_packet_v<E>) *ts = select(eta == E(1), d, t);
        else if (eta == E(1)) *ts = d;
        *den = d + r;
    }
    // R' alone (one division). Also used per wavelength in spectral mode (batch_spectral.h).
    template <typename V, typename E> static V slab_reflectance(V cos_o, E eta) {
        V rs, ts, den;
        slab_ratio(cos_o, eta, &rs, &ts, &den);
        return rs / den;
    }

    // Lobe choice with probabilities proportional to R' and T' (restricted by sample_flags), so
    // the common 1 / den cancels from the choice and the pdf: pr, pt are the numerators, one
    // reciprocal of pr + pt serves both. f = R' / |cos_i| (or T') in one division.
    template <typename V>
    BSDFSample<V> sample_f(const Vec3<V> &wo, V uc, Point2<V>, TransportMode, uint8_t sample_flags) const {
        BSDFSample<V> s;
        V cos_i = DeltaAbsCos(wo); // |wi.z| = |wo.z| for both lobes
        V rs, ts, den, pr, pt;
        {
            // slab_ratio with the interface's terms from outside (|cos| > 0 on every lane the
            // acceptance rule keeps: wo.z = 0 is rejected there), without FrDielectricRatio's side
            // and grazing selects; the same formulas for a per-lane eta (spectral packets) as for a
            // scalar one
            V r, t, d;
            FrDielectricRatioScaledAbove(AbsCosTheta(wo), V(1), eta, &r, &t, &d);
            slab_terms(r, t, d, eta, &rs, &ts, &den);
        }
        restrict_lobes(rs, ts, sample_flags, &pr, &pt);
        V sum = pr + pt;
        Mask<V> active = sum > V(0);
        V inv_sum = V(1) / select(active, sum, V(1));
        // ChooseFirstLobe's rule with pr / (pr + pt) as pr * inv_sum (core/sampling.h).
        Mask<V> reflect = (pr > V(0)) & ((pt <= V(0)) | (uc < pr * inv_sum));
        s.wi = Vec3<V>(-wo.x, -wo.y, select(reflect, wo.z, -wo.z));
        s.f = Spectrum<V>(select(reflect, rs, ts) / (den * cos_i));
        s.pdf = select(reflect, pr, pt) * inv_sum;
        s.flags = lobe_flag<V>(SpecularReflection, !reflect);
        s.eta = V(1);
        s.valid = active;
        return s;
    }

    void regularize() {}
};

} // namespace bsdfkit
