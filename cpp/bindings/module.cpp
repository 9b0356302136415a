// bsdfkit._core: thread pool control and the model bindings (models, batch kernels, gradients,
// spectral). No Embree, OpenImageIO or Assimp: the renderer and image I/O are the optional
// extension bsdfkit._render (render.cpp), which reaches the models through _core._render_abi.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <atomic>
#include <string>
#include <thread>

#include "block_cache.h"
#include "bsdfkit/pool.h"

namespace py = pybind11;

namespace bsdfkit::py_bind {

static std::atomic<int> g_threads{int(std::max(1u, std::thread::hardware_concurrency()))};
int num_threads() { return g_threads.load(); }

void bind_all(py::module_ &m);
void bind_pbrt_models(py::module_ &m);
void bind_filament_models(py::module_ &m);
void bind_measured_models(py::module_ &m);
void bind_plastic_extras(py::module_ &m);
void bind_hair_models(py::module_ &m);
void bind_grad_models(py::module_ &m);
void bind_render_abi(py::module_ &m);  // render_abi.cpp: the table bsdfkit._render calls
void bind_spectral(py::module_ &m);  // spectral.cpp: SpectralParam (the forms are bound with their models)
void bind_spectral_measured(py::module_ &m);  // spectral_measured.cpp: the measured forms' tables

} // namespace bsdfkit::py_bind

using namespace bsdfkit;

PYBIND11_MODULE(_core, m) {
    m.doc() = "bsdfkit compiled core (use the bsdfkit package, not this module directly)";
    // Batch kernels poll this between chunks (pool.h): Ctrl-C stops a long eval / albedo call
    // and the binding re-raises the KeyboardInterrupt.
    interrupt_hook() = +[]() -> bool {
        py::gil_scoped_acquire gil;
        return PyErr_CheckSignals() != 0;
    };
    m.def("set_num_threads", [](int n) {
        if (n < 1) throw py::value_error("n: number of threads must be >= 1");
        py_bind::g_threads = n;
    });
    m.def("get_num_threads", [] { return py_bind::g_threads.load(); });
    m.def("hardware_concurrency", [] { return int(std::max(1u, std::thread::hardware_concurrency())); });
    m.def("release_memory", [] { return py_bind::BlockCache::instance().clear(); });
    m.def("cached_bytes", [] { return py_bind::BlockCache::instance().kept_bytes(); });

    py_bind::bind_filament_models(m);  // first: the models' Params refer to its FilamentDFG
    py_bind::bind_measured_models(m);  // likewise: MERLTable, MeasuredTable
    py_bind::bind_all(m);
    py_bind::bind_pbrt_models(m);
    py_bind::bind_plastic_extras(m);
    py_bind::bind_hair_models(m);
    py_bind::bind_grad_models(m);  // eval_grad on the bound classes (after bind_all)
    py_bind::bind_spectral(m);
    py_bind::bind_spectral_measured(m);

    py_bind::bind_render_abi(m);
}
