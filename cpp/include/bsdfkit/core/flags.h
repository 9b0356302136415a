// Enumerations mirroring pbrt-v4's names (BxDFFlags, BxDFReflTransFlags, TransportMode).
#pragma once
#include <cstdint>

namespace bsdfkit {

enum class TransportMode : uint8_t { Radiance = 0, Importance = 1 };

enum BxDFFlags : uint8_t {
    Unset = 0,
    Reflection = 1 << 0,
    Transmission = 1 << 1,
    Diffuse = 1 << 2,
    Glossy = 1 << 3,
    Specular = 1 << 4,
    DiffuseReflection = Diffuse | Reflection,
    DiffuseTransmission = Diffuse | Transmission,
    GlossyReflection = Glossy | Reflection,
    GlossyTransmission = Glossy | Transmission,
    SpecularReflection = Specular | Reflection,
    SpecularTransmission = Specular | Transmission,
    All = Diffuse | Glossy | Specular | Reflection | Transmission
};
inline BxDFFlags operator|(BxDFFlags a, BxDFFlags b) { return BxDFFlags(uint8_t(a) | uint8_t(b)); }

enum ReflTrans : uint8_t { RT_Unset = 0, RT_Reflection = 1, RT_Transmission = 2, RT_All = 3 };

inline bool is_specular(uint8_t f) { return f & Specular; }

} // namespace bsdfkit
