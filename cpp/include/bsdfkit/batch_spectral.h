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
        BSDFSample<F, 4> r;
        r.f = Spectrum4<F>(s.f[0]);
        r.wi = s.wi;
        r.pdf = s.pdf;
        r.flags = s.flags;
        r.eta = s.eta;
        r.pdf_is_proportional = s.pdf_is_proportional;
        r.valid = s.valid;
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
        BSDFSample<F, 4> r;
        r.f = Spectrum4<F>(s.f[0]);
        r.wi = s.wi;
        r.pdf = s.pdf;
        r.flags = s.flags;
        r.eta = s.eta;
        r.valid = s.valid;
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
