// RGL measured BRDFs (Dupuy & Jakob 2018, "An Adaptive Parameterization for Efficient Material
// Acquisition and Rendering"): the tensor files of the RGL material database, as pbrt-v4's
// MeasuredBxDF and Mitsuba 3's `measured` plugin read them.
//
// Tables (MeasuredTable; read and validated by bsdfkit/models/measured.py), over the unit square
// u = (u_theta, u_phi) with theta = u_theta^2 pi/2, phi = (2 u_phi - 1) pi:
//   ndf        D(wm)                        2-D, evaluation only
//   sigma      projected area sigma(wo)     2-D, evaluation only
//   vndf       D_wo(wm) in u space          conditioned on (phi_o, theta_o), sampled and inverted
//   luminance  luminance in sample space    conditioned on (phi_o, theta_o), sampled
//   rgb        reflectance in sample space  conditioned on (phi_o, theta_o), 3 channels (spectral
//                                           files are projected to RGB on load, in Python)
// wo is the conditioning direction (the one toward the viewer: Mitsuba's si.wi), wi the other.
//   f(wo, wi) cos(theta_i) = rgb(vndf^-1(u_wm)) [ndf(u_wm) / (4 sigma(u_wo)) if jacobian]
//   pdf(wi) = vndf_pdf luminance_pdf / (4 (wo.wm) max(2 pi^2 u_theta sin(theta_m), 1e-6))
// Isotropic files (n_phi <= 2) index wm's azimuth relative to wo's; anisotropic files with a
// reduction (2 pi / (phi_last - phi_first) = 2 or 4) mirror wo and wi into the stored
// half-plane or quadrant first (Mitsuba's sign folding). The `jacobian` flag is honoured as
// Mitsuba does (pbrt-v4 always applies the ndf / (4 sigma) factor). Elevation as Mitsuba:
// 2 asin(|d - z| / 2) (stable near the pole).
// Conventions: reflection only; two-sided by flipping both directions when wo.z < 0 (pbrt-v4).
// f = (f cos) / max(cos(theta_i), kMinCos): the tables do not make f cos vanish exactly at the
// horizon (bilinear interpolation leaks a little of the last measured value), so the exact
// quotient (pbrt-v4's f, Mitsuba's eval / cos) grows without bound in the last fraction of a
// degree; bsdfkit bounds it there. f cos equals Mitsuba's eval for theta_i < 89.43 degrees.
#pragma once
#include <memory>

#include "../core/bsdf_sample.h"
#include "../core/table.h"
#include "../core/frame.h"
#include "../core/warp2d.h"

namespace bsdfkit {

template <typename F> struct MeasuredSpectral;  // its spectral form (batch_spectral.h / spectral/)

struct MeasuredTable {
    Warp2DData ndf, sigma, vndf, luminance, rgb;
    bool isotropic = true, jacobian = true;
    int reduction = 1;
};

namespace measured {
template <typename F> inline F theta2u(F theta) { return std::sqrt(max_(theta, F(0)) * F(2 / 3.14159265358979323846)); }
template <typename F> inline F phi2u(F phi) { return (phi + Pi<F>) * Inv2Pi<F>; }
template <typename F> inline F u2theta(F u) { return u * u * PiOver2<F>; }
template <typename F> inline F u2phi(F u) { return (F(2) * u - F(1)) * Pi<F>; }
// Elevation of a unit vector, 2 asin(|d - z| / 2) (Mitsuba measured.cpp: stable near theta = 0).
template <typename F> inline F elevation(const Vec3<F> &d) {
    F dist = std::sqrt(d.x * d.x + d.y * d.y + sqr(d.z - F(1)));
    return F(2) * std::asin(clamp(F(0.5) * dist, F(-1), F(1)));
}
// x with its sign flipped unless s is negative (dr::mulsign_neg): folds into the stored domain.
template <typename F> inline F mulsign_neg(F x, F s) { return std::signbit(s) ? x : -x; }
inline constexpr double kMinCos = 1e-2;
} // namespace measured

// Scalar only (no `Vectorized`, issue 17): sampling and pdf walk the Warp2D tables (a data-dependent
// binary search per dimension over cumulative rows, core/warp2d.h) and eval reads per-element table
// cells; a packet would turn every step into gathers with divergent search lengths.
template <typename F> struct MeasuredKernel {
    Warp2D<F, 0> ndf, sigma;
    Warp2D<F, 2> vndf, luminance, rgb;
    bool isotropic = true, jacobian = true;
    int reduction = 1;

    uint8_t flags() const { return uint8_t(GlossyReflection); }

    // Folds (wo, wi) into the stored azimuth range of a reduced anisotropic file.
    void fold(Vec3<F> &wo, Vec3<F> &wi, F *sx, F *sy) const {
        using measured::mulsign_neg;
        bool red = reduction >= 2;
        *sy = red ? wo.y : F(-1);
        *sx = red ? (reduction == 4 ? wo.x : *sy) : F(-1);
        wo.x = mulsign_neg(wo.x, *sx), wo.y = mulsign_neg(wo.y, *sy);
        wi.x = mulsign_neg(wi.x, *sx), wi.y = mulsign_neg(wi.y, *sy);
    }

    struct Coords {
        F params[2];     // (phi_o, theta_o)
        Point2<F> u_wo, u_wm;
        Vec3<F> wm;
    };
    Coords coords(const Vec3<F> &wo, const Vec3<F> &wi) const {
        using namespace measured;
        Coords c;
        Vec3<F> m = wo + wi;
        F len2 = length_squared(m);
        c.wm = m * (F(1) / std::sqrt(len2 > F(0) ? len2 : F(1)));
        F theta_o = elevation(wo), phi_o = std::atan2(wo.y, wo.x);
        F theta_m = elevation(c.wm), phi_m = std::atan2(c.wm.y, c.wm.x);
        c.params[0] = phi_o;
        c.params[1] = theta_o;
        c.u_wo = {theta2u(theta_o), phi2u(phi_o)};
        F up = phi2u(isotropic ? phi_m - phi_o : phi_m);
        c.u_wm = {theta2u(theta_m), up - std::floor(up)};
        return c;
    }

    // ndf / (4 sigma) if the file says so (else 1): the factor of the tabulated reflectance.
    F jacobian_scale(const Coords &c) const {
        return jacobian ? ndf.eval(c.u_wm, nullptr) / (F(4) * sigma.eval(c.u_wo, nullptr)) : F(1);
    }

    // rgb at sample-space point s, times jacobian_scale: f cos(theta_i).
    Spectrum<F> f_cos(Point2<F> s, const Coords &c) const {
        Spectrum<F> v;
        auto w = rgb.weights(c.params);  // one parameter search for the three channels
        for (int ch = 0; ch < 3; ++ch) v[ch] = rgb.eval(s, w, ch);
        return v * jacobian_scale(c);
    }

    // The part of f and pdf shared by every channel layout (RGB here, wavelengths in
    // spectral/measured_spectral.h): ONE flip + fold + coordinates prelude and ONE VNDF inverse.
    struct Lookup {
        Coords c;
        Point2<F> s;     // wm's point in sample space (the VNDF inverse)
        F vndf_pdf;
        F cos_i;         // wi.z after the flip
        F wo_wm;         // wo . wm after the flip and fold
        bool active;     // same hemisphere
    };
    Lookup lookup(Vec3<F> wo, Vec3<F> wi) const {
        Lookup l;
        l.active = SameHemisphere(wo, wi);
        bool flip = wo.z < F(0);
        wo = select(flip, -wo, wo);
        wi = select(flip, -wi, wi);
        F sx, sy;
        fold(wo, wi, &sx, &sy);
        l.c = coords(wo, wi);
        auto [s, vndf_pdf] = vndf.invert(l.c.u_wm, l.c.params);
        l.s = s;
        l.vndf_pdf = vndf_pdf;
        l.cos_i = wi.z;
        l.wo_wm = dot(wo, l.c.wm);
        return l;
    }
    // f from f cos(theta_i): the bounded quotient (see the header), 0 off the hemisphere.
    template <int N> Spectrum<F, N> f_of(const Spectrum<F, N> &fcos, const Lookup &l) const {
        Spectrum<F, N> v = fcos * (F(1) / max_(l.cos_i, F(measured::kMinCos)));
        return select(l.active & (l.cos_i > F(0)), v, Spectrum<F, N>(F(0)));
    }
    // pdf of wi as sample_f produces it (all lobes allowed).
    F pdf_of(const Lookup &l) const {
        F lum_pdf = luminance.eval(l.s, l.c.params);
        F sin_m = std::sqrt(l.c.wm.x * l.c.wm.x + l.c.wm.y * l.c.wm.y);
        F jac = max_(F(2) * sqr(Pi<F>) * l.c.u_wm.x * sin_m, F(1e-6)) * F(4) * l.wo_wm;
        return l.active ? l.vndf_pdf * lum_pdf / jac : F(0);
    }

    // f and pdf of one pair (either may be skipped: a null pointer, a constant after
    // inlining) through one lookup(), shared by f(), pdf() and sample_f().
    void f_pdf(Vec3<F> wo, Vec3<F> wi, Spectrum<F> *f_out, F *pdf_out) const {
        Lookup l = lookup(wo, wi);
        if (f_out) *f_out = f_of(f_cos(l.s, l.c), l);
        if (pdf_out) *pdf_out = pdf_of(l);
    }

    Spectrum<F> f(Vec3<F> wo, Vec3<F> wi, TransportMode) const {
        Spectrum<F> v;
        f_pdf(wo, wi, &v, nullptr);
        return v;
    }

    F pdf(Vec3<F> wo, Vec3<F> wi, TransportMode, uint8_t sample_flags) const {
        F p;
        f_pdf(wo, wi, nullptr, &p);
        return keep_or_zero(p, (sample_flags & RT_Reflection) != 0);
    }

    // The sampled direction (luminance warp, then the VNDF warp; Mitsuba swaps the uniforms
    // first) in wo's frame (unflipped, unfolded); *ok: wo and wi above the surface after the flip.
    Vec3<F> sample_wi(Vec3<F> wo, Point2<F> u, bool *ok) const {
        using namespace measured;
        bool flip = wo.z < F(0);
        wo = select(flip, -wo, wo);
        Vec3<F> dummy(0, 0, 1);
        F sx, sy;
        fold(wo, dummy, &sx, &sy);
        F theta_o = elevation(wo), phi_o = std::atan2(wo.y, wo.x);
        F params[2] = {phi_o, theta_o};
        auto [s, lum_pdf_unused] = luminance.sample(Point2<F>{u.y, u.x}, params);
        auto [um, vndf_pdf_unused] = vndf.sample(s, params);
        (void)lum_pdf_unused;
        (void)vndf_pdf_unused;
        F phi_m = u2phi(um.y) + (isotropic ? phi_o : F(0)), theta_m = u2theta(um.x);
        F sp, cp, st, ct;
        sincos_(phi_m, &sp, &cp);
        sincos_(theta_m, &st, &ct);
        Vec3<F> wi = Reflect(wo, Vec3<F>(cp * st, sp * st, ct));
        *ok = (wo.z > F(0)) & (wi.z > F(0));
        wi.x = mulsign_neg(wi.x, sx);
        wi.y = mulsign_neg(wi.y, sy);
        return select(flip, -wi, wi);
    }

    BSDFSample<F> sample_f(Vec3<F> wo, F, Point2<F> u, TransportMode, uint8_t sample_flags) const {
        BSDFSample<F> r;
        bool ok;
        r.wi = sample_wi(wo, u, &ok);
        // f and pdf of the final direction through eval's own path (the warp inverse, once for
        // both), so that sample() agrees with eval()/pdf() to the last bit, not only to the
        // inverse's round trip.
        f_pdf(wo, r.wi, &r.f, &r.pdf);
        // A negative (out-of-gamut) channel is 0, as eval reports it (core/bsdf.h bsdf_f): without
        // this the BSDF-level rules reject the whole sample (f must be >= 0), so sample() lost the
        // samples that eval/pdf count (found in session 7 on a partial-range spectral file: 3 %).
        for (int ch = 0; ch < 3; ++ch) r.f[ch] = select(r.f[ch] > F(0), r.f[ch], F(0));
        r.flags = uint8_t(GlossyReflection);
        r.valid = ((sample_flags & RT_Reflection) != 0) & ok;
        return r;
    }

    void regularize() {}
};

// Content digest of a table (core/table.h): every warp's values and parameter grids, and the flags.
inline uint64_t content_digest(const Warp2DData &w, uint64_t h) {
    int head[4] = {w.W, w.H, w.channels, w.n_params};
    h = digest_bytes(head, sizeof head, h);
    for (const auto &pv : w.params64) h = digest_bytes(pv.data(), pv.size() * sizeof(double), h);
    return digest_bytes(w.data64.data(), w.data64.size() * sizeof(double), h);
}
inline uint64_t content_digest(const MeasuredTable &t) {
    int head[3] = {int(t.isotropic), int(t.jacobian), t.reduction};
    uint64_t h = digest_bytes(head, sizeof head);
    for (const Warp2DData *w : {&t.ndf, &t.sigma, &t.vndf, &t.luminance, &t.rgb}) h = content_digest(*w, h);
    return h;
}

// Parameters (core/bxdf.h): the table read from an RGL tensor file (Python: bsdfkit.Measured).
struct MeasuredParams {
    SharedTable<MeasuredTable> table;  // required
    template <class V> void fields(V &&v) { v("table", table); }
};

template <typename F> struct MeasuredBxDF : MeasuredKernel<F> {
    using Kernel = MeasuredKernel<F>;
    using Params = MeasuredParams;
    SharedTable<MeasuredTable> table;  // keeps the data alive

    static constexpr const char *Name = "Measured";
    using Spectral = MeasuredSpectral<F>;  // its spectral form (core/bxdf.h)

    static MeasuredBxDF make(const Params &p) {
        MeasuredBxDF m;
        const MeasuredTable &t = *p.table;
        m.ndf = Warp2D<F, 0>(t.ndf);
        m.sigma = Warp2D<F, 0>(t.sigma);
        m.vndf = Warp2D<F, 2>(t.vndf);
        m.luminance = Warp2D<F, 2>(t.luminance);
        m.rgb = Warp2D<F, 2>(t.rgb);
        m.isotropic = t.isotropic;
        m.jacobian = t.jacobian;
        m.reduction = t.reduction;
        m.table = p.table;
        return m;
    }
};

} // namespace bsdfkit
