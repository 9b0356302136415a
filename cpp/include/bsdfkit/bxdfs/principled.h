// Principled: Mitsuba 3's `principled` BSDF (Burley 2012 "Physically Based Shading at Disney" and
// Burley 2015 "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering", as
// Mitsuba 3.9 writes it in src/bsdfs/principled.cpp and principledhelpers.h), term for term, so
// that eval and pdf agree with Mitsuba's pointwise. Lobes, each weighted as Mitsuba weights it:
//   diffuse      (1 - metallic)(1 - spec_trans) base/pi [lerp(Burley diffuse + retro, fake SSS, flatness)]
//   sheen        sheen (1 - metallic) Schlick(cos_d) lerp(1, tint, sheen_tint)
//   main specular  anisotropic GGX, separable Smith G, the "principled" Fresnel (dielectric, metallic
//                Schlick and tinted Schlick blended), reflection on both sides
//   transmission (1 - metallic) spec_trans sqrt(base) rough dielectric transmission (Walter 2007)
//   clearcoat    0.25 clearcoat Schlick(0.04) GTR1(alpha_cc) G(0.25), Mitsuba's form (no 1/(4 cos cos))
// Mitsuba's conventions: wo (its si.wi) above the surface sees every lobe; below it (the
// material's inside) only the main specular reflection (bsdf-weighted dielectric Fresnel) and the
// transmission. Where the material has no transmission, it is black from below (f = pdf = 0;
// Mitsuba's pdf there is the specular lobe's density though its sampler returns nothing).
// Sampling: Mitsuba's lobe probabilities (with its three sampling rates) and densities: the
// cosine hemisphere, GTR1 normals (Burley 2012 eq. 2), visible GGX normals; the pdf is the mixture.
// Scalar code (not packet-vectorized); not differentiable; no spectral form (the tints divide the
// colour by its luminance, which has no per-wavelength meaning).
#pragma once
#include <array>

#include "../core/bsdf_sample.h"
#include "../core/bxdf.h"
#include "../core/frame.h"
#include "../core/fresnel.h"
#include "../core/microfacet.h"
#include "../core/sampling.h"

namespace bsdfkit {

// The parameters under Mitsuba's names (eta: the Python class converts `specular` to it).
struct PrincipledParams {
    std::array<double, 3> base_color{0.5, 0.5, 0.5};
    double roughness = 0.5, anisotropic = 0, metallic = 0, spec_trans = 0, eta = 1.5;
    double spec_tint = 0, sheen = 0, sheen_tint = 0, flatness = 0, clearcoat = 0, clearcoat_gloss = 0;
    double main_specular_sampling_rate = 1, clearcoat_sampling_rate = 1, diffuse_reflectance_sampling_rate = 1;
    template <class V> void fields(V &&v) {
        v("base_color", base_color);
        v("roughness", roughness);
        v("anisotropic", anisotropic);
        v("metallic", metallic);
        v("spec_trans", spec_trans);
        v("eta", eta);
        v("spec_tint", spec_tint);
        v("sheen", sheen);
        v("sheen_tint", sheen_tint);
        v("flatness", flatness);
        v("clearcoat", clearcoat);
        v("clearcoat_gloss", clearcoat_gloss);
        v("main_specular_sampling_rate", main_specular_sampling_rate);
        v("clearcoat_sampling_rate", clearcoat_sampling_rate);
        v("diffuse_reflectance_sampling_rate", diffuse_reflectance_sampling_rate);
    }
};

// PrincipledThin's parameters under Mitsuba's names (principledthin.cpp): diff_trans in [0, 2].
struct PrincipledThinParams {
    std::array<double, 3> base_color{0.5, 0.5, 0.5};
    double roughness = 0.5, anisotropic = 0, spec_trans = 0, eta = 1.5, spec_tint = 0, sheen = 0, sheen_tint = 0;
    double flatness = 0, diff_trans = 0;
    double specular_reflectance_sampling_rate = 1, specular_transmittance_sampling_rate = 1;
    double diffuse_reflectance_sampling_rate = 1, diffuse_transmittance_sampling_rate = 1;
    template <class V> void fields(V &&v) {
        v("base_color", base_color);
        v("roughness", roughness);
        v("anisotropic", anisotropic);
        v("spec_trans", spec_trans);
        v("eta", eta);
        v("spec_tint", spec_tint);
        v("sheen", sheen);
        v("sheen_tint", sheen_tint);
        v("flatness", flatness);
        v("diff_trans", diff_trans);
        v("specular_reflectance_sampling_rate", specular_reflectance_sampling_rate);
        v("specular_transmittance_sampling_rate", specular_transmittance_sampling_rate);
        v("diffuse_reflectance_sampling_rate", diffuse_reflectance_sampling_rate);
        v("diffuse_transmittance_sampling_rate", diffuse_transmittance_sampling_rate);
    }
};

namespace principled {

// Schlick's weight (1 - cos)^5, clamped (Schlick 1994; Mitsuba principledhelpers.h schlick_weight).
template <typename F> inline F SchlickWeight(F c) {
    F m = clamp(F(1) - c, F(0), F(1));
    return sqr(sqr(m)) * m;
}

// Schlick's Fresnel R0 + (1 - R0) w, w taken at the transmitted cosine when light leaves the denser
// side (Mitsuba principledhelpers.h calc_schlick).
template <typename F, typename T> inline T Schlick(const T &R0, F cos_i, F eta) {
    F eta_it = select(cos_i >= F(0), eta, F(1) / eta);
    F cos_t = safe_sqrt(F(1) - (F(1) - sqr(cos_i)) / sqr(eta_it));
    F w = select(eta_it > F(1), SchlickWeight(abs(cos_i)), SchlickWeight(cos_t));
    return R0 * (F(1) - w) + T(w);
}

// R0 of an interface of relative IOR eta, ((eta - 1) / (eta + 1))^2 (Schlick 1994).
template <typename F> inline F SchlickR0(F eta) { return sqr((eta - F(1)) / (eta + F(1))); }

// The tint colour base / luminance (1 for a black base), luminance by Rec. 709 (Mitsuba
// core/spectrum.h luminance), computed in double.
template <typename F> inline Spectrum<F> Tint(const std::array<double, 3> &base) {
    double lum = Luminance(to_spectrum<double>(base));
    Spectrum<F> t;
    for (int c = 0; c < 3; ++c) t[c] = F(lum > 0 ? base[size_t(c)] / lum : 1.0);
    return t;
}

// GGX alphas from roughness and anisotropy: r^2 / aspect, r^2 aspect, aspect = sqrt(1 - 0.9 an),
// floored at 0.001 (Burley 2012 addenda; Mitsuba calc_dist_params).
template <typename F> inline void DistParams(F roughness, F anisotropic, F *ax, F *ay) {
    F r2 = sqr(roughness), aspect = sqrt(F(1) - F(0.9) * anisotropic);
    *ax = max_(F(0.001), r2 / aspect);
    *ay = max_(F(0.001), r2 * aspect);
}

// Anisotropic GGX D(m), 0 where D cos_m <= 1e-20 (Walter 2007 / Heitz 2014 eq. 85; Mitsuba microfacet.h).
template <typename F> inline F GGXD(const Vec3<F> &m, F ax, F ay) {
    F d = F(1) / (Pi<F> * ax * ay * sqr(sqr(m.x / ax) + sqr(m.y / ay) + sqr(m.z)));
    return select(d * m.z > F(1e-20), d, F(0));
}

// Smith G1 of GGX, 2 / (1 + sqrt(1 + alpha^2 tan^2)), 1 at normal incidence, 0 on back-facing
// microfacets (Walter 2007 eq. 34; Mitsuba microfacet.h smith_g1).
template <typename F> inline F GGXG1(const Vec3<F> &v, const Vec3<F> &m, F ax, F ay) {
    F xy = sqr(ax * v.x) + sqr(ay * v.y);
    F g = F(2) / (F(1) + sqrt(F(1) + xy / sqr(v.z)));
    g = select(xy == F(0), F(1), g);
    return select(dot(v, m) * v.z <= F(0), F(0), g);
}

// h / |h|, scaled by its largest component first so that |h|^2 cannot underflow (a half vector of
// two grazing directions in float32); +z for h = 0 (no half vector: eta 1 and wi = -wo).
template <typename F> inline Vec3<F> SafeNormalize(Vec3<F> h) {
    F m = max_(abs(h.x), max_(abs(h.y), abs(h.z)));
    if (!(m > F(0))) return {F(0), F(0), F(1)};
    h = h / m;
    return h / sqrt(dot(h, h));
}

// The visible-normal density D(m) G1(w, m) |w.m| / w.z, w above (Heitz 2014 eq. 2).
template <typename F> inline F GGXVisiblePdf(const Vec3<F> &w, const Vec3<F> &m, F ax, F ay) {
    return GGXD(m, ax, ay) * GGXG1(w, m, ax, ay) * abs(dot(w, m)) / w.z;
}

// Isotropic Smith G1 of the clear coat (alpha 0.25), the tan form (Burley 2012; Mitsuba smith_ggx1).
template <typename F> inline F CoatG1(const Vec3<F> &v, const Vec3<F> &m) {
    F c2 = sqr(v.z), t2 = (F(1) - c2) / c2;
    F g = F(2) / (F(1) + sqrt(F(1) + F(0.0625) * t2));
    g = select(v.z == F(1), F(1), g);
    return select(dot(v, m) * v.z <= F(0), F(0), g);
}

// GTR1 (Berry) D(m) = (a^2 - 1) / (pi log(a^2) (1 + (a^2 - 1) cos^2)) (Burley 2012 eq. 4), 0 where
// D cos_m <= 1e-20 (Mitsuba GTR1Isotropic::eval).
template <typename F> inline F GTR1D(const Vec3<F> &m, F a2) {
    F d = (a2 - F(1)) / (Pi<F> * log(a2) * (F(1) + (a2 - F(1)) * sqr(m.z)));
    return select(d * m.z > F(1e-20), d, F(0));
}

// GTR1 normal from u: cos^2 = (1 - a2^(1 - u.y)) / (1 - a2), phi = 2 pi u.x (Burley 2012 eq. 5).
template <typename F> inline Vec3<F> SampleGTR1(Point2<F> u, F a2) {
    F c2 = (F(1) - pow(a2, F(1) - u.y)) / (F(1) - a2);
    F s = safe_sqrt(F(1) - c2), c = safe_sqrt(c2), sp, cp;
    sincos_(F(2) * Pi<F> * u.x, &sp, &cp);
    return {cp * s, sp * s, c};
}

// The principled Fresnel: (1 - metallic)(1 - spec_tint) F_dielectric + metallic Schlick(base) +
// (1 - metallic) spec_tint Schlick(tint R0(eta)); below the surface bsdf F_dielectric
// (Mitsuba principledhelpers.h principled_fresnel).
template <typename F>
inline Spectrum<F> PrincipledFresnel(F Fd, F cos_i, F eta, bool front, F metallic, F spec_tint, F bsdf,
                                     const Spectrum<F> &base, const Spectrum<F> &tint) {
    F eta_it = select(cos_i >= F(0), eta, F(1) / eta);
    Spectrum<F> fs = Schlick(base, cos_i, eta) * metallic +
                     Schlick(tint * SchlickR0(eta_it), cos_i, eta) * ((F(1) - metallic) * spec_tint);
    Spectrum<F> front_f = fs + Spectrum<F>((F(1) - metallic) * (F(1) - spec_tint) * Fd);
    return front ? front_f : Spectrum<F>(bsdf * Fd);
}

// Burley's diffuse with retro-reflection: (1 - Fi/2)(1 - Fo/2) + Rr (Fo + Fi + Fo Fi (Rr - 1)),
// Rr = 2 roughness cos_d^2 (Burley 2015 eq. 4); blended with Hanrahan-Krueger's fake subsurface,
// 1.25 (Fss (1 / (cos_o + cos_i) - 0.5) + 0.5), Fss = (1 + (Rr/2 - 1) Fo)(1 + (Rr/2 - 1) Fi)
// (Burley 2012 sec. 5.3), by flatness.
template <typename F> inline F BurleyDiffuse(F cos_o, F cos_i, F cos_d, F roughness, F flatness) {
    F Fo = SchlickWeight(cos_o), Fi = SchlickWeight(cos_i);
    F diff = (F(1) - F(0.5) * Fi) * (F(1) - F(0.5) * Fo);
    F Rr = F(2) * roughness * sqr(cos_d);
    F retro = Rr * (Fo + Fi + Fo * Fi * (Rr - F(1)));
    F fss90 = Rr / F(2);
    F fss = (F(1) + (fss90 - F(1)) * Fo) * (F(1) + (fss90 - F(1)) * Fi);
    F ss = F(1.25) * (fss * (F(1) / (cos_o + cos_i) - F(0.5)) + F(0.5));
    return (diff + retro) * (F(1) - flatness) + ss * flatness;
}

} // namespace principled

template <typename F> struct PrincipledBxDF {
    using Params = PrincipledParams;
    static constexpr const char *Name = "Principled";

    Spectrum<F> base{F(0.5)}, sqrt_base{F(0.5)}, tint{F(1)};  // tint: base / luminance (1 if black)
    F ax = 0, ay = 0, roughness = 0, metallic = 0, spec_trans = 0, eta = 1.5, spec_tint = 0;
    F sheen = 0, sheen_tint = 0, flatness = 0, clearcoat = 0, cc_a2 = 0;
    F brdf = 1, bsdf = 0;                           // (1 - metallic)(1 - spec_trans), (1 - metallic) spec_trans
    F spec_rate = 1, cc_rate = 1, diffuse_rate = 1;  // Mitsuba's sampling rates

    static PrincipledBxDF make(const Params &p) {
        PrincipledBxDF m;
        m.base = to_spectrum<F>(p.base_color);
        for (int c = 0; c < 3; ++c) m.sqrt_base[c] = F(std::sqrt(p.base_color[size_t(c)]));
        m.tint = principled::Tint<F>(p.base_color);
        principled::DistParams(F(p.roughness), F(p.anisotropic), &m.ax, &m.ay);
        m.roughness = F(p.roughness);
        m.metallic = F(p.metallic);
        m.spec_trans = F(p.spec_trans);
        m.eta = F(p.eta);
        m.spec_tint = F(p.spec_tint);
        m.sheen = F(p.sheen);
        m.sheen_tint = F(p.sheen_tint);
        m.flatness = F(p.flatness);
        m.clearcoat = F(p.clearcoat);
        // clear-coat alpha lerp(0.1, 0.001, gloss) (Burley 2012 addenda)
        double a = 0.1 * (1 - p.clearcoat_gloss) + 0.001 * p.clearcoat_gloss;
        m.cc_a2 = F(a * a);
        m.brdf = F((1 - p.metallic) * (1 - p.spec_trans));
        m.bsdf = F((1 - p.metallic) * p.spec_trans);
        m.spec_rate = F(p.main_specular_sampling_rate);
        m.cc_rate = F(p.clearcoat_sampling_rate);
        m.diffuse_rate = F(p.diffuse_reflectance_sampling_rate);
        return m;
    }

    // Mitsuba's has_spec_trans (the lobe exists) and whether anything reaches the inside.
    bool has_transmission() const { return spec_trans > F(0); }
    bool transmissive() const { return spec_trans > F(0) && bsdf > F(0); }

    uint8_t flags() const {
        uint8_t fl = GlossyReflection;
        if (brdf > F(0)) fl |= DiffuseReflection;
        if (has_transmission() && bsdf > F(0)) fl |= GlossyTransmission;
        return fl;
    }

    // The half vector of Mitsuba's eval/pdf: wo + wi (reflection) or wo + eta_path wi
    // (transmission, Walter 2007 eq. 16), normalized and turned up.
    Vec3<F> half_vector(const Vec3<F> &wo, const Vec3<F> &wi, bool reflect, F eta_path) const {
        Vec3<F> h = principled::SafeNormalize(wo + wi * (reflect ? F(1) : eta_path));
        return h.z < F(0) ? -h : h;
    }

    // Macro/micro-surface agreement: wo on m's side (m turned to wo's side of the surface), wi on
    // the same side for reflection, the other for transmission (Mitsuba mac_mic_compatibility).
    static bool compatible(const Vec3<F> &m, const Vec3<F> &wo, const Vec3<F> &wi, F cos_o, bool reflect) {
        Vec3<F> ms = cos_o < F(0) ? -m : m;
        return dot(wo, ms) > F(0) && (reflect ? dot(wi, ms) > F(0) : dot(wi, ms) < F(0));
    }

    // Mitsuba's eval divided by |cos wi|: wo is Mitsuba's si.wi, wi its wo.
    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode) const {
        using namespace principled;
        F cos_o = wo.z, cos_i = wi.z;
        Spectrum<F> value(F(0));
        if (!(cos_o != F(0)) || !(cos_i != F(0))) return value;  // grazing pairs: no response
        bool reflect = cos_o * cos_i > F(0), refract = cos_o * cos_i < F(0), front = cos_o > F(0);
        if (!front && !transmissive()) return value;              // opaque from below: black
        F eta_path = front ? eta : F(1) / eta, inv_eta_path = F(1) / eta_path;
        Vec3<F> wh = half_vector(wo, wi, reflect, eta_path);
        F o_h = dot(wo, wh), i_h = dot(wi, wh);
        F Fd = FrDielectric(o_h, eta);
        F D = GGXD(wh, ax, ay), G = GGXG1(wo, wh, ax, ay) * GGXG1(wi, wh, ax, ay);
        F aco = abs(cos_o), aci = abs(cos_i);
        // main specular reflection: F D G / (4 |cos_o| |cos_i|)
        if (reflect && compatible(wh, wo, wi, cos_o, true) && Fd > F(0)) {
            Spectrum<F> Fp = PrincipledFresnel(Fd, o_h, eta, front, metallic, spec_tint, bsdf, base, tint);
            value = value + Fp * (D * G / (F(4) * aco * aci));
        }
        // transmission: sqrt(base) bsdf (1 - F) D G eta^2 |o.h i.h| / (|cos_o cos_i| (o.h + eta i.h)^2),
        // over eta_path^2 for radiance (Walter 2007 eq. 21)
        if (refract && has_transmission() && bsdf > F(0) && compatible(wh, wo, wi, cos_o, false) && Fd < F(1)) {
            F scale = mode == TransportMode::Radiance ? sqr(inv_eta_path) : F(1);
            F t = abs(scale * (F(1) - Fd) * D * G * sqr(eta_path) * o_h * i_h / (cos_o * sqr(o_h + eta_path * i_h)));
            value = value + sqrt_base * (bsdf * t / aci);
        }
        if (!(front && reflect)) return value;
        // clear coat: 0.25 clearcoat Schlick(0.04) D_GTR1 G_0.25 (Mitsuba's form, without 1/(4 cos cos))
        if (clearcoat > F(0) && compatible(wh, wo, wi, cos_o, true)) {
            F Fcc = Schlick(F(0.04), o_h, eta);
            F Gcc = CoatG1(wo, wh) * CoatG1(wi, wh);
            value = value + Spectrum<F>(F(0.25) * clearcoat * Fcc * GTR1D(wh, cc_a2) * Gcc);
        }
        // diffuse, retro-reflection and fake subsurface: brdf base / pi (...)
        if (brdf > F(0))
            value = value + base * (brdf * InvPi<F> * BurleyDiffuse(aci, aco, i_h, roughness, flatness));
        // sheen: sheen (1 - metallic) Schlick(cos_d) lerp(1, tint, sheen_tint) (Burley 2012 sec. 5.5)
        if (sheen > F(0) && F(1) - metallic > F(0)) {
            Spectrum<F> c = Spectrum<F>(F(1) - sheen_tint) + tint * sheen_tint;
            value = value + c * (sheen * (F(1) - metallic) * SchlickWeight(abs(i_h)));
        }
        return value;
    }

    // Mitsuba's lobe probabilities at the half vector's dielectric Fresnel Fd: the main specular
    // reflection and transmission, the clear coat and the diffuse lobe, normalized. With all lobes
    // allowed the total does not depend on Fd (so the mixture density is exact); when sample_flags
    // excludes transmission the specular lobe always reflects (probability spec_rate above, 1
    // below), when it excludes reflection it is the only lobe (all zero if nothing is allowed).
    void lobe_probabilities(bool front, F Fd, uint8_t sample_flags, F *p_r, F *p_t, F *p_cc, F *p_d) const {
        const bool allow_r = sample_flags & RT_Reflection, allow_t = sample_flags & RT_Transmission;
        *p_r = front ? spec_rate * (F(1) - bsdf * (F(1) - Fd)) : Fd;
        *p_t = has_transmission() ? (front ? spec_rate * bsdf * (F(1) - Fd) : F(1) - Fd) : F(0);
        *p_cc = front && clearcoat > F(0) ? F(0.25) * clearcoat * cc_rate : F(0);
        *p_d = front ? brdf * diffuse_rate : F(0);
        if (!allow_t) *p_r = front ? spec_rate : F(1), *p_t = F(0);
        if (!allow_r) *p_r = *p_cc = *p_d = F(0), *p_t = has_transmission() ? F(1) : F(0);
        F total = *p_r + *p_t + *p_cc + *p_d;
        F inv = total > F(0) ? F(1) / total : F(0);
        *p_r *= inv, *p_t *= inv, *p_cc *= inv, *p_d *= inv;
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const {
        using namespace principled;
        F cos_o = wo.z, cos_i = wi.z;
        if (!(cos_o != F(0)) || !(cos_i != F(0))) return F(0);
        bool reflect = cos_o * cos_i > F(0), front = cos_o > F(0);
        if (!front && !transmissive()) return F(0);
        F eta_path = front ? eta : F(1) / eta;
        Vec3<F> wh = half_vector(wo, wi, reflect, eta_path);
        F o_h = dot(wo, wh), i_h = dot(wi, wh);
        F p_r, p_t, p_cc, p_d;
        lobe_probabilities(front, FrDielectric(o_h, eta), sample_flags, &p_r, &p_t, &p_cc, &p_d);
        // |d wh / d wi|: 1 / (4 |i.h|) for reflection, eta^2 |i.h| / (o.h + eta i.h)^2 for
        // transmission (Walter 2007 eqs. 14, 17)
        F jac = abs(reflect ? F(1) / (F(4) * i_h) : sqr(eta_path) * i_h / sqr(o_h + eta_path * i_h));
        Vec3<F> w_up = front ? wo : -wo;
        F p = F(0);
        if (compatible(wh, wo, wi, cos_o, reflect)) {
            F vis = GGXVisiblePdf(w_up, wh, ax, ay) * jac;
            p += (reflect ? p_r : p_t) * vis;
            if (reflect) p += p_cc * (wh.z < F(0) ? F(0) : wh.z * GTR1D(wh, cc_a2)) * jac;
        }
        if (reflect) p += p_d * InvPi<F> * cos_i;
        return p;
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        using namespace principled;
        BSDFSample<F> s;
        F cos_o = wo.z;
        bool front = cos_o > F(0);
        if (!(cos_o != F(0)) || (!front && !transmissive())) return s;
        u = clamp_uniform(u);
        uc = clamp_uniform(uc);
        // the main specular lobe's visible normal, of wo turned up (Heitz 2018 via Microfacet)
        Vec3<F> w_up = front ? wo : -wo;
        Microfacet<F> tr(ax, ay, Masking::Separable);
        Vec3<F> m = tr.Sample_wm(w_up, u);
        F p_r, p_t, p_cc, p_d;
        lobe_probabilities(front, FrDielectric(dot(wo, m), eta), sample_flags, &p_r, &p_t, &p_cc, &p_d);
        Vec3<F> wi;
        uint8_t flag;
        if (uc < p_d) {
            wi = SampleCosineHemisphere(u);
            flag = DiffuseReflection;
        } else if (uc < p_d + p_cc) {
            m = SampleGTR1(u, cc_a2);
            wi = Reflect(wo, m);
            flag = GlossyReflection;
        } else if (uc < p_d + p_cc + p_t) {
            F etap;
            if (!Refract(wo, m, eta, &etap, &wi)) return s;
            flag = GlossyTransmission;
            s.eta = etap;
        } else if (p_r > F(0)) {
            wi = Reflect(wo, m);
            flag = GlossyReflection;
        } else {
            return s;                                        // no lobe allowed by sample_flags
        }
        bool reflect = wi.z * cos_o > F(0);
        if (reflect != bool(flag & Reflection)) return s;   // the sampled direction left its side
        // a microfacet lobe's sample where its normal does not face both directions is no sample
        // of that lobe (its density is 0 there; Mitsuba's sampler drops it the same way)
        if (flag != DiffuseReflection && !compatible(m, wo, wi, cos_o, reflect)) return s;
        s.wi = wi;
        s.flags = flag;
        s.pdf = pdf(wo, wi, mode, sample_flags);
        s.f = f(wo, wi, mode);
        s.valid = s.pdf > F(0);
        if (!s.valid) s = BSDFSample<F>{};
        return s;
    }

    void regularize() {}
};

// PrincipledThin: Mitsuba 3's `principledthin` (Burley 2015 sec. 5's thin-surface BSDF, as Mitsuba
// 3.9 writes it in src/bsdfs/principledthin.cpp): a two-sided sheet without refraction.
//   specular reflection   spec_trans lerp(F, Schlick(tint R0), spec_tint) D G / (4 cos_o cos_i)
//   specular transmission spec_trans base (1 - F) D' G' / (4 cos_o cos_i), wi mirrored up, D' of the
//                         roughness scaled by (0.65 eta - 0.35) (Burley 2015 fig. 15)
//   diffuse, sheen        (1 - spec_trans)(1 - dt) (base/pi lerp(Burley + retro, fake SSS, flatness) + sheen)
//   diffuse transmission  (1 - spec_trans) dt base / pi,  dt = diff_trans / 2
// Both sides alike (wo below mirrors the pair); no transport-mode dependence (no refraction).
template <typename F> struct PrincipledThinBxDF {
    using Params = PrincipledThinParams;
    static constexpr const char *Name = "PrincipledThin";

    Spectrum<F> base{F(0.5)}, tint{F(1)};
    F ax = 0, ay = 0, tax = 0, tay = 0;  // GGX alphas of the reflection and (scaled) transmission lobes
    F roughness = 0, spec_trans = 0, eta = 1.5, spec_tint = 0, sheen = 0, sheen_tint = 0, flatness = 0, dt = 0;
    F rate_sr = 1, rate_st = 1, rate_dr = 1, rate_dt = 1;

    static PrincipledThinBxDF make(const Params &p) {
        PrincipledThinBxDF m;
        m.base = to_spectrum<F>(p.base_color);
        m.tint = principled::Tint<F>(p.base_color);
        principled::DistParams(F(p.roughness), F(p.anisotropic), &m.ax, &m.ay);
        // the transmission lobe's roughness (0.65 eta - 0.35) r (Burley 2015 fig. 15)
        principled::DistParams(F((0.65 * p.eta - 0.35) * p.roughness), F(p.anisotropic), &m.tax, &m.tay);
        m.roughness = F(p.roughness);
        m.spec_trans = F(p.spec_trans);
        m.eta = F(p.eta);
        m.spec_tint = F(p.spec_tint);
        m.sheen = F(p.sheen);
        m.sheen_tint = F(p.sheen_tint);
        m.flatness = F(p.flatness);
        m.dt = F(p.diff_trans / 2);
        m.rate_sr = F(p.specular_reflectance_sampling_rate);
        m.rate_st = F(p.specular_transmittance_sampling_rate);
        m.rate_dr = F(p.diffuse_reflectance_sampling_rate);
        m.rate_dt = F(p.diffuse_transmittance_sampling_rate);
        return m;
    }

    uint8_t flags() const {
        uint8_t fl = DiffuseReflection;
        if (spec_trans > F(0)) fl |= GlossyReflection | GlossyTransmission;
        if (dt > F(0)) fl |= DiffuseTransmission;
        return fl;
    }

    // The pair turned so that wo is above, and the half vector of wo and wi mirrored up
    // (Mitsuba principledthin.cpp: the sheet is symmetric; transmission is a mirrored reflection).
    static void frame(const Vec3<F> &wo, const Vec3<F> &wi, Vec3<F> *o, Vec3<F> *t, Vec3<F> *h) {
        F s = wo.z < F(0) ? F(-1) : F(1);
        *o = wo * s;
        *t = wi * s;
        Vec3<F> r(t->x, t->y, abs(t->z));
        *h = principled::SafeNormalize(*o + r);
    }

    Spectrum<F> f(const Vec3<F> &wo_, const Vec3<F> &wi_, TransportMode) const {
        using namespace principled;
        Spectrum<F> value(F(0));
        if (!(wo_.z != F(0)) || !(wi_.z != F(0))) return value;
        Vec3<F> wo, wi, wh;
        frame(wo_, wi_, &wo, &wi, &wh);
        F cos_o = wo.z, cos_i = wi.z, aci = abs(cos_i);
        bool reflect = cos_i > F(0);
        F o_h = dot(wo, wh);
        if (spec_trans > F(0)) {
            F Fd = FrDielectric(o_h, eta);
            if (reflect && o_h > F(0) && dot(wi, wh) > F(0)) {
                // lerp(F, Schlick(tint R0(eta)), spec_tint) (Mitsuba principledhelpers.h thin_fresnel)
                Spectrum<F> Ft = Spectrum<F>(Fd * (F(1) - spec_tint)) +
                                 Schlick(tint * SchlickR0(eta), o_h, eta) * spec_tint;
                F G = GGXG1(wo, wh, ax, ay) * GGXG1(wi, wh, ax, ay);
                value = value + Ft * (spec_trans * GGXD(wh, ax, ay) * G / (F(4) * cos_o * aci));
            }
            if (!reflect && o_h > F(0) && dot(wi, wh) < F(0)) {
                F G = GGXG1(wo, wh, tax, tay) * GGXG1(wi, wh, tax, tay);
                value = value + base * (spec_trans * (F(1) - Fd) * GGXD(wh, tax, tay) * G / (F(4) * cos_o * aci));
            }
        }
        if (reflect && spec_trans < F(1) && dt < F(1)) {
            F w = (F(1) - spec_trans) * (F(1) - dt);
            F cos_d = dot(wh, wi);
            value = value + base * (w * InvPi<F> * BurleyDiffuse(aci, cos_o, cos_d, roughness, flatness));
            // sheen (Burley 2012 sec. 5.5), weighted as the diffuse lobe
            if (sheen > F(0)) {
                Spectrum<F> c = Spectrum<F>(F(1) - sheen_tint) + tint * sheen_tint;
                value = value + c * (sheen * w * SchlickWeight(abs(cos_d)));
            }
        }
        // Lambertian transmission (1 - spec_trans) dt base / pi
        if (!reflect && spec_trans < F(1) && dt > F(0)) value = value + base * ((F(1) - spec_trans) * dt * InvPi<F>);
        return value;
    }

    // Mitsuba's lobe probabilities (specular reflection / transmission, diffuse reflection /
    // transmission), normalized over the lobes sample_flags allows.
    void lobe_probabilities(uint8_t sample_flags, F *p_sr, F *p_st, F *p_dr, F *p_dt) const {
        F keep_r = (sample_flags & RT_Reflection) ? F(1) : F(0), keep_t = (sample_flags & RT_Transmission) ? F(1) : F(0);
        *p_sr = keep_r * spec_trans * rate_sr / F(2);
        *p_st = keep_t * spec_trans * rate_st / F(2);
        *p_dr = keep_r * rate_dr * (F(1) - spec_trans) * (F(1) - dt);
        *p_dt = keep_t * (dt > F(0) ? rate_dt * (F(1) - spec_trans) * dt : F(0));
        F total = *p_sr + *p_st + *p_dr + *p_dt;
        F inv = total > F(0) ? F(1) / total : F(0);
        *p_sr *= inv, *p_st *= inv, *p_dr *= inv, *p_dt *= inv;
    }

    F pdf(const Vec3<F> &wo_, const Vec3<F> &wi_, TransportMode, uint8_t sample_flags) const {
        using namespace principled;
        if (!(wo_.z != F(0)) || !(wi_.z != F(0))) return F(0);
        Vec3<F> wo, wi, wh;
        frame(wo_, wi_, &wo, &wi, &wh);
        bool reflect = wi.z > F(0);
        F p_sr, p_st, p_dr, p_dt;
        lobe_probabilities(sample_flags, &p_sr, &p_st, &p_dr, &p_dt);
        F p = F(0);
        if (spec_trans > F(0) && dot(wo, wh) > F(0) && (reflect ? dot(wi, wh) > F(0) : dot(wi, wh) < F(0))) {
            // |d wh / d wi| = 1 / (4 |wi_r.h|), wi_r the mirrored wi (Walter 2007 eq. 14)
            F jac = F(1) / (F(4) * abs(dot(Vec3<F>(wi.x, wi.y, abs(wi.z)), wh)));
            p += reflect ? p_sr * GGXVisiblePdf(wo, wh, ax, ay) * jac : p_st * GGXVisiblePdf(wo, wh, tax, tay) * jac;
        }
        p += (reflect ? p_dr : p_dt) * InvPi<F> * abs(wi.z);
        return p;
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo_, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        using namespace principled;
        BSDFSample<F> s;
        if (!(wo_.z != F(0))) return s;
        u = clamp_uniform(u);
        uc = clamp_uniform(uc);
        F sign = wo_.z < F(0) ? F(-1) : F(1);
        Vec3<F> wo = wo_ * sign, wi;
        F p_sr, p_st, p_dr, p_dt;
        lobe_probabilities(sample_flags, &p_sr, &p_st, &p_dr, &p_dt);
        uint8_t flag;
        Vec3<F> m(F(0), F(0), F(1));
        if (uc < p_sr) {
            m = Microfacet<F>(ax, ay, Masking::Separable).Sample_wm(wo, u);
            wi = Reflect(wo, m);
            flag = GlossyReflection;
        } else if (uc < p_sr + p_st) {
            m = Microfacet<F>(tax, tay, Masking::Separable).Sample_wm(wo, u);
            wi = Reflect(wo, m);
            wi.z = -wi.z;
            flag = GlossyTransmission;
        } else if (uc < p_sr + p_st + p_dr) {
            wi = SampleCosineHemisphere(u);
            flag = DiffuseReflection;
        } else if (p_dt > F(0)) {
            wi = -SampleCosineHemisphere(u);
            flag = DiffuseTransmission;
        } else {
            return s;
        }
        if ((wi.z > F(0)) != bool(flag & Reflection)) return s;  // the sampled direction left its side
        // a specular sample whose normal faces away from wo or wi belongs to no lobe (its density
        // is 0 there; Mitsuba's sampler drops it the same way)
        bool glossy = flag & Glossy;
        if (glossy && !(dot(wo, m) > F(0) && (flag & Reflection ? dot(wi, m) > F(0) : dot(wi, m) < F(0)))) return s;
        s.wi = wi * sign;
        s.flags = flag;
        s.pdf = pdf(wo_, s.wi, mode, sample_flags);
        s.f = f(wo_, s.wi, mode);
        s.valid = s.pdf > F(0);
        if (!s.valid) s = BSDFSample<F>{};
        return s;
    }

    void regularize() {}
};

} // namespace bsdfkit
