// Spectral path tracer of the preview renderer (render/spectral.h): the estimator of
// integrator.cpp (pbrt-v4 PathIntegrator::Li: MIS-weighted environment sample and escaped ray,
// the directional light, Russian roulette on beta * eta_scale) with 4 wavelengths per path.
// Per path: the pixel jitter, then one uniform for the wavelengths (pbrt-v4
// SampledWavelengths::SampleVisible), then per vertex the environment sample's uniforms, the
// BSDF sample's and the roulette's, as in the RGB tracer.
// Paths of a tile advance bounce by bounce (Embree 16-wide packets for the rays and the shadow
// rays); each hit is shaded on its own with its material's spectral adapter (batch_spectral.h:
// scalar per-element code). Every path owns its random stream and its sums, so the image does
// not depend on the grouping of paths or on the thread count.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <vector>

#include "bsdfkit/render/sampler.h"
#include "bsdfkit/render/spectral.h"

namespace bsdfkit::render {

namespace {

constexpr int kTileS = 16;
constexpr int kWaveS = 4;  // sample indices of a tile traced together
constexpr Float kInfS = std::numeric_limits<Float>::infinity();

struct SPath {
    Spec4 L, beta;
    double lam[kSpectralN], pdf[kSpectralN];
    Float p_b, eta_scale;
    int depth;
    bool specular_bounce;
    SampleRng rng;
};

struct SShadow {
    int path;
    Spec4 contribution;
};

struct SWave {
    std::vector<SPath> paths;
    std::vector<RTCRayHit> rays, next_rays;
    std::vector<int> ray_path, next_path;
    std::vector<RTCRay> shadow_rays;
    std::vector<SShadow> shadows;
};

inline bool nonzero(const Spec4 &s) { return !s.is_black(); }

// A PerElementModel adapter's model built once per hit at the path's wavelengths (the adapter's
// own f / pdf / sample rebuild it on every call: the same calls on the same model, once).
template <typename B> struct BuiltAtHit {
    B b;
    Spec4 f(const Vec3f &wo, const Vec3f &wi, const double *, TransportMode mode) const { return bsdf_f(b, wo, wi, mode); }
    Float pdf(const Vec3f &wo, const Vec3f &wi, const double *, TransportMode mode, uint8_t sf) const {
        return bsdf_pdf(b, wo, wi, mode, sf);
    }
    BSDFSample<Float, 4> sample(const Vec3f &wo, Float uc, Point2<Float> u, const double *, TransportMode mode,
                                uint8_t sf, bool *terminated) const {
        *terminated = false;
        return bsdf_sample(b, wo, uc, u, mode, sf);
    }
};

struct SpectralTracer {
    const Scene &scene;
    const SpectralScene &spec;
    const Camera &camera;
    const RenderSettings &st;

    // One ray of a bounce: an escaped ray adds the environment; a hit is shaded (light samples
    // queued as shadow rays) and queues the path's next ray.
    void step(int pi, const RTCRayHit &rh, SWave &w) const {
        SPath &path = w.paths[size_t(pi)];
        Vec3f d(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
        const Environment &env = scene.env;
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
            Float u, v;
            latlong_uv(d, &u, &v);
            Spec4 le = spec.env_uv(u, v, path.lam);
            if (path.depth == 0 || path.specular_bounce) path.L = path.L + path.beta * le;
            else path.L = path.L + path.beta * le * power_heuristic(path.p_b, env.pdf_uv_dir(d, u, v));
            return;
        }
        if (path.depth++ == st.max_depth) return;
        Hit h;
        scene.hit_point(rh, &h);
        uint8_t flags = scene.flags[size_t(h.material)];
        if (flags == Unset) return;
        const SpectralMaterial &sm = spec.materials[size_t(h.material)];
        Frame fr(h.n, h.tangent);
        Vec3f wo = fr.to_local(-d);
        std::visit(
            [&](const auto &m) {
                using M = std::decay_t<decltype(m)>;
                if constexpr (std::is_base_of_v<PerElementModel<M, Float>, M>) {
                    using B = decltype(m.at(w.paths[size_t(pi)].lam));
                    shade(BuiltAtHit<B>{m.at(w.paths[size_t(pi)].lam)}, pi, h, fr, wo, flags, w);
                } else if constexpr (!std::is_same_v<M, std::monostate>) {
                    shade(m, pi, h, fr, wo, flags, w);
                }
            },
            sm);
    }

    template <typename SM>
    void shade(const SM &m, int pi, const Hit &h, const Frame &fr, const Vec3f &wo, uint8_t flags, SWave &w) const {
        SPath &path = w.paths[size_t(pi)];
        const Environment &env = scene.env;
        if (has_nonspecular(flags)) {
            // One environment sample MIS-weighted against BSDF sampling (the RGB tracer's uniforms
            // and sampling: the luminance of the RGB environment), plus the directional light.
            double u0 = path.rng.next_double();
            Float u1 = path.rng.next();
            Float uu, vv, prob, pdf_l;
            Vec3f wi;
            env.sample_cell(u0, u1, &uu, &vv, &prob);
            env.sample_finish(u0, u1, uu, vv, prob, &wi, &pdf_l);
            if (pdf_l > Float(0)) {
                Spec4 le = spec.env_uv(uu, vv, path.lam);
                if (nonzero(le)) {
                    Vec3f wl = fr.to_local(wi);
                    Spec4 f = m.f(wo, wl, path.lam, kMode) * std::abs(wl.z);
                    if (nonzero(f)) {
                        Float pb = m.pdf(wo, wl, path.lam, kMode, uint8_t(RT_All));
                        w.shadows.push_back({pi, path.beta * f * le * (power_heuristic(pdf_l, pb) / pdf_l)});
                        w.shadow_rays.emplace_back();
                        make_spawn_ray(w.shadow_rays.back(), h, wi, kInfS);
                    }
                }
            }
            if (scene.sun.enabled) {
                Vec3f ws = fr.to_local(scene.sun.dir);
                Spec4 f = m.f(wo, ws, path.lam, kMode) * std::abs(ws.z);
                if (nonzero(f)) {
                    w.shadows.push_back({pi, path.beta * f * spec.illuminant(spec.sun, path.lam)});
                    w.shadow_rays.emplace_back();
                    make_spawn_ray(w.shadow_rays.back(), h, scene.sun.dir, kInfS);
                }
            }
        }
        Float uc = path.rng.next();
        Point2<Float> u = path.rng.next2();
        bool terminated = false;
        BSDFSample<Float, 4> bs = m.sample(wo, uc, u, path.lam, kMode, uint8_t(RT_All), &terminated);
        if (!bs.valid) return;
        // Layered-style samples only know their pdf up to a factor: ask pdf() for MIS.
        Float p_b = bs.pdf_is_proportional ? m.pdf(wo, bs.wi, path.lam, kMode, uint8_t(RT_All)) : bs.pdf;
        if (terminated && path.pdf[1] > 0.0) {
            // pbrt-v4 SampledWavelengths::TerminateSecondary: lambda0 alone carries the path on.
            for (int i = 1; i < kSpectralN; ++i) path.pdf[i] = 0.0;
            path.pdf[0] /= double(kSpectralN);
        }
        path.beta = path.beta * bs.f * (std::abs(bs.wi.z) / bs.pdf);
        path.p_b = p_b;
        path.specular_bounce = (bs.flags & Specular) != 0;
        if ((bs.flags & Transmission) != 0) path.eta_scale *= sqr(bs.eta);
        Vec3f nd = normalize(fr.to_world(bs.wi));
        Spec4 rr = path.beta * path.eta_scale;
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

    int64_t render_tile_wave(int x0, int y0, int x1, int y1, int s, int ns, double *acc, SWave &w, int64_t *bad) const {
        const int W = st.width;
        int64_t rays = 0;
        w.paths.clear();
        w.rays.clear();
        w.ray_path.clear();
        for (int k = 0; k < ns; ++k)
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    uint64_t pix = uint64_t(y) * uint64_t(W) + uint64_t(x);
                    SPath p;
                    p.L = Spec4(Float(0));
                    p.beta = Spec4(Float(1));
                    p.p_b = 1;
                    p.eta_scale = 1;
                    p.depth = 0;
                    p.specular_bounce = false;
                    p.rng = SampleRng(st.seed, pix, uint64_t(s + k));
                    Point2<Float> j = p.rng.next2();  // box filter: uniform over the pixel
                    SpectralScene::sample_wavelengths(p.rng.next_double(), p.lam, p.pdf);
                    Vec3f d = camera.direction(Float(x) + j.x, Float(y) + j.y, W, st.height);
                    w.rays.emplace_back();
                    make_rayhit(w.rays.back(), camera.origin, d);
                    w.ray_path.push_back(int(w.paths.size()));
                    w.paths.push_back(p);
                }
        bool coherent = true;
        while (!w.rays.empty()) {
            scene.intersect_n(w.rays.data(), unsigned(w.rays.size()), coherent);
            rays += int64_t(w.rays.size());
            w.next_rays.clear();
            w.next_path.clear();
            w.shadow_rays.clear();
            w.shadows.clear();
            for (size_t k = 0; k < w.rays.size(); ++k) step(w.ray_path[k], w.rays[k], w);
            if (!w.shadow_rays.empty()) {
                scene.occluded_n(w.shadow_rays.data(), unsigned(w.shadow_rays.size()), false);
                rays += int64_t(w.shadow_rays.size());
                for (size_t k = 0; k < w.shadows.size(); ++k)
                    if (!(w.shadow_rays[k].tfar < 0.f)) {
                        SPath &p = w.paths[size_t(w.shadows[k].path)];
                        p.L = p.L + w.shadows[k].contribution;
                    }
            }
            std::swap(w.rays, w.next_rays);
            std::swap(w.ray_path, w.next_path);
            coherent = false;
        }
        const int npix = (x1 - x0) * (y1 - y0);
        int k = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x, ++k) {
                double *a = acc + (size_t(y) * size_t(W) + size_t(x)) * 3;
                for (int q = 0; q < ns; ++q) {
                    const SPath &p = w.paths[size_t(q * npix + k)];
                    double rgb[3];
                    spec.to_rgb(p.L, p.lam, p.pdf, rgb);
                    if (!(std::isfinite(rgb[0]) && std::isfinite(rgb[1]) && std::isfinite(rgb[2]))) {
                        ++*bad;
                        continue;
                    }
                    a[0] += rgb[0];
                    a[1] += rgb[1];
                    a[2] += rgb[2];
                }
            }
        return rays;
    }
};

} // namespace

bool render_samples_spectral(const Scene &scene, const SpectralScene &spec, const Camera &camera,
                             const RenderSettings &st, int s0, int s1, double *acc, RenderStats *stats,
                             const std::function<bool()> &should_stop) {
    const int W = st.width, H = st.height;
    const int tiles_x = (W + kTileS - 1) / kTileS, tiles_y = (H + kTileS - 1) / kTileS;
    const int64_t ntiles = int64_t(tiles_x) * tiles_y;
    SpectralTracer tracer{scene, spec, camera, st};
    std::atomic<bool> stop{false};
    std::atomic<int64_t> rays_total{0}, nonfinite_total{0};
    using clock = std::chrono::steady_clock;
    auto last_poll = clock::now();

    auto run_tile = [&](int64_t t, SWave &w) {
        int tx = int(t % tiles_x), ty = int(t / tiles_x);
        int x0 = tx * kTileS, y0 = ty * kTileS, x1 = std::min(W, x0 + kTileS), y1 = std::min(H, y0 + kTileS);
        int64_t rays = 0, bad = 0;
        for (int s = s0; s < s1; s += kWaveS)
            rays += tracer.render_tile_wave(x0, y0, x1, y1, s, std::min(kWaveS, s1 - s), acc, w, &bad);
        rays_total += rays;
        nonfinite_total += bad;
    };
    auto poll = [&]() {
        if (!should_stop || stop.load(std::memory_order_relaxed)) return;
        auto now = clock::now();
        if (now - last_poll < std::chrono::milliseconds(50)) return;
        last_poll = now;
        if (should_stop()) stop = true;
    };
    int nthreads = std::max(1, st.threads);
    if (nthreads == 1 || ntiles == 1) {
        SWave w;
        for (int64_t t = 0; t < ntiles && !stop; ++t) {
            run_tile(t, w);
            poll();
        }
    } else {
#pragma omp parallel num_threads(nthreads)
        {
            SWave w;
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
