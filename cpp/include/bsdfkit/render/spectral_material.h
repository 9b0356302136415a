// The materials of the preview renderer's spectral mode (render/spectral.h): the spectral
// adapters of batch_spectral.h at the renderer's precision. Kept apart from spectral.h (no
// Embree) so that the spectral bindings (cpp/bindings/spectral.cpp) can convert their models.
#pragma once
#include <variant>

#include "../batch_spectral.h"
#include "../spectral/hair_spectral.h"
#include "../spectral/layered_spectral.h"
#include "../spectral/measured_spectral.h"
#include "material.h"

namespace bsdfkit::render {

using Spec4 = Spectrum4<Float>;

// A material's spectral adapter (float); monostate: the material has none.
using SpectralMaterial =
    std::variant<std::monostate, DiffuseSpectral<Float>, DiffuseTransmissionSpectral<Float>, ConductorSpectral<Float>,
                 ConductorSchlickSpectral<Float>, ConductorF82Spectral<Float>, DielectricSpectral<Float>,
                 ThinDielectricSpectral<Float>, PlasticSpectral<Float>, FilamentStandardSpectral<Float>,
                 FilamentStandardCoatSpectral<Float>, FilamentStandardSheenSpectral<Float>,
                 FilamentStandardCoatSheenSpectral<Float>, CoatedDiffuseAnalyticSpectral<Float>,
                 CoatedConductorAnalyticSpectral<Float>, NormalizedFresnelSpectral<Float>,
                 HairSpectral<Float>,
                 MeasuredSpectral<Float>, MERLNearestSpectral<Float>, MERLLinearSpectral<Float>,
                 CoatedDiffuseSpectral<Float>, CoatedConductorSpectral<Float>>;

} // namespace bsdfkit::render
