// Keyword bindings of the pbrt family (Diffuse, DiffuseTransmission, Conductor (3 Fresnel variants), Dielectric, ThinDielectric): bind_all.h on PbrtModels (bxdfs/all.h).
// One translation unit per family so that the model kernels compile in parallel and a change to
// one family's header instantiates only that family's kernels again.
#include "bind_all.h"

namespace bsdfkit::py_bind {

void bind_family_pbrt(py::module_ &m, std::vector<std::string> &names) { bind_list<PbrtModels>(m, names); }

} // namespace bsdfkit::py_bind
