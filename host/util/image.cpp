#include "util/image.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "util/error.h"

#ifdef RAYSORT_NO_IMAGES
namespace raysort {

// The bundle built with -DRAYSORT_IMAGES=OFF (CMakeLists.txt) writes no images.
void write_png(const Image&, const std::string& path, float, PngEncoding) {
  throw Error(fmt::format("cannot write '{}': this raysort was built with -DRAYSORT_IMAGES=OFF (no OpenImageIO); "
                          "use a default build to write images",
                          path));
}
void write_exr(const Image& img, const std::string& path) { write_png(img, path, 1.0f, PngEncoding::AsIs); }

}  // namespace raysort
#else
#include <OpenImageIO/imageio.h>

namespace raysort {

void write_png(const Image& img, const std::string& path, float scale, PngEncoding encoding) {
  std::vector<unsigned char> bytes(img.rgb.size());
  for (std::size_t i = 0; i < img.rgb.size(); ++i) {
    const float c = std::clamp(img.rgb[i] * scale, 0.0f, 1.0f);
    const float v = encoding == PngEncoding::AsIs ? c
                    : c <= 0.0031308f             ? 12.92f * c
                                                  : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
    bytes[i] = static_cast<unsigned char>(std::lround(v * 255.0f));
  }
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error(fmt::format("cannot write '{}': {} (use a .png path)", path, OIIO::geterror()));
  OIIO::ImageSpec spec(static_cast<int>(img.width), static_cast<int>(img.height), 3, OIIO::TypeDesc::UINT8);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) || !out->close())
    throw Error(fmt::format("writing '{}' failed: {}", path, out->geterror()));
}

void write_exr(const Image& img, const std::string& path) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error(fmt::format("cannot write '{}': {}", path, OIIO::geterror()));
  OIIO::ImageSpec spec(static_cast<int>(img.width), static_cast<int>(img.height), 3, OIIO::TypeDesc::FLOAT);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, img.rgb.data()) || !out->close())
    throw Error(fmt::format("writing '{}' failed: {}", path, out->geterror()));
}

}  // namespace raysort
#endif
