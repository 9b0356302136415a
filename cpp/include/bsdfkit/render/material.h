// Type-erased material of the preview renderer: one of the per-element models, used only
// through the BSDF-level wrappers of core/bsdf.h (no second implementation of any model).
// The materials are exactly the compiled models of bxdfs/all.h: nothing to add here for a new model.
#pragma once
#include <variant>

#include "../bxdfs/all.h"
#include "../core/bsdf.h"

namespace bsdfkit::render {

// The renderer's precision knob: scenes are traced in float (Embree is float-only).
using Float = float;
using Vec3f = Vec3<Float>;
using RGB = Spectrum<Float>;

using Material = AllModels::Variant<Float>;

// The renderer only solves the light transport equation for radiance (camera paths).
inline constexpr TransportMode kMode = TransportMode::Radiance;

inline uint8_t material_flags(const Material &m) {
    return std::visit([](const auto &b) { return b.flags(); }, m);
}
inline RGB material_f(const Material &m, const Vec3f &wo, const Vec3f &wi) {
    return std::visit([&](const auto &b) { return bsdf_f(b, wo, wi, kMode); }, m);
}
inline Float material_pdf(const Material &m, const Vec3f &wo, const Vec3f &wi) {
    return std::visit([&](const auto &b) { return bsdf_pdf(b, wo, wi, kMode, uint8_t(RT_All)); }, m);
}
inline BSDFSample<Float> material_sample(const Material &m, const Vec3f &wo, Float uc, Point2<Float> u) {
    return std::visit([&](const auto &b) { return bsdf_sample(b, wo, uc, u, kMode, uint8_t(RT_All)); }, m);
}
// pbrt-v4 IsNonSpecular: the lobes light sampling can reach.
inline bool has_nonspecular(uint8_t flags) { return (flags & (Diffuse | Glossy)) != 0; }

} // namespace bsdfkit::render
