// The orthonormal shading frame of a surface hit (render/scene.h's Hit carries one).
#pragma once
#include "material.h"

namespace bsdfkit::render {

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

    // Gram-Schmidt: tangent made orthogonal to the unit normal, then normalized (any tangent).
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
    // Any frame around a unit normal (basis).
    static Frame around(const Vec3f &normal) {
        Frame f;
        f.n = normal;
        basis(normal, &f.s, &f.t);
        return f;
    }
    // From a unit normal and a unit tangent already orthogonal to it (no normalization).
    static Frame orthonormal(const Vec3f &normal, const Vec3f &unit_tangent) {
        Frame f;
        f.n = normal;
        f.s = unit_tangent;
        f.t = cross(normal, unit_tangent);
        return f;
    }
    Vec3f to_local(const Vec3f &v) const { return Vec3f(dot(v, s), dot(v, t), dot(v, n)); }
    Vec3f to_world(const Vec3f &v) const {
        return {mul_add(s.x, v.x, mul_add(t.x, v.y, n.x * v.z)), mul_add(s.y, v.x, mul_add(t.y, v.y, n.y * v.z)),
                mul_add(s.z, v.x, mul_add(t.z, v.y, n.z * v.z))};
    }
};

} // namespace bsdfkit::render
