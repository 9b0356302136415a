// Spectral mode bindings (issue 15): _core.SpectralParam and one _core.<Model>Spectral class per
// model family with a spectral adapter (batch_spectral.h). The Python layer (models/_spectral.py)
// validates, broadcasts and flattens the arguments and calls the row-array entries below; as in
// bind_model.h, the checks here are a second line of defence (a misuse raises, never reads out
// of bounds). Wavelengths: float64 rows of 4 (for both precisions), nm, finite and in [360, 830];
// the kernels count the bad ones and the entries return the counts (the Python layer raises).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "bind_spectral.h"
#include "bsdfkit/render/spectral_material.h"

namespace bsdfkit::py_bind {

namespace {

Masking to_masking(int v) {
    if (v != 0 && v != 1) value_error("masking: must be 0 (correlated) or 1 (separable)");
    return Masking(v);
}

template <typename F> TrowbridgeReitz<F> make_mfd(double ax, double ay, int masking) {
    return TrowbridgeReitz<F>(F(ax), F(ay), to_masking(masking));
}

template <ConductorFresnel FR, template <typename> class SM>
void bind_conductor(py::module_ &m, const char *name) {
    bind_spectral_model<SM>(m, name).def(
        py::init([](const PySpectralParam &eta, const PySpectralParam &k, double ax, double ay, int masking) {
            PySpectral<SM> r;
            r.m32.eta = r.m64.eta = eta.p;
            r.m32.k = r.m64.k = k.p;
            r.m32.mfd = make_mfd<float>(ax, ay, masking);
            r.m64.mfd = make_mfd<double>(ax, ay, masking);
            r.keep = {eta, k};
            return r;
        }),
        py::arg("eta"), py::arg("k"), py::arg("alpha_x"), py::arg("alpha_y"), py::arg("masking"));
}

template <typename Fm> void check_plastic(double eta, double alpha, double w) {
    if (!(eta > 0) || eta == 1 || !std::isfinite(eta)) value_error("eta: must be finite, > 0 and != 1");
    if (!(alpha >= 0) || !std::isfinite(alpha)) value_error("alpha: must be finite and >= 0");
    if (!(w >= 0 && w <= 1)) value_error("spec_weight: must be in [0, 1]");
}

// The analytic coated models: Params from the keyword arguments (the RGB projection, as the RGB
// binding), the spectral parameters beside them.
template <template <typename> class SM, template <typename> class Model>
PySpectral<SM> coated_spectral(const char *name, const py::kwargs &kw) {
    using Params = typename Model<double>::Params;
    Params p = bind_detail::params_from_kwargs<Params>(name, py::args(), kw);
    PySpectral<SM> o;
    o.m32.proto = Model<float>::make(p);
    o.m64.proto = Model<double>::make(p);
    o.m32.internal = AnalyticInternal::of(o.m32.proto.top, o.m32.proto.thickness);
    o.m64.internal = AnalyticInternal::of(o.m64.proto.top, o.m64.proto.thickness);
    return o;
}

template <template <typename> class SM, bool Coat, bool Sheen> void bind_filament(py::module_ &m, const char *name) {
    bind_spectral_model<SM>(m, name).def(
        py::init([](const PySpectralParam &base, const PySpectralParam &sheen, const py::kwargs &kw) {
            FilamentStandardParams p = bind_detail::params_from_kwargs<FilamentStandardParams>("FilamentStandard", py::args(), kw);
            PySpectral<SM> o;
            o.m32.proto = FilamentStandardT<float, Coat, Sheen>::make(p);   // the kernel part
            o.m64.proto = FilamentStandardT<double, Coat, Sheen>::make(p);
            o.m32.params = o.m64.params = p;  // owns the DFG table the kernels point into
            o.m32.base_color = o.m64.base_color = base.p;
            o.m32.sheen_color = o.m64.sheen_color = sheen.p;
            o.keep = {base, sheen};
            return o;
        }),
        // positional (no names): the keyword arguments carry base_color / sheen_color's RGB projection
        "FilamentStandard spectral kernel: (base_color, sheen_color) as SpectralParam, then the FilamentStandard "
        "keyword arguments (base_color / sheen_color as their RGB projection).");
}

} // namespace

void bind_spectral(py::module_ &m) {
    py::class_<PySpectralParam>(m, "SpectralParam",
                                "A model parameter as a function of wavelength (core/spectral.h): constant, "
                                "sigmoid (an uplifted RGB) or a piecewise-linear table with nodes from 360 to 830 nm.")
        .def_static("constant", [](double v) {
            if (!std::isfinite(v)) value_error("value: must be finite");
            PySpectralParam r;
            r.p.kind = SpectralParam::Constant;
            r.p.c[0] = v;
            return r;
        }, py::arg("value"))
        .def_static("sigmoid", [](double c0, double c1, double c2, double scale) {
            if (!std::isfinite(c0) || !std::isfinite(c1) || std::isnan(c2) || !std::isfinite(scale))
                value_error("coefficients: c0, c1 and scale must be finite, c2 not NaN");
            PySpectralParam r;
            r.p.kind = SpectralParam::Sigmoid;
            r.p.c[0] = c0;
            r.p.c[1] = c1;
            r.p.c[2] = c2;
            r.p.scale = scale;
            return r;
        }, py::arg("c0"), py::arg("c1"), py::arg("c2"), py::arg("scale"))
        .def_static("table", [](py::array_t<double, py::array::c_style | py::array::forcecast> x,
                                py::array_t<double, py::array::c_style | py::array::forcecast> v) {
            if (x.ndim() != 1 || v.ndim() != 1 || x.shape(0) != v.shape(0) || x.shape(0) < 2)
                value_error("table: expected two 1-D arrays of the same length >= 2 (nodes in nm, values)");
            int64_t n = x.shape(0);
            auto t = std::make_shared<TableData>();
            t->x.assign(x.data(), x.data() + n);
            t->v.assign(v.data(), v.data() + n);
            if (t->x.front() != kLambdaMin || t->x.back() != kLambdaMax)
                value_error("table: the nodes must start at 360 and end at 830 nm");
            for (int64_t i = 0; i < n; ++i) {
                if (!std::isfinite(t->v[size_t(i)])) value_error("table: values must be finite");
                if (i && !(t->x[size_t(i)] > t->x[size_t(i - 1)])) value_error("table: nodes must increase");
            }
            t->slope.resize(size_t(n - 1));
            for (int64_t i = 0; i + 1 < n; ++i)
                t->slope[size_t(i)] = (t->v[size_t(i + 1)] - t->v[size_t(i)]) / (t->x[size_t(i + 1)] - t->x[size_t(i)]);
            t->first.resize(kDenseN);
            int32_t j = 0;
            for (int k = 0; k < kDenseN; ++k) {  // the last node <= 360 + k, at most n - 2
                double l = kLambdaMin + k;
                while (j + 2 < n && t->x[size_t(j + 1)] <= l) ++j;
                t->first[size_t(k)] = j;
            }
            PySpectralParam r;
            r.table = t;
            r.p.kind = SpectralParam::Table;
            r.p.x = t->x.data();
            r.p.v = t->v.data();
            r.p.slope = t->slope.data();
            r.p.first = t->first.data();
            r.p.n = int32_t(n);
            return r;
        }, py::arg("nodes"), py::arg("values"))
        .def_property_readonly("kind", [](const PySpectralParam &s) { return kind_name(s.p.kind); })
        .def("__call__", [](const PySpectralParam &s, py::array_t<double, py::array::c_style | py::array::forcecast> l) {
            py::array_t<double> out(l.request().shape);
            const double *pl = l.data();
            double *po = out.mutable_data();
            for (py::ssize_t i = 0; i < l.size(); ++i) po[i] = s.p(pl[i]);
            return out;
        }, py::arg("wavelengths"), "Values at wavelengths (nm), float64, as the kernels evaluate them.");

    bind_spectral_model<DiffuseSpectral>(m, "DiffuseSpectral")
        .def(py::init([](const PySpectralParam &r) {
                 PySpectral<DiffuseSpectral> o;
                 o.m32.reflectance = o.m64.reflectance = r.p;
                 o.keep = {r};
                 return o;
             }),
             py::arg("reflectance"));
    bind_spectral_model<DiffuseTransmissionSpectral>(m, "DiffuseTransmissionSpectral")
        .def(py::init([](const PySpectralParam &r, const PySpectralParam &t) {
                 PySpectral<DiffuseTransmissionSpectral> o;
                 o.m32.reflectance = o.m64.reflectance = r.p;
                 o.m32.transmittance = o.m64.transmittance = t.p;
                 o.keep = {r, t};
                 return o;
             }),
             py::arg("reflectance"), py::arg("transmittance"));
    bind_conductor<ConductorFresnel::Exact, ConductorSpectral>(m, "ConductorSpectral");
    bind_conductor<ConductorFresnel::Schlick, ConductorSchlickSpectral>(m, "ConductorSchlickSpectral");
    bind_conductor<ConductorFresnel::F82, ConductorF82Spectral>(m, "ConductorF82Spectral");
    bind_spectral_model<DielectricSpectral>(m, "DielectricSpectral")
        .def(py::init([](const PySpectralParam &eta, double ax, double ay, int masking, bool dispersive) {
                 PySpectral<DielectricSpectral> o;
                 o.m32.eta = o.m64.eta = eta.p;
                 o.m32.mfd = make_mfd<float>(ax, ay, masking);
                 o.m64.mfd = make_mfd<double>(ax, ay, masking);
                 o.m32.disp = o.m64.disp = dispersive;
                 o.keep = {eta};
                 return o;
             }),
             py::arg("eta"), py::arg("alpha_x"), py::arg("alpha_y"), py::arg("masking"), py::arg("dispersive"));
    bind_spectral_model<ThinDielectricSpectral>(m, "ThinDielectricSpectral")
        .def(py::init([](const PySpectralParam &eta, bool dispersive) {
                 PySpectral<ThinDielectricSpectral> o;
                 o.m32.eta = o.m64.eta = eta.p;
                 o.m32.disp = o.m64.disp = dispersive;
                 o.keep = {eta};
                 return o;
             }),
             py::arg("eta"), py::arg("dispersive"));
    bind_spectral_model<PlasticSpectral>(m, "PlasticSpectral")
        .def(py::init([](const PySpectralParam &r, const PySpectralParam &ks, double eta, double alpha, bool nonlinear,
                         int masking, double spec_weight, bool has_diffuse) {
                 check_plastic<double>(eta, alpha, spec_weight);
                 PlasticParams p;
                 p.eta = eta;
                 p.alpha = alpha;
                 p.nonlinear = nonlinear;
                 p.masking = to_masking(masking);
                 PlasticTables tab = PlasticBxDF<double>::tables(p);
                 double fdr = PlasticBxDF<double>::is_rough(p) ? tab.fdr : FresnelDiffuseReflectance(1 / eta);
                 PySpectral<PlasticSpectral> o;
                 o.m32.proto = PlasticBxDF<float>::make(p, tab);
                 o.m64.proto = PlasticBxDF<double>::make(p, tab);
                 o.m32.proto.spec_weight = float(spec_weight);
                 o.m64.proto.spec_weight = spec_weight;
                 o.m32.proto.has_diffuse = o.m64.proto.has_diffuse = has_diffuse;
                 o.m32.reflectance = o.m64.reflectance = r.p;
                 o.m32.specular = o.m64.specular = ks.p;
                 o.m32.fdr = o.m64.fdr = fdr;
                 o.m32.eta = o.m64.eta = eta;
                 o.m32.nonlinear = o.m64.nonlinear = nonlinear;
                 o.keep = {r, ks};
                 return o;
             }),
             py::arg("reflectance"), py::arg("specular_reflectance"), py::arg("eta"), py::arg("alpha"),
             py::arg("nonlinear"), py::arg("masking"), py::arg("spec_weight"), py::arg("has_diffuse"));
    bind_filament<FilamentStandardSpectral, false, false>(m, "FilamentStandardSpectral");
    bind_filament<FilamentStandardCoatSpectral, true, false>(m, "FilamentStandardCoatSpectral");
    bind_filament<FilamentStandardSheenSpectral, false, true>(m, "FilamentStandardSheenSpectral");
    bind_filament<FilamentStandardCoatSheenSpectral, true, true>(m, "FilamentStandardCoatSheenSpectral");
    bind_spectral_model<CoatedDiffuseAnalyticSpectral>(m, "CoatedDiffuseAnalyticSpectral")
        .def(py::init([](const PySpectralParam &r, const PySpectralParam &albedo, const py::kwargs &kw) {
                 auto o = coated_spectral<CoatedDiffuseAnalyticSpectral, CoatedDiffuseAnalyticBxDF>(
                     "CoatedDiffuseAnalytic", kw);
                 o.m32.reflectance = o.m64.reflectance = r.p;
                 o.m32.albedo = o.m64.albedo = albedo.p;
                 o.keep = {r, albedo};
                 return o;
             }),
             "CoatedDiffuseAnalytic spectral kernel: (reflectance, albedo) as SpectralParam, then the "
             "CoatedDiffuseAnalytic keyword arguments (reflectance / albedo as their RGB projection).");
    bind_spectral_model<CoatedConductorAnalyticSpectral>(m, "CoatedConductorAnalyticSpectral")
        .def(py::init([](const PySpectralParam &eta, const PySpectralParam &k, const PySpectralParam &albedo,
                         const py::kwargs &kw) {
                 auto o = coated_spectral<CoatedConductorAnalyticSpectral, CoatedConductorAnalyticBxDF>(
                     "CoatedConductorAnalytic", kw);
                 double ie = bind_detail::params_from_kwargs<CoatedConductorParams>("CoatedConductorAnalytic", py::args(), kw).interface_eta;
                 o.m32.eta = o.m64.eta = eta.p;
                 o.m32.k = o.m64.k = k.p;
                 o.m32.albedo = o.m64.albedo = albedo.p;
                 o.m32.interface_eta = o.m64.interface_eta = ie;
                 o.m32.init_quadrature();
                 o.m64.init_quadrature();
                 o.keep = {eta, k, albedo};
                 return o;
             }),
             "CoatedConductorAnalytic spectral kernel: (conductor_eta, conductor_k, albedo) as SpectralParam, then "
             "the CoatedConductorAnalytic keyword arguments (the same as their RGB projection).");
    bind_spectral_model<NormalizedFresnelSpectral>(m, "NormalizedFresnelSpectral")
        .def(py::init([](const PySpectralParam &eta) {
                 PySpectral<NormalizedFresnelSpectral> o;
                 o.m32.eta = o.m64.eta = eta.p;
                 o.keep = {eta};
                 return o;
             }),
             py::arg("eta"));
}

// For the preview renderer's spectral mode (cpp/bindings/render.cpp): the float adapter of a bound
// spectral model (a _core.<Model>Spectral); false if h is none of them. The caller keeps h alive
// (the adapter points into its tables).
template <template <typename> class SM> static bool spectral_as(const py::handle &h, render::SpectralMaterial *out) {
    if (!py::isinstance<PySpectral<SM>>(h)) return false;
    *out = h.cast<const PySpectral<SM> &>().m32;
    return true;
}
bool spectral_hair_render_material(const py::handle &h, render::SpectralMaterial *out);  // spectral_hair.cpp
bool spectral_measured_render_material(const py::handle &h, render::SpectralMaterial *out);  // spectral_measured.cpp
bool spectral_render_material(const py::handle &h, render::SpectralMaterial *out) {
    return spectral_measured_render_material(h, out) || spectral_as<DiffuseSpectral>(h, out) || spectral_as<DiffuseTransmissionSpectral>(h, out) ||
           spectral_as<ConductorSpectral>(h, out) || spectral_as<ConductorSchlickSpectral>(h, out) ||
           spectral_as<ConductorF82Spectral>(h, out) || spectral_as<DielectricSpectral>(h, out) ||
           spectral_as<ThinDielectricSpectral>(h, out) || spectral_as<PlasticSpectral>(h, out) ||
           spectral_as<FilamentStandardSpectral>(h, out) || spectral_as<FilamentStandardCoatSpectral>(h, out) ||
           spectral_as<FilamentStandardSheenSpectral>(h, out) ||
           spectral_as<FilamentStandardCoatSheenSpectral>(h, out) ||
           spectral_as<CoatedDiffuseAnalyticSpectral>(h, out) ||
           spectral_as<CoatedConductorAnalyticSpectral>(h, out) || spectral_as<NormalizedFresnelSpectral>(h, out) ||
           spectral_hair_render_material(h, out);
}

} // namespace bsdfkit::py_bind
