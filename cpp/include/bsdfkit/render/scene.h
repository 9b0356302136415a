// Scene of the preview renderer: spheres (Embree user geometry with the analytic intersection of
// scene.cpp), triangle meshes and fibres (round Catmull-Rom curves) in an Embree 3 BVH, one
// material (or a checkerboard of two) per object, distant lighting and ray queries.
//
// Fibres. A curve hit at parameter u of a segment has the axis point c(u), the unit tangent T(u) and
// the radius r(u) (Embree's own interpolation of the control points, rtcInterpolate1). Its frame:
// x = T; for a hair material (Hair, HairFarField) z = the part of wo = -d normal to T, normalised
// (the ribbon facing the ray, as pbrt-v4's curves), y = z x x; for any other material z = the tube's
// outward normal at the hit. The offset across the fibre is the signed distance between the ray and
// the axis, along y, in units of r: h = ((p - c) . y) / r, clamped to [-1, 1] (exact for a straight
// fibre: (p - c) . y does not depend on where along the ray p is, since d . y = 0). With that sign,
// the R lobe's azimuth phi_i - phi_o = -2 asin h (pbrt-v4 Phi(0)) is the mirror reflection of the ray
// off the cylinder at p. A Hair(h=...) material on a fibre takes h from the hit (its own h is ignored).
// Where rays leave a fibre: for a surface material (anything but Hair / HairFarField) from the
// hit point pushed off the tube along its normal, as from any surface (and as Mitsuba does), so
// that one fibre's hard shadow on another falls where the tube's does. For a hair material from
// the axis point c with tnear = the distance at which they exit its cylinder, 1.05 r / |d x T|
// (capped at 50 r): the hair model is a far-field description of the whole fibre (its TT and TRT
// lobes leave from the far side, pbrt-v4's Hair BSDF is evaluated on a ribbon through the axis),
// and the fibre never shadows or re-hits itself at the scattering point, whatever its width in
// floats.
#pragma once
#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "environment.h"
#include "shading_frame.h"

namespace bsdfkit::render {

struct Object {
    enum class Kind : uint8_t { Sphere, Mesh, Curves } kind = Kind::Mesh;
    int mat_a = 0, mat_b = 0;
    Float inv_checker = 0;           // > 0: mat_a / mat_b alternate on squares of size 1 / inv_checker in world x, z
    Vec3f center{0, 0, 0};           // sphere
    Float radius = 1;                // sphere
    std::vector<Float> vertices;     // mesh: x, y, z per vertex
    std::vector<uint32_t> indices;   // mesh: 3 per triangle, counter-clockwise seen from outside
    std::vector<Float> frames;       // mesh: per triangle its shading frame's unit n, then s (6 floats)
    RTCGeometry geometry = nullptr;  // curves: retained for rtcInterpolate1 (released by ~Scene)
};

// A sphere as its Embree user geometry sees it (scene.cpp).
struct SphereGeom {
    Vec3f center;
    Float radius;
};

// Surface point: position, shading frame (frame.n: the outward geometric normal, for fibres the
// frame's z, see above; frame.s: the tangent made orthogonal to it) and the material index.
// Fibre hits also carry the axis point, the unit fibre tangent, the radius and the offset h
// across the fibre.
struct Hit {
    Vec3f p;
    Frame frame;
    int material = 0;
    bool fibre = false;
    bool from_axis = false;  // rays leave from the fibre's axis (a hair material on a fibre)
    Vec3f axis{0, 0, 0}, axis_dir{1, 0, 0};
    Float radius = 0, h = 0;
};

class Scene {
public:
    Scene();
    ~Scene();
    Scene(const Scene &) = delete;
    Scene &operator=(const Scene &) = delete;

    int add_material(const Material &m);
    // Returns "" or the reason the object was refused (the bindings validate first).
    std::string add_sphere(const Vec3f &center, Float radius, int mat_a, int mat_b, Float checker);
    std::string add_mesh(const Float *vertices, int64_t n_vertices, const uint32_t *indices, int64_t n_triangles,
                         int mat_a, int mat_b, Float checker);
    // Round Catmull-Rom curves (RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE): control points x, y, z,
    // radius; segment k uses points [segments[k], segments[k] + 3].
    std::string add_curves(const Float *points, int64_t n_points, const uint32_t *segments, int64_t n_segments,
                           int mat);
    // Builds the BVH; returns "" or Embree's error.
    std::string commit();
    bool committed() const { return committed_; }

    // Closest hit along o + t d, t in (0, inf).
    bool intersect(const Vec3f &o, const Vec3f &d, Hit *hit) const;
    // Anything along o + t d, t in (0, tfar)?
    bool occluded(const Vec3f &o, const Vec3f &d, Float tfar) const;

    // Batched queries for the wavefront integrator (Embree packet traversal: coherent camera
    // and shadow rays share node fetches). Rays are set up with make_ray / make_rayhit.
    void intersect_n(RTCRayHit *rays, unsigned n, bool coherent) const;
    void occluded_n(RTCRay *rays, unsigned n, bool coherent) const;
    // The surface point of a ray that hit (rh.hit.geomID valid).
    void hit_point(const RTCRayHit &rh, Hit *hit) const;

    Environment env = Environment::uniform(RGB(Float(1)));
    DirectionalLight sun;
    std::vector<Material> materials;
    std::vector<uint8_t> flags;  // material_flags of each material (a visit of the variant per hit was 8 % of a render)
    std::vector<Object> objects;

private:
    void curve_hit(const Object &ob, const RTCRayHit &rh, Hit *hit) const;
    std::vector<std::unique_ptr<SphereGeom>> spheres_;  // user data of the spheres' Embree geometries
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
    bool committed_ = false;
};

inline void make_ray(RTCRay &r, const Vec3f &o, const Vec3f &d, Float tfar) {
    r.org_x = o.x;
    r.org_y = o.y;
    r.org_z = o.z;
    r.tnear = 0.f;
    r.dir_x = d.x;
    r.dir_y = d.y;
    r.dir_z = d.z;
    r.time = 0.f;
    r.tfar = tfar;
    r.mask = ~0u;
    r.id = 0;
    r.flags = 0;
}
inline void make_rayhit(RTCRayHit &rh, const Vec3f &o, const Vec3f &d) {
    make_ray(rh.ray, o, d, std::numeric_limits<float>::infinity());
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

// The material to shade a hit with: the scene's, or for a Hair material on a fibre a copy in
// *scratch with the hit's offset h.
inline const Material &material_at(const Scene &scene, const Hit &hit, Material *scratch) {
    const Material &m = scene.materials[size_t(hit.material)];
    if (hit.fibre) {
        if (const auto *hb = std::get_if<HairBxDF<Float>>(&m)) {
            HairBxDF<Float> b = *hb;
            b.set_h(double(hit.h));
            *scratch = b;
            return *scratch;
        }
    }
    return m;
}

// Whether a material is shaded in the fibre frame of a hair model (see the header comment).
inline bool is_hair_material(const Material &m) {
    return std::holds_alternative<HairBxDF<Float>>(m) || std::holds_alternative<HairFarFieldBxDF<Float>>(m);
}

// Ray origin for leaving p toward d: p pushed off the surface along n to d's side, by an
// amount relative to the coordinates' magnitude (float rounding of the hit point).
inline Vec3f offset_ray_origin(const Vec3f &p, const Vec3f &n, const Vec3f &d) {
    Float m = max_(max_(std::abs(p.x), std::abs(p.y)), max_(std::abs(p.z), Float(1)));
    Float eps = Float(1e-4) * m;
    return p + n * (dot(n, d) < Float(0) ? -eps : eps);
}

// A ray leaving hit toward d (unit): from p pushed off the surface, or for a hair fibre from its
// axis point with tnear past its own cylinder (see the header comment).
inline void make_spawn_ray(RTCRay &r, const Hit &hit, const Vec3f &d, Float tfar) {
    if (!hit.from_axis) {
        make_ray(r, offset_ray_origin(hit.p, hit.frame.n, d), d, tfar);
        return;
    }
    make_ray(r, hit.axis, d, tfar);
    Float s = std::sqrt(length_squared(cross(d, hit.axis_dir)));
    r.tnear = Float(1.05) * hit.radius / max_(s, Float(0.021));
}
inline void make_spawn_rayhit(RTCRayHit &rh, const Hit &hit, const Vec3f &d) {
    make_spawn_ray(rh.ray, hit, d, std::numeric_limits<float>::infinity());
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

} // namespace bsdfkit::render
