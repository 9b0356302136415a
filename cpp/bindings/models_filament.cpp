// Bindings of Filament's DFG table and its builder, and of the individual Filament terms (for
// term-by-term reference tests). The models are bound by bind_all (models.cpp) from bxdfs/all.h;
// they take the table as their Params field `dfg`. The table is built and cached by bsdfkit.filament.
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "bind_model.h"
#include "bsdfkit/bxdfs/filament.h"

namespace bsdfkit::py_bind {

namespace {

// Immutable, shared DFG table (core/table.h); every model built from it holds a reference, so
// the table lives as long as the last model (or Python handle) that uses it.
using PyDFG = SharedTable<FilamentDFG>;

template <typename F>
py::array term_t(const std::string &name, const std::vector<py::array> &args) {
    using namespace filament;
    int64_t n = -1;
    std::vector<const F *> p;
    for (size_t k = 0; k < args.size(); ++k) {
        int64_t rows;
        p.push_back(checked<F>(args[k], "args", {}, &rows));
        if (n >= 0 && rows != n) value_error("args: all arrays must have the same length");
        n = rows;
    }
    if (n < 0) value_error("args: at least one array is needed");
    py::array_t<F> out(n);
    F *o = out.mutable_data();
    auto need = [&](size_t k) {
        if (args.size() != k) value_error(name + ": expects " + std::to_string(k) + " arrays");
    };
    auto a = [&](size_t k, int64_t i) { return p[k][i]; };
    if (name == "D_GGX") {  // (alpha_t, alpha_b, hx, hy, hz)
        need(5);
        for (int64_t i = 0; i < n; ++i) {
            Microfacet<F> d;
            d.alpha_x = a(0, i);
            d.alpha_y = a(1, i);
            o[i] = D_GGX(d, Vec3<F>(a(2, i), a(3, i), a(4, i)));
        }
    } else if (name == "D_Charlie") {
        need(2);
        for (int64_t i = 0; i < n; ++i) o[i] = D_Charlie(a(0, i), a(1, i));
    } else if (name == "D_Ashikhmin") {
        need(2);
        for (int64_t i = 0; i < n; ++i) o[i] = D_Ashikhmin(a(0, i), a(1, i));
    } else if (name == "V_SmithGGXCorrelated") {
        need(3);
        for (int64_t i = 0; i < n; ++i) o[i] = V_SmithGGXCorrelated(a(0, i), a(1, i), a(2, i));
    } else if (name == "V_SmithGGXCorrelated_Fast") {
        need(3);
        for (int64_t i = 0; i < n; ++i) o[i] = V_SmithGGXCorrelated_Fast(a(0, i), a(1, i), a(2, i));
    } else if (name == "V_SmithGGXCorrelated_Anisotropic") {
        need(8);
        for (int64_t i = 0; i < n; ++i)
            o[i] = V_SmithGGXCorrelated_Anisotropic(a(0, i), a(1, i), a(2, i), a(3, i), a(4, i), a(5, i), a(6, i),
                                                    a(7, i));
    } else if (name == "V_Kelemen") {
        need(1);
        for (int64_t i = 0; i < n; ++i) o[i] = V_Kelemen(a(0, i));
    } else if (name == "V_Neubelt") {
        need(2);
        for (int64_t i = 0; i < n; ++i) o[i] = V_Neubelt(a(0, i), a(1, i));
    } else if (name == "F_Schlick") {
        need(3);
        for (int64_t i = 0; i < n; ++i) o[i] = F_Schlick(a(0, i), a(1, i), a(2, i));
    } else if (name == "Fd_Lambert") {
        need(1);
        for (int64_t i = 0; i < n; ++i) o[i] = Fd_Lambert<F>();
    } else if (name == "Fd_Burley") {
        need(4);
        for (int64_t i = 0; i < n; ++i) o[i] = Fd_Burley(a(0, i), a(1, i), a(2, i), a(3, i));
    } else if (name == "Fd_Wrap") {
        need(2);
        for (int64_t i = 0; i < n; ++i) o[i] = Fd_Wrap(a(0, i), a(1, i));
    } else if (name == "f0ClearCoatToSurface") {
        need(1);
        for (int64_t i = 0; i < n; ++i) o[i] = F(f0ClearCoatToSurface(double(a(0, i))));
    } else {
        value_error("name: unknown Filament term '" + name + "'");
    }
    return out;
}

} // namespace

void bind_filament_models(py::module_ &m) {
    py::class_<PyDFG>(m, "FilamentDFG")
        .def(py::init([](py::array_t<double, py::array::c_style | py::array::forcecast> a, int samples) {
            if (a.ndim() != 3 || a.shape(0) != a.shape(1) || a.shape(2) != 3 || a.shape(0) < 2)
                value_error("table: expected a (size, size, 3) array with size >= 2");
            return make_filament_dfg(int(a.shape(0)), samples, a.data());
        }))
        .def_property_readonly("size", [](const PyDFG &d) { return d->size; })
        .def_property_readonly("samples", [](const PyDFG &d) { return d->samples; })
        .def_property_readonly("digest", [](const PyDFG &d) { return d.digest(); },
                               "64-bit content digest of the table's values (core/table.h)")
        // equal values compare equal (by digest), so Params read back from two models compare
        .def("__eq__", [](const PyDFG &a, const py::object &b) {
            return py::isinstance<PyDFG>(b) && a == b.cast<const PyDFG &>();
        })
        .def("__hash__", [](const PyDFG &d) { return py::hash(py::int_(d.digest())); })
        .def("array", [](const PyDFG &d) {
            int s = d->size;
            py::array_t<double> out({s, s, 3});
            std::copy(d->d64.begin(), d->d64.end(), out.mutable_data());
            return out;
        });

    m.def("filament_dfg_rows", [](int size, int samples, int row_begin, int row_end) {
        if (size < 2) value_error("size: must be >= 2");
        if (samples < 2) value_error("samples: must be >= 2");
        if (row_begin < 0 || row_end > size || row_begin > row_end) value_error("rows: out of range");
        py::array_t<double> out({row_end - row_begin, size, 3});
        double *o = out.mutable_data();
        {
            py::gil_scoped_release release;
            filament_dfg_rows(size, samples, row_begin, row_end, o, num_threads());
        }
        return out;
    });

    m.def("filament_term", [](const std::string &name, const std::vector<py::array> &args) {
        bool f32 = !args.empty() && is_dtype<float>(args[0]);
        return f32 ? term_t<float>(name, args) : term_t<double>(name, args);
    });

}

} // namespace bsdfkit::py_bind
