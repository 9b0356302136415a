// Warps from [0,1)^2 to disks, hemispheres and spheres, with their densities.
#pragma once
#include <limits>

#include "math.h"

namespace bsdfkit {

// The largest value below 1 (pbrt-v4 OneMinusEpsilon): uniforms documented on [0, 1] are
// used on [0, 1), so a warp or a lobe CDF never sees u = 1.
template <typename F> inline constexpr F OneMinusEpsilon = F(1) - std::numeric_limits<F>::epsilon() / F(2);
template <typename F> inline F clamp_uniform(F u) {
    const F one_minus = F(OneMinusEpsilon<scalar_t<F>>);
    return min_(u, one_minus);  // select(u < one_minus, u, one_minus), NaN kept
}
template <typename F> inline Point2<F> clamp_uniform(Point2<F> u) { return {clamp_uniform(u.x), clamp_uniform(u.y)}; }

// Lobe choice between two lobes of (unnormalized) probabilities pr, pt with uc in [0, 1]: the
// first is taken with probability pr / (pr + pt); a lobe of probability 0 is never taken and
// the only nonzero lobe always is, at both ends of uc (uc = 1 with pt = 0 picks the first).
// uc (pr + pt) < pr is pbrt-v4's uc < pr / (pr + pt) without the division (pr, pt >= 0 finite).
template <typename F> inline Mask<F> ChooseFirstLobe(F uc, F pr, F pt) {
    return (pr > F(0)) & ((pt <= F(0)) | (uc * (pr + pt) < pr));
}

// Shirley & Chiu 1997 concentric map, (0,0) -> centre.
// r2: the squared radius of the point (x^2 + y^2 = r^2), for callers that need it without
// waiting for the angle (SampleCosineHemisphere).
template <typename F> inline Point2<F> SampleUniformDiskConcentric(Point2<F> u, F *r2 = nullptr) {
    F ox = F(2) * u.x - F(1), oy = F(2) * u.y - F(1);
    Mask<F> first = abs(ox) > abs(oy);
    F r = select(first, ox, oy), num = select(first, oy, ox);
    if (r2) *r2 = r * r;
    // den == 0 only at the centre (num == 0 too), where ratio = 0 as in safe_div. One division
    // of selected operands: two safe_divs let GCC's PRE build bool selects that do not vectorize.
    using S = scalar_t<F>;
    F ratio = num / select(r != F(0), r, F(1));
    // theta = x = pi/4 ratio (first) or pi/2 - x: |x| <= pi/4 is already reduced, so the sine and
    // cosine of x come straight from the polynomials (core/math.h sincos_poly), and
    // (cos, sin)(pi/2 - x) = (sin, cos)(x): no range reduction on the sampler's critical path.
    F s, c;
    sincos_poly(F(PiOver4<S>) * ratio, &s, &c);
    return {r * select(first, c, s), r * select(first, s, c)};
}

// Malley's method: project the concentric disk up to the hemisphere.
// z = sqrt(1 - r^2) from the disk's radius, r^2 = x^2 + y^2 (pbrt-v4 and Mitsuba take it from x and
// y): the square root then runs beside the angle's sincos instead of after it.
// *sin2_out (optional): sin^2 of the sample's angle to z, the disk radius^2 (exact, no 1 - z^2).
template <typename F> inline Vec3<F> SampleCosineHemisphere(Point2<F> u, F *sin2_out = nullptr) {
    F r2;
    Point2<F> d = SampleUniformDiskConcentric(u, &r2);
    if (sin2_out) *sin2_out = r2;
    F z = safe_sqrt(F(1) - r2);
    return {d.x, d.y, z};
}
template <typename F> inline F CosineHemispherePDF(F cos_theta) { return cos_theta * F(InvPi<scalar_t<F>>); }

template <typename F> inline Vec3<F> SampleUniformHemisphere(Point2<F> u) {
    F z = u.x, r = safe_sqrt(F(1) - z * z), phi = F(2) * Pi<F> * u.y;
    F sp, cp;
    sincos_(phi, &sp, &cp);
    return {r * cp, r * sp, z};
}
template <typename F> inline F UniformHemispherePDF() { return Inv2Pi<F>; }

template <typename F> inline Vec3<F> SampleUniformSphere(Point2<F> u) {
    F z = F(1) - F(2) * u.x, r = safe_sqrt(F(1) - z * z), phi = F(2) * Pi<F> * u.y;
    F sp, cp;
    sincos_(phi, &sp, &cp);
    return {r * cp, r * sp, z};
}
template <typename F> inline F UniformSpherePDF() { return F(0.25) * InvPi<F>; }

} // namespace bsdfkit
