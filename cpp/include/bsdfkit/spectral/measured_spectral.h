// Spectral mode of the measured models (issue 15): RGL tensor files (Measured) evaluated from
// the file's spectra, and MERL tables (RGB data) through a per-bin uplift.
//
// MeasuredSpectral (pbrt-v4 MeasuredBxDF, Mitsuba 3 `measured`, both spectral): the file's
// `spectra` tensor [n_phi, n_theta, n_lambda, N, N] is a warp conditioned on (phi_o, theta_o)
// with one channel per tabulated wavelength (core/warp2d.h); f cos(theta_i) at a wavelength is
// the bilinear value at the VNDF inverse of wm, linear between the two tabulated wavelengths
// around it (the multilinear interpolation in (phi_o, theta_o, lambda) of Mitsuba's
// Marginal2D<3> / pbrt-v4's PiecewiseLinear2D<3>), clamped to >= 0 as pbrt-v4 does, times
// ndf / (4 sigma). Wavelengths outside the file's range take the end value (the interpolation
// weight clamped to [0, 1], as both renderers do). The prelude (flip, fold, coordinates, one VNDF
// inverse), pdf and sampling are the RGB model's (MeasuredKernel::lookup, pdf_of, sample_wi): the
// luminance warp does not depend on the wavelength, so pdf is one value per element.
//
// MERLSpectral (Nearest / Linear): MERL data are RGB. Every bin's RGB value (channel scales
// applied) is uplifted once, at construction, to pbrt-v4's RGBUnboundedSpectrum: scale 2 max(rgb)
// times the Jakob & Hanika 2019 sigmoid s(c0 lambda^2 + c1 lambda + c2) of rgb / scale (the
// sRGB coefficient table, bsdfkit.spectral.uplift), stored as 4 float32 per bin (c0, c1, c2,
// scale; 23.3 MB for the 1,458,000 bins). f(lambda) at a direction pair is the uplifted spectrum
// of the bin the RGB model reads there (nearest), or the trilinear interpolation of the 8
// bins' spectra at lambda (linear: the same weights as the RGB model's interpolation of their RGB
// values). pdf and sampling are the RGB model's (luminance-based, wavelength-independent).
#pragma once
#include <array>
#include <memory>
#include <stdexcept>
#include <vector>

#include "../batch_spectral.h"
#include "../bxdfs/measured.h"
#include "../bxdfs/merl.h"

namespace bsdfkit {

// ---------------------------------------------------------------- RGL tensor files

// The spectral part of a file: the spectra warp and the tabulated wavelengths (nm).
struct MeasuredSpectraTable {
    Warp2DData spectra;                 // channels = n_lambda, conditioned on (phi_i, theta_i)
    std::vector<double> wavelengths;    // increasing
};

template <typename F> struct MeasuredSpectral {
    MeasuredKernel<F> kern;             // ndf, sigma, vndf, luminance (its rgb warp is not read)
    Warp2D<F, 2> spectra;
    const double *wl = nullptr;         // the file's wavelengths
    int n_wl = 1;
    static constexpr std::array<SpectralField, 0> kFields{};  // the spectra come from the file
    // a.template table<MeasuredSpectraTable>("spectra"): the file's spectra (the caller keeps the
    // tables alive: kern and spectra point into them)
    template <class A> static MeasuredSpectral make(const MeasuredParams &p, const A &a) {
        const MeasuredSpectraTable &t = a.template table<MeasuredSpectraTable>("spectra");
        if (!p.table) throw std::invalid_argument("table: must not be empty");
        if (p.table->vndf.param_size != t.spectra.param_size)
            throw std::invalid_argument("spectra: its (phi_i, theta_i) grid differs from the table's");
        MeasuredSpectral s;
        s.kern = MeasuredBxDF<F>::make(p);
        s.spectra = Warp2D<F, 2>(t.spectra);
        s.wl = t.wavelengths.data();
        s.n_wl = int(t.wavelengths.size());
        return s;
    }

    bool dispersive() const { return false; }

    // The tabulated wavelength interval holding lambda and the weight of its upper end (clamped
    // to [0, 1]: the end values outside the file's range).
    void bracket(double lambda, int *j, F *t) const {
        int i = count_leading(n_wl - 2, [&](int k) { return wl[k + 1] < lambda; });
        int i1 = n_wl > 1 ? i + 1 : i;
        double w = n_wl > 1 ? (lambda - wl[i]) / (wl[i1] - wl[i]) : 0.0;
        *j = i;
        *t = F(w < 0.0 ? 0.0 : (w > 1.0 ? 1.0 : w));
    }

    // f cos(theta_i) at the 4 wavelengths (before the cosine quotient of f_of).
    Spectrum4<F> f_cos(const typename MeasuredKernel<F>::Lookup &l, const double *lam) const {
        auto w = spectra.weights(l.c.params);  // one parameter search for every wavelength
        F scale = kern.jacobian_scale(l.c);
        Spectrum4<F> v;
        for (int i = 0; i < kSpectralN; ++i) {
            int j;
            F t;
            bracket(lam[i], &j, &t);
            F a = spectra.eval(l.s, w, j), b = n_wl > 1 ? spectra.eval(l.s, w, j + 1) : a;
            v[i] = max_(lerp(t, a, b), F(0)) * scale;  // negative samples -> 0 (pbrt-v4)
        }
        return v;
    }

    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode) const {
        auto l = kern.lookup(wo, wi);
        Spectrum4<F> v = finite_or_zero(kern.f_of(f_cos(l, lam), l));
        return select(wo.z != F(0), v, Spectrum4<F>(F(0)));
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(kern, wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F, Point2<F> u, const double *lam, TransportMode, uint8_t sf,
                            bool *terminated) const {
        *terminated = false;
        BSDFSample<F, 4> r;
        bool ok;
        r.wi = kern.sample_wi(wo, clamp_uniform(u), &ok);
        auto l = kern.lookup(wo, r.wi);  // eval's own path (sample agrees with eval / pdf bit for bit)
        r.f = kern.f_of(f_cos(l, lam), l);
        r.pdf = kern.pdf_of(l);
        r.flags = uint8_t(GlossyReflection);
        r.valid = ok;
        return accepted_sample(r, wo, (sf & RT_Reflection) != 0);
    }
};

// ---------------------------------------------------------------- MERL

// The uplift of every bin: c0, c1, c2, scale (float32), [bin][4].
struct MERLSpectralTable {
    std::vector<float> coef;
};

// RGBUnboundedSpectrum of one bin at lambda (nm): scale s(c0 lambda^2 + c1 lambda + c2), in
// double as core/spectral.h's SpectralParam evaluates an uplifted parameter.
inline double merl_uplift(const float *c, double lambda) {
    return double(c[3]) * SigmoidJH((double(c[0]) * lambda + double(c[1])) * lambda + double(c[2]));
}

template <typename F, bool Linear> struct MERLSpectralT {
    MERLKernel<F, Linear> kern;         // pdf and sampling (the RGB model's)
    const float *coef = nullptr;
    static constexpr std::array<SpectralField, 0> kFields{};  // every bin uplifted: a.table("coefficients")
    template <class A> static MERLSpectralT make(const MERLParams &p, const A &a) {
        if (!p.table) throw std::invalid_argument("table: must not be empty");
        MERLSpectralT s;
        s.kern = MERLT<F, Linear>::make(p);
        s.coef = a.template table<MERLSpectralTable>("coefficients").coef.data();
        return s;
    }

    bool dispersive() const { return false; }

    Spectrum4<F> f(const Vec3<F> &wo, const Vec3<F> &wi, const double *lam, TransportMode) const {
        Spectrum4<F> v = kern.template f_with<4>(wo, wi, [&](int64_t bin) {
            const float *c = coef + 4 * bin;
            Spectrum4<F> s;
            for (int i = 0; i < kSpectralN; ++i) s[i] = F(merl_uplift(c, lam[i]));
            return s;
        });
        v = finite_or_zero(v);
        return select(wo.z != F(0), v, Spectrum4<F>(F(0)));
    }
    F pdf(const Vec3<F> &wo, const Vec3<F> &wi, const double *, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(kern, wo, wi, mode, sf);
    }
    BSDFSample<F, 4> sample(const Vec3<F> &wo, F uc, Point2<F> u, const double *lam, TransportMode mode, uint8_t sf,
                            bool *terminated) const {
        *terminated = false;
        BSDFSample<F> s = kern.sample_f(wo, clamp_uniform(uc), clamp_uniform(u), mode, sf);
        Spectrum4<F> f = s.valid ? this->f(wo, s.wi, lam, mode) : Spectrum4<F>(F(0));
        return accepted_sample(with_spectrum(s, f), wo, (kern.flags() & sf) != 0);
    }
};
template <typename F> using MERLNearestSpectral = MERLSpectralT<F, false>;
template <typename F> using MERLLinearSpectral = MERLSpectralT<F, true>;

} // namespace bsdfkit
