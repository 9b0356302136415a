// Distant lighting: a latitude-longitude environment map (or a constant radiance) with
// luminance importance sampling, and an optional directional light.
//
// World space is y-up. Direction <-> lat-long (u, v) in [0,1)^2, image row 0 at the top:
//   theta = pi v (from +y), phi = 2 pi u,  d = (sin phi sin theta, cos theta, -cos phi sin theta)
// which is the mapping documented for Mitsuba 3's `envmap` plugin (u = 0.5 looks along +z,
// u = 0 and 1 along -z, u = 0.25 along +x), so the same image lights both renderers alike.
// Radiance is the bilinear interpolant of the pixel values placed at the pixel centres
// ((x + 0.5) / W, (y + 0.5) / H), periodic in u and clamped in v.
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

inline Vec3f latlong_direction(Float u, Float v, Float *sin_theta) {
    Float st, ct, sp, cp;
    sincos_(Pi<Float> * v, &st, &ct);
    sincos_(Float(2) * Pi<Float> * u, &sp, &cp);
    st = max_(st, Float(0));
    *sin_theta = st;
    return Vec3f(sp * st, ct, -cp * st);
}
inline void latlong_uv(const Vec3f &d, Float *u, Float *v) {
    Float uu = fast_atan2(d.x, -d.z) * Inv2Pi<Float>;
    uu = uu < Float(0) ? uu + Float(1) : uu;
    *u = uu >= Float(1) ? Float(0) : uu;
    // theta = acos(y), as atan2(sin, cos): accurate near the poles too
    Float v0 = fast_atan2(std::sqrt(d.x * d.x + d.z * d.z), d.y) * InvPi<Float>;
    *v = v0 < Float(1) ? v0 : Float(0x1.fffffep-1f);
}

struct Environment {
    bool constant = true;
    RGB constant_L{Float(1)};
    int width = 0, height = 0;
    std::vector<Float> rgb;  // height rows of (width + 1) RGB pixels: column width repeats column 0
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
        e.rgb.resize(size_t(w + 1) * h * 3);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x <= w; ++x)
                for (int c = 0; c < 3; ++c)
                    e.rgb[(size_t(y) * (w + 1) + x) * 3 + c] = data[(size_t(y) * w + (x % w)) * 3 + c];
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
        return e;
    }

    RGB pixel(int x, int y) const {
        const Float *p = &rgb[(size_t(y) * (width + 1) + x) * 3];
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
        const Float *ra = &rgb[(size_t(ya) * (width + 1) + x0) * 3];
        const Float *rb = &rgb[(size_t(yb) * (width + 1) + x0) * 3];
        RGB c;
        for (int k = 0; k < 3; ++k)
            c[k] = (ra[k] * (Float(1) - tx) + ra[k + 3] * tx) * (Float(1) - ty) +
                   (rb[k] * (Float(1) - tx) + rb[k + 3] * tx) * ty;
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
        return cells.pmf(size_t(y) * width + x) * Float(width) * Float(height);
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
        Float uu, vv, prob;
        sample_cell(u0, u1, &uu, &vv, &prob);
        return sample_finish(u0, u1, uu, vv, prob, wi, pdf);
    }
    // Stage 1: the lat-long position (uu, vv) and the probability of its cell (alias table).
    void sample_cell(double u0, Float u1, Float *uu, Float *vv, Float *cell_prob) const {
        if (constant || cells.empty()) {
            *uu = *vv = *cell_prob = 0;
            return;
        }
        double rem;
        float prob;
        uint32_t c = cells.sample(u0, &rem, &prob);
        int x = int(c % uint32_t(width)), y = int(c / uint32_t(width));
        Float a = (Float(x) + Float(rem)) / Float(width), b = (Float(y) + u1) / Float(height);
        *uu = a < Float(1) ? a : 0x1.fffffep-1f;
        *vv = b < Float(1) ? b : 0x1.fffffep-1f;
        *cell_prob = prob;
    }
    // Stage 2: direction, solid-angle pdf and radiance of the position of stage 1.
    RGB sample_finish(double u0, Float u1, Float uu, Float vv, Float prob, Vec3f *wi, Float *pdf) const {
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
        Float puv = prob * Float(width) * Float(height);
        bool ok = puv > Float(0) && st > Float(0);
        *pdf = ok ? puv / (Float(2) * Pi<Float> * Pi<Float> * st) : Float(0);
        return ok ? lookup(uu, vv) : RGB(Float(0));
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
