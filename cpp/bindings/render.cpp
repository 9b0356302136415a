// bsdfkit._render: the preview renderer (bsdfkit.render is the public API), image I/O (bsdfkit.io)
// and mesh files; the optional extension that links Embree, OpenImageIO and Assimp, imported on
// first use. Materials arrive as the model objects' `_core` (PyModel<X> of bsdfkit._core) and are
// converted, float precision, into the renderer's variant by _core itself (render_abi.h), so this
// module compiles none of the model bindings. Arrays are validated here too: bad input raises
// ValueError, it never crashes.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "bsdfkit/io.h"
#include "bsdfkit/render/render.h"
#include "bsdfkit/render/spectral.h"
#include "render_abi.h"

namespace py = pybind11;

namespace bsdfkit::py_bind {

void bind_texture(py::module_ &m);   // render_texture.cpp: image textures (OIIO TextureSystem)

using namespace bsdfkit::render;

using V3 = std::array<double, 3>;
template <typename T> using carray = py::array_t<T, py::array::c_style | py::array::forcecast>;

namespace {

[[noreturn]] void value_error(const std::string &msg) { throw py::value_error(msg); }

// _core's table (render_abi.h), checked at import.
const RenderAbi *g_abi = nullptr;

void load_abi() {
    py::object cap = py::module_::import("bsdfkit._core").attr("_render_abi");
    auto *abi = static_cast<const RenderAbi *>(PyCapsule_GetPointer(cap.ptr(), kRenderAbiCapsule));
    if (!abi) throw py::error_already_set();
    if (abi->version != kRenderAbiVersion || abi->material_size != abi_size<Material>() ||
        abi->material_align != abi_align<Material>() || abi->spectral_size != abi_size<SpectralMaterial>() ||
        abi->spectral_align != abi_align<SpectralMaterial>())
        throw py::import_error("bsdfkit._render does not match bsdfkit._core (built from different sources or "
                               "flags): rebuild and reinstall bsdfkit (pip install .)");
    g_abi = abi;
    cap.inc_ref();  // the table is static in _core; keep _core's capsule (and module) alive
}

int num_threads() { return g_abi->num_threads(); }

Material to_material(const py::object &model) {
    py::object core = py::hasattr(model, "_core") ? model.attr("_core") : model;
    Material m;
    if (!g_abi->material(core.ptr(), &m))
        throw py::type_error("material: expected a bsdfkit model, got " + std::string(py::str(py::type::of(model))));
    return m;
}

bool spectral_render_material(const py::handle &h, SpectralMaterial *out) {
    return g_abi->spectral_material(h.ptr(), out);
}

Vec3f to_vec(const V3 &a, const char *name) {
    for (double x : a)
        if (!std::isfinite(x)) value_error(std::string(name) + ": must be finite");
    return Vec3f(Float(a[0]), Float(a[1]), Float(a[2]));
}

RGB to_rgb(const V3 &a, const char *name) {
    RGB c;
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(a[size_t(i)]) || a[size_t(i)] < 0) value_error(std::string(name) + ": must be finite and >= 0");
        c[i] = Float(a[size_t(i)]);
    }
    return c;
}

struct PyScene {
    std::unique_ptr<Scene> scene = std::make_unique<Scene>();
    SpectralScene spec;                  // spectral mode (set_spectral_*; render_spectral)
    std::vector<py::object> spec_keep;   // the spectral models the adapters point into
    bool spec_tables = false, spec_lights = false;

    void check_open() const {
        if (scene->committed()) throw py::value_error("scene: already committed; build a new scene");
    }
    void check_material(int m, const char *name) const {
        if (m < 0 || m >= int(scene->materials.size())) value_error(std::string(name) + ": no such material");
    }
    static Float checker_of(double c) {
        if (!std::isfinite(c) || c < 0) value_error("checker: must be finite and >= 0");
        return Float(c);
    }

    int add_material(const py::object &model) {
        check_open();
        return scene->add_material(to_material(model));
    }

    void add_sphere(const V3 &center, double radius, int mat_a, int mat_b, double checker) {
        check_open();
        Vec3f c = to_vec(center, "center");
        if (!std::isfinite(radius) || !(radius > 0)) value_error("radius: must be finite and > 0");
        check_material(mat_a, "material");
        check_material(mat_b, "checker material");
        std::string err = scene->add_sphere(c, Float(radius), mat_a, mat_b, checker_of(checker));
        if (!err.empty()) throw std::runtime_error(err);
    }

    void add_mesh(const py::array &vertices, const py::array &indices, int mat_a, int mat_b, double checker) {
        check_open();
        carray<float> v = vertices;
        if (v.ndim() != 2 || v.shape(1) != 3) value_error("vertices: expected shape (N, 3)");
        char kind = indices.dtype().kind();
        if (kind != 'i' && kind != 'u') throw py::type_error("indices: expected an integer array");
        carray<int64_t> ix = indices;
        if (ix.ndim() != 2 || ix.shape(1) != 3) value_error("indices: expected shape (M, 3)");
        int64_t nv = v.shape(0), nt = ix.shape(0);
        if (nv == 0 || nt == 0) value_error("mesh: needs at least one vertex and one triangle");
        if (nv > int64_t(UINT32_MAX)) value_error("vertices: too many vertices");
        const float *pv = v.data();
        for (int64_t i = 0; i < nv * 3; ++i)
            if (!std::isfinite(pv[i])) value_error("vertices: contains NaN or Inf (vertex " + std::to_string(i / 3) + ")");
        std::vector<uint32_t> idx(size_t(nt * 3));
        const int64_t *pi = ix.data();
        for (int64_t i = 0; i < nt * 3; ++i) {
            if (pi[i] < 0 || pi[i] >= nv)
                value_error("indices: index " + std::to_string(pi[i]) + " out of range [0, " + std::to_string(nv) +
                            ") in triangle " + std::to_string(i / 3));
            idx[size_t(i)] = uint32_t(pi[i]);
        }
        check_material(mat_a, "material");
        check_material(mat_b, "checker material");
        std::string err = scene->add_mesh(pv, nv, idx.data(), nt, mat_a, mat_b, checker_of(checker));
        if (!err.empty()) throw std::runtime_error(err);
    }

    // Fibres: points (N, 4) control points x, y, z, radius of round Catmull-Rom curves; segments (M,)
    // the first control point of each segment (it uses 4 consecutive points).
    void add_curves(const py::array &points, const py::array &segments, int mat) {
        check_open();
        carray<float> v = points;
        if (v.ndim() != 2 || v.shape(1) != 4) value_error("points: expected shape (N, 4) (x, y, z, radius)");
        char kind = segments.dtype().kind();
        if (kind != 'i' && kind != 'u') throw py::type_error("segments: expected an integer array");
        carray<int64_t> ix = segments;
        if (ix.ndim() != 1) value_error("segments: expected shape (M,)");
        int64_t np = v.shape(0), ns = ix.shape(0);
        if (np < 4 || ns == 0) value_error("curves: need at least 4 control points and one segment");
        if (np > int64_t(UINT32_MAX)) value_error("points: too many control points");
        const float *pv = v.data();
        for (int64_t i = 0; i < np; ++i) {
            for (int k = 0; k < 4; ++k)
                if (!std::isfinite(pv[4 * i + k])) value_error("points: contains NaN or Inf (point " + std::to_string(i) + ")");
            if (!(pv[4 * i + 3] > 0)) value_error("points: radius must be > 0 (point " + std::to_string(i) + ")");
        }
        std::vector<uint32_t> idx(static_cast<size_t>(ns));
        const int64_t *pi = ix.data();
        for (int64_t i = 0; i < ns; ++i) {
            if (pi[i] < 0 || pi[i] + 3 >= np)
                value_error("segments: first point " + std::to_string(pi[i]) + " out of range [0, " +
                            std::to_string(np - 3) + ") in segment " + std::to_string(i));
            idx[size_t(i)] = uint32_t(pi[i]);
        }
        check_material(mat, "material");
        std::string err = scene->add_curves(pv, np, idx.data(), ns, mat);
        if (!err.empty()) throw std::runtime_error(err);
    }

    // The first hit of the ray (origin, direction) and how the renderer shades it, for tests: None on
    // a miss, else a dict with p, the frame (s, t, n: local x, y, z in world space), fibre, h (fibre
    // offset), material, wo (local) and, for world directions wi (K, 3), wi_local (K, 3) and
    // f_cos (K, 3) = f(wo, wi) |cos| of the material as shaded there (the integrator's code path).
    py::object debug_hit(const V3 &origin, const V3 &direction, carray<double> wi) {
        commit();
        if (wi.ndim() != 2 || wi.shape(1) != 3) value_error("wi: expected shape (K, 3)");
        Vec3f o = to_vec(origin, "origin"), d = to_vec(direction, "direction");
        if (!(length_squared(d) > 0)) value_error("direction: must be non-zero");
        d = normalize(d);
        RTCRayHit rh;
        make_rayhit(rh, o, d);
        scene->intersect_n(&rh, 1, false);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return py::none();
        Hit h;
        scene->hit_point(rh, &h);
        Material scratch;
        const Material &m = material_at(*scene, h, &scratch);
        const Frame &fr = h.frame;
        Vec3f wo = fr.to_local(-d);
        int64_t k = wi.shape(0);
        py::array_t<double> wl({k, int64_t(3)}), fc({k, int64_t(3)});
        const double *pw = wi.data();
        double *pl = wl.mutable_data(), *pf = fc.mutable_data();
        for (int64_t i = 0; i < k; ++i) {
            Vec3f w = normalize(Vec3f(Float(pw[3 * i]), Float(pw[3 * i + 1]), Float(pw[3 * i + 2])));
            Vec3f l = fr.to_local(w);
            RGB f = material_f(m, wo, l) * std::abs(l.z);
            for (int c = 0; c < 3; ++c) {
                pl[3 * i + c] = c == 0 ? l.x : (c == 1 ? l.y : l.z);
                pf[3 * i + c] = f[c];
            }
        }
        auto v3 = [](const Vec3f &a) { return py::make_tuple(a.x, a.y, a.z); };
        py::dict r;
        r["p"] = v3(h.p);
        r["s"] = v3(fr.s);
        r["t"] = v3(fr.t);
        r["n"] = v3(fr.n);
        r["fibre"] = h.fibre;
        r["h"] = h.h;
        r["material"] = h.material;
        r["wo"] = v3(wo);
        r["wi_local"] = wl;
        r["f_cos"] = fc;
        return r;
    }

    void set_environment_constant(const V3 &L) { scene->env = Environment::uniform(to_rgb(L, "environment")); }

    void set_environment_latlong(const py::array &img) {
        carray<float> a = img;
        if (a.ndim() != 3 || a.shape(2) != 3) value_error("environment: expected an (H, W, 3) image");
        int h = int(a.shape(0)), w = int(a.shape(1));
        if (h < 1 || w < 1) value_error("environment: empty image");
        const float *p = a.data();
        for (int64_t i = 0; i < int64_t(h) * w * 3; ++i)
            if (!std::isfinite(p[i]) || p[i] < 0) value_error("environment: values must be finite and >= 0");
        py::gil_scoped_release release;
        scene->env = Environment::latlong(p, w, h);
    }

    void set_directional(const V3 &dir, const V3 &E) {
        Vec3f d = to_vec(dir, "direction");
        Float l = std::sqrt(length_squared(d));
        if (!(l > 0)) value_error("direction: must be non-zero");
        scene->sun.enabled = true;
        scene->sun.dir = d / l;
        scene->sun.E = to_rgb(E, "irradiance");
    }

    void commit() {
        if (scene->committed()) return;
        std::string err;
        {
            py::gil_scoped_release release;
            err = scene->commit();
        }
        if (!err.empty()) throw std::runtime_error(err);
    }

    // Spectral mode: material m's spectral model (a _core.<Model>Spectral, kept alive here).
    void set_spectral_material(int m, const py::object &core) {
        check_material(m, "material");
        if (spec.materials.size() < scene->materials.size()) spec.materials.resize(scene->materials.size());
        SpectralMaterial sm;
        if (!spectral_render_material(core, &sm))
            throw py::type_error("material: expected a spectral model (_core.<Model>Spectral), got " +
                                 std::string(py::str(py::type::of(core))));
        spec.materials[size_t(m)] = sm;
        spec_keep.push_back(core);
    }

    static UniformTable table_of(const carray<double> &a, double x0, double step, int ncol, const char *name) {
        if (!(a.ndim() == (ncol == 1 ? 1 : 2)) || a.shape(0) < 2 || (ncol > 1 && a.shape(1) != ncol))
            value_error(std::string(name) + ": wrong shape");
        if (!std::isfinite(x0) || !(step > 0)) value_error(std::string(name) + ": bad grid");
        UniformTable t;
        t.x0 = x0;
        t.step = step;
        t.n = int(a.shape(0));
        t.ncol = ncol;
        t.v.assign(a.data(), a.data() + a.size());
        for (double x : t.v)
            if (!std::isfinite(x)) value_error(std::string(name) + ": must be finite");
        return t;
    }

    // The colour tables: D65 of unit luminance on x0 + k step, and M cmf / integral(y-bar) (n, 3).
    void set_spectral_tables(const carray<double> &d65, double d65_x0, double d65_step, const carray<double> &match,
                             double match_x0, double match_step) {
        spec.d65 = table_of(d65, d65_x0, d65_step, 1, "d65");
        spec.rgb_match = table_of(match, match_x0, match_step, 3, "rgb_match");
        spec_tables = true;
    }

    static Uplifted uplifted(const double *c, const char *name) {
        if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || std::isnan(c[2]) || !std::isfinite(c[3]) || c[3] < 0)
            value_error(std::string(name) + ": bad sigmoid coefficients");
        return Uplifted{c[0], c[1], c[2], c[3]};
    }

    // The uplifted lights: (c0, c1, c2, scale) of the constant environment and of the sun, and
    // for a lat-long environment its texels' (H, W, 4) (None for a constant environment).
    void set_spectral_lights(const carray<double> &constant, const carray<double> &sun, const py::object &texels) {
        if (constant.size() != 4 || sun.size() != 4) value_error("lights: expected 4 coefficients each");
        spec.constant_env = uplifted(constant.data(), "environment");
        spec.sun = uplifted(sun.data(), "irradiance");
        spec.width = spec.height = 0;
        spec.texels.clear();
        if (!texels.is_none()) {
            carray<double> t = texels;
            const Environment &env = scene->env;
            if (env.constant || t.ndim() != 3 || t.shape(0) != env.height || t.shape(1) != env.width || t.shape(2) != 4)
                value_error("texels: expected (H, W, 4) for the scene's lat-long environment");
            int w = env.width, h = env.height;
            spec.texels.resize(size_t(w + 1) * size_t(h));
            const double *p = t.data();
            for (int y = 0; y < h; ++y)
                for (int x = 0; x <= w; ++x)
                    spec.texels[size_t(y) * size_t(w + 1) + size_t(x)] =
                        uplifted(p + (size_t(y) * size_t(w) + size_t(x % w)) * 4, "texels");
            spec.width = w;
            spec.height = h;
        } else if (!scene->env.constant) {
            value_error("texels: the scene's environment is a lat-long image: its texels are needed");
        }
        spec_lights = true;
    }

    // Adds samples [s0, s1) to acc (H, W, 3) float64. Returns (completed, rays, nonfinite); a
    // pending KeyboardInterrupt (Ctrl-C) stops the pass early and is re-raised. spectral: the
    // spectral tracer (render/spectral.h), its materials, tables and lights set before.
    py::tuple render_impl(const V3 &origin, const V3 &target, const V3 &up, double fov, int max_depth, uint64_t seed,
                          int s0, int s1, py::array_t<double> acc, bool spectral) {
        commit();
        if (!(acc.flags() & py::array::c_style) || !acc.writeable() || acc.ndim() != 3 || acc.shape(2) != 3)
            value_error("acc: expected a writable C-contiguous (H, W, 3) float64 array");
        RenderSettings st;
        st.height = int(acc.shape(0));
        st.width = int(acc.shape(1));
        if (st.width < 1 || st.height < 1) value_error("width, height: must be >= 1");
        if (max_depth < 0) value_error("max_depth: must be >= 0");
        if (s0 < 0 || s1 < s0) value_error("samples: bad range");
        if (!(fov > 0 && fov < 180)) value_error("fov: must be in (0, 180) degrees");
        Vec3f o = to_vec(origin, "origin"), t = to_vec(target, "target"), u = to_vec(up, "up");
        Vec3f fwd = t - o;
        if (!(length_squared(fwd) > 0)) value_error("target: must differ from origin");
        if (!(length_squared(cross(normalize(fwd), u)) > Float(1e-12))) value_error("up: must not be parallel to the view direction");
        if (spectral) {
            if (!spec_tables || !spec_lights) value_error("spectral: the tables and lights are not set");
            if (spec.materials.size() < scene->materials.size()) spec.materials.resize(scene->materials.size());
            for (size_t m = 0; m < scene->materials.size(); ++m)
                if (std::holds_alternative<std::monostate>(spec.materials[m]))
                    value_error("material " + std::to_string(m) + ": has no spectral model");
            if (spec.width != (scene->env.constant ? 0 : scene->env.width))
                value_error("texels: do not match the scene's environment");
        }
        Camera cam = Camera::look_at(o, t, u, Float(fov));
        st.max_depth = max_depth;
        st.seed = seed;
        st.threads = num_threads();
        RenderStats stats;
        bool interrupted = false;
        bool done;
        double *pacc = acc.mutable_data();
        {
            py::gil_scoped_release release;
            auto should_stop = [&interrupted]() {
                py::gil_scoped_acquire gil;
                if (PyErr_CheckSignals() != 0) interrupted = true;
                return interrupted;
            };
            done = spectral ? render_samples_spectral(*scene, spec, cam, st, s0, s1, pacc, &stats, should_stop)
                            : render_samples(*scene, cam, st, s0, s1, pacc, &stats, should_stop);
        }
        if (interrupted) throw py::error_already_set();
        return py::make_tuple(done, stats.rays, stats.nonfinite);
    }
    py::tuple render(const V3 &origin, const V3 &target, const V3 &up, double fov, int max_depth, uint64_t seed,
                     int s0, int s1, py::array_t<double> acc) {
        return render_impl(origin, target, up, fov, max_depth, seed, s0, s1, acc, false);
    }
    py::tuple render_spectral(const V3 &origin, const V3 &target, const V3 &up, double fov, int max_depth,
                              uint64_t seed, int s0, int s1, py::array_t<double> acc) {
        return render_impl(origin, target, up, fov, max_depth, seed, s0, s1, acc, true);
    }

    // Environment sampling, exposed for tests: u (N, 2) -> (wi (N, 3), pdf (N,), L (N, 3)).
    py::tuple env_sample(carray<double> u) const {
        if (u.ndim() != 2 || u.shape(1) != 2) value_error("u: expected shape (N, 2)");
        int64_t n = u.shape(0);
        py::array_t<float> wi({n, int64_t(3)}), pdf({n}), L({n, int64_t(3)});
        const double *pu = u.data();
        float *pw = wi.mutable_data(), *pp = pdf.mutable_data(), *pl = L.mutable_data();
        for (int64_t i = 0; i < n; ++i) {
            Vec3f w;
            Float p;
            double u0 = clamp(pu[2 * i], 0.0, 0x1.fffffffffffffp-1);
            Float u1 = Float(clamp(pu[2 * i + 1], 0.0, double(0x1.fffffep-1f)));
            RGB c = scene->env.sample(u0, u1, &w, &p);
            pw[3 * i] = w.x, pw[3 * i + 1] = w.y, pw[3 * i + 2] = w.z;
            pp[i] = p;
            for (int c3 = 0; c3 < 3; ++c3) pl[3 * i + c3] = c[c3];
        }
        return py::make_tuple(wi, pdf, L);
    }

    py::tuple env_eval_pdf(carray<float> dirs) const {
        if (dirs.ndim() != 2 || dirs.shape(1) != 3) value_error("dirs: expected shape (N, 3)");
        int64_t n = dirs.shape(0);
        py::array_t<float> pdf({n}), L({n, int64_t(3)});
        const float *pd = dirs.data();
        float *pp = pdf.mutable_data(), *pl = L.mutable_data();
        for (int64_t i = 0; i < n; ++i) {
            Vec3f d(pd[3 * i], pd[3 * i + 1], pd[3 * i + 2]);
            Float l2 = length_squared(d);
            if (!(l2 > 0) || !std::isfinite(l2)) value_error("dirs: must be finite and non-zero");
            d = d / std::sqrt(l2);
            pp[i] = scene->env.pdf(d);
            RGB c = scene->env.eval(d);
            for (int c3 = 0; c3 < 3; ++c3) pl[3 * i + c3] = c[c3];
        }
        return py::make_tuple(pdf, L);
    }
};

} // namespace

static void bind_render(py::module_ &m) {
    py::class_<PyScene>(m, "RenderScene")
        .def(py::init<>())
        .def("add_material", &PyScene::add_material)
        .def("add_sphere", &PyScene::add_sphere)
        .def("add_mesh", &PyScene::add_mesh)
        .def("add_curves", &PyScene::add_curves)
        .def("debug_hit", &PyScene::debug_hit)
        .def("set_environment_constant", &PyScene::set_environment_constant)
        .def("set_environment_latlong", &PyScene::set_environment_latlong)
        .def("set_directional", &PyScene::set_directional)
        .def("commit", &PyScene::commit)
        .def("render", &PyScene::render)
        .def("set_spectral_material", &PyScene::set_spectral_material)
        .def("set_spectral_tables", &PyScene::set_spectral_tables)
        .def("set_spectral_lights", &PyScene::set_spectral_lights)
        .def("render_spectral", &PyScene::render_spectral)
        .def("env_sample", &PyScene::env_sample)
        .def("env_eval_pdf", &PyScene::env_eval_pdf)
        .def_property_readonly("num_objects", [](const PyScene &s) { return s.scene->objects.size(); });

    m.def("load_mesh", [](const std::string &path) {
        std::vector<Float> v;
        std::vector<uint32_t> ix;
        std::string err;
        {
            py::gil_scoped_release release;
            err = load_mesh(path, &v, &ix);
        }
        if (!err.empty()) throw std::runtime_error(err);
        py::array_t<float> va({int64_t(v.size() / 3), int64_t(3)});
        py::array_t<int64_t> ia({int64_t(ix.size() / 3), int64_t(3)});
        std::copy(v.begin(), v.end(), va.mutable_data());
        std::copy(ix.begin(), ix.end(), ia.mutable_data());
        return py::make_tuple(va, ia);
    });
}

} // namespace bsdfkit::py_bind

using namespace bsdfkit;

PYBIND11_MODULE(_render, m) {
    m.doc() = "bsdfkit renderer and image I/O (Embree, OpenImageIO); use bsdfkit.render / bsdfkit.io";
    py_bind::load_abi();
    py_bind::bind_render(m);
    py_bind::bind_texture(m);

    m.def("read_image", [](const std::string &path) {
        io::Image img;
        std::string err;
        {
            py::gil_scoped_release release;
            err = io::read_image(path, img);
        }
        if (!err.empty()) throw std::runtime_error(err);
        py::array_t<float> a({img.height, img.width, img.channels});
        std::copy(img.pixels.begin(), img.pixels.end(), a.mutable_data());
        return a;
    });
    m.def("write_image", [](const std::string &path, py::array_t<float, py::array::c_style | py::array::forcecast> a) {
        if (a.ndim() != 3) throw py::value_error("img: expected an (H, W, C) array");
        int h = int(a.shape(0)), w = int(a.shape(1)), c = int(a.shape(2));
        std::string err;
        {
            py::gil_scoped_release release;
            err = io::write_image(path, a.data(), w, h, c);
        }
        if (!err.empty()) throw std::runtime_error(err);
    });
    m.def("embree_version", &io::embree_version);
    m.def("openimageio_version", &io::openimageio_version);
}
