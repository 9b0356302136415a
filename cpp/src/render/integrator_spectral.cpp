// Spectral path tracer of the preview renderer (render/spectral.h): the estimator of
// integrator.cpp (pbrt-v4 PathIntegrator::Li: MIS-weighted environment sample and escaped ray,
// the directional light, Russian roulette on beta * eta_scale) with 4 wavelengths per path.
// Per path: the pixel jitter, then one uniform for the wavelengths (pbrt-v4
// SampledWavelengths::SampleVisible), then per vertex the environment sample's uniforms, the
// BSDF sample's and the roulette's, as in the RGB tracer.
// Paths of a tile advance bounce by bounce in the wavefront loop shared with the RGB tracer
// (render/wavefront.h); each hit is shaded on its own with its material's spectral adapter
// (batch_spectral.h: scalar per-element code). Every path owns its random stream and its sums,
// so the image does not depend on the grouping of paths or on the thread count.
#include <cmath>
#include <type_traits>
#include <utility>
#include <vector>

#include "bsdfkit/render/sampler.h"
#include "bsdfkit/render/spectral.h"
#include "bsdfkit/render/wavefront.h"

namespace bsdfkit::render {

namespace {

constexpr Float kInfS = std::numeric_limits<Float>::infinity();

struct SPath {
    Spec4 L, beta;
    double lam[kSpectralN], pdf[kSpectralN];
    Float p_b, eta_scale;
    int depth;
    bool specular_bounce;
    SampleRng rng;
};

using SWave = WaveBase<SPath, Spec4>;

inline bool nonzero(const Spec4 &s) { return !s.is_black(); }

// Models with an offset across a fibre (the hair models: set_h).
template <typename B, typename = void> struct has_set_h : std::false_type {};
template <typename B> struct has_set_h<B, std::void_t<decltype(std::declval<B &>().set_h(0.0))>> : std::true_type {};

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
    using Path = SPath;
    using Wave = SWave;
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
        const Frame &fr = h.frame;
        Vec3f wo = fr.to_local(-d);
        std::visit(
            [&](const auto &m) {
                using M = std::decay_t<decltype(m)>;
                if constexpr (std::is_base_of_v<PerElementModel<M, Float>, M>) {
                    using B = decltype(m.at(w.paths[size_t(pi)].lam));
                    BuiltAtHit<B> built{m.at(w.paths[size_t(pi)].lam)};
                    // a hair model on a fibre takes the offset h of the hit (as material_at in RGB mode)
                    if constexpr (has_set_h<B>::value)
                        if (h.fibre) built.b.set_h(double(h.h));
                    shade(built, pi, h, fr, wo, flags, w);
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
            Float uu, vv, pdf_l;
            int texel;
            Vec3f wi;
            env.sample_cell(u0, u1, &uu, &vv, &texel);
            env.sample_finish(u0, u1, uu, vv, texel, &wi, &pdf_l);
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

    // The wavefront loop's hooks (wavefront.h).
    void start(SPath &p) const {
        p.L = Spec4(Float(0));
        p.beta = Spec4(Float(1));
        p.p_b = 1;
        p.eta_scale = 1;
        p.depth = 0;
        p.specular_bounce = false;
        SpectralScene::sample_wavelengths(p.rng.next_double(), p.lam, p.pdf);
    }
    void bounce(SWave &w) const {
        for (size_t k = 0; k < w.rays.size(); ++k) step(w.ray_path[k], w.rays[k], w);
    }
    bool pixel_value(const SPath &p, double *rgb) const {
        spec.to_rgb(p.L, p.lam, p.pdf, rgb);
        return std::isfinite(rgb[0]) && std::isfinite(rgb[1]) && std::isfinite(rgb[2]);
    }
};

} // namespace

bool render_samples_spectral(const Scene &scene, const SpectralScene &spec, const Camera &camera,
                             const RenderSettings &st, int s0, int s1, double *acc, RenderStats *stats,
                             const std::function<bool()> &should_stop) {
    return render_tiles(SpectralTracer{scene, spec, camera, st}, scene, camera, st, s0, s1, acc, stats, should_stop);
}

} // namespace bsdfkit::render
