// Scalar math vocabulary shared by every model. Written so that GCC can
// if-convert and vectorize it: selects instead of branches, no fmin/fmax
// (their NaN rules block vectorization), no errno-setting calls.
#pragma once
#include <cmath>
#include <cstdint>
#include <limits>

namespace bsdfkit {

template <typename Float> inline constexpr Float Pi = Float(3.14159265358979323846);
template <typename Float> inline constexpr Float InvPi = Float(0.31830988618379067154);
template <typename Float> inline constexpr Float Inv2Pi = Float(0.15915494309189533577);
template <typename Float> inline constexpr Float PiOver2 = Float(1.57079632679489661923);
template <typename Float> inline constexpr Float PiOver4 = Float(0.78539816339744830962);

template <typename T> inline T sqr(T x) { return x * x; }
template <typename T> inline T select(bool c, T a, T b) { return c ? a : b; }
// max/min as selects: operands are finite in every use, and selects vectorize.
template <typename T> inline T max_(T a, T b) { return a > b ? a : b; }
template <typename T> inline T min_(T a, T b) { return a < b ? a : b; }
template <typename T> inline T clamp(T x, T lo, T hi) { return x < lo ? lo : (x > hi ? hi : x); }
template <typename T> inline T lerp(T t, T a, T b) { return (1 - t) * a + t * b; }
template <typename T> inline T safe_sqrt(T x) { return std::sqrt(x > T(0) ? x : T(0)); }
template <typename T> inline T safe_div(T a, T b) { return b != T(0) ? a / b : T(0); }
template <typename T> inline T copysign1(T mag, T sgn) { return sgn < T(0) ? -mag : mag; }

template <typename Float> struct Vec3 {
    Float x, y, z;
    Vec3() = default;
    constexpr Vec3(Float x, Float y, Float z) : x(x), y(y), z(z) {}
    Vec3 operator+(const Vec3 &o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3 operator-(const Vec3 &o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3 operator*(Float s) const { return {x * s, y * s, z * s}; }
    Vec3 operator/(Float s) const { Float r = Float(1) / s; return {x * r, y * r, z * r}; }
};
template <typename Float> inline Vec3<Float> operator*(Float s, const Vec3<Float> &v) { return v * s; }
template <typename Float> inline Float dot(const Vec3<Float> &a, const Vec3<Float> &b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename Float> inline Float absdot(const Vec3<Float> &a, const Vec3<Float> &b) {
    return std::abs(dot(a, b));
}
template <typename Float> inline Vec3<Float> cross(const Vec3<Float> &a, const Vec3<Float> &b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename Float> inline Float length_squared(const Vec3<Float> &v) { return dot(v, v); }
template <typename Float> inline Vec3<Float> normalize(const Vec3<Float> &v) {
    return v / std::sqrt(dot(v, v));
}
template <typename Float> inline Vec3<Float> select(bool c, const Vec3<Float> &a, const Vec3<Float> &b) {
    return {c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z};
}
// Flip v into the hemisphere of n.
template <typename Float> inline Vec3<Float> face_forward(const Vec3<Float> &v, const Vec3<Float> &n) {
    return dot(v, n) < Float(0) ? -v : v;
}

template <typename Float> struct Point2 {
    Float x, y;
};

} // namespace bsdfkit
