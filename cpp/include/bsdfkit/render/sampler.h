// Random streams and MIS weights shared by the RGB and spectral integrators of the preview renderer.
#pragma once
#include <cmath>
#include <cstdint>

#include "../core/rng.h"
#include "material.h"

namespace bsdfkit::render {

// SplitMix64 stream seeded from (seed, pixel, sample): independent of tiles and threads.
struct SampleRng {
    uint64_t state = 0;
    SampleRng() = default;
    SampleRng(uint64_t seed, uint64_t pixel, uint64_t sample) : state(hash3(seed, pixel, sample)) {}
    Float next() {
        state += 0x9e3779b97f4a7c15ull;
        return uniform_from_bits<Float>(mix64(state));
    }
    double next_double() {
        state += 0x9e3779b97f4a7c15ull;
        return uniform_from_bits<double>(mix64(state));
    }
    Point2<Float> next2() {
        Float a = next();
        return Point2<Float>{a, next()};
    }
};

// Power heuristic with beta = 2 for one sample of each technique (Veach 1997 eq. 9.13).
inline Float power_heuristic(Float f, Float g) {
    Float f2 = f * f, g2 = g * g;
    if (std::isinf(f2)) return Float(1);
    return f2 + g2 > Float(0) ? f2 / (f2 + g2) : Float(0);
}

} // namespace bsdfkit::render
