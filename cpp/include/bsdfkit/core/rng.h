// Counter-based random numbers: a value depends only on (seed, stream, index),
// so results never depend on thread count or chunking.
#pragma once
#include <cstdint>

namespace bsdfkit {

// SplitMix64 finaliser (Steele, Lea, Flood 2014), used as a 64-bit hash.
inline uint64_t mix64(uint64_t z) {
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
inline uint64_t hash3(uint64_t a, uint64_t b, uint64_t c) { return mix64(mix64(mix64(a) ^ b) ^ c); }

// Uniform in [0, 1): top bits of a hash, exactly representable in Float.
template <typename Float> inline Float uniform_from_bits(uint64_t h);
template <> inline float uniform_from_bits<float>(uint64_t h) { return float(h >> 40) * 0x1p-24f; }
template <> inline double uniform_from_bits<double>(uint64_t h) { return double(h >> 11) * 0x1p-53; }

} // namespace bsdfkit
