// Spectral mode of the preview renderer (issue 15): hero-wavelength paths as pbrt-v4's
// PathIntegrator with SampledWavelengths (Pharr, Jakob, Humphreys, "Physically Based Rendering"
// 4th ed., sec. 4.6.5 and 13.4): each path carries 4 wavelengths, sampled together by the
// visible-wavelength importance density; the materials are the spectral adapters of
// batch_spectral.h (the models' own per-element code with 4 channels), the lights are the RGB
// lighting uplifted to illuminant spectra (pbrt-v4 RGBIlluminantSpectrum: s(lambda) =
// scale * sigmoid(poly(lambda)) * D65(lambda), D65 of unit luminance), and a refraction through
// a dispersive dielectric terminates the secondary wavelengths (pbrt-v4 TerminateSecondary).
// The estimate of a path is converted to linear sRGB as bk.spectrum_to_rgb does:
//   rgb = M_XYZ->sRGB (1/4) sum_i cmf(lambda_i) L_i / pdf_i / integral(y-bar), 0 where pdf_i = 0.
// The tables (the D65 5 nm table, the CMFs' 1 nm table already multiplied by the matrix and
// divided by the y-bar integral, the sigmoid coefficients) come from bsdfkit.spectral.
#pragma once
#include <cmath>
#include <variant>
#include <vector>

#include "render.h"
#include "spectral_material.h"

namespace bsdfkit::render {

// A table on a uniform wavelength grid x0 + k step (k < n), ncol columns, linear between nodes
// and 0 outside (colorimetry._lerp_table).
struct UniformTable {
    double x0 = 360.0, step = 1.0;
    int n = 0, ncol = 1;
    std::vector<double> v;  // n rows of ncol

    void at(double lambda, double *out) const {
        double t = (lambda - x0) / step;
        bool inside = (lambda >= x0) & (lambda <= x0 + step * double(n - 1));
        int i0 = int(t);
        i0 = i0 < 0 ? 0 : (i0 > n - 2 ? n - 2 : i0);
        double a = t - double(i0);
        for (int c = 0; c < ncol; ++c) {
            double y = (1.0 - a) * v[size_t(i0 * ncol + c)] + a * v[size_t((i0 + 1) * ncol + c)];
            out[c] = inside ? y : 0.0;
        }
    }
};

// Sigmoid coefficients (c0, c1, c2 in nm units) and scale of one uplifted RGB (Jakob & Hanika 2019
// eq. 3 times the scale); its value without the illuminant.
struct Uplifted {
    double c0 = 0, c1 = 0, c2 = -INFINITY, scale = 0;
    double operator()(double lambda) const { return scale * SigmoidJH((c0 * lambda + c1) * lambda + c2); }
};

struct SpectralScene {
    std::vector<SpectralMaterial> materials;  // one per scene material
    UniformTable d65;                          // D65 of unit luminance (1 column)
    UniformTable rgb_match;                    // M cmf / integral(y-bar) (3 columns)
    Uplifted constant_env, sun;                // uplifted constant environment and sun irradiance
    int width = 0, height = 0;                 // lat-long environment (width 0: constant)
    std::vector<Uplifted> texels;              // height rows of width + 1 (column width repeats 0)

    // pbrt-v4 SampleVisibleWavelengths / VisibleWavelengthsPDF (Radziszewski et al. 2009), the 4
    // wavelengths at u + i/4 wrapped (bk.sample_wavelengths(method="visible"), bit for bit in double).
    static void sample_wavelengths(double u, double *lam, double *pdf) {
        for (int i = 0; i < kSpectralN; ++i) {
            double up = u + double(i) / double(kSpectralN);
            up = up > 1.0 ? up - 1.0 : up;
            double l = 538.0 - 138.888889 * std::atanh(0.85691062 - 1.82750197 * up);
            l = l < kLambdaMin ? kLambdaMin : (l > kLambdaMax ? kLambdaMax : l);
            double ch = std::cosh(0.0072 * (l - 538.0));
            lam[i] = l;
            pdf[i] = 0.0039398042 / (ch * ch);
        }
    }

    // An uplifted illuminant at the path's wavelengths (times D65).
    Spec4 illuminant(const Uplifted &s, const double *lam) const {
        Spec4 r;
        for (int i = 0; i < kSpectralN; ++i) {
            double d;
            d65.at(lam[i], &d);
            r[i] = Float(s(lam[i]) * d);
        }
        return r;
    }

    // Environment radiance at lat-long (u, v): the bilinear interpolant of the texels' spectra
    // (the same weights as Environment::lookup on their RGB values, so its colour is the RGB
    // render's interpolant up to the uplift's round trip).
    Spec4 env_uv(float u, float v, const double *lam) const {
        if (width == 0) return illuminant(constant_env, lam);
        float px = u * float(width) - 0.5f, py = v * float(height) - 0.5f;
        float fx0 = std::floor(px), fy0 = std::floor(py);
        float tx = px - fx0, ty = py - fy0;
        int x0 = int(fx0), y0 = int(fy0);
        x0 = x0 < 0 ? width - 1 : (x0 >= width ? width - 1 : x0);
        int ya = clamp(y0, 0, height - 1), yb = clamp(y0 + 1, 0, height - 1);
        const Uplifted *ra = &texels[size_t(ya) * size_t(width + 1) + size_t(x0)];
        const Uplifted *rb = &texels[size_t(yb) * size_t(width + 1) + size_t(x0)];
        double w00 = double((1.f - tx) * (1.f - ty)), w01 = double(tx * (1.f - ty)), w10 = double((1.f - tx) * ty),
               w11 = double(tx * ty);
        Spec4 r;
        for (int i = 0; i < kSpectralN; ++i) {
            double l = lam[i], d;
            d65.at(l, &d);
            double s = w00 * ra[0](l) + w01 * ra[1](l) + w10 * rb[0](l) + w11 * rb[1](l);
            r[i] = Float(s * d);
        }
        return r;
    }

    // Linear sRGB of one path's estimate (see the header comment).
    void to_rgb(const Spec4 &L, const double *lam, const double *pdf, double *rgb) const {
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        for (int i = 0; i < kSpectralN; ++i) {
            if (!(pdf[i] > 0.0)) continue;
            double w[3];
            rgb_match.at(lam[i], w);
            double li = double(L[i]) / pdf[i];
            for (int c = 0; c < 3; ++c) rgb[c] += w[c] * li;
        }
        for (int c = 0; c < 3; ++c) rgb[c] /= double(kSpectralN);
    }
};

// Adds samples [s0, s1) of every pixel to acc (linear sRGB), as render_samples (render.h) with
// the same determinism: each sample's random numbers (its wavelengths included) depend only on
// (seed, pixel, sample index), each pixel sums its samples in index order.
bool render_samples_spectral(const Scene &scene, const SpectralScene &spec, const Camera &camera,
                             const RenderSettings &settings, int s0, int s1, double *acc, RenderStats *stats,
                             const std::function<bool()> &should_stop);

} // namespace bsdfkit::render
