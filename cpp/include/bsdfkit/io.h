// Image I/O through OpenImageIO and a probe of the Embree device (the renderer builds on both).
#pragma once
#include <string>
#include <vector>

namespace bsdfkit::io {

struct Image {
    int width = 0, height = 0, channels = 0;
    std::vector<float> pixels; // row-major, channels interleaved, linear float
};

// Returns an empty string on success, else OpenImageIO's reason prefixed by the path.
std::string read_image(const std::string &path, Image &img);
std::string write_image(const std::string &path, const float *data, int width, int height, int channels);

std::string embree_version();
std::string openimageio_version();

} // namespace bsdfkit::io
