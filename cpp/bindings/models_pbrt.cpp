// Bindings of the pbrt-v4 reflection models. Parameters arrive validated from Python.
#include <pybind11/stl.h>

#include "bind_model.h"
#include "bsdfkit/bxdfs/conductor.h"
#include "bsdfkit/bxdfs/dielectric.h"
#include "bsdfkit/bxdfs/diffuse.h"
#include "bsdfkit/bxdfs/diffuse_transmission.h"
#include "bsdfkit/bxdfs/thin_dielectric.h"

namespace bsdfkit::py_bind {

using RGB = std::array<double, 3>;

void bind_pbrt_models(py::module_ &m) {
    bind_model<DiffuseBxDF>(m, "Diffuse").def(py::init([](const RGB &r) {
        return PyModel<DiffuseBxDF>{{to_spectrum<float>(r)}, {to_spectrum<double>(r)}};
    }));
    bind_model<DiffuseTransmissionBxDF>(m, "DiffuseTransmission").def(py::init([](const RGB &r, const RGB &t) {
        return PyModel<DiffuseTransmissionBxDF>{{to_spectrum<float>(r), to_spectrum<float>(t)},
                                                {to_spectrum<double>(r), to_spectrum<double>(t)}};
    }));
    bind_model<ConductorBxDF>(m, "Conductor")
        .def(py::init([](const RGB &eta, const RGB &k, double ax, double ay, int masking) {
            Masking mk = to_masking(masking);
            return PyModel<ConductorBxDF>{
                {TrowbridgeReitz<float>(float(ax), float(ay), mk), to_spectrum<float>(eta), to_spectrum<float>(k)},
                {TrowbridgeReitz<double>(ax, ay, mk), to_spectrum<double>(eta), to_spectrum<double>(k)}};
        }));
    bind_model<DielectricBxDF>(m, "Dielectric").def(py::init([](double eta, double ax, double ay, int masking) {
        Masking mk = to_masking(masking);
        return PyModel<DielectricBxDF>{{float(eta), TrowbridgeReitz<float>(float(ax), float(ay), mk)},
                                       {eta, TrowbridgeReitz<double>(ax, ay, mk)}};
    }));
    bind_model<ThinDielectricBxDF>(m, "ThinDielectric").def(py::init([](double eta) {
        return PyModel<ThinDielectricBxDF>{{float(eta)}, {eta}};
    }));
}

} // namespace bsdfkit::py_bind
