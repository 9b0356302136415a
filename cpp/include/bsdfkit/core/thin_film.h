// Thin-film interference (iridescence) Fresnel: Belcour & Barla 2017, "A Practical Extension to
// Microfacet Theory for the Modeling of Varying Iridescence" (ACM TOG 36(4)), RGB form; and the
// Gulbrandsen 2014 "Artist Friendly Metallic Fresnel" (JCGT 3(4)) map from (reflectivity, edge
// tint) to a complex IOR, for giving an F82-tint metal an effective base IOR under a film.
//
// What it computes: the reflectance of a smooth three-layer stack, outside (IOR 1) | film
// (IOR eta_film, thickness d) | base (eta_base, or eta_base + i k_base), at the outside cosine
// cos_i, averaged over s and p polarization and integrated against the CIE 1931 colour matching
// functions (illuminant E), returned as linear Rec. 709 RGB.
//  - Per polarization, the Airy reflectance R(D) = |r12 + t12 t21 r23 e^{iD} / (1 - r21 r23 e^{iD})|^2
//    (paper eq. 3), D = 2 pi OPD / lambda, OPD = 2 eta_film d cos_t (cos_t in the film), is written
//    as the Fourier series (paper eqs. 6-8)
//        R = C_0 + 2 sum_{m>=1} C_m cos(m (D + phi21 + phi23)),
//        C_0 = R12 + Rs,  C_m = (Rs - T121) rho^m,  Rs = T121^2 R23 / (1 - R12 R23),
//        T121 = 1 - R12,  rho = sqrt(R12 R23),
//    with phi21 = arg r21 (0 or pi) and phi23 = arg r23 (any angle for a conductor, or under total
//    internal reflection at the film-base interface). Amplitudes in ONE convention throughout:
//    r_s = (n_i c_i - n_t c_t)/(n_i c_i + n_t c_t), r_p = (n_t c_i - n_i c_t)/(n_t c_i + n_i c_t),
//    complex c_t = sqrt(1 - sin^2 / n_t^2) on the principal branch (n + i k, k >= 0).
//  - Each cos(m (2 pi OPD / lambda) + m phi) is integrated against a colour matching function in
//    closed form by the paper's Gaussian fit of x, y, z over wavenumber (paper eq. 9 and its
//    supplemental code): S(OPD, shift) = sum_j A_j cos(2 pi pos_j OPD + shift) exp(-var_j (2 pi OPD)^2).
//    Constants: Belcour's supplemental code as carried in MaterialX mx_microfacet_specular.glsl
//    (mx_eval_sensitivity). The amplitudes are normalized per channel so that S(0, 0) = 1 exactly
//    (the paper divides all three by the y integral 1.0685e-7: x and z then sum to 1.0005 and
//    1.0011), so that a flat spectrum maps to XYZ = (1, 1, 1) and thickness 0 gives the base Fresnel.
//  - The m-series is summed explicitly for m = 1..kAiryTerms and its tail m > M = kAiryTerms in
//    closed form, the envelope exp(-var m^2 p^2) taken with m^2 replaced by its tangent at M + 1
//    (a geometric series): exact at OPD = 0 (the whole series, Re z/(1-z)) and where the
//    envelope has decayed; the tail matters near grazing incidence only, where rho -> 1.
//  - XYZ (illuminant E) -> linear Rec. 709 RGB with D65 white, Bradford-adapted from E to D65, so
//    XYZ = (1, 1, 1) maps to RGB = (1, 1, 1) (MaterialX uses CIE 1931 RGB instead). Result clamped
//    to [0, 1] per channel.
// Conventions and edge cases:
//  - thickness_um in micrometres (OpenPBR's thin_film_thickness); thickness <= 0 returns the
//    base Fresnel exactly: FrDielectric(cos_i, eta_base) / FrComplex(cos_i, eta_base, k_base).
//  - eta_film is clamped to >= 1 (as MaterialX: a film of IOR < 1 under total internal
//    reflection from outside would need frustrated-TIR terms the series does not carry);
//    eta_film = 1 is no film (r12 = 0) and returns the base Fresnel at any thickness.
//  - cos_i is clamped to [0, 1] (light from outside only); cos_i = 0 gives 1.
//  - Conductor with an RGB base: channel c of the result is channel c of the RGB colour of the film
//    over a grey base of IOR eta_base[c] + i k_base[c] (three XYZ evaluations). Belcour's code (and
//    MaterialX) instead feed base channel c to the c-th CIE sensitivity (x, y, z) and convert that
//    XYZ, which mixes an RGB quantity into XYZ and does not reduce to FrComplex at thickness 0
//    (measured: off by up to 0.34 for a gold-like base); ours does, and equals theirs for a grey base.
//    The dielectric base is a scalar (one XYZ evaluation).
//  - All IORs are relative to the outside medium.
#pragma once
#include "fresnel.h"
#include "math.h"
#include "spectrum.h"

namespace bsdfkit {

namespace thin_film_detail {

// Explicit terms of the Airy series before its closed-form tail.
inline constexpr int kAiryTerms = 12;

// Belcour & Barla 2017 Gaussian fit of the CIE 1931 x, y, z over wavenumber (val, pos [1/m],
// var [m^2]; MaterialX mx_eval_sensitivity): x has two lobes, y and z one.
struct SensitivityLobe {
    double val, pos, var;
};
inline constexpr SensitivityLobe kLobes[4] = {
    {5.4856e-13, 1.6810e+06, 4.3278e+09}, // x
    {9.7470e-14, 2.2399e+06, 4.5282e+09}, // x (blue lobe)
    {4.4201e-13, 1.7953e+06, 9.3046e+09}, // y
    {5.2481e-13, 2.2084e+06, 6.6121e+09}, // z
};
inline constexpr int kLobeChannel[4] = {0, 0, 1, 2};

// Amplitudes A_j = val sqrt(2 pi var), normalized so that each channel's sum is 1.
struct SensitivityTable {
    double amp[4];
    SensitivityTable() {
        double a[4], sum[3] = {0, 0, 0};
        for (int j = 0; j < 4; ++j) {
            a[j] = kLobes[j].val * std::sqrt(2.0 * 3.14159265358979323846 * kLobes[j].var);
            sum[kLobeChannel[j]] += a[j];
        }
        for (int j = 0; j < 4; ++j) amp[j] = a[j] / sum[kLobeChannel[j]];
    }
};
inline const SensitivityTable &sensitivity_table() {
    static const SensitivityTable t;
    return t;
}

// XYZ (illuminant E) -> linear Rec. 709 (D65), Bradford-adapted E -> D65 (computed in double from
// the Rec. 709 primaries, D65 (0.3127, 0.3290) and the Bradford cone matrix; rows sum to 1).
inline constexpr double kXYZToRGB[3][3] = {
    {3.1466576541, -1.6664637545, -0.4801938996},
    {-0.9955216058, 1.9557567338, 0.0397648720},
    {0.0635948029, -0.2145632222, 1.1509684193},
};

// The interfaces for one polarization and one base channel: R12, the sign of r21 (e^{i phi21}),
// R23 and e^{i phi23}. c1 = outside cosine, c2 = film cosine (real: eta_film >= 1), n2 = film IOR,
// (n3, k3) the base, sin2_1 = 1 - c1^2.
template <typename F> struct AiryInterfaces {
    F R12[2], e21[2], R23[2];
    Cplx<F> e23[2];
};
template <typename F>
inline AiryInterfaces<F> airy_interfaces(F c1, F c2, F sin2_1, F n2, F n3, F k3) {
    AiryInterfaces<F> o;
    // 1 -> 2 (real): r_s = (c1 - n2 c2)/(c1 + n2 c2), r_p = (n2 c1 - c2)/(n2 c1 + c2); r21 = -r12.
    F rs = (c1 - n2 * c2) / (c1 + n2 * c2);
    F rp = (n2 * c1 - c2) / (n2 * c1 + c2);
    o.R12[0] = sqr(rs);
    o.R12[1] = sqr(rp);
    o.e21[0] = select(rs > F(0), F(-1), F(1)); // arg(r21) = arg(-r12)
    o.e21[1] = select(rp > F(0), F(-1), F(1));
    // 2 -> 3 (complex): n3~ = n3 + i k3, c3 = sqrt(1 - sin2_1 / n3~^2) (principal branch).
    Cplx<F> n{n3, k3};
    Cplx<F> nn = cmul(n, n);
    F inv = F(1) / cnorm(nn);
    Cplx<F> z{F(1) - sin2_1 * nn.re * inv, sin2_1 * nn.im * inv}; // 1 - sin^2 conj(nn) / |nn|^2
    Cplx<F> c3 = csqrt(z);
    Cplx<F> nc3 = cmul(n, c3);
    Cplx<F> n2c2{n2 * c2, F(0)};
    // s: (n2 c2 - n3~ c3) / (n2 c2 + n3~ c3);  p: (n3~ c2 - n2 c3) / (n3~ c2 + n2 c3)
    Cplx<F> num[2] = {{n2c2.re - nc3.re, -nc3.im}, {n.re * c2 - n2 * c3.re, n.im * c2 - n2 * c3.im}};
    Cplx<F> den[2] = {{n2c2.re + nc3.re, nc3.im}, {n.re * c2 + n2 * c3.re, n.im * c2 + n2 * c3.im}};
    for (int i = 0; i < 2; ++i) {
        F dn = cnorm(den[i]);
        F nm = cnorm(num[i]);
        o.R23[i] = select(dn > F(0), nm / dn, F(1));
        // e^{i phi23} = num conj(den) / |num conj(den)|; 1 where num = 0 (R23 = 0, unused)
        Cplx<F> q = cmul(num[i], Cplx<F>{den[i].re, -den[i].im});
        F qn = cnorm(q);
        Mask<F> ok = qn > F(0);
        F iq = F(1) / sqrt(select(ok, qn, F(1)));
        o.e23[i] = {select(ok, q.re * iq, F(1)), select(ok, q.im * iq, F(0))};
    }
    return o;
}

// One XYZ channel ch of one polarization: C_0 + 2 sum_m C_m S_ch(m OPD, m phi), with p = 2 pi OPD.
template <typename F> inline F airy_channel(int ch, F R12, F e21, F R23, Cplx<F> e23, F p) {
    const SensitivityTable &tab = sensitivity_table();
    F T = F(1) - R12;
    F den = neg_mul_add(R12, R23, F(1));
    Mask<F> ok = den > F(0);
    F Rs = select(ok, T * T * R23 / select(ok, den, F(1)), F(0));
    F rho = sqrt(R12 * R23);
    F c_base = Rs - T; // C_m / rho^m
    Cplx<F> ephi{e21 * e23.re, e21 * e23.im};
    F sum(0);
    for (int j = 0; j < 4; ++j) {
        if (kLobeChannel[j] != ch) continue;
        const SensitivityLobe &L = kLobes[j];
        F s, c;
        sincos_(F(L.pos) * p, &s, &c);
        Cplx<F> z = cmul(Cplx<F>{rho * c, rho * s}, ephi); // rho e^{i (pos p + phi)}
        F g = exp(F(-L.var) * p * p), g2 = g * g;          // envelope exp(-var m^2 p^2) = g^{m^2}
        F env(1), step = g;                                 // step = g^{2m - 1}
        Cplx<F> zm{F(1), F(0)};
        F acc(0);
        for (int m = 1; m <= kAiryTerms; ++m) {
            zm = cmul(zm, z);
            env = env * step;
            step = step * g2;
            acc = mul_add(zm.re, env, acc);
        }
        // tail m > M: m^2 replaced by its tangent at M + 1, g^{m^2} ~ g^{(M+1)^2} h^{m-M-1} with
        // h = g^{2(M+1)}: env_{M+1} Re(z^{M+1} / (1 - h z)), a geometric series (h = 1 at p = 0)
        zm = cmul(zm, z);
        env = env * step;
        F h = step * g;
        Cplx<F> omz{neg_mul_add(h, z.re, F(1)), -h * z.im};
        F d = cnorm(omz);
        Mask<F> dok = d > F(0);
        F tail = (zm.re * omz.re + zm.im * omz.im) / select(dok, d, F(1));
        acc = mul_add(select(dok, tail, F(0)), env, acc);
        sum = mul_add(F(tab.amp[j]), acc, sum);
    }
    return R12 + Rs + F(2) * c_base * sum;
}

// p = 2 pi OPD [m] capped where every m >= 1 term's envelope is below exp(-60) (the phases of
// such terms do not matter; the cap keeps sincos_'s argument small).
template <typename F> inline F airy_phase(F c2, F n2, F thickness_um) {
    constexpr double kVarMin = 4.3278e+09;
    const double cap = std::sqrt(60.0 / kVarMin);
    F p = F(2.0 * 3.14159265358979323846 * 2.0e-6) * n2 * c2 * thickness_um;
    return min_(p, F(cap));
}

// The film over a base of one complex IOR n3 + i k3 (the same at every wavelength), in XYZ.
template <typename F> inline void airy_xyz(F c1, F c2, F sin2_1, F nf, F n3, F k3, F p, F xyz[3]) {
    AiryInterfaces<F> ifc = airy_interfaces(c1, c2, sin2_1, nf, n3, k3);
    for (int ch = 0; ch < 3; ++ch) {
        F acc(0);
        for (int pol = 0; pol < 2; ++pol)
            acc = acc + airy_channel(ch, ifc.R12[pol], ifc.e21[pol], ifc.R23[pol], ifc.e23[pol], p);
        xyz[ch] = F(0.5) * acc;
    }
}
template <typename F> inline F xyz_to_rgb_row(int i, const F xyz[3]) {
    return mul_add(F(kXYZToRGB[i][0]), xyz[0], mul_add(F(kXYZToRGB[i][1]), xyz[1], F(kXYZToRGB[i][2]) * xyz[2]));
}

// Channel c of the result is channel c of the RGB colour of the film over a grey base of IOR
// (n3[c], k3[c]) (one_base: n3[0], k3[0] for all three, one XYZ evaluation). Unclamped.
template <typename F>
inline Spectrum<F> airy_rgb(F c1, F eta_film, const F n3[3], const F k3[3], F thickness_um, bool one_base) {
    F sin2_1 = neg_mul_add(c1, c1, F(1));
    F c2 = safe_sqrt(F(1) - sin2_1 / sqr(eta_film));
    F p = airy_phase(c2, eta_film, thickness_um);
    Spectrum<F> rgb;
    F xyz[3];
    for (int c = 0; c < 3; ++c) {
        if (c == 0 || !one_base) airy_xyz(c1, c2, sin2_1, eta_film, n3[c], k3[c], p, xyz);
        rgb[c] = xyz_to_rgb_row(c, xyz);
    }
    return rgb;
}

} // namespace thin_film_detail

// Film of IOR eta_film and thickness thickness_um [micrometres] on a dielectric of IOR eta_base
// (both relative to the outside), seen from outside at cos_i: linear Rec. 709 RGB reflectance.
template <typename F>
inline Spectrum<F> AiryReflectanceDielectric(F cos_i, F eta_film, F eta_base, F thickness_um) {
    F c1 = clamp(cos_i, F(0), F(1));
    F nf = max_(eta_film, F(1));
    F n3[3] = {eta_base, eta_base, eta_base}, k3[3] = {F(0), F(0), F(0)};
    Spectrum<F> film = thin_film_detail::airy_rgb(c1, nf, n3, k3, thickness_um, true);
    Spectrum<F> bare(FrDielectric(c1, eta_base));
    Mask<F> none = (thickness_um <= F(0)) | (nf == F(1));
    for (int i = 0; i < 3; ++i) film[i] = clamp(film[i], F(0), F(1));
    return select(none, bare, film);
}

// The same over a conductor eta_base + i k_base (RGB, relative to the outside).
template <typename F>
inline Spectrum<F> AiryReflectanceConductor(F cos_i, F eta_film, const Spectrum<F> &eta_base,
                                            const Spectrum<F> &k_base, F thickness_um) {
    F c1 = clamp(cos_i, F(0), F(1));
    F nf = max_(eta_film, F(1));
    F n3[3] = {eta_base[0], eta_base[1], eta_base[2]}, k3[3] = {k_base[0], k_base[1], k_base[2]};
    Spectrum<F> film = thin_film_detail::airy_rgb(c1, nf, n3, k3, thickness_um, false);
    Spectrum<F> bare;
    for (int i = 0; i < 3; ++i) bare[i] = FrComplex(c1, eta_base[i], k_base[i]);
    Mask<F> none = (thickness_um <= F(0)) | (nf == F(1));
    for (int i = 0; i < 3; ++i) film[i] = clamp(film[i], F(0), F(1));
    return select(none, bare, film);
}

// Gulbrandsen 2014, "Artist Friendly Metallic Fresnel" (JCGT 3(4), section 3): the complex IOR
// whose normal reflectance is r and whose edge behaviour follows the tint g, per channel:
//   n = g n_min + (1 - g) n_max,  n_min = (1 - r)/(1 + r),  n_max = (1 + sqrt r)/(1 - sqrt r),
//   k^2 = ((n + 1)^2 r - (n - 1)^2) / (1 - r)   (>= 0 for n in [n_min, n_max]).
// r is clamped to [0, 0.99] (the paper's reference code; r = 1 makes n_max infinite), g to [0, 1].
template <typename F>
inline void EdgeTintToComplexIOR(const Spectrum<F> &r, const Spectrum<F> &g, Spectrum<F> *eta, Spectrum<F> *k) {
    for (int i = 0; i < 3; ++i) {
        F rr = clamp(r[i], F(0), F(0.99)), gg = clamp(g[i], F(0), F(1));
        F sr = sqrt(rr);
        F n_min = (F(1) - rr) / (F(1) + rr), n_max = (F(1) + sr) / (F(1) - sr);
        F n = mul_add(gg, n_min - n_max, n_max);
        F k2 = (sqr(n + F(1)) * rr - sqr(n - F(1))) / (F(1) - rr);
        (*eta)[i] = n;
        (*k)[i] = safe_sqrt(k2);
    }
}

} // namespace bsdfkit
