// Result of sampling a BxDF. `valid` replaces pbrt-v4's optional<> so that batch
// loops stay branch-free: an invalid sample has f = 0, pdf = 0.
#pragma once
#include "flags.h"
#include "spectrum.h"

namespace bsdfkit {

template <typename F> struct BSDFSample {
    Spectrum<F> f{F(0)};
    Vec3<F> wi{0, 0, 0};
    F pdf = 0;
    uint8_t flags = Unset;
    F eta = 1;
    bool pdf_is_proportional = false;
    bool valid = false;

    bool is_reflection() const { return flags & Reflection; }
    bool is_transmission() const { return flags & Transmission; }
    bool is_specular() const { return flags & Specular; }
};

template <typename F> inline BSDFSample<F> invalid_sample() { return BSDFSample<F>{}; }

} // namespace bsdfkit
