// _core's side of the table the renderer extension (bsdfkit._render) calls (render_abi.h): the
// bound models converted to the renderer's float materials. Part of _core, so that _render needs
// none of the model bindings (and _core none of Embree / OpenImageIO).
#include <pybind11/pybind11.h>

#include "bind_model.h"
#include "render_abi.h"

namespace bsdfkit::py_bind {

int num_threads();                                                              // module.cpp
bool spectral_render_material(const py::handle &h, render::SpectralMaterial *out);  // spectral.cpp

namespace {

template <typename T> struct type_tag {
    using type = T;
};

// The bound model `h` (a PyModel<M> for one M of AllModels, bxdfs/all.h) at float precision.
template <template <typename> class... Ms>
bool to_material_impl(const py::handle &h, render::Material *out, ModelList<Ms...> *) {
    auto one = [&](auto tag) {
        using P = typename decltype(tag)::type;
        if (!py::isinstance<P>(h)) return false;
        // per-element parameters have no one material (the Python side says so first)
        if (!h.cast<const P &>().varying.empty()) return false;
        *out = h.cast<const P &>().template get<render::Float>();
        return true;
    };
    return (one(type_tag<PyModel<Ms>>{}) || ...);
}

bool abi_material(PyObject *core, render::Material *out) {
    try {
        return to_material_impl(py::handle(core), out, static_cast<AllModels *>(nullptr));
    } catch (...) {
        return false;
    }
}

bool abi_spectral_material(PyObject *core, render::SpectralMaterial *out) {
    try {
        return spectral_render_material(py::handle(core), out);
    } catch (...) {
        return false;
    }
}

const RenderAbi kAbi{kRenderAbiVersion,
                     abi_size<render::Material>(), abi_align<render::Material>(),
                     abi_size<render::SpectralMaterial>(), abi_align<render::SpectralMaterial>(),
                     &abi_material, &abi_spectral_material, &num_threads};

} // namespace

void bind_render_abi(py::module_ &m) {
    m.attr("_render_abi") = py::capsule(static_cast<const void *>(&kAbi), kRenderAbiCapsule);
}

} // namespace bsdfkit::py_bind
