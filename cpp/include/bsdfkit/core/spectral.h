// Spectral mode (issue 15; docs/SPECTRAL.md): parameters as functions of wavelength, evaluated
// per element at the element's 4 wavelengths (pbrt-v4 SampledWavelengths, NSpectrumSamples = 4).
// The wavelengths are an input of every spectral kernel (batch_spectral.h), never sampled inside,
// so results depend on nothing but the element's own inputs.
#pragma once
#include <cmath>
#include <cstdint>

#include "simd.h"
#include "spectrum.h"

namespace bsdfkit {

inline constexpr int kSpectralN = 4;            // wavelengths per element (pbrt-v4 NSpectrumSamples)
inline constexpr double kLambdaMin = 360.0;     // nm (pbrt-v4 Lambda_min / Lambda_max)
inline constexpr double kLambdaMax = 830.0;
inline constexpr int kDenseN = 471;             // whole nm in [360, 830] (the Table's index)

template <typename F> using Spectrum4 = Spectrum<F, kSpectralN>;

// Jakob & Hanika 2019 eq. 3: s(x) = 1/2 + x / (2 sqrt(1 + x^2)), s(+-inf) = 1, 0.
inline double SigmoidJH(double x) {
    double ax = std::abs(x);
    double r = ax > 1e150 ? 1.0 : ax / std::sqrt(1.0 + x * x); // no overflow of x^2, inf -> 1
    return 0.5 + 0.5 * std::copysign(r, x);
}

// One spectral parameter (trivially copyable; a table is owned by the binding that made it):
//   Constant  c[0] at every wavelength
//   Sigmoid   scale * s(c0 lambda^2 + c1 lambda + c2), lambda in nm (an uplifted RGB: Jakob &
//             Hanika 2019, pbrt-v4 RGBAlbedoSpectrum / RGBUnboundedSpectrum); c2 may be +-inf
//   Table     a piecewise-linear spectrum: n nodes x[0] = 360 < ... < x[n-1] = 830 nm with values
//             v (sampled and named spectra, their end values carried to 360 / 830 nm), and
//             first[k] = the segment holding 360 + k nm (k = 0..470), so a lookup is one gather
//             plus a step past the nodes inside that nm (usually none): the exact piecewise-linear
//             value, as Mitsuba's IrregularSpectrum (pbrt-v4's DenselySampledSpectrum instead
//             rounds to the nearest nm: up to 2.5e-3 relative on the Cu eta data).
// Evaluated in double: one sqrt and one division (Sigmoid) or a gather and a multiply-add with
// the segment's precomputed slope (Table) per wavelength.
struct SpectralParam {
    enum Kind : uint8_t { Constant = 0, Sigmoid = 1, Table = 2 };
    Kind kind = Constant;
    double c[3] = {0.0, 0.0, 0.0};
    double scale = 1.0;
    const double *x = nullptr, *v = nullptr, *slope = nullptr;  // slope[j] = (v[j+1]-v[j]) / (x[j+1]-x[j])
    const int32_t *first = nullptr;
    int32_t n = 0;

    double operator()(double lambda) const {
        if (kind == Constant) return c[0];
        if (kind == Sigmoid) return scale * SigmoidJH((c[0] * lambda + c[1]) * lambda + c[2]);
        double l = lambda >= kLambdaMin ? lambda : kLambdaMin;  // also maps a NaN to 360
        l = l <= kLambdaMax ? l : kLambdaMax;
        int32_t j = first[int(l - kLambdaMin)];
        while ((j + 2 < n) & (x[j + 1] < l)) ++j;               // nodes within this nm
        return slope[j] * (l - x[j]) + v[j];                   // numpy.interp's form, no division
    }

    // The parameter at an element's wavelengths, at the model's precision.
    template <typename F> Spectrum4<F> at(const double *lambda) const {
        Spectrum4<F> s;
        for (int i = 0; i < kSpectralN; ++i) s[i] = F((*this)(lambda[i]));
        return s;
    }

    // ---- Per lane: the same values for a packet D of wavelengths (Packet<double>, core/simd.h),
    // the same operations in the same order as operator() (the build does not contract a * b + c),
    // so each lane equals the scalar value bit for bit. The kind is uniform (one branch per
    // packet); a table lookup gathers per lane: the segment index first[k], then (rarely) the
    // step past nodes inside that nm while any lane needs it, then x, v and slope of the segment.
    // The index is kept in double (whole numbers) so that every mask is a mask of D.
    template <typename D> D lanes(const D &lambda) const {
        if (kind == Constant) return D(c[0]);
        if (kind == Sigmoid) return D(scale) * sigmoid_lanes((D(c[0]) * lambda + D(c[1])) * lambda + D(c[2]));
        using I = drjit::int32_array_t<D>;
        D l = select(lambda >= D(kLambdaMin), lambda, D(kLambdaMin));  // also maps a NaN to 360
        l = select(l <= D(kLambdaMax), l, D(kLambdaMax));
        D j = D(drjit::gather<I>(first, I(l - D(kLambdaMin))));
        // j + 2 < n needs no test: the last node is 830 >= l, so the step stops at j = n - 2.
        for (;;) {
            auto step = drjit::gather<D>(x, I(j) + 1) < l;
            if (drjit::none(step)) break;
            j = select(step, j + D(1), j);
        }
        I ju(j);
        return drjit::gather<D>(slope, ju) * (l - drjit::gather<D>(x, ju)) + drjit::gather<D>(v, ju);
    }
    // SigmoidJH per lane (the same operations).
    template <typename D> static D sigmoid_lanes(const D &x) {
        D ax = abs(x);
        D r = select(ax > D(1e150), D(1), ax / sqrt(D(1) + x * x));
        return D(0.5) + D(0.5) * drjit::copysign(r, x);
    }
    // The parameter at a packet's wavelengths (lam[i]: wavelength i of every lane) as channel
    // values of type C (Packet<float> or Packet<double>).
    template <typename C, typename D> Spectrum4<C> at_lanes(const D (&lam)[kSpectralN]) const {
        Spectrum4<C> s;
        for (int i = 0; i < kSpectralN; ++i) s[i] = C(lanes(lam[i]));
        return s;
    }
};

// A spectral form's declaration of one spectral parameter (core/bxdf.h `Spectral`): the Params
// field it replaces and how Python uplifts that field's RGB value: "reflectance" (in [0, 1]:
// pbrt-v4 RGBAlbedoSpectrum) or "unbounded" (RGBUnboundedSpectrum). An adapter lists them in
// `static constexpr SpectralField kFields[]`; the bindings expose them as spectral_fields.
struct SpectralField {
    const char *name;
    const char *kind;
};

// Whether a wavelength is one the kernels accept: finite and in [360, 830] nm (NaN fails both).
inline bool valid_wavelength(double l) { return (l >= kLambdaMin) & (l <= kLambdaMax); }

} // namespace bsdfkit
