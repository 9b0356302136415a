// The FresnelMoment1 polynomial alone (used by NormalizedFresnel). The models themselves
// (Hair, HairFarField, NormalizedFresnel) are bound by bind_all (models.cpp) from bxdfs/all.h.
#include "bind_model.h"
#include "bsdfkit/bxdfs/normalized_fresnel.h"

namespace bsdfkit::py_bind {

void bind_hair_models(py::module_ &m) {
    m.def("fresnel_moment1", [](double eta) { return FresnelMoment1(eta); });
}

} // namespace bsdfkit::py_bind
