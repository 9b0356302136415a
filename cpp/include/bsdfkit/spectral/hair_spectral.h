// Spectral adapters of Hair, HairFarField and FilamentCloth (issue 15; docs/SPECTRAL.md). They
// follow batch_spectral.h's adapter shape (dispersive(), f, pdf, sample with the element's 4
// wavelengths) and run through its kernels; kept in their own header so that the hair and cloth
// model code compiles only where it is bound (cpp/bindings/spectral_hair.cpp) and rendered.
#pragma once
#include <cmath>

#include "../batch_spectral.h"
#include "../bxdfs/filament.h"
#include "../bxdfs/hair.h"

namespace bsdfkit {

// ---- Hair: sigma_a(lambda). pbrt-v4's HairBxDF is spectral: HairMaterial::GetBxDF evaluates
// sigma_a at the path's SampledWavelengths (an RGB sigma_a as RGBUnboundedSpectrum, melanin
// concentrations through SigmaAFromConcentration's RGB then RGBUnboundedSpectrum, a colour as
// RGBAlbedoSpectrum then SigmaAFromReflectance per wavelength; pbrt-v4 src/pbrt/materials.h and
// materials.cpp, HairMaterial). eta, beta_m, beta_n, alpha and h are wavelength-independent.
// The fibre is built once (proto, 4 channels, sigma_a 0); per element, sigma_a is set at the 4
// wavelengths and HairBxDF's own code runs with the wavelengths as its channels. So the lobe
// weights of sample / pdf are A_p averaged over the 4 wavelengths (pbrt-v4 HairBxDF::ApPDF,
// SampledSpectrum::Average): the spectral pdf differs from the RGB pdf (an average over 3 RGB
// channels) by that average, and depends on the wavelengths.
template <typename F> struct HairSpectral : PerElementModel<HairSpectral<F>, F> {
    using Model = HairBxDF<F, kSpectralN>;
    static constexpr SpectralField kFields[] = {{"sigma_a", "unbounded"}};
    SpectralParam sigma_a;
    Model proto;
    template <class A> static HairSpectral make(const HairParams &p, const A &a) {
        HairSpectral s;
        s.proto = Model::make_fibre(p);
        s.sigma_a = a.param("sigma_a");
        return s;
    }

    Model at(const double *lam) const {
        Model m = proto;
        m.set_sigma_a(sigma_a.at<F>(lam));
        return m;
    }
    // The fibre seen at offset h (a fibre hit of the preview renderer, as HairBxDF::set_h).
    void set_h(double h) { proto.set_h(h); }
};

// The far-field fibre (HairFarFieldBxDF: HairBxDF averaged over h) with sigma_a(lambda): the node
// tables are built once in proto; per element a copy gets sigma_a at the 4 wavelengths (the copy,
// 5 x 64 values, costs little next to the 64 fibre evaluations it serves).
template <typename F> struct HairFarFieldSpectral : PerElementModel<HairFarFieldSpectral<F>, F> {
    using Model = HairFarFieldBxDF<F, kSpectralN>;
    static constexpr SpectralField kFields[] = {{"sigma_a", "unbounded"}};
    SpectralParam sigma_a;
    Model proto;
    template <class A> static HairFarFieldSpectral make(const HairFarFieldParams &p, const A &a) {
        HairFarFieldSpectral s;
        s.proto = Model::make(p);
        s.sigma_a = a.param("sigma_a");
        return s;
    }

    Model at(const double *lam) const {
        Model m = proto;
        m.base.set_sigma_a(sigma_a.at<F>(lam));
        return m;
    }
};

// ---- FilamentCloth: base_color(lambda), sheen_color(lambda) and subsurface_color(lambda), split
// channels as FilamentStandardSpectralT (batch_spectral.h SplitChannelModel). Per wavelength the
// diffuse colour, the sheen colour and the subsurface colour are what one RGB channel of the kernel
// holds; a sheen colour not given is Filament's default sqrt(baseColor) per wavelength. The lobe
// choice (FilamentClothKernel::lobes: max(baseColor), max(sheenColor) and the DFG row) stays the
// RGB projection's (Filament defines it on the RGB triple), so pdf is the RGB model's.
template <typename F>
struct FilamentClothSpectral : SplitChannelModel<FilamentClothSpectral<F>, F, FilamentClothKernel<F>> {
    static constexpr bool kSharedChoice = true;  // lobes() reads base_max, sheen_max and dfg_row only
    SpectralParam base_color, sheen_color, subsurface_color;
    bool sheen_from_base = false;   // sheen_color = sqrt(base_color(lambda)) (Filament's default)
    SharedTable<FilamentDFG> dfg;   // keeps the DFG table alive (proto's dfg_row points into it)
    static constexpr SpectralField kFields[] = {
        {"base_color", "reflectance"}, {"sheen_color", "reflectance"}, {"subsurface_color", "reflectance"}};
    // a.flag("sheen_from_base"): no sheen colour given (Filament's sqrt(baseColor) per wavelength)
    template <class A> static FilamentClothSpectral make(const FilamentClothParams &p, const A &a) {
        FilamentClothSpectral s;
        s.proto = FilamentClothBxDF<F>::make(p);  // the kernel part
        s.dfg = p.dfg;
        s.base_color = a.param("base_color");
        s.sheen_color = a.param("sheen_color");
        s.subsurface_color = a.param("subsurface_color");
        s.sheen_from_base = a.flag("sheen_from_base");
        return s;
    }

    struct Chan {
        F base, sheen, subsurface;
    };
    Chan chan(double l) const {
        double b = base_color(l);
        return {F(b), F(sheen_from_base ? std::sqrt(b) : sheen_color(l)), F(subsurface_color(l))};
    }
    static void put(FilamentClothKernel<F> &m, int c, const Chan &v) {
        m.base_color[c] = v.base;
        m.sheen_color[c] = v.sheen;
        m.subsurface_color[c] = v.subsurface;
    }
};

} // namespace bsdfkit
