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

template <template <typename> class Model> void bind_conductor(py::module_ &m, const char *name) {
    bind_model<Model>(m, name).def(py::init([](const RGB &eta, const RGB &k, double ax, double ay, int masking) {
        Masking mk = to_masking(masking);
        return PyModel<Model>{
            Model<float>(TrowbridgeReitz<float>(float(ax), float(ay), mk), to_spectrum<float>(eta), to_spectrum<float>(k)),
            Model<double>(TrowbridgeReitz<double>(ax, ay, mk), to_spectrum<double>(eta), to_spectrum<double>(k))};
    }));
}

void bind_pbrt_models(py::module_ &m) {
    bind_model<DiffuseBxDF>(m, "Diffuse").def(py::init([](const RGB &r) {
        return PyModel<DiffuseBxDF>{{to_spectrum<float>(r)}, {to_spectrum<double>(r)}};
    }));
    bind_model<DiffuseTransmissionBxDF>(m, "DiffuseTransmission").def(py::init([](const RGB &r, const RGB &t) {
        return PyModel<DiffuseTransmissionBxDF>{{to_spectrum<float>(r), to_spectrum<float>(t)},
                                                {to_spectrum<double>(r), to_spectrum<double>(t)}};
    }));
    // One class per Fresnel variant (a compile-time policy of ConductorBxDF, so each batch loop
    // vectorizes); Python picks one from Conductor's `fresnel` (_models.py).
    bind_conductor<ConductorBxDF>(m, "Conductor");
    bind_conductor<ConductorSchlickBxDF>(m, "ConductorSchlick");
    bind_conductor<ConductorF82BxDF>(m, "ConductorF82");
    // The conductor Fresnel term alone, float64: cos (n,), eta / k RGB, which 0/1/2 -> (n, 3).
    m.def("conductor_fresnel", [](py::array_t<double, py::array::c_style | py::array::forcecast> cos,
                                  const RGB &eta, const RGB &k, int which) {
        if (cos.ndim() != 1) value_error("cos_theta: expected a 1-D array");
        if (which < 0 || which > 2) value_error("fresnel: must be 0 (exact), 1 (schlick) or 2 (f82)");
        int64_t n = cos.shape(0);
        py::array_t<double> out({n, int64_t(3)});
        const double *c = cos.data();
        double *o = out.mutable_data();
        TrowbridgeReitz<double> smooth(0.0, 0.0, Masking(0));
        auto run = [&](const auto &model) {
            py::gil_scoped_release release;
            for (int64_t i = 0; i < n; ++i) {
                Spectrum<double> fr = model.fresnel(c[i]);
                for (int j = 0; j < 3; ++j) o[3 * i + j] = fr[j];
            }
        };
        Spectrum<double> e = to_spectrum<double>(eta), kk = to_spectrum<double>(k);
        if (which == 0) run(ConductorBxDF<double>(smooth, e, kk));
        else if (which == 1) run(ConductorSchlickBxDF<double>(smooth, e, kk));
        else run(ConductorF82BxDF<double>(smooth, e, kk));
        return out;
    });
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
