// A bilinear (piecewise-linear) 2-D density on a regular grid over [0,1]^2, optionally
// conditioned on two extra parameters (multilinear interpolation between parameter slices), with
// evaluation, sampling and the exact inverse of the sampling map. This is the "continuous
// marginal" warp of Dupuy & Jakob 2018 (Mitsuba 3 Marginal2D<Float, Dim, Continuous=true>,
// pbrt-v4 PiecewiseLinear2D): the row is sampled from the marginal of the bilinear interpolant
// (a linear density between rows: sample_segment), then the column from the conditional at that
// fractional row. Grid: W columns (x, the fastest index) by H rows (y), node i at i / (W - 1).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

#include "math.h"

namespace bsdfkit {

// Element k of a table, read through its bits (an integer load cannot alias the float outputs of
// the batch kernels, so the vectorizer may gather; as DFGRow::at).
template <typename F> inline F table_at(const F *p, int64_t k) {
    using U = std::conditional_t<std::is_same_v<F, float>, uint32_t, uint64_t>;
    return __builtin_bit_cast(F, reinterpret_cast<const U *>(p)[k]);
}

// Number of leading indices in [0, n) for which the monotone predicate holds (n if all):
// branch-free bisection, floor(log2 n) + 1 iterations (the count depends on n only, which is
// uniform per table, never on the data).
template <typename Pred> inline int count_leading(int n, const Pred &pred) {
    int i = 0, top = 1;
    while (top * 2 <= n) top *= 2;
    for (int s = top; s > 0; s >>= 1) {
        int j = i + s;
        bool in = j <= n;
        int jj = in ? j : n;
        i = (in & pred(jj > 0 ? jj - 1 : 0)) ? j : i;
    }
    return i;
}

// The data of one warp, in float64 and float32 (the kernels read one of them).
struct Warp2DData {
    int W = 0, H = 0;          // columns (x) and rows (y) of one slice
    int channels = 1;          // extra innermost slice dimension read by eval(…, channel) (RGB tables)
    int n_params = 0;          // 0 or 2 conditioning parameters (phi_i, theta_i)
    std::array<int, 2> param_size{1, 1};
    std::array<int64_t, 2> param_stride{0, 0};  // in slices (0 for a parameter with one value)
    std::vector<double> params64[2];
    std::vector<float> params32[2];
    std::vector<double> data64, marg64, cond64;  // data [slice][channel][H][W]; marg [slice][H-1]; cond [slice][H][W-1]
    std::vector<float> data32, marg32, cond32;
    bool sampling = false;

    // Builds from raw values: slices = prod(param_size), each channels x H x W. With `normalize`
    // every slice is scaled to integrate to 1 over [0,1]^2 and the CDFs are built (in double).
    // A slice with a zero or non-finite integral is reported by returning its index (else -1).
    int64_t build(const double *values, int W_, int H_, int channels_, std::array<int, 2> psize,
                  const std::vector<double> pvals[2], int n_params_, bool normalize) {
        W = W_, H = H_, channels = channels_, n_params = n_params_, sampling = normalize;
        int64_t slices = 1;
        for (int d = n_params - 1; d >= 0; --d) {
            param_size[d] = psize[d];
            param_stride[d] = psize[d] > 1 ? slices : 0;
            slices *= psize[d];
            params64[d] = pvals[d];
            params32[d].assign(pvals[d].begin(), pvals[d].end());
        }
        int64_t n = int64_t(W) * H * channels;
        data64.assign(values, values + slices * n);
        int64_t bad = -1;
        if (normalize) {
            marg64.assign(size_t(slices * (H - 1)), 0.0);
            cond64.assign(size_t(slices * H * (W - 1)), 0.0);
            double sx = 0.5 / (W - 1), sy = 0.5 / (H - 1);
            std::vector<double> row_sum(static_cast<size_t>(H));
            for (int64_t s = 0; s < slices; ++s) {
                double *d = data64.data() + s * n, *cond = cond64.data() + s * H * (W - 1),
                       *marg = marg64.data() + s * (H - 1);
                for (int y = 0; y < H; ++y) {  // conditional CDFs of every row (trapezoids)
                    double acc = 0;
                    for (int x = 0; x < W - 1; ++x) {
                        acc += sx * (d[y * W + x] + d[y * W + x + 1]);
                        cond[y * (W - 1) + x] = acc;
                    }
                    row_sum[size_t(y)] = acc;
                }
                double acc = 0;
                for (int y = 0; y < H - 1; ++y) {  // marginal CDF
                    acc += sy * (row_sum[size_t(y)] + row_sum[size_t(y) + 1]);
                    marg[y] = acc;
                }
                if (!(acc > 0) || !std::isfinite(acc)) {
                    if (bad < 0) bad = s;
                    continue;
                }
                double norm = 1.0 / acc;
                for (int64_t i = 0; i < H * (W - 1); ++i) cond[i] *= norm;
                for (int i = 0; i < H - 1; ++i) marg[i] *= norm;
                for (int64_t i = 0; i < n; ++i) d[i] *= norm;
            }
        }
        data32.assign(data64.begin(), data64.end());
        marg32.assign(marg64.begin(), marg64.end());
        cond32.assign(cond64.begin(), cond64.end());
        return bad;
    }
};

// Per-element view of a Warp2DData (trivially copyable: pointers and sizes).
template <typename F, int Dim> struct Warp2D {
    const F *data = nullptr, *marg = nullptr, *cond = nullptr;
    const F *pv[2] = {nullptr, nullptr};
    int psize[2] = {1, 1};
    int64_t pstride[2] = {0, 0};
    int W = 2, H = 2, channels = 1;
    F patch_x = 1, patch_y = 1, inv_patch_x = 1, inv_patch_y = 1;

    Warp2D() = default;
    explicit Warp2D(const Warp2DData &d) {
        if constexpr (std::is_same_v<F, float>) {
            data = d.data32.data(), marg = d.marg32.data(), cond = d.cond32.data();
            for (int i = 0; i < Dim; ++i) pv[i] = d.params32[i].data();
        } else {
            data = d.data64.data(), marg = d.marg64.data(), cond = d.cond64.data();
            for (int i = 0; i < Dim; ++i) pv[i] = d.params64[i].data();
        }
        for (int i = 0; i < Dim; ++i) psize[i] = d.param_size[i], pstride[i] = d.param_stride[i];
        W = d.W, H = d.H, channels = d.channels;
        patch_x = F(1.0 / (W - 1)), patch_y = F(1.0 / (H - 1));
        inv_patch_x = F(W - 1), inv_patch_y = F(H - 1);
    }

    // Slice offset and interpolation weights of the parameters (Mitsuba interpolate_weights):
    // the interval [p_k, p_k+1] holding the value (clamped), weight clamped to [0, 1].
    struct Params {
        int64_t slice = 0;
        F w[2][2];
    };
    Params weights(const F *param) const {
        Params p;
        for (int d = 0; d < Dim; ++d) {
            const F *v = pv[d];
            int n = psize[d];
            F x = param[d];
            int idx = count_leading(n - 2, [&](int i) { return table_at(v, i + 1) < x; });
            F p0 = table_at(v, idx), p1 = table_at(v, n > 1 ? idx + 1 : idx);
            F t = n > 1 ? clamp((x - p0) / (p1 - p0), F(0), F(1)) : F(0);
            p.w[d][0] = F(1) - t;
            p.w[d][1] = t;
            p.slice += int64_t(idx) * pstride[d];
        }
        return p;
    }

    // Value at element index i of a per-slice table (slice_len elements per slice), interpolated
    // over the parameter corners.
    F lookup(const F *tab, int64_t slice_len, const Params &p, int64_t i) const {
        if constexpr (Dim == 0) {
            return table_at(tab, i);
        } else {
            int64_t base = p.slice * slice_len + i;
            int64_t s0 = pstride[0] * slice_len, s1 = pstride[1] * slice_len;
            F a = table_at(tab, base) * p.w[1][0] + table_at(tab, base + s1) * p.w[1][1];
            F b = table_at(tab, base + s0) * p.w[1][0] + table_at(tab, base + s0 + s1) * p.w[1][1];
            return a * p.w[0][0] + b * p.w[0][1];
        }
    }
    int64_t n_data() const { return int64_t(W) * H * channels; }
    int64_t n_marg() const { return H - 1; }
    int64_t n_cond() const { return int64_t(H) * (W - 1); }
    F D(const Params &p, int64_t i) const { return lookup(data, n_data(), p, i); }
    F M(const Params &p, int64_t i) const { return lookup(marg, n_marg(), p, i); }
    F C(const Params &p, int64_t i) const { return lookup(cond, n_cond(), p, i); }

    // Bilinear value at pos in [0,1]^2 (channel c of the slice).
    F eval(Point2<F> pos, const F *param, int c = 0) const { return eval(pos, weights(param), c); }
    // The same with the parameter weights already computed (several channels at one point).
    F eval(Point2<F> pos, const Params &p, int c) const {
        F x = clamp(pos.x, F(0), F(1)) * inv_patch_x, y = clamp(pos.y, F(0), F(1)) * inv_patch_y;
        int ix = min_(int(x), W - 2), iy = min_(int(y), H - 2);
        x -= F(ix), y -= F(iy);
        int64_t i = int64_t(c) * W * H + int64_t(iy) * W + ix;
        F v00 = D(p, i), v10 = D(p, i + 1), v01 = D(p, i + W), v11 = D(p, i + W + 1);
        return lerp(y, lerp(x, v00, v10), lerp(x, v01, v11));
    }

    // Inverse CDF of the linear density v0 -> v1 over one cell of width 1/inv_width, at mass s.
    static F sample_segment(F s, F inv_width, F v0, F v1) {
        bool non_const = std::abs(v0 - v1) > F(1e-4) * (v0 + v1);
        F divisor = non_const ? v0 - v1 : v0 + v1;
        s = s * (F(2) * inv_width);
        s = non_const ? v0 - safe_sqrt(v0 * v0 + s * (v1 - v0)) : s;
        return divisor != F(0) ? s / (divisor != F(0) ? divisor : F(1)) : s;
    }
    // Its inverse: the mass of [0, s] of the cell.
    static F invert_segment(F s, F width, F v0, F v1) { return s * lerp(F(0.5) * s, v0, v1) * width; }

    // Sample: (point in [0,1]^2, density there). Requires a normalized (sampling) warp.
    std::pair<Point2<F>, F> sample(Point2<F> u, const F *param) const {
        Params p = weights(param);
        const F eps = std::numeric_limits<F>::epsilon() * F(0.5);
        u.x = clamp(u.x, eps, F(1) - eps);
        u.y = clamp(u.y, eps, F(1) - eps);
        // row from the marginal CDF
        int row = count_leading(H - 2, [&](int i) { return M(p, i) < u.y; });
        u.y -= row > 0 ? M(p, row > 0 ? row - 1 : 0) : F(0);
        int64_t oc = int64_t(row) * (W - 1);
        F r0 = C(p, oc + W - 2), r1 = C(p, oc + 2 * (W - 1) - 1);
        u.y = sample_segment(u.y, inv_patch_y, r0, r1);
        u.x *= lerp(u.y, r0, r1);
        // column from the conditional CDF at the fractional row
        auto cc = [&](int i) { return lerp(u.y, C(p, oc + i), C(p, oc + (W - 1) + i)); };
        int col = count_leading(W - 1, [&](int i) { return cc(i) < u.x; });
        col = min_(col, W - 2);
        u.x -= col > 0 ? cc(col > 0 ? col - 1 : 0) : F(0);
        int64_t od = int64_t(row) * W + col;
        F v00 = D(p, od), v10 = D(p, od + 1), v01 = D(p, od + W), v11 = D(p, od + W + 1);
        F c0 = lerp(u.y, v00, v01), c1 = lerp(u.y, v10, v11);
        u.x = sample_segment(u.x, inv_patch_x, c0, c1);
        return {Point2<F>{(F(col) + u.x) * patch_x, (F(row) + u.y) * patch_y}, lerp(u.x, c0, c1)};
    }

    // Exact inverse of sample: (uniform point, density at pos).
    std::pair<Point2<F>, F> invert(Point2<F> pos, const F *param) const {
        Params p = weights(param);
        F x = clamp(pos.x, F(0), F(1)) * inv_patch_x, y = clamp(pos.y, F(0), F(1)) * inv_patch_y;
        int ix = min_(int(x), W - 2), iy = min_(int(y), H - 2);
        x -= F(ix), y -= F(iy);
        int64_t od = int64_t(iy) * W + ix;
        F v00 = D(p, od), v10 = D(p, od + 1), v01 = D(p, od + W), v11 = D(p, od + W + 1);
        F c0 = lerp(y, v00, v01), c1 = lerp(y, v10, v11);
        F pdf = lerp(x, c0, c1);
        x = invert_segment(x, patch_x, c0, c1);
        int64_t oc = int64_t(iy) * (W - 1);
        auto cc = [&](int i) { return lerp(y, C(p, oc + i), C(p, oc + (W - 1) + i)); };
        x += ix > 0 ? cc(ix > 0 ? ix - 1 : 0) : F(0);
        F r0 = C(p, oc + W - 2), r1 = C(p, oc + 2 * (W - 1) - 1);
        F rs = lerp(y, r0, r1);
        x = rs != F(0) ? x / (rs != F(0) ? rs : F(1)) : x;
        y = invert_segment(y, patch_y, r0, r1);
        y += iy > 0 ? M(p, iy > 0 ? iy - 1 : 0) : F(0);
        return {Point2<F>{x, y}, pdf};
    }
};

} // namespace bsdfkit
