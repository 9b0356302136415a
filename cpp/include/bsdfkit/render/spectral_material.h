// The materials of the preview renderer's spectral mode (render/spectral.h): the spectral
// forms of the models (spectral/all.h) at the renderer's precision. Kept apart from spectral.h (no
// Embree) so that the spectral bindings (cpp/bindings/spectral.cpp) can convert their models.
#pragma once
#include <variant>

#include "../spectral/all.h"
#include "material.h"

namespace bsdfkit::render {

using Spec4 = Spectrum4<Float>;

// A material's spectral form (float), of any model of the list that declares one (core/bxdf.h
// `Spectral`); monostate: the material has none.
using SpectralMaterial = AllModels::SpectralVariant<Float>;

} // namespace bsdfkit::render
