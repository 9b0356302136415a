// The table through which the optional extension bsdfkit._render (renderer, image and mesh I/O;
// Embree, OpenImageIO, Assimp) reaches what lives in bsdfkit._core: the bound models' conversion
// to the renderer's materials and the kernels' thread count. _core publishes it as the capsule
// _core._render_abi; _render checks version and layout at import (both are built from the same
// headers and flags by the same CMake run; a mismatch raises ImportError instead of misreading).
// No C++ exception crosses the boundary: the functions return false / a count.
#pragma once
#include <Python.h>

#include <cstdint>

#include "bsdfkit/render/material.h"
#include "bsdfkit/render/spectral_material.h"

namespace bsdfkit::py_bind {

inline constexpr uint32_t kRenderAbiVersion = 1;
inline constexpr const char *kRenderAbiCapsule = "bsdfkit._core._render_abi";

struct RenderAbi {
    uint32_t version;
    uint32_t material_size, material_align;            // sizeof / alignof(render::Material)
    uint32_t spectral_size, spectral_align;            // sizeof / alignof(render::SpectralMaterial)
    // A bound model (PyModel<M> of bxdfs/all.h, the model object's `_core`) as a renderer
    // material; false if `core` is none of them.
    bool (*material)(PyObject *core, render::Material *out);
    // A spectral kernel object (_core.<Model>Spectral) as the spectral renderer's material (it
    // points into the object's tables: the caller keeps the object alive); false if none.
    bool (*spectral_material)(PyObject *core, render::SpectralMaterial *out);
    int (*num_threads)();                              // bk.set_num_threads
};

template <typename T> constexpr uint32_t abi_size() { return uint32_t(sizeof(T)); }
template <typename T> constexpr uint32_t abi_align() { return uint32_t(alignof(T)); }

} // namespace bsdfkit::py_bind
