// Spectral mode of the array kernels (issue 15; docs/SPECTRAL.md): eval / pdf / sample / albedo
// with a wavelength input, 4 wavelengths (nm) per element, broadcast with the directions.
// f and albedo carry one value per wavelength; pdf stays one value per element.
//
// Each model family has a spectral adapter (below): its parameters as SpectralParam
// (core/spectral.h) plus the wavelength-independent ones. Per element, the adapter evaluates the
// parameters at the element's 4 wavelengths and runs the model's own per-element code: the RGB
// models with 4 channels instead of 3 (DiffuseBxDF<F, 4>, ConductorBxDF<F, FR, 4>, ...), the
// dielectrics with the hero wavelength's eta (plus the other wavelengths' Fresnel terms where
// the direction is shared, see DielectricSpectral). Bodies of the models do not change.
//
// Two paths. The scalar path runs one element at a time: the model instance is built per element
// from the parameters at its wavelengths (every adapter has it; the renderer uses it). The packet
// path (adapters with `kPackets`, below) runs kPacketWidth elements at a time on Packet<F> with
// the padded tail of batch.h: the parameters are evaluated per lane (SpectralParam::lanes, in
// double, the same operations as the scalar path) and the model is instantiated with per-lane
// channel values (DiffuseBxDF<F, 4, Packet<F>>, ConductorBxDF<F, FR, 4, Packet<F>>,
// DielectricBxDF<F, Packet<F>>, ...), the same model code as RGB mode. Per element both paths
// compute the same operations; they agree bit for bit except where packet math differs from
// libm (the rough models' visible-normal sampling: sincos; tests/test_spectral_packets.py).
// Adapters without `kPackets` (the split-channel ones, the other helpers' families) and
// parameters a packet model cannot take (see on_packets()) stay on the scalar path.
//
// Determinism: element i's results depend only on element i's inputs (and, in albedo, on the
// seed and its indices), so they are bit-identical for any thread count and array position.
// Kept apart from batch.h so that the RGB kernels' translation units do not recompile for it.
#pragma once
#include <atomic>
#include <stdexcept>
#include <cstdint>
#include <vector>

#include "batch.h"
#include "bxdfs/conductor.h"
#include "bxdfs/dielectric.h"
#include "bxdfs/diffuse.h"
#include "bxdfs/diffuse_transmission.h"
#include "bxdfs/filament.h"
#include "bxdfs/layered_analytic.h"
#include "bxdfs/normalized_fresnel.h"
#include "bxdfs/plastic.h"
#include "bxdfs/thin_dielectric.h"
#include "core/spectral.h"

namespace bsdfkit {

// ---- Adapters. Each has: dispersive(), f(wo, wi, lambda, mode) (BSDF-level rules applied),
// pdf(wo, wi, lambda, mode, sf), sample(wo, uc, u, lambda, mode, sf, &terminated) (bsdf_sample's
// rules: an invalid sample has f = pdf = 0 and wi = +z). lambda: the element's 4 wavelengths.
// Each is its model's `Spectral` form (core/bxdf.h) and is built by
//   template <class A> static X make(const Params &p, const A &a)
// from the model's RGB Params (the RGB projection, for what stays wavelength-independent) and
// `a`, the binding's named inputs: a.param(name) the SpectralParam of each of kFields,
// a.flag(name) / a.number(name) / a.template table<T>(name) the few extra inputs a model needs.

// The 4 wavelengths of kPacketWidth elements: l[i] holds wavelength i of every lane (nm, float64).
struct LambdaLanes {
    Packet<double> l[kSpectralN];
};

// Families whose spectral model is the RGB model with 4 channels: Derived::at(lambda) builds it.
// The packet path (Derived::kPackets): Derived::lanes(lam) builds it with per-lane channel values.
template <typename Derived, typename F> struct PerElementModel {
    bool dispersive() const { return false; }
    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode) const {
        return bsdf_f(self().at(lam), wo, wi, mode);
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(self().at(lam), wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F uc, Point2<F> u, const double *lam, TransportMode mode, uint8_t sf,
                            bool *terminated) const {
        *terminated = false;
        return bsdf_sample(self().at(lam), wo, uc, u, mode, sf);
    }

    // ---- Packet path (instantiated only for a Derived with lanes()).
    using P = Packet<F>;
    bool on_packets() const { return true; }
    Spectrum<P, 4> f(const Vec3<P> &wo, const Vec3<P> &wi, const LambdaLanes &lam, TransportMode mode) const {
        return bsdf_f(self().lanes(lam), wo, wi, mode);
    }
    P pdf(const Vec3<P> &wo, const Vec3<P> &wi, const LambdaLanes &lam, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(self().lanes(lam), wo, wi, mode, sf);
    }
    // model_ok = true: these models' sample_f already honours sample_flags, and a model whose
    // flags() are Unset at an element's wavelengths (a reflectance that is 0 at all 4) samples
    // f = 0, which the acceptance rule rejects as the scalar path's flags() test does.
    BSDFSample<P, 4> sample(const Vec3<P> &wo, P uc, Point2<P> u, const LambdaLanes &lam, TransportMode mode,
                            uint8_t sf, Mask<P> *terminated) const {
        *terminated = Mask<P>(false);
        return accepted_sample(self().lanes(lam).sample_f(wo, clamp_uniform(uc), clamp_uniform(u), mode, sf), wo, true);
    }

  private:
    const Derived &self() const { return static_cast<const Derived &>(*this); }
};

// ---- The generic spectral form (parameter kinds): a model whose wavelength-dependent
// parameters are exactly its colour fields (std::array<S, 3> in Params; every other field a
// scalar or a knob) is its own spectral form. Per element its make() runs on the Params with
// each colour at the element's 4 wavelengths (Params::WithColours<4, double>), so the model is
// M<F, 4>; on packets, with each colour per lane (WithColours<4, Packet<double>>, the model
// M<F, 4, Packet<F>>). The model: a template M<F, NC, C> whose Params template takes the colour
// channel count and type (DiffuseParamsT) and whose make() is written for any of them
// (to_channels<C>). Colours uplift as reflectances (RGBAlbedoSpectrum). The special cases keep
// their own forms below (the conductors' per-lane F0, the dielectrics' hero wavelength, the
// split-channel and measured forms).
template <template <typename, int, typename> class M, typename F>
struct ColourSpectral : PerElementModel<ColourSpectral<M, F>, F> {
    static constexpr bool kPackets = true;
    using Params = typename M<double, 3, double>::Params;
    static constexpr int kMaxColours = 8;
    static constexpr int kMaxFields = 64;  // params4's pointer table
    Params p;                            // the RGB Params: every field but the colours
    SpectralParam colour[kMaxColours];   // the colour fields, in field order
    int n_colours = 0;

    template <typename T> static constexpr bool is_colour = std::is_same_v<T, std::array<double, 3>>;

    // kFields, from the Params walk: the colour fields.
    static std::vector<SpectralField> spectral_fields() {
        std::vector<SpectralField> r;
        Params q;
        q.fields([&](const char *name, auto &f) {
            if constexpr (is_colour<std::decay_t<decltype(f)>>) r.push_back({name, "reflectance"});
        });
        return r;
    }
    template <class A> static ColourSpectral make(const Params &p, const A &a) {
        ColourSpectral s;
        s.p = p;
        Params q = p;
        int n_fields = 0;
        q.fields([&](const char *, auto &) { ++n_fields; });
        if (n_fields > kMaxFields) throw std::invalid_argument("ColourSpectral: too many Params fields");
        q.fields([&](const char *name, auto &f) {
            if constexpr (is_colour<std::decay_t<decltype(f)>>) {
                if (s.n_colours == kMaxColours) throw std::invalid_argument("ColourSpectral: too many colour fields");
                s.colour[s.n_colours++] = a.param(name);
            }
        });
        return s;
    }

    // The Params at 4 channels of type Col: colour i from value(colour[i]), the rest copied.
    template <typename Col, typename Value> typename Params::template WithColours<4, Col> params4(const Value &value) const {
        typename Params::template WithColours<4, Col> q;
        const void *src[kMaxFields];  // make() checked the count
        int n = 0, c = 0, i = 0;
        const_cast<Params &>(p).fields([&](const char *, auto &f) { src[n++] = &f; });
        q.fields([&](const char *, auto &f) {
            using T = std::decay_t<decltype(f)>;
            if constexpr (std::is_same_v<T, std::array<Col, 4>>) f = value(colour[c++]);
            else f = *static_cast<const T *>(src[i]);
            ++i;
        });
        return q;
    }

    M<F, 4, F> at(const double *lam) const {
        return M<F, 4, F>::make(params4<double>([&](const SpectralParam &sp) {
            return std::array<double, 4>{sp(lam[0]), sp(lam[1]), sp(lam[2]), sp(lam[3])};
        }));
    }
    M<F, 4, Packet<F>> lanes(const LambdaLanes &lam) const {
        using D = Packet<double>;
        return M<F, 4, Packet<F>>::make(params4<D>([&](const SpectralParam &sp) {
            return std::array<D, 4>{sp.lanes(lam.l[0]), sp.lanes(lam.l[1]), sp.lanes(lam.l[2]), sp.lanes(lam.l[3])};
        }));
    }
};

template <typename F, ConductorFresnel FR>
struct ConductorSpectralT : PerElementModel<ConductorSpectralT<F, FR>, F> {
    static constexpr bool kPackets = true;
    static constexpr SpectralField kFields[] = {{"eta", "unbounded"}, {"k", "unbounded"}};
    SpectralParam eta, k;
    Microfacet<F> mfd;
    template <class A> static ConductorSpectralT make(const ConductorParams &p, const A &a) {
        ConductorSpectralT s;
        s.eta = a.param("eta");
        s.k = a.param("k");
        s.mfd = p.template microfacet<F>();
        return s;
    }
    ConductorBxDF<F, FR, 4> at(const double *lam) const { return ConductorBxDF<F, FR, 4>(mfd, eta.at<F>(lam), k.at<F>(lam)); }
    // As the constructor, per lane: F0 and the F82 coefficient in double from eta, k at the
    // model's precision (unused by Exact).
    ConductorBxDF<F, FR, 4, Packet<F>> lanes(const LambdaLanes &lam) const {
        using P = Packet<F>;
        ConductorBxDF<F, FR, 4, P> m;
        m.mfd = mfd;
        m.eta = eta.at_lanes<P>(lam.l);
        m.k = k.at_lanes<P>(lam.l);
        if constexpr (FR != ConductorFresnel::Exact)
            for (int i = 0; i < kSpectralN; ++i) {
                Packet<double> e(m.eta[i]), kk(m.k[i]);
                m.f0[i] = P(ConductorF0(e, kk));
                m.f82_a[i] = P(ConductorF82A(e, kk));
            }
        return m;
    }
};
template <typename F> using ConductorSpectral = ConductorSpectralT<F, ConductorFresnel::Exact>;
template <typename F> using ConductorSchlickSpectral = ConductorSpectralT<F, ConductorFresnel::Schlick>;
template <typename F> using ConductorF82Spectral = ConductorSpectralT<F, ConductorFresnel::F82>;

// A 3-channel sample whose f is replaced by 4 per-wavelength values (direction, pdf, lobe and
// flags as sampled).
template <typename F> inline BSDFSample<F, 4> with_spectrum(const BSDFSample<F> &s, const Spectrum4<F> &f) {
    BSDFSample<F, 4> r;
    r.f = f;
    r.wi = s.wi;
    r.pdf = s.pdf;
    r.flags = s.flags;
    r.eta = s.eta;
    r.pdf_is_proportional = s.pdf_is_proportional;
    r.valid = s.valid;
    return r;
}

// Whether a sample (valid: wi.z != 0, wo.z != 0) crossed the surface. F: a scalar or a packet.
template <typename F, int N> inline Mask<F> crossed(const BSDFSample<F, N> &s, const Vec3<F> &wo) {
    return (s.wi.z < F(0)) ^ (wo.z < F(0));
}

// The hero wavelength lambda0's sample: m0's sample under pbrt-v4's BSDF-level rules (as
// bsdf_sample; model_ok: m0 has a lobe in sf), its f copied to the 4 channels; where
// `secondaries` and the sample is valid, channel i = 1..3 is fi(i, s) instead: wavelength i's
// value at the same direction. V: a scalar or a packet (per lane).
template <typename V, typename Model, typename Fi>
inline BSDFSample<V, 4> hero_sample(const Model &m0, bool model_ok, const Vec3<V> &wo, V uc, Point2<V> u,
                                    TransportMode mode, uint8_t sf, bool secondaries, const Fi &fi) {
    BSDFSample<V> s = accepted_sample(m0.sample_f(wo, clamp_uniform(uc), clamp_uniform(u), mode, sf), wo, model_ok);
    BSDFSample<V, 4> r = with_spectrum(s, Spectrum4<V>(s.f[0]));
    if (secondaries & bool(any(s.valid)))
        for (int i = 1; i < kSpectralN; ++i) r.f[i] = select(s.valid, fi(i, s), V(0));
    return r;
}

// Dielectric with eta(lambda). Not dispersive (eta constant): the RGB model at that eta, its
// value copied to the 4 wavelengths. Dispersive (docs/SPECTRAL.md):
//  - sample: the hero wavelength lambda0's model chooses the lobe and the direction; a
//    reflection keeps all 4 wavelengths (same direction, f per wavelength with eta(lambda_i));
//    a refraction keeps lambda0 only (f of lambda1..3 = 0, `terminated` set: the caller applies
//    pbrt-v4's TerminateSecondary to its wavelength pdfs);
//  - eval: a reflection pair per wavelength; a transmission pair is a refraction of lambda0
//    only (f of lambda1..3 = 0);
//  - pdf: lambda0's, in both cases (the density sample uses).
// Packets: a constant eta as the RGB model's (lane-uniform); a dispersive eta per lane
// (DielectricBxDF<F, Packet<F>>) when it never reaches 1 (eta_never_one: the index-matched case
// is a per-model switch of DielectricBxDF); otherwise the scalar path.
template <typename F> struct DielectricSpectral {
    static constexpr bool kPackets = true;
    static constexpr SpectralField kFields[] = {{"eta", "unbounded"}};
    SpectralParam eta;
    Microfacet<F> mfd;
    bool disp = false;
    // a.flag("dispersive"): eta is a non-constant spectrum (Python's rule, models/_spectral.py)
    template <class A> static DielectricSpectral make(const DielectricParams &p, const A &a) {
        DielectricSpectral s;
        s.eta = a.param("eta");
        s.mfd = p.template microfacet<F>();
        s.disp = a.flag("dispersive");
        return s;
    }

    bool dispersive() const { return disp; }
    DielectricBxDF<F> at1(double e) const { return {F(e), mfd}; }

    // Shared by both paths (V = F or Packet<F>; M: the hero's model, eta_i(i): eta at lambda_i).
    template <typename V, typename M, typename Models>
    Spectrum4<V> f_hero(const M &m0, const Vec3<V> &wo, const Vec3<V> &wi, TransportMode mode, const Models &model_i) const {
        Spectrum4<V> r(bsdf_f(m0, wo, wi, mode)[0]);
        if (disp) {
            Mask<V> reflect = CosTheta(wi) * CosTheta(wo) > V(0);
            for (int i = 1; i < kSpectralN; ++i) r[i] = select(reflect, bsdf_f(model_i(i), wo, wi, mode)[0], V(0));
        }
        return r;
    }
    template <typename V, typename M, typename EtaAt>
    BSDFSample<V, 4> sample_hero(const M &m0, bool model_ok, const Vec3<V> &wo, V uc, Point2<V> u, TransportMode mode,
                                 uint8_t sf, const EtaAt &eta_i, Mask<V> *terminated) const {
        const bool smooth = m0.is_smooth();
        BSDFSample<V, 4> r = hero_sample(m0, model_ok, wo, uc, u, mode, sf, disp, [&](int i, const BSDFSample<V> &s) {
            V e = eta_i(i), v;
            if (smooth) { // the delta mirror: Fresnel reflectance / |cos| (sample_smooth)
                V fr = FrDielectric(CosTheta(wo), e);
                if constexpr (!is_packet_v<V>) fr = keep_or_zero(fr, e != V(1)); // a packet eta is never 1
                v = fr / DeltaAbsCos(s.wi);
            } else {
                v = DielectricBxDF<F, V>{e, mfd}.f(wo, s.wi, mode)[0];
            }
            return select(crossed(s, wo), V(0), finite_or_zero(v));
        });
        *terminated = Mask<V>(disp) & r.valid & crossed(r, wo);
        return r;
    }

    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode) const {
        return f_hero(at1(eta(lam[0])), wo, wi, mode, [&](int i) { return at1(eta(lam[i])); });
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(at1(eta(lam[0])), wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F uc, Point2<F> u, const double *lam, TransportMode mode, uint8_t sf,
                            bool *terminated) const {
        DielectricBxDF<F> m0 = at1(eta(lam[0]));
        return sample_hero(m0, (m0.flags() & sf) != 0, wo, uc, u, mode, sf, [&](int i) { return F(eta(lam[i])); },
                           terminated);
    }

    // ---- Packet path
    using P = Packet<F>;
    // A table or constant eta whose values keep away from 1 (so does its piecewise-linear
    // interpolant, also at the model's precision).
    bool eta_never_one() const {
        if (eta.kind == SpectralParam::Constant) return std::abs(eta.c[0] - 1.0) > 1e-6;
        if (eta.kind != SpectralParam::Table) return false;
        bool above = true, below = true;
        for (int32_t j = 0; j < eta.n; ++j) {
            above &= eta.v[j] > 1.0 + 1e-6;
            below &= eta.v[j] < 1.0 - 1e-6;
        }
        return above | below;
    }
    bool on_packets() const { return disp ? eta_never_one() : eta.kind == SpectralParam::Constant; }
    DielectricBxDF<F, P> lanes1(const Packet<double> &l) const { return {P(eta.lanes(l)), mfd}; }

    Spectrum<P, 4> f(const Vec3<P> &wo, const Vec3<P> &wi, const LambdaLanes &lam, TransportMode mode) const {
        if (!disp) return Spectrum<P, 4>(bsdf_f(at1(eta.c[0]), wo, wi, mode)[0]);
        return f_hero(lanes1(lam.l[0]), wo, wi, mode, [&](int i) { return lanes1(lam.l[i]); });
    }
    P pdf(const Vec3<P> &wo, const Vec3<P> &wi, const LambdaLanes &lam, TransportMode mode, uint8_t sf) const {
        if (!disp) return bsdf_pdf(at1(eta.c[0]), wo, wi, mode, sf);
        return bsdf_pdf(lanes1(lam.l[0]), wo, wi, mode, sf);
    }
    BSDFSample<P, 4> sample(const Vec3<P> &wo, P uc, Point2<P> u, const LambdaLanes &lam, TransportMode mode,
                            uint8_t sf, Mask<P> *terminated) const {
        auto eta_i = [&](int i) { return P(eta.lanes(lam.l[i])); };
        if (!disp) {
            DielectricBxDF<F> m0 = at1(eta.c[0]);
            return sample_hero(m0, (m0.flags() & sf) != 0, wo, uc, u, mode, sf, eta_i, terminated);
        }
        // flags(): both lobes (eta != 1), Specular or Glossy
        return sample_hero(lanes1(lam.l[0]), (uint8_t(Reflection | Transmission) & sf) != 0, wo, uc, u, mode, sf,
                           eta_i, terminated);
    }
};

// Thin slab with eta(lambda). Both lobes keep their direction for every wavelength (mirror and
// straight through), so a dispersive slab never terminates: lambda0 chooses the lobe, f per
// wavelength is that lobe's slab reflectance / transmittance at eta(lambda_i). (pbrt-v4
// terminates the secondaries for any non-constant eta; here it is not needed.) Packets: eta per
// lane (ThinDielectricBxDF<F, Packet<F>>), any parameter.
template <typename F> struct ThinDielectricSpectral {
    static constexpr bool kPackets = true;
    static constexpr SpectralField kFields[] = {{"eta", "unbounded"}};
    SpectralParam eta;
    bool disp = false;
    template <class A> static ThinDielectricSpectral make(const ThinDielectricParams &, const A &a) {
        ThinDielectricSpectral s;
        s.eta = a.param("eta");
        s.disp = a.flag("dispersive");
        return s;
    }

    bool dispersive() const { return false; }
    ThinDielectricBxDF<F> at1(double e) const { return {F(e)}; }

    template <typename V, typename M, typename EtaAt>
    BSDFSample<V, 4> sample_hero(const M &m0, const Vec3<V> &wo, V uc, Point2<V> u, TransportMode mode, uint8_t sf,
                                 const EtaAt &eta_i) const {
        return hero_sample(m0, (m0.flags() & sf) != 0, wo, uc, u, mode, sf, disp, [&](int i, const BSDFSample<V> &s) {
            V Rs = ThinDielectricBxDF<F>::slab_reflectance(AbsCosTheta(wo), eta_i(i));
            return finite_or_zero(select(crossed(s, wo), V(1) - Rs, Rs) * (V(1) / DeltaAbsCos(s.wi)));
        });
    }

    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode) const {
        return Spectrum4<F>(bsdf_f(at1(eta(lam[0])), wo, wi, mode)[0]); // 0: delta lobes
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(at1(eta(lam[0])), wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F uc, Point2<F> u, const double *lam, TransportMode mode, uint8_t sf,
                            bool *terminated) const {
        *terminated = false;
        return sample_hero(at1(eta(lam[0])), wo, uc, u, mode, sf, [&](int i) { return F(eta(lam[i])); });
    }

    // ---- Packet path
    using P = Packet<F>;
    bool on_packets() const { return true; }
    ThinDielectricBxDF<F, P> lanes1(const Packet<double> &l) const { return {P(eta.lanes(l))}; }
    Spectrum<P, 4> f(const Vec3<P> &, const Vec3<P> &, const LambdaLanes &, TransportMode) const {
        return Spectrum<P, 4>(P(0)); // delta lobes (bsdf_f of the model: 0)
    }
    P pdf(const Vec3<P> &, const Vec3<P> &, const LambdaLanes &, TransportMode, uint8_t) const { return P(0); }
    BSDFSample<P, 4> sample(const Vec3<P> &wo, P uc, Point2<P> u, const LambdaLanes &lam, TransportMode mode,
                            uint8_t sf, Mask<P> *terminated) const {
        *terminated = Mask<P>(false);
        return sample_hero(lanes1(lam.l[0]), wo, uc, u, mode, sf, [&](int i) { return P(eta.lanes(lam.l[i])); });
    }
};

// ---- Split-channel adapters (Plastic, FilamentStandard, the analytic coated models): the RGB
// model's own per-element code with its colour channels carrying wavelengths. Per element, two
// copies of the RGB model `proto` get their per-channel fields set at (lambda0, lambda1, lambda2)
// and at lambda3 (all three channels); f is the first copy's 3 values and the second's first.
// What couples the channels in RGB mode (the lobe-choice weights from channel means or maxima,
// Filament's f90 from the sum of f0) is wavelength-independent here: it stays the proto's, set
// from the model's RGB projection or, where Mitsuba defines it spectrally, from the spectral
// mean (Plastic's specular sampling weight, set by the binding). So pdf is the proto's, one value
// per element, and for constant spectra every value equals the RGB model's bit for bit.
//
// Derived provides: `struct Chan` (one wavelength's per-channel values), `Chan chan(double
// lambda)`, `void put(M &, int c, const Chan &)`, and kSharedChoice: true when the copies choose
// the sample's lobe and direction exactly as proto (their channels do not enter the choice: the
// sample is the copies' own, delta lobes included); false (FilamentStandard: its lobe weights
// read f0 per channel) takes proto's direction and evaluates f there (no delta lobes allowed).
template <typename F, int N = 3> inline Spectrum4<F> join_channels(const Spectrum<F, N> &a, const Spectrum<F, N> &b) {
    Spectrum4<F> r;
    r[0] = a[0];
    r[1] = a[1];
    r[2] = a[2];
    r[3] = b[0];
    return r;
}

template <typename Derived, typename F, typename M> struct SplitChannelModel {
    M proto;

    bool dispersive() const { return false; }

    void split(const double *lam, M *a, M *b) const {
        *a = proto;
        *b = proto;
        for (int c = 0; c < 3; ++c) self().put(*a, c, self().chan(lam[c]));
        auto c3 = self().chan(lam[3]);
        for (int c = 0; c < 3; ++c) self().put(*b, c, c3);
    }
    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode) const {
        M a, b;
        split(lam, &a, &b);
        return join_channels(bsdf_f(a, wo, wi, mode), bsdf_f(b, wo, wi, mode));
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(proto, wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F uc, Point2<F> u, const double *lam, TransportMode mode, uint8_t sf,
                            bool *terminated) const {
        *terminated = false;
        M a, b;
        split(lam, &a, &b);
        uc = clamp_uniform(uc);
        u = clamp_uniform(u);
        BSDFSample<F> s0;
        Spectrum4<F> f;
        if constexpr (Derived::kSharedChoice) {
            s0 = a.sample_f(wo, uc, u, mode, sf);
            f = join_channels(s0.f, b.sample_f(wo, uc, u, mode, sf).f);
        } else {
            s0 = proto.sample_f(wo, uc, u, mode, sf);
            f = join_channels(a.f(wo, s0.wi, mode), b.f(wo, s0.wi, mode));
        }
        // pbrt-v4's BSDF-level rules on the 4 values (as bsdf_sample)
        return accepted_sample(with_spectrum(s0, f), wo, (proto.flags() & sf) != 0);
    }

  private:
    const Derived &self() const { return static_cast<const Derived &>(*this); }
};

// Plastic: reflectance R(lambda) and specular_reflectance Ks(lambda); eta, alpha and the coating's
// tables are wavelength-independent (Mitsuba's plastic / roughplastic take a scalar IOR). The
// lobe weight w = mean Ks / (mean R + mean Ks) with spectral means over [360, 830] nm (Mitsuba's
// Texture::mean() in its spectral variants), set by the binding in proto.spec_weight.
template <typename F> struct PlasticSpectral : SplitChannelModel<PlasticSpectral<F>, F, PlasticBxDF<F>> {
    static constexpr bool kSharedChoice = true;  // the choice reads spec_weight, eta, the table
    static constexpr SpectralField kFields[] = {{"reflectance", "reflectance"},
                                                {"specular_reflectance", "reflectance"}};
    SpectralParam reflectance, specular;
    double fdr = 0, eta = 1.49;
    bool nonlinear = false;
    // a.number("spec_weight"): the lobe weight from the spectral means (Python computes it);
    // a.flag("has_diffuse"): the reflectance spectrum is not 0.
    template <class A> static PlasticSpectral make(const PlasticParams &p, const A &a) {
        double w = a.number("spec_weight");
        if (!(w >= 0 && w <= 1)) throw std::invalid_argument("spec_weight: must be in [0, 1]");
        PlasticTables tab = PlasticBxDF<double>::tables(p);
        PlasticSpectral s;
        s.proto = PlasticBxDF<F>::make(p, tab);
        s.proto.spec_weight = F(w);
        s.proto.has_diffuse = a.flag("has_diffuse");
        s.reflectance = a.param("reflectance");
        s.specular = a.param("specular_reflectance");
        s.fdr = PlasticBxDF<double>::is_rough(p) ? tab.fdr : FresnelDiffuseReflectance(1 / p.eta);
        s.eta = p.eta;
        s.nonlinear = p.nonlinear;
        return s;
    }
    struct Chan {
        double scale;  // R / (1 - {Fdr | R Fdr}) (PlasticBxDF::make)
        F Ks;
    };
    Chan chan(double l) const {
        double R = reflectance(l);
        return {R / (1 - (nonlinear ? R * fdr : fdr)), F(specular(l))};
    }
    void put(PlasticBxDF<F> &m, int c, const Chan &v) const {
        PlasticBxDF<F>::set_base(m, c, v.scale, eta);
        m.Ks[c] = v.Ks;
    }
};

// FilamentStandard (each lobe variant): base_color(lambda) and sheen_color(lambda); f0 and the
// diffuse colour per wavelength as per RGB channel (surface_colors). f90, the lobe weights and the
// sheen scaling's max(sheenColor) are the RGB projection's (Filament defines them on RGB).
template <typename F, bool Coat, bool Sheen>
struct FilamentStandardSpectralT
    : SplitChannelModel<FilamentStandardSpectralT<F, Coat, Sheen>, F, FilamentStandardKernel<F, Coat, Sheen>> {
    using Model = FilamentStandardT<F, Coat, Sheen>;
    static constexpr bool kSharedChoice = false;  // lobes() reads f0 per channel
    static constexpr SpectralField kFields[] = {{"base_color", "reflectance"}, {"sheen_color", "reflectance"}};
    SpectralParam base_color, sheen_color;
    FilamentStandardParams params;  // keeps the DFG table alive (proto points into it)
    template <class A> static FilamentStandardSpectralT make(const FilamentStandardParams &p, const A &a) {
        FilamentStandardSpectralT s;
        s.proto = Model::make(p);  // the kernel part
        s.params = p;
        s.base_color = a.param("base_color");
        s.sheen_color = a.param("sheen_color");
        return s;
    }
    struct Chan {
        F f0, diffuse, sheen;
    };
    Chan chan(double l) const {
        double f0, diffuse;
        Model::surface_colors(params, base_color(l), &f0, &diffuse);
        return {F(f0), F(diffuse), Sheen ? F(sheen_color(l)) : F(0)};
    }
    static void put(FilamentStandardKernel<F, Coat, Sheen> &m, int c, const Chan &v) {
        m.f0[c] = v.f0;
        m.diffuse_color[c] = v.diffuse;
        m.sheen_color[c] = v.sheen;
    }
};
template <typename F> using FilamentStandardSpectral = FilamentStandardSpectralT<F, false, false>;
template <typename F> using FilamentStandardCoatSpectral = FilamentStandardSpectralT<F, true, false>;
template <typename F> using FilamentStandardSheenSpectral = FilamentStandardSpectralT<F, false, true>;
template <typename F> using FilamentStandardCoatSheenSpectral = FilamentStandardSpectralT<F, true, true>;

// The analytic coated models: the base (a diffuse reflectance, or the metal's eta and k relative
// to the coating) and the medium's albedo per wavelength, with the internal-reflection sum
// M = 1 / (1 - rho_b Fdr_int t_d^2) per wavelength (AnalyticLayeredBxDF::set_layer); the coating's
// IOR, roughness and the thickness are wavelength-independent, and so is the lobe choice
// (base_weight and q_cos from the RGB projection: kSharedChoice).
// Fdr_int and t_d as set_layer computes them (from proto's eta and thickness), and M as it does.
struct AnalyticInternal {
    double fdr_int = 0, td = 0;
    template <typename F> static AnalyticInternal of(const DielectricBxDF<F> &top, F thickness) {
        return {DiffuseFresnel(1.0 / double(top.eta)), DiffuseSlabTransmittance(double(thickness))};
    }
    double multi(double rho) const { return 1.0 / (1.0 - rho * fdr_int * td * td); }
};

template <typename F>
struct CoatedDiffuseAnalyticSpectral
    : SplitChannelModel<CoatedDiffuseAnalyticSpectral<F>, F, CoatedDiffuseAnalyticBxDF<F>> {
    static constexpr bool kSharedChoice = true;
    static constexpr SpectralField kFields[] = {{"reflectance", "reflectance"}, {"albedo", "reflectance"}};
    SpectralParam reflectance, albedo;
    AnalyticInternal internal;
    template <class A> static CoatedDiffuseAnalyticSpectral make(const CoatedDiffuseParams &p, const A &a) {
        CoatedDiffuseAnalyticSpectral s;
        s.proto = CoatedDiffuseAnalyticBxDF<F>::make(p);
        s.internal = AnalyticInternal::of(s.proto.top, s.proto.thickness);
        s.reflectance = a.param("reflectance");
        s.albedo = a.param("albedo");
        return s;
    }
    struct Chan {
        F R, multi, albedo;
    };
    Chan chan(double l) const {
        double R = reflectance(l);
        return {F(R), F(internal.multi(R)), F(albedo(l))};
    }
    static void put(CoatedDiffuseAnalyticBxDF<F> &m, int c, const Chan &v) {
        m.bottom.R[c] = v.R;
        m.multi[c] = v.multi;
        m.albedo[c] = v.albedo;
    }
};

template <typename F>
struct CoatedConductorAnalyticSpectral
    : SplitChannelModel<CoatedConductorAnalyticSpectral<F>, F, CoatedConductorAnalyticBxDF<F>> {
    static constexpr bool kSharedChoice = true;
    static constexpr SpectralField kFields[] = {
        {"conductor_eta", "unbounded"}, {"conductor_k", "unbounded"}, {"albedo", "reflectance"}};
    SpectralParam eta, k, albedo;
    double interface_eta = 1.5;
    AnalyticInternal internal;
    double gl_x[64] = {}, gl_w[64] = {};  // CosineWeightedMean's Gauss-Legendre rule, computed once
    template <class A> static CoatedConductorAnalyticSpectral make(const CoatedConductorParams &p, const A &a) {
        CoatedConductorAnalyticSpectral s;
        s.proto = CoatedConductorAnalyticBxDF<F>::make(p);
        s.internal = AnalyticInternal::of(s.proto.top, s.proto.thickness);
        s.eta = a.param("conductor_eta");
        s.k = a.param("conductor_k");
        s.albedo = a.param("albedo");
        s.interface_eta = p.interface_eta;
        s.init_quadrature();
        return s;
    }

    void init_quadrature() { GaussLegendre(64, gl_x, gl_w); }
    struct Chan {
        F eta, k, multi, albedo;
    };
    Chan chan(double l) const {
        // the metal relative to the coating and its smooth hemispherical albedo
        // 2 int F mu dmu (CoatedConductorAnalyticBxDF::make: CosineWeightedMean on [0, 1], the same
        // arithmetic, with the rule's nodes computed once instead of per call)
        double e = eta(l) / interface_eta, kk = k(l) / interface_eta;
        double rho = 0.0;
        for (int i = 0; i < 64; ++i) {
            double mu = 0.0 + (1.0 - 0.0) * 0.5 * (gl_x[i] + 1);
            rho += 2.0 * FrComplex(mu, e, kk) * mu * 0.5 * (1.0 - 0.0) * gl_w[i];
        }
        return {F(e), F(kk), F(internal.multi(rho)), F(albedo(l))};
    }
    static void put(CoatedConductorAnalyticBxDF<F> &m, int c, const Chan &v) {
        m.bottom.eta[c] = v.eta;
        m.bottom.k[c] = v.k;
        m.multi[c] = v.multi;
        m.albedo[c] = v.albedo;
    }
};

// NormalizedFresnel with eta(lambda): one scalar model per wavelength (its f is the same in every
// channel); the cosine-weighted sampling does not depend on eta, so pdf and the direction are
// lambda0's model's and f_i is model i's value at that direction.
template <typename F> struct NormalizedFresnelSpectral {
    static constexpr bool kPackets = true;
    static constexpr SpectralField kFields[] = {{"eta", "unbounded"}};
    SpectralParam eta;
    template <class A> static NormalizedFresnelSpectral make(const NormalizedFresnelParams &, const A &a) {
        NormalizedFresnelSpectral s;
        s.eta = a.param("eta");
        return s;
    }

    bool dispersive() const { return false; }
    static NormalizedFresnelBxDF<F> at1(double e) { return NormalizedFresnelBxDF<F>::make({e}); }

    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode) const {
        Spectrum4<F> r;
        for (int i = 0; i < kSpectralN; ++i) r[i] = bsdf_f(at1(eta(lam[i])), wo, wi, mode)[0];
        return r;
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(at1(eta(lam[0])), wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F uc, Point2<F> u, const double *lam, TransportMode mode, uint8_t sf,
                            bool *terminated) const {
        *terminated = false;
        NormalizedFresnelBxDF<F> m0 = at1(eta(lam[0]));
        return hero_sample(m0, (m0.flags() & sf) != 0, wo, uc, u, mode, sf, true, [&](int i, const BSDFSample<F> &s) {
            return bsdf_f(at1(eta(lam[i])), wo, s.wi, mode)[0];
        });
    }

    // ---- Packet path: one model per wavelength with eta per lane (its 1 / (c pi) per lane).
    using P = Packet<F>;
    bool on_packets() const { return true; }
    NormalizedFresnelBxDF<F, P> lanes1(const Packet<double> &l) const {
        return NormalizedFresnelBxDF<F, P>::from_eta(eta.lanes(l));
    }
    Spectrum<P, 4> f(const Vec3<P> &wo, const Vec3<P> &wi, const LambdaLanes &lam, TransportMode mode) const {
        Spectrum<P, 4> r;
        for (int i = 0; i < kSpectralN; ++i) r[i] = bsdf_f(lanes1(lam.l[i]), wo, wi, mode)[0];
        return r;
    }
    P pdf(const Vec3<P> &wo, const Vec3<P> &wi, const LambdaLanes &lam, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(lanes1(lam.l[0]), wo, wi, mode, sf); // cosine-weighted: eta unread
    }
    BSDFSample<P, 4> sample(const Vec3<P> &wo, P uc, Point2<P> u, const LambdaLanes &lam, TransportMode mode,
                            uint8_t sf, Mask<P> *terminated) const {
        *terminated = Mask<P>(false);
        NormalizedFresnelBxDF<F, P> m0 = lanes1(lam.l[0]);
        return hero_sample(m0, (m0.flags() & sf) != 0, wo, uc, u, mode, sf, true, [&](int i, const BSDFSample<P> &s) {
            return bsdf_f(lanes1(lam.l[i]), wo, s.wi, mode)[0];
        });
    }
};

// ---- Kernels. Strides: so / si / sl = 3 / 3 / 4 for full arrays, 0 for one broadcast row.
// Wavelengths are float64 for both precisions (the parameters are evaluated in double).

struct SpectralBadCounts : BadCounts {
    std::atomic<int64_t> lam{0};  // wavelengths not finite or outside [360, 830] nm
};

template <typename F> struct SpectralSampleOut {
    F *wi, *f, *pdf, *eta;
    uint8_t *flags;
    bool *valid, *proportional, *terminated;
};

inline int64_t load_lambda(const double *p, int64_t i, int64_t sl, double (&l)[kSpectralN]) {
    int64_t bad = 0;
    for (int c = 0; c < kSpectralN; ++c) {
        l[c] = p[i * sl + c];
        bad += !valid_wavelength(l[c]);
    }
    return bad > 0;
}

// ---- The packet path's building blocks (batch.h's packet loop and lane loads / stores).

// Whether an adapter has the packet path (`static constexpr bool kPackets = true;` and the
// packet overloads of f / pdf / sample plus on_packets(), whether its parameters allow it).
template <typename SM, typename = void> struct spectral_packets : std::false_type {};
template <typename SM>
struct spectral_packets<SM, std::void_t<decltype(SM::kPackets)>> : std::bool_constant<SM::kPackets> {};
template <typename SM> inline bool use_packets(const SM &m, bool packets) {
    if constexpr (spectral_packets<SM>::value) return packets & m.on_packets();
    else return false;
}

// A row array of directions (stride 3) or one broadcast row (stride 0) as batch.h's Dirs.
template <typename F> inline Dirs<F> spectral_dirs(const F *p, int64_t stride) {
    return {p, stride == 0 ? DirLayout::One : DirLayout::Rows, 0};
}

// Lanes [i, i + cnt) of the wavelength rows (stride sl: 4, or 0 for one broadcast row); past cnt,
// 550 nm. Adds the elements with a wavelength outside [360, 830] nm (or NaN) to bad.lam.
inline void load_lambda_lanes(const double *p, int64_t sl, int64_t i, int64_t cnt, LambdaLanes &lam,
                              SpectralBadCounts &bad) {
    using D = Packet<double>;
    static constexpr double pad[kSpectralN] = {550.0, 550.0, 550.0, 550.0};
    if (sl == 0) load_lanes<0, kSpectralN>(p, i, cnt, pad, lam.l);
    else load_lanes<kSpectralN, kSpectralN>(p, i, cnt, pad, lam.l);
    Mask<D> ok(true);
    for (int c = 0; c < kSpectralN; ++c) ok = ok & (lam.l[c] >= D(kLambdaMin)) & (lam.l[c] <= D(kLambdaMax));
    int64_t nbad = int64_t(drjit::count(!ok));
    if (nbad > 0) bad.lam += sl == 0 ? cnt : nbad;  // a broadcast row: once per element
}

template <typename F> inline void store4_lanes(F *p, int64_t i, int64_t cnt, const Spectrum<Packet<F>, 4> &s) {
    const Packet<F> v[4] = {s[0], s[1], s[2], s[3]};
    store_lanes<4>(p, i, cnt, v);
}

// sample on packets: the adapter returns the accepted sample (pbrt-v4's rules applied) and the
// terminated mask; the uniforms are checked on the loaded packets and the byte outputs (flags,
// pdf_is_proportional, terminated, valid) written from registers, as batch.h's
// sample_chunk_packet.
template <typename SM, typename F>
void sample_spectral_packets(const SM &m, const F *wo, int64_t so, const F *uc, const F *u, const double *lam,
                             int64_t sl, int64_t n, TransportMode mode, uint8_t sf, const SpectralSampleOut<F> &out,
                             int nthreads, SpectralBadCounts &bad) {
    using P = Packet<F>;
    const Dirs<F> dwo = spectral_dirs(wo, so);
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        int64_t bo = 0, buc = 0, bu = 0;
        const DenormalsFlushedFor<SM> ftz;
        const SM mloc = m;
        for (int64_t i = b; i < e; i += kW<F>) {
            int64_t cnt = std::min(kW<F>, e - i);
            Vec3<P> o = load_dirs<kAnyLayout>(dwo, i, cnt);
            bo += count_not_unit(o);
            P c, uv[2];
            load_uniforms(uc, u, i, cnt, &c, uv, &buc, &bu);
            LambdaLanes l;
            load_lambda_lanes(lam, sl, i, cnt, l, bad);
            Mask<P> term;
            BSDFSample<P, 4> s = mloc.sample(o, c, Point2<P>{uv[0], uv[1]}, l, mode, sf, &term);
            store4_lanes(out.f, i, cnt, s.f);
            store3_lanes(out.wi, i, cnt, s.wi);
            store1_lanes(out.pdf, i, cnt, s.pdf);
            store1_lanes(out.eta, i, cnt, s.eta);
            store_bytes(out.flags, i, cnt, s.flags);
            store_bytes(reinterpret_cast<uint8_t *>(out.proportional), i, cnt, mask_to_float<P>(s.pdf_is_proportional));
            store_bytes(reinterpret_cast<uint8_t *>(out.terminated), i, cnt, mask_to_float<P>(term));
            // accepted samples have pdf > 0, rejected ones 0
            store_bytes(reinterpret_cast<uint8_t *>(out.valid), i, cnt, mask_to_float<P>(s.pdf > F(0)));
        }
        bad.wo += so == 0 ? (bo > 0 ? e - b : 0) : bo;
        bad.uc += buc;
        bad.u += bu;
    });
}

// The per-element loop of spectral eval and pdf (the scalar adapters, and the packet adapters with
// packets = false): per chunk a local model, per element the pair and its wavelengths loaded and
// the bad inputs counted, then store(model, wo, wi, lambda, i) computes and writes element i.
template <typename SM, typename F, typename Store>
void spectral_pair_scalar_loop(const SM &m, const F *wo, int64_t so, const F *wi, int64_t si, const double *lam,
                               int64_t sl, int64_t n, int nthreads, SpectralBadCounts &bad, const Store &store) {
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        int64_t bo = 0, bi = 0, bl = 0;
        const DenormalsFlushedFor<SM> ftz;
        const SM mloc = m;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o(wo[i * so], wo[i * so + 1], wo[i * so + 2]), w(wi[i * si], wi[i * si + 1], wi[i * si + 2]);
            double l[kSpectralN];
            bl += load_lambda(lam, i, sl, l);
            bo += check_dir(&o);
            bi += check_dir(&w);
            store(mloc, o, w, l, i);
        }
        bad.wo += bo;
        bad.wi += bi;
        bad.lam += bl;
    });
}

// packets = false keeps the scalar path (tests compare the two; tests/test_spectral_packets.py).
template <typename SM, typename F>
void eval_spectral_batch(const SM &m, const F *wo, int64_t so, const F *wi, int64_t si, const double *lam, int64_t sl,
                         int64_t n, TransportMode mode, F *out, int nthreads, SpectralBadCounts &bad,
                         bool packets = true) {
    if constexpr (spectral_packets<SM>::value) {
        if (use_packets(m, packets)) {
            pair_packet_loop<kAnyLayout, kAnyLayout>(
                m, spectral_dirs(wo, so), spectral_dirs(wi, si), n, nthreads, bad,
                store_out([out](int64_t i, int64_t cnt, const auto &v) { store4_lanes(out, i, cnt, v); }),
                [&](const SM &mm, const auto &o, const auto &w, int64_t i, int64_t cnt) {
                    LambdaLanes l;
                    load_lambda_lanes(lam, sl, i, cnt, l, bad);
                    return mm.f(o, w, l, mode);
                });
            return;
        }
    }
    spectral_pair_scalar_loop(m, wo, so, wi, si, lam, sl, n, nthreads, bad,
                              [&](const SM &mm, const Vec3<F> &o, const Vec3<F> &w, const double *l, int64_t i) {
                                  Spectrum4<F> v = mm.f(o, w, l, mode);
                                  for (int c = 0; c < kSpectralN; ++c) out[kSpectralN * i + c] = v[c];
                              });
}

template <typename SM, typename F>
void pdf_spectral_batch(const SM &m, const F *wo, int64_t so, const F *wi, int64_t si, const double *lam, int64_t sl,
                        int64_t n, TransportMode mode, uint8_t sf, F *out, int nthreads, SpectralBadCounts &bad,
                        bool packets = true) {
    if constexpr (spectral_packets<SM>::value) {
        if (use_packets(m, packets)) {
            pair_packet_loop<kAnyLayout, kAnyLayout>(
                m, spectral_dirs(wo, so), spectral_dirs(wi, si), n, nthreads, bad,
                store_out([out](int64_t i, int64_t cnt, const auto &v) { store1_lanes(out, i, cnt, v); }),
                [&](const SM &mm, const auto &o, const auto &w, int64_t i, int64_t cnt) {
                    LambdaLanes l;
                    load_lambda_lanes(lam, sl, i, cnt, l, bad);
                    return mm.pdf(o, w, l, mode, sf);
                });
            return;
        }
    }
    spectral_pair_scalar_loop(m, wo, so, wi, si, lam, sl, n, nthreads, bad,
                              [&](const SM &mm, const Vec3<F> &o, const Vec3<F> &w, const double *l, int64_t i) {
                                  out[i] = mm.pdf(o, w, l, mode, sf);
                              });
}

template <typename SM, typename F>
void sample_spectral_batch(const SM &m, const F *wo, int64_t so, const F *uc, const F *u, const double *lam, int64_t sl,
                           int64_t n, TransportMode mode, uint8_t sf, const SpectralSampleOut<F> &out, int nthreads,
                           SpectralBadCounts &bad, bool packets = true) {
    if constexpr (spectral_packets<SM>::value) {
        if (use_packets(m, packets)) {
            sample_spectral_packets(m, wo, so, uc, u, lam, sl, n, mode, sf, out, nthreads, bad);
            return;
        }
    }
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        int64_t bo = 0, bl = 0;
        int64_t buc = count_bad_uniforms(uc, b, e), bu = count_bad_uniforms(u, 2 * b, 2 * e);
        const DenormalsFlushedFor<SM> ftz;
        const SM mloc = m;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o(wo[i * so], wo[i * so + 1], wo[i * so + 2]);
            double l[kSpectralN];
            bl += load_lambda(lam, i, sl, l);
            bo += check_dir(&o);
            bool term = false;
            BSDFSample<F, 4> s = mloc.sample(o, uc[i], Point2<F>{u[2 * i], u[2 * i + 1]}, l, mode, sf, &term);
            for (int c = 0; c < kSpectralN; ++c) out.f[kSpectralN * i + c] = s.f[c];
            out.wi[3 * i] = s.wi.x;
            out.wi[3 * i + 1] = s.wi.y;
            out.wi[3 * i + 2] = s.wi.z;
            out.pdf[i] = s.pdf;
            out.eta[i] = s.eta;
            out.flags[i] = s.flags;
            out.valid[i] = s.valid;
            out.proportional[i] = s.pdf_is_proportional;
            out.terminated[i] = term & bool(s.valid);
        }
        bad.wo += bo;
        bad.lam += bl;
        bad.uc += buc;
        bad.u += bu;
    });
}

// Directional albedo per wavelength, rho_i(wo) = E[f_i |cos wi| / pdf], with the uniforms of
// the RGB albedo (albedo_batch: counter hash of seed, wo index, sample index; fixed blocks):
// deterministic for any thread count. A dispersive model is run once per wavelength with that
// wavelength as the hero (lambda0), so each rho_i includes its refracted light (a terminated
// secondary would drop it).
template <typename SM, typename F>
void albedo_spectral_batch(const SM &m, const F *wo, int64_t n_wo, const double *lam, int64_t sl, int64_t n_samples,
                           uint64_t seed, TransportMode mode, F *out, int nthreads, SpectralBadCounts &bad) {
    const int64_t block = 4096;
    int64_t nblocks = (n_samples + block - 1) / block;
    std::vector<double> partial(size_t(n_wo * nblocks * kSpectralN), 0.0);
    const bool disp = m.dispersive();
    parallel_chunks(n_wo * nblocks, nthreads, 1, [&](int64_t item, int64_t) {
        int64_t j = item / nblocks, blk = item % nblocks;
        const DenormalsFlushedFor<SM> ftz;
        Vec3<F> o = load3<F, 3>(wo, j);
        double l[kSpectralN];
        int64_t bl = load_lambda(lam, j, sl, l);
        int64_t bad_o = check_dir(&o);
        if (blk == 0) {
            bad.wo += bad_o;
            bad.lam += bl;
        }
        int64_t s0 = blk * block, s1 = std::min(n_samples, s0 + block);
        double acc[kSpectralN] = {0, 0, 0, 0};
        for (int hero = 0; hero < (disp ? kSpectralN : 1); ++hero) {
            double lh[kSpectralN] = {l[hero], l[(hero + 1) % 4], l[(hero + 2) % 4], l[(hero + 3) % 4]};
            for (int64_t k = s0; k < s1; ++k) {
                uint64_t h = hash3(seed, uint64_t(j), uint64_t(k));
                F uc = uniform_from_bits<F>(mix64(h ^ 1)), u0 = uniform_from_bits<F>(mix64(h ^ 2)),
                  u1 = uniform_from_bits<F>(mix64(h ^ 3));
                bool term;
                BSDFSample<F, 4> s = m.sample(o, uc, Point2<F>{u0, u1}, lh, mode, uint8_t(RT_All), &term);
                F w = s.valid ? AbsCosTheta(s.wi) / s.pdf : F(0);
                if (disp) acc[hero] += double(s.f[0] * w);
                else
                    for (int c = 0; c < kSpectralN; ++c) acc[c] += double(s.f[c] * w);
            }
        }
        for (int c = 0; c < kSpectralN; ++c) partial[size_t(item * kSpectralN + c)] = acc[c];
    });
    for (int64_t j = 0; j < n_wo; ++j)
        for (int c = 0; c < kSpectralN; ++c) {
            double sum = 0;
            for (int64_t blk = 0; blk < nblocks; ++blk) sum += partial[size_t((j * nblocks + blk) * kSpectralN + c)];
            out[kSpectralN * j + c] = n_samples > 0 ? F(sum / double(n_samples)) : F(0);
        }
}

} // namespace bsdfkit
