// OpenPBR: the OpenPBR Surface 1.1 material (Academy Software Foundation, spec v1.1.1), reduced
// to a mixture of lobes with albedo scaling as the spec's "Reduction to a mixture of lobes"
// section derives it (the form of its MaterialX reference):
//   f_surface  = F f_fuzz + (1 - F E_fuzz(mu_o)) f_coated
//   f_coated   = C f_coat + lerp(1, T_coat (1 - E_coat(qo)), C) Dk f_base
//   f_base     = lerp(f_dielectric, f_metal, M)
//   f_dielectric = f_R + (1 - T)(1 - E_R(qo)) lerp(f_diffuse, f_sss, S) + T f_T
// with F, C, M, T, S the fuzz, coat, metalness, transmission and subsurface weights. Lobes:
//   f_R      GGX dielectric reflection at the modulated relative IOR eta' (spec eq. modulated_ior),
//            tinted by specular_color; with thin film, its Fresnel is lerped toward Belcour &
//            Barla 2017's Airy reflectance by thin_film_weight
//   f_T      GGX dielectric transmission (Walter 2007) at eta', tinted by transmission_color
//            (transmission_depth 0: the on-surface tint)
//   f_metal  GGX conductor with the F82-tint Fresnel (Kutz et al. 2021): F0 = base_weight
//            base_color, edge tint specular_color, times specular_weight; a film multiplies it by
//            the Airy reflectance over the Gulbrandsen-mapped metal relative to that bare metal
//   f_diffuse  EON (energy-preserving Oren-Nayar, Portsmouth et al. 2024), rho = base_weight base_color
//   f_sss    subsurface_color / pi: the subsurface slab as a Lambertian lobe (no volume transport)
//   f_coat   GGX dielectric reflection at coat_ior, untinted; T_coat the view-dependent
//            absorption coat_color^((1/mu_t,o + 1/mu_t,i)/2) (spec "View-dependent absorption"),
//            Dk the modulated darkening lerp(1, (1 - K)/(1 - E_b K), C coat_darkening) (spec
//            "Darkening"); the base lobes are roughened by the coat (spec "Roughening")
//   f_fuzz   Zeltner, Burley & Chiang 2022 LTC sheen, tinted by fuzz_color
// Every microfacet lobe is GGX with height-correlated Smith masking; alphas from roughness and
// anisotropy by the spec's formula, floored at 1e-3 (so no lobe is a delta). The albedos E of the
// layering are tabulated at construction in mu_o (48 nodes, (i/47)^3) and, for an anisotropic
// lobe, in wo's azimuth (9 nodes over [0, pi/2]): Gauss-Legendre over visible normals, 24 x 24
// (about 4e-3 absolute at worst, near grazing). compensation="turquin" scales each GGX
// reflection lobe by 1 + F0 (1 - E1) / E1 (Turquin 2019; E1: the lobe's albedo with F = 1) and
// the transmission so that reflection plus transmission of the white dielectric is 1.
// layering="reciprocal" replaces each albedo-scaling factor (1 - E(mu_o)) by
// sqrt((1 - E(mu_o))(1 - E(mu_i))).
// Seen from below (wo.z < 0): the bare dielectric interface, (1 - M) T (f_R + f_T) at 1/eta'
// (no coat, fuzz or diffuse: they have no inside). Thin-walled: the surface is two-sided (a wo
// below is mirrored above with wi), the translucent base becomes a thin sheet whose transmission
// is the reflection lobe mirrored through the surface, (1 - F) transmission_color, and the
// subsurface slab splits subsurface_color into diffuse reflection (1 - g)/2 and transmission
// (1 + g)/2 (spec eq. thin_wall_subsurface).
// Scalar code (not packet-vectorized); no spectral form; no gradients.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/frame.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"
#include "../core/sampling.h"
#include "../core/sheen.h"
#include "../core/thin_film.h"
#include "eon.h"
#include "layered_analytic.h"  // DiffuseFresnel
#include "plastic.h"           // GaussLegendre

namespace bsdfkit {

enum class OpenPBRCompensation : uint8_t { None = 0, Turquin = 1 };
inline constexpr std::array<const char *, 2> enum_names(OpenPBRCompensation) { return {"none", "turquin"}; }
enum class OpenPBRLayering : uint8_t { AlbedoScaling = 0, Reciprocal = 1 };
inline constexpr std::array<const char *, 2> enum_names(OpenPBRLayering) { return {"albedo-scaling", "reciprocal"}; }

// The parameters under the MaterialX open_pbr_surface names, with its defaults.
struct OpenPBRParams {
    double base_weight = 1.0;
    std::array<double, 3> base_color{0.8, 0.8, 0.8};
    double base_metalness = 0.0, base_diffuse_roughness = 0.0;
    double specular_weight = 1.0;
    std::array<double, 3> specular_color{1, 1, 1};
    double specular_roughness = 0.3, specular_roughness_anisotropy = 0.0, specular_ior = 1.5;
    double transmission_weight = 0.0;
    std::array<double, 3> transmission_color{1, 1, 1};
    double subsurface_weight = 0.0;
    std::array<double, 3> subsurface_color{0.8, 0.8, 0.8};
    double subsurface_scatter_anisotropy = 0.0;
    double coat_weight = 0.0;
    std::array<double, 3> coat_color{1, 1, 1};
    double coat_roughness = 0.0, coat_roughness_anisotropy = 0.0, coat_ior = 1.6, coat_darkening = 1.0;
    double fuzz_weight = 0.0;
    std::array<double, 3> fuzz_color{1, 1, 1};
    double fuzz_roughness = 0.5;
    double thin_film_weight = 0.0, thin_film_thickness = 0.5, thin_film_ior = 1.4;
    bool geometry_thin_walled = false;
    OpenPBRCompensation compensation = OpenPBRCompensation::Turquin;
    OpenPBRLayering layering = OpenPBRLayering::AlbedoScaling;
    template <class V> void fields(V &&v) {
        v("base_weight", base_weight);
        v("base_color", base_color);
        v("base_metalness", base_metalness);
        v("base_diffuse_roughness", base_diffuse_roughness);
        v("specular_weight", specular_weight);
        v("specular_color", specular_color);
        v("specular_roughness", specular_roughness);
        v("specular_roughness_anisotropy", specular_roughness_anisotropy);
        v("specular_ior", specular_ior);
        v("transmission_weight", transmission_weight);
        v("transmission_color", transmission_color);
        v("subsurface_weight", subsurface_weight);
        v("subsurface_color", subsurface_color);
        v("subsurface_scatter_anisotropy", subsurface_scatter_anisotropy);
        v("coat_weight", coat_weight);
        v("coat_color", coat_color);
        v("coat_roughness", coat_roughness);
        v("coat_roughness_anisotropy", coat_roughness_anisotropy);
        v("coat_ior", coat_ior);
        v("coat_darkening", coat_darkening);
        v("fuzz_weight", fuzz_weight);
        v("fuzz_color", fuzz_color);
        v("fuzz_roughness", fuzz_roughness);
        v("thin_film_weight", thin_film_weight);
        v("thin_film_thickness", thin_film_thickness);
        v("thin_film_ior", thin_film_ior);
        v("geometry_thin_walled", geometry_thin_walled);
        v("compensation", compensation);
        v("layering", layering);
    }
};

namespace openpbr {

inline constexpr int kTableRes = 48;   // albedo table nodes in mu_o (TableNode)
inline constexpr int kTablePhi = 9;    // ... and in wo's azimuth over [0, pi/2] (anisotropic lobes only)
inline constexpr int kQuadNodes = 24;  // Gauss-Legendre nodes per axis of the albedo integrals
inline constexpr double kAlphaFloor = 1e-3;

// GGX alphas from roughness r and anisotropy a: alpha_t = r^2 sqrt(2 / (1 + (1 - a)^2)),
// alpha_b = (1 - a) alpha_t (OpenPBR eq. openpbr-anisotropy-formula), floored.
inline void AnisotropicAlphas(double r, double a, double *at, double *ab) {
    double t = r * r * std::sqrt(2.0 / (1.0 + (1.0 - a) * (1.0 - a)));
    *at = std::max(openpbr::kAlphaFloor, t);
    *ab = std::max(openpbr::kAlphaFloor, (1.0 - a) * t);
}

// The base roughness under a coat: lerp(r_b, min(1, r_b^4 + 2 r_c^4)^(1/4), C) (OpenPBR "Roughening").
inline double RoughenedRoughness(double r_b, double r_c, double C) {
    double r4 = std::min(1.0, std::pow(r_b, 4) + 2.0 * std::pow(r_c, 4));
    return lerp(C, r_b, std::pow(r4, 0.25));
}

// The specular IOR ratio against the surrounding medium, coat-weighted, with the TIR fix:
// lerp(n_b, n_b/n_c or n_c/n_b when n_c > n_b, C) (OpenPBR eqs. specular_ior_ratio, specular_ior_ratio_with_tir_fix).
inline double SpecularIORRatio(double n_b, double n_c, double C) {
    double bc = n_c > n_b ? n_c / n_b : n_b / n_c;
    return lerp(C, n_b, bc);
}

// specular_weight's IOR modulation: F_s = ((1 - eta)/(1 + eta))^2, xi clamped to [0, 1/F_s],
// eps = sgn(eta - 1) sqrt(xi F_s), eta' = (1 + eps)/(1 - eps) (OpenPBR eqs. unmodulated_fresnel, modulated_ior).
inline double ModulatedIOR(double eta, double xi) {
    double fs = sqr((1.0 - eta) / (1.0 + eta));
    if (!(fs > 0)) return 1.0;
    xi = std::min(std::max(xi, 0.0), 1.0 / fs);
    double eps = (eta > 1 ? 1.0 : -1.0) * std::sqrt(xi * fs);
    return (1.0 + eps) / (1.0 - eps);
}

// The darkening factor Delta = (1 - K)/(1 - E_b K) (OpenPBR eq. general_darkening_formula).
template <typename F> inline F Darkening(F E_b, F K) { return (F(1) - K) / (F(1) - E_b * K); }

// Refracted cosine into the coat, sqrt(1 - (1 - mu^2)/eta_c^2) (OpenPBR "View-dependent absorption").
template <typename F> inline F CoatCosine(F mu, F eta_c) { return safe_sqrt(F(1) - (F(1) - mu * mu) / (eta_c * eta_c)); }

template <typename F> inline Spectrum<F> Lerp(F t, const Spectrum<F> &a, const Spectrum<F> &b) { return a + (b - a) * t; }

// Per channel into [0, 1]: a specular_color above 1 (the spec's examples go to 1.39) may lift a
// Fresnel factor, never past 1.
template <typename F> inline Spectrum<F> Clamp01(const Spectrum<F> &s) {
    Spectrum<F> r;
    for (int c = 0; c < 3; ++c) r[c] = min_(F(1), max_(F(0), s[c]));
    return r;
}

// The table nodes mu_i = (i / (N - 1))^3, dense toward grazing where the albedos of a nearly
// smooth lobe change fastest (Fresnel and masking on the scale mu ~ alpha: E of alpha 1e-3 peaks
// near mu = 0.006); the first taken at 1e-5 (a horizon wo has no albedo integral). Lookups
// interpolate linearly in mu^(1/3).
inline double TableNode(int i) { double t = double(i) / (kTableRes - 1); return std::max(1e-5, t * t * t); }

// Where a direction falls in the tables: mu = |cos theta| and its azimuth folded into
// [0, pi/2] (the GGX lobes are symmetric about both tangent axes), as a fraction of pi/2.
template <typename F> struct TabPos {
    F mu, phi;
};
template <typename F> inline TabPos<F> TablePos(const Vec3<F> &w) {
    F ax = abs(w.x), ay = abs(w.y);
    F phi = ax + ay > F(0) ? atan2(ay, ax) * F(2 / 3.14159265358979323846) : F(0);
    return {abs(w.z), phi};
}

// A function of (mu_o, phi_o) tabulated at (TableNode(i), j / (kTablePhi - 1)), row-major in mu,
// bilinear in (mu^(1/3), phi) between nodes; an isotropic table has only its column 0.
template <typename T, typename F> inline T TableLookup(const T *tab, const TabPos<F> &q, bool aniso) {
    double x = std::cbrt(std::max(0.0, double(q.mu))) * (kTableRes - 1);
    x = std::min(std::max(x, 0.0), double(kTableRes - 1));
    int i = std::min(int(x), kTableRes - 2);
    double t = x - i;
    if (!aniso) return tab[i * kTablePhi] * (1 - t) + tab[(i + 1) * kTablePhi] * t;
    double y = std::min(std::max(double(q.phi), 0.0), 1.0) * (kTablePhi - 1);
    int j = std::min(int(y), kTablePhi - 2);
    double v = y - j;
    const T *r0 = tab + i * kTablePhi + j, *r1 = r0 + kTablePhi;
    return (r0[0] * (1 - v) + r0[1] * v) * (1 - t) + (r1[0] * (1 - v) + r1[1] * v) * t;
}

// Reflection at the microfacet normal of the half vector: D(h) G2 / (4 mu_o mu_i), wo and wi above.
template <typename F> inline F MicrofacetReflection(const Microfacet<F> &mf, const Vec3<F> &wo, const Vec3<F> &wi, Vec3<F> *h) {
    Vec3<F> s = wo + wi;
    F len2 = dot(s, s);
    if (!(len2 > F(0))) return F(0);
    *h = s / sqrt(len2);
    if (!(dot(wo, *h) > F(0)) || !(dot(wi, *h) > F(0))) return F(0);
    return mf.D(*h) * mf.G(wo, wi) / (F(4) * wo.z * wi.z);
}

// Transmission from wo (above, IOR 1) to wi (below, relative IOR e): Walter 2007 eq. 21 without
// the Fresnel factor, D G |wi.h wo.h| e^2 / (|mu_o mu_i| (wo.h + e wi.h)^2), over e^2 for
// radiance; h the generalized half vector normalize(wo + e wi) turned up. 0 for a back-facing h.
template <typename F>
inline F MicrofacetTransmission(const Microfacet<F> &mf, F e, const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode,
                                Vec3<F> *h, F *jac) {
    Vec3<F> s = wo + wi * e;
    F len2 = dot(s, s);
    if (!(len2 > F(0))) return F(0);
    *h = s / sqrt(len2);
    if (h->z < F(0)) *h = -*h;
    F oh = dot(wo, *h), ih = dot(wi, *h);
    if (!(oh > F(0)) || !(ih < F(0))) return F(0);
    F denom = sqr(oh + e * ih);
    *jac = e * e * abs(ih) / denom;  // |d h / d wi| (Walter 2007 eq. 17)
    F v = mf.D(*h) * mf.G(wo, wi) * abs(ih * oh) * e * e / (abs(wo.z * wi.z) * denom);
    return mode == TransportMode::Radiance ? v / (e * e) : v;
}

} // namespace openpbr

template <typename F> struct OpenPBRBxDF {
    using Params = OpenPBRParams;
    static constexpr const char *Name = "OpenPBR";
    static constexpr int N = openpbr::kTableRes * openpbr::kTablePhi;
    using Pos = openpbr::TabPos<F>;

    Microfacet<F> spec, coat;  // the base's (roughened) and the coat's GGX distributions
    EONBxDF<F> eon;            // the diffuse lobe, rho = base_weight base_color
    F eta = 1.5, coat_eta = 1.6, f0_diel = 0.04, f0_coat = 0.05;
    F eta_f = 1.5;  // eta' itself, for the Fresnel factors (eta: the refraction's, kept 1e-3 from 1)
    Spectrum<F> spec_color{F(1)}, trans_color{F(1)}, coat_color{F(1)}, fuzz_color{F(1)}, sss_color{F(0.8)};
    Spectrum<F> metal_f0{F(0.8)}, metal_a{F(0)}, rho{F(0.8)}, E_b{F(0)};
    Spectrum<F> film_eta{F(1)}, film_k{F(0)};  // the metal's effective complex IOR (thin film)
    F spec_weight = 1, M = 0, T = 0, S = 0, C = 0, Fw = 0, fuzz_r = 0.5, sss_g = 0;
    F tf_w = 0, tf_thick = 0.5, tf_ior = 1.4, dark = 1, K_r = 0, r_b = 0;
    bool thin_walled = false, turquin = true, reciprocal = false;
    bool aniso = false;  // either lobe anisotropic: the tables carry wo's azimuth
    // albedo tables in mu_o: E_Rw (the dielectric reflection, untinted, with the film), E_M (the
    // metal), E_T (the transmission, energy, with the film), E1 / E1c (the GGX lobes with F = 1),
    // E_c (the coat)
    Spectrum<F> E_Rw[N], E_M[N], E_T[N];
    F E1[N], E1c[N], E_c[N];
    template <typename T> T look(const T *tab, const Pos &q) const { return openpbr::TableLookup(tab, q, aniso); }

    // ---- construction

    // The dielectric base's Fresnel at wo.h: exact at eta', lerped toward the Airy film.
    Spectrum<F> fresnel_dielectric(F c) const {
        F fd = FrDielectric(c, eta_f);
        if (!(tf_w > F(0))) return Spectrum<F>(fd);
        return openpbr::Lerp(tf_w, Spectrum<F>(fd), AiryReflectanceDielectric(c, tf_ior, eta_f, tf_thick));
    }
    // The metal's Fresnel: specular_weight F82-tint, lerped toward the filmed metal. The film
    // modulates the F82 curve by the Airy reflectance of the film over the metal's effective
    // complex IOR (Gulbrandsen 2014 from F0 and the edge tint, as the spec suggests) relative to
    // that bare metal's Fresnel: so thickness 0 is the F82 metal exactly, and a white metal stays
    // white where the mapping (reflectivity clamped below 1) would absorb.
    Spectrum<F> fresnel_metal(F c) const {
        Spectrum<F> f82 = openpbr::Clamp01(FrF82Tint(c, metal_f0, metal_a));
        if (!(tf_w > F(0))) return f82 * spec_weight;
        Spectrum<F> air = AiryReflectanceConductor(c, tf_ior, film_eta, film_k, tf_thick);
        Spectrum<F> bare = FrComplex(c, film_eta, film_k), film;
        for (int k = 0; k < 3; ++k) film[k] = bare[k] > F(0) ? f82[k] * air[k] / bare[k] : air[k];
        return openpbr::Lerp(tf_w, f82, openpbr::Clamp01(film)) * spec_weight;
    }

    static OpenPBRBxDF make(const Params &p) {
        using namespace openpbr;
        OpenPBRBxDF m;
        m.M = F(p.base_metalness);
        m.T = F(p.transmission_weight);
        m.S = F(p.subsurface_weight);
        m.C = F(p.coat_weight);
        m.Fw = F(p.fuzz_weight);
        m.fuzz_r = F(p.fuzz_roughness);
        m.sss_g = F(p.subsurface_scatter_anisotropy);
        m.thin_walled = p.geometry_thin_walled;
        m.turquin = p.compensation == OpenPBRCompensation::Turquin;
        m.reciprocal = p.layering == OpenPBRLayering::Reciprocal;
        m.dark = F(p.coat_darkening);
        m.spec_weight = F(p.specular_weight);
        m.spec_color = to_spectrum<F>(p.specular_color);
        m.trans_color = to_spectrum<F>(p.transmission_color);
        m.coat_color = to_spectrum<F>(p.coat_color);
        m.fuzz_color = to_spectrum<F>(p.fuzz_color);
        m.sss_color = to_spectrum<F>(p.subsurface_color);
        m.tf_w = F(p.thin_film_weight);
        m.tf_thick = F(p.thin_film_thickness);
        m.tf_ior = F(p.thin_film_ior);
        // the base (roughened by the coat) and the coat
        double rs = RoughenedRoughness(p.specular_roughness, p.coat_roughness, p.coat_weight), ax, ay;
        AnisotropicAlphas(rs, p.specular_roughness_anisotropy, &ax, &ay);
        m.spec = Microfacet<F>(F(ax), F(ay), Masking::Correlated);
        double ax_s = ax, ay_s = ay;
        AnisotropicAlphas(p.coat_roughness, p.coat_roughness_anisotropy, &ax, &ay);
        m.coat = Microfacet<F>(F(ax), F(ay), Masking::Correlated);
        // the dielectric's relative IOR, kept 1e-3 away from 1 (an index-matched rough interface
        // would be a delta transmission)
        double e = ModulatedIOR(SpecularIORRatio(p.specular_ior, p.coat_ior, p.coat_weight), p.specular_weight);
        m.eta_f = F(e);  // eta' = 1 (specular_weight 0, or a coat matching the base): no reflection
        if (std::abs(e - 1.0) < 1e-3) e = e >= 1.0 ? 1.001 : 0.999;
        m.eta = F(e);
        m.f0_diel = F(sqr((double(m.eta_f) - 1) / (double(m.eta_f) + 1)));
        m.coat_eta = F(p.coat_ior);
        m.f0_coat = F(sqr((p.coat_ior - 1) / (p.coat_ior + 1)));
        // the metal: F0 = base_weight base_color, F82 edge = specular_color Schlick(1/7)
        // (OpenPBR "Metal"; a as core/fresnel.h's FrF82Tint takes it)
        double mb = kF82Cos, w6 = mb * std::pow(1 - mb, 6);
        for (int c = 0; c < 3; ++c) {
            double f0 = p.base_weight * p.base_color[size_t(c)];
            double schlick = f0 + (1 - f0) * std::pow(1 - mb, 5);
            m.metal_f0[c] = F(f0);
            m.metal_a[c] = F(schlick * (1 - p.specular_color[size_t(c)]) / w6);
        }
        if (p.thin_film_weight > 0) {
            Spectrum<F> r = m.metal_f0, g = m.spec_color;
            for (int c = 0; c < 3; ++c) r[c] = min_(r[c], F(0.9999)), g[c] = min_(g[c], F(1));
            EdgeTintToComplexIOR(r, g, &m.film_eta, &m.film_k);
        }
        // the diffuse lobe
        typename EONBxDF<F>::Params ep;
        for (int c = 0; c < 3; ++c) ep.reflectance[size_t(c)] = p.base_weight * p.base_color[size_t(c)];
        ep.roughness = p.base_diffuse_roughness;
        m.eon = EONBxDF<F>::make(ep);
        m.rho = to_spectrum<F>(ep.reflectance);
        m.aniso = ax_s != ay_s || ax != ay;
        m.integrate_tables();
        // darkening: K = lerp(K_s(mu_o), K_r, r_b), K_r = 1 - (1 - E_F)/eta_c^2 (OpenPBR eqs.
        // internal_diffuse_reflection_coefficient_*), r_b = lerp(lerp(1, r, xi F_s), r, M)
        double etab = SpecularIORRatio(p.specular_ior, p.coat_ior, p.coat_weight);
        double fs = sqr((1 - etab) / (1 + etab));
        double rd = lerp(std::min(1.0, std::max(0.0, p.specular_weight * fs)), 1.0, p.specular_roughness);
        m.r_b = F(lerp(p.base_metalness, rd, p.specular_roughness));
        m.K_r = F(1.0 - (1.0 - DiffuseFresnel(p.coat_ior)) / sqr(p.coat_ior));
        // E_b: the normal-incidence albedo of the base, its slabs blended by their weights (the
        // translucent slab's reflection plus transmission)
        Pos normal{F(1), F(0)};
        Spectrum<F> er = m.E_R(normal), opaque = Lerp(m.S, m.rho, m.sss_color);
        Spectrum<F> diel = er + (Spectrum<F>(F(1)) - er) * (opaque * (F(1) - m.T) + m.trans_color * m.T);
        m.E_b = Lerp(m.M, diel, m.E_metal(normal));
        return m;
    }

    // The albedo tables (Gauss-Legendre over the visible normals, as plastic.h's
    // RoughInterfaceAlbedo): E = int F G2 / G1(wo) dD_wo, at each node's (mu_o, phi_o); over
    // phi only when a lobe is anisotropic.
    void integrate_tables() {
        using namespace openpbr;
        double x[kQuadNodes], w[kQuadNodes];
        GaussLegendre(kQuadNodes, x, w);
        const int nphi = aniso ? kTablePhi : 1;
        // with a film, the two Fresnel curves tabulated in wo.m first (512 intervals, linear):
        // the Airy sum is the integrals' cost otherwise
        constexpr int K = 512;
        const bool film = tf_w > F(0);
        std::vector<Spectrum<F>> fd_tab(film ? K + 1 : 0), fm_tab(film ? K + 1 : 0);
        for (int j = 0; film && j <= K; ++j) fd_tab[j] = fresnel_dielectric(F(j) / F(K)), fm_tab[j] = fresnel_metal(F(j) / F(K));
        auto curve = [&](const std::vector<Spectrum<F>> &tab, F c) {
            double y = std::min(std::max(double(c), 0.0), 1.0) * K;
            int j = std::min(int(y), K - 1);
            double t = y - j;
            return tab[j] * F(1 - t) + tab[j + 1] * F(t);
        };
        for (int i = 0; i < kTableRes; ++i)
            for (int j = 0; j < nphi; ++j) {
                double mu = TableNode(i), st = std::sqrt(1 - mu * mu), ph = j * (3.14159265358979323846 / 2) / (kTablePhi - 1);
                Vec3<F> wo(F(st * std::cos(ph)), F(st * std::sin(ph)), F(mu));
                F g1o = spec.G1(wo), g1c = coat.G1(wo);
                Spectrum<F> er(F(0)), em(F(0)), et(F(0));
                F e1(0), e1c(0), ec(0);
                for (int a = 0; a < kQuadNodes; ++a)
                    for (int b = 0; b < kQuadNodes; ++b) {
                        Point2<F> u{F(0.5 * x[b] + 0.5), F(0.5 * x[a] + 0.5)};
                        F wt = F(0.25 * w[a] * w[b]);
                        Vec3<F> mh = spec.Sample_wm(wo, u);
                        F c = dot(wo, mh);
                        Vec3<F> wi = Reflect(wo, mh);
                        Spectrum<F> fd = film ? curve(fd_tab, c) : fresnel_dielectric(c);
                        if (wi.z > F(0)) {
                            F g = wt * spec.G(wo, wi) / g1o;
                            e1 += g;
                            er = er + fd * g;
                            em = em + (film ? curve(fm_tab, c) : fresnel_metal(c)) * g;
                        }
                        Vec3<F> wt_dir;
                        F etap;
                        if (Refract(wo, mh, eta, &etap, &wt_dir) && wt_dir.z < F(0))
                            et = et + (Spectrum<F>(F(1)) - fd) * (wt * spec.G(wo, wt_dir) / g1o);
                        Vec3<F> mc = coat.Sample_wm(wo, u), wc = Reflect(wo, mc);
                        if (wc.z > F(0)) {
                            F g = wt * coat.G(wo, wc) / g1c;
                            e1c += g;
                            ec += FrDielectric(dot(wo, mc), coat_eta) * g;
                        }
                    }
                int k = i * kTablePhi + j;
                E_Rw[k] = er, E_M[k] = em, E_T[k] = et, E1[k] = e1, E1c[k] = e1c, E_c[k] = ec;
            }
    }

    // ---- the layering's albedos at mu_o, with the compensation when on

    // Turquin 2019's factor 1 + F0 (1 - E1)/E1 of a GGX lobe whose F = 1 albedo is e1.
    template <typename T> T turquin_factor(const T &f0, F e1) const {
        if (!turquin || !(e1 > F(0))) return f0 * F(0) + F(1);
        return f0 * ((F(1) - e1) / e1) + F(1);
    }
    F e1(const Pos &q) const { return look(E1, q); }
    F e1c(const Pos &q) const { return look(E1c, q); }
    // the dielectric reflection's albedo, untinted (compensated)
    Spectrum<F> E_Rw_c(const Pos &q) const { return look(E_Rw, q) * turquin_factor(f0_diel, e1(q)); }
    Spectrum<F> E_R(const Pos &q) const { return openpbr::Clamp01(spec_color * E_Rw_c(q)); }
    Spectrum<F> E_metal(const Pos &q) const { return look(E_M, q) * turquin_factor(metal_f0 * spec_weight, e1(q)); }
    F E_coat(const Pos &q) const { return look(E_c, q) * turquin_factor(f0_coat, e1c(q)); }
    // The transmission's scale: 1, or (1 - E_Rw_c)/E_T so that the white interface conserves energy.
    Spectrum<F> trans_scale(const Pos &q) const {
        if (!turquin) return Spectrum<F>(F(1));
        return ratio(Spectrum<F>(F(1)) - E_Rw_c(q), look(E_T, q));
    }
    // The thin sheet's transmission scale: 1, or (1 - E_Rw_c)/(E1 - E_Rw), its mirrored lobe's
    // albedo being that of the reflection lobe with 1 - F for F.
    Spectrum<F> sheet_scale(const Pos &q) const {
        if (!turquin) return Spectrum<F>(F(1));
        return ratio(Spectrum<F>(F(1)) - E_Rw_c(q), Spectrum<F>(e1(q)) - look(E_Rw, q));
    }
    static Spectrum<F> ratio(const Spectrum<F> &a, const Spectrum<F> &b) {
        Spectrum<F> s;
        for (int c = 0; c < 3; ++c) s[c] = b[c] > F(0) ? max_(F(0), a[c]) / b[c] : F(1);
        return s;
    }
    F E_fuzz(F mu) const { return Fw > F(0) ? ZeltnerSheen<F>::make(mu, fuzz_r).albedo() : F(0); }
    // The modulated darkening lerp(1, Delta, C coat_darkening) at mu_o.
    Spectrum<F> darkening(F mu) const {
        F K = lerp(r_b, FrDielectric(mu, coat_eta), K_r);
        Spectrum<F> d;
        for (int c = 0; c < 3; ++c) d[c] = lerp(C * dark, F(1), openpbr::Darkening(E_b[c], K));
        return d;
    }
    // The coat's transmittance for the pair, coat_color^((1/mu_t,o + 1/mu_t,i)/2).
    Spectrum<F> coat_transmittance(F mu_o, F mu_i) const {
        F ex = F(0.5) * (F(1) / openpbr::CoatCosine(mu_o, coat_eta) + F(1) / openpbr::CoatCosine(mu_i, coat_eta));
        Spectrum<F> t;
        for (int c = 0; c < 3; ++c) t[c] = coat_color[c] > F(0) ? pow(coat_color[c], ex) : F(0);
        return t;
    }
    // Albedo scaling 1 - E(mu_o), or the reciprocal sqrt((1 - E(mu_o))(1 - E(mu_i))).
    template <typename T> T scaling(const T &e_o, const T &e_i) const {
        if (!reciprocal) return T(F(1)) - e_o;
        T a = T(F(1)) - e_o, b = T(F(1)) - e_i;
        if constexpr (std::is_same_v<T, F>) return sqrt(max_(F(0), a * b));
        else {
            T r;
            for (int c = 0; c < 3; ++c) r[c] = sqrt(max_(F(0), a[c] * b[c]));
            return r;
        }
    }

    // ---- the model interface

    uint8_t flags() const {
        uint8_t fl = GlossyReflection;
        if (M < F(1) && (T < F(1) || thin_walled)) fl |= DiffuseReflection;
        if (M < F(1) && T > F(0)) fl |= GlossyTransmission;
        if (thin_walled && M < F(1) && T < F(1) && S > F(0)) fl |= DiffuseTransmission;
        return fl;
    }

    // The thin-walled sheet's lobes and the subsurface stand-in seen from above.
    Spectrum<F> opaque_reflection(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode) const {
        Spectrum<F> sss = thin_walled ? sss_color * (F(0.5) * (F(1) - sss_g) * InvPi<F>) : sss_color * InvPi<F>;
        return openpbr::Lerp(S, eon.f(wo, wi, mode), sss);
    }

    Spectrum<F> f(const Vec3<F> &wo_, const Vec3<F> &wi_, TransportMode mode) const {
        Spectrum<F> zero(F(0));
        if (!(wo_.z != F(0)) || !(wi_.z != F(0))) return zero;
        Vec3<F> wo = wo_, wi = wi_;
        if (wo.z < F(0)) {
            if (!thin_walled) return inside_f(wo, wi, mode);
            wo.z = -wo.z, wi.z = -wi.z;  // thin-walled: the same from either side
        }
        F mu_o = wo.z, mu_i = abs(wi.z);
        Pos qo = openpbr::TablePos(wo), qi = openpbr::TablePos(wi);
        bool reflect = wi.z > F(0);
        Spectrum<F> base(F(0));
        if (reflect) {
            Vec3<F> h;
            F dg = openpbr::MicrofacetReflection(spec, wo, wi, &h);
            F c = dot(wo, h);
            Spectrum<F> diel(F(0));
            if (M < F(1)) {
                Spectrum<F> er_o = E_R(qo);
                Spectrum<F> fr = dg > F(0) ? openpbr::Clamp01(spec_color * fresnel_dielectric(c)) * (dg * turquin_factor(f0_diel, e1(qo)))
                                           : zero;
                Spectrum<F> sc = scaling(er_o, reciprocal ? E_R(qi) : er_o);
                diel = fr + sc * opaque_reflection(wo, wi, mode) * (F(1) - T);
            }
            Spectrum<F> metal = dg > F(0) && M > F(0)
                                    ? fresnel_metal(c) * turquin_factor(metal_f0 * spec_weight, e1(qo)) * dg
                                    : zero;
            base = openpbr::Lerp(M, diel, metal);
        } else if (M < F(1)) {
            Spectrum<F> t(F(0));
            if (T > F(0)) {
                if (thin_walled) {
                    // the sheet: the reflection lobe mirrored through the surface, (1 - F) tinted
                    Vec3<F> wm(wi.x, wi.y, -wi.z), h;
                    F dg = openpbr::MicrofacetReflection(spec, wo, wm, &h);
                    if (dg > F(0))
                        t = trans_color * (Spectrum<F>(F(1)) - fresnel_dielectric(dot(wo, h))) * sheet_scale(qo) *
                            (dg * T);
                } else {
                    Vec3<F> h;
                    F jac;
                    F v = openpbr::MicrofacetTransmission(spec, eta, wo, wi, mode, &h, &jac);
                    if (v > F(0))
                        t = trans_color * (Spectrum<F>(F(1)) - fresnel_dielectric(dot(wo, h))) * trans_scale(qo) * (v * T);
                }
            }
            if (thin_walled && S > F(0) && T < F(1)) {
                Spectrum<F> er_o = E_R(qo);
                Spectrum<F> sc = scaling(er_o, reciprocal ? E_R(qi) : er_o);
                t = t + sc * sss_color * (F(0.5) * (F(1) + sss_g) * InvPi<F> * S * (F(1) - T));
            }
            base = t * (F(1) - M);
        }
        // the coat
        Spectrum<F> coated = base;
        if (C > F(0)) {
            Spectrum<F> fc(F(0));
            if (reflect) {
                Vec3<F> h;
                F dg = openpbr::MicrofacetReflection(coat, wo, wi, &h);
                if (dg > F(0)) fc = Spectrum<F>(FrDielectric(dot(wo, h), coat_eta) * dg * turquin_factor(f0_coat, e1c(qo)) * C);
            }
            F ec_o = E_coat(qo), ec_i = reciprocal ? E_coat(qi) : ec_o;
            Spectrum<F> through = coat_transmittance(mu_o, mu_i) * scaling(ec_o, ec_i);
            Spectrum<F> scale = openpbr::Lerp(C, Spectrum<F>(F(1)), through) * darkening(mu_o);
            coated = fc + scale * base;
        }
        // the fuzz
        if (!(Fw > F(0))) return coated;
        Spectrum<F> ff(F(0));
        ZeltnerSheen<F> sh = ZeltnerSheen<F>::make(mu_o, fuzz_r);
        if (reflect) ff = fuzz_color * (Fw * sh.eval(wo, wi));
        F ef_o = Fw * sh.albedo(), ef_i = reciprocal ? Fw * E_fuzz(mu_i) : ef_o;
        return ff + coated * scaling(ef_o, ef_i);
    }

    // Seen from below (not thin-walled): (1 - M) T times the bare interface at 1/eta', mirrored
    // above: reflection untinted, transmission tinted by transmission_color.
    Spectrum<F> inside_f(const Vec3<F> &wo_, const Vec3<F> &wi_, TransportMode mode) const {
        F w = (F(1) - M) * T;
        if (!(w > F(0))) return Spectrum<F>(F(0));
        Vec3<F> wo(wo_.x, wo_.y, -wo_.z), wi(wi_.x, wi_.y, -wi_.z);
        F e = F(1) / eta;
        Vec3<F> h;
        if (wi.z > F(0)) {
            F dg = openpbr::MicrofacetReflection(spec, wo, wi, &h);
            return Spectrum<F>(dg > F(0) ? FrDielectric(dot(wo, h), F(1) / eta_f) * dg * w : F(0));
        }
        F jac, v = openpbr::MicrofacetTransmission(spec, e, wo, wi, mode, &h, &jac);
        return v > F(0) ? trans_color * ((F(1) - FrDielectric(dot(wo, h), F(1) / eta_f)) * v * w) : Spectrum<F>(F(0));
    }

    // ---- sampling: a mixture of the lobes, each chosen with its albedo weight at wo

    enum Lobe { kFuzz = 0, kCoat, kSpec, kTrans, kDiffuse, kDiffuseT, kLobes };

    void lobe_weights(const Vec3<F> &wo, uint8_t sample_flags, F *p) const {
        for (int k = 0; k < kLobes; ++k) p[k] = F(0);
        F mu = wo.z;
        Pos q = openpbr::TablePos(wo);
        const bool allow_r = sample_flags & RT_Reflection, allow_t = sample_flags & RT_Transmission;
        F top = F(1);
        if (Fw > F(0)) {
            F ef = Fw * E_fuzz(mu);
            p[kFuzz] = ef * max_(F(1e-3), Luminance(fuzz_color));
            top = F(1) - ef;
        }
        F wb = top;
        if (C > F(0)) {
            F ec = E_coat(q);
            p[kCoat] = top * C * ec;
            Spectrum<F> th = coat_transmittance(mu, mu) * (F(1) - ec);
            wb = top * lerp(C, F(1), Luminance(th)) * Luminance(darkening(mu));
        }
        Spectrum<F> er = E_R(q);
        p[kSpec] = wb * ((F(1) - M) * Luminance(er) + M * Luminance(E_metal(q)));
        if (M < F(1)) {
            F er_l = max_(F(0), F(1) - Luminance(er));
            if (T > F(0)) {
                Spectrum<F> et = thin_walled ? (Spectrum<F>(e1(q)) - look(E_Rw, q)) * sheet_scale(q) : look(E_T, q) * trans_scale(q);
                et = et * trans_color;
                p[kTrans] = wb * (F(1) - M) * T * max_(F(1e-3), Luminance(et));
            }
            Spectrum<F> op = openpbr::Lerp(S, rho, sss_color);
            F sss_r = thin_walled ? F(0.5) * (F(1) - sss_g) : F(1);
            F d_l = lerp(S, Luminance(rho), Luminance(sss_color) * sss_r);
            p[kDiffuse] = wb * (F(1) - M) * (F(1) - T) * er_l * max_(F(1e-3), d_l) * F(op.max_component() > F(0));
            if (thin_walled && S > F(0))
                p[kDiffuseT] = wb * (F(1) - M) * (F(1) - T) * er_l * S *
                               max_(F(1e-3), Luminance(sss_color) * F(0.5) * (F(1) + sss_g));
        }
        if (!allow_r) p[kFuzz] = p[kCoat] = p[kSpec] = p[kDiffuse] = F(0);
        if (!allow_t) p[kTrans] = p[kDiffuseT] = F(0);
        F total = F(0);
        for (int k = 0; k < kLobes; ++k) total += p[k];
        F inv = total > F(0) ? F(1) / total : F(0);
        for (int k = 0; k < kLobes; ++k) p[k] *= inv;
    }

    // Density of each lobe's sampler at wi (wo above).
    F lobe_pdf(int k, const Vec3<F> &wo, const Vec3<F> &wi) const {
        Vec3<F> h;
        switch (k) {
        case kFuzz:
            return wi.z > F(0) ? ZeltnerSheen<F>::make(wo.z, fuzz_r).pdf(wo, wi) : F(0);
        case kCoat:
        case kSpec: {
            const Microfacet<F> &mf = k == kCoat ? coat : spec;
            if (!(wi.z > F(0)) || !(openpbr::MicrofacetReflection(mf, wo, wi, &h) > F(0))) return F(0);
            return mf.D(wo, h) / (F(4) * dot(wo, h));
        }
        case kTrans: {
            if (!(wi.z < F(0))) return F(0);
            if (thin_walled) {
                Vec3<F> wm(wi.x, wi.y, -wi.z);
                if (!(openpbr::MicrofacetReflection(spec, wo, wm, &h) > F(0))) return F(0);
                return spec.D(wo, h) / (F(4) * dot(wo, h));
            }
            F jac;
            if (!(openpbr::MicrofacetTransmission(spec, eta, wo, wi, TransportMode::Importance, &h, &jac) > F(0)))
                return F(0);
            return spec.D(wo, h) * jac;
        }
        case kDiffuse:
            return wi.z > F(0) ? eon.pdf(wo, wi, TransportMode::Radiance, RT_Reflection) : F(0);
        case kDiffuseT: {
            Vec3<F> wm(wi.x, wi.y, -wi.z);
            return wi.z < F(0) ? eon.pdf(wo, wm, TransportMode::Radiance, RT_Reflection) : F(0);
        }
        }
        return F(0);
    }

    // The inside (not thin-walled): the interface's reflection with probability F(wo.h), else
    // its transmission, at 1/eta' (pbrt-v4 DielectricBxDF's rough sampler), mirrored above.
    F inside_pdf(const Vec3<F> &wo_, const Vec3<F> &wi_, uint8_t sample_flags) const {
        if (!((F(1) - M) * T > F(0))) return F(0);
        Vec3<F> wo(wo_.x, wo_.y, -wo_.z), wi(wi_.x, wi_.y, -wi_.z);
        F e = F(1) / eta, jac;
        Vec3<F> h;
        const bool allow_r = sample_flags & RT_Reflection, allow_t = sample_flags & RT_Transmission;
        if (wi.z > F(0)) {
            if (!allow_r || !(openpbr::MicrofacetReflection(spec, wo, wi, &h) > F(0))) return F(0);
            F fr = FrDielectric(dot(wo, h), F(1) / eta_f), pr = allow_t ? fr : F(1);
            return pr * spec.D(wo, h) / (F(4) * dot(wo, h));
        }
        if (!allow_t || !(openpbr::MicrofacetTransmission(spec, e, wo, wi, TransportMode::Importance, &h, &jac) > F(0)))
            return F(0);
        F fr = FrDielectric(dot(wo, h), F(1) / eta_f), pt = allow_r ? F(1) - fr : F(1);
        return pt * spec.D(wo, h) * jac;
    }

    F pdf(const Vec3<F> &wo_, const Vec3<F> &wi_, TransportMode, uint8_t sample_flags) const {
        if (!(wo_.z != F(0)) || !(wi_.z != F(0))) return F(0);
        Vec3<F> wo = wo_, wi = wi_;
        if (wo.z < F(0)) {
            if (!thin_walled) return inside_pdf(wo, wi, sample_flags);
            wo.z = -wo.z, wi.z = -wi.z;
        }
        F p[kLobes];
        lobe_weights(wo, sample_flags, p);
        return mixture_pdf(p, wo, wi);
    }

    // The mixture's density at wi for the lobe weights p of wo (both above, or mirrored there).
    F mixture_pdf(const F *p, const Vec3<F> &wo, const Vec3<F> &wi) const {
        F total = F(0);
        for (int k = 0; k < kLobes; ++k)
            if (p[k] > F(0)) total += p[k] * lobe_pdf(k, wo, wi);
        return total;
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo_, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        if (!(wo_.z != F(0))) return invalid_sample<F>();
        Vec3<F> wo = wo_;
        bool flip = wo.z < F(0);
        Vec3<F> wi;
        F density;
        BxDFFlags lobe = GlossyReflection;
        if (flip && !thin_walled) {
            // the inside: choose reflection or transmission by the Fresnel of the sampled normal
            if (!((F(1) - M) * T > F(0))) return invalid_sample<F>();
            Vec3<F> w(wo.x, wo.y, -wo.z);
            Vec3<F> h = spec.Sample_wm(w, u);
            F e = F(1) / eta, fr = FrDielectric(dot(w, h), F(1) / eta_f);
            const bool allow_r = sample_flags & RT_Reflection, allow_t = sample_flags & RT_Transmission;
            F pr = allow_r ? (allow_t ? fr : F(1)) : F(0);
            if (!allow_r && !allow_t) return invalid_sample<F>();
            if (uc < pr) {
                wi = Reflect(w, h);
                if (!(wi.z > F(0))) return invalid_sample<F>();  // below the horizon: no sample
            } else {
                F etap;
                if (!Refract(w, h, e, &etap, &wi) || !(wi.z < F(0))) return invalid_sample<F>();
            }
            wi.z = -wi.z;
            density = inside_pdf(wo, wi, sample_flags);
        } else {
            if (flip) wo.z = -wo.z;
            F p[kLobes];
            lobe_weights(wo, sample_flags, p);
            int k = 0;
            F cdf = F(0);
            for (; k < kLobes - 1; ++k) {
                if (uc < cdf + p[k] && p[k] > F(0)) break;
                cdf += p[k];
            }
            if (!(p[k] > F(0))) {
                // rounding past the last nonzero lobe: take the last one with weight
                while (k > 0 && !(p[k] > F(0))) --k;
                if (!(p[k] > F(0))) return invalid_sample<F>();
                cdf = F(0);
                for (int j = 0; j < k; ++j) cdf += p[j];
            }
            F ur = clamp_uniform((uc - cdf) / p[k]);
            lobe = k == kDiffuse ? DiffuseReflection : k == kDiffuseT ? DiffuseTransmission : GlossyReflection;
            switch (k) {
            case kFuzz: wi = ZeltnerSheen<F>::make(wo.z, fuzz_r).sample(wo, u); break;
            case kCoat: wi = Reflect(wo, coat.Sample_wm(wo, u)); break;
            case kSpec: wi = Reflect(wo, spec.Sample_wm(wo, u)); break;
            case kTrans: {
                Vec3<F> h = spec.Sample_wm(wo, u);
                if (thin_walled) {
                    wi = Reflect(wo, h);
                    wi.z = -wi.z;  // a reflection below the horizon becomes wi.z > 0: rejected below
                } else {
                    F etap;
                    if (!Refract(wo, h, eta, &etap, &wi)) return invalid_sample<F>();
                }
                break;
            }
            case kDiffuse: wi = eon.sample_f(wo, ur, u, mode, RT_Reflection).wi; break;
            case kDiffuseT: wi = eon.sample_f(wo, ur, u, mode, RT_Reflection).wi, wi.z = -wi.z; break;
            }
            // a lobe's sample outside its own hemisphere is no sample (the densities of
            // lobe_pdf are those of the samplers on their hemisphere)
            bool into = k == kTrans || k == kDiffuseT;
            if (into ? !(wi.z < F(0)) : !(wi.z > F(0))) return invalid_sample<F>();
            density = mixture_pdf(p, wo, wi);  // the weights just drawn from: pdf()'s value
            if (flip) wi.z = -wi.z;
        }
        BSDFSample<F> s;
        s.wi = wi;
        s.pdf = density;
        s.f = f(wo_, wi, mode);
        bool transmit = wi.z * wo_.z < F(0);
        s.flags = lobe == DiffuseTransmission ? uint8_t(DiffuseTransmission) : lobe_flag(lobe, transmit);
        s.eta = transmit && !thin_walled ? (wo_.z > F(0) ? eta : F(1) / eta) : F(1);
        s.valid = s.pdf > F(0) && wi.z != F(0);
        return s;
    }

    void regularize() {}
};

} // namespace bsdfkit
