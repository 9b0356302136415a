// bind_all: one bsdfkit._core class per entry of bxdfs/all.h (AllModels), in list order. The
// generic keyword binding is bind_all.h; each model family is bound in its own translation unit
// (models_bind_<family>.cpp) so that the kernels compile in parallel and separately.
#include <pybind11/pybind11.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "bsdfkit/bxdfs/all.h"

namespace bsdfkit::py_bind {

namespace py = pybind11;

void bind_family_pbrt(py::module_ &m, std::vector<std::string> &names);
void bind_family_filament(py::module_ &m, std::vector<std::string> &names);
void bind_family_measured(py::module_ &m, std::vector<std::string> &names);
void bind_family_layered(py::module_ &m, std::vector<std::string> &names);
void bind_family_hair(py::module_ &m, std::vector<std::string> &names);
void bind_family_production(py::module_ &m, std::vector<std::string> &names);

namespace {
struct NameCollector {
    std::vector<std::string> &names;
    template <template <typename> class Model> void apply() { names.emplace_back(Model<double>::Name); }
};
} // namespace

void bind_all(py::module_ &m) {
    std::vector<std::string> names;
    bind_family_pbrt(m, names);
    bind_family_filament(m, names);
    bind_family_measured(m, names);
    bind_family_layered(m, names);
    bind_family_hair(m, names);
    bind_family_production(m, names);
    // The families concatenated are AllModels (all.h asserts it at compile time); check the order
    // that model_names reports as well.
    std::vector<std::string> expected;
    AllModels::for_each(NameCollector{expected});
    if (names != expected) throw std::logic_error("bind_all: the family lists do not add up to AllModels");
    m.def("model_names", [names] {
        py::list l;
        for (const std::string &n : names) l.append(n);
        return l;
    }, "Names of the compiled models (bxdfs/all.h), in list order.");
}

} // namespace bsdfkit::py_bind
