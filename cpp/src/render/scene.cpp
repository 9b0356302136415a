// Embree 3 glue of the preview renderer's scene.
#include "bsdfkit/render/scene.h"

#include "bsdfkit/render/camera.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

namespace bsdfkit::render {

namespace {
const char *embree_error_name(RTCError e) {
    switch (e) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
    }
}
std::string embree_status(RTCDevice dev, const char *what) {
    RTCError e = rtcGetDeviceError(dev);
    return e == RTC_ERROR_NONE ? std::string() : std::string("Embree: ") + what + ": " + embree_error_name(e);
}
} // namespace

Scene::Scene() {
    device_ = rtcNewDevice(nullptr);
    if (device_) scene_ = rtcNewScene(device_);
    if (scene_) {
        rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    }
}

Scene::~Scene() {
    for (Object &o : objects)
        if (o.geometry) rtcReleaseGeometry(o.geometry);
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
}

int Scene::add_material(const Material &m) {
    materials.push_back(m);
    flags.push_back(material_flags(m));
    return int(materials.size()) - 1;
}

// Spheres are Embree user geometry with the intersection below (Mitsuba registers its spheres the
// same way): on the bench scene (bench/RENDER.md, Debian's Embree 3.13.5) Embree's own
// RTC_GEOMETRY_TYPE_SPHERE_POINT took 2x the time of these callbacks for the rays and 1.7x for
// the shadow rays. The quadratic runs in double on the offset o - c (as Mitsuba's sphere on the
// CPU), so a root is accurate near tangency and for origins just off the surface.
namespace {
// Nearest root t of |o + t d - c| = r in (tnear, tfar), or -1.
inline double sphere_root(const SphereGeom &ob, float ox, float oy, float oz, float dx, float dy, float dz, float tnear,
                          float tfar) {
    double px = double(ox) - double(ob.center.x), py = double(oy) - double(ob.center.y),
           pz = double(oz) - double(ob.center.z);
    double a = double(dx) * dx + double(dy) * dy + double(dz) * dz;
    double b = px * dx + py * dy + pz * dz;
    double c = px * px + py * py + pz * pz - double(ob.radius) * double(ob.radius);
    double disc = b * b - a * c;
    if (!(disc >= 0.0) || !(a > 0.0)) return -1.0;
    double sq = std::sqrt(disc);
    // Both roots without cancellation (the citardauq form of a t^2 + 2 b t + c = 0); q = 0 only
    // for a ray tangent to the sphere at its origin.
    double q = b < 0.0 ? -b + sq : -b - sq;
    if (q == 0.0) return -1.0;
    double t0 = c / q, t1 = q / a;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > double(tnear) && t0 < double(tfar)) return t0;
    if (t1 > double(tnear) && t1 < double(tfar)) return t1;
    return -1.0;
}
void sphere_bounds(const RTCBoundsFunctionArguments *args) {
    const SphereGeom &ob = *static_cast<const SphereGeom *>(args->geometryUserPtr);
    RTCBounds *b = args->bounds_o;
    // c -/+ r in double, rounded outward to float: no root is culled by the box's rounding
    const float lo = -std::numeric_limits<float>::infinity(), hi = std::numeric_limits<float>::infinity();
    auto down = [&](float c) { return std::nextafter(float(double(c) - double(ob.radius)), lo); };
    auto up = [&](float c) { return std::nextafter(float(double(c) + double(ob.radius)), hi); };
    b->lower_x = down(ob.center.x), b->lower_y = down(ob.center.y), b->lower_z = down(ob.center.z);
    b->upper_x = up(ob.center.x), b->upper_y = up(ob.center.y), b->upper_z = up(ob.center.z);
}
// hit(i, t) for each valid ray i of the N meeting the sphere in (tnear, tfar), t its nearest root.
template <typename OnHit> void sphere_hits(const void *geom, const int *valid, RTCRayN *ray, unsigned N, OnHit hit) {
    const SphereGeom &ob = *static_cast<const SphereGeom *>(geom);
    for (unsigned i = 0; i < N; ++i) {
        if (!valid[i]) continue;
        double t = sphere_root(ob, RTCRayN_org_x(ray, N, i), RTCRayN_org_y(ray, N, i), RTCRayN_org_z(ray, N, i),
                               RTCRayN_dir_x(ray, N, i), RTCRayN_dir_y(ray, N, i), RTCRayN_dir_z(ray, N, i),
                               RTCRayN_tnear(ray, N, i), RTCRayN_tfar(ray, N, i));
        if (t >= 0.0) hit(i, t);
    }
}
void sphere_intersect(const RTCIntersectFunctionNArguments *args) {
    const unsigned N = args->N;
    RTCRayN *ray = RTCRayHitN_RayN(args->rayhit, N);
    RTCHitN *hit = RTCRayHitN_HitN(args->rayhit, N);
    sphere_hits(args->geometryUserPtr, args->valid, ray, N, [&](unsigned i, double t) {
        float tf = float(t), &tfar = RTCRayN_tfar(ray, N, i);
        if (!(tf < tfar)) return;
        tfar = tf;
        RTCHitN_u(hit, N, i) = 0.f;
        RTCHitN_v(hit, N, i) = 0.f;
        RTCHitN_primID(hit, N, i) = args->primID;
        RTCHitN_geomID(hit, N, i) = args->geomID;
        RTCHitN_instID(hit, N, i, 0) = args->context->instID[0];
    });
}
void sphere_occluded(const RTCOccludedFunctionNArguments *args) {
    const unsigned N = args->N;
    RTCRayN *ray = args->ray;
    sphere_hits(args->geometryUserPtr, args->valid, ray, N,
                [&](unsigned i, double) { RTCRayN_tfar(ray, N, i) = -std::numeric_limits<float>::infinity(); });
}
} // namespace

std::string Scene::add_sphere(const Vec3f &center, Float radius, int mat_a, int mat_b, Float checker) {
    if (!scene_) return "Embree: could not create a device";
    if (committed_) return "scene already committed";
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
    if (!g) return embree_status(device_, "rtcNewGeometry");
    rtcSetGeometryUserPrimitiveCount(g, 1);
    spheres_.push_back(std::make_unique<SphereGeom>(SphereGeom{center, radius}));
    rtcSetGeometryUserData(g, spheres_.back().get());
    rtcSetGeometryBoundsFunction(g, sphere_bounds, nullptr);
    rtcSetGeometryIntersectFunction(g, sphere_intersect);
    rtcSetGeometryOccludedFunction(g, sphere_occluded);
    rtcCommitGeometry(g);
    unsigned id = unsigned(objects.size());
    rtcAttachGeometryByID(scene_, g, id);
    rtcReleaseGeometry(g);
    Object o;
    o.kind = Object::Kind::Sphere;
    o.center = center;
    o.radius = radius;
    o.mat_a = mat_a;
    o.mat_b = mat_b;
    o.inv_checker = checker > Float(0) ? Float(1) / checker : Float(0);
    objects.push_back(std::move(o));
    return embree_status(device_, "sphere");
}

// The shading frame of a triangle, in double (per triangle at add_mesh, not per hit: a hit then
// needs no square root or division for it): n the unit geometric normal e1 x e2 ((0, 1, 0) for a
// degenerate triangle), s the edge e1 = p1 - p0 made orthogonal to n (Gram-Schmidt), or
// Frame::around(n)'s tangent where e1 is (nearly) along n or zero.
static void triangle_frame(const Float *v, const uint32_t *ix, Float *out) {
    using Vec3d = Vec3<double>;
    auto vertex = [&](int i) {
        const Float *q = v + 3 * size_t(ix[i]);
        return Vec3d(q[0], q[1], q[2]);
    };
    const Vec3d p0 = vertex(0), e1 = vertex(1) - p0, e2 = vertex(2) - p0;
    Vec3d n = cross(e1, e2);
    n = length_squared(n) > 0 ? normalize(n) : Vec3d(0, 1, 0);
    const Vec3d t = e1 - n * dot(n, e1);
    const double t2 = length_squared(t);
    const Vec3f nf(Float(n.x), Float(n.y), Float(n.z));
    Vec3f sf = Frame::around(nf).s;
    if (t2 > 1e-12 * length_squared(e1) && t2 > 0) {
        const Vec3d s = t / std::sqrt(t2);
        sf = Vec3f(Float(s.x), Float(s.y), Float(s.z));
    }
    out[0] = nf.x, out[1] = nf.y, out[2] = nf.z, out[3] = sf.x, out[4] = sf.y, out[5] = sf.z;
}

std::string Scene::add_mesh(const Float *vertices, int64_t nv, const uint32_t *indices, int64_t nt, int mat_a,
                            int mat_b, Float checker) {
    if (!scene_) return "Embree: could not create a device";
    if (committed_) return "scene already committed";
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g) return embree_status(device_, "rtcNewGeometry");
    // Embree pads its own buffers for vector loads past the last vertex.
    auto *v = static_cast<float *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), size_t(nv)));
    auto *ix = static_cast<unsigned *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), size_t(nt)));
    if (!v || !ix) {
        rtcReleaseGeometry(g);
        return embree_status(device_, "mesh buffers");
    }
    std::memcpy(v, vertices, size_t(nv) * 3 * sizeof(float));
    std::memcpy(ix, indices, size_t(nt) * 3 * sizeof(unsigned));
    rtcCommitGeometry(g);
    unsigned id = unsigned(objects.size());
    rtcAttachGeometryByID(scene_, g, id);
    rtcReleaseGeometry(g);
    Object o;
    o.kind = Object::Kind::Mesh;
    o.vertices.assign(vertices, vertices + nv * 3);
    o.indices.assign(indices, indices + nt * 3);
    o.frames.resize(size_t(nt) * 6);
    for (int64_t k = 0; k < nt; ++k) triangle_frame(vertices, indices + 3 * k, &o.frames[size_t(k) * 6]);
    o.mat_a = mat_a;
    o.mat_b = mat_b;
    o.inv_checker = checker > Float(0) ? Float(1) / checker : Float(0);
    objects.push_back(std::move(o));
    return embree_status(device_, "mesh");
}

std::string Scene::add_curves(const Float *points, int64_t np, const uint32_t *segments, int64_t ns, int mat) {
    if (!scene_) return "Embree: could not create a device";
    if (committed_) return "scene already committed";
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE);
    if (!g) return embree_status(device_, "rtcNewGeometry");
    auto *v = static_cast<float *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), size_t(np)));
    auto *ix = static_cast<unsigned *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned), size_t(ns)));
    if (!v || !ix) {
        rtcReleaseGeometry(g);
        return embree_status(device_, "curve buffers");
    }
    std::memcpy(v, points, size_t(np) * 4 * sizeof(float));
    std::memcpy(ix, segments, size_t(ns) * sizeof(unsigned));
    rtcCommitGeometry(g);
    unsigned id = unsigned(objects.size());
    rtcAttachGeometryByID(scene_, g, id);
    Object o;
    o.kind = Object::Kind::Curves;
    o.geometry = g;  // keeps our reference for rtcInterpolate1
    o.mat_a = mat;
    o.mat_b = mat;
    objects.push_back(std::move(o));
    return embree_status(device_, "curves");
}

std::string Scene::commit() {
    if (!scene_) return "Embree: could not create a device";
    rtcCommitScene(scene_);
    committed_ = true;
    return embree_status(device_, "rtcCommitScene");
}

bool Scene::intersect(const Vec3f &o, const Vec3f &d, Hit *hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    make_rayhit(rh, o, d);
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit_point(rh, hit);
    return true;
}

bool Scene::occluded(const Vec3f &o, const Vec3f &d, Float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    make_ray(r, o, d, tfar);
    rtcOccluded1(scene_, &ctx, &r);
    return r.tfar < 0.f;  // Embree sets tfar = -inf on a hit
}

void Scene::intersect_n(RTCRayHit *rays, unsigned n, bool coherent) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    // Packets of 16 (SoA): Embree traverses the BVH once for all 16 rays.
    alignas(64) RTCRayHit16 p;
    alignas(64) int valid[16];
    for (unsigned b = 0; b < n; b += 16) {
        unsigned m = std::min(16u, n - b);
        for (unsigned i = 0; i < 16; ++i) {
            const RTCRayHit &r = rays[b + (i < m ? i : 0)];
            valid[i] = i < m ? -1 : 0;
            p.ray.org_x[i] = r.ray.org_x;
            p.ray.org_y[i] = r.ray.org_y;
            p.ray.org_z[i] = r.ray.org_z;
            p.ray.tnear[i] = r.ray.tnear;
            p.ray.dir_x[i] = r.ray.dir_x;
            p.ray.dir_y[i] = r.ray.dir_y;
            p.ray.dir_z[i] = r.ray.dir_z;
            p.ray.time[i] = 0.f;
            p.ray.tfar[i] = r.ray.tfar;
            p.ray.mask[i] = ~0u;
            p.ray.id[i] = 0;
            p.ray.flags[i] = 0;
            p.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            p.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid, scene_, &ctx, &p);
        for (unsigned i = 0; i < m; ++i) {
            RTCRayHit &r = rays[b + i];
            r.ray.tfar = p.ray.tfar[i];
            r.hit.geomID = p.hit.geomID[i];
            r.hit.primID = p.hit.primID[i];
            r.hit.u = p.hit.u[i];
            r.hit.v = p.hit.v[i];
        }
    }
}

void Scene::occluded_n(RTCRay *rays, unsigned n, bool coherent) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    alignas(64) RTCRay16 p;
    alignas(64) int valid[16];
    for (unsigned b = 0; b < n; b += 16) {
        unsigned m = std::min(16u, n - b);
        for (unsigned i = 0; i < 16; ++i) {
            const RTCRay &r = rays[b + (i < m ? i : 0)];
            valid[i] = i < m ? -1 : 0;
            p.org_x[i] = r.org_x;
            p.org_y[i] = r.org_y;
            p.org_z[i] = r.org_z;
            p.tnear[i] = r.tnear;
            p.dir_x[i] = r.dir_x;
            p.dir_y[i] = r.dir_y;
            p.dir_z[i] = r.dir_z;
            p.time[i] = 0.f;
            p.tfar[i] = r.tfar;
            p.mask[i] = ~0u;
            p.id[i] = 0;
            p.flags[i] = 0;
        }
        rtcOccluded16(valid, scene_, &ctx, &p);
        for (unsigned i = 0; i < m; ++i) rays[b + i].tfar = p.tfar[i];
    }
}

void Scene::hit_point(const RTCRayHit &rh, Hit *hit) const {
    const Object &ob = objects[rh.hit.geomID];
    Vec3f o(rh.ray.org_x, rh.ray.org_y, rh.ray.org_z), d(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
    if (ob.kind == Object::Kind::Curves) {
        curve_hit(ob, rh, hit);
        return;
    }
    if (ob.kind == Object::Kind::Sphere) {
        // Re-project the hit onto the sphere: o + t d carries the error of t.
        Vec3f p = o + d * rh.ray.tfar;
        Vec3f m = p - ob.center;
        Float l2 = length_squared(m), q2 = mul_add(m.x, m.x, m.z * m.z);
        Vec3f n = l2 > Float(0) ? m / std::sqrt(l2) : Vec3f(0, 1, 0);
        hit->p = ob.center + n * ob.radius;
        // Tangent: dp/dphi of the lat-long parametrisation around +y (brushed along parallels),
        // (-m.z, 0, m.x), orthogonal to m by construction: normalized from m directly, so its
        // square root does not wait for n's (Gram-Schmidt would repeat both); the poles take
        // Frame's basis, as the Gram-Schmidt frame did below the same threshold.
        hit->frame = q2 > Float(1e-12) * l2 ? Frame::orthonormal(n, Vec3f(-m.z, 0, m.x) / std::sqrt(q2))
                                            : Frame::around(n);
    } else {
        // Barycentric interpolation of the vertices is exact to rounding, unlike o + t d.
        const uint32_t *ix = &ob.indices[size_t(rh.hit.primID) * 3];
        const Float *v = ob.vertices.data();
        Vec3f p0(v[3 * ix[0]], v[3 * ix[0] + 1], v[3 * ix[0] + 2]);
        Vec3f p1(v[3 * ix[1]], v[3 * ix[1] + 1], v[3 * ix[1] + 2]);
        Vec3f p2(v[3 * ix[2]], v[3 * ix[2] + 1], v[3 * ix[2] + 2]);
        Float b1 = rh.hit.u, b2 = rh.hit.v;
        hit->p = p0 * (Float(1) - b1 - b2) + p1 * b1 + p2 * b2;
        const Float *f = &ob.frames[size_t(rh.hit.primID) * 6];
        hit->frame = Frame::orthonormal(Vec3f(f[0], f[1], f[2]), Vec3f(f[3], f[4], f[5]));
    }
    int mat = ob.mat_a;
    if (ob.inv_checker > Float(0)) {
        long cx = long(std::floor(hit->p.x * ob.inv_checker)), cz = long(std::floor(hit->p.z * ob.inv_checker));
        mat = ((cx + cz) & 1) ? ob.mat_b : ob.mat_a;
    }
    hit->material = mat;
    hit->fibre = false;
    hit->from_axis = false;
}

// Fibre hit (see scene.h): axis point, tangent and radius interpolated by Embree at u, the
// frame and the offset h.
void Scene::curve_hit(const Object &ob, const RTCRayHit &rh, Hit *hit) const {
    Vec3f o(rh.ray.org_x, rh.ray.org_y, rh.ray.org_z), d(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
    float P[4], dP[4];
    rtcInterpolate1(ob.geometry, rh.hit.primID, rh.hit.u, rh.hit.v, RTC_BUFFER_TYPE_VERTEX, 0, P, dP, nullptr, 4);
    Vec3f c(P[0], P[1], P[2]), T(dP[0], dP[1], dP[2]);
    Float tl2 = length_squared(T);
    T = tl2 > Float(0) ? T / std::sqrt(tl2) : Vec3f(1, 0, 0);
    Float r = max_(P[3], Float(1e-30));
    Vec3f p = o + d * rh.ray.tfar;
    Vec3f wo = -normalize(d);
    // z: wo's part normal to the fibre (the ribbon facing the ray); any normal if wo is along T
    Vec3f z = wo - T * dot(wo, T);
    Float zl2 = length_squared(z);
    if (zl2 > Float(1e-12)) {
        z = z / std::sqrt(zl2);
    } else {
        Vec3f b1, b2;
        Frame::basis(T, &b1, &b2);
        z = b1;
    }
    Vec3f y = cross(z, T);
    hit->h = clamp(dot(p - c, y) / r, Float(-1), Float(1));
    hit->p = p;
    hit->fibre = true;
    hit->axis = c;
    hit->axis_dir = T;
    hit->radius = r;
    hit->material = ob.mat_a;
    hit->from_axis = is_hair_material(materials[size_t(ob.mat_a)]);
    Vec3f n = z;
    if (!hit->from_axis) {
        // the tube's outward normal at p (facing the ray when p is numerically on the axis)
        Vec3f q = p - c;
        q = q - T * dot(q, T);
        Float ql2 = length_squared(q);
        if (ql2 > Float(1e-20) * r * r) n = q / std::sqrt(ql2);
    }
    hit->frame = Frame(n, T);
}

} // namespace bsdfkit::render
