// Pinhole perspective camera (look-at form, world y-up) and the shading frame of a hit.
#pragma once
#include "material.h"

namespace bsdfkit::render {

// fov is the full horizontal field of view (Mitsuba's default fov_axis = "x"). Image x grows
// along right = forward x up, image rows grow downward (row 0 at the top).
struct Camera {
    Vec3f origin{0, 0, 0}, forward{0, 0, -1}, right{1, 0, 0}, up{0, 1, 0};
    Float tan_half_fov = Float(0.36397); // tan(20 deg)

    static Camera look_at(const Vec3f &origin, const Vec3f &target, const Vec3f &up_hint, Float fov_deg) {
        Camera c;
        c.origin = origin;
        c.forward = normalize(target - origin);
        c.right = normalize(cross(c.forward, up_hint));
        c.up = cross(c.right, c.forward);
        c.tan_half_fov = std::tan(fov_deg * Pi<Float> / Float(360));
        return c;
    }

    // Primary ray direction through film position (fx, fy) in pixels, (0, 0) = top-left corner.
    // The per-image scales are loop invariants of the caller's pixel loop (one division each per
    // image, not per ray).
    Vec3f direction(Float fx, Float fy, int width, int height) const {
        const Float kx = Float(2) / Float(width), ky = Float(2) / Float(height);
        Float sx = mul_add(fx, kx, Float(-1)) * tan_half_fov;
        Float sy = mul_add(-fy, ky, Float(1)) * (tan_half_fov * Float(height) / Float(width));
        return normalize(forward + sx * right + sy * up);
    }
};

// Orthonormal shading frame: z = n, x = the tangent made orthogonal to n.
struct Frame {
    Vec3f s, t, n;

    Frame() = default;
    // Branchless orthonormal basis around n (Duff et al. 2017, "Building an orthonormal basis, revisited").
    static void basis(const Vec3f &n, Vec3f *b1, Vec3f *b2) {
        Float sign = std::copysign(Float(1), n.z);
        Float a = Float(-1) / (sign + n.z), b = n.x * n.y * a;
        *b1 = Vec3f(Float(1) + sign * n.x * n.x * a, sign * b, -sign * n.x);
        *b2 = Vec3f(b, sign + n.y * n.y * a, -n.y);
    }

    Frame(const Vec3f &normal, const Vec3f &tangent) : n(normal) {
        Vec3f ts = tangent - n * dot(n, tangent);
        Float l2 = length_squared(ts);
        if (l2 > Float(1e-12)) {
            s = ts / std::sqrt(l2);
            t = cross(n, s);
        } else {
            basis(n, &s, &t);
        }
    }
    Vec3f to_local(const Vec3f &v) const { return Vec3f(dot(v, s), dot(v, t), dot(v, n)); }
    Vec3f to_world(const Vec3f &v) const {
        return {mul_add(s.x, v.x, mul_add(t.x, v.y, n.x * v.z)), mul_add(s.y, v.x, mul_add(t.y, v.y, n.y * v.z)),
                mul_add(s.z, v.x, mul_add(t.z, v.y, n.z * v.z))};
    }
};

} // namespace bsdfkit::render
