// Extra bindings of the plastic family that the generic keyword binding (models.cpp, from
// bxdfs/all.h) cannot provide: the tabulated coating transmittance and the diffuse Fresnel fit.
#include <pybind11/stl.h>

#include "bind_model.h"
#include "bsdfkit/bxdfs/plastic.h"

namespace bsdfkit::py_bind {

void bind_plastic_extras(py::module_ &m) {
    // _core.Plastic is created by bind_all (keyword Params); add the table read-out to it.
    auto cls = py::reinterpret_borrow<py::class_<PyModel<PlasticBxDF>>>(m.attr("Plastic"));
    // The tabulated coating transmittance T(cos) at cos = i / 63 (float64; all 1 - F for smooth).
    cls.def_property_readonly("transmittance_table", [](const PyModel<PlasticBxDF> &self) {
        const auto &k = self.m64;
        std::vector<double> t(kPlasticTableRes);
        for (int i = 0; i < kPlasticTableRes; ++i)
            t[i] = k.smooth ? 1 - FrDielectric(double(i) / (kPlasticTableRes - 1), k.eta) : k.table[i];
        return t;
    });
    m.def("fresnel_diffuse_reflectance", &FresnelDiffuseReflectance);
}

} // namespace bsdfkit::py_bind
