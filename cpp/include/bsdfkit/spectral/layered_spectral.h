// Spectral mode of the stochastic layered models (issue 15; pbrt-v4 LayeredBxDF carries a
// SampledSpectrum through its random walk): CoatedDiffuse / CoatedConductor with
// method="stochastic" and 4 wavelengths per element.
//
// Per element the adapter builds the walk with a 4-channel base and throughput
// (LayeredBxDF<F, Bottom4, 4>, bxdfs/layered.h): the base's reflectance, or the metal's eta and k
// relative to the coating, and the medium's albedo at the element's 4 wavelengths. The coating
// (one IOR, one roughness), the thickness, g and the estimator settings are
// wavelength-independent. Every wavelength follows the same path (one hashed generator per call,
// seeded from (seed, wo, wi) as in RGB mode): the interfaces and the base evaluate per
// wavelength, Russian roulette reads the largest of the 4 throughputs (pbrt-v4's
// MaxComponentValue). So with a grey spectrum every channel equals the RGB model's bit for bit;
// with a coloured one each wavelength is an unbiased estimate of its own f (the paths are shared,
// as pbrt-v4's hero wavelengths share theirs).
// has_albedo (the walk samples the medium) is set from the whole albedo spectrum (the binding),
// not from the 4 values, so that the estimator is the same for every element.
#pragma once
#include "../batch_spectral.h"
#include "../bxdfs/layered.h"

namespace bsdfkit {

template <typename F> struct CoatedDiffuseSpectral : PerElementModel<CoatedDiffuseSpectral<F>, F> {
    using Walk = LayeredBxDF<F, DiffuseBxDF<F, 4>, 4>;
    Walk proto;  // coating, layer and estimator settings (base and albedo set per element)
    static constexpr SpectralField kFields[] = {{"reflectance", "reflectance"}, {"albedo", "reflectance"}};
    SpectralParam reflectance, albedo;
    // a.flag("has_albedo"): the walk samples the medium (the whole albedo spectrum is not 0)
    template <class A> static CoatedDiffuseSpectral make(const CoatedDiffuseParams &p, const A &a) {
        CoatedDiffuseSpectral s;
        s.proto.top = CoatedDiffuseBxDF<F>::make(p).top;
        s.proto.set_layer(p.layer);
        s.proto.has_albedo = a.flag("has_albedo");
        s.reflectance = a.param("reflectance");
        s.albedo = a.param("albedo");
        return s;
    }

    Walk at(const double *lam) const {
        Walk m = proto;
        m.bottom.R = reflectance.at<F>(lam);
        m.albedo = albedo.at<F>(lam);
        return m;
    }
};

template <typename F> struct CoatedConductorSpectral : PerElementModel<CoatedConductorSpectral<F>, F> {
    using Walk = LayeredBxDF<F, ConductorBxDF<F, ConductorFresnel::Exact, 4>, 4>;
    Walk proto;  // coating, the metal's roughness (proto.bottom.mfd), layer and estimator settings
    static constexpr SpectralField kFields[] = {
        {"conductor_eta", "unbounded"}, {"conductor_k", "unbounded"}, {"albedo", "reflectance"}};
    SpectralParam eta, k, albedo;
    double interface_eta = 1.5;
    template <class A> static CoatedConductorSpectral make(const CoatedConductorParams &p, const A &a) {
        CoatedConductorSpectral s;
        s.proto.top = CoatedConductorBxDF<F>::make(p).top;
        s.proto.set_layer(p.layer);
        s.proto.has_albedo = a.flag("has_albedo");
        s.proto.bottom.mfd = Microfacet<F>(F(p.conductor_alpha_x), F(p.conductor_alpha_y), p.masking);
        s.eta = a.param("conductor_eta");
        s.k = a.param("conductor_k");
        s.albedo = a.param("albedo");
        s.interface_eta = p.interface_eta;
        return s;
    }

    Walk at(const double *lam) const {
        Walk m = proto;
        // the metal relative to the coating (CoatedConductorBxDF::make, pbrt-v4 PR #343)
        Spectrum4<F> e, kk;
        for (int i = 0; i < kSpectralN; ++i) {
            e[i] = F(eta(lam[i]) / interface_eta);
            kk[i] = F(k(lam[i]) / interface_eta);
        }
        m.bottom = ConductorBxDF<F, ConductorFresnel::Exact, 4>(proto.bottom.mfd, e, kk);
        m.albedo = albedo.at<F>(lam);
        return m;
    }
};

} // namespace bsdfkit
