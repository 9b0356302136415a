// Spectral bindings of the hair family and of Filament's cloth (issue 15): _core.HairSpectral,
// _core.HairFarFieldSpectral and _core.FilamentClothSpectral (adapters in
// bsdfkit/spectral/hair_spectral.h), bound with bind_spectral.h's helper; and the preview
// renderer's conversion of HairSpectral (spectral_hair_render_material, called by spectral.cpp's
// spectral_render_material). The Python layer (models/hair.py, models/filament/materials.py)
// validates the parameters; the keyword arguments are the RGB binding's (bxdfs/all.h Params), their
// colours the RGB projection of the spectral ones.
#include "bind_spectral.h"
#include "bsdfkit/render/spectral_material.h"
#include "bsdfkit/spectral/hair_spectral.h"

namespace bsdfkit::py_bind {

void bind_spectral_hair(py::module_ &m) {
    bind_spectral_model<HairSpectral>(m, "HairSpectral")
        .def(py::init([](const PySpectralParam &sigma_a, const py::kwargs &kw) {
                 HairParams p = bind_detail::params_from_kwargs<HairParams>("Hair", py::args(), kw);
                 PySpectral<HairSpectral> o;
                 o.m32.proto = HairBxDF<float, kSpectralN>::make_fibre(p);
                 o.m64.proto = HairBxDF<double, kSpectralN>::make_fibre(p);
                 o.m32.sigma_a = o.m64.sigma_a = sigma_a.p;
                 o.keep = {sigma_a};
                 return o;
             }),
             "Hair spectral kernel: sigma_a as SpectralParam, then the Hair keyword arguments (sigma_a, if "
             "given, is ignored).");
    bind_spectral_model<HairFarFieldSpectral>(m, "HairFarFieldSpectral")
        .def(py::init([](const PySpectralParam &sigma_a, const py::kwargs &kw) {
                 HairFarFieldParams p =
                     bind_detail::params_from_kwargs<HairFarFieldParams>("HairFarField", py::args(), kw);
                 PySpectral<HairFarFieldSpectral> o;
                 o.m32.proto = HairFarFieldBxDF<float, kSpectralN>::make(p);
                 o.m64.proto = HairFarFieldBxDF<double, kSpectralN>::make(p);
                 o.m32.sigma_a = o.m64.sigma_a = sigma_a.p;
                 o.keep = {sigma_a};
                 return o;
             }),
             "HairFarField spectral kernel: sigma_a as SpectralParam, then the HairFarField keyword arguments "
             "(sigma_a, if given, is ignored).");
    bind_spectral_model<FilamentClothSpectral>(m, "FilamentClothSpectral")
        .def(py::init([](const PySpectralParam &base, const PySpectralParam &sheen, const PySpectralParam &subsurface,
                         bool sheen_from_base, const py::kwargs &kw) {
                 FilamentClothParams p =
                     bind_detail::params_from_kwargs<FilamentClothParams>("FilamentCloth", py::args(), kw);
                 PySpectral<FilamentClothSpectral> o;
                 o.m32.proto = FilamentClothBxDF<float>::make(p);   // the kernel part
                 o.m64.proto = FilamentClothBxDF<double>::make(p);
                 o.m32.dfg = o.m64.dfg = p.dfg;
                 o.m32.base_color = o.m64.base_color = base.p;
                 o.m32.sheen_color = o.m64.sheen_color = sheen.p;
                 o.m32.subsurface_color = o.m64.subsurface_color = subsurface.p;
                 o.m32.sheen_from_base = o.m64.sheen_from_base = sheen_from_base;
                 o.keep = {base, sheen, subsurface};
                 return o;
             }),
             // positional (no names): the keyword arguments carry the colours' RGB projection
             "FilamentCloth spectral kernel: (base_color, sheen_color, subsurface_color) as SpectralParam and "
             "sheen_from_base (sheen = sqrt(base) per wavelength), then the FilamentCloth keyword arguments.");
}

// For the preview renderer's spectral mode: the float adapter of a _core.HairSpectral (its fibre
// hits set h per hit); false if h is not one. The caller keeps h alive.
bool spectral_hair_render_material(const py::handle &h, render::SpectralMaterial *out) {
    if (!py::isinstance<PySpectral<HairSpectral>>(h)) return false;
    *out = h.cast<const PySpectral<HairSpectral> &>().m32;
    return true;
}

} // namespace bsdfkit::py_bind
