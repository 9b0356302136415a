// Float atan2 for the lat-long mapping of environment maps, branch-light and about 2 ulp: the
// minimax polynomial of Cephes' atanf (S. L. Moshier, "Methods and Programs for Mathematical
// Functions", 1989). glibc's atan2/sin/cos were ~10 % of the renderer's time (every environment
// lookup and sample needs them); sin and cos come from core/math.h's sincos_, as in the models.
#pragma once
#include <cmath>
#include <cstdint>

namespace bsdfkit::render {

// atan(t) for t in [0, 1]: Cephes atanf's reduction around tan(pi/8) and its polynomial.
inline float fast_atan01(float t) {
    bool big = t > 0.41421356237309503f;
    float x = big ? (t - 1.f) / (t + 1.f) : t;
    float z = x * x;
    float y = (((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * x + x;
    return big ? y + 0.78539816339744831f : y;
}

// atan2(y, x) in (-pi, pi]; 0 for (0, 0).
inline float fast_atan2(float y, float x) {
    float ax = std::abs(x), ay = std::abs(y);
    float mx = ax > ay ? ax : ay, mn = ax > ay ? ay : ax;
    float a = mx > 0.f ? fast_atan01(mn / mx) : 0.f;
    a = ay > ax ? 1.5707963267948966f - a : a;
    a = x < 0.f ? 3.14159265358979323846f - a : a;
    return y < 0.f ? -a : a;
}

} // namespace bsdfkit::render
