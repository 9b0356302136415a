// Float atan2 for the lat-long mapping of environment maps, branch-free and about 2 ulp: the
// minimax polynomial of Cephes' atanf (S. L. Moshier, "Methods and Programs for Mathematical
// Functions", 1989). glibc's atan2/sin/cos were ~10 % of the renderer's time (every environment
// lookup and sample needs them); sin and cos come from core/math.h's sincos_, as in the models.
// Written once on V = float or a float packet (selects, no branches): a packet lane returns the
// scalar call's bits.
#pragma once
#include <cmath>
#include <cstdint>

#include "../core/math.h"

namespace bsdfkit::render {

// atan(t) for t in [0, 1]: Cephes atanf's reduction around tan(pi/8) and its polynomial.
template <typename V> inline V fast_atan01(V t) {
    auto big = t > V(0.41421356237309503f);
    V x = select(big, (t - V(1.f)) / (t + V(1.f)), t);
    V z = x * x;
    V y = (((V(8.05374449538e-2f) * z - V(1.38776856032e-1f)) * z + V(1.99777106478e-1f)) * z - V(3.33329491539e-1f)) *
              z * x + x;
    return select(big, y + V(0.78539816339744831f), y);
}

// atan2(y, x) in (-pi, pi]; 0 for (0, 0).
template <typename V> inline V fast_atan2(V y, V x) {
    V ax = abs(x), ay = abs(y);
    auto xbig = ax > ay;
    V mx = select(xbig, ax, ay), mn = select(xbig, ay, ax);
    V a = select(mx > V(0.f), fast_atan01(mn / mx), V(0.f));
    a = select(ay > ax, V(1.5707963267948966f) - a, a);
    a = select(x < V(0.f), V(3.14159265358979323846f) - a, a);
    return select(y < V(0.f), -a, a);
}

} // namespace bsdfkit::render
