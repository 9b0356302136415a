#include "bsdfkit/io.h"

#include <embree3/rtcore.h>

#include <OpenImageIO/imageio.h>

#include <cctype>
#include <memory>

namespace bsdfkit::io {

std::string read_image(const std::string &path, Image &img) {
    // The stored values: a PNG's colour is not multiplied by its alpha (OpenImageIO's default
    // converts to associated alpha, which darkens a base colour texture wherever alpha < 1).
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) return path + ": " + OIIO::geterror();
    const OIIO::ImageSpec &spec = in->spec();
    img.width = spec.width;
    img.height = spec.height;
    img.channels = spec.nchannels;
    img.pixels.assign(size_t(img.width) * img.height * img.channels, 0.0f);
    bool ok = in->read_image(0, 0, 0, img.channels, OIIO::TypeDesc::FLOAT, img.pixels.data());
    std::string err = ok ? "" : path + ": " + in->geterror();
    in->close();
    return err;
}

std::string write_image(const std::string &path, const float *data, int width, int height, int channels) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) return path + ": " + OIIO::geterror();
    // Integer formats store the values as given (the caller applies any transfer curve).
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
    std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
    for (auto &ch : ext) ch = char(std::tolower(ch));
    if (ext == ".png" || ext == ".jpg" || ext == "jpeg" || ext == ".bmp") spec.set_format(OIIO::TypeDesc::UINT8);
    if (!out->open(path, spec)) return path + ": " + out->geterror();
    bool ok = out->write_image(OIIO::TypeDesc::FLOAT, data);
    std::string err = ok ? "" : path + ": " + out->geterror();
    out->close();
    return err;
}

std::string embree_version() {
    RTCDevice dev = rtcNewDevice(nullptr);
    if (!dev) return "unavailable";
    long v = long(rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION));
    rtcReleaseDevice(dev);
    return std::to_string(v / 10000) + "." + std::to_string((v / 100) % 100) + "." + std::to_string(v % 100);
}

std::string openimageio_version() { return OIIO_VERSION_STRING; }

} // namespace bsdfkit::io
