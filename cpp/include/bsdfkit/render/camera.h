// Pinhole perspective camera (look-at form, world y-up).
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

    // The per-image constants of direction(): pixels to the screen plane at distance 1.
    struct Raster {
        Float kx, ky, tan_x, tan_y;
    };
    Raster raster(int width, int height) const {
        return {Float(2) / Float(width), Float(2) / Float(height), tan_half_fov,
                tan_half_fov * Float(height) / Float(width)};
    }
    // Primary ray direction through film position (fx, fy) in pixels, (0, 0) = top-left corner;
    // r = raster(width, height), computed once per image (its divisions are not per ray).
    Vec3f direction(Float fx, Float fy, const Raster &r) const {
        Float sx = mul_add(fx, r.kx, Float(-1)) * r.tan_x;
        Float sy = mul_add(-fy, r.ky, Float(1)) * r.tan_y;
        return normalize(forward + sx * right + sy * up);
    }
};

} // namespace bsdfkit::render
