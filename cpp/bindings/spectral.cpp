// Spectral mode bindings (issue 15): _core.SpectralParam, and the preview renderer's conversion
// of a bound spectral form (_core.<Name>Spectral, bound with its model by bind_all.h). The Python
// layer (models/_spectral.py) validates, broadcasts and flattens the arguments and calls the
// row-array entries (bind_spectral.h); as in bind_model.h, the checks there are a second line of
// defence. Wavelengths: float64 rows of 4 (for both precisions), nm, finite and in [360, 830];
// the kernels count the bad ones and the entries return the counts (the Python layer raises).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "bind_spectral.h"
#include "bsdfkit/render/spectral_material.h"

namespace bsdfkit::py_bind {

void bind_spectral(py::module_ &m) {
    py::class_<PySpectralParam>(m, "SpectralParam",
                                "A model parameter as a function of wavelength (core/spectral.h): constant, "
                                "sigmoid (an uplifted RGB) or a piecewise-linear table with nodes from 360 to 830 nm.")
        .def_static("constant", [](double v) {
            if (!std::isfinite(v)) value_error("value: must be finite");
            PySpectralParam r;
            r.p.kind = SpectralParam::Constant;
            r.p.c[0] = v;
            return r;
        }, py::arg("value"))
        .def_static("sigmoid", [](double c0, double c1, double c2, double scale) {
            if (!std::isfinite(c0) || !std::isfinite(c1) || std::isnan(c2) || !std::isfinite(scale))
                value_error("coefficients: c0, c1 and scale must be finite, c2 not NaN");
            PySpectralParam r;
            r.p.kind = SpectralParam::Sigmoid;
            r.p.c[0] = c0;
            r.p.c[1] = c1;
            r.p.c[2] = c2;
            r.p.scale = scale;
            return r;
        }, py::arg("c0"), py::arg("c1"), py::arg("c2"), py::arg("scale"))
        .def_static("table", [](py::array_t<double, py::array::c_style | py::array::forcecast> x,
                                py::array_t<double, py::array::c_style | py::array::forcecast> v) {
            if (x.ndim() != 1 || v.ndim() != 1 || x.shape(0) != v.shape(0) || x.shape(0) < 2)
                value_error("table: expected two 1-D arrays of the same length >= 2 (nodes in nm, values)");
            int64_t n = x.shape(0);
            auto t = std::make_shared<TableData>();
            t->x.assign(x.data(), x.data() + n);
            t->v.assign(v.data(), v.data() + n);
            if (t->x.front() != kLambdaMin || t->x.back() != kLambdaMax)
                value_error("table: the nodes must start at 360 and end at 830 nm");
            for (int64_t i = 0; i < n; ++i) {
                if (!std::isfinite(t->v[size_t(i)])) value_error("table: values must be finite");
                if (i && !(t->x[size_t(i)] > t->x[size_t(i - 1)])) value_error("table: nodes must increase");
            }
            t->slope.resize(size_t(n - 1));
            for (int64_t i = 0; i + 1 < n; ++i)
                t->slope[size_t(i)] = (t->v[size_t(i + 1)] - t->v[size_t(i)]) / (t->x[size_t(i + 1)] - t->x[size_t(i)]);
            t->first.resize(kDenseN);
            int32_t j = 0;
            for (int k = 0; k < kDenseN; ++k) {  // the last node <= 360 + k, at most n - 2
                double l = kLambdaMin + k;
                while (j + 2 < n && t->x[size_t(j + 1)] <= l) ++j;
                t->first[size_t(k)] = j;
            }
            PySpectralParam r;
            r.table = t;
            r.p.kind = SpectralParam::Table;
            r.p.x = t->x.data();
            r.p.v = t->v.data();
            r.p.slope = t->slope.data();
            r.p.first = t->first.data();
            r.p.n = int32_t(n);
            return r;
        }, py::arg("nodes"), py::arg("values"))
        .def_property_readonly("kind", [](const PySpectralParam &s) { return kind_name(s.p.kind); })
        .def("__call__", [](const PySpectralParam &s, py::array_t<double, py::array::c_style | py::array::forcecast> l) {
            py::array_t<double> out(l.request().shape);
            const double *pl = l.data();
            double *po = out.mutable_data();
            for (py::ssize_t i = 0; i < l.size(); ++i) po[i] = s.p(pl[i]);
            return out;
        }, py::arg("wavelengths"), "Values at wavelengths (nm), float64, as the kernels evaluate them.");
}

// For the preview renderer's spectral mode (cpp/bindings/render.cpp): the float form of a bound
// spectral model (a _core.<Name>Spectral of any model of the list); false if h is none of them.
// The caller keeps h alive (the form points into its tables).
namespace {
struct SpectralCaster {
    const py::handle &h;
    render::SpectralMaterial *out;
    bool found = false;
    template <template <typename> class Model> void apply() {
        if constexpr (has_spectral<Model<double>>::value) {
            if (!found && py::isinstance<PySpectral<Model>>(h)) {
                *out = h.cast<const PySpectral<Model> &>().m32;
                found = true;
            }
        }
    }
};
} // namespace

bool spectral_render_material(const py::handle &h, render::SpectralMaterial *out) {
    SpectralCaster c{h, out};
    AllModels::for_each(c);
    return c.found;
}

} // namespace bsdfkit::py_bind
