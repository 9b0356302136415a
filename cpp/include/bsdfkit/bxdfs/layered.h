// Layered BSDFs: a dielectric coating over a diffuse or conductor base with an optional
// homogeneous Henyey-Greenstein medium between them (pbrt-v4 LayeredBxDF<DielectricBxDF,
// DiffuseBxDF | ConductorBxDF, twoSided = true> = CoatedDiffuseBxDF / CoatedConductorBxDF;
// Guo, Hasan, Yan and Zhao 2018, "Position-free Monte Carlo simulation for arbitrary layered
// BSDFs"; pbrt-v4 book section 14.3).
//
//   top         DielectricBxDF, the coating interface (eta, GGX alpha), at z = thickness
//   bottom      DiffuseBxDF or ConductorBxDF, the base, at z = 0 (never transmissive)
//   thickness   slab thickness in mean free paths (sigma_t = 1), floored at FLT_MIN
//   albedo, g   single-scattering albedo (RGB) and HG asymmetry of the medium (g clamped to
//               +-0.99, the range where pbrt-v4's HG sampler is stable)
//   max_depth   longest random walk; n_samples  walks averaged per call; seed  realization
//
// f, sample_f and pdf are pbrt-v4's stochastic estimators (the book's f, Sample_f with
// pdf_is_proportional = true, and the approximate PDF mixed with 10 % of the uniform sphere
// density), run on a private generator seeded from a hash of (seed, wo, wi) (f), (seed, wi, wo)
// (pdf) or (seed, wo, uc, u) (sample_f): every result is a deterministic function of the call's
// inputs, independent of threads, chunking and array position. The bit patterns of the
// directions are hashed after adding +0.0, so -0.0 and +0.0 give the same stream. The
// generator is SplitMix64 (Steele et al. 2014), not pbrt's PCG32 + MurmurHash: the estimators
// are the same random variables, not the same realizations as pbrt's.
//
// The random walk is a data-dependent loop (its length depends on Russian roulette, the medium
// and the interfaces' samples), so these models do not vectorize across elements; the batch
// kernels run them element by element.
//
// Because the base never transmits, the exit interface of every contributing path is the top
// one (pbrt-v4's TT terms are empty): f and pdf are zero / uniform for wo and wi on opposite
// sides, and sample_f only returns reflection.
#pragma once
#include <array>
#include <cstdint>
#include <cstring>

#include "../core/bsdf.h"
#include "../core/rng.h"
#include "conductor.h"
#include "dielectric.h"
#include "diffuse.h"

namespace bsdfkit {

template <typename F> struct CoatedConductorSpectral;  // its spectral form (batch_spectral.h / spectral/)

template <typename F> struct CoatedDiffuseSpectral;  // its spectral form (batch_spectral.h / spectral/)

// ---------------------------------------------------------------- medium and walk helpers

// Henyey-Greenstein 1941 phase function in pbrt-v4's convention (wo, wi both pointing away
// from the scattering point, so g > 0 peaks at wi = -wo): (1 - g^2) / (4 pi (1 + g^2 + 2 g cos)^1.5).
template <typename F> inline F HenyeyGreenstein(F cos_theta, F g) {
    F denom = F(1) + g * g + F(2) * g * cos_theta;
    return F(0.25 * InvPi<double>) * (F(1) - g * g) / (denom * safe_sqrt(denom));
}

// Orthonormal basis around a unit v (Duff et al. 2017, "Building an orthonormal basis, revisited").
template <typename F> inline void CoordinateSystem(const Vec3<F> &v, Vec3<F> *a, Vec3<F> *b) {
    F sign = v.z < F(0) ? F(-1) : F(1);
    F k = F(-1) / (sign + v.z), c = v.x * v.y * k;
    *a = Vec3<F>(F(1) + sign * v.x * v.x * k, sign * c, -sign * v.x);
    *b = Vec3<F>(c, sign + v.y * v.y * k, -v.y);
}

// Inversion sampling of HG about wo (pbrt-v4 SampleHenyeyGreenstein); returns wi, *pdf = p.
template <typename F> inline Vec3<F> SampleHenyeyGreenstein(const Vec3<F> &wo, F g, Point2<F> u, F *pdf) {
    F cos_t = std::abs(g) < F(1e-3) ? F(1) - F(2) * u.x
                                     : F(-1) / (F(2) * g) *
                                           (F(1) + g * g - sqr((F(1) - g * g) / (F(1) + g - F(2) * g * u.x)));
    cos_t = clamp(cos_t, F(-1), F(1));
    F sin_t = safe_sqrt(F(1) - cos_t * cos_t), sp, cp;
    sincos_(F(2) * Pi<F> * u.y, &sp, &cp);
    Vec3<F> a, b;
    CoordinateSystem(wo, &a, &b);
    *pdf = HenyeyGreenstein(cos_t, g);
    return a * (sin_t * cp) + b * (sin_t * sp) + wo * cos_t;
}

// Veach's power heuristic with one sample per technique (pbrt-v4 PowerHeuristic).
template <typename F> inline F PowerHeuristic(F f, F g) {
    F f2 = f * f, s = f2 + g * g;
    return f2 > std::numeric_limits<F>::max() ? F(1) : (s > F(0) ? f2 / s : F(0));
}

// Beer-Lambert transmittance over a depth dz along w with sigma_t = 1 (pbrt-v4 LayeredBxDF::Tr).
template <typename F> inline F LayerTr(F dz, const Vec3<F> &w) {
    return std::abs(dz) <= F(std::numeric_limits<float>::min()) ? F(1) : std::exp(-std::abs(dz / w.z));
}

// The walk's private generator: SplitMix64 over a counter started at a hash of the inputs.
template <typename F> struct WalkRNG {
    uint64_t state;
    F operator()() { return uniform_from_bits<F>(mix64(state++)); }  // in [0, 1)
};

template <typename F> inline uint64_t float_bits(F x) {
    x = x + F(0);  // -0.0 -> +0.0
    if constexpr (sizeof(F) == 4) {
        uint32_t b;
        std::memcpy(&b, &x, 4);
        return b;
    } else {
        uint64_t b;
        std::memcpy(&b, &x, 8);
        return b;
    }
}
template <typename F> inline uint64_t hash_vec(uint64_t h, const Vec3<F> &w) {
    return hash3(h ^ float_bits(w.x), float_bits(w.y), float_bits(w.z));
}

// pbrt-v4's "!bs || !bs->f || bs->pdf == 0 || bs->wi.z == 0" test of an interface sample.
template <typename F, int N> inline bool usable(const BSDFSample<F, N> &s) {
    return s.valid & nonzero_mask(s.f) & (s.pdf > F(0)) & (s.wi.z != F(0));
}

inline TransportMode flip_mode(TransportMode m) {
    return m == TransportMode::Radiance ? TransportMode::Importance : TransportMode::Radiance;
}

// ---------------------------------------------------------------- parameters

// S: the continuous parameters' scalar type, double (a Dual for the gradients of the analytic
// method, layered_analytic.h; core/math.h param_t). The stochastic models use the double forms.
template <typename S = double> struct LayerParamsT {  // the medium and the estimator, shared by both models
    S thickness = 0.01;
    std::array<S, 3> albedo{0, 0, 0};
    S g = 0;
    int max_depth = 10;
    int n_samples = 1;
    int seed = 0;  // >= 0; an int field (core/bxdf.h), widened to 64 bits for hashing
    // MIS weight of the exit interface's transmission after a base / phase sample: pbrt-v4 uses
    // top.PDF(-w, wi) (the density of wi given the inner direction) against the sample's density
    // of the inner direction; false keeps that (the book's estimator, biased high with a rough
    // coat), true uses top.PDF(wi, -w) in the adjoint mode, the density of the same inner
    // direction under the NEE strategy, so the two MIS weights sum to one (unbiased).
    bool consistent_mis = false;

    template <class V> void fields(V &&v) {
        v("thickness", thickness);
        v("albedo", albedo);
        v("g", g);
        v("max_depth", max_depth);
        v("n_samples", n_samples);
        v("seed", seed);
        v("consistent_mis", consistent_mis);
    }
};
using LayerParams = LayerParamsT<>;

template <typename S = double> struct CoatedDiffuseParamsT {
    std::array<S, 3> reflectance{0.5, 0.5, 0.5};
    S eta = 1.5, alpha_x = 0, alpha_y = 0;
    Masking masking = Masking::Correlated;
    LayerParamsT<S> layer;

    template <class V> void fields(V &&v) {
        v("reflectance", reflectance);
        v("eta", eta);
        v("alpha_x", alpha_x);
        v("alpha_y", alpha_y);
        v("masking", masking);
        layer.fields(v);
    }
};
using CoatedDiffuseParams = CoatedDiffuseParamsT<>;

template <typename S = double> struct CoatedConductorParamsT {
    // absolute (vacuum-relative) IOR of the metal; make() divides both by interface_eta
    std::array<S, 3> conductor_eta{0.2, 0.92, 1.1}, conductor_k{3.9, 2.45, 2.14};
    S conductor_alpha_x = 0, conductor_alpha_y = 0;
    S interface_eta = 1.5, interface_alpha_x = 0, interface_alpha_y = 0;
    Masking masking = Masking::Correlated;
    LayerParamsT<S> layer;

    template <class V> void fields(V &&v) {
        v("conductor_eta", conductor_eta);
        v("conductor_k", conductor_k);
        v("conductor_alpha_x", conductor_alpha_x);
        v("conductor_alpha_y", conductor_alpha_y);
        v("interface_eta", interface_eta);
        v("interface_alpha_x", interface_alpha_x);
        v("interface_alpha_y", interface_alpha_y);
        v("masking", masking);
        layer.fields(v);
    }
};
using CoatedConductorParams = CoatedConductorParamsT<>;

// ---------------------------------------------------------------- the layered estimator

// Scalar only (no `Vectorized`; the batch kernels run it per element, issue 17): the random walk's
// length is data-dependent (each path ends by absorption, escape, Russian roulette or max_depth), so
// the lanes of a packet would diverge at every bounce and wait for the longest walk; per element,
// each path costs only its own depth. The analytic counterpart (layered_analytic.h) runs on packets.
// NC: channels of the throughput, 3 (RGB) or 4 (spectral mode: one per wavelength, with a 4-channel
// Bottom; pbrt-v4 carries a SampledSpectrum through the walk). The coating is grey (one eta), so
// its 3-channel values enter as their first channel (grey()); Russian roulette reads the largest
// channel, the only place where the channels meet.
template <typename F, typename Bottom, int NC = 3> struct LayeredBxDF {
    using Spec = Spectrum<F, NC>;
    DielectricBxDF<F> top;
    Bottom bottom;
    F thickness = F(0.01);
    Spec albedo{F(0)};
    bool has_albedo = false;
    F g = 0;
    int max_depth = 10, n_samples = 1;
    uint64_t seed = 0;
    bool consistent_mis = false;

    void set_layer(const LayerParams &p) {
        thickness = max_(F(p.thickness), F(std::numeric_limits<float>::min()));
        albedo = Spec(F(0));
        for (int c = 0; c < 3; ++c) albedo[c] = F(p.albedo[c]);
        has_albedo = !albedo.is_black();
        g = F(clamp(p.g, -0.99, 0.99));
        max_depth = p.max_depth;
        n_samples = p.n_samples;
        seed = uint64_t(p.seed);
        consistent_mis = p.consistent_mis;
    }

    // Density used to MIS-weight a transmission through the exit (top) interface towards wi from
    // the inner direction -w (see LayerParams::consistent_mis).
    F exit_pdf(const Vec3<F> &w, const Vec3<F> &wi, TransportMode mode) const {
        return consistent_mis ? top.pdf(wi, -w, flip_mode(mode), RT_Transmission)
                              : top.pdf(-w, wi, mode, RT_Transmission);
    }

    // The coating's (grey) value as NC channels (the identity for RGB).
    static Spec grey(const Spectrum<F> &s) {
        if constexpr (NC == 3) return s; else return Spec(s[0]);
    }
    static BSDFSample<F, NC> grey(const BSDFSample<F> &s) {
        if constexpr (NC == 3) {
            return s;
        } else {
            BSDFSample<F, NC> r;
            r.f = Spec(s.f[0]);
            r.wi = s.wi;
            r.pdf = s.pdf;
            r.flags = s.flags;
            r.eta = s.eta;
            r.pdf_is_proportional = s.pdf_is_proportional;
            r.valid = s.valid;
            return r;
        }
    }

    bool top_specular() const { return top.is_smooth(); }
    bool bottom_specular() const { return (bottom.flags() & Specular) != 0; }

    // pbrt-v4 LayeredBxDF::Flags with a non-transmissive base.
    uint8_t flags() const {
        uint8_t bf = bottom.flags();
        uint8_t f = Reflection;
        if (top_specular()) f |= Specular;
        if ((bf & Diffuse) || has_albedo) f |= Diffuse;
        else if (!top_specular() || (bf & Glossy)) f |= Glossy;
        return f;
    }

    // ---- f: pbrt-v4 LayeredBxDF::f (book eq. 14.38 estimator), exit interface = top
    Spec f(Vec3<F> wo, Vec3<F> wi, TransportMode mode) const {
        if (wo.z < F(0)) {  // two-sided
            wo = -wo;
            wi = -wi;
        }
        Spec fsum(F(0));
        if (!SameHemisphere(wo, wi)) return fsum;  // no transmission through the base
        // specular or glossy reflection at the entrance, counted once per sample
        fsum = grey(top.f(wo, wi, mode)) * F(n_samples);
        WalkRNG<F> r{hash_vec(hash_vec(mix64(seed), wo), wi)};
        const F exit_z = thickness;
        const bool top_spec = top_specular(), bot_spec = bottom_specular();
        for (int s = 0; s < n_samples; ++s) {
            // transmission through the entrance, and the "virtual light" path from wi (adjoint mode)
            F uc = r();
            Point2<F> u0{r(), r()};
            BSDFSample<F> wos = top.sample_f(wo, uc, u0, mode, RT_Transmission);
            if (!usable(wos)) continue;
            uc = r();
            Point2<F> u1{r(), r()};
            BSDFSample<F> wis = top.sample_f(wi, uc, u1, flip_mode(mode), RT_Transmission);
            if (!usable(wis)) continue;
            Spec beta = grey(wos.f) * (AbsCosTheta(wos.wi) / wos.pdf);
            Spec wis_w = grey(wis.f) / wis.pdf;
            F z = thickness;
            Vec3<F> w = wos.wi;
            for (int depth = 0; depth < max_depth; ++depth) {
                // Russian roulette
                F bmax = beta.max_component();
                if (depth > 3 && bmax < F(0.25)) {
                    F q = max_(F(0), F(1) - bmax);
                    if (r() < q) break;
                    beta = beta / (F(1) - q);
                }
                if (!has_albedo) {
                    // straight to the other interface
                    z = (z == thickness) ? F(0) : thickness;
                    beta = beta * LayerTr(thickness, w);
                } else {
                    // free flight with sigma_t = 1 along w
                    F dz = -std::log(F(1) - r()) * std::abs(w.z);
                    F zp = w.z > F(0) ? z + dz : z - dz;
                    if (zp == z) continue;
                    if (F(0) < zp && zp < thickness) {
                        // scattering in the medium: NEE through the exit along wis (MIS with the phase function)
                        F ph = HenyeyGreenstein(dot(-w, -wis.wi), g);
                        F wt = top_spec ? F(1) : PowerHeuristic(wis.pdf, ph);
                        fsum = fsum + beta * albedo * wis_w * (ph * wt * LayerTr(zp - exit_z, wis.wi));
                        F ps_pdf;
                        Point2<F> up{r(), r()};
                        Vec3<F> wn = SampleHenyeyGreenstein(-w, g, up, &ps_pdf);
                        if (!(ps_pdf > F(0)) || wn.z == F(0)) continue;
                        beta = beta * albedo;  // p / pdf = 1 for exact HG sampling
                        w = wn;
                        z = zp;
                        // the phase sample heading for the exit interface: its transmission (MIS)
                        if (((z < exit_z && w.z > F(0)) || (z > exit_z && w.z < F(0))) && !top_spec) {
                            Spec fe = grey(top.f(-w, wi, mode));
                            if (nonzero_mask(fe)) {
                                F ep = exit_pdf(w, wi, mode);
                                fsum = fsum + beta * fe * (LayerTr(zp - exit_z, w) * PowerHeuristic(ps_pdf, ep));
                            }
                        }
                        continue;
                    }
                    z = clamp(zp, F(0), thickness);
                }
                if (z == exit_z) {
                    // internal reflection at the coating
                    uc = r();
                    Point2<F> u{r(), r()};
                    BSDFSample<F> bs = top.sample_f(-w, uc, u, mode, RT_Reflection);
                    if (!usable(bs)) break;
                    beta = beta * grey(bs.f) * (AbsCosTheta(bs.wi) / bs.pdf);
                    w = bs.wi;
                } else {
                    // the base: NEE along wis, then a reflection sample, then its exit (MIS)
                    if (!bot_spec) {
                        F wt = top_spec ? F(1) : PowerHeuristic(wis.pdf, bottom.pdf(-w, -wis.wi, mode, RT_All));
                        fsum = fsum + beta * bottom.f(-w, -wis.wi, mode) * wis_w *
                                          (AbsCosTheta(wis.wi) * wt * LayerTr(thickness, wis.wi));
                    }
                    uc = r();
                    Point2<F> u{r(), r()};
                    BSDFSample<F, NC> bs = bottom.sample_f(-w, uc, u, mode, RT_Reflection);
                    if (!usable(bs)) break;
                    beta = beta * bs.f * (AbsCosTheta(bs.wi) / bs.pdf);
                    w = bs.wi;
                    if (!top_spec) {
                        Spec fe = grey(top.f(-w, wi, mode));
                        if (nonzero_mask(fe)) {
                            F wt = F(1);
                            if (!bot_spec) wt = PowerHeuristic(bs.pdf, exit_pdf(w, wi, mode));
                            fsum = fsum + beta * fe * (LayerTr(thickness, bs.wi) * wt);
                        }
                    }
                }
            }
        }
        return fsum / F(n_samples);
    }

    // ---- sample_f: pbrt-v4 LayeredBxDF::Sample_f (pdf_is_proportional = true)
    BSDFSample<F, NC> sample_f(Vec3<F> wo, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        BSDFSample<F, NC> none;
        if (!(sample_flags & RT_Reflection)) return none;  // the walk only returns reflection
        bool flip = wo.z < F(0);
        if (flip) wo = -wo;
        BSDFSample<F> bs = top.sample_f(wo, uc, u, mode, RT_All);
        if (!usable(bs)) return none;
        if (bs.is_reflection()) {
            if (flip) bs.wi = -bs.wi;
            bs.pdf_is_proportional = true;
            return grey(bs);
        }
        Vec3<F> w = bs.wi;
        bool specular_path = bs.is_specular();
        uint64_t h = hash3(mix64(seed ^ 0x5a5a5a5aull), float_bits(uc), float_bits(u.x) ^ (float_bits(u.y) << 1));
        WalkRNG<F> r{hash_vec(h, wo)};
        Spec f = grey(bs.f) * AbsCosTheta(bs.wi);
        F pdf = bs.pdf;
        F z = thickness;
        for (int depth = 0; depth < max_depth; ++depth) {
            F rr_beta = f.max_component() / pdf;
            if (depth > 3 && rr_beta < F(0.25)) {
                F q = max_(F(0), F(1) - rr_beta);
                if (r() < q) return none;
                pdf *= F(1) - q;
            }
            if (w.z == F(0)) return none;
            if (has_albedo) {
                F dz = -std::log(F(1) - r()) * std::abs(w.z);
                F zp = w.z > F(0) ? z + dz : z - dz;
                if (zp == z) return none;
                if (F(0) < zp && zp < thickness) {
                    F ps_pdf;
                    Point2<F> up{r(), r()};
                    Vec3<F> wn = SampleHenyeyGreenstein(-w, g, up, &ps_pdf);
                    if (!(ps_pdf > F(0)) || wn.z == F(0)) return none;
                    f = f * albedo * ps_pdf;
                    pdf *= ps_pdf;
                    specular_path = false;
                    w = wn;
                    z = zp;
                    continue;
                }
                z = clamp(zp, F(0), thickness);
            } else {
                z = (z == thickness) ? F(0) : thickness;
                f = f * LayerTr(thickness, w);
            }
            F uc2 = r();
            Point2<F> u2{r(), r()};
            BSDFSample<F, NC> is = z == F(0) ? bottom.sample_f(-w, uc2, u2, mode, RT_All)
                                             : grey(top.sample_f(-w, uc2, u2, mode, RT_All));
            if (!usable(is)) return none;
            f = f * is.f;
            pdf *= is.pdf;
            specular_path = specular_path & is.is_specular();
            w = is.wi;
            if (is.is_transmission()) {  // left the slab (only the top transmits)
                BSDFSample<F, NC> out;
                out.f = f;
                out.wi = flip ? -w : w;
                out.pdf = pdf;
                out.flags = uint8_t((SameHemisphere(wo, w) ? Reflection : Transmission) | (specular_path ? Specular : Glossy));
                out.eta = F(1);
                out.pdf_is_proportional = true;
                out.valid = true;
                return out;
            }
            f = f * AbsCosTheta(is.wi);
        }
        return none;
    }

    // ---- pdf: pbrt-v4 LayeredBxDF::PDF (book eq. 14.36 estimate, mixed with the uniform sphere)
    F pdf(Vec3<F> wo, Vec3<F> wi, TransportMode mode, uint8_t sample_flags) const {
        if (!(sample_flags & RT_Reflection)) return F(0);
        if (wo.z < F(0)) {
            wo = -wo;
            wi = -wi;
        }
        WalkRNG<F> r{hash_vec(hash_vec(mix64(seed ^ 0xa5a5a5a5ull), wi), wo)};
        F psum = 0;
        if (SameHemisphere(wo, wi)) {
            psum = F(n_samples) * top.pdf(wo, wi, mode, RT_Reflection);
            const bool top_spec = top_specular(), bot_spec = bottom_specular();
            for (int s = 0; s < n_samples; ++s) {
                // TRT: into the slab, off the base, out again
                F uc = r();
                Point2<F> u0{r(), r()};
                BSDFSample<F> wos = top.sample_f(wo, uc, u0, mode, RT_Transmission);
                uc = r();
                Point2<F> u1{r(), r()};
                BSDFSample<F> wis = top.sample_f(wi, uc, u1, flip_mode(mode), RT_Transmission);
                bool ok = wos.valid & nonzero_mask(wos.f) & (wos.pdf > F(0)) & wis.valid & nonzero_mask(wis.f) &
                          (wis.pdf > F(0));
                if (!ok) continue;
                if (top_spec) {
                    psum += bottom.pdf(-wos.wi, -wis.wi, mode, RT_All);
                } else {
                    uc = r();
                    Point2<F> u2{r(), r()};
                    BSDFSample<F, NC> rs = bottom.sample_f(-wos.wi, uc, u2, mode, RT_All);
                    if (!(rs.valid & nonzero_mask(rs.f) & (rs.pdf > F(0)))) continue;
                    if (bot_spec) {
                        psum += top.pdf(-rs.wi, wi, mode, RT_All);
                    } else {
                        F r_pdf = bottom.pdf(-wos.wi, -wis.wi, mode, RT_All);
                        psum += PowerHeuristic(wis.pdf, r_pdf) * r_pdf;
                        F t_pdf = top.pdf(-rs.wi, wi, mode, RT_All);
                        psum += PowerHeuristic(rs.pdf, t_pdf) * t_pdf;
                    }
                }
            }
        }
        // pbrt-v4: Lerp(0.9, 1 / (4 pi), estimate)
        return F(0.1) * UniformSpherePDF<F>() + F(0.9) * psum / F(n_samples);
    }

    void regularize() {
        top.regularize();
        bottom.regularize();
    }
};

// ---------------------------------------------------------------- the two models

template <typename F> struct CoatedDiffuseBxDF : LayeredBxDF<F, DiffuseBxDF<F>> {
    using Params = CoatedDiffuseParams;
    static constexpr const char *Name = "CoatedDiffuse";
    using Spectral = CoatedDiffuseSpectral<F>;  // its spectral form (core/bxdf.h)

    static CoatedDiffuseBxDF make(const Params &p) {
        CoatedDiffuseBxDF m;
        m.top.eta = F(p.eta);
        m.top.mfd = Microfacet<F>(F(p.alpha_x), F(p.alpha_y), p.masking);
        for (int c = 0; c < 3; ++c) m.bottom.R[c] = F(p.reflectance[c]);
        m.set_layer(p.layer);
        return m;
    }
};

template <typename F> struct CoatedConductorBxDF : LayeredBxDF<F, ConductorBxDF<F>> {
    using Params = CoatedConductorParams;
    static constexpr const char *Name = "CoatedConductor";
    using Spectral = CoatedConductorSpectral<F>;  // its spectral form (core/bxdf.h)

    static CoatedConductorBxDF make(const Params &p) {
        CoatedConductorBxDF m;
        m.top.eta = F(p.interface_eta);
        m.top.mfd = Microfacet<F>(F(p.interface_alpha_x), F(p.interface_alpha_y), p.masking);
        // The metal sits in the coating, so its IOR relative to the coating is eta / interface_eta
        // (pbrt-v4 CoatedConductorMaterial since PR #343, issue #342).
        Spectrum<F> ce, ck;
        for (int c = 0; c < 3; ++c) {
            ce[c] = F(p.conductor_eta[c] / p.interface_eta);
            ck[c] = F(p.conductor_k[c] / p.interface_eta);
        }
        m.bottom = ConductorBxDF<F>(Microfacet<F>(F(p.conductor_alpha_x), F(p.conductor_alpha_y), p.masking), ce, ck);
        m.set_layer(p.layer);
        return m;
    }
};

} // namespace bsdfkit
