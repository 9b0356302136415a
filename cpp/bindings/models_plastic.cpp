// Bindings of the plastic family (Mitsuba 3 plastic / roughplastic). Parameters arrive
// validated from Python (bsdfkit/models/plastic.py).
#include <pybind11/stl.h>

#include "bind_model.h"
#include "bsdfkit/bxdfs/plastic.h"

namespace bsdfkit::py_bind {

void bind_plastic_models(py::module_ &m) {
    using RGB = std::array<double, 3>;
    bind_model<PlasticBxDF>(m, "Plastic")
        .def(py::init([](const RGB &reflectance, double eta, double alpha, bool nonlinear, int masking,
                         const RGB &specular_reflectance) {
            PlasticParams p;
            p.reflectance = reflectance;
            p.eta = eta;
            p.alpha = alpha;
            p.nonlinear = nonlinear;
            p.masking = to_masking(masking);
            p.specular_reflectance = specular_reflectance;
            py::gil_scoped_release release;  // the rough tables take a few ms
            PlasticTables t = PlasticBxDF<double>::tables(p);
            return PyModel<PlasticBxDF>{PlasticBxDF<float>::make(p, t), PlasticBxDF<double>::make(p, t)};
        }))
        // The tabulated coating transmittance T(cos) at cos = i / 63 (float64; all 1 - F for smooth).
        .def_property_readonly("transmittance_table", [](const PyModel<PlasticBxDF> &self) {
            const auto &k = self.m64;
            std::vector<double> t(kPlasticTableRes);
            for (int i = 0; i < kPlasticTableRes; ++i)
                t[i] = k.smooth ? 1 - FrDielectric(double(i) / (kPlasticTableRes - 1), k.eta) : k.table[i];
            return t;
        });
    m.def("fresnel_diffuse_reflectance", &FresnelDiffuseReflectance);
}

} // namespace bsdfkit::py_bind
