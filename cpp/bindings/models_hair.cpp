// Bindings of pbrt-v4's last two BxDFs: HairBxDF and NormalizedFresnelBxDF. Parameters arrive
// validated from Python (bsdfkit.models.hair).
#include <pybind11/stl.h>

#include "bind_model.h"
#include "bsdfkit/bxdfs/hair.h"
#include "bsdfkit/bxdfs/normalized_fresnel.h"

namespace bsdfkit::py_bind {

using RGB = std::array<double, 3>;

void bind_hair_models(py::module_ &m) {
    bind_model<HairBxDF>(m, "Hair").def(
        py::init([](const RGB &sigma_a, double eta, double beta_m, double beta_n, double alpha, double h) {
            HairBxDF<double>::Params p;
            p.sigma_a = sigma_a;
            p.eta = eta;
            p.beta_m = beta_m;
            p.beta_n = beta_n;
            p.alpha = alpha;
            p.h = h;
            HairBxDF<float>::Params pf;
            pf.sigma_a = sigma_a;
            pf.eta = eta;
            pf.beta_m = beta_m;
            pf.beta_n = beta_n;
            pf.alpha = alpha;
            pf.h = h;
            return PyModel<HairBxDF>{HairBxDF<float>::make(pf), HairBxDF<double>::make(p)};
        }));
    bind_model<HairFarFieldBxDF>(m, "HairFarField").def(
        py::init([](const RGB &sigma_a, double eta, double beta_m, double beta_n, double alpha) {
            HairFarFieldBxDF<double>::Params p;
            HairFarFieldBxDF<float>::Params pf;
            p.sigma_a = pf.sigma_a = sigma_a;
            p.eta = pf.eta = eta;
            p.beta_m = pf.beta_m = beta_m;
            p.beta_n = pf.beta_n = beta_n;
            p.alpha = pf.alpha = alpha;
            return PyModel<HairFarFieldBxDF>{HairFarFieldBxDF<float>::make(pf), HairFarFieldBxDF<double>::make(p)};
        }));
    bind_model<NormalizedFresnelBxDF>(m, "NormalizedFresnel").def(py::init([](double eta) {
        NormalizedFresnelBxDF<double>::Params p;
        p.eta = eta;
        NormalizedFresnelBxDF<float>::Params pf;
        pf.eta = eta;
        return PyModel<NormalizedFresnelBxDF>{NormalizedFresnelBxDF<float>::make(pf),
                                              NormalizedFresnelBxDF<double>::make(p)};
    }));
    m.def("fresnel_moment1", [](double eta) { return FresnelMoment1(eta); });
}

} // namespace bsdfkit::py_bind
