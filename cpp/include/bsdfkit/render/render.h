// Path tracer of the preview renderer: the light transport equation estimated with BSDF
// sampling and environment sampling combined by multiple importance sampling (power
// heuristic), Russian roulette and a maximum depth (pbrt-v4 PathIntegrator, sec. 13.4).
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include "camera.h"
#include "scene.h"

namespace bsdfkit::render {

struct RenderSettings {
    int width = 256, height = 256;
    int max_depth = 8;   // scattering events; 0 shows only what the camera sees of the environment
    uint64_t seed = 0;
    int threads = 1;
};

struct RenderStats {
    int64_t rays = 0;       // closest-hit and shadow rays traced
    int64_t nonfinite = 0;  // path samples discarded because they were NaN or Inf
};

// Adds samples [s0, s1) of every pixel to acc (height * width * 3 doubles, row-major, RGB).
// Each sample's random numbers depend only on (seed, pixel, sample index) and each pixel sums its
// samples in index order, so acc is bit-identical for any thread count and any split of the
// sample range into calls. should_stop (may be empty) is polled on the calling thread between
// tiles; when it returns true the call stops early and returns false (acc is then partial).
bool render_samples(const Scene &scene, const Camera &camera, const RenderSettings &settings, int s0, int s1,
                    double *acc, RenderStats *stats, const std::function<bool()> &should_stop);

// Triangle mesh from a file (OBJ, PLY, ... through Assimp), all meshes of the file merged and
// triangulated. Returns "" or the reason naming the file.
std::string load_mesh(const std::string &path, std::vector<Float> *vertices, std::vector<uint32_t> *indices);

} // namespace bsdfkit::render
