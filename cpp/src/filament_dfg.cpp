// Builder of Filament's DFG table (layout and channel definitions in bxdfs/filament_dfg.h),
// in double precision, by deterministic quasi-Monte Carlo integration: the same 2D point set
// ((k + 1/2) / n, frac((k + 1/2) / golden ratio)) (a golden-ratio Kronecker lattice) for every
// texel, so the table is a deterministic function of (size, samples) and of nothing else.
//
// x, y: visible-normal sampling of the GGX lobe (Heitz 2018, Microfacet::Sample_wm of
// core/microfacet.h). With pdf(l) = G1(v) D / (4 NoV), the per-sample weight of the F = 1 lobe
// D V <NoL> is 4 NoV NoL V / G1(v) = G2 / G1(v) in [0, 1]. The first coordinate is warped by
// u = 1 - (1 - t)^2 (weight 2 (1 - t)): the rim of the visible-normal disk, where l crosses the
// horizon, would otherwise fall inside the last stratum and bias y by up to 1e-3 for small alpha.
// (Filament's cmgen samples the NDF instead, pdf D NoH; the integrals are the same.)
// z: the Charlie sheen lobe D_Charlie V_Neubelt <NoL> (cmgen DFV_Charlie_Uniform integrand) by two
// strategies, `samples` points each, combined with the balance heuristic (Veach 1997):
//   Charlie: the NDF sampler (pdf D cos(theta_h), Filament's hemisphereImportanceSampleDCharlie)
//            conditioned on the cap NoH > NoV / 2, outside which l = reflect(v, h) is below the
//            horizon: sin(theta_h) = s_max u^(a / (2 a + 1)), s_max = sqrt(1 - NoV^2 / 4);
//   horizon: l directly, with cos(theta_l) = u^2 (pdf 1 / (4 pi sqrt(cos theta_l))), which
//            resolves the ramp NoL / (NoL + NoV - NoL NoV) of V_Neubelt <NoL> at grazing angles.
// Accuracy against Gauss-Legendre quadrature (tests/models/test_filament_dfg.py), 1024 samples: <= 1.2e-4
// for x and y, <= 2.5e-4 for z (relative where z > 1).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "bsdfkit/bxdfs/filament.h"

namespace bsdfkit {

namespace {

Point2<double> lattice(int k, int n) {
    constexpr double inv_golden = 0.6180339887498949;
    return {(k + 0.5) / n, std::fmod((k + 0.5) * inv_golden, 1.0)};
}

void dfg_texel(int size, int samples, int i, int j, double *out) {
    using namespace filament;
    const double NoV = i == 0 ? kMinNoV : double(i) / (size - 1), r = double(j) / (size - 1), a = r * r;
    if (j == 0) {  // alpha -> 0: a mirror (y = 1, x = Fc(NoV)); the sheen lobe vanishes
        out[0] = pow5(1 - NoV);
        out[1] = 1;
        out[2] = 0;
        return;
    }
    const Vec3<double> v(std::sqrt(1 - NoV * NoV), 0, NoV);
    // The raw distribution (no pbrt floors: a may be below 1e-4 here).
    Microfacet<double> ggx;
    ggx.alpha_x = ggx.alpha_y = a;
    const double G1v = ggx.G1(v);
    double x = 0, y = 0;
    for (int k = 0; k < samples; ++k) {
        Point2<double> u = lattice(k, samples);
        double om = 1 - u.x, jac = 2 * om;
        u.x = 1 - om * om;
        Vec3<double> h = ggx.Sample_wm(v, u);
        Vec3<double> l = Reflect(v, h);
        double NoL = l.z, VoH = dot(v, h);
        if (!(NoL > 0 && VoH > 0)) continue;
        double w = jac * 4 * NoV * NoL * V_SmithGGXCorrelated(a, NoV, NoL) / G1v;
        x += w * pow5(1 - VoH);  // DFV_Multiscatter: x += Gv Fc, y += Gv
        y += w;
    }
    // Charlie sheen lobe (densities in the half-vector measure; dw_l = 4 VoH dw_h)
    const int half = samples;  // points per strategy
    const double c_lo = 0.5 * NoV, s2_max = 1 - c_lo * c_lo, s_max = std::sqrt(s2_max);
    const double inv_a = 1 / a, log_c = std::log((2 + inv_a) * (0.5 * InvPi<double>));
    double z = 0;
    for (int k = 0; k < 2 * half; ++k) {
        Point2<double> u = lattice(k % half, half);
        Vec3<double> h, l;
        double phi = 2 * Pi<double> * u.y;
        if (k < half) {
            double st = s_max * std::pow(u.x, a / (2 * a + 1)), ct = std::sqrt(std::max(0.0, 1 - st * st));
            h = Vec3<double>(st * std::cos(phi), st * std::sin(phi), ct);
            l = Reflect(v, h);
        } else {
            double mu = u.x * u.x, sl = std::sqrt(std::max(0.0, 1 - mu * mu));
            l = Vec3<double>(sl * std::cos(phi), sl * std::sin(phi), mu);
            h = normalize(v + l);
        }
        double NoL = l.z, VoH = dot(v, h), NoH = h.z;
        if (!(NoL > 0 && VoH > 0 && NoH > c_lo)) continue;
        double sin2h = h.x * h.x + h.y * h.y;
        double D = std::exp(log_c + 0.5 * inv_a * std::log(sin2h));                          // D_Charlie
        double p_ch = std::exp(log_c + 0.5 * inv_a * std::log(sin2h / s2_max)) * NoH / s2_max;  // D cos / s_max^(1/a+2)
        double p_hz = 4 * VoH / (4 * Pi<double> * std::sqrt(NoL));
        z += D * V_Neubelt(NoV, NoL) * NoL * 4 * VoH / (0.5 * (p_ch + p_hz));  // f <NoL> / p(l)
    }
    out[0] = x / samples;
    out[1] = y / samples;
    out[2] = z / (2 * half);
}

} // namespace

void filament_dfg_rows(int size, int samples, int row_begin, int row_end, double *out, int nthreads) {
    const int64_t n = int64_t(row_end - row_begin) * size;
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 8)
    for (int64_t t = 0; t < n; ++t) {
        int j = row_begin + int(t / size), i = int(t % size);
        dfg_texel(size, samples, i, j, out + 3 * t);
    }
}

SharedTable<FilamentDFG> make_filament_dfg(int size, int samples, const double *values) {
    auto t = std::make_shared<FilamentDFG>();
    t->size = size;
    t->samples = samples;
    t->d64.assign(values, values + size_t(size) * size * 3);
    t->d32.resize(t->d64.size());
    for (size_t k = 0; k < t->d64.size(); ++k) t->d32[k] = float(t->d64[k]);
    return SharedTable<FilamentDFG>(std::move(t));
}

SharedTable<FilamentDFG> make_filament_dfg(int size, int samples, int nthreads) {
    std::vector<double> v(size_t(size) * size * 3);
    filament_dfg_rows(size, samples, 0, size, v.data(), nthreads);
    return make_filament_dfg(size, samples, v.data());
}

} // namespace bsdfkit
