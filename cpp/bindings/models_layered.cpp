// Bindings of the layered family (pbrt-v4 CoatedDiffuse / CoatedConductor). Parameters arrive
// validated from Python (bsdfkit/models/layered.py).
#include <pybind11/stl.h>

#include "bind_model.h"
#include "bsdfkit/bxdfs/layered.h"

namespace bsdfkit::py_bind {

using RGB = std::array<double, 3>;

static LayerParams layer_params(double thickness, const RGB &albedo, double g, int max_depth, int n_samples,
                                uint64_t seed, bool consistent_mis) {
    LayerParams l;
    l.thickness = thickness;
    l.albedo = albedo;
    l.g = g;
    l.max_depth = max_depth;
    l.n_samples = n_samples;
    l.seed = seed;
    l.consistent_mis = consistent_mis;
    return l;
}

void bind_layered_models(py::module_ &m) {
    bind_model<CoatedDiffuseBxDF>(m, "CoatedDiffuse")
        .def(py::init([](const RGB &reflectance, double eta, double ax, double ay, int masking, double thickness,
                         const RGB &albedo, double g, int max_depth, int n_samples, uint64_t seed, bool cmis) {
            CoatedDiffuseParams p;
            p.reflectance = reflectance;
            p.eta = eta;
            p.alpha_x = ax;
            p.alpha_y = ay;
            p.masking = to_masking(masking);
            p.layer = layer_params(thickness, albedo, g, max_depth, n_samples, seed, cmis);
            return PyModel<CoatedDiffuseBxDF>{CoatedDiffuseBxDF<float>::make(p), CoatedDiffuseBxDF<double>::make(p)};
        }));
    bind_model<CoatedConductorBxDF>(m, "CoatedConductor")
        .def(py::init([](const RGB &ce, const RGB &ck, double cax, double cay, double ieta, double iax, double iay,
                         int masking, double thickness, const RGB &albedo, double g, int max_depth, int n_samples,
                         uint64_t seed, bool cmis) {
            CoatedConductorParams p;
            p.conductor_eta = ce;
            p.conductor_k = ck;
            p.conductor_alpha_x = cax;
            p.conductor_alpha_y = cay;
            p.interface_eta = ieta;
            p.interface_alpha_x = iax;
            p.interface_alpha_y = iay;
            p.masking = to_masking(masking);
            p.layer = layer_params(thickness, albedo, g, max_depth, n_samples, seed, cmis);
            return PyModel<CoatedConductorBxDF>{CoatedConductorBxDF<float>::make(p),
                                                CoatedConductorBxDF<double>::make(p)};
        }));
}

} // namespace bsdfkit::py_bind
