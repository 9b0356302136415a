// Fixed-size spectrum: 3 RGB channels. Parameters are uniform per model.
#pragma once
#include <array>

#include "math.h"

namespace bsdfkit {

template <typename Float, int N = 3> struct Spectrum {
    static constexpr int Size = N;
    Float v[N];
    Spectrum() = default;
    explicit constexpr Spectrum(Float c) : v{} { for (int i = 0; i < N; ++i) v[i] = c; }
    Float &operator[](int i) { return v[i]; }
    const Float &operator[](int i) const { return v[i]; }
#define BSDFKIT_SPEC_OP(op)                                                                  \
    Spectrum operator op(const Spectrum &o) const {                                          \
        Spectrum r; for (int i = 0; i < N; ++i) r.v[i] = v[i] op o.v[i]; return r;           \
    }                                                                                        \
    Spectrum operator op(Float s) const {                                                    \
        Spectrum r; for (int i = 0; i < N; ++i) r.v[i] = v[i] op s; return r;                \
    }
    BSDFKIT_SPEC_OP(+) BSDFKIT_SPEC_OP(-) BSDFKIT_SPEC_OP(*) BSDFKIT_SPEC_OP(/)
#undef BSDFKIT_SPEC_OP
    Float max_component() const { Float m = v[0]; for (int i = 1; i < N; ++i) m = max_(m, v[i]); return m; }
    Float average() const { Float s = 0; for (int i = 0; i < N; ++i) s += v[i]; return s / N; }
    bool is_black() const { bool b = true; for (int i = 0; i < N; ++i) b = b && (v[i] == Float(0)); return b; }
};
template <typename Float, int N> struct is_lane_struct<Spectrum<Float, N>> : std::true_type {};
template <typename Float, int N>
inline Spectrum<Float, N> operator*(Float s, const Spectrum<Float, N> &a) { return a * s; }
template <typename Float, int N>
inline Spectrum<Float, N> operator-(Float s, const Spectrum<Float, N> &a) { return Spectrum<Float, N>(s) - a; }
template <typename Float, int N>
inline Spectrum<Float, N> select(const Mask<Float> &c, const Spectrum<Float, N> &a, const Spectrum<Float, N> &b) {
    Spectrum<Float, N> r; for (int i = 0; i < N; ++i) r.v[i] = select(c, a.v[i], b.v[i]); return r;
}

// Rec. 709 luminance of linear RGB, with Mitsuba 3's weights (core/spectrum.h luminance).
template <typename Float> inline Float Luminance(const Spectrum<Float> &s) {
    return Float(0.212671) * s[0] + Float(0.715160) * s[1] + Float(0.072169) * s[2];
}

// An RGB parameter (Params field: double, or a Dual for a Dual model) at the model's precision.
template <typename Float, typename S> inline Spectrum<Float> to_spectrum(const std::array<S, 3> &a) {
    Spectrum<Float> s;
    for (int i = 0; i < 3; ++i) s[i] = Float(a[size_t(i)]);
    return s;
}

// A colour parameter of any channel count at the channel type C (the model's F, or a packet).
template <typename C, typename S, size_t N> inline Spectrum<C, int(N)> to_channels(const std::array<S, N> &a) {
    Spectrum<C, int(N)> s;
    for (size_t i = 0; i < N; ++i) s[int(i)] = C(a[i]);
    return s;
}

} // namespace bsdfkit
