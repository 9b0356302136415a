// Spectral mode bindings of the measured models and the stochastic coated walk (issue 15):
// _core.MeasuredSpectraTable / MeasuredSpectral (RGL tensor files, from the file's spectra),
// _core.MERLSpectralTable / MERLNearestSpectral / MERLLinearSpectral (MERL RGB bins uplifted),
// _core.CoatedDiffuseSpectral / CoatedConductorSpectral (the random walk with 4 channels).
// Adapters: bsdfkit/spectral/measured_spectral.h and layered_spectral.h. The Python layer
// (models/measured.py, models/layered.py) validates the files and parameters; the checks here are
// the second line of defence. Tables are held by the Python objects passed in (keep_alive).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "bind_spectral.h"
#include "bsdfkit/render/spectral_material.h"
#include "bsdfkit/spectral/layered_spectral.h"
#include "bsdfkit/spectral/measured_spectral.h"

namespace bsdfkit::py_bind {

namespace {

// A bound handle of a shared immutable table. (Not a bare std::shared_ptr: pybind11 reads a
// shared_ptr<T> argument as the holder of a bound T, which these are not.)
template <typename T> struct TableHandle {
    std::shared_ptr<const T> p;
    TableHandle(std::shared_ptr<const T> q) : p(std::move(q)) {}
    const T *operator->() const { return p.get(); }
    explicit operator bool() const { return bool(p); }
};
using PyMeasuredSpectra = TableHandle<MeasuredSpectraTable>;
using PyMERLSpectral = TableHandle<MERLSpectralTable>;
using Arr = py::array_t<double, py::array::c_style | py::array::forcecast>;

template <template <typename> class SM, bool Linear> void bind_merl(py::module_ &m, const char *name) {
    bind_spectral_model<SM>(m, name).def(
        py::init([](const SharedTable<MERLTable> &table, const PyMERLSpectral &coef) {
            if (!table || !coef) value_error("table, coefficients: must not be empty");
            PySpectral<SM> o;
            o.m32.kern = MERLT<float, Linear>::make({table});
            o.m64.kern = MERLT<double, Linear>::make({table});
            o.m32.coef = o.m64.coef = coef->coef.data();
            return o;
        }),
        py::arg("table"), py::arg("coefficients"), py::keep_alive<1, 2>(), py::keep_alive<1, 3>());
}

// The walk's coating, layer and estimator settings from the RGB model's keyword arguments.
template <template <typename> class SM, template <typename> class RGBModel>
PySpectral<SM> coated_walk(const char *name, bool has_albedo, const py::kwargs &kw) {
    using Params = typename RGBModel<double>::Params;
    Params p = bind_detail::params_from_kwargs<Params>(name, py::args(), kw);
    PySpectral<SM> o;
    auto fill = [&](auto &proto, auto rgb) {
        proto.top = rgb.top;
        proto.set_layer(p.layer);
        proto.has_albedo = has_albedo;
    };
    fill(o.m32.proto, RGBModel<float>::make(p));
    fill(o.m64.proto, RGBModel<double>::make(p));
    return o;
}

} // namespace

void bind_spectral_measured(py::module_ &m) {
    py::class_<PyMeasuredSpectra>(m, "MeasuredSpectraTable",
                                  "The spectra of an RGL tensor file: a warp per (phi_i, theta_i) with one channel "
                                  "per tabulated wavelength (spectral/measured_spectral.h).")
        .def(py::init([](const Arr &spectra, const std::vector<double> &wavelengths, const std::vector<double> &phi_i,
                         const std::vector<double> &theta_i) {
                 if (spectra.ndim() != 5) value_error("spectra: expected (n_phi, n_theta, n_lambda, N, N)");
                 if (phi_i.empty() || theta_i.empty()) value_error("phi_i, theta_i: must not be empty");
                 if (size_t(spectra.shape(0)) != phi_i.size() || size_t(spectra.shape(1)) != theta_i.size())
                     value_error("spectra: slice count does not match phi_i / theta_i");
                 if (wavelengths.empty() || size_t(spectra.shape(2)) != wavelengths.size())
                     value_error("wavelengths: one per spectra channel required");
                 for (size_t i = 0; i < wavelengths.size(); ++i)
                     if (!std::isfinite(wavelengths[i]) || (i && !(wavelengths[i] > wavelengths[i - 1])))
                         value_error("wavelengths: must be finite and increase strictly");
                 int H = int(spectra.shape(3)), W = int(spectra.shape(4));
                 if (H < 2 || W < 2) value_error("spectra: each 2-D slice must be at least 2 x 2");
                 for (py::ssize_t i = 0; i < spectra.size(); ++i)
                     if (!std::isfinite(spectra.data()[i])) value_error("spectra: non-finite value");
                 auto t = std::make_shared<MeasuredSpectraTable>();
                 std::vector<double> pv[2] = {phi_i, theta_i};
                 t->spectra.build(spectra.data(), W, H, int(wavelengths.size()),
                                  {int(phi_i.size()), int(theta_i.size())}, pv, 2, false);
                 t->wavelengths = wavelengths;
                 return PyMeasuredSpectra(std::move(t));
             }),
             py::arg("spectra"), py::arg("wavelengths"), py::arg("phi_i"), py::arg("theta_i"))
        .def_property_readonly("wavelengths", [](const PyMeasuredSpectra &t) { return t->wavelengths; })
        .def_property_readonly("nbytes", [](const PyMeasuredSpectra &t) {
            return py::int_(t->spectra.data64.size() * 8 + t->spectra.data32.size() * 4);
        });

    bind_spectral_model<MeasuredSpectral>(m, "MeasuredSpectral")
        .def(py::init([](const SharedTable<MeasuredTable> &table, const PyMeasuredSpectra &spectra) {
                 if (!table || !spectra) value_error("table, spectra: must not be empty");
                 if (table->vndf.param_size != spectra->spectra.param_size)
                     value_error("spectra: its (phi_i, theta_i) grid differs from the table's");
                 PySpectral<MeasuredSpectral> o;
                 o.m32.kern = MeasuredBxDF<float>::make({table});
                 o.m64.kern = MeasuredBxDF<double>::make({table});
                 o.m32.spectra = Warp2D<float, 2>(spectra->spectra);
                 o.m64.spectra = Warp2D<double, 2>(spectra->spectra);
                 o.m32.wl = o.m64.wl = spectra->wavelengths.data();
                 o.m32.n_wl = o.m64.n_wl = int(spectra->wavelengths.size());
                 return o;
             }),
             py::arg("table"), py::arg("spectra"), py::keep_alive<1, 2>(), py::keep_alive<1, 3>());

    py::class_<PyMERLSpectral>(m, "MERLSpectralTable",
                               "Every MERL bin's RGB uplifted to pbrt-v4's RGBUnboundedSpectrum: (c0, c1, c2, scale) "
                               "float32 per bin (spectral/measured_spectral.h).")
        .def(py::init([](py::array_t<float, py::array::c_style | py::array::forcecast> c) {
                 using namespace merl;
                 if (c.ndim() != 4 || c.shape(0) != kThetaH || c.shape(1) != kThetaD || c.shape(2) != kPhiD ||
                     c.shape(3) != 4)
                     value_error("coefficients: expected a (90, 90, 180, 4) array (c0, c1, c2, scale)");
                 const float *p = c.data();
                 for (py::ssize_t i = 0; i < c.size(); i += 4)
                     if (!std::isfinite(p[i]) || !std::isfinite(p[i + 1]) || std::isnan(p[i + 2]) ||
                         !(p[i + 3] >= 0) || !std::isfinite(p[i + 3]))
                         value_error("coefficients: c0, c1 and scale must be finite, scale >= 0, c2 not NaN");
                 auto t = std::make_shared<MERLSpectralTable>();
                 t->coef.assign(p, p + c.size());
                 return PyMERLSpectral(std::move(t));
             }),
             py::arg("coefficients"))
        .def_property_readonly("nbytes", [](const PyMERLSpectral &t) { return py::int_(t->coef.size() * 4); });
    bind_merl<MERLNearestSpectral, false>(m, "MERLNearestSpectral");
    bind_merl<MERLLinearSpectral, true>(m, "MERLLinearSpectral");

    bind_spectral_model<CoatedDiffuseSpectral>(m, "CoatedDiffuseSpectral")
        .def(py::init([](const PySpectralParam &r, const PySpectralParam &albedo, bool has_albedo,
                         const py::kwargs &kw) {
                 auto o = coated_walk<CoatedDiffuseSpectral, CoatedDiffuseBxDF>("CoatedDiffuse", has_albedo, kw);
                 o.m32.reflectance = o.m64.reflectance = r.p;
                 o.m32.albedo = o.m64.albedo = albedo.p;
                 o.keep = {r, albedo};
                 return o;
             }),
             "CoatedDiffuse (stochastic walk) spectral kernel: (reflectance, albedo) as SpectralParam, has_albedo "
             "(the albedo spectrum is not 0), then the CoatedDiffuse keyword arguments (reflectance / albedo as "
             "their RGB projection).");
    bind_spectral_model<CoatedConductorSpectral>(m, "CoatedConductorSpectral")
        .def(py::init([](const PySpectralParam &eta, const PySpectralParam &k, const PySpectralParam &albedo,
                         bool has_albedo, const py::kwargs &kw) {
                 auto o = coated_walk<CoatedConductorSpectral, CoatedConductorBxDF>("CoatedConductor",
                                                                                           has_albedo, kw);
                 CoatedConductorParams p =
                     bind_detail::params_from_kwargs<CoatedConductorParams>("CoatedConductor", py::args(), kw);
                 o.m32.proto.bottom.mfd = TrowbridgeReitz<float>(float(p.conductor_alpha_x), float(p.conductor_alpha_y),
                                                                 p.masking);
                 o.m64.proto.bottom.mfd = TrowbridgeReitz<double>(p.conductor_alpha_x, p.conductor_alpha_y, p.masking);
                 o.m32.eta = o.m64.eta = eta.p;
                 o.m32.k = o.m64.k = k.p;
                 o.m32.albedo = o.m64.albedo = albedo.p;
                 o.m32.interface_eta = o.m64.interface_eta = p.interface_eta;
                 o.keep = {eta, k, albedo};
                 return o;
             }),
             "CoatedConductor (stochastic walk) spectral kernel: (conductor_eta, conductor_k, albedo) as "
             "SpectralParam, has_albedo, then the CoatedConductor keyword arguments (the same as their RGB "
             "projection).");
}

// For the preview renderer's spectral mode (spectral.cpp's spectral_render_material asks here
// too): the float adapter of one of the models above; false if h is none of them.
template <template <typename> class SM> static bool measured_as(const py::handle &h, render::SpectralMaterial *out) {
    if (!py::isinstance<PySpectral<SM>>(h)) return false;
    *out = h.cast<const PySpectral<SM> &>().m32;
    return true;
}
bool spectral_measured_render_material(const py::handle &h, render::SpectralMaterial *out) {
    return measured_as<MeasuredSpectral>(h, out) || measured_as<MERLNearestSpectral>(h, out) ||
           measured_as<MERLLinearSpectral>(h, out) || measured_as<CoatedDiffuseSpectral>(h, out) ||
           measured_as<CoatedConductorSpectral>(h, out);
}

} // namespace bsdfkit::py_bind
