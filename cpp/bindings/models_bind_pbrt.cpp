// Keyword bindings of the pbrt family (PbrtModels, bxdfs/all.h): bind_all.h on its models.
// One translation unit per family so that the model kernels compile in parallel and a change to
// one family's header instantiates only that family's kernels again. The pbrt family is the
// largest, so it is two units: this one (its first five models: diffuse and conductors) and
// models_bind_pbrt_dielectric.cpp (the rest; one unit of all seven peaked at 2.2 GB and 140 CPU-s
// under g++ 12 -O3). A model added to the end of PbrtModels lands in the second unit.
#include <type_traits>

#include "bind_all.h"

namespace bsdfkit::py_bind {

using PbrtModelsA = ModelListSplit<PbrtModels, 5>::head;
static_assert(std::is_same_v<PbrtModelsA, ModelList<DiffuseBxDF, DiffuseTransmissionBxDF, ConductorBxDF,
                                                    ConductorSchlickBxDF, ConductorF82BxDF>>,
              "models_bind_pbrt.cpp: the first unit holds the diffuse models and the conductors");

void bind_family_pbrt_dielectric(py::module_ &m, std::vector<std::string> &names);  // models_bind_pbrt_dielectric.cpp

void bind_family_pbrt(py::module_ &m, std::vector<std::string> &names) {
    bind_list<PbrtModelsA>(m, names);
    bind_family_pbrt_dielectric(m, names);
}

} // namespace bsdfkit::py_bind
