// Keyword bindings of the layered family (Plastic, CoatedDiffuse, CoatedConductor and their analytic forms): bind_all.h on LayeredModels (bxdfs/all.h).
// One translation unit per family so that the model kernels compile in parallel and a change to
// one family's header instantiates only that family's kernels again.
#include "bind_all.h"

namespace bsdfkit::py_bind {

void bind_family_layered(py::module_ &m, std::vector<std::string> &names) { bind_list<LayeredModels>(m, names); }

} // namespace bsdfkit::py_bind
