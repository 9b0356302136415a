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
// Why scalar (one element at a time) rather than packets: the model instance is built per
// element from per-element parameters (a table gather, a sigmoid, the conductor's per-wavelength
// setup), whereas the packet path keeps one model for a whole packet with lane-uniform
// parameters. Making the models' parameters per lane is the next step (see docs/SPECTRAL.md);
// bench/SPECTRAL.md measures what the scalar path costs against RGB.
//
// Determinism: element i's results depend only on element i's inputs (and, in albedo, on the
// seed and its indices), so they are bit-identical for any thread count and array position.
// Kept apart from batch.h so that the RGB kernels' translation units do not recompile for it.
#pragma once
#include <atomic>
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

// Families whose spectral model is the RGB model with 4 channels: Derived::at(lambda) builds it.
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

  private:
    const Derived &self() const { return static_cast<const Derived &>(*this); }
};

template <typename F> struct DiffuseSpectral : PerElementModel<DiffuseSpectral<F>, F> {
    SpectralParam reflectance;
    DiffuseBxDF<F, 4> at(const double *lam) const { return {reflectance.at<F>(lam)}; }
};

template <typename F> struct DiffuseTransmissionSpectral : PerElementModel<DiffuseTransmissionSpectral<F>, F> {
    SpectralParam reflectance, transmittance;
    DiffuseTransmissionBxDF<F, 4> at(const double *lam) const {
        return {reflectance.at<F>(lam), transmittance.at<F>(lam)};
    }
};

template <typename F, ConductorFresnel FR>
struct ConductorSpectralT : PerElementModel<ConductorSpectralT<F, FR>, F> {
    SpectralParam eta, k;
    TrowbridgeReitz<F> mfd;
    ConductorBxDF<F, FR, 4> at(const double *lam) const { return ConductorBxDF<F, FR, 4>(mfd, eta.at<F>(lam), k.at<F>(lam)); }
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

// Dielectric with eta(lambda). Not dispersive (eta constant): the RGB model at that eta, its
// value copied to the 4 wavelengths. Dispersive (docs/SPECTRAL.md):
//  - sample: the hero wavelength lambda0's model chooses the lobe and the direction; a
//    reflection keeps all 4 wavelengths (same direction, f per wavelength with eta(lambda_i));
//    a refraction keeps lambda0 only (f of lambda1..3 = 0, `terminated` set: the caller applies
//    pbrt-v4's TerminateSecondary to its wavelength pdfs);
//  - eval: a reflection pair per wavelength; a transmission pair is a refraction of lambda0
//    only (f of lambda1..3 = 0);
//  - pdf: lambda0's, in both cases (the density sample uses).
template <typename F> struct DielectricSpectral {
    SpectralParam eta;
    TrowbridgeReitz<F> mfd;
    bool disp = false;

    bool dispersive() const { return disp; }
    DielectricBxDF<F> at1(double e) const { return {F(e), mfd}; }

    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode) const {
        Spectrum4<F> r(bsdf_f(at1(eta(lam[0])), wo, wi, mode)[0]);
        if (disp) {
            bool reflect = CosTheta(wi) * CosTheta(wo) > F(0);
            for (int i = 1; i < kSpectralN; ++i)
                r[i] = reflect ? bsdf_f(at1(eta(lam[i])), wo, wi, mode)[0] : F(0);
        }
        return r;
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(at1(eta(lam[0])), wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F uc, Point2<F> u, const double *lam, TransportMode mode, uint8_t sf,
                            bool *terminated) const {
        DielectricBxDF<F> m0 = at1(eta(lam[0]));
        BSDFSample<F> s = bsdf_sample(m0, wo, uc, u, mode, sf);
        BSDFSample<F, 4> r = with_spectrum(s, Spectrum4<F>(s.f[0]));
        *terminated = false;
        if (disp & bool(s.valid)) {
            if (s.flags & Transmission) {
                for (int i = 1; i < kSpectralN; ++i) r.f[i] = F(0);
                *terminated = true;
            } else {
                for (int i = 1; i < kSpectralN; ++i) {
                    double e = eta(lam[i]);
                    F v;
                    if (m0.is_smooth()) // the delta mirror: Fresnel reflectance / |cos| (sample_smooth)
                        v = keep_or_zero(FrDielectric(CosTheta(wo), F(e)), e != 1.0) / DeltaAbsCos(s.wi);
                    else
                        v = at1(e).f(wo, s.wi, mode)[0];
                    r.f[i] = finite_or_zero(v);
                }
            }
        }
        return r;
    }
};

// Thin slab with eta(lambda). Both lobes keep their direction for every wavelength (mirror and
// straight through), so a dispersive slab never terminates: lambda0 chooses the lobe, f per
// wavelength is that lobe's slab reflectance / transmittance at eta(lambda_i). (pbrt-v4
// terminates the secondaries for any non-constant eta; here it is not needed.)
template <typename F> struct ThinDielectricSpectral {
    SpectralParam eta;
    bool disp = false;

    bool dispersive() const { return false; }
    ThinDielectricBxDF<F> at1(double e) const { return {F(e)}; }

    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode) const {
        return Spectrum4<F>(bsdf_f(at1(eta(lam[0])), wo, wi, mode)[0]); // 0: delta lobes
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(at1(eta(lam[0])), wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F uc, Point2<F> u, const double *lam, TransportMode mode, uint8_t sf,
                            bool *terminated) const {
        BSDFSample<F> s = bsdf_sample(at1(eta(lam[0])), wo, uc, u, mode, sf);
        BSDFSample<F, 4> r = with_spectrum(s, Spectrum4<F>(s.f[0]));
        *terminated = false;
        if (disp & bool(s.valid)) {
            bool reflect = !(s.flags & Transmission);
            F inv_cos = F(1) / DeltaAbsCos(s.wi);
            for (int i = 1; i < kSpectralN; ++i) {
                F Rs = ThinDielectricBxDF<F>::slab_reflectance(AbsCosTheta(wo), F(eta(lam[i])));
                r.f[i] = finite_or_zero((reflect ? Rs : F(1) - Rs) * inv_cos);
            }
        }
        return r;
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
    SpectralParam reflectance, specular;
    double fdr = 0, eta = 1.49;
    bool nonlinear = false;
    struct Chan {
        F diffuse, Ks;
    };
    Chan chan(double l) const {
        double R = reflectance(l);
        // R / (1 - {Fdr | R Fdr}) / (pi eta^2) (PlasticBxDF::make)
        return {F(R / (1 - (nonlinear ? R * fdr : fdr)) * InvPi<double> / (eta * eta)), F(specular(l))};
    }
    static void put(PlasticBxDF<F> &m, int c, const Chan &v) {
        m.diffuse[c] = v.diffuse;
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
    SpectralParam base_color, sheen_color;
    FilamentStandardParams params;  // keeps the DFG table alive (proto points into it)
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
    SpectralParam reflectance, albedo;
    AnalyticInternal internal;
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
    SpectralParam eta, k, albedo;
    double interface_eta = 1.5;
    AnalyticInternal internal;
    double gl_x[64] = {}, gl_w[64] = {};  // CosineWeightedMean's Gauss-Legendre rule, computed once

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
    SpectralParam eta;

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
        BSDFSample<F> s = bsdf_sample(at1(eta(lam[0])), wo, uc, u, mode, sf);
        BSDFSample<F, 4> r = with_spectrum(s, Spectrum4<F>(s.f[0]));
        *terminated = false;
        if (s.valid)
            for (int i = 1; i < kSpectralN; ++i) r.f[i] = bsdf_f(at1(eta(lam[i])), wo, s.wi, mode)[0];
        return r;
    }
};

// ---- Kernels. Strides: so / si / sl = 3 / 3 / 4 for full arrays, 0 for one broadcast row.
// Wavelengths are float64 for both precisions (the parameters are evaluated in double).

struct SpectralBadCounts : BadCounts {
    std::atomic<int64_t> lam{0};  // wavelengths not finite or outside [360, 830] nm
};

inline int64_t load_lambda(const double *p, int64_t i, int64_t sl, double (&l)[kSpectralN]) {
    int64_t bad = 0;
    for (int c = 0; c < kSpectralN; ++c) {
        l[c] = p[i * sl + c];
        bad += !valid_wavelength(l[c]);
    }
    return bad > 0;
}

template <typename SM, typename F>
void eval_spectral_batch(const SM &m, const F *wo, int64_t so, const F *wi, int64_t si, const double *lam, int64_t sl,
                         int64_t n, TransportMode mode, F *out, int nthreads, SpectralBadCounts &bad) {
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        int64_t bo = 0, bi = 0, bl = 0;
        const SM mloc = m;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o(wo[i * so], wo[i * so + 1], wo[i * so + 2]), w(wi[i * si], wi[i * si + 1], wi[i * si + 2]);
            double l[kSpectralN];
            bl += load_lambda(lam, i, sl, l);
            bo += not_unit(o);
            bi += not_unit(w);
            Spectrum4<F> v = mloc.f(o, w, l, mode);
            for (int c = 0; c < kSpectralN; ++c) out[kSpectralN * i + c] = v[c];
        }
        bad.wo += bo;
        bad.wi += bi;
        bad.lam += bl;
    });
}

template <typename SM, typename F>
void pdf_spectral_batch(const SM &m, const F *wo, int64_t so, const F *wi, int64_t si, const double *lam, int64_t sl,
                        int64_t n, TransportMode mode, uint8_t sf, F *out, int nthreads, SpectralBadCounts &bad) {
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        int64_t bo = 0, bi = 0, bl = 0;
        const SM mloc = m;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o(wo[i * so], wo[i * so + 1], wo[i * so + 2]), w(wi[i * si], wi[i * si + 1], wi[i * si + 2]);
            double l[kSpectralN];
            bl += load_lambda(lam, i, sl, l);
            bo += not_unit(o);
            bi += not_unit(w);
            out[i] = mloc.pdf(o, w, l, mode, sf);
        }
        bad.wo += bo;
        bad.wi += bi;
        bad.lam += bl;
    });
}

template <typename F> struct SpectralSampleOut {
    F *wi, *f, *pdf, *eta;
    uint8_t *flags;
    bool *valid, *proportional, *terminated;
};

template <typename SM, typename F>
void sample_spectral_batch(const SM &m, const F *wo, int64_t so, const F *uc, const F *u, const double *lam, int64_t sl,
                           int64_t n, TransportMode mode, uint8_t sf, const SpectralSampleOut<F> &out, int nthreads,
                           SpectralBadCounts &bad) {
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        int64_t bo = 0, bl = 0;
        int64_t buc = count_bad_uniforms(uc, b, e), bu = count_bad_uniforms(u, 2 * b, 2 * e);
        const SM mloc = m;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o(wo[i * so], wo[i * so + 1], wo[i * so + 2]);
            double l[kSpectralN];
            bl += load_lambda(lam, i, sl, l);
            bo += not_unit(o);
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
        Vec3<F> o = load3<F, 3>(wo, j);
        double l[kSpectralN];
        int64_t bl = load_lambda(lam, j, sl, l);
        if (blk == 0) {
            bad.wo += not_unit(o);
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
