// MERL measured isotropic BRDF tables (Matusik, Pfister, Brand, McMillan 2003, "A Data-Driven
// Reflectance Model"), evaluated and importance-sampled.
//
// Table (MERLTable; loaded and validated by bsdfkit/models/merl.py): 90 x 90 x 180 bins over the
// Rusinkiewicz half/difference angles (theta_h, theta_d, phi_d), RGB, already multiplied by the
// channel scales 1/1500, 1.15/1500, 1.66/1500 (so values are f in 1/sr, cosine excluded).
// Not-measured bins (negative in the file) are stored as 0 (BBM / ALTA convention).
//   theta_h bin  i_h = sqrt(theta_h / (pi/2)) * 90   (non-linear: fine near the specular peak)
//   theta_d bin  i_d = theta_d / (pi/2) * 90
//   phi_d bin    i_p = phi_d / pi * 180 after the reciprocity fold phi_d < 0 -> phi_d + pi
// Knob `Linear`: false = MERL's own lookup (floor to the bin, the bin's value); true = trilinear
// interpolation between bin centres (clamped on theta_h / theta_d, periodic on phi_d: the fold
// makes f pi-periodic in phi_d).
//
// Conventions: reflection only, two-sided by flipping both directions when wo.z < 0 (as
// pbrt-v4's MeasuredBxDF); f = 0 unless wo and wi are on the same side. The difference vector
// is computed from wi (MERL's "in", the light direction; the fold makes the choice irrelevant).
//
// Sampling (bsdfkit's own tabulated sampler, built once per table by make_merl_table): for K
// incidence angles theta_o,k = (k + 1/2) / K * pi/2 (wo in the xz plane), a piecewise-constant
// density of the half vector h over cells [theta_h row r (MERL's 90 non-linear rows)] x [phi_h
// column c (n_phi uniform columns over 2 pi)], constant per unit solid angle inside a cell, with
// cell masses proportional to luminance(f) cos(theta_i) 4 |wo.h| (the h-density that makes
// pdf(wi) proportional to luminance(f) cos(theta_i)) averaged over 2 x 2 points per cell.
// At a given theta_o the two neighbouring tables are mixed linearly (the lobe uniform picks one),
// rotated to wo's azimuth, and the whole is mixed with cosine sampling (probability kMERLCosine,
// which keeps pdf > 0 wherever f > 0). wi = reflect(wo, h); samples below the horizon are invalid.
// pdf(wi) = (1 - c) sum_k w_k p_k(h) / (4 |wo.h|) + c cos(theta_i) / pi. Data-dependent loops:
// none (the CDF searches are fixed-count branch-free bisections).
#pragma once
#include <array>
#include <memory>
#include <type_traits>
#include <vector>

#include "../core/bsdf_sample.h"
#include "../core/table.h"
#include "../core/frame.h"
#include "../core/sampling.h"
#include "../core/warp2d.h"

namespace bsdfkit {

template <typename F, bool Linear> struct MERLSpectralT;  // its spectral form (batch_spectral.h / spectral/)

namespace merl {
inline constexpr int kThetaH = 90, kThetaD = 90, kPhiD = 180;
inline constexpr int kSize = kThetaH * kThetaD * kPhiD;        // bins per channel
inline constexpr double kScale[3] = {1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0};  // RED/GREEN/BLUE_SCALE
inline constexpr double kCosineFraction = 0.1;                 // defensive cosine-sampling share
inline constexpr double kLum[3] = {0.2126, 0.7152, 0.0722};    // Rec. 709 / sRGB luminance weights
} // namespace merl

struct MERLTable {
    // Scaled values, [(i_h * 90 + i_d) * 180 + i_p] * 3 + channel.
    std::vector<double> v64;
    std::vector<float> v32;
    // Sampler: K theta_o tables of 90 rows x n_phi columns.
    int K = 0, n_phi = 0;
    std::vector<double> marg64, cond64, dens64;  // [k][r] row CDF, [k][r][c] column CDF, [k][r][c] density per sr of h
    std::vector<float> marg32, cond32, dens32;

    template <typename F> const F *values() const {
        if constexpr (std::is_same_v<F, float>) return v32.data(); else return v64.data();
    }
    template <typename F> const F *marg() const {
        if constexpr (std::is_same_v<F, float>) return marg32.data(); else return marg64.data();
    }
    template <typename F> const F *cond() const {
        if constexpr (std::is_same_v<F, float>) return cond32.data(); else return cond64.data();
    }
    template <typename F> const F *dens() const {
        if constexpr (std::is_same_v<F, float>) return dens32.data(); else return dens64.data();
    }
};

// First index i in [0, n) with cdf[i] > u (n - 1 if none): branch-free bisection, fixed count.
// Strict, so that the chosen interval always has positive mass when u < cdf[n - 1] = 1.
template <typename F> inline int cdf_search(const F *cdf, int n, F u) {
    int i = 0;
    for (int s = 1 << 10; s > 0; s >>= 1) {
        int j = i + s;
        bool ok = j <= n - 1;
        int jj = ok ? j : n - 1;
        i = (ok & (table_at(cdf, jj - 1) <= u)) ? j : i;
    }
    return i;
}

// Rusinkiewicz coordinates of (wi, wo) (Rusinkiewicz 1998; MERL std_coords_to_half_diff_coords):
// h = normalize(wi + wo); d = wi rotated by -phi_h about n, then by -theta_h about the binormal.
template <typename F> struct HalfDiff {
    F cos_h, theta_h, theta_d, phi_d;
};
template <typename F> inline HalfDiff<F> half_diff(const Vec3<F> &wo, const Vec3<F> &wi) {
    Vec3<F> h = wo + wi;
    F len2 = length_squared(h);
    h = h * (F(1) / std::sqrt(len2 > F(0) ? len2 : F(1)));
    h = len2 > F(0) ? h : Vec3<F>(0, 0, 1);
    F r2 = h.x * h.x + h.y * h.y;
    bool pole = r2 <= F(0);
    F inv_r = F(1) / std::sqrt(pole ? F(1) : r2);
    F cp = pole ? F(1) : h.x * inv_r, sp = pole ? F(0) : h.y * inv_r;
    F ct = clamp(h.z, F(-1), F(1)), st = std::sqrt(pole ? F(0) : r2);
    // rotate wi by -phi_h about z, then by -theta_h about y
    F x1 = cp * wi.x + sp * wi.y, y1 = -sp * wi.x + cp * wi.y;
    F x2 = ct * x1 - st * wi.z, z2 = st * x1 + ct * wi.z;
    HalfDiff<F> r;
    r.cos_h = ct;
    r.theta_h = std::acos(ct);
    r.theta_d = std::acos(clamp(z2, F(-1), F(1)));
    F pd = std::atan2(y1, x2);
    r.phi_d = pd < F(0) ? pd + Pi<F> : pd;  // reciprocity fold (MERL lookup_brdf_val)
    return r;
}

// Scalar only (no `Vectorized`, issue 17): per element a lookup at a data-dependent index of the
// 90 x 90 x 180 table (nearest or trilinear), plus acos/atan2 of the half/difference angles; its
// sampler walks the tabulated marginals. Candidates for gathers later, not a divide-bound kernel.
template <typename F, bool Linear> struct MERLKernel {
    const F *values = nullptr;
    const F *marg = nullptr, *cond = nullptr, *dens = nullptr;
    int K = 0, n_phi = 0;

    uint8_t flags() const { return uint8_t(GlossyReflection); }

    F value(int64_t bin, int c) const { return table_at(values, bin * 3 + c); }

    // The table at (theta_h, theta_d, phi_d), folded phi_d in [0, pi]: the bins' values through
    // get(bin) -> Spectrum<F, N> (the RGB values here; spectral/measured_spectral.h reads the
    // bins' uplifted spectra), nearest or trilinear per channel.
    template <int N, typename Get> Spectrum<F, N> lookup_with(const HalfDiff<F> &hd, const Get &get) const {
        using namespace merl;
        F xh = std::sqrt(max_(hd.theta_h, F(0)) * F(2 / 3.14159265358979323846)) * F(kThetaH);
        F xd = hd.theta_d * F(2 / 3.14159265358979323846) * F(kThetaD);
        F xp = hd.phi_d * F(1 / 3.14159265358979323846) * F(kPhiD);
        Spectrum<F, N> out;
        if constexpr (!Linear) {
            // MERL: int(x), clamped to the table
            int ih = int(clamp(xh, F(0), F(kThetaH - 1)));
            int id = int(clamp(xd, F(0), F(kThetaD - 1)));
            int ip = int(clamp(xp, F(0), F(kPhiD - 1)));
            out = get((int64_t(ih) * kThetaD + id) * kPhiD + ip);
        } else {
            // bin centres at x = i + 1/2
            F th = clamp(xh - F(0.5), F(0), F(kThetaH - 1)), td = clamp(xd - F(0.5), F(0), F(kThetaD - 1));
            F tp = xp - F(0.5);
            int h0 = min_(int(th), kThetaH - 2), d0 = min_(int(td), kThetaD - 2);
            F fp = std::floor(tp);
            int p0 = int(fp);
            F wh = th - F(h0), wd = td - F(d0), wp = tp - fp;
            int p1 = p0 + 1;
            p0 = p0 < 0 ? p0 + kPhiD : p0;            // periodic in phi_d (period pi)
            p1 = p1 >= kPhiD ? p1 - kPhiD : p1;
            p0 = clamp(p0, 0, kPhiD - 1);
            p1 = clamp(p1, 0, kPhiD - 1);
            auto at = [&](int a, int b, int p) { return get((int64_t(a) * kThetaD + b) * kPhiD + p); };
            Spectrum<F, N> a000 = at(h0, d0, p0), a001 = at(h0, d0, p1), a010 = at(h0, d0 + 1, p0),
                           a011 = at(h0, d0 + 1, p1), a100 = at(h0 + 1, d0, p0), a101 = at(h0 + 1, d0, p1),
                           a110 = at(h0 + 1, d0 + 1, p0), a111 = at(h0 + 1, d0 + 1, p1);
            for (int c = 0; c < N; ++c) {
                F v00 = lerp(wp, a000[c], a001[c]);
                F v01 = lerp(wp, a010[c], a011[c]);
                F v10 = lerp(wp, a100[c], a101[c]);
                F v11 = lerp(wp, a110[c], a111[c]);
                out[c] = lerp(wh, lerp(wd, v00, v01), lerp(wd, v10, v11));
            }
        }
        return out;
    }
    // The RGB values of a bin.
    Spectrum<F> rgb_at(int64_t bin) const {
        Spectrum<F> v;
        for (int c = 0; c < 3; ++c) v[c] = value(bin, c);
        return v;
    }

    // f through lookup_with: reflection only, two-sided by flipping (pbrt-v4 MeasuredBxDF).
    template <int N, typename Get> Spectrum<F, N> f_with(Vec3<F> wo, Vec3<F> wi, const Get &get) const {
        bool active = SameHemisphere(wo, wi);
        bool flip = wo.z < F(0);
        wo = select(flip, -wo, wo);
        wi = select(flip, -wi, wi);
        Spectrum<F, N> v = lookup_with<N>(half_diff(wo, wi), get);
        return select(active, v, Spectrum<F, N>(F(0)));
    }

    Spectrum<F> f(Vec3<F> wo, Vec3<F> wi, TransportMode) const {
        return f_with<3>(wo, wi, [&](int64_t bin) { return rgb_at(bin); });
    }

    // ---------------------------------------------------------------- sampling

    // theta_o table pair and weight for cos(theta_o) = z (table k at theta = (k + 1/2) / K pi/2).
    void theta_o_tables(F z, int *k0, int *k1, F *t) const {
        F x = std::acos(clamp(z, F(0), F(1))) * F(2 / 3.14159265358979323846) * F(K) - F(0.5);
        F xc = clamp(x, F(0), F(K - 1));
        int a = min_(int(xc), K - 1);
        *k0 = a;
        *k1 = min_(a + 1, K - 1);
        *t = xc - F(a);
    }

    // Row r spans theta_h in [(pi/2)(r/90)^2, (pi/2)((r+1)/90)^2].
    static F row_theta(int r) { return F(0.5) * Pi<F> * sqr(F(r) * F(1.0 / merl::kThetaH)); }

    // Density per unit solid angle of h (in the frame where wo has azimuth 0) under table k.
    F table_density(int k, F theta_h, F phi_h) const {
        using namespace merl;
        int r = min_(int(std::sqrt(max_(theta_h, F(0)) * F(2 / 3.14159265358979323846)) * F(kThetaH)), kThetaH - 1);
        F ph = phi_h < F(0) ? phi_h + F(2) * Pi<F> : phi_h;
        int c = clamp(int(ph * F(n_phi) * Inv2Pi<F>), 0, n_phi - 1);
        return table_at(dens, (int64_t(k) * kThetaH + r) * n_phi + c);
    }

    // wo's azimuth as (cos, sin); (1, 0) at the pole.
    static void azimuth(const Vec3<F> &w, F *c, F *s) {
        F r2 = w.x * w.x + w.y * w.y;
        bool pole = r2 <= F(0);
        F inv = F(1) / std::sqrt(pole ? F(1) : r2);
        *c = pole ? F(1) : w.x * inv;
        *s = pole ? F(0) : w.y * inv;
    }

    F pdf_upper(const Vec3<F> &wo, const Vec3<F> &wi) const {
        Vec3<F> h = wo + wi;
        F len2 = length_squared(h);
        h = h * (F(1) / std::sqrt(len2 > F(0) ? len2 : F(1)));
        F ca, sa;
        azimuth(wo, &ca, &sa);
        // h in the frame where wo has azimuth 0
        F hx = ca * h.x + sa * h.y, hy = -sa * h.x + ca * h.y;
        F theta_h = std::acos(clamp(h.z, F(-1), F(1)));
        F phi_h = std::atan2(hy, hx);
        int k0, k1;
        F t;
        theta_o_tables(wo.z, &k0, &k1, &t);
        F ph = lerp(t, table_density(k0, theta_h, phi_h), table_density(k1, theta_h, phi_h));
        F jac = F(1) / (F(4) * max_(absdot(wo, h), std::numeric_limits<F>::min()));
        F p_tab = (len2 > F(0)) & (h.z > F(0)) ? ph * jac : F(0);
        return (F(1) - F(merl::kCosineFraction)) * p_tab + F(merl::kCosineFraction) * CosineHemispherePDF(wi.z);
    }

    F pdf(Vec3<F> wo, Vec3<F> wi, TransportMode, uint8_t sample_flags) const {
        bool active = SameHemisphere(wo, wi);
        bool flip = wo.z < F(0);
        wo = select(flip, -wo, wo);
        wi = select(flip, -wi, wi);
        F p = pdf_upper(wo, wi);
        return keep_or_zero(active ? p : F(0), (sample_flags & RT_Reflection) != 0);
    }

    BSDFSample<F> sample_f(Vec3<F> wo, F uc, Point2<F> u, TransportMode mode, uint8_t sample_flags) const {
        using namespace merl;
        bool flip = wo.z < F(0);
        wo = select(flip, -wo, wo);
        const F c = F(kCosineFraction);
        bool pick_cos = uc < c;
        F uc2 = (uc - c) * (F(1) / (F(1) - c));
        int k0, k1;
        F t;
        theta_o_tables(wo.z, &k0, &k1, &t);
        int k = uc2 < t ? k1 : k0;
        // row from the marginal CDF, column from the row's conditional CDF, both re-used inside the cell
        const F *mc = marg + int64_t(k) * kThetaH;
        int r = cdf_search(mc, kThetaH, u.y);
        F m0 = r > 0 ? table_at(mc, r - 1) : F(0), m1 = table_at(mc, r);
        F vy = clamp((u.y - m0) / (m1 > m0 ? m1 - m0 : F(1)), F(0), F(1));
        const F *cc = cond + (int64_t(k) * kThetaH + r) * n_phi;
        int col = cdf_search(cc, n_phi, u.x);
        F c0 = col > 0 ? table_at(cc, col - 1) : F(0), c1 = table_at(cc, col);
        F vx = clamp((u.x - c0) / (c1 > c0 ? c1 - c0 : F(1)), F(0), F(1));
        // uniform in solid angle inside the cell
        F cos0 = std::cos(row_theta(r)), cos1 = std::cos(row_theta(r + 1));
        F cos_h = lerp(vy, cos0, cos1);
        F sin_h = safe_sqrt(F(1) - cos_h * cos_h);
        F phi_h = (F(col) + vx) * (F(2) * Pi<F> / F(n_phi));
        F sp, cp;
        sincos_(phi_h, &sp, &cp);
        F ca, sa;
        azimuth(wo, &ca, &sa);
        // back to wo's azimuth
        F hx = sin_h * cp, hy = sin_h * sp;
        Vec3<F> h(ca * hx - sa * hy, sa * hx + ca * hy, cos_h);
        Vec3<F> wi = Reflect(wo, h);
        wi = select(pick_cos, SampleCosineHemisphere(u), wi);
        BSDFSample<F> s;
        s.f = f(wo, wi, mode);
        s.pdf = pdf_upper(wo, wi);
        s.wi = select(flip, -wi, wi);
        s.flags = uint8_t(GlossyReflection);
        s.valid = ((sample_flags & RT_Reflection) != 0) & (wo.z > F(0)) & (wi.z > F(0));
        return s;
    }

    void regularize() {}
};

// Content digest of a table (core/table.h): its values and sampler resolution.
inline uint64_t content_digest(const MERLTable &t) {
    int head[2] = {t.K, t.n_phi};
    return digest_bytes(t.v64.data(), t.v64.size() * sizeof(double), digest_bytes(head, sizeof head));
}

// Parameters (core/bxdf.h), shared by MERLNearest and MERLLinear: the table (Python: bsdfkit.MERL).
struct MERLParams {
    SharedTable<MERLTable> table;  // required
    template <class V> void fields(V &&v) { v("table", table); }
};

template <typename F, bool Linear> struct MERLT : MERLKernel<F, Linear> {
    using Kernel = MERLKernel<F, Linear>;
    using Params = MERLParams;
    SharedTable<MERLTable> table;  // keeps the data alive

    static constexpr const char *Name = Linear ? "MERLLinear" : "MERLNearest";
    using Spectral = MERLSpectralT<F, Linear>;  // its spectral form (core/bxdf.h)

    static MERLT make(const Params &p) {
        MERLT m;
        const MERLTable &t = *p.table;
        m.values = t.template values<F>();
        m.marg = t.template marg<F>();
        m.cond = t.template cond<F>();
        m.dens = t.template dens<F>();
        m.K = t.K;
        m.n_phi = t.n_phi;
        m.table = p.table;
        return m;
    }
};

template <typename F> using MERLNearestBxDF = MERLT<F, false>;
template <typename F> using MERLLinearBxDF = MERLT<F, true>;

// Builds a table from scaled values (kSize * 3, channel-interleaved, unmeasured already 0) and its sampler
// (K theta_o tables, n_phi azimuth columns) from the `Linear` lookup (cpp/src/measured.cpp); nthreads pool
// threads, deterministic. nullptr when the interrupt hook (Ctrl-C, pool.h) stopped it: its error is set.
std::shared_ptr<const MERLTable> make_merl_table(std::vector<double> values, int K, int n_phi, bool linear,
                                                 int nthreads);

} // namespace bsdfkit
