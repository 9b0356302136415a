// Analytic layered approximation: the deterministic, closed-form counterpart of the stochastic
// CoatedDiffuse / CoatedConductor (bxdfs/layered.h), selected in Python by method="analytic".
// Same parameters (the Params structs of layered.h; max_depth, n_samples, seed and
// consistent_mis are ignored), same conventions (two-sided, reflection only, base IOR relative
// to the coating). Cheap and noise-free, but biased: it is an approximation of the layered
// material, not an estimator of it.
//
// f(wo, wi) = f_coat(wo, wi)                                                        (1)
//           + T(wo) T(wi) / eta^2 * [ M f_base(wo', wi') a(wo', wi')                  (2)
//                                   + albedo p_HG(wo', wi') (1 - a) / (cos_o' + cos_i') ]  (3)
// (1) the coating's own reflection: a delta mirror F(cos_o) (smooth) or the microfacet lobe
//     D F G / (4 cos_o cos_i) (rough) -- Weidlich & Wilkie 2007, "Arbitrarily layered
//     micro-facet surfaces", the top layer's specular term.
// (2) the base seen through the coating: Fresnel transmittances T = 1 - F at the macro normal,
//     the base evaluated at the directions refracted by the macro normal, wo', wi' (Snell), the
//     solid-angle compression 1 / eta^2 of the two refractions, and the absorption along the
//     refracted paths a = exp(-thickness (1 / cos_o' + 1 / cos_i')) (sigma_t = 1) -- Weidlich &
//     Wilkie 2007, eq. of the layered term (T12 f_r2(refracted) T21 a). M sums the internal
//     reflections: light leaving the base is reflected back by the coating's inside with its
//     hemispherical (diffuse) reflectance Fdr_int and returns to the base, M = 1 / (1 - rho_b
//     Fdr_int t_d^2), rho_b the base's cosine-weighted hemispherical albedo and t_d the slab's
//     diffuse transmittance 2 int exp(-thickness / mu) mu dmu (the geometric series of
//     Weidlich & Wilkie's "total internal reflection" term, in the form of the
//     Kubelka-Munk-like sum R / (1 - R Fdr) of Mitsuba's nonlinear plastic).
// (3) single scattering in the medium (albedo, Henyey-Greenstein g) between the interfaces:
//     Hanrahan & Krueger 1993, eq. 21 (a slab of optical thickness d: albedo p (1 - exp(-d
//     (1/cos_i + 1/cos_o))) / (cos_i + cos_o)); multiple scattering in the medium is ignored.
// A smooth conductor base gives a delta lobe in the mirror direction (macro refraction keeps
// it there); its internal reflections are summed exactly for a smooth coating:
// T(cos_o)^2 Fc(cos_o') a / (1 - F(cos_o) Fc(cos_o') a), a = exp(-2 thickness / cos_o').
//
// Sampling (exact pdf, so sample() equals eval() / pdf() up to rounding): the coating lobe with
// the Fresnel-weighted probability p_c = F(cos_o) / (F(cos_o) + (1 - F(cos_o)) w_b), w_b the
// base's mean albedo (plus the medium's); otherwise the base: a cosine-weighted direction (a
// diffuse base, and the medium's share q of a conductor base), or the conductor's lobe sampled
// at wo' and refracted out (its density times the Jacobian cos_i / (eta^2 cos_i')).
#pragma once
#include <array>
#include <type_traits>

#include "layered.h"
#include "plastic.h"  // GaussLegendre

namespace bsdfkit {

// 2 int_0^1 g(mu) mu dmu by Gauss-Legendre on [a, 1] (g = 1 on [0, a], the total internal
// reflection range of a Fresnel reflectance). T: double, or a Dual (make() of a gradient model),
// whose derivative is that of the quadrature.
template <typename T, class G> inline T CosineWeightedMean(G g, T a = T(0), int n = 64) {
    double x[128], w[128];
    GaussLegendre(n, x, w);
    T s = a * a;  // 2 int_0^a mu dmu
    for (int i = 0; i < n; ++i) {
        T mu = a + (T(1) - a) * T(0.5) * T(x[i] + 1);
        s += T(2) * g(mu) * mu * T(0.5) * (T(1) - a) * T(w[i]);
    }
    return s;
}

// Hemispherical (diffuse) reflectance of a smooth dielectric interface for light arriving
// from the side where the relative IOR is e (e < 1: total internal reflection below
// mu_c = sqrt(1 - e^2)).
template <typename T> inline T DiffuseFresnel(T e) {
    T a = e < T(1) ? sqrt(T(1) - e * e) : T(0);
    return CosineWeightedMean<T>([e](T mu) { return FrDielectric(mu, e); }, a);
}

// The slab's diffuse transmittance 2 int exp(-d / mu) mu dmu (= 2 E_3(d)).
template <typename T> inline T DiffuseSlabTransmittance(T d) {
    return CosineWeightedMean<T>([d](T mu) { return exp(-d / mu); });
}

template <typename F, typename Bottom> struct AnalyticLayeredBxDF {
    DielectricBxDF<F> top;
    Bottom bottom;
    F thickness = F(0.01);
    Spectrum<F> albedo{F(0)};
    Spectrum<F> multi{F(1)};  // M, the internal-reflection sum of the base term
    F g = 0;
    F base_weight = 0;         // w_b of the lobe choice
    F q_cos = 1;               // probability of a cosine-weighted direction within the base branch
    bool has_albedo = false, base_diffuse = true, base_smooth = false;

    // rho_b: the base's cosine-weighted hemispherical albedo (per channel). S = param_t<F>
    // (double, or the Dual of a gradient model: M's derivative flows through the quadratures).
    template <typename S> void set_layer(const LayerParamsT<S> &p, const Spectrum<S> &rho_b) {
        thickness = max_(F(p.thickness), F(std::numeric_limits<float>::min()));
        for (int c = 0; c < 3; ++c) albedo[c] = F(p.albedo[c]);
        has_albedo = !albedo.is_black();
        g = F(clamp(p.g, S(-0.99), S(0.99)));
        S eta = S(top.eta), fdr_int = DiffuseFresnel(S(1) / eta);
        S td = DiffuseSlabTransmittance(S(thickness)), t2 = exp(S(-2) * S(thickness));
        S rb = 0, med = 0;
        for (int c = 0; c < 3; ++c) {
            multi[c] = F(S(1) / (S(1) - rho_b[c] * fdr_int * td * td));
            rb += rho_b[c] / S(3);
            med += p.albedo[c] / S(3);
        }
        S s = med * (S(1) - t2), b = rb * t2;
        base_weight = F(b + s);
        q_cos = base_diffuse ? F(1) : F(s + b > S(0) ? s / (s + b) : S(0));
    }

    bool top_smooth() const { return top.is_smooth(); }

    uint8_t flags() const {
        uint8_t f = Reflection;
        bool spec = top_smooth() | base_smooth;
        bool glossy = !top_smooth() | (!base_diffuse & !base_smooth);
        bool diff = base_diffuse | has_albedo;
        if (spec) f |= Specular;
        if (glossy) f |= Glossy;
        if (diff) f |= Diffuse;
        return f;
    }

    // Snell at the macro normal: the inner direction of an outside direction w (w.z > 0),
    // pointing up into the slab's upper half (cos = 0 beyond the critical angle).
    Vec3<F> refracted(const Vec3<F> &w) const {
        F inv = F(1) / top.eta;
        return Vec3<F>(w.x * inv, w.y * inv, safe_sqrt(F(1) - (F(1) - w.z * w.z) * inv * inv));
    }

    // Beer-Lambert along both refracted paths (sigma_t = 1), 0 at a horizon inner direction.
    F absorption(F co, F ci) const {
        F prod = co * ci;
        return prod > F(0) ? exp(-thickness * (co + ci) / prod) : F(0);
    }

    // Fresnel-weighted probability of the coating lobe (p_c above).
    F prob_coat(F Fo) const {
        F sum = Fo + (F(1) - Fo) * base_weight;
        return sum > F(0) ? Fo / sum : F(1);
    }

    // The non-delta part of f, both directions in the upper hemisphere.
    Spectrum<F> f_upper(const Vec3<F> &o, const Vec3<F> &i, TransportMode mode) const {
        F eta = top.eta;
        F To = F(1) - FrDielectric(o.z, eta), Ti = F(1) - FrDielectric(i.z, eta);
        Vec3<F> op = refracted(o), ip = refracted(i);
        F a = absorption(op.z, ip.z);
        Spectrum<F> inner(F(0));
        if (!base_smooth) inner = bottom.f(op, ip, mode) * multi * a;  // (2)
        if (has_albedo) {                                              // (3)
            F cs = op.z + ip.z;
            F ss = cs > F(0) ? HenyeyGreenstein(dot(op, ip), g) * (F(1) - a) / cs : F(0);
            inner = inner + albedo * ss;
        }
        Spectrum<F> v = inner * (To * Ti / (eta * eta));
        if (!top_smooth()) v = v + top.f(o, i, mode);                  // (1)
        return v;
    }

    // Density of the coating's rough reflection lobe (visible normals, reflection Jacobian).
    F pdf_coat(const Vec3<F> &o, const Vec3<F> &i) const {
        Vec3<F> wm = normalize(o + i);
        F c = absdot(o, wm);
        return c > F(0) ? top.mfd.PDF(o, wm) / (F(4) * c) : F(0);
    }

    // Density of the non-delta lobes at i, both directions in the upper hemisphere.
    F pdf_upper(const Vec3<F> &o, const Vec3<F> &i, TransportMode mode) const {
        F pc = prob_coat(FrDielectric(o.z, top.eta));
        F p = (F(1) - pc) * q_cos * CosineHemispherePDF(i.z);
        if (!top_smooth()) p += pc * pdf_coat(o, i);
        if (!base_diffuse & !base_smooth) {
            Vec3<F> op = refracted(o), ip = refracted(i);
            F jac = ip.z > F(0) ? i.z / (top.eta * top.eta * ip.z) : F(0);
            p += (F(1) - pc) * (F(1) - q_cos) * bottom.pdf(op, ip, mode, RT_Reflection) * jac;
        }
        return p;
    }

    // Reflectance of the delta lobes (mirror direction) and their total discrete probability.
    F delta_prob(F pc) const {
        F p = top_smooth() ? pc : F(0);
        if (base_smooth) p += (F(1) - pc) * (F(1) - q_cos);
        return p;
    }
    Spectrum<F> delta_reflectance(const Vec3<F> &o) const {
        F Fo = FrDielectric(o.z, top.eta);
        Spectrum<F> r(top_smooth() ? Fo : F(0));
        if constexpr (!std::is_same_v<Bottom, DiffuseBxDF<F>>) {
            F cp = refracted(o).z;
            F a = absorption(cp, cp);
            Spectrum<F> fc = bottom.fresnel(cp) * a;
            // exact sum of the inter-reflections between the smooth coat and the mirror
            Spectrum<F> denom = Spectrum<F>(F(1)) - fc * Fo;
            if (base_smooth) r = r + fc * sqr(F(1) - Fo) / denom;
        }
        return r;
    }

    Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode) const {
        F s = wo.z < F(0) ? F(-1) : F(1);  // two-sided
        Vec3<F> o = wo * s, i = wi * s;
        bool active = (o.z > F(0)) & (i.z > F(0));
        Spectrum<F> v = f_upper(o, i, mode);
        return select(active, v, Spectrum<F>(F(0)));
    }

    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode mode, uint8_t sample_flags) const {
        F s = wo.z < F(0) ? F(-1) : F(1);
        Vec3<F> o = wo * s, i = wi * s;
        bool active = (o.z > F(0)) & (i.z > F(0)) & ((sample_flags & RT_Reflection) != 0);
        F p = pdf_upper(o, i, mode);
        return active ? p : F(0);
    }

    BSDFSample<F> sample_f(const Vec3<F> &wo, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        BSDFSample<F> r;
        F s = wo.z < F(0) ? F(-1) : F(1);
        Vec3<F> o = wo * s;
        F pc = prob_coat(FrDielectric(o.z, top.eta));
        bool coat = uc < pc;
        F ub = pc < F(1) ? (uc - pc) / (F(1) - pc) : F(0);
        bool cosine = !coat & (ub < q_cos);
        bool delta = coat ? top_smooth() : (!cosine & base_smooth);
        Vec3<F> mirror(-o.x, -o.y, o.z), i;
        if (delta) {
            i = mirror;
        } else if (coat) {
            i = Reflect(o, top.mfd.Sample_wm(o, u));
        } else if (cosine) {
            i = SampleCosineHemisphere(u);
        } else {
            // the conductor's lobe at wo', refracted out through the macro normal
            BSDFSample<F> b = bottom.sample_f(refracted(o), F(0), u, mode, RT_Reflection);
            F sin2 = (F(1) - b.wi.z * b.wi.z) * top.eta * top.eta;
            bool out = b.valid & (b.wi.z > F(0)) & (sin2 < F(1));
            i = out ? Vec3<F>(b.wi.x * top.eta, b.wi.y * top.eta, std::sqrt(F(1) - sin2)) : Vec3<F>(0, 0, -1);
        }
        if (delta) {
            F cos_i = DeltaAbsCos(i);
            r.f = delta_reflectance(o) / cos_i;
            r.pdf = delta_prob(pc);
            r.flags = SpecularReflection;
        } else {
            bool up = i.z > F(0);
            r.f = up ? f_upper(o, i, mode) : Spectrum<F>(F(0));
            r.pdf = up ? pdf_upper(o, i, mode) : F(0);
            r.flags = cosine ? uint8_t(DiffuseReflection) : uint8_t(GlossyReflection);
        }
        r.wi = i * s;
        r.eta = F(1);
        r.valid = (o.z > F(0)) & (i.z > F(0)) & (r.pdf > F(0)) & ((sample_flags & RT_Reflection) != 0);
        return r;
    }

    void regularize() {
        top.regularize();
        bottom.regularize();
        base_smooth = (bottom.flags() & Specular) != 0;
    }
};

// Params on S = param_t<F> (a Dual for gradients, bindings/models_grad.cpp): every derived
// parameter (relative metal IOR, the base albedo, M, the lobe weights) is computed in S.
template <typename F> struct CoatedDiffuseAnalyticBxDF : AnalyticLayeredBxDF<F, DiffuseBxDF<F>> {
    using Params = CoatedDiffuseParamsT<param_t<F>>;
    static constexpr const char *Name = "CoatedDiffuseAnalytic";

    static CoatedDiffuseAnalyticBxDF make(const Params &p) {
        using S = param_t<F>;
        CoatedDiffuseAnalyticBxDF m;
        m.top.eta = F(p.eta);
        m.top.mfd = TrowbridgeReitz<F>(F(p.alpha_x), F(p.alpha_y), p.masking);
        Spectrum<S> rho;
        for (int c = 0; c < 3; ++c) {
            m.bottom.R[c] = F(p.reflectance[c]);
            rho[c] = p.reflectance[c];
        }
        m.base_diffuse = true;
        m.base_smooth = false;
        m.set_layer(p.layer, rho);
        return m;
    }
};

template <typename F> struct CoatedConductorAnalyticBxDF : AnalyticLayeredBxDF<F, ConductorBxDF<F>> {
    using Params = CoatedConductorParamsT<param_t<F>>;
    static constexpr const char *Name = "CoatedConductorAnalytic";

    static CoatedConductorAnalyticBxDF make(const Params &p) {
        using S = param_t<F>;
        CoatedConductorAnalyticBxDF m;
        m.top.eta = F(p.interface_eta);
        m.top.mfd = TrowbridgeReitz<F>(F(p.interface_alpha_x), F(p.interface_alpha_y), p.masking);
        // the metal relative to the coating, as the stochastic model (pbrt-v4 PR #343)
        Spectrum<F> ce, ck;
        Spectrum<S> rho;
        for (int c = 0; c < 3; ++c) {
            S e = p.conductor_eta[c] / p.interface_eta, k = p.conductor_k[c] / p.interface_eta;
            ce[c] = F(e);
            ck[c] = F(k);
            // the smooth metal's hemispherical albedo (roughness neglected)
            rho[c] = CosineWeightedMean<S>([e, k](S mu) { return FrComplex(mu, e, k); });
        }
        m.bottom = ConductorBxDF<F>(TrowbridgeReitz<F>(F(p.conductor_alpha_x), F(p.conductor_alpha_y), p.masking), ce, ck);
        m.base_diffuse = false;
        m.base_smooth = m.bottom.is_smooth();
        m.set_layer(p.layer, rho);
        return m;
    }
};

} // namespace bsdfkit
