// Distant lighting: a latitude-longitude environment map (or a constant radiance) with
// luminance importance sampling, and an optional directional light.
//
// World space is y-up. Direction <-> lat-long (u, v) in [0,1)^2, image row 0 at the top:
//   theta = pi v (from +y), phi = 2 pi u,  d = (sin phi sin theta, cos theta, -cos phi sin theta)
// which is the mapping documented for Mitsuba 3's `envmap` plugin (u = 0.5 looks along +z,
// u = 0 and 1 along -z, u = 0.25 along +x), so the same image lights both renderers alike.
// Radiance is the bilinear interpolant of the pixel values placed at the pixel centres
// ((x + 0.5) / W, (y + 0.5) / H), periodic in u and clamped in v.
//
// The lookups come in two forms with the same arithmetic, operation for operation: scalar
// (Float) and packet (V = Packet<Float>, the integrator's environment passes), so a packet lane
// returns the scalar function's bits.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "distribution.h"
#include "fast_math.h"
#include "material.h"

namespace bsdfkit::render {

// Rec. 709 / sRGB luminance weights.
inline Float luminance(const RGB &c) { return Float(0.2126) * c[0] + Float(0.7152) * c[1] + Float(0.0722) * c[2]; }

template <typename V> inline Vec3<V> latlong_direction(V u, V v, V *sin_theta) {
    V st, ct, sp, cp;
    sincos_(V(Pi<Float>) * v, &st, &ct);
    sincos_(V(Float(2) * Pi<Float>) * u, &sp, &cp);
    st = max_(st, V(0));
    *sin_theta = st;
    return Vec3<V>(sp * st, ct, -cp * st);
}
template <typename V> inline void latlong_uv(V dx, V dy, V dz, V *u, V *v) {
    V uu = fast_atan2(dx, -dz) * V(Inv2Pi<Float>);
    uu = select(uu < V(0), uu + V(1), uu);
    *u = select(uu >= V(1), V(0), uu);
    // theta = acos(y), as atan2(sin, cos): accurate near the poles too
    V v0 = fast_atan2(sqrt(dx * dx + dz * dz), dy) * V(InvPi<Float>);
    *v = select(v0 < V(1), v0, V(0x1.fffffep-1f));
}
inline void latlong_uv(const Vec3f &d, Float *u, Float *v) { latlong_uv(d.x, d.y, d.z, u, v); }

struct Environment {
    bool constant = true;
    RGB constant_L{Float(1)};
    int width = 0, height = 0;
    // height rows of (width + 1) texels of 4 floats: the pixel's linear RGB, then the probability
    // of pixel cell (x, y) under `cells` (column width repeats column 0). The probability of a
    // sampled cell is read from a texel the bilinear lookup loads anyway, and a 16-byte texel
    // never straddles a cache line.
    std::vector<Float> texels;
    AliasTable cells;        // sampling weights of the width * height pixel cells, row-major

    static Environment uniform(const RGB &L) {
        Environment e;
        e.constant = true;
        e.constant_L = L;
        return e;
    }

    // data: height x width x 3 linear radiance, finite and >= 0 (the caller validates).
    static Environment latlong(const Float *data, int w, int h) {
        Environment e;
        e.constant = false;
        e.width = w;
        e.height = h;
        e.texels.assign(size_t(w + 1) * h * 4, Float(0));
        for (int y = 0; y < h; ++y)
            for (int x = 0; x <= w; ++x)
                for (int c = 0; c < 3; ++c)
                    e.texels[(size_t(y) * (w + 1) + x) * 4 + c] = data[(size_t(y) * w + (x % w)) * 3 + c];
        // Sampling weight of a pixel cell: the exact mean of the bilinear interpolant's luminance
        // over the cell (separable weights 1/8, 3/4, 1/8), times sin(theta) at the cell centre for
        // the lat-long area distortion. Positive wherever the radiance is.
        std::vector<Float> lum(size_t(w) * h), f(size_t(w) * h);
        for (int i = 0; i < w * h; ++i) lum[size_t(i)] = luminance(e.pixel(i % w, i / w));
        const Float wt[3] = {Float(0.125), Float(0.75), Float(0.125)};
        for (int y = 0; y < h; ++y) {
            Float st = std::sin(Pi<Float> * (Float(y) + Float(0.5)) / Float(h));
            for (int x = 0; x < w; ++x) {
                Float s = 0;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        int yy = std::clamp(y + dy, 0, h - 1), xx = ((x + dx) % w + w) % w;
                        s += wt[dy + 1] * wt[dx + 1] * lum[size_t(yy) * w + xx];
                    }
                f[size_t(y) * w + x] = s * st;
            }
        }
        e.cells = AliasTable(f.data(), f.size());
        for (int y = 0; y < h; ++y)
            for (int x = 0; x <= w; ++x)
                e.texels[(size_t(y) * (w + 1) + x) * 4 + 3] = e.cells.pmf(size_t(y) * w + size_t(x % w));
        return e;
    }

    RGB pixel(int x, int y) const {
        const Float *p = &texels[(size_t(y) * (width + 1) + x) * 4];
        RGB c;
        c[0] = p[0];
        c[1] = p[1];
        c[2] = p[2];
        return c;
    }

    RGB lookup(Float u, Float v) const {
        Float px = u * Float(width) - Float(0.5), py = v * Float(height) - Float(0.5);
        Float fx0 = std::floor(px), fy0 = std::floor(py);
        Float tx = px - fx0, ty = py - fy0;
        int x0 = int(fx0), y0 = int(fy0);
        x0 = x0 < 0 ? width - 1 : (x0 >= width ? width - 1 : x0);  // u in [0,1): x0 in [-1, width-1]
        int ya = clamp(y0, 0, height - 1), yb = clamp(y0 + 1, 0, height - 1);
        const Float *ra = &texels[(size_t(ya) * (width + 1) + x0) * 4];
        const Float *rb = &texels[(size_t(yb) * (width + 1) + x0) * 4];
        RGB c;
        for (int k = 0; k < 3; ++k)
            c[k] = (ra[k] * (Float(1) - tx) + ra[k + 4] * tx) * (Float(1) - ty) +
                   (rb[k] * (Float(1) - tx) + rb[k + 4] * tx) * ty;
        return c;
    }

    // eval(d) and pdf(d) with d's lat-long coordinates already computed (latlong_uv).
    RGB eval_uv(const Vec3f &, Float u, Float v) const { return constant ? constant_L : lookup(u, v); }
    Float pdf_uv_dir(const Vec3f &d, Float u, Float v) const {
        if (constant) return UniformSpherePDF<Float>();
        Float st = std::sqrt(max_(Float(0), d.x * d.x + d.z * d.z));
        return st > Float(0) ? pdf_uv(u, v) / (Float(2) * Pi<Float> * Pi<Float> * st) : Float(0);
    }

    // Radiance arriving from direction d (world space, unit).
    RGB eval(const Vec3f &d) const {
        if (constant) return constant_L;
        Float u, v;
        latlong_uv(d, &u, &v);
        return lookup(u, v);
    }

    // Density of (u, v) under sample(): uniform inside each cell.
    Float pdf_uv(Float u, Float v) const {
        if (cells.empty()) return Float(0);
        int x = clamp(int(u * Float(width)), 0, width - 1), y = clamp(int(v * Float(height)), 0, height - 1);
        return texels[(size_t(y) * (width + 1) + x) * 4 + 3] * Float(width) * Float(height);
    }

    // Solid-angle density of sample(): p(u, v) / (2 pi^2 sin theta) (the lat-long Jacobian).
    Float pdf(const Vec3f &d) const {
        if (constant) return UniformSpherePDF<Float>();
        Float u, v;
        latlong_uv(d, &u, &v);
        Float st = std::sqrt(max_(Float(0), d.x * d.x + d.z * d.z));
        return st > Float(0) ? pdf_uv(u, v) / (Float(2) * Pi<Float> * Pi<Float> * st) : Float(0);
    }

    // Importance-samples a direction toward the environment from two uniforms (u0 is consumed
    // at double precision: the alias table splits it into a cell and a position); pdf = 0
    // means no sample. = sample_cell then sample_finish (the integrator runs the two stages in
    // separate loops over a bounce, so that their cache misses overlap).
    RGB sample(double u0, Float u1, Vec3f *wi, Float *pdf) const {
        Float uu, vv;
        int cell;
        sample_cell(u0, u1, &uu, &vv, &cell);
        return sample_finish(u0, u1, uu, vv, cell, wi, pdf);
    }
    // Stage 1: the lat-long position (uu, vv) and its cell (alias table); *texel: the index of
    // the cell's texel (its probability is texels[4 texel + 3]).
    void sample_cell(double u0, Float u1, Float *uu, Float *vv, int *texel) const {
        if (constant || cells.empty()) {
            *uu = *vv = 0;
            *texel = 0;
            return;
        }
        double rem;
        uint32_t c = cells.sample(u0, &rem);
        int x = int(c % uint32_t(width)), y = int(c / uint32_t(width));
        Float a = (Float(x) + Float(rem)) / Float(width), b = (Float(y) + u1) / Float(height);
        *uu = a < Float(1) ? a : 0x1.fffffep-1f;
        *vv = b < Float(1) ? b : 0x1.fffffep-1f;
        *texel = y * (width + 1) + x;
    }
    // Stage 2: direction, solid-angle pdf and radiance of the position of stage 1.
    RGB sample_finish(double u0, Float u1, Float uu, Float vv, int texel, Vec3f *wi, Float *pdf) const {
        if (constant) {
            *wi = SampleUniformSphere(Point2<Float>{Float(u0), u1});
            *pdf = UniformSpherePDF<Float>();
            return constant_L;
        }
        if (cells.empty()) {
            *pdf = 0;
            *wi = Vec3f(0, 1, 0);
            return RGB(Float(0));
        }
        Float st;
        *wi = latlong_direction(uu, vv, &st);
        Float prob = texels[size_t(texel) * 4 + 3];
        Float puv = prob * Float(width) * Float(height);
        bool ok = puv > Float(0) && st > Float(0);
        *pdf = ok ? puv / (Float(2) * Pi<Float> * Pi<Float> * st) : Float(0);
        return ok ? lookup(uu, vv) : RGB(Float(0));
    }

    // ---- packet forms (a lat-long map with a non-empty table: !constant && !cells.empty()) ----
    template <typename V> using IntOf = drjit::int32_array_t<V>;

    template <typename V> V texel_at(const IntOf<V> &i) const {
        return drjit::gather<V>(static_cast<const void *>(texels.data()), i);
    }
    // lookup(u, v) lane by lane.
    template <typename V> Spectrum<V> lookup(const V &u, const V &v) const {
        using I = IntOf<V>;
        V px = u * V(Float(width)) - V(Float(0.5)), py = v * V(Float(height)) - V(Float(0.5));
        V fx0 = floor(px), fy0 = floor(py);
        V tx = px - fx0, ty = py - fy0;
        I x0 = I(fx0), y0 = I(fy0);
        const I wm1(width - 1), hm1(height - 1), zero(0);
        x0 = drjit::select(x0 < zero, wm1, drjit::select(x0 >= I(width), wm1, x0));
        I ya = drjit::minimum(drjit::maximum(y0, zero), hm1), yb = drjit::minimum(drjit::maximum(y0 + I(1), zero), hm1);
        I ia = (ya * I(width + 1) + x0) * I(4), ib = (yb * I(width + 1) + x0) * I(4);
        Spectrum<V> c;
        for (int k = 0; k < 3; ++k)
            c[k] = (texel_at<V>(ia + I(k)) * (V(1) - tx) + texel_at<V>(ia + I(k + 4)) * tx) * (V(1) - ty) +
                   (texel_at<V>(ib + I(k)) * (V(1) - tx) + texel_at<V>(ib + I(k + 4)) * tx) * ty;
        return c;
    }
    // eval(d) and pdf(d) of escaped rays (d unit, world), lane by lane.
    template <typename V> void eval_pdf(const Vec3<V> &d, Spectrum<V> *le, V *pdf_out) const {
        using I = IntOf<V>;
        V u, v;
        latlong_uv(d.x, d.y, d.z, &u, &v);
        *le = lookup(u, v);
        V st = sqrt(max_(V(0), d.x * d.x + d.z * d.z));
        I x = drjit::minimum(drjit::maximum(I(u * V(Float(width))), I(0)), I(width - 1));
        I y = drjit::minimum(drjit::maximum(I(v * V(Float(height))), I(0)), I(height - 1));
        V puv = texel_at<V>((y * I(width + 1) + x) * I(4) + I(3)) * V(Float(width)) * V(Float(height));
        *pdf_out = select(st > V(0), puv / (V(Float(2) * Pi<Float> * Pi<Float>) * st), V(0));
    }
    // sample_cell lane by lane (a lat-long map with a non-empty table). c / width as a double
    // quotient truncated: exact for c < 2^31 (the remainder's gap 1/width is far above the
    // quotient's rounding).
    template <typename V>
    void sample_cell(const drjit::float64_array_t<V> &u0, const V &u1, V *uu, V *vv, IntOf<V> *texel) const {
        using I = IntOf<V>;
        using D = drjit::float64_array_t<V>;
        D rem;
        I c = cells.template sample<D, I>(u0, &rem);
        I y = I(D(c) / D(double(width)));
        I x = c - y * I(width);
        V a = (V(x) + V(rem)) / V(Float(width)), b = (V(y) + u1) / V(Float(height));
        *uu = select(a < V(1), a, V(0x1.fffffep-1f));
        *vv = select(b < V(1), b, V(0x1.fffffep-1f));
        *texel = y * I(width + 1) + x;
    }
    // sample_finish lane by lane (texel: stage 1's).
    template <typename V>
    Spectrum<V> sample_finish(const V &uu, const V &vv, const IntOf<V> &texel, Vec3<V> *wi, V *pdf_out) const {
        using I = IntOf<V>;
        V st;
        *wi = latlong_direction(uu, vv, &st);
        V puv = texel_at<V>(texel * I(4) + I(3)) * V(Float(width)) * V(Float(height));
        auto ok = (puv > V(0)) & (st > V(0));
        *pdf_out = select(ok, puv / (V(Float(2) * Pi<Float> * Pi<Float>) * st), V(0));
        Spectrum<V> c = lookup(uu, vv);
        for (int k = 0; k < 3; ++k) c[k] = select(ok, c[k], V(0));
        return c;
    }
};

// A delta light at infinity: irradiance E (on a surface facing it) from unit direction `dir`
// (pointing toward the light).
struct DirectionalLight {
    bool enabled = false;
    Vec3f dir{0, 1, 0};
    RGB E{Float(0)};
};

} // namespace bsdfkit::render
