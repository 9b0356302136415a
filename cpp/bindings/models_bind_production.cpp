// Keyword bindings of the production-material family (Principled, PrincipledThin): bind_all.h on ProductionModels (bxdfs/all.h).
#include "bind_all.h"

namespace bsdfkit::py_bind {

void bind_family_production(py::module_ &m, std::vector<std::string> &names) { bind_list<ProductionModels>(m, names); }

} // namespace bsdfkit::py_bind
