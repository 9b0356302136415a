// Keyword bindings of the pbrt family's dielectrics (Dielectric, ThinDielectric): the second unit
// of the pbrt family (models_bind_pbrt.cpp binds the rest and checks that the halves add up).
#include "bind_all.h"

namespace bsdfkit::py_bind {

void bind_family_pbrt_dielectric(py::module_ &m, std::vector<std::string> &names) {
    bind_list<ModelList<DielectricBxDF, ThinDielectricBxDF>>(m, names);
}

} // namespace bsdfkit::py_bind
