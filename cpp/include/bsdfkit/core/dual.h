// Forward-mode dual numbers: Dual<T, K> = a value and K partial derivatives, K fixed at compile
// time, used as a model's Float so that d f / d theta comes out of the one model implementation
// (bindings/models_grad.cpp instantiates the models with F = Dual<double, K>).
//
// Design
//  * Arithmetic and the math functions the model code calls (sqrt, abs, exp, log, pow, floor,
//    sincos_, atan2, acos, asin, erf, fma, copysign, min/max through the selects of core/math.h)
//    propagate the partials by the chain rule (Griewank & Walther 2008, ch. 3).
//  * Comparisons compare the values and return bool, so the model code's masks (`active &= ...`,
//    `select`, `c ? a : b`) work unchanged, and a select carries the whole chosen Dual: a branch
//    that is not taken cannot leak a NaN partial. Mask<Dual> is bool.
//  * No conversion to T: dropping the partials is explicit (value_of), so a parameter cannot
//    lose its derivative silently on the way through a model's preprocessing.
//  * The parameters are seeded where the model is built: a model's Params are templated on their
//    scalar type (core/math.h param_t: double for float/double models, Dual for a Dual model), and
//    make() computes every derived quantity (Schlick F0, F82 a, Filament's f0 / alpha / DFG row)
//    in that type, so the derivative flows through the preprocessing.
//
// Where the derivative is a one-sided limit or zero (documented once here; the models' headers
// and Python docstrings refer to this list):
//  * Selects and clamps (max_, min_, clamp, saturate, finite_or_zero): the derivative of the
//    branch taken, so at a kink the one-sided derivative of the side the comparison picks
//    (e.g. clamp(x, lo, hi) at x == lo has the derivative of x, since `x < lo` is false), and 0
//    where a bound is active.
//  * Microfacet smooth/rough switch (max(alpha) < 1e-3 makes the lobe a delta, whose f is 0):
//    below it f and its derivative are 0; at and above it, the rough lobe's derivative (the
//    switch is a discontinuity of f, not differentiable). The alpha floor 1e-4 of a rough lobe's
//    other axis gives that axis a zero derivative below 1e-4.
//  * sqrt at 0: derivative taken as 0 (the one-sided derivative is infinite); likewise pow(x, y)
//    with x == 0 and log at 0 give 0 partials instead of inf/NaN.
//  * Table lookups (Filament's DFG): the derivative of the bilinear interpolant along roughness
//    and NoV, i.e. piecewise constant between nodes, one-sided at the nodes.
//  * Integer-valued steps (floor in sincos_'s range reduction): derivative 0.
#pragma once
#include <cmath>
#include <cstdint>
#include <limits>

#include "math.h"

namespace bsdfkit {

template <typename T, int K> struct Dual {
    static_assert(K >= 1, "Dual: at least one partial");
    static constexpr int Size = K;
    T v;
    T d[K];

    constexpr Dual() : v(0), d{} {}
    constexpr Dual(T x) : v(x), d{} {}  // a constant (implicit, as F(0.5) or `F x = 0` in model code)
    template <typename U, std::enable_if_t<std::is_arithmetic_v<U> && !std::is_same_v<U, T>, int> = 0>
    constexpr Dual(U x) : v(T(x)), d{} {}
    // A variable: value x with d/dtheta_i = 1.
    static constexpr Dual variable(T x, int i) {
        Dual r(x);
        r.d[i] = T(1);
        return r;
    }

    // ---- arithmetic (chain rule)
    friend constexpr Dual operator+(const Dual &a) { return a; }
    friend constexpr Dual operator-(const Dual &a) {
        Dual r;
        r.v = -a.v;
        for (int i = 0; i < K; ++i) r.d[i] = -a.d[i];
        return r;
    }
    friend constexpr Dual operator+(const Dual &a, const Dual &b) {
        Dual r;
        r.v = a.v + b.v;
        for (int i = 0; i < K; ++i) r.d[i] = a.d[i] + b.d[i];
        return r;
    }
    friend constexpr Dual operator-(const Dual &a, const Dual &b) {
        Dual r;
        r.v = a.v - b.v;
        for (int i = 0; i < K; ++i) r.d[i] = a.d[i] - b.d[i];
        return r;
    }
    friend constexpr Dual operator*(const Dual &a, const Dual &b) {
        Dual r;
        r.v = a.v * b.v;
        for (int i = 0; i < K; ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
        return r;
    }
    // Values are computed exactly as the plain-number operation (a.v / b.v, not a.v * (1 / b.v)),
    // so the value of a Dual evaluation is bit-identical to the double evaluation.
    friend constexpr Dual operator/(const Dual &a, const Dual &b) {
        Dual r;
        T inv = T(1) / b.v;
        r.v = a.v / b.v;
        for (int i = 0; i < K; ++i) r.d[i] = (a.d[i] - r.v * b.d[i]) * inv;
        return r;
    }
    // with a constant (no partials to combine)
    friend constexpr Dual operator+(const Dual &a, T b) { Dual r = a; r.v += b; return r; }
    friend constexpr Dual operator+(T a, const Dual &b) { Dual r = b; r.v += a; return r; }
    friend constexpr Dual operator-(const Dual &a, T b) { Dual r = a; r.v -= b; return r; }
    friend constexpr Dual operator-(T a, const Dual &b) { Dual r = -b; r.v += a; return r; }
    friend constexpr Dual operator*(const Dual &a, T b) {
        Dual r;
        r.v = a.v * b;
        for (int i = 0; i < K; ++i) r.d[i] = a.d[i] * b;
        return r;
    }
    friend constexpr Dual operator*(T a, const Dual &b) { return b * a; }
    friend constexpr Dual operator/(const Dual &a, T b) {
        Dual r;
        r.v = a.v / b;
        T inv = T(1) / b;
        for (int i = 0; i < K; ++i) r.d[i] = a.d[i] * inv;
        return r;
    }
    friend constexpr Dual operator/(T a, const Dual &b) {
        Dual r;
        T inv = T(1) / b.v;
        r.v = a / b.v;
        T s = -r.v * inv;  // d(a/b) = -a/b^2 db
        for (int i = 0; i < K; ++i) r.d[i] = s * b.d[i];
        return r;
    }
    Dual &operator+=(const Dual &o) { return *this = *this + o; }
    Dual &operator-=(const Dual &o) { return *this = *this - o; }
    Dual &operator*=(const Dual &o) { return *this = *this * o; }
    Dual &operator/=(const Dual &o) { return *this = *this / o; }

    // ---- comparisons on the value (masks are bool)
    friend constexpr bool operator<(const Dual &a, const Dual &b) { return a.v < b.v; }
    friend constexpr bool operator<=(const Dual &a, const Dual &b) { return a.v <= b.v; }
    friend constexpr bool operator>(const Dual &a, const Dual &b) { return a.v > b.v; }
    friend constexpr bool operator>=(const Dual &a, const Dual &b) { return a.v >= b.v; }
    friend constexpr bool operator==(const Dual &a, const Dual &b) { return a.v == b.v; }
    friend constexpr bool operator!=(const Dual &a, const Dual &b) { return a.v != b.v; }
    friend constexpr bool operator<(const Dual &a, T b) { return a.v < b; }
    friend constexpr bool operator<=(const Dual &a, T b) { return a.v <= b; }
    friend constexpr bool operator>(const Dual &a, T b) { return a.v > b; }
    friend constexpr bool operator>=(const Dual &a, T b) { return a.v >= b; }
    friend constexpr bool operator==(const Dual &a, T b) { return a.v == b; }
    friend constexpr bool operator!=(const Dual &a, T b) { return a.v != b; }
    friend constexpr bool operator<(T a, const Dual &b) { return a < b.v; }
    friend constexpr bool operator<=(T a, const Dual &b) { return a <= b.v; }
    friend constexpr bool operator>(T a, const Dual &b) { return a > b.v; }
    friend constexpr bool operator>=(T a, const Dual &b) { return a >= b.v; }
    friend constexpr bool operator==(T a, const Dual &b) { return a == b.v; }
    friend constexpr bool operator!=(T a, const Dual &b) { return a != b.v; }
};

template <typename T> struct is_dual : std::false_type {};
template <typename T, int K> struct is_dual<Dual<T, K>> : std::true_type {};

// core/simd.h traits: a Dual is a scalar evaluation type (Mask = bool, one lane) whose scalar_t
// (the type of constants and tables) is its value type; core/math.h: a Dual model's Params hold Duals.
template <typename T, int K> struct simd_traits<Dual<T, K>, void> {
    using Scalar = T;
    using Mask = bool;
    static constexpr size_t Width = 1;
};
template <typename T, int K> struct ParamOf<Dual<T, K>> { using type = Dual<T, K>; };

template <typename T, int K> constexpr T value_of(const Dual<T, K> &x) { return x.v; }
// Whether any partial is non-zero (a parameter being differentiated).
template <typename T, int K> constexpr bool is_variable(const Dual<T, K> &x) {
    bool b = false;
    for (int i = 0; i < K; ++i) b = b | (x.d[i] != T(0));
    return b;
}

// f(x) with f'(x) = df: the value fx and the chain rule on every partial.
template <typename T, int K> constexpr Dual<T, K> chain(const Dual<T, K> &x, T fx, T df) {
    Dual<T, K> r;
    r.v = fx;
    for (int i = 0; i < K; ++i) r.d[i] = df * x.d[i];
    return r;
}

// ---- the math functions (found by ordinary lookup in namespace bsdfkit and by ADL)
template <typename T, int K> inline Dual<T, K> sqrt(const Dual<T, K> &x) {
    T s = std::sqrt(x.v);
    return chain(x, s, s > T(0) ? T(0.5) / s : T(0));  // 0 at x = 0 (see the list above)
}
template <typename T, int K> inline Dual<T, K> abs(const Dual<T, K> &x) { return std::signbit(x.v) ? -x : x; }
template <typename T, int K> inline Dual<T, K> fabs(const Dual<T, K> &x) { return abs(x); }
template <typename T, int K> inline Dual<T, K> exp(const Dual<T, K> &x) {
    T e = std::exp(x.v);
    return chain(x, e, e);
}
template <typename T, int K> inline Dual<T, K> log(const Dual<T, K> &x) {
    return chain(x, std::log(x.v), x.v > T(0) ? T(1) / x.v : T(0));
}
template <typename T, int K> inline Dual<T, K> floor(const Dual<T, K> &x) { return Dual<T, K>(std::floor(x.v)); }
template <typename T, int K> inline Dual<T, K> ceil(const Dual<T, K> &x) { return Dual<T, K>(std::ceil(x.v)); }
template <typename T, int K> inline Dual<T, K> sin(const Dual<T, K> &x) { return chain(x, std::sin(x.v), std::cos(x.v)); }
template <typename T, int K> inline Dual<T, K> cos(const Dual<T, K> &x) { return chain(x, std::cos(x.v), -std::sin(x.v)); }
template <typename T, int K> inline Dual<T, K> tan(const Dual<T, K> &x) {
    T t = std::tan(x.v);
    return chain(x, t, T(1) + t * t);
}
template <typename T, int K> inline Dual<T, K> asin(const Dual<T, K> &x) {
    T s = std::sqrt(T(1) - x.v * x.v);
    return chain(x, std::asin(x.v), s > T(0) ? T(1) / s : T(0));
}
template <typename T, int K> inline Dual<T, K> acos(const Dual<T, K> &x) {
    T s = std::sqrt(T(1) - x.v * x.v);
    return chain(x, std::acos(x.v), s > T(0) ? T(-1) / s : T(0));
}
template <typename T, int K> inline Dual<T, K> atan(const Dual<T, K> &x) {
    return chain(x, std::atan(x.v), T(1) / (T(1) + x.v * x.v));
}
// d atan2(y, x) = (x dy - y dx) / (x^2 + y^2)
template <typename T, int K> inline Dual<T, K> atan2(const Dual<T, K> &y, const Dual<T, K> &x) {
    Dual<T, K> r;
    r.v = std::atan2(y.v, x.v);
    T n = x.v * x.v + y.v * y.v;
    T inv = n > T(0) ? T(1) / n : T(0);
    for (int i = 0; i < K; ++i) r.d[i] = (x.v * y.d[i] - y.v * x.d[i]) * inv;
    return r;
}
// d erf(x) = 2/sqrt(pi) exp(-x^2) dx
template <typename T, int K> inline Dual<T, K> erf(const Dual<T, K> &x) {
    return chain(x, std::erf(x.v), T(1.12837916709551257390) * std::exp(-x.v * x.v));
}
// x^y for a Dual exponent too: d(x^y) = y x^(y-1) dx + x^y log(x) dy (0 where x == 0).
template <typename T, int K> inline Dual<T, K> pow(const Dual<T, K> &x, const Dual<T, K> &y) {
    Dual<T, K> r;
    T p = std::pow(x.v, y.v);
    r.v = p;
    T dx = x.v != T(0) ? y.v * std::pow(x.v, y.v - T(1)) : T(0);
    T dy = x.v > T(0) ? p * std::log(x.v) : T(0);
    for (int i = 0; i < K; ++i) r.d[i] = dx * x.d[i] + dy * y.d[i];
    return r;
}
template <typename T, int K> inline Dual<T, K> pow(const Dual<T, K> &x, T y) { return pow(x, Dual<T, K>(y)); }
template <typename T, int K> inline Dual<T, K> pow(T x, const Dual<T, K> &y) { return pow(Dual<T, K>(x), y); }
// mul_add's dual form (core/math.h): the value fused as in plain code, so eval_grad's value is eval's.
template <typename T, int K> inline Dual<T, K> fmadd(const Dual<T, K> &a, const Dual<T, K> &b, const Dual<T, K> &c) {
    Dual<T, K> r;
    r.v = mul_add(a.v, b.v, c.v);
    for (int i = 0; i < K; ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i] + c.d[i];
    return r;
}
template <typename T, int K> inline Dual<T, K> copysign(const Dual<T, K> &mag, const Dual<T, K> &sgn) {
    bool flip = std::signbit(mag.v) != std::signbit(sgn.v);
    return flip ? -mag : mag;
}
template <typename T, int K> inline bool isfinite(const Dual<T, K> &x) { return std::isfinite(x.v); }
template <typename T, int K> inline bool isnan(const Dual<T, K> &x) { return std::isnan(x.v); }

// core/math.h's sincos_ on the value (its range reduction is integer-valued), chain rule after.
template <typename T, int K> inline void sincos_(Dual<T, K> x, Dual<T, K> *s, Dual<T, K> *c) {
    T sv, cv;
    sincos_(x.v, &sv, &cv);
    *s = chain(x, sv, cv);
    *c = chain(x, cv, -sv);
}

// core/math.h's keep_or_zero masks bits of a float; for a Dual, the whole number.
template <typename T, int K> inline Dual<T, K> keep_or_zero(const Dual<T, K> &x, bool keep) {
    return keep ? x : Dual<T, K>(T(0));
}

// core/bsdf.h's last line of defence, for a Dual: a value that is not finite and >= 0 zeroes the
// whole number, as for a float; a non-finite partial of a kept value (a degenerate limit where
// the value stays finite, e.g. D at the horizon) is zeroed too, so no NaN leaves eval_grad.
template <typename T, int K> inline Dual<T, K> finite_or_zero(Dual<T, K> x) {
    bool ok = (x.v >= T(0)) & (x.v <= std::numeric_limits<T>::max());
    if (!ok) return Dual<T, K>(T(0));
    for (int i = 0; i < K; ++i) x.d[i] = std::isfinite(x.d[i]) ? x.d[i] : T(0);
    return x;
}

} // namespace bsdfkit

// numeric_limits of the value type (core/frame.h, core/bsdf.h read min / max / infinity).
template <typename T, int K> struct std::numeric_limits<bsdfkit::Dual<T, K>> : std::numeric_limits<T> {
    using D = bsdfkit::Dual<T, K>;
    static constexpr D min() noexcept { return D(std::numeric_limits<T>::min()); }
    static constexpr D max() noexcept { return D(std::numeric_limits<T>::max()); }
    static constexpr D lowest() noexcept { return D(std::numeric_limits<T>::lowest()); }
    static constexpr D epsilon() noexcept { return D(std::numeric_limits<T>::epsilon()); }
    static constexpr D infinity() noexcept { return D(std::numeric_limits<T>::infinity()); }
    static constexpr D quiet_NaN() noexcept { return D(std::numeric_limits<T>::quiet_NaN()); }
};
