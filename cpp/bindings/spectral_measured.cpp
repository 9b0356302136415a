// The tables of the measured models' spectral forms (issue 15): _core.MeasuredSpectraTable (the
// spectra of an RGL tensor file) and _core.MERLSpectralTable (every MERL bin's RGB uplifted),
// the `spectra` / `coefficients` inputs of _core.MeasuredSpectral / MERL*Spectral (bound with their
// models, bind_all.h; forms in bsdfkit/spectral/measured_spectral.h). The Python layer
// (models/measured.py) validates the files; the checks here are the second line of defence.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "bind_spectral.h"

namespace bsdfkit::py_bind {

namespace {
using PyMeasuredSpectra = TableHandle<MeasuredSpectraTable>;
using PyMERLSpectral = TableHandle<MERLSpectralTable>;
using Arr = py::array_t<double, py::array::c_style | py::array::forcecast>;
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
}

} // namespace bsdfkit::py_bind
