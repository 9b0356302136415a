// The conductor Fresnel term alone (bsdfkit.conductor_fresnel), by the same code as the models.
// The models themselves are bound by bind_all (models.cpp) from bxdfs/all.h.
#include <pybind11/stl.h>

#include "bind_model.h"
#include "bsdfkit/bxdfs/conductor.h"

namespace bsdfkit::py_bind {

void bind_pbrt_models(py::module_ &m) {
    // float64: cos (n,), eta / k RGB, which 0/1/2 (exact, schlick, f82) -> (n, 3).
    m.def("conductor_fresnel", [](py::array_t<double, py::array::c_style | py::array::forcecast> cos,
                                  const std::array<double, 3> &eta, const std::array<double, 3> &k, int which) {
        if (cos.ndim() != 1) value_error("cos_theta: expected a 1-D array");
        if (which < 0 || which > 2) value_error("fresnel: must be 0 (exact), 1 (schlick) or 2 (f82)");
        int64_t n = cos.shape(0);
        py::array_t<double> out({n, int64_t(3)});
        const double *c = cos.data();
        double *o = out.mutable_data();
        auto run = [&](const auto &model) {
            py::gil_scoped_release release;
            for (int64_t i = 0; i < n; ++i) {
                Spectrum<double> fr = model.fresnel(c[i]);
                for (int j = 0; j < 3; ++j) o[3 * i + j] = fr[j];
            }
        };
        ConductorParams p;
        p.eta = eta;
        p.k = k;
        if (which == 0) run(ConductorBxDF<double>::make(p));
        else if (which == 1) run(ConductorSchlickBxDF<double>::make(p));
        else run(ConductorF82BxDF<double>::make(p));
        return out;
    });
}

} // namespace bsdfkit::py_bind
