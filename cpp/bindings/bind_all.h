// The generic keyword binding of the models (one bsdfkit._core class per entry of a ModelList of
// bxdfs/all.h, plus _core.<Name>Spectral for a model with a spectral form, bind_spectral.h).
// Each is constructed from keyword arguments named exactly as its Params fields (bind_params.h).
// The field visitor drives the conversion both ways (`params` reads the fields back). Parameters are validated by the Python classes;
// these checks are a second line of defence, so that a misuse of _core raises instead of building
// garbage. Included by the per-family translation units models_bind_<family>.cpp (compile time:
// each instantiates the kernels of its own family only).
#pragma once
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "bind_model.h"
#include "bind_params.h"
#include "bind_spectral.h"
#include "bsdfkit/bxdfs/all.h"

namespace bsdfkit::py_bind {

namespace bind_detail {

template <template <typename> class Model> void bind_one(py::module_ &m) {
    using Params = typename Model<double>::Params;
    const char *name = Model<double>::Name;
    std::vector<std::string> names = field_names<Params>();
    auto cls = bind_model<Model>(m, name);
    cls.def(py::init([name](const py::args &args, const py::kwargs &kw) {
           std::vector<VaryingField> varying;
           Params p = params_from_kwargs<Params>(name, args, kw, &varying);
           return PyModel<Model>{Model<float>::make(p), Model<double>::make(p), p, std::move(varying)};
       }))
        .def_property_readonly("params",
                               [](const PyModel<Model> &self) {
                                   py::dict d;
                                   Params p = self.params;
                                   int k = 0;
                                   size_t j = 0;
                                   p.fields([&](const char *n, const auto &field) {
                                       if (j < self.varying.size() && self.varying[j].field == k) d[n] = self.varying[j++].values;
                                       else d[n] = to_py(field);
                                       ++k;
                                   });
                                   return d;
                               })
        .def_property_readonly("varying_shapes", [](const PyModel<Model> &self) {
            // ((field, its batch shape), ...): the shapes a call broadcasts with the directions'
            py::list l;
            for (const VaryingField &f : self.varying) l.append(py::make_tuple(f.name.substr(f.name.find('.') + 1),
                                                                                door::to_tuple(f.shape)));
            return py::tuple(l);
        })
        .def_property_readonly("varying", [](const PyModel<Model> &self) {
            py::list l;
            Params p = self.params;
            int k = 0;
            size_t j = 0;
            p.fields([&](const char *n, const auto &) {
                if (j < self.varying.size() && self.varying[j].field == k) l.append(py::str(n)), ++j;
                ++k;
            });
            return py::tuple(l);
        });
    py::tuple fields(names.size());
    for (size_t i = 0; i < names.size(); ++i) fields[i] = py::str(names[i]);
    cls.attr("fields") = fields;
    cls.attr("__doc__") = "bsdfkit model " + std::string(name) + " (bxdfs/all.h); keyword arguments: " + join(names) +
                          " (a missing one keeps its C++ Params default).";
}

// ModelList::for_each visitor: binds each model, records its name.
struct Binder {
    py::module_ &m;
    std::vector<std::string> &names;
    template <template <typename> class Model> void apply() {
        bind_one<Model>(m);
        if constexpr (has_spectral<Model<double>>::value) bind_spectral_form<Model>(m);  // _core.<Name>Spectral
        names.emplace_back(Model<double>::Name);
    }
};

} // namespace bind_detail

// Binds every model of List (a ModelList) in list order, appending their names.
template <class List> void bind_list(py::module_ &m, std::vector<std::string> &names) {
    List::for_each(bind_detail::Binder{m, names});
}

} // namespace bsdfkit::py_bind
