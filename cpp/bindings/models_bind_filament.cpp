// Keyword bindings of the filament family (FilamentStandard (4 lobe variants), FilamentCloth): bind_all.h on FilamentModels (bxdfs/all.h).
// One translation unit per family so that the model kernels compile in parallel and a change to
// one family's header instantiates only that family's kernels again.
#include "bind_all.h"

namespace bsdfkit::py_bind {

void bind_family_filament(py::module_ &m, std::vector<std::string> &names) { bind_list<FilamentModels>(m, names); }

} // namespace bsdfkit::py_bind
