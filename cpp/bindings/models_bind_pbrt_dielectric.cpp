// Keyword bindings of the pbrt family after its first five models (the dielectrics and any model
// added at the end of PbrtModels): the second unit of the pbrt family (models_bind_pbrt.cpp).
#include "bind_all.h"

namespace bsdfkit::py_bind {

void bind_family_pbrt_dielectric(py::module_ &m, std::vector<std::string> &names) {
    bind_list<ModelListSplit<PbrtModels, 5>::tail>(m, names);
}

} // namespace bsdfkit::py_bind
