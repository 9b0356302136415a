// The wavefront loop shared by the RGB and the spectral path tracers (integrator.cpp,
// integrator_spectral.cpp): tiles of 16 x 16 pixels over the threads, kWaveSamples sample
// indices of a tile traced together, one bounce at a time (Embree 16-wide packets for the rays
// and the shadow rays), each pixel summing its samples in index order.
//
// A tracer T supplies the path state and what happens at a bounce:
//   T::Path     has L (a spectrum with +), rng (SampleRng) and whatever else the tracer carries;
//   T::Wave     derives from WaveBase<T::Path, T::Contribution> (its own per-bounce scratch besides);
//   void start(Path &p) const           path set-up after the pixel jitter drew two uniforms
//                                       from p.rng (the spectral tracer draws its wavelengths);
//   void bounce(Wave &w) const          the rays w.rays of paths w.ray_path have been traced:
//                                       queue shadow rays (w.shadow_rays + w.shadows) and next
//                                       rays (w.next_rays + w.next_path);
//   bool pixel_value(const Path &, double rgb[3]) const
//                                       the path's linear RGB (false: not finite, dropped).
// Every path owns its random stream and its radiance sum, so the image does not depend on the
// grouping of paths into waves, tiles or threads.
#pragma once
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "render.h"
#include "sampler.h"

namespace bsdfkit::render {

// Pixels per tile side, and sample indices of a tile traced together: one wave holds
// kTile^2 * kWaveSamples paths, enough for each material's hits of a bounce to fill whole packets.
inline constexpr int kTile = 16;
inline constexpr int kWaveSamples = 4;

// An allocator whose emplace_back() default-initializes (a trivial type, e.g. an Embree ray, is
// left uninitialized instead of zeroed: the caller writes it next).
template <typename T> struct DefaultInitAllocator : std::allocator<T> {
    template <typename U> struct rebind {
        using other = DefaultInitAllocator<U>;
    };
    DefaultInitAllocator() = default;
    template <typename U> DefaultInitAllocator(const DefaultInitAllocator<U> &) noexcept {}
    template <typename U> void construct(U *p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void *>(p)) U;
    }
    template <typename U, typename... A> void construct(U *p, A &&...a) {
        ::new (static_cast<void *>(p)) U(std::forward<A>(a)...);
    }
};
// A vector for per-bounce records that are written right after emplace_back().
template <typename T> using ScratchVector = std::vector<T, DefaultInitAllocator<T>>;

// The ray streams of one wave (one per thread, reused).
template <typename Path, typename Contribution> struct WaveBase {
    struct Shadow {
        int path;
        Contribution contribution;  // added to the path's L when the shadow ray is unoccluded
    };
    std::vector<Path> paths;
    ScratchVector<RTCRayHit> rays, next_rays;
    std::vector<int> ray_path, next_path;  // path of each ray
    ScratchVector<RTCRay> shadow_rays;
    std::vector<Shadow> shadows;
};

// Sample indices [s, s + ns) of every pixel of tile [x0, x1) x [y0, y1); adds to acc in
// pixel-then-sample order, returns the rays traced.
template <typename T>
int64_t trace_wave(const T &tracer, const Scene &scene, const Camera &camera, const RenderSettings &st, int x0,
                   int y0, int x1, int y1, int s, int ns, double *acc, typename T::Wave &w, int64_t *bad) {
    const int W = st.width;
    int64_t rays = 0;
    w.paths.clear();
    w.rays.clear();
    w.ray_path.clear();
    const Camera::Raster raster = camera.raster(W, st.height);
    for (int k = 0; k < ns; ++k)
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                uint64_t pix = uint64_t(y) * uint64_t(W) + uint64_t(x);
                typename T::Path p;
                p.rng = SampleRng(st.seed, pix, uint64_t(s + k));
                Point2<Float> j = p.rng.next2();  // box filter: uniform over the pixel
                tracer.start(p);
                Vec3f d = camera.direction(Float(x) + j.x, Float(y) + j.y, raster);
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
        tracer.bounce(w);
        if (!w.shadow_rays.empty()) {
            scene.occluded_n(w.shadow_rays.data(), unsigned(w.shadow_rays.size()), false);
            rays += int64_t(w.shadow_rays.size());
            for (size_t k = 0; k < w.shadows.size(); ++k)
                if (!(w.shadow_rays[k].tfar < 0.f)) {
                    auto &p = w.paths[size_t(w.shadows[k].path)];
                    p.L = p.L + w.shadows[k].contribution;
                }
        }
        std::swap(w.rays, w.next_rays);
        std::swap(w.ray_path, w.next_path);
        coherent = false;
    }
    // Accumulate in pixel order, each pixel's samples in index order (the per-pixel sum order
    // of one sample per call).
    const int npix = (x1 - x0) * (y1 - y0);
    int k = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x, ++k) {
            double *a = acc + (size_t(y) * size_t(W) + size_t(x)) * 3;
            for (int q = 0; q < ns; ++q) {
                double rgb[3];
                if (!tracer.pixel_value(w.paths[size_t(q * npix + k)], rgb)) {
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

// Adds samples [s0, s1) of every pixel to acc (render_samples' contract, render.h): the tiles on
// st.threads OpenMP threads (dynamic schedule, one Wave per thread); should_stop polled on the
// calling thread at most every 50 ms.
template <typename T>
bool render_tiles(const T &tracer, const Scene &scene, const Camera &camera, const RenderSettings &st, int s0, int s1,
                  double *acc, RenderStats *stats, const std::function<bool()> &should_stop) {
    const int W = st.width, H = st.height;
    const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;
    const int64_t ntiles = int64_t(tiles_x) * tiles_y;
    std::atomic<bool> stop{false};
    std::atomic<int64_t> rays_total{0}, nonfinite_total{0};
    using clock = std::chrono::steady_clock;
    auto last_poll = clock::now();

    auto run_tile = [&](int64_t t, typename T::Wave &w) {
        int tx = int(t % tiles_x), ty = int(t / tiles_x);
        int x0 = tx * kTile, y0 = ty * kTile, x1 = std::min(W, x0 + kTile), y1 = std::min(H, y0 + kTile);
        int64_t rays = 0, bad = 0;
        for (int s = s0; s < s1; s += kWaveSamples)
            rays += trace_wave(tracer, scene, camera, st, x0, y0, x1, y1, s, std::min(kWaveSamples, s1 - s), acc, w,
                               &bad);
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
        typename T::Wave w;
        for (int64_t t = 0; t < ntiles && !stop; ++t) {
            run_tile(t, w);
            poll();
        }
    } else {
#pragma omp parallel num_threads(nthreads)
        {
            typename T::Wave w;
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
