// Bindings of the measured models (MERL tables; RGL tensor files). Files are read and validated
// in Python (bsdfkit/models/merl.py, measured.py); the tables arrive here as float64 arrays.
#include <pybind11/stl.h>

#include <vector>

#include "bind_model.h"
#include "bsdfkit/core/table.h"
#include "bsdfkit/bxdfs/measured.h"
#include "bsdfkit/bxdfs/merl.h"

namespace bsdfkit::py_bind {

namespace {

// Immutable, shared tables (core/table.h); every model built from one holds a reference. The
// models themselves are bound generically from bxdfs/all.h (models.cpp), with keyword `table`.
using PyMERLTable = SharedTable<MERLTable>;
using PyMeasuredTable = SharedTable<MeasuredTable>;

template <typename T> void bind_table_identity(py::class_<SharedTable<T>> &c) {
    c.def_property_readonly("digest", [](const SharedTable<T> &d) { return d.digest(); },
                            "64-bit content digest of the table's values (core/table.h)")
        .def("__eq__", [](const SharedTable<T> &a, const py::object &b) {
            return py::isinstance<SharedTable<T>>(b) && a == b.cast<const SharedTable<T> &>();
        })
        .def("__hash__", [](const SharedTable<T> &d) { return py::hash(py::int_(d.digest())); });
}

using Arr = py::array_t<double, py::array::c_style | py::array::forcecast>;

// One warp from an array whose last two axes are (H, W); `lead` axes before them are the
// parameter slices (phi_i, theta_i) and, for rgb, the channel axis.
void build_warp(Warp2DData &w, const char *name, const Arr &a, int n_params, int channels,
                const std::vector<double> pv[2], bool normalize) {
    int nd = int(a.ndim());
    int expect = 2 + n_params + (channels > 1 ? 1 : 0);
    if (nd != expect) value_error(std::string(name) + ": wrong number of dimensions");
    int H = int(a.shape(nd - 2)), W = int(a.shape(nd - 1));
    if (H < 2 || W < 2) value_error(std::string(name) + ": each 2-D slice must be at least 2 x 2");
    std::array<int, 2> ps{1, 1};
    for (int d = 0; d < n_params; ++d) {
        ps[d] = int(a.shape(d));
        if (ps[d] != int(pv[d].size())) value_error(std::string(name) + ": slice count does not match phi_i / theta_i");
    }
    if (channels > 1 && a.shape(nd - 3) != channels) value_error(std::string(name) + ": wrong channel count");
    for (py::ssize_t i = 0; i < a.size(); ++i)
        if (!std::isfinite(a.data()[i])) value_error(std::string(name) + ": non-finite value");
    int64_t bad = w.build(a.data(), W, H, channels, ps, pv, n_params, normalize);
    if (bad >= 0)
        value_error(std::string(name) + ": slice " + std::to_string(bad) +
                    " integrates to zero (or is not finite): no density can be built from it");
}

} // namespace

void bind_measured_models(py::module_ &m) {
    py::class_<PyMERLTable> merl_table(m, "MERLTable");
    bind_table_identity(merl_table);
    merl_table
        .def(py::init([](py::array_t<double, py::array::c_style | py::array::forcecast> a, int K, int n_phi,
                         bool linear) {
            using namespace merl;
            if (a.ndim() != 4 || a.shape(0) != kThetaH || a.shape(1) != kThetaD || a.shape(2) != kPhiD ||
                a.shape(3) != 3)
                value_error("values: expected a (90, 90, 180, 3) array");
            if (K < 1 || K > 1024) value_error("K: must be in [1, 1024]");
            if (n_phi < 1 || n_phi > 2048) value_error("n_phi: must be in [1, 2048]");
            std::vector<double> v(a.data(), a.data() + a.size());
            for (double &x : v)
                if (!(x >= 0) || !std::isfinite(x)) x = 0;  // unmeasured (negative) -> 0
            std::shared_ptr<const MERLTable> t;
            {
                py::gil_scoped_release release;
                t = make_merl_table(std::move(v), K, n_phi, linear, num_threads());
            }
            // Ctrl-C stopped the build (the pool's hook set KeyboardInterrupt): raise it. Returning a
            // value with the error set was Python's "SystemError: ... returned a result with an
            // exception set" (issue 50 item 18).
            raise_if_interrupted();
            if (!t) throw std::runtime_error("MERLTable: the table build was interrupted");  // cannot happen
            return PyMERLTable(t);
        }))
        .def_property_readonly("K", [](const PyMERLTable &t) { return t->K; })
        .def_property_readonly("n_phi", [](const PyMERLTable &t) { return t->n_phi; })
        .def("values", [](const PyMERLTable &t) {
            py::array_t<double> out({merl::kThetaH, merl::kThetaD, merl::kPhiD, 3});
            std::copy(t->v64.begin(), t->v64.end(), out.mutable_data());
            return out;
        })
        .def("sampler", [](const PyMERLTable &t) {
            const MERLTable &T = *t;
            auto arr = [&](const std::vector<double> &v, std::vector<py::ssize_t> shape) {
                py::array_t<double> out(shape);
                std::copy(v.begin(), v.end(), out.mutable_data());
                return out;
            };
            return py::make_tuple(arr(T.marg64, {T.K, merl::kThetaH}), arr(T.cond64, {T.K, merl::kThetaH, T.n_phi}),
                                  arr(T.dens64, {T.K, merl::kThetaH, T.n_phi}));
        });

    py::class_<PyMeasuredTable> measured_table(m, "MeasuredTable");
    bind_table_identity(measured_table);
    measured_table
        .def(py::init([](const Arr &ndf, const Arr &sigma, const Arr &vndf, const Arr &luminance, const Arr &rgb,
                         const std::vector<double> &phi_i, const std::vector<double> &theta_i, bool isotropic,
                         bool jacobian, int reduction) {
            if (phi_i.empty() || theta_i.empty()) value_error("phi_i, theta_i: must not be empty");
            if (reduction != 1 && reduction != 2 && reduction != 4) value_error("reduction: must be 1, 2 or 4");
            auto t = std::make_shared<MeasuredTable>();
            std::vector<double> pv[2] = {phi_i, theta_i}, none[2];
            build_warp(t->ndf, "ndf", ndf, 0, 1, none, false);
            build_warp(t->sigma, "sigma", sigma, 0, 1, none, false);
            build_warp(t->vndf, "vndf", vndf, 2, 1, pv, true);
            build_warp(t->luminance, "luminance", luminance, 2, 1, pv, true);
            build_warp(t->rgb, "rgb", rgb, 2, 3, pv, false);
            t->isotropic = isotropic;
            t->jacobian = jacobian;
            t->reduction = reduction;
            return PyMeasuredTable(std::shared_ptr<const MeasuredTable>(std::move(t)));
        }));
    // One unconditioned warp, float64, for tabulation and tests: eval / sample / invert over (n, 2) arrays.
    struct PyWarp {
        std::shared_ptr<Warp2DData> d;
    };
    py::class_<PyWarp>(m, "Warp2D")
        .def(py::init([](const Arr &a, bool normalize) {
            PyWarp w{std::make_shared<Warp2DData>()};
            std::vector<double> none[2];
            build_warp(*w.d, "data", a, 0, 1, none, normalize);
            return w;
        }))
        .def("eval", [](const PyWarp &w, const Arr &p) {
            if (p.ndim() != 2 || p.shape(1) != 2) value_error("pos: expected an (n, 2) array");
            Warp2D<double, 0> v(*w.d);
            py::array_t<double> out(p.shape(0));
            for (py::ssize_t i = 0; i < p.shape(0); ++i) out.mutable_data()[i] = v.eval({p.at(i, 0), p.at(i, 1)}, nullptr);
            return out;
        })
        .def("sample", [](const PyWarp &w, const Arr &u, bool inverse) {
            if (u.ndim() != 2 || u.shape(1) != 2) value_error("u: expected an (n, 2) array");
            if (!w.d->sampling) value_error("sample: the warp was built without normalize");
            Warp2D<double, 0> v(*w.d);
            py::ssize_t n = u.shape(0);
            py::array_t<double> pts({n, py::ssize_t(2)}), pdf(n);
            for (py::ssize_t i = 0; i < n; ++i) {
                auto r = inverse ? v.invert({u.at(i, 0), u.at(i, 1)}, nullptr) : v.sample({u.at(i, 0), u.at(i, 1)}, nullptr);
                pts.mutable_at(i, 0) = r.first.x;
                pts.mutable_at(i, 1) = r.first.y;
                pdf.mutable_data()[i] = r.second;
            }
            return py::make_tuple(pts, pdf);
        });

}

} // namespace bsdfkit::py_bind
