// Keyword bindings of the pbrt family (Diffuse, DiffuseTransmission, Conductor (3 Fresnel variants), Dielectric, ThinDielectric): bind_all.h on PbrtModels (bxdfs/all.h).
// One translation unit per family so that the model kernels compile in parallel and a change to
// one family's header instantiates only that family's kernels again. The pbrt family is the
// largest, so it is two units: this one (diffuse and conductors) and models_bind_pbrt_dielectric.cpp
// (one unit of all seven peaked at 2.2 GB and 140 CPU-s under g++ 12 -O3).
#include <type_traits>

#include "bind_all.h"

namespace bsdfkit::py_bind {

using PbrtModelsA = ModelList<DiffuseBxDF, DiffuseTransmissionBxDF, ConductorBxDF, ConductorSchlickBxDF, ConductorF82BxDF>;
using PbrtModelsB = ModelList<DielectricBxDF, ThinDielectricBxDF>;
static_assert(std::is_same_v<ModelListCat<PbrtModelsA, PbrtModelsB>::type, PbrtModels>,
              "models_bind_pbrt*.cpp: the two halves must add up to PbrtModels (bxdfs/all.h), in order");

void bind_family_pbrt_dielectric(py::module_ &m, std::vector<std::string> &names);  // models_bind_pbrt_dielectric.cpp

void bind_family_pbrt(py::module_ &m, std::vector<std::string> &names) {
    bind_list<PbrtModelsA>(m, names);
    bind_family_pbrt_dielectric(m, names);
}

} // namespace bsdfkit::py_bind
