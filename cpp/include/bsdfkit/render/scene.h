// Scene of the preview renderer: spheres and triangle meshes in an Embree 3 BVH, one material
// (or a checkerboard of two) per object, distant lighting and ray queries.
#pragma once
#include <embree3/rtcore.h>

#include <cstdint>
#include <string>
#include <vector>

#include "environment.h"

namespace bsdfkit::render {

struct Object {
    enum class Kind : uint8_t { Sphere, Mesh } kind = Kind::Mesh;
    int mat_a = 0, mat_b = 0;
    Float checker = 0;               // > 0: mat_a / mat_b alternate on squares of this size in world x, z
    Vec3f center{0, 0, 0};           // sphere
    Float radius = 1;                // sphere
    std::vector<Float> vertices;     // mesh: x, y, z per vertex
    std::vector<uint32_t> indices;   // mesh: 3 per triangle, counter-clockwise seen from outside
};

// Surface point: position, outward geometric normal, a tangent and the material index.
struct Hit {
    Vec3f p, n, tangent;
    int material = 0;
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
    std::vector<Object> objects;

private:
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

// Ray origin for leaving p toward d: p pushed off the surface along n to d's side, by an
// amount relative to the coordinates' magnitude (float rounding of the hit point).
inline Vec3f offset_ray_origin(const Vec3f &p, const Vec3f &n, const Vec3f &d) {
    Float m = max_(max_(std::abs(p.x), std::abs(p.y)), max_(std::abs(p.z), Float(1)));
    Float eps = Float(1e-4) * m;
    return p + n * (dot(n, d) < Float(0) ? -eps : eps);
}

} // namespace bsdfkit::render
