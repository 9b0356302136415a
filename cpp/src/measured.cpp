// Table builders of the measured models: the MERL tabulated sampler (bxdfs/merl.h).
#include <cmath>

#include "bsdfkit/batch.h"
#include "bsdfkit/bxdfs/merl.h"

namespace bsdfkit {

namespace {

template <bool Linear>
void merl_sampler_rows(const MERLTable &t, int k, std::vector<double> &mass) {
    using namespace merl;
    MERLKernel<double, Linear> m;
    m.values = t.v64.data();
    const int R = kThetaH, C = t.n_phi;
    double theta_o = (k + 0.5) / t.K * (0.5 * M_PI);
    Vec3<double> wo(std::sin(theta_o), 0.0, std::cos(theta_o));
    double dphi = 2 * M_PI / C;
    for (int r = 0; r < R; ++r) {
        double cos0 = std::cos(MERLKernel<double, Linear>::row_theta(r)),
               cos1 = std::cos(MERLKernel<double, Linear>::row_theta(r + 1));
        double omega = (cos0 - cos1) * dphi;  // solid angle of the cell
        for (int c = 0; c < C; ++c) {
            double acc = 0;
            for (int j = 0; j < 2; ++j)
                for (int i = 0; i < 2; ++i) {
                    double ch = cos0 + (cos1 - cos0) * (j + 0.5) * 0.5;
                    double sh = std::sqrt(std::max(0.0, 1 - ch * ch));
                    double ph = (c + (i + 0.5) * 0.5) * dphi;
                    Vec3<double> h(sh * std::cos(ph), sh * std::sin(ph), ch);
                    Vec3<double> wi = Reflect(wo, h);
                    if (!(wi.z > 0)) continue;
                    Spectrum<double> f = m.f(wo, wi, TransportMode::Radiance);
                    double lum = 0;
                    for (int q = 0; q < 3; ++q) lum += kLum[q] * std::max(f[q], 0.0);
                    acc += lum * wi.z * 4 * dot(wo, h);  // pdf_h proportional to lum(f) cos_i |dwi/dh|
                }
            mass[size_t(r) * C + c] = 0.25 * acc * omega;
        }
    }
}

} // namespace

std::shared_ptr<const MERLTable> make_merl_table(std::vector<double> values, int K, int n_phi, bool linear,
                                                 int nthreads) {
    using namespace merl;
    auto t = std::make_shared<MERLTable>();
    t->v64 = std::move(values);
    t->v32.assign(t->v64.begin(), t->v64.end());
    t->K = K;
    t->n_phi = n_phi;
    const int R = kThetaH, C = n_phi;
    t->marg64.assign(size_t(K) * R, 0.0);
    t->cond64.assign(size_t(K) * R * C, 0.0);
    t->dens64.assign(size_t(K) * R * C, 0.0);
    const bool done = parallel_chunks(K, nthreads, 1, [&](int64_t k, int64_t) {
        std::vector<double> mass(size_t(R) * C);
        if (linear) merl_sampler_rows<true>(*t, int(k), mass);
        else merl_sampler_rows<false>(*t, int(k), mass);
        double total = 0;
        for (double v : mass) total += v;
        double dphi = 2 * M_PI / C;
        if (!(total > 0)) {  // nothing measured at this incidence: uniform in solid angle
            for (int r = 0; r < R; ++r) {
                double omega = (std::cos(MERLKernel<double, false>::row_theta(r)) -
                                std::cos(MERLKernel<double, false>::row_theta(r + 1))) * dphi;
                for (int c = 0; c < C; ++c) mass[size_t(r) * C + c] = omega;
            }
            total = 0;
            for (double v : mass) total += v;
        }
        double acc_r = 0;
        for (int r = 0; r < R; ++r) {
            double omega = (std::cos(MERLKernel<double, false>::row_theta(r)) -
                            std::cos(MERLKernel<double, false>::row_theta(r + 1))) * dphi;
            double row = 0;
            for (int c = 0; c < C; ++c) row += mass[size_t(r) * C + c];
            double acc_c = 0;
            for (int c = 0; c < C; ++c) {
                size_t i = (size_t(k) * R + r) * C + c;
                acc_c += mass[size_t(r) * C + c];
                t->cond64[i] = row > 0 ? acc_c / row : double(c + 1) / C;
                t->dens64[i] = mass[size_t(r) * C + c] / total / omega;
            }
            t->cond64[(size_t(k) * R + r) * C + C - 1] = 1.0;
            acc_r += row;
            t->marg64[size_t(k) * R + r] = acc_r / total;
        }
        t->marg64[size_t(k) * R + R - 1] = 1.0;
    });
    if (!done) return nullptr;  // stopped by Ctrl-C: the rows are incomplete, no table
    t->marg32.assign(t->marg64.begin(), t->marg64.end());
    t->cond32.assign(t->cond64.begin(), t->cond64.end());
    t->dens32.assign(t->dens64.begin(), t->dens64.end());
    return t;
}

} // namespace bsdfkit
