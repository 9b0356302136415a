// Path tracer of the preview renderer (see render/render.h). The estimator follows pbrt-v4's
// PathIntegrator::Li (Pharr, Jakob, Humphreys, "Physically Based Rendering" 4th ed. sec. 13.4):
//   L = sum over path vertices of beta * (MIS-weighted light sample + MIS-weighted escaped ray),
//   beta *= f |cos| / pdf after each BSDF sample; power heuristic (Veach 1997 sec. 9.2.4).
// It runs as a small wavefront: the paths of kWaveSamples sample indices over a 16 x 16 tile
// advance together, one bounce at a time. Each bounce: Embree traces the rays as 16-wide
// packets; the environment data of all rays is computed in tight loops of its own (alias-table
// sample, texel lookups: memory-bound work whose misses then overlap); every surface hit becomes
// a Vertex (frame, wo, environment sample, uniforms); the vertices are grouped by material and
// each group is shaded through its model's concrete type, on 16-lane packets (f and pdf toward
// the environment sample, f toward the directional light, the BSDF sample) for models with a
// packet path, scalar otherwise (and for Hair on fibres, whose h is per hit); then each path
// queues its shadow rays and its next ray. Every path owns its random stream (drawn in the same
// order as a one-path-at-a-time tracer) and its radiance sum, and a packet lane's result depends
// on its own inputs only, so the image does not depend on how paths are grouped or on threads.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <vector>

#include "bsdfkit/render/render.h"
#include "bsdfkit/render/sampler.h"

namespace bsdfkit::render {

namespace {

inline bool finite_rgb(const RGB &c) {
    return std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
}

constexpr int kTile = 16;
// Sample indices of a tile traced together: one wave holds kTile^2 * kWaveSamples paths, enough
// for each material's hits of a bounce to fill whole packets.
constexpr int kWaveSamples = 4;
constexpr Float kInf = std::numeric_limits<Float>::infinity();

using P = Packet<Float>;
constexpr int kPW = int(kPacketWidth);

struct Path {
    RGB L, beta;
    Float p_b, eta_scale;
    int depth;
    bool specular_bounce;
    SampleRng rng;
    double env_u0;  // uniforms of this vertex's environment sample, drawn first (prepare)
    Float env_u1;
};

// A surface hit of one bounce, between the scalar set-up (pass A), the shading of its material
// group (pass B: packets for models with a packet path) and the path update (pass C).
struct Vertex {
    Hit h;
    Frame fr;
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
    Float uu, vv, cell_prob;
    Vec3f wi;
    RGB le;
    Float pdf;
};

struct Shadow {
    int path;
    RGB contribution;  // added to the path's L when the ray is unoccluded
};

// Scratch of one thread: the paths of a wave and their ray streams.
struct Wave {
    std::vector<Path> paths;
    std::vector<RTCRayHit> rays;
    std::vector<int> ray_path;      // path of each ray in `rays`
    std::vector<Point2<Float>> miss_uv;  // lat-long coordinates of the rays that escaped
    std::vector<EnvRay> env;             // per ray: its environment sample (hits) or radiance (misses)
    std::vector<RTCRayHit> next_rays;
    std::vector<int> next_path;
    std::vector<RTCRay> shadow_rays;
    std::vector<Shadow> shadows;
    std::vector<Vertex> verts;
    std::vector<int> vert_mat;      // material of each vertex
    std::vector<int> group_start, group_items;  // vertices grouped by material (counting sort)
};

// Packet lanes of vertex fields: gathered into aligned SoA rows, padded past cnt.
struct Lanes {
    alignas(64) Float v[10][kPacketWidth];
};

struct Tracer {
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

    // First pass over a bounce's rays: lat-long coordinates of escaped rays, environment-sample
    // uniforms of surface hits.
    void prepare(int pi, const RTCRayHit &rh, Point2<Float> *uv, Wave &w) const {
        Path &path = w.paths[size_t(pi)];
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
            latlong_uv(Vec3f(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z), &uv->x, &uv->y);
        } else {
            path.env_u0 = path.rng.next_double();
            path.env_u1 = path.rng.next();
        }
    }

    // The environment stages of a bounce (see EnvRay), each a loop of its own.
    void environment_pass(Wave &w) const {
        const size_t nr = w.rays.size();
        const Environment &env = scene.env;
        for (size_t k = 0; k < nr; ++k)
            if (w.rays[k].hit.geomID != RTC_INVALID_GEOMETRY_ID) {
                const Path &p = w.paths[size_t(w.ray_path[k])];
                EnvRay &e = w.env[k];
                env.sample_cell(p.env_u0, p.env_u1, &e.uu, &e.vv, &e.cell_prob);
            }
        for (size_t k = 0; k < nr; ++k)
            if (w.rays[k].hit.geomID == RTC_INVALID_GEOMETRY_ID) {
                const RTCRay &r = w.rays[k].ray;
                Vec3f d(r.dir_x, r.dir_y, r.dir_z);
                EnvRay &e = w.env[k];
                e.le = env.eval_uv(d, w.miss_uv[k].x, w.miss_uv[k].y);
                e.pdf = env.pdf_uv_dir(d, w.miss_uv[k].x, w.miss_uv[k].y);
            }
        for (size_t k = 0; k < nr; ++k)
            if (w.rays[k].hit.geomID != RTC_INVALID_GEOMETRY_ID) {
                const Path &p = w.paths[size_t(w.ray_path[k])];
                EnvRay &e = w.env[k];
                e.le = env.sample_finish(p.env_u0, p.env_u1, e.uu, e.vv, e.cell_prob, &e.wi, &e.pdf);
            }
    }

    // Pass A: an escaped ray adds the environment; a surface hit becomes a vertex (frame, wo,
    // environment sample, the uniforms of its BSDF sample).
    void setup(int pi, const RTCRayHit &rh, const EnvRay &er, Wave &w) const {
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
        v.fr = Frame(v.h.n, v.h.tangent);
        v.wo = v.fr.to_local(-d);
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
                v.wl = v.fr.to_local(er.wi);
            }
            if (scene.sun.enabled) v.wsun = v.fr.to_local(scene.sun.dir);
        }
        v.uc = path.rng.next();
        Point2<Float> u = path.rng.next2();
        v.u0 = u.x;
        v.u1 = u.y;
        w.vert_mat.push_back(v.h.material);
    }

    // Pass C: light-sample contributions (shadow rays) and the path's next ray.
    void finish(Vertex &v, Wave &w) const {
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
        Vec3f nd = normalize(v.fr.to_world(v.bs_wi));

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

    // Sample indices [s, s + ns) of every pixel of tile [x0, x1) x [y0, y1); adds to acc in
    // pixel-then-sample order, returns the rays traced.
    int64_t render_tile_wave(int x0, int y0, int x1, int y1, int s, int ns, double *acc, Wave &w, int64_t *bad) const {
        const int W = st.width, H = st.height;
        int64_t rays = 0;
        w.paths.clear();
        w.rays.clear();
        w.ray_path.clear();
        for (int k = 0; k < ns; ++k)
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
                    p.rng = SampleRng(st.seed, pix, uint64_t(s + k));
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
            w.verts.clear();
            w.vert_mat.clear();
            const size_t nr = w.rays.size();
            w.miss_uv.resize(nr);
            w.env.resize(nr);
            for (size_t k = 0; k < nr; ++k) prepare(w.ray_path[k], w.rays[k], &w.miss_uv[k], w);
            environment_pass(w);
            for (size_t k = 0; k < nr; ++k) setup(w.ray_path[k], w.rays[k], w.env[k], w);
            shade(w);
            for (Vertex &v : w.verts) finish(v, w);
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
        // Accumulate in pixel order, each pixel's samples in index order (the per-pixel sum order
        // of one sample per call).
        const int npix = (x1 - x0) * (y1 - y0);
        int k = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x, ++k) {
                double *a = acc + (size_t(y) * size_t(W) + size_t(x)) * 3;
                for (int q = 0; q < ns; ++q) {
                    const RGB &L = w.paths[size_t(q * npix + k)].L;
                    if (!finite_rgb(L)) {
                        ++*bad;
                        continue;
                    }
                    a[0] += double(L[0]);
                    a[1] += double(L[1]);
                    a[2] += double(L[2]);
                }
            }
        (void)H;
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
        for (int s = s0; s < s1; s += kWaveSamples)
            rays += tracer.render_tile_wave(x0, y0, x1, y1, s, std::min(kWaveSamples, s1 - s), acc, w, &bad);
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
