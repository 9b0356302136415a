// bsdfkit._render texture functions: image textures through OpenImageIO's TextureSystem (tiled,
// MIP-mapped, filtered lookups with wrap modes). bsdfkit.textures is the public API; it passes
// checked, contiguous arrays, so this file only converts, runs the lookups in parallel and turns
// OIIO's errors into Python exceptions.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>

#include <atomic>
#include <mutex>
#include <string>

namespace py = pybind11;

namespace bsdfkit::py_bind {

namespace {

// One shared TextureSystem for the process (its ImageCache is shared with OIIO's default one).
// automip: an untiled, un-MIP-mapped file is MIP-mapped in the cache on first use, so a plain PNG
// gets the same filters as a .tx file; autotile: big scanline images are cached in tiles.
OIIO::TextureSystem *texsys() {
    static OIIO::TextureSystem *ts = [] {
        OIIO::TextureSystem *t = OIIO::TextureSystem::create(true);
        t->attribute("automip", 1);
        t->attribute("autotile", 64);
        // stored colours: not multiplied by alpha (bk.io.read_image reads them the same way)
        t->attribute("unassociatedalpha", 1);
        return t;
    }();
    return ts;
}

[[noreturn]] void os_error(const std::string &msg) {
    PyErr_SetString(PyExc_OSError, msg.c_str());
    throw py::error_already_set();
}

// (width, height, channels, format) of an image file, from its header only.
py::tuple image_info(const std::string &path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) os_error(path + ": cannot read the image: " + OIIO::geterror());
    const OIIO::ImageSpec &s = in->spec();
    py::tuple r = py::make_tuple(s.width, s.height, s.nchannels, s.format.c_str());
    in->close();
    return r;
}

// Writes pixels (H, W, C) float32 as a tiled, MIP-mapped float texture file (OIIO make_texture,
// box-filtered MIP levels), the form the TextureSystem reads fastest.
void make_texture(const std::string &path, py::array_t<float, py::array::c_style> px) {
    if (px.ndim() != 3) throw py::value_error("pixels: expected an (H, W, C) array");
    OIIO::ImageSpec spec(int(px.shape(1)), int(px.shape(0)), int(px.shape(2)), OIIO::TypeDesc::FLOAT);
    OIIO::ImageBuf buf(spec, const_cast<float *>(px.data()));
    OIIO::ImageSpec config;
    config.tile_width = 64;
    config.tile_height = 64;
    config.format = OIIO::TypeDesc::FLOAT;
    bool ok;
    std::string err;
    {
        py::gil_scoped_release release;
        ok = OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, buf, path, config);
        if (!ok) err = OIIO::geterror();
    }
    if (!ok) os_error(path + ": cannot write the texture: " + err);
}

// Filtered lookups at uv (N, 2), float64 (pixel centres at (i + 0.5) / W, v = 0 the first row).
// derivs: (N, 4) (du/dx, dv/dx, du/dy, dv/dy) or None (point lookups). Returns (N, nchannels).
py::array_t<float> lookup(const std::string &path, py::array_t<double, py::array::c_style> uv, py::object derivs,
                          int interp, int mip, int wrap_s, int wrap_t, int firstchannel, int nchannels) {
    const py::ssize_t n = uv.shape(0);
    const double *d = nullptr;
    py::array_t<double, py::array::c_style> dd;
    if (!derivs.is_none()) {
        dd = derivs.cast<py::array_t<double, py::array::c_style>>();
        if (dd.ndim() != 2 || dd.shape(0) != n || dd.shape(1) != 4)
            throw py::value_error("derivatives: expected an (N, 4) array");
        d = dd.data();
    }
    OIIO::TextureOpt opt;
    opt.interpmode = OIIO::TextureOpt::InterpMode(interp);
    opt.mipmode = OIIO::TextureOpt::MipMode(mip);
    opt.swrap = OIIO::TextureOpt::Wrap(wrap_s);
    opt.twrap = OIIO::TextureOpt::Wrap(wrap_t);
    opt.firstchannel = firstchannel;
    opt.fill = 0.0f;
    py::array_t<float> out({n, py::ssize_t(nchannels)});
    float *o = out.mutable_data();
    const double *u = uv.data();
    std::atomic<bool> failed{false};
    std::string err;
    std::mutex err_mutex;
    OIIO::TextureSystem *ts = texsys();
    OIIO::ustring name(path);
    {
        py::gil_scoped_release release;
#pragma omp parallel
        {
            OIIO::TextureSystem::Perthread *pt = ts->get_perthread_info();
            OIIO::TextureSystem::TextureHandle *th = ts->get_texture_handle(name, pt);
            OIIO::TextureOpt local = opt;
#pragma omp for schedule(static)
            for (py::ssize_t i = 0; i < n; ++i) {
                if (failed.load(std::memory_order_relaxed)) continue;
                float dsdx = 0, dtdx = 0, dsdy = 0, dtdy = 0;
                if (d) {
                    dsdx = float(d[4 * i]);
                    dtdx = float(d[4 * i + 1]);
                    dsdy = float(d[4 * i + 2]);
                    dtdy = float(d[4 * i + 3]);
                }
                if (!ts->texture(th, pt, local, float(u[2 * i]), float(u[2 * i + 1]), dsdx, dtdx, dsdy, dtdy,
                                 nchannels, o + i * nchannels)) {
                    std::lock_guard<std::mutex> lock(err_mutex);
                    if (!failed.exchange(true)) err = ts->geterror();
                }
            }
        }
    }
    if (failed) os_error(path + ": texture lookup failed: " + (err.empty() ? std::string("unknown error") : err));
    return out;
}

} // namespace

void bind_texture(py::module_ &m) {
    m.def("image_info", &image_info, py::arg("path"));
    m.def("make_texture", &make_texture, py::arg("path"), py::arg("pixels"));
    m.def("texture_lookup", &lookup, py::arg("path"), py::arg("uv"), py::arg("derivs"), py::arg("interp"),
          py::arg("mip"), py::arg("wrap_s"), py::arg("wrap_t"), py::arg("firstchannel"), py::arg("nchannels"));
}

} // namespace bsdfkit::py_bind
