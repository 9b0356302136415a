// Path tracer of the preview renderer (see render/render.h). The estimator follows pbrt-v4's
// PathIntegrator::Li (Pharr, Jakob, Humphreys, "Physically Based Rendering" 4th ed. sec. 13.4):
//   L = sum over path vertices of beta * (MIS-weighted light sample + MIS-weighted escaped ray),
//   beta *= f |cos| / pdf after each BSDF sample; power heuristic (Veach 1997 sec. 9.2.4).
// It runs in the wavefront loop shared with the spectral tracer (render/wavefront.h): the paths
// of kWaveSamples sample indices over a 16 x 16 tile advance together, one bounce at a time.
// Each bounce: Embree traces the rays as 16-wide packets; the environment data of all rays is
// computed in passes of its own (the alias-table walk in a tight scalar loop, memory-bound work
// whose misses then overlap; lat-long coordinates, texel lookups, directions and pdfs on 16-lane
// packets, lane by lane the scalar arithmetic); every surface hit becomes
// a Vertex (frame, wo, environment sample, uniforms); the vertices are grouped by material and
// each group is shaded through its model's concrete type, on 16-lane packets (f and pdf toward
// the environment sample, f toward the directional light, the BSDF sample) for models with a
// packet path, scalar otherwise (and for Hair on fibres, whose h is per hit); then each path
// queues its shadow rays and its next ray. Every path owns its random stream (drawn in the same
// order as a one-path-at-a-time tracer) and its radiance sum, and a packet lane's result depends
// on its own inputs only, so the image does not depend on how paths are grouped or on threads.
#include <algorithm>
#include <cmath>
#include <vector>

#include "bsdfkit/render/render.h"
#include "bsdfkit/render/sampler.h"
#include "bsdfkit/render/wavefront.h"

namespace bsdfkit::render {

namespace {

inline bool finite_rgb(const RGB &c) {
    return std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
}

constexpr Float kInf = std::numeric_limits<Float>::infinity();

using P = Packet<Float>;
constexpr int kPW = int(kPacketWidth);

struct Path {
    RGB L, beta;
    Float p_b, eta_scale;
    int depth;
    bool specular_bounce;
    SampleRng rng;
};

// A surface hit of one bounce, between the scalar set-up (pass A), the shading of its material
// group (pass B: packets for models with a packet path) and the path update (pass C).
struct Vertex {
    Hit h;           // h.frame: the shading frame
    Vec3f wo;        // local
    Vec3f wl;        // environment sample direction, local ((0, 0, 1) when there is none)
    Vec3f wi_env;    // the same, world
    RGB le;          // its radiance (black: no environment sample)
    Float p_l;
    Vec3f wsun;      // directional light, local
    Float uc, u0, u1;
    int path;
    bool nonspecular;
    // pass B results
    RGB f_env, f_sun;  // f |cos| toward the environment sample and the directional light
    Float pdf_env;     // BSDF pdf of the environment sample's direction
    RGB bs_f;
    Vec3f bs_wi;
    Float bs_pdf, bs_eta, p_b;  // p_b: pdf for MIS (pdf() when the sample's pdf is proportional)
    uint8_t bs_flags;
    bool bs_valid;
};

// Environment data of one ray of a bounce, computed in tight loops over the bounce before the
// per-hit set-up (their table and texel cache misses then overlap): for a surface hit the
// environment sample of its vertex, for an escaped ray the radiance and pdf of its direction.
struct EnvRay {
    Vec3f wi;
    RGB le;
    Float pdf;
};

// Scratch of one thread: the paths of a wave, their ray streams (WaveBase) and the per-bounce data.
struct Wave : WaveBase<Path, RGB> {
    std::vector<EnvRay> env;             // per ray: its environment sample (hits) or radiance (misses)
    std::vector<int> hit_rays, miss_rays;  // indices of the rays that hit a surface / escaped
    std::vector<double> env_u0;  // per hit ray (hit_rays order, padded to packets): the uniforms of
    std::vector<Float> env_u1;   // its environment sample, drawn first
    ScratchVector<Vertex> verts;
    std::vector<int> vert_mat;      // material of each vertex
    std::vector<int> group_start, group_items;  // vertices grouped by material (counting sort)
};

// Packet lanes of vertex fields: gathered into aligned SoA rows, padded past cnt.
struct Lanes {
    alignas(64) Float v[10][kPacketWidth];
};

struct Tracer {
    using Path = render::Path;
    using Wave = render::Wave;
    const Scene &scene;
    const Camera &camera;
    const RenderSettings &st;

    // ---- pass B: the shading of one material's vertices ----

    // One vertex on the scalar path (models without a packet path; fibres of hair models).
    template <typename M> void shade_one(const M &b, Vertex &v) const {
        if (v.nonspecular) {
            v.f_env = RGB(Float(0));
            v.pdf_env = 0;
            if (!v.le.is_black()) {
                v.f_env = bsdf_f(b, v.wo, v.wl, kMode) * std::abs(v.wl.z);
                if (!v.f_env.is_black()) v.pdf_env = bsdf_pdf(b, v.wo, v.wl, kMode, uint8_t(RT_All));
            }
            if (scene.sun.enabled) v.f_sun = bsdf_f(b, v.wo, v.wsun, kMode) * std::abs(v.wsun.z);
        }
        BSDFSample<Float> bs = bsdf_sample(b, v.wo, v.uc, Point2<Float>{v.u0, v.u1}, kMode, uint8_t(RT_All));
        v.bs_valid = bs.valid;
        v.bs_f = bs.f;
        v.bs_wi = bs.wi;
        v.bs_pdf = bs.pdf;
        v.bs_eta = bs.eta;
        v.bs_flags = bs.flags;
        // Layered-style samples only know their pdf up to a factor: ask pdf() for MIS.
        v.p_b = bs.valid && bs.pdf_is_proportional ? bsdf_pdf(b, v.wo, bs.wi, kMode, uint8_t(RT_All)) : bs.pdf;
    }

    // The vertices items[0, n) of one material with a packet path: kPacketWidth lanes at a time,
    // the tail padded (wo = wi = (0, 0, 1), uniforms 0) through the same code, so every lane's
    // result depends on its own inputs only (not on how hits were grouped).
    template <typename M> void shade_packets(const M &model, const int *items, int n, Wave &w) const {
        const KernelOf_t<M> b = model;
        const bool nonspec = has_nonspecular(b.flags());
        const bool sun = scene.sun.enabled;
        const Mask<P> model_ok((b.flags() & uint8_t(RT_All)) != 0);
        Lanes in, out;
        for (int i0 = 0; i0 < n; i0 += kPW) {
            int cnt = std::min(kPW, n - i0);
            for (int j = 0; j < kPW; ++j) {
                if (j < cnt) {
                    const Vertex &v = w.verts[size_t(items[i0 + j])];
                    in.v[0][j] = v.wo.x, in.v[1][j] = v.wo.y, in.v[2][j] = v.wo.z;
                    in.v[3][j] = v.wl.x, in.v[4][j] = v.wl.y, in.v[5][j] = v.wl.z;
                    in.v[6][j] = v.uc, in.v[7][j] = v.u0, in.v[8][j] = v.u1;
                } else {
                    in.v[0][j] = 0, in.v[1][j] = 0, in.v[2][j] = 1;
                    in.v[3][j] = 0, in.v[4][j] = 0, in.v[5][j] = 1;
                    in.v[6][j] = 0, in.v[7][j] = 0, in.v[8][j] = 0;
                }
            }
            auto ld = [&](int r) { return drjit::load_aligned<P>(in.v[r]); };
            Vec3<P> wo(ld(0), ld(1), ld(2));
            if (nonspec) {
                Vec3<P> wl(ld(3), ld(4), ld(5));
                Spectrum<P> fe = bsdf_f(b, wo, wl, kMode);
                P pe = bsdf_pdf(b, wo, wl, kMode, uint8_t(RT_All));
                P c = abs(wl.z);
                for (int k = 0; k < 3; ++k) drjit::store_aligned(out.v[k], fe[k] * c);
                drjit::store_aligned(out.v[3], pe);
                for (int j = 0; j < cnt; ++j) {
                    Vertex &v = w.verts[size_t(items[i0 + j])];
                    // a lane without an environment sample (le black) keeps f = 0, as the scalar path
                    bool has = !v.le.is_black();
                    for (int k = 0; k < 3; ++k) v.f_env[k] = has ? out.v[k][j] : Float(0);
                    v.pdf_env = has ? out.v[3][j] : Float(0);
                }
                if (sun) {
                    for (int j = 0; j < kPW; ++j) {
                        const Vertex &v = w.verts[size_t(items[i0 + std::min(j, cnt - 1)])];
                        in.v[3][j] = j < cnt ? v.wsun.x : Float(0);
                        in.v[4][j] = j < cnt ? v.wsun.y : Float(0);
                        in.v[5][j] = j < cnt ? v.wsun.z : Float(1);
                    }
                    Vec3<P> ws(ld(3), ld(4), ld(5));
                    Spectrum<P> fs = bsdf_f(b, wo, ws, kMode);
                    P cs = abs(ws.z);
                    for (int k = 0; k < 3; ++k) drjit::store_aligned(out.v[k], fs[k] * cs);
                    for (int j = 0; j < cnt; ++j) {
                        Vertex &v = w.verts[size_t(items[i0 + j])];
                        for (int k = 0; k < 3; ++k) v.f_sun[k] = out.v[k][j];
                    }
                }
            }
            // bsdf_sample's rules (core/bsdf.h) on packets, as batch.h's sample kernel.
            BSDFSample<P> s = b.sample_f(wo, clamp_uniform(ld(6)), clamp_uniform(Point2<P>{ld(7), ld(8)}), kMode,
                                         uint8_t(RT_All));
            Mask<P> ok = sample_accepted(s, wo) & model_ok;
            P pdf = select(ok, s.pdf, P(0));
            P p_b = pdf;
            Mask<P> prop = ok & s.pdf_is_proportional;
            if (drjit::any(prop)) p_b = select(prop, bsdf_pdf(b, wo, select(ok, s.wi, kInvalidSampleWi<P>()), kMode,
                                                               uint8_t(RT_All)), pdf);
            Spectrum<P> f = select(ok, s.f, Spectrum<P>(P(0)));
            Vec3<P> wi = select(ok, s.wi, kInvalidSampleWi<P>());
            for (int k = 0; k < 3; ++k) drjit::store_aligned(out.v[k], f[k]);
            drjit::store_aligned(out.v[3], wi.x);
            drjit::store_aligned(out.v[4], wi.y);
            drjit::store_aligned(out.v[5], wi.z);
            drjit::store_aligned(out.v[6], pdf);
            drjit::store_aligned(out.v[7], select(ok, s.eta, P(1)));
            drjit::store_aligned(out.v[8], p_b);
            drjit::store_aligned(out.v[9], select(ok, P(s.flags), P(0)));
            for (int j = 0; j < cnt; ++j) {
                Vertex &v = w.verts[size_t(items[i0 + j])];
                for (int k = 0; k < 3; ++k) v.bs_f[k] = out.v[k][j];
                v.bs_wi = Vec3f(out.v[3][j], out.v[4][j], out.v[5][j]);
                v.bs_pdf = out.v[6][j];
                v.bs_eta = out.v[7][j];
                v.p_b = out.v[8][j];
                v.bs_flags = uint8_t(int(out.v[9][j]));
                v.bs_valid = v.bs_pdf > Float(0);  // exactly bsdf_sample's rule (an invalid sample has pdf 0)
            }
        }
    }

    template <typename M> void shade_group(const M &b, const int *items, int n, Wave &w) const {
        const DenormalsFlushedFor<M> ftz; // Hair: FTZ | DAZ, as its batch kernels (core/simd.h)
        if constexpr (std::is_same_v<M, HairBxDF<Float>>) {
            // h comes from each fibre hit (material_at)
            for (int i = 0; i < n; ++i) {
                Vertex &v = w.verts[size_t(items[i])];
                if (v.h.fibre) {
                    HairBxDF<Float> bh = b;
                    bh.set_h(double(v.h.h));
                    shade_one(bh, v);
                } else {
                    shade_one(b, v);
                }
            }
        } else if constexpr (is_vectorized<M>::value) {
            shade_packets(b, items, n, w);
        } else {
            const KernelOf_t<M> bl = b;
            for (int i = 0; i < n; ++i) shade_one(bl, w.verts[size_t(items[i])]);
        }
    }

    // ---- passes A and C ----

    // The environment passes of a bounce (see EnvRay). Surface hits draw their environment
    // sample's uniforms first (every hit, as a one-path-at-a-time tracer would); then the
    // alias-table walk, the lat-long arithmetic and the texel lookups of the samples, and those
    // of escaped rays, run on packets (the tails padded, lanes independent; gathers let the
    // table and texel cache misses of 16 lanes overlap), lane by lane the scalar functions of
    // Environment.
    void environment_pass(Wave &w) const {
        const size_t nr = w.rays.size();
        const Environment &env = scene.env;
        w.hit_rays.clear();
        w.miss_rays.clear();
        w.env_u0.clear();
        w.env_u1.clear();
        for (size_t k = 0; k < nr; ++k) {
            if (w.rays[k].hit.geomID == RTC_INVALID_GEOMETRY_ID) {
                w.miss_rays.push_back(int(k));
            } else {
                Path &path = w.paths[size_t(w.ray_path[k])];
                w.env_u0.push_back(path.rng.next_double());
                w.env_u1.push_back(path.rng.next());
                w.hit_rays.push_back(int(k));
            }
        }
        if (env.constant || env.cells.empty()) {
            for (int k : w.miss_rays) {
                const RTCRay &r = w.rays[size_t(k)].ray;
                Vec3f d(r.dir_x, r.dir_y, r.dir_z);
                Float u = 0, v = 0;
                if (!env.constant) latlong_uv(d, &u, &v);
                w.env[size_t(k)].le = env.eval_uv(d, u, v);
                w.env[size_t(k)].pdf = env.pdf_uv_dir(d, u, v);
            }
            for (size_t i = 0; i < w.hit_rays.size(); ++i) {
                EnvRay &e = w.env[size_t(w.hit_rays[i])];
                e.le = env.sample(w.env_u0[i], w.env_u1[i], &e.wi, &e.pdf);
            }
            return;
        }
        using I = Environment::IntOf<P>;
        alignas(64) Float a[4][kPacketWidth];
        // escaped rays: radiance and pdf of their direction
        const int nm = int(w.miss_rays.size());
        for (int i0 = 0; i0 < nm; i0 += kPW) {
            int cnt = std::min(kPW, nm - i0);
            for (int j = 0; j < kPW; ++j) {
                const RTCRay &r = w.rays[size_t(w.miss_rays[size_t(i0 + std::min(j, cnt - 1))])].ray;
                a[0][j] = r.dir_x, a[1][j] = r.dir_y, a[2][j] = r.dir_z;
            }
            Vec3<P> d(drjit::load_aligned<P>(a[0]), drjit::load_aligned<P>(a[1]), drjit::load_aligned<P>(a[2]));
            Spectrum<P> le;
            P pdf;
            env.eval_pdf(d, &le, &pdf);
            for (int k = 0; k < 3; ++k) drjit::store_aligned(a[k], le[k]);
            drjit::store_aligned(a[3], pdf);
            for (int j = 0; j < cnt; ++j) {
                EnvRay &e = w.env[size_t(w.miss_rays[size_t(i0 + j)])];
                for (int k = 0; k < 3; ++k) e.le[k] = a[k][j];
                e.pdf = a[3][j];
            }
        }
        // surface hits: their environment sample (cell, direction, pdf, radiance)
        using D = drjit::float64_array_t<P>;
        const int nh = int(w.hit_rays.size());
        if (nh > 0) {  // the tail padded with copies of the last hit's uniforms
            w.env_u0.resize(size_t((nh + kPW - 1) / kPW * kPW), w.env_u0.back());
            w.env_u1.resize(w.env_u0.size(), w.env_u1.back());
        }
        for (int i0 = 0; i0 < nh; i0 += kPW) {
            int cnt = std::min(kPW, nh - i0);
            P uu, vv;
            I texel;
            env.sample_cell(drjit::load<D>(&w.env_u0[size_t(i0)]), drjit::load<P>(&w.env_u1[size_t(i0)]), &uu, &vv,
                            &texel);
            Vec3<P> wi;
            P pdf;
            Spectrum<P> le = env.sample_finish(uu, vv, texel, &wi, &pdf);
            alignas(64) Float o[7][kPacketWidth];
            for (int k = 0; k < 3; ++k) drjit::store_aligned(o[k], le[k]);
            drjit::store_aligned(o[3], wi.x);
            drjit::store_aligned(o[4], wi.y);
            drjit::store_aligned(o[5], wi.z);
            drjit::store_aligned(o[6], pdf);
            for (int j = 0; j < cnt; ++j) {
                EnvRay &e = w.env[size_t(w.hit_rays[size_t(i0 + j)])];
                for (int k = 0; k < 3; ++k) e.le[k] = o[k][j];
                e.wi = Vec3f(o[3][j], o[4][j], o[5][j]);
                e.pdf = o[6][j];
            }
        }
    }

    // Pass A: an escaped ray adds the environment; a surface hit becomes a vertex (frame, wo,
    // environment sample, the uniforms of its BSDF sample). flatten (also on finish): GCC left
    // dot, Frame::to_local and make_spawn_ray as calls in these loops; inlined, a render of
    // bench/render.py's scene takes 11 % less time (same image bits).
    __attribute__((flatten)) void setup(int pi, const RTCRayHit &rh, const EnvRay &er, Wave &w) const {
        Path &path = w.paths[size_t(pi)];
        Vec3f d(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
            // Escaped: environment radiance, MIS-weighted unless only BSDF sampling could have
            // produced this direction (camera ray or a delta lobe).
            if (path.depth == 0 || path.specular_bounce) path.L = path.L + path.beta * er.le;
            else path.L = path.L + path.beta * er.le * power_heuristic(path.p_b, er.pdf);
            return;
        }
        if (path.depth++ == st.max_depth) return;
        w.verts.emplace_back();
        Vertex &v = w.verts.back();
        scene.hit_point(rh, &v.h);
        uint8_t flags = scene.flags[size_t(v.h.material)];
        if (flags == Unset) {
            w.verts.pop_back();
            return;
        }
        v.path = pi;
        v.wo = v.h.frame.to_local(-d);
        v.nonspecular = has_nonspecular(flags);
        v.le = RGB(Float(0));
        v.p_l = 0;
        v.wl = Vec3f(0, 0, 1);
        v.f_env = v.f_sun = RGB(Float(0));
        v.pdf_env = 0;
        if (v.nonspecular) {
            // Direct light: one environment sample MIS-weighted against BSDF sampling, plus the
            // directional light (a delta: light sampling only).
            if (er.pdf > Float(0) && !er.le.is_black()) {
                v.le = er.le;
                v.p_l = er.pdf;
                v.wi_env = er.wi;
                v.wl = v.h.frame.to_local(er.wi);
            }
            if (scene.sun.enabled) v.wsun = v.h.frame.to_local(scene.sun.dir);
        }
        v.uc = path.rng.next();
        Point2<Float> u = path.rng.next2();
        v.u0 = u.x;
        v.u1 = u.y;
        w.vert_mat.push_back(v.h.material);
    }

    // Pass C: light-sample contributions (shadow rays) and the path's next ray.
    __attribute__((flatten)) void finish(Vertex &v, Wave &w) const {
        const int pi = v.path;
        Path &path = w.paths[size_t(pi)];
        if (v.nonspecular) {
            if (!v.f_env.is_black()) {
                w.shadows.push_back({pi, path.beta * v.f_env * v.le * (power_heuristic(v.p_l, v.pdf_env) / v.p_l)});
                w.shadow_rays.emplace_back();
                make_spawn_ray(w.shadow_rays.back(), v.h, v.wi_env, kInf);
            }
            if (scene.sun.enabled && !v.f_sun.is_black()) {
                w.shadows.push_back({pi, path.beta * v.f_sun * scene.sun.E});
                w.shadow_rays.emplace_back();
                make_spawn_ray(w.shadow_rays.back(), v.h, scene.sun.dir, kInf);
            }
        }
        if (!v.bs_valid) return;
        path.beta = path.beta * v.bs_f * (std::abs(v.bs_wi.z) / v.bs_pdf);
        path.p_b = v.p_b;
        path.specular_bounce = (v.bs_flags & Specular) != 0;
        if ((v.bs_flags & Transmission) != 0) path.eta_scale *= sqr(v.bs_eta);
        Vec3f nd = normalize(v.h.frame.to_world(v.bs_wi));

        // Russian roulette on the throughput without the radiance 1/eta^2 scaling.
        RGB rr = path.beta * path.eta_scale;
        Float mx = rr.max_component();
        if (mx < Float(1) && path.depth > 1) {
            Float q = max_(Float(0), Float(1) - mx);
            if (path.rng.next() < q) return;
            path.beta = path.beta / (Float(1) - q);
        }
        w.next_rays.emplace_back();
        make_spawn_rayhit(w.next_rays.back(), v.h, nd);
        w.next_path.push_back(pi);
    }

    // Pass B: the vertices grouped by material (counting sort, vertex order kept within a
    // group), each group shaded through its model's concrete type.
    void shade(Wave &w) const {
        const int nm = int(scene.materials.size()), nv = int(w.verts.size());
        w.group_start.assign(size_t(nm + 1), 0);
        for (int m : w.vert_mat) ++w.group_start[size_t(m + 1)];
        for (int m = 0; m < nm; ++m) w.group_start[size_t(m + 1)] += w.group_start[size_t(m)];
        w.group_items.resize(size_t(nv));
        {
            std::vector<int> &pos = w.next_path;  // scratch: filled only after shading
            pos.assign(w.group_start.begin(), w.group_start.end() - 1);
            for (int i = 0; i < nv; ++i) w.group_items[size_t(pos[size_t(w.vert_mat[size_t(i)])]++)] = i;
            pos.clear();
        }
        for (int m = 0; m < nm; ++m) {
            int b = w.group_start[size_t(m)], e = w.group_start[size_t(m + 1)];
            if (b == e) continue;
            const int *items = w.group_items.data() + b;
            std::visit([&](const auto &model) { shade_group(model, items, e - b, w); }, scene.materials[size_t(m)]);
        }
    }

    // ---- the wavefront loop's hooks (wavefront.h) ----
    void start(Path &p) const {
        p.L = RGB(Float(0));
        p.beta = RGB(Float(1));
        p.p_b = 1;
        p.eta_scale = 1;
        p.depth = 0;
        p.specular_bounce = false;
    }
    void bounce(Wave &w) const {
        w.verts.clear();
        w.vert_mat.clear();
        const size_t nr = w.rays.size();
        w.env.resize(nr);
        environment_pass(w);
        for (size_t k = 0; k < nr; ++k) setup(w.ray_path[k], w.rays[k], w.env[k], w);
        shade(w);
        for (Vertex &v : w.verts) finish(v, w);
    }
    bool pixel_value(const Path &p, double *rgb) const {
        if (!finite_rgb(p.L)) return false;
        for (int c = 0; c < 3; ++c) rgb[c] = double(p.L[c]);
        return true;
    }
};

} // namespace

bool render_samples(const Scene &scene, const Camera &camera, const RenderSettings &st, int s0, int s1, double *acc,
                    RenderStats *stats, const std::function<bool()> &should_stop) {
    return render_tiles(Tracer{scene, camera, st}, scene, camera, st, s0, s1, acc, stats, should_stop);
}

} // namespace bsdfkit::render
