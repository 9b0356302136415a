// Filament's material models, evaluated and importance-sampled: the standard model (metallic /
// roughness, anisotropy, clear coat, sheen, multiple-scattering energy compensation) and the
// cloth model (Charlie sheen, Neubelt visibility, Lambert or wrapped diffuse).
// Sources: Filament's document "Physically Based Rendering in Filament" (cited as "doc §...")
// and its shaders (surface_brdf.fs, surface_shading_model_{standard,cloth}.fs,
// surface_shading_lit.fs, common_material.fs); notation of ../shared/research/pbrt_filament.md §4.
//
// Parameters (FilamentStandardParams; Python: bsdfkit.FilamentStandard)
//   base_color            RGB in [0,1]    diffuse albedo of dielectrics, f0 of metals
//   metallic              [0,1]           f0 = 0.16 reflectance^2 (1 - metallic) + base_color metallic
//   roughness             [0,1]           perceptual roughness r; alpha = r^2
//   reflectance           [0,1]           dielectric f0 = 0.16 reflectance^2 (0.5 -> 4 %)
//   anisotropy            [-1,1]          alpha_t = alpha (1 + a), alpha_b = alpha (1 - a) (Kulla 2017), t = x
//   clear_coat            [0,1]           strength of an IOR 1.5 GGX coat (Kelemen visibility)
//   clear_coat_roughness  [0,1]           perceptual; raises the base roughness by mix(r, max(r, r_c), cc)
//   sheen_color           RGB in [0,1]    Charlie sheen lobe; the base is scaled by 1 - max(sheen) DFG.z
//   sheen_roughness       [0,1]           perceptual roughness of the sheen lobe
// Knobs (defaults: Filament desktop, FILAMENT_QUALITY_HIGH)
//   diffuse     Lambert | Burley             (BRDF_DIFFUSE)
//   visibility  Correlated | Fast            (V_SmithGGXCorrelated | _Fast; anisotropic lobes always
//                                              use V_SmithGGXCorrelated_Anisotropic, as Filament)
//   f90         one | filament               (f90 = saturate(50 * 0.33 * sum(f0)), "specular occlusion")
//   energy_compensation                      color = Fd + Fr (1 + f0 (1 / DFG.y - 1))
//   min_perceptual_roughness                 0.045 desktop, 0.089 mobile (MIN_PERCEPTUAL_ROUGHNESS)
//   layering    Code | Doc                   (Fd + Fr) (1 - Fc) + Frc, or (Fd + Fr (1 - Fc)) (1 - Fc) + Frc
//   clear_coat_ior_change                    f0 <- mix(f0, f0ClearCoatToSurface(f0), cc) (Filament default on)
//
// Conventions. One-sided reflection models, as in Filament: f = pdf = 0 unless wo.z > 0 and
// wi.z > 0 (below the horizon nothing is reflected; never NaN). f excludes the cosine: Filament's
// per-light shading is f <NoL>, so the cloth model's wrapped diffuse, which Filament does not
// multiply by NoL, appears here divided by NoL. NoV is clamped to MIN_N_DOT_V = 1e-4 where
// Filament clamps it (visibility, Burley, DFG lookups). The shaders' fp16 overflow guards are not
// applied: the visibility floors 7.7e-6 / 3.9e-6 / 1.532e-5 (mobile only in Filament) and D_GGX's
// cap k <= 453.5 (every platform; it lowers D only for alpha < 1/453.5, perceptual roughness
// < 0.047, by up to 16 % at the peak for the desktop minimum 0.045): D_GGX here is the exact
// Trowbridge-Reitz D of core/microfacet.h, whose pbrt cutoff makes D = 0 for NoH < 1e-4.
// D_Charlie keeps its sin^2 >= 2^-7 floor (part of the shader formula on every platform).
//
// Sampling: lobe selection in proportion to each lobe's albedo estimated at wo from the DFG
// table; visible-normal sampling (core/microfacet.h) for the base and coat GGX lobes, cosine
// sampling for the diffuse lobe (cloth with a subsurface color: density proportional to
// NoL + 0.5, the wrap term), and for the sheen lobe an equal mixture of Charlie-NDF sampling
// (pdf D_Charlie cos(theta_h), sin(theta_h) = u^(alpha / (2 alpha + 1)), as Filament's cmgen)
// and the diffuse sampler. pdf is always the full mixture density; sample_f returns the full f.
#pragma once
#include <array>
#include <memory>

#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/microfacet.h"
#include "../core/sampling.h"
#include "filament_dfg.h"

namespace bsdfkit {

template <typename F> struct FilamentClothSpectral;  // its spectral form (batch_spectral.h / spectral/)

template <typename F, bool Coat, bool Sheen> struct FilamentStandardSpectralT;  // its spectral form (batch_spectral.h / spectral/)

namespace filament {

inline constexpr double kMinNoV = 1e-4;                   // MIN_N_DOT_V (common_material.fs)
inline constexpr double kMinPerceptualRoughnessDesktop = 0.045;  // MIN_PERCEPTUAL_ROUGHNESS, desktop
inline constexpr double kMinPerceptualRoughnessMobile = 0.089;   // MIN_PERCEPTUAL_ROUGHNESS, mobile
inline constexpr double kCharlieSin2Floor = 0.0078125;    // 2^-7 floor on sin^2(theta_h) (brdf.fs D_Charlie)
inline constexpr double kClearCoatF0 = 0.04;              // IOR 1.5 coat (doc §"Clear coat", f0(1.5))
inline constexpr double kF90Scale = 50.0 * 0.33;          // f90 = saturate(dot(f0, vec3(50 * 0.33)))
inline constexpr double kClothWrap = 0.5;                 // Fd_Wrap(NoL, 0.5) (shading_model_cloth.fs)

enum class DiffuseTerm : uint8_t { Lambert = 0, Burley = 1 };
enum class VisibilityTerm : uint8_t { Correlated = 0, Fast = 1 };
enum class Layering : uint8_t { Code = 0, Doc = 1 };
inline constexpr std::array<const char *, 2> enum_names(DiffuseTerm) { return {"lambert", "burley"}; }
inline constexpr std::array<const char *, 2> enum_names(VisibilityTerm) { return {"correlated", "fast"}; }
inline constexpr std::array<const char *, 2> enum_names(Layering) { return {"code", "doc"}; }

template <typename F> inline F pow5(F x) {
    F x2 = x * x;
    return x2 * x2 * x;
}
template <typename F> inline F saturate(F x) { return clamp(x, F(0), F(1)); }

// ------------------------------------------------------------------ terms (brdf.fs names)

// D_GGX and D_GGX_Anisotropic (Walter 2007; Burley 2012): with (t, b, n) = (x, y, z) both are
// the Trowbridge-Reitz D(h) of core/microfacet.h.
template <typename F> inline F D_GGX(const Microfacet<F> &mfd, const Vec3<F> &h) { return mfd.D(h); }

// D_Charlie (Estevez & Kulla 2017, brdf.fs): (2 + 1/a) sin^(1/a)(theta_h) / (2 pi), sin^2 >= 2^-7.
template <typename F> inline F D_Charlie_sin2(F alpha, F sin2h) {
    F inv = F(1) / alpha;
    F s2 = max_(sin2h, F(kCharlieSin2Floor));
    return (F(2) + inv) * pow(s2, inv * F(0.5)) * (F(0.5) * InvPi<F>);
}
template <typename F> inline F D_Charlie(F alpha, F NoH) { return D_Charlie_sin2(alpha, F(1) - NoH * NoH); }

// The normalised Charlie NDF without the floor (CubemapIBL DistributionCharlie): the density of
// the sheen sampler (with cos(theta_h)) and the DFG z channel.
template <typename F> inline F D_CharlieExact_sin2(F alpha, F sin2h) {
    F inv = F(1) / alpha;
    return (F(2) + inv) * pow(max_(sin2h, F(0)), inv * F(0.5)) * F(0.5 * InvPi<double>);
}

// D_Ashikhmin (Neubelt & Pettineo 2013 normalisation of Ashikhmin 2007 velvet; older brdf.fs):
// (4 exp(-cot^2 / a^2) + sin^4) / (pi (1 + 4 a^2) sin^4), sin^2 >= 2^-7.
template <typename F> inline F D_Ashikhmin(F alpha, F NoH) {
    F a2 = alpha * alpha, cos2h = NoH * NoH;
    F sin2h = max_(F(1) - cos2h, F(kCharlieSin2Floor));
    F sin4h = sin2h * sin2h;
    F cot2 = -cos2h / (a2 * sin2h);
    return (F(4) * std::exp(cot2) + sin4h) / (Pi<F> * (F(4) * a2 + F(1)) * sin4h);
}

// V_SmithGGXCorrelated (Heitz 2014, brdf.fs): 0.5 / (NoL sqrt(NoV^2 (1 - a^2) + a^2) + NoV sqrt(NoL^2 (1 - a^2) + a^2)).
template <typename F> inline F V_SmithGGXCorrelated(F alpha, F NoV, F NoL) {
    F a2 = alpha * alpha;
    F lambdaV = NoL * sqrt((NoV - a2 * NoV) * NoV + a2);
    F lambdaL = NoV * sqrt((NoL - a2 * NoL) * NoL + a2);
    return F(0.5) / (lambdaV + lambdaL);
}

// V_SmithGGXCorrelated_Fast (Hammon 2017, brdf.fs): 0.5 / mix(2 NoL NoV, NoL + NoV, a).
template <typename F> inline F V_SmithGGXCorrelated_Fast(F alpha, F NoV, F NoL) {
    return F(0.5) / lerp(alpha, F(2) * NoL * NoV, NoL + NoV);
}

// V_SmithGGXCorrelated_Anisotropic (Heitz 2014, brdf.fs):
// 0.5 / (NoL |(at ToV, ab BoV, NoV)| + NoV |(at ToL, ab BoL, NoL)|).
template <typename F>
inline F V_SmithGGXCorrelated_Anisotropic(F at, F ab, F ToV, F BoV, F ToL, F BoL, F NoV, F NoL) {
    F lambdaV = NoL * sqrt(sqr(at * ToV) + sqr(ab * BoV) + NoV * NoV);
    F lambdaL = NoV * sqrt(sqr(at * ToL) + sqr(ab * BoL) + NoL * NoL);
    return F(0.5) / (lambdaV + lambdaL);
}

// V_Kelemen (Kelemen 2001, brdf.fs): 0.25 / LoH^2 (LoH^2 floored at the smallest normal number
// so that an underflowing LoH cannot make it infinite).
template <typename F> inline F V_Kelemen(F LoH) {
    return F(0.25) / max_(LoH * LoH, std::numeric_limits<F>::min());
}

// V_Neubelt (Neubelt & Pettineo 2013, brdf.fs): 1 / (4 (NoL + NoV - NoL NoV)).
template <typename F> inline F V_Neubelt(F NoV, F NoL) { return F(1) / (F(4) * (NoL + NoV - NoL * NoV)); }

// F_Schlick (Schlick 1994, brdf.fs): f0 + (f90 - f0) (1 - VoH)^5.
template <typename F> inline F F_Schlick(F f0, F f90, F VoH) { return f0 + (f90 - f0) * pow5(F(1) - VoH); }
template <typename F> inline Spectrum<F> F_Schlick(const Spectrum<F> &f0, F f90, F VoH) {
    F fc = pow5(F(1) - VoH);
    return f0 + (Spectrum<F>(f90) - f0) * fc;
}

// Fd_Lambert (brdf.fs): 1 / pi.
template <typename F> inline F Fd_Lambert() { return InvPi<F>; }

// Fd_Burley (Burley 2012, brdf.fs): F_Schlick(1, f90, NoL) F_Schlick(1, f90, NoV) / pi, f90 = 0.5 + 2 a LoH^2.
template <typename F> inline F Fd_Burley(F alpha, F NoV, F NoL, F LoH) {
    F f90 = F(0.5) + F(2) * alpha * LoH * LoH;
    return F_Schlick(F(1), f90, NoL) * F_Schlick(F(1), f90, NoV) * F(InvPi<scalar_t<F>>);
}

// Fd_Wrap (brdf.fs, energy-conserving wrap, no 1/pi): saturate((NoL + w) / (1 + w)^2).
template <typename F> inline F Fd_Wrap(F NoL, F w) { return saturate((NoL + w) / sqr(F(1) + w)); }

// f0ClearCoatToSurface (common_material.fs, desktop fit of iorToF0(f0ToIor(f0), 1.5)); T is
// double (make() computes in double) or a Dual (core/dual.h).
template <typename T> inline T f0ClearCoatToSurface(T f0) {
    return saturate(f0 * (f0 * (T(0.941892) - T(0.263008) * f0) + T(0.346479)) - T(0.0285998));
}

// ------------------------------------------------------------------ samplers

// Charlie NDF sampling (cmgen hemisphereImportanceSampleDCharlie): pdf_h = D_CharlieExact cos(theta_h).
template <typename F> inline Vec3<F> SampleCharlie(F alpha, Point2<F> u) {
    F sin_t = pow(u.x, alpha / (F(2) * alpha + F(1)));
    F cos_t = safe_sqrt(F(1) - sin_t * sin_t);
    F phi = F(2 * Pi<double>) * u.y, sp, cp;
    sincos_(phi, &sp, &cp);
    return {sin_t * cp, sin_t * sp, cos_t};
}
template <typename F> inline F CharliePDF(F alpha, const Vec3<F> &h) {
    return D_CharlieExact_sin2(alpha, h.x * h.x + h.y * h.y) * max_(h.z, F(0));
}

// Hemisphere density proportional to cos(theta) + w (w = 0.5 matches Fd_Wrap):
// pdf = (mu + w) / (2 pi (1/2 + w)); mu from the inverse CDF (mu^2 / 2 + w mu) / (1/2 + w) = u,
// written without cancellation.
template <typename F> inline Vec3<F> SampleWrapHemisphere(Point2<F> u, F w) {
    F c = u.x * (F(1) + F(2) * w);
    F mu = c / (w + std::sqrt(w * w + c));
    F r = safe_sqrt(F(1) - mu * mu), phi = F(2) * Pi<F> * u.y, sp, cp;
    sincos_(phi, &sp, &cp);
    return {r * cp, r * sp, mu};
}
template <typename F> inline F WrapHemispherePDF(F mu, F w) {
    return (max_(mu, F(0)) + w) * (Inv2Pi<F> / (F(0.5) + w));
}

} // namespace filament

// ====================================================================== standard model

// S: the continuous parameters' scalar type, double (core/math.h param_t; a Dual for gradients,
// core/dual.h); the knobs stay plain.
template <typename S = double> struct FilamentStandardParamsT {
    std::array<S, 3> base_color{0.8, 0.8, 0.8};
    S metallic = 0, roughness = 0.5, reflectance = 0.5, anisotropy = 0;
    S clear_coat = 0, clear_coat_roughness = 0;
    std::array<S, 3> sheen_color{0, 0, 0};
    S sheen_roughness = 0;
    filament::DiffuseTerm diffuse = filament::DiffuseTerm::Lambert;
    filament::VisibilityTerm visibility = filament::VisibilityTerm::Correlated;
    bool f90_filament = true;
    bool energy_compensation = true;
    double min_perceptual_roughness = filament::kMinPerceptualRoughnessDesktop;
    filament::Layering layering = filament::Layering::Code;
    bool clear_coat_ior_change = true;
    SharedTable<FilamentDFG> dfg;  // required (bsdfkit.filament's cached table)

    template <class V> void fields(V &&v) {
        v("base_color", base_color);
        v("metallic", metallic);
        v("roughness", roughness);
        v("reflectance", reflectance);
        v("anisotropy", anisotropy);
        v("clear_coat", clear_coat);
        v("clear_coat_roughness", clear_coat_roughness);
        v("sheen_color", sheen_color);
        v("sheen_roughness", sheen_roughness);
        v("diffuse", diffuse);
        v("visibility", visibility);
        v("f90_filament", f90_filament);
        v("energy_compensation", energy_compensation);
        v("min_perceptual_roughness", min_perceptual_roughness);
        v("layering", layering);
        v("clear_coat_ior_change", clear_coat_ior_change);
        v("dfg", dfg);
    }
};
using FilamentStandardParams = FilamentStandardParamsT<>;

// Written for the batch kernels' vectorizer: uniform switches are stored as F (0 or 1) and
// applied with compares/selects or as arithmetic factors (a bool loaded from the model cannot
// mask a float vector), and the optional lobes are compile-time variants: Coat (a lobe the
// common case should not pay for) and Sheen (whose pow() has no vector form), so the common
// case has no call and no branch per element.
static_assert(DiffuseReflection == GlossyReflection - (Glossy - Diffuse));

template <typename F, bool Coat, bool Sheen> struct FilamentStandardKernel {
    // Derived at construction (surface_shading_lit.fs getPixelParams), see make().
    Spectrum<F> diffuse_color{F(0)}, f0{F(0)}, sheen_color{F(0)};
    F f90 = 1;
    F alpha = 0;              // base GGX alpha after the clear-coat raise and the clamp
    Microfacet<F> spec;  // (alpha_t, alpha_b) on (x, y)
    Microfacet<F> coat;  // isotropic clear-coat alpha
    F clear_coat = 0, sheen_alpha = 1, sheen_max = 0, diffuse_max = 0;
    // knobs as 0/1 factors
    F anisotropic = 0, fast_v = 0, burley = 0, energy_compensation = 1, doc_layering = 0;
    DFGRow<F> dfg_base, dfg_coat, dfg_sheen;   // DFG rows at the base / coat / sheen roughness


    uint8_t flags() const { return diffuse_max > F(0) ? uint8_t(GlossyReflection | Diffuse) : uint8_t(GlossyReflection); }

    // The kernel runs on packets in the batch kernels (batch.h): every method is written once on the
    // evaluation type V (F, a packet of F, or a Dual of the gradient path, core/dual.h; the knobs
    // are uniform branches). Only IEEE-exact operations (+ - * / sqrt floor select) and libm's pow
    // (pow_libm, per lane) enter f, so that a float64 packet gives the Dual path's value bit for bit.
    static constexpr bool Vectorized = true;

    // Sheen scaling 1 - max(sheenColor) DFG.z(sheen roughness, NoV), floored at 0: the sheen albedo
    // z exceeds 1 at grazing NoV for sheen roughness below ~0.1 (up to ~10), where Filament's
    // factor turns negative; here the base is switched off instead of subtracted.
    template <typename V> V sheen_scaling(V NoV) const {
        if constexpr (Sheen) return max_(V(1) - V(sheen_max) * dfg_sheen.lookup(NoV, 2), V(0)); else return V(1);
    }

    // visibility() of brdf.fs as its denominator: V = 0.5 / lambda. Anisotropic lobes always use
    // V_SmithGGXCorrelated_Anisotropic (as Filament); else V_SmithGGXCorrelated or its _Fast form.
    template <typename V> V visibility_denom(const Vec3<V> &wo, const Vec3<V> &wi, V NoV, V NoL) const {
        if (anisotropic > F(0)) {
            V at(spec.alpha_x), ab(spec.alpha_y);
            return NoL * sqrt(sqr(at * wo.x) + sqr(ab * wo.y) + NoV * NoV) +
                   NoV * sqrt(sqr(at * wi.x) + sqr(ab * wi.y) + NoL * NoL);
        }
        V a(spec.alpha_x);
        if (fast_v > F(0)) return lerp(a, V(2) * NoL * NoV, NoL + NoV);
        V a2 = a * a;
        return NoL * sqrt((NoV - a2 * NoV) * NoV + a2) + NoV * sqrt((NoL - a2 * NoL) * NoL + a2);
    }
    template <typename V> V diffuse(V NoV, V NoL, V LoH) const {
        if (burley > F(0)) return filament::Fd_Burley(V(alpha), NoV, NoL, LoH);
        return V(InvPi<scalar_t<V>>);
    }

    // f = ((Fd + Fr Ec [(1 - Fc)]) sheenScaling + Fsheen) (1 - Fc) + Frc   (surfaceShading, cosine excluded)
    // Divisions: the half vector 1, D V Ec / one product (D = 1 / D_denom, core/microfacet.h; V = 0.5 /
    // lambda; Ec = (y + f0 (1 - y)) / y, y = DFG.y) 1, sheen 1, coat 1.
    template <typename V> Spectrum<V> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode) const {
        using namespace filament;
        Mask<V> active = (wo.z > V(0)) & (wi.z > V(0));
        Vec3<V> h = reflection_half_vector(wo, wi, active);
        V NoV = max_(wo.z, V(kMinNoV));  // clampNoV
        V NoL = saturate(wi.z);
        V LoH = saturate(dot(wi, h));
        // Clear coat Fresnel (clearCoatLobe): Fc = F_Schlick(0.04, 1, LoH) clearCoat
        V Fc = V(0);
        if constexpr (Coat) Fc = F_Schlick(V(kClearCoatF0), V(1), LoH) * V(clear_coat);
        // Base specular lobe D V F Ec (isotropicLobe / anisotropicLobe; getEnergyCompensationPixelParams)
        Mask<V> d_ok = active;
        V dd = spec.D_denom(h, d_ok);
        V y = dfg_base.lookup(NoV, 1);
        V dv = V(0.5) * (V(1) - V(doc_layering) * Fc) / (dd * visibility_denom(wo, wi, NoV, NoL) * y);
        dv = select(d_ok, dv, V(0));
        V fc5 = pow5(V(1) - LoH), ec = V(energy_compensation) * (V(1) - y);
        Spectrum<V> color;
        V fd = diffuse(NoV, NoL, LoH);
        for (int c = 0; c < 3; ++c) {
            V f0c(f0[c]);
            V Fs = f0c + (V(f90) - f0c) * fc5;  // F_Schlick(f0, f90, LoH)
            color[c] = V(diffuse_color[c]) * fd + Fs * ((y + f0c * ec) * dv);
        }
        // Sheen lobe (sheenLobe) after scaling the base: D_Charlie V_Neubelt
        if constexpr (Sheen) {
            V inv_a = V(F(1) / sheen_alpha);
            V s2 = max_(h.x * h.x + h.y * h.y, V(kCharlieSin2Floor));
            V ds = (V(2) + inv_a) * pow_libm(s2, inv_a * V(0.5)) * V(0.5 * InvPi<double>);
            V sv = ds / (V(4) * (NoL + NoV - NoL * NoV));
            V sc = sheen_scaling(NoV);
            for (int c = 0; c < 3; ++c) color[c] = color[c] * sc + V(sheen_color[c]) * sv;
        }
        // Clear coat lobe D_GGX(alpha_c) V_Kelemen(LoH) Fc on top of the attenuated base:
        // Fc 0.25 / (D_denom LoH^2) (LoH^2 floored at the smallest normal number)
        if constexpr (Coat) {
            Mask<V> c_ok = active;
            V ddc = coat.D_denom(h, c_ok);
            V frc = select(c_ok, Fc * V(0.25) / (ddc * max_(LoH * LoH, V(std::numeric_limits<scalar_t<V>>::min()))), V(0));
            for (int c = 0; c < 3; ++c) color[c] = color[c] * (V(1) - Fc) + frc;
        }
        return select(active, color, Spectrum<V>(V(0)));
    }

    // Lobe selection probabilities at wo, in proportion to each lobe's estimated albedo:
    // diffuse and the sheen's cosine half share the cosine sampler. All weights are scaled by
    // DFG.y so that Ec's 1 / y cancels: one division.
    template <typename V> struct Lobes {
        V diffuse, sheen_cos, ggx, coat, charlie;
    };
    template <typename V> Lobes<V> lobes(V NoV) const {
        using namespace filament;
        V att = V(1);
        if constexpr (Coat) att = V(1) - F_Schlick(V(kClearCoatF0), V(1), NoV) * V(clear_coat);
        V x = dfg_base.lookup(NoV, 0), y = dfg_base.lookup(NoV, 1);
        V scale = sheen_scaling(NoV);
        V ec = V(energy_compensation) * (V(1) - y);
        // Schlick GGX albedo (f0 (y - x) + f90 x) Ec, times y
        V es = V(0);
        for (int c = 0; c < 3; ++c) {
            V f0c(f0[c]);
            es = max_(es, (f0c * (y - x) + V(f90) * x) * (y + f0c * ec));
        }
        V w_spec = es * scale * att * (V(1) - V(doc_layering) * (V(1) - att));
        V w_diff = V(diffuse_max) * scale * att * y;
        V w_coat = V(0), w_sheen = V(0);
        if constexpr (Coat) {
            V xc = dfg_coat.lookup(NoV, 0), yc = dfg_coat.lookup(NoV, 1);
            w_coat = V(clear_coat) * (V(kClearCoatF0) * (yc - xc) + xc) * y;
        }
        if constexpr (Sheen) w_sheen = V(sheen_max) * dfg_sheen.lookup(NoV, 2) * att * y;
        V total = w_spec + w_diff + w_sheen + w_coat;
        Mask<V> ok = total > V(0);
        V inv = V(1) / select(ok, total, V(1));
        Lobes<V> l;
        l.diffuse = w_diff * inv;
        l.sheen_cos = V(0.5) * w_sheen * inv;
        l.charlie = l.sheen_cos;
        l.coat = w_coat * inv;
        l.ggx = select(ok, w_spec * inv, V(1));
        return l;
    }

    template <typename V>
    BSDFSample<V> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode mode, uint8_t sample_flags) const {
        using namespace filament;
        V NoV = max_(wo.z, V(kMinNoV));
        Lobes<V> l = lobes(NoV);
        V c_diff = l.diffuse, c_cos = c_diff + l.sheen_cos, c_ggx = c_cos + l.ggx, c_coat = c_ggx + l.coat;
        Mask<V> pick_cos = uc < c_cos;
        Mask<V> pick_ggx = (!pick_cos) & (uc < c_ggx);
        Mask<V> pick_coat = Mask<V>(Coat) & !pick_cos & !pick_ggx & (uc < c_coat) & (l.coat > V(0));
        // One visible-normal sample for whichever GGX lobe was picked
        Microfacet<V> d;
        d.alpha_x = select(pick_coat, V(coat.alpha_x), V(spec.alpha_x));
        d.alpha_y = select(pick_coat, V(coat.alpha_y), V(spec.alpha_y));
        Vec3<V> wi = Reflect(wo, d.Sample_wm(wo, u));
        if constexpr (Sheen) {
            Mask<V> pick_charlie = (!pick_cos) & (!pick_ggx) & (!pick_coat) & (l.charlie > V(0));
            wi = select(pick_charlie, Reflect(wo, SampleCharlie(V(sheen_alpha), u)), wi);
        }
        wi = select(pick_cos, SampleCosineHemisphere(u), wi);
        BSDFSample<V> s;
        s.wi = wi;
        s.f = f(wo, wi, mode);
        s.pdf = pdf(wo, wi, mode, sample_flags);
        s.flags = select_flag<V>(pick_cos & (uc < c_diff), DiffuseReflection, GlossyReflection);
        s.valid = Mask<V>((sample_flags & RT_Reflection) != 0) & (wo.z > V(0)) & (wi.z > V(0));
        return s;
    }

    // Full mixture density: sum of selection probability x lobe sampler density. A GGX lobe's
    // visible-normal density through the reflection Jacobian is 1 / (D_denom 2 (cos_o + root_o))
    // (core/microfacet.h): one division per lobe.
    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode, uint8_t sample_flags) const {
        using namespace filament;
        Mask<V> active = (wo.z > V(0)) & (wi.z > V(0)) & Mask<V>((sample_flags & RT_Reflection) != 0);
        Vec3<V> h = reflection_half_vector(wo, wi, active);
        Lobes<V> l = lobes(max_(wo.z, V(kMinNoV)));
        V cos_o = wo.z;
        Mask<V> s_ok = active;
        V dds = spec.D_denom(h, s_ok);
        V p = (l.diffuse + l.sheen_cos) * CosineHemispherePDF(wi.z) +
              select(s_ok, l.ggx / (dds * spec.reflection_pdf_denom(cos_o, spec.smith_root(wo))), V(0));
        if constexpr (Coat) {
            Mask<V> c_ok = active;
            V ddc = coat.D_denom(h, c_ok);
            p += select(c_ok, l.coat / (ddc * coat.reflection_pdf_denom(cos_o, coat.smith_root(wo))), V(0));
        }
        if constexpr (Sheen) p += l.charlie * CharliePDF(V(sheen_alpha), h) / (V(4) * abs(dot(wo, h)));
        return select(active, p, V(0));
    }

    void regularize() {
        spec.regularize();
        coat.regularize();
    }
};

// The model: the kernel (trivially copyable, so the batch kernels work on a per-chunk local copy
// whose parameters stay in registers) plus the shared DFG table it points into (core/table.h).
template <typename F, bool Coat, bool Sheen> struct FilamentStandardT : FilamentStandardKernel<F, Coat, Sheen> {
    using Kernel = FilamentStandardKernel<F, Coat, Sheen>;
    using Params = FilamentStandardParamsT<param_t<F>>;
    static constexpr const char *Name = Coat ? (Sheen ? "FilamentStandardCoatSheen" : "FilamentStandardCoat")
                                             : (Sheen ? "FilamentStandardSheen" : "FilamentStandard");
    using Spectral = FilamentStandardSpectralT<F, Coat, Sheen>;  // its spectral form (core/bxdf.h)
    static constexpr int GradColumns = 16;  // eval_grad columns at most
    SharedTable<FilamentDFG> dfg;  // keeps the table alive

    // One colour channel's f0 and diffuse colour from its base colour (surface_shading_lit.fs
    // getPixelParams: computeDielectricF0, computeF0 with CLEAR_COAT_IOR_CHANGE, computeDiffuseColor);
    // make() per RGB channel, the spectral adapter (batch_spectral.h) per wavelength.
    template <typename S>
    static void surface_colors(const FilamentStandardParamsT<S> &p, S base, S *f0, S *diffuse) {
        using namespace filament;
        S f0d = S(0.16) * p.reflectance * p.reflectance;  // computeDielectricF0
        S f = base * p.metallic + f0d * (S(1) - p.metallic);  // computeF0
        if (p.clear_coat_ior_change) f = lerp(p.clear_coat, f, f0ClearCoatToSurface(f));
        *f0 = f;
        *diffuse = base * (S(1) - p.metallic);
    }

    // Derived parameters in S = param_t<F>: double, or the Dual of a gradient model, so that
    // derivatives flow through this preprocessing (core/dual.h lists the one-sided points: the
    // roughness clamps, saturate(f90), the alpha floors, the DFG rows' bilinear weights).
    static FilamentStandardT make(const Params &p) {
        using namespace filament;
        using S = param_t<F>;
        const FilamentDFG *table = p.dfg.get();
        FilamentStandardT m;
        double min_pr = p.min_perceptual_roughness, min_alpha = min_pr * min_pr;
        S cc = p.clear_coat;
        for (int c = 0; c < 3; ++c) {
            S f0, diffuse;
            surface_colors(p, p.base_color[c], &f0, &diffuse);
            m.f0[c] = F(f0);
            m.diffuse_color[c] = F(diffuse);
            m.sheen_color[c] = Sheen ? F(p.sheen_color[c]) : F(0);
        }
        S sum_f0 = S(m.f0[0]) + S(m.f0[1]) + S(m.f0[2]);
        m.f90 = p.f90_filament ? F(saturate(S(kF90Scale) * sum_f0)) : F(1);  // fresnel(), quality > LOW
        // getClearCoatPixelParams / getRoughnessPixelParams
        S cc_pr = clamp(p.clear_coat_roughness, S(min_pr), S(1));
        S pr = lerp(cc, p.roughness, p.roughness > cc_pr ? p.roughness : cc_pr);
        pr = clamp(pr, S(min_pr), S(1));
        S a = pr * pr;
        // anisotropicLobe: at = max(a (1 + aniso), MIN_ROUGHNESS), ab = max(a (1 - aniso), MIN_ROUGHNESS)
        S at = a * (S(1) + p.anisotropy), ab = a * (S(1) - p.anisotropy);
        at = at > S(min_alpha) ? at : S(min_alpha);
        ab = ab > S(min_alpha) ? ab : S(min_alpha);
        m.alpha = F(a);
        m.spec = Microfacet<F>(F(at), F(ab), Masking::Correlated);
        m.coat = Microfacet<F>(F(cc_pr * cc_pr), F(cc_pr * cc_pr), Masking::Correlated);
        m.clear_coat = Coat ? F(cc) : F(0);
        S s_pr = clamp(p.sheen_roughness, S(min_pr), S(1));  // getSheenPixelParams
        m.sheen_alpha = F(s_pr * s_pr);
        m.sheen_max = m.sheen_color.max_component();
        m.diffuse_max = m.diffuse_color.max_component();
        // A differentiated anisotropy takes the anisotropic V even at 0 (equal in value there; the
        // isotropic form would miss d V / d anisotropy).
        m.anisotropic = (p.anisotropy != S(0)) | is_variable(p.anisotropy) ? F(1) : F(0);
        m.fast_v = p.visibility == VisibilityTerm::Fast ? F(1) : F(0);
        m.burley = p.diffuse == DiffuseTerm::Burley ? F(1) : F(0);
        m.energy_compensation = p.energy_compensation ? F(1) : F(0);
        m.doc_layering = p.layering == Layering::Doc ? F(1) : F(0);
        const scalar_t<F> *d = table->template data<scalar_t<F>>();
        m.dfg_base = DFGRow<F>(d, table->size, pr);
        m.dfg_coat = DFGRow<F>(d, table->size, cc_pr);
        m.dfg_sheen = DFGRow<F>(d, table->size, s_pr);
        m.dfg = p.dfg;
        return m;
    }
};

// The variants the bindings expose (Python picks by whether clear_coat and sheen_color are non-zero);
// a variant without a lobe equals the general model with that lobe's strength 0.
template <typename F> using FilamentStandardBxDF = FilamentStandardT<F, false, false>;
template <typename F> using FilamentStandardCoatBxDF = FilamentStandardT<F, true, false>;
template <typename F> using FilamentStandardSheenBxDF = FilamentStandardT<F, false, true>;
template <typename F> using FilamentStandardCoatSheenBxDF = FilamentStandardT<F, true, true>;

// ====================================================================== cloth model

// S: the continuous parameters' scalar type (as FilamentStandardParamsT; a Dual for gradients).
template <typename S = double> struct FilamentClothParamsT {
    std::array<S, 3> base_color{0.5, 0.5, 0.5};
    std::array<S, 3> sheen_color{0.7071067811865476, 0.7071067811865476, 0.7071067811865476};
    std::array<S, 3> subsurface_color{0, 0, 0};
    bool has_subsurface = false;
    S roughness = 0.5;
    filament::DiffuseTerm diffuse = filament::DiffuseTerm::Lambert;
    double min_perceptual_roughness = filament::kMinPerceptualRoughnessDesktop;
    SharedTable<FilamentDFG> dfg;  // required (bsdfkit.filament's cached table)

    template <class V> void fields(V &&v) {
        v("base_color", base_color);
        v("sheen_color", sheen_color);
        v("subsurface_color", subsurface_color);
        v("has_subsurface", has_subsurface);
        v("roughness", roughness);
        v("diffuse", diffuse);
        v("min_perceptual_roughness", min_perceptual_roughness);
        v("dfg", dfg);
    }
};
using FilamentClothParams = FilamentClothParamsT<>;

// Cloth (surface_shading_model_cloth.fs): Fr = D_Charlie V_Neubelt sheenColor (no Fresnel, no
// energy compensation); Fd = diffuse baseColor, or with a subsurface color
// Fd = diffuse Fd_Wrap(NoL, 0.5) saturate(subsurfaceColor + NoL) baseColor, which Filament does not
// multiply by NoL: here f = Fd / NoL + Fr (f <NoL> is bounded; f itself grows as 1/NoL at the horizon).
template <typename F> struct FilamentClothKernel {
    Spectrum<F> base_color{F(0)}, sheen_color{F(0)}, subsurface_color{F(0)};
    F alpha = 0.25, base_max = 0, sheen_max = 0;
    F subsurface = 0, burley = 0;  // knobs as 0/1 factors (see FilamentStandardT)
    DFGRow<F> dfg_row;


    uint8_t flags() const { return base_max > F(0) ? uint8_t(GlossyReflection | Diffuse) : uint8_t(GlossyReflection); }

    // brdf.fs diffuse() dispatch (the knob as a 0/1 factor)
    F diffuse(F NoV, F NoL, F LoH) const {
        return burley > F(0) ? filament::Fd_Burley(alpha, NoV, NoL, LoH) : filament::Fd_Lambert<F>();
    }

    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const {
        using namespace filament;
        bool active = (wo.z > F(0)) & (wi.z > F(0));
        Vec3<F> h = reflection_half_vector(wo, wi, active);
        F NoV = max_(wo.z, F(kMinNoV));
        F NoL = saturate(wi.z);
        F LoH = saturate(dot(wi, h));
        // specular: D_Charlie V_Neubelt sheenColor
        Spectrum<F> Fr = sheen_color * (D_Charlie_sin2(alpha, h.x * h.x + h.y * h.y) * V_Neubelt(NoV, NoL));
        F fd = diffuse(NoV, NoL, LoH);
        // with a subsurface color: wrapped diffuse and cheap subsurface, which Filament does not
        // multiply by NoL: divide here
        F wrap = Fd_Wrap(NoL, F(kClothWrap)) / max_(NoL, std::numeric_limits<F>::min());
        bool ss = subsurface > F(0);
        Spectrum<F> Fd;
        for (int c = 0; c < 3; ++c)
            Fd[c] = base_color[c] * fd * (ss ? saturate(subsurface_color[c] + NoL) * wrap : F(1));
        return select(active, Fd + Fr, Spectrum<F>(F(0)));
    }

    // Probabilities of the base sampler (cosine, or cos + 0.5 with a subsurface color; also the
    // sheen's defensive half) and of the Charlie sampler.
    struct Lobes {
        F diffuse, sheen_base, charlie;
    };
    Lobes lobes(F NoV) const {
        F w_diff = base_max;
        F w_sheen = sheen_max * dfg_row(NoV, 2);
        F total = w_diff + w_sheen;
        bool ok = total > F(0);
        F inv = F(1) / (ok ? total : F(1));
        Lobes l;
        l.diffuse = ok ? w_diff * inv : F(1);
        l.sheen_base = F(0.5) * w_sheen * inv;
        l.charlie = F(0.5) * w_sheen * inv;
        return l;
    }

    F base_pdf(F mu) const {
        return subsurface > F(0) ? filament::WrapHemispherePDF(mu, F(filament::kClothWrap)) : CosineHemispherePDF(mu);
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        using namespace filament;
        Lobes l = lobes(max_(wo.z, F(kMinNoV)));
        bool pick_base = uc < l.diffuse + l.sheen_base;
        Vec3<F> wb = select(subsurface > F(0), SampleWrapHemisphere(u, F(kClothWrap)), SampleCosineHemisphere(u));
        Vec3<F> wi = select(pick_base, wb, Reflect(wo, SampleCharlie(alpha, u)));
        BSDFSample<F> s;
        s.wi = wi;
        s.f = f(wo, wi, mode);
        s.pdf = pdf(wo, wi, mode, sample_flags);
        // Flags by arithmetic (rule V2, core/math.h).
        s.flags = uint8_t(GlossyReflection - (Glossy - Diffuse) * int(pick_base & (uc < l.diffuse)));
        s.valid = ((sample_flags & RT_Reflection) != 0) & (wo.z > F(0)) & (wi.z > F(0));
        return s;
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        using namespace filament;
        bool active = (wo.z > F(0)) & (wi.z > F(0));
        Vec3<F> h = reflection_half_vector(wo, wi, active);
        Lobes l = lobes(max_(wo.z, F(kMinNoV)));
        F p = (l.diffuse + l.sheen_base) * base_pdf(wi.z) + l.charlie * CharliePDF(alpha, h) / (F(4) * absdot(wo, h));
        return keep_or_zero(active ? p : F(0), (sample_flags & RT_Reflection) != 0);
    }

    void regularize() {}
};

// The model: the kernel (trivially copyable, so the batch kernels work on a per-chunk local copy
// whose parameters stay in registers) plus the shared DFG table it points into.
template <typename F> struct FilamentClothBxDF : FilamentClothKernel<F> {
    using Kernel = FilamentClothKernel<F>;
    using Params = FilamentClothParamsT<param_t<F>>;
    static constexpr const char *Name = "FilamentCloth";
    using Spectral = FilamentClothSpectral<F>;  // its spectral form (core/bxdf.h)
    static constexpr int GradColumns = 16;  // eval_grad columns at most
    SharedTable<FilamentDFG> dfg;  // keeps the table alive

    // Derived parameters in S = param_t<F> (a Dual for gradients: the roughness clamp is one-sided,
    // core/dual.h; the DFG row only weights the sampler, not f).
    static FilamentClothBxDF make(const Params &p) {
        using S = param_t<F>;
        const FilamentDFG *table = p.dfg.get();
        FilamentClothBxDF m;
        for (int c = 0; c < 3; ++c) {
            m.base_color[c] = F(p.base_color[c]);
            m.sheen_color[c] = F(p.sheen_color[c]);
            m.subsurface_color[c] = F(p.subsurface_color[c]);
        }
        m.subsurface = p.has_subsurface ? F(1) : F(0);
        S pr = clamp(p.roughness, S(p.min_perceptual_roughness), S(1));  // getRoughnessPixelParams
        m.alpha = F(pr * pr);
        m.base_max = m.base_color.max_component();
        m.sheen_max = m.sheen_color.max_component();
        m.burley = p.diffuse == filament::DiffuseTerm::Burley ? F(1) : F(0);
        m.dfg_row = DFGRow<F>(table->template data<scalar_t<F>>(), table->size, pr);
        m.dfg = p.dfg;
        return m;
    }
};

} // namespace bsdfkit
