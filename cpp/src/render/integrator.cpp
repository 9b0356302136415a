// Path tracer of the preview renderer (see render/render.h). The estimator follows pbrt-v4's
// PathIntegrator::Li (Pharr, Jakob, Humphreys, "Physically Based Rendering" 4th ed. sec. 13.4):
//   L = sum over path vertices of beta * (MIS-weighted light sample + MIS-weighted escaped ray),
//   beta *= f |cos| / pdf after each BSDF sample; power heuristic (Veach 1997 sec. 9.2.4).
// It runs as a small wavefront: the paths of one sample index over a 16 x 16 tile advance
// together, one bounce at a time, so that Embree traces each bounce's rays (and shadow rays)
// as one stream. Every path owns its random stream and its radiance sum, so the result does not
// depend on how paths are grouped.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <vector>

#include "bsdfkit/core/rng.h"
#include "bsdfkit/render/render.h"

namespace bsdfkit::render {

namespace {

// SplitMix64 stream seeded from (seed, pixel, sample): independent of tiles and threads.
struct SampleRng {
    uint64_t state = 0;
    SampleRng() = default;
    SampleRng(uint64_t seed, uint64_t pixel, uint64_t sample) : state(hash3(seed, pixel, sample)) {}
    Float next() {
        state += 0x9e3779b97f4a7c15ull;
        return uniform_from_bits<Float>(mix64(state));
    }
    double next_double() {
        state += 0x9e3779b97f4a7c15ull;
        return uniform_from_bits<double>(mix64(state));
    }
    Point2<Float> next2() {
        Float a = next();
        return Point2<Float>{a, next()};
    }
};

// Power heuristic with beta = 2 for one sample of each technique (Veach 1997 eq. 9.13).
inline Float power_heuristic(Float f, Float g) {
    Float f2 = f * f, g2 = g * g;
    if (std::isinf(f2)) return Float(1);
    return f2 + g2 > Float(0) ? f2 / (f2 + g2) : Float(0);
}

inline bool finite_rgb(const RGB &c) {
    return std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
}

constexpr int kTile = 16;
constexpr Float kInf = std::numeric_limits<Float>::infinity();

struct Path {
    RGB L, beta;
    Float p_b, eta_scale;
    int depth;
    bool specular_bounce;
    SampleRng rng;
    double env_u0;  // uniforms of this vertex's environment sample, drawn (and prefetched) early
    Float env_u1;
};

struct Shadow {
    int path;
    RGB contribution;  // added to the path's L when the ray is unoccluded
};

// Scratch of one thread: the paths of a tile and their ray streams.
struct Wave {
    std::vector<Path> paths;
    std::vector<RTCRayHit> rays;
    std::vector<int> ray_path;      // path of each ray in `rays`
    std::vector<Point2<Float>> miss_uv;  // lat-long coordinates of the rays that escaped
    std::vector<RTCRayHit> next_rays;
    std::vector<int> next_path;
    std::vector<RTCRay> shadow_rays;
    std::vector<Shadow> shadows;
};

struct Tracer {
    const Scene &scene;
    const Camera &camera;
    const RenderSettings &st;

    // Direct light at a non-specular vertex: one environment sample MIS-weighted against BSDF
    // sampling, plus the directional light (a delta: light sampling only). Queues shadow rays.
    void sample_ld(int pi, Path &path, const Hit &h, const Frame &fr, const Material &m, const Vec3f &wo,
                   Wave &w) const {
        double u0 = path.env_u0;
        Float u1 = path.env_u1;
        Vec3f wi;
        Float p_l;
        RGB le = scene.env.sample(u0, u1, &wi, &p_l);
        if (p_l > Float(0) && !le.is_black()) {
            Vec3f wl = fr.to_local(wi);
            RGB f = material_f(m, wo, wl) * std::abs(wl.z);
            if (!f.is_black()) {
                Float p_b = material_pdf(m, wo, wl);
                w.shadows.push_back({pi, path.beta * f * le * (power_heuristic(p_l, p_b) / p_l)});
                w.shadow_rays.emplace_back();
                make_spawn_ray(w.shadow_rays.back(), h, wi, kInf);
            }
        }
        if (scene.sun.enabled) {
            Vec3f wl = fr.to_local(scene.sun.dir);
            RGB f = material_f(m, wo, wl) * std::abs(wl.z);
            if (!f.is_black()) {
                w.shadows.push_back({pi, path.beta * f * scene.sun.E});
                w.shadow_rays.emplace_back();
                make_spawn_ray(w.shadow_rays.back(), h, scene.sun.dir, kInf);
            }
        }
    }

    // One bounce of path pi whose ray rh was just traced; queues its continuation ray.
    // First pass over a bounce's rays: lat-long coordinates of escaped rays, environment-sample
    // uniforms of surface hits, and prefetches of the map texels / alias entries they will read.
    void prepare(int pi, const RTCRayHit &rh, Point2<Float> *uv, Wave &w) const {
        Path &path = w.paths[size_t(pi)];
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
            latlong_uv(Vec3f(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z), &uv->x, &uv->y);
            scene.env.prefetch_uv(uv->x, uv->y);
        } else {
            path.env_u0 = path.rng.next_double();
            path.env_u1 = path.rng.next();
            scene.env.prefetch_sample(path.env_u0);
        }
    }

    void advance(int pi, const RTCRayHit &rh, const Point2<Float> &uv, Wave &w) const {
        Path &path = w.paths[size_t(pi)];
        Vec3f d(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
            // Escaped: environment radiance, MIS-weighted unless only BSDF sampling could have
            // produced this direction (camera ray or a delta lobe).
            RGB le = scene.env.eval_uv(d, uv.x, uv.y);
            if (path.depth == 0 || path.specular_bounce) path.L = path.L + path.beta * le;
            else path.L = path.L + path.beta * le * power_heuristic(path.p_b, scene.env.pdf_uv_dir(d, uv.x, uv.y));
            return;
        }
        if (path.depth++ == st.max_depth) return;
        Hit h;
        scene.hit_point(rh, &h);
        Material scratch;
        const Material &m = material_at(scene, h, &scratch);
        uint8_t flags = material_flags(m);
        if (flags == Unset) return;
        Frame fr(h.n, h.tangent);
        Vec3f wo = fr.to_local(-d);
        if (has_nonspecular(flags)) sample_ld(pi, path, h, fr, m, wo, w);

        Float uc = path.rng.next();
        Point2<Float> u = path.rng.next2();
        BSDFSample<Float> bs = material_sample(m, wo, uc, u);
        if (!bs.valid) return;
        path.beta = path.beta * bs.f * (std::abs(bs.wi.z) / bs.pdf);
        // Layered-style samples only know their pdf up to a factor: ask pdf() for MIS.
        path.p_b = bs.pdf_is_proportional ? material_pdf(m, wo, bs.wi) : bs.pdf;
        path.specular_bounce = bs.is_specular();
        if (bs.is_transmission()) path.eta_scale *= sqr(bs.eta);
        Vec3f nd = normalize(fr.to_world(bs.wi));

        // Russian roulette on the throughput without the radiance 1/eta^2 scaling.
        RGB rr = path.beta * path.eta_scale;
        Float mx = rr.max_component();
        if (mx < Float(1) && path.depth > 1) {
            Float q = max_(Float(0), Float(1) - mx);
            if (path.rng.next() < q) return;
            path.beta = path.beta / (Float(1) - q);
        }
        w.next_rays.emplace_back();
        make_spawn_rayhit(w.next_rays.back(), h, nd);
        w.next_path.push_back(pi);
    }

    // Sample index s of every pixel of tile [x0, x1) x [y0, y1); adds to acc, returns rays traced.
    int64_t render_tile_sample(int x0, int y0, int x1, int y1, int s, double *acc, Wave &w, int64_t *bad) const {
        const int W = st.width, H = st.height;
        int64_t rays = 0;
        w.paths.clear();
        w.rays.clear();
        w.ray_path.clear();
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                uint64_t pix = uint64_t(y) * uint64_t(W) + uint64_t(x);
                Path p;
                p.L = RGB(Float(0));
                p.beta = RGB(Float(1));
                p.p_b = 1;
                p.eta_scale = 1;
                p.depth = 0;
                p.specular_bounce = false;
                p.rng = SampleRng(st.seed, pix, uint64_t(s));
                Point2<Float> j = p.rng.next2();  // box filter: uniform over the pixel
                Vec3f d = camera.direction(Float(x) + j.x, Float(y) + j.y, W, H);
                w.rays.emplace_back();
                make_rayhit(w.rays.back(), camera.origin, d);
                w.ray_path.push_back(int(w.paths.size()));
                w.paths.push_back(p);
            }
        bool coherent = true;  // camera rays of a tile
        while (!w.rays.empty()) {
            scene.intersect_n(w.rays.data(), unsigned(w.rays.size()), coherent);
            rays += int64_t(w.rays.size());
            w.next_rays.clear();
            w.next_path.clear();
            w.shadow_rays.clear();
            w.shadows.clear();
            w.miss_uv.resize(w.rays.size());
            for (size_t k = 0; k < w.rays.size(); ++k) prepare(w.ray_path[k], w.rays[k], &w.miss_uv[k], w);
            for (size_t k = 0; k < w.rays.size(); ++k) advance(w.ray_path[k], w.rays[k], w.miss_uv[k], w);
            if (!w.shadow_rays.empty()) {
                scene.occluded_n(w.shadow_rays.data(), unsigned(w.shadow_rays.size()), false);
                rays += int64_t(w.shadow_rays.size());
                for (size_t k = 0; k < w.shadows.size(); ++k)
                    if (!(w.shadow_rays[k].tfar < 0.f)) {
                        Path &p = w.paths[size_t(w.shadows[k].path)];
                        p.L = p.L + w.shadows[k].contribution;
                    }
            }
            std::swap(w.rays, w.next_rays);
            std::swap(w.ray_path, w.next_path);
            coherent = false;
        }
        // Accumulate in pixel order; one sample per pixel per call keeps the per-pixel sum order.
        int k = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x, ++k) {
                const RGB &L = w.paths[size_t(k)].L;
                if (!finite_rgb(L)) {
                    ++*bad;
                    continue;
                }
                double *a = acc + (size_t(y) * size_t(W) + size_t(x)) * 3;
                a[0] += double(L[0]);
                a[1] += double(L[1]);
                a[2] += double(L[2]);
            }
        return rays;
    }
};

} // namespace

bool render_samples(const Scene &scene, const Camera &camera, const RenderSettings &st, int s0, int s1, double *acc,
                    RenderStats *stats, const std::function<bool()> &should_stop) {
    const int W = st.width, H = st.height;
    const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;
    const int64_t ntiles = int64_t(tiles_x) * tiles_y;
    Tracer tracer{scene, camera, st};
    std::atomic<bool> stop{false};
    std::atomic<int64_t> rays_total{0}, nonfinite_total{0};
    using clock = std::chrono::steady_clock;
    auto last_poll = clock::now();

    auto run_tile = [&](int64_t t, Wave &w) {
        int tx = int(t % tiles_x), ty = int(t / tiles_x);
        int x0 = tx * kTile, y0 = ty * kTile, x1 = std::min(W, x0 + kTile), y1 = std::min(H, y0 + kTile);
        int64_t rays = 0, bad = 0;
        for (int s = s0; s < s1; ++s) rays += tracer.render_tile_sample(x0, y0, x1, y1, s, acc, w, &bad);
        rays_total += rays;
        nonfinite_total += bad;
    };

    // The calling thread (OpenMP thread 0) polls should_stop at most every 50 ms.
    auto poll = [&]() {
        if (!should_stop || stop.load(std::memory_order_relaxed)) return;
        auto now = clock::now();
        if (now - last_poll < std::chrono::milliseconds(50)) return;
        last_poll = now;
        if (should_stop()) stop = true;
    };

    int nthreads = std::max(1, st.threads);
    if (nthreads == 1 || ntiles == 1) {
        Wave w;
        for (int64_t t = 0; t < ntiles && !stop; ++t) {
            run_tile(t, w);
            poll();
        }
    } else {
#pragma omp parallel num_threads(nthreads)
        {
            Wave w;
#pragma omp for schedule(dynamic, 1)
            for (int64_t t = 0; t < ntiles; ++t) {
                if (stop.load(std::memory_order_relaxed)) continue;
                run_tile(t, w);
                if (omp_get_thread_num() == 0) poll();
            }
        }
    }
    if (stats) {
        stats->rays += rays_total.load();
        stats->nonfinite += nonfinite_total.load();
    }
    return !stop.load();
}

} // namespace bsdfkit::render
