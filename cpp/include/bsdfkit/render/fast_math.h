// Float sin/cos and atan2 for the lat-long mapping of environment maps, branch-light and about
// 2 ulp: Cody-Waite range reduction and the minimax polynomials of Cephes' sinf/cosf/atanf
// (S. L. Moshier, "Methods and Programs for Mathematical Functions", 1989). glibc's versions
// were ~10 % of the renderer's time (every environment lookup and sample needs them).
#pragma once
#include <cmath>
#include <cstdint>

namespace bsdfkit::render {

// sin(x), cos(x) for |x| up to ~1e4 (the renderer passes [0, 2 pi]).
inline void fast_sincos(float x, float *s, float *c) {
    float j = std::nearbyint(x * 0.63661977236758134f);  // x / (pi / 2)
    // x - j pi/2 in three parts (pi/2 = DP1 + DP2 + DP3), exact products for |j| < 2^11
    float r = ((x - j * 1.5703125f) - j * 4.837512969970703125e-4f) - j * 7.54978995489188216e-8f;
    float z = r * r;
    float sr = r + r * z * ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f);
    float cr = 1.f - 0.5f * z + z * z * ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f);
    int q = int(int64_t(j) & 3);
    float ss = (q & 1) ? cr : sr, cc = (q & 1) ? sr : cr;
    *s = (q & 2) ? -ss : ss;
    *c = ((q + 1) & 2) ? -cc : cc;
}

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
