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

template <typename F> struct CoatedConductorAnalyticSpectral;  // its spectral form (batch_spectral.h / spectral/)

template <typename F> struct CoatedDiffuseAnalyticSpectral;  // its spectral form (batch_spectral.h / spectral/)

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
        bool glossy = (!top_smooth()) | ((!base_diffuse) & (!base_smooth));
        bool diff = base_diffuse | has_albedo;
        if (spec) f |= Specular;
        if (glossy) f |= Glossy;
        if (diff) f |= Diffuse;
        return f;
    }

    // The model runs on packets in the batch kernels (batch.h): every method is written once on
    // the evaluation type V (F, or a packet of F; core/simd.h); the model's switches (top_smooth,
    // base_smooth, base_diffuse, has_albedo) are uniform branches, and sample_f computes each
    // lobe's direction and selects per lane.
    static constexpr bool Vectorized = true;

    // Snell at the macro normal: the inner direction of an outside direction w (w.z > 0),
    // pointing up into the slab's upper half (cos = 0 beyond the critical angle).
    template <typename V> Vec3<V> refracted(const Vec3<V> &w) const {
        V inv(F(1) / top.eta);
        return Vec3<V>(w.x * inv, w.y * inv, safe_sqrt(V(1) - (V(1) - w.z * w.z) * inv * inv));
    }

    // Beer-Lambert along both refracted paths (sigma_t = 1), 0 at a horizon inner direction.
    template <typename V> V absorption(V co, V ci) const {
        V prod = co * ci;
        Mask<V> ok = prod > V(0);
        // (libm's exp in float64, so that a gradient model's value equals eval bit for bit)
        return select(ok, exp_f64libm(-V(thickness) * (co + ci) / select(ok, prod, V(1))), V(0));
    }

    // Fresnel-weighted probability of the coating lobe (p_c above).
    template <typename V> V prob_coat(V Fo) const {
        V sum = Fo + (V(1) - Fo) * V(base_weight);
        Mask<V> ok = sum > V(0);
        return select(ok, Fo / select(ok, sum, V(1)), V(1));
    }

    // The non-delta part of f, both directions in the upper hemisphere. T(o) T(i) / eta^2 from
    // the Fresnel transmittances' numerators over one product of denominators (core/fresnel.h).
    template <typename V> Spectrum<V> f_upper(const Vec3<V> &o, const Vec3<V> &i, TransportMode mode) const {
        F eta = top.eta;
        V ro, to, den_o, ri, ti, den_i;
        FrDielectricRatio(o.z, eta, &ro, &to, &den_o);
        FrDielectricRatio(i.z, eta, &ri, &ti, &den_i);
        Vec3<V> op = refracted(o), ip = refracted(i);
        V a = absorption(op.z, ip.z);
        Spectrum<V> inner(V(0));
        if (!base_smooth) inner = bottom.f(op, ip, mode) * to_lanes<V>(multi) * a;  // (2)
        if (has_albedo) {                                                            // (3)
            V cs = op.z + ip.z;
            Mask<V> ok = cs > V(0);
            V ss = select(ok, HenyeyGreenstein(dot(op, ip), V(g)) * (V(1) - a) / select(ok, cs, V(1)), V(0));
            inner = inner + to_lanes<V>(albedo) * ss;
        }
        Spectrum<V> v = inner * (to * ti / (den_o * den_i * V(eta * eta)));
        if (!top_smooth()) v = v + top.f(o, i, mode);                                // (1)
        return v;
    }

    // Density of the coating's rough reflection lobe: visible normals through the reflection
    // Jacobian, 1 / (D_denom 2 (cos_o + root_o)) (core/microfacet.h).
    template <typename V> V pdf_coat(const Vec3<V> &o, const Vec3<V> &i) const {
        Mask<V> ok = Mask<V>(true);
        Vec3<V> wm = reflection_half_vector(o, i, ok);
        V dd = top.mfd.D_denom(wm, ok);
        return select(ok, V(1) / (dd * top.mfd.reflection_pdf_denom(o.z, top.mfd.smith_root(o))), V(0));
    }

    // Density of the non-delta lobes at i, both directions in the upper hemisphere.
    template <typename V> V pdf_upper(const Vec3<V> &o, const Vec3<V> &i, TransportMode mode) const {
        V pc = prob_coat(FrDielectric(o.z, top.eta));
        V p = (V(1) - pc) * V(q_cos) * CosineHemispherePDF(i.z);
        if (!top_smooth()) p += pc * pdf_coat(o, i);
        if (!base_diffuse & !base_smooth) {
            Vec3<V> op = refracted(o), ip = refracted(i);
            Mask<V> ok = ip.z > V(0);
            V jac = select(ok, i.z / (V(top.eta * top.eta) * select(ok, ip.z, V(1))), V(0));
            p += (V(1) - pc) * V(F(1) - q_cos) * bottom.pdf(op, ip, mode, RT_Reflection) * jac;
        }
        return p;
    }

    // Reflectance of the delta lobes (mirror direction) and their total discrete probability.
    template <typename V> V delta_prob(V pc) const {
        V p = top_smooth() ? pc : V(0);
        if (base_smooth) p += (V(1) - pc) * V(F(1) - q_cos);
        return p;
    }
    template <typename V> Spectrum<V> delta_reflectance(const Vec3<V> &o) const {
        V Fo = FrDielectric(o.z, top.eta);
        Spectrum<V> r(top_smooth() ? Fo : V(0));
        if constexpr (!std::is_same_v<Bottom, DiffuseBxDF<F>>) {
            if (base_smooth) {
                // exact sum of the inter-reflections between the smooth coat and the mirror
                V cp = refracted(o).z;
                Spectrum<V> fc = bottom.fresnel(cp) * absorption(cp, cp);
                Spectrum<V> denom = Spectrum<V>(V(1)) - fc * Fo;
                r = r + fc * sqr(V(1) - Fo) / denom;
            }
        }
        return r;
    }

    template <typename V> Spectrum<V> f(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode mode) const {
        V s = select(wo.z < V(0), V(-1), V(1));  // two-sided
        Vec3<V> o = wo * s, i = wi * s;
        Mask<V> active = (o.z > V(0)) & (i.z > V(0));
        return select(active, f_upper(o, i, mode), Spectrum<V>(V(0)));
    }

    template <typename V> V pdf(const Vec3<V> &wo, const Vec3<V> &wi, TransportMode mode, uint8_t sample_flags) const {
        V s = select(wo.z < V(0), V(-1), V(1));
        Vec3<V> o = wo * s, i = wi * s;
        Mask<V> active = (o.z > V(0)) & (i.z > V(0)) & Mask<V>((sample_flags & RT_Reflection) != 0);
        return select(active, pdf_upper(o, i, mode), V(0));
    }

    template <typename V>
    BSDFSample<V> sample_f(const Vec3<V> &wo, V uc, Point2<V> u, TransportMode mode, uint8_t sample_flags) const {
        BSDFSample<V> r;
        V s = select(wo.z < V(0), V(-1), V(1));
        Vec3<V> o = wo * s;
        V pc = prob_coat(FrDielectric(o.z, top.eta));
        Mask<V> coat = uc < pc;
        Mask<V> rest = pc < V(1);
        V ub = select(rest, (uc - pc) / select(rest, V(1) - pc, V(1)), V(0));
        Mask<V> cosine = (!coat) & (ub < V(q_cos));
        Mask<V> delta = (coat & Mask<V>(top_smooth())) | ((!coat) & (!cosine) & Mask<V>(base_smooth));
        Vec3<V> mirror(-o.x, -o.y, o.z);
        // every lobe's direction, then one per lane
        Vec3<V> i = SampleCosineHemisphere(u);
        if (!base_diffuse & !base_smooth) {
            // the conductor's lobe at wo', refracted out through the macro normal
            BSDFSample<V> b = bottom.sample_f(refracted(o), V(0), u, mode, RT_Reflection);
            V e(top.eta);
            V sin2 = (V(1) - b.wi.z * b.wi.z) * e * e;
            Mask<V> out = b.valid & (b.wi.z > V(0)) & (sin2 < V(1));
            Vec3<V> ib = select(out, Vec3<V>(b.wi.x * e, b.wi.y * e, safe_sqrt(V(1) - sin2)), Vec3<V>(V(0), V(0), V(-1)));
            i = select(cosine, i, ib);
        }
        if (!top_smooth()) i = select(coat, Reflect(o, top.mfd.Sample_wm(o, u)), i);
        i = select(delta, mirror, i);
        // delta lobes: f = R / cos, discrete probability
        Spectrum<V> f_delta = delta_reflectance(o) * (V(1) / DeltaAbsCos(i));
        V p_delta = delta_prob(pc);
        Mask<V> up = i.z > V(0);
        Spectrum<V> f_nd = select(up, f_upper(o, i, mode), Spectrum<V>(V(0)));
        V p_nd = select(up, pdf_upper(o, i, mode), V(0));
        r.f = select(delta, f_delta, f_nd);
        r.pdf = select(delta, p_delta, p_nd);
        r.flags = select_flag<V>(delta, SpecularReflection, GlossyReflection);
        if constexpr (is_packet_v<V>) r.flags = select(cosine & !delta, V(scalar_t<V>(DiffuseReflection)), r.flags);
        else r.flags = (cosine & !delta) ? uint8_t(DiffuseReflection) : r.flags;
        r.wi = i * s;
        r.eta = V(1);
        r.valid = (o.z > V(0)) & (i.z > V(0)) & (r.pdf > V(0)) & Mask<V>((sample_flags & RT_Reflection) != 0);
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
    using Spectral = CoatedDiffuseAnalyticSpectral<F>;  // its spectral form (core/bxdf.h)
    static constexpr int GradColumns = 16;  // eval_grad columns at most

    static CoatedDiffuseAnalyticBxDF make(const Params &p) {
        using S = param_t<F>;
        CoatedDiffuseAnalyticBxDF m;
        m.top.eta = F(p.eta);
        m.top.mfd = Microfacet<F>(F(p.alpha_x), F(p.alpha_y), p.masking);
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
    using Spectral = CoatedConductorAnalyticSpectral<F>;  // its spectral form (core/bxdf.h)
    static constexpr int GradColumns = 16;  // eval_grad columns at most

    static CoatedConductorAnalyticBxDF make(const Params &p) {
        using S = param_t<F>;
        CoatedConductorAnalyticBxDF m;
        m.top.eta = F(p.interface_eta);
        m.top.mfd = Microfacet<F>(F(p.interface_alpha_x), F(p.interface_alpha_y), p.masking);
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
        m.bottom = ConductorBxDF<F>(Microfacet<F>(F(p.conductor_alpha_x), F(p.conductor_alpha_y), p.masking), ce, ck);
        m.base_diffuse = false;
        m.base_smooth = m.bottom.is_smooth();
        m.set_layer(p.layer, rho);
        return m;
    }
};

} // namespace bsdfkit
