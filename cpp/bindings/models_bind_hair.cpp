// Keyword bindings of the hair family (NormalizedFresnel, Hair, HairFarField): bind_all.h on HairModels (bxdfs/all.h).
// One translation unit per family so that the model kernels compile in parallel and a change to
// one family's header instantiates only that family's kernels again.
#include "bind_all.h"

namespace bsdfkit::py_bind {

void bind_family_hair(py::module_ &m, std::vector<std::string> &names) { bind_list<HairModels>(m, names); }

} // namespace bsdfkit::py_bind
