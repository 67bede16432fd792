#pragma once
// Images on disk: the one place raysort writes pictures (the path-traced image, its cost heatmap,
// the cut overlay, and the result sets' plots), through OpenImageIO.
#include <cstdint>
#include <string>
#include <vector>

namespace raysort {

// An RGB image of floats, row-major from the top-left pixel.
struct Image {
  std::uint32_t width = 0, height = 0;
  std::vector<float> rgb;
  Image() = default;
  Image(std::uint32_t w, std::uint32_t h) : width(w), height(h), rgb(std::size_t{w} * h * 3, 0.0f) {}
  // Out-of-image coordinates are ignored (lines and boxes may run off the edge).
  void set(int x, int y, float r, float g, float b) {
    if (x < 0 || y < 0 || x >= static_cast<int>(width) || y >= static_cast<int>(height)) return;
    float* p = &rgb[(static_cast<std::size_t>(y) * width + static_cast<std::size_t>(x)) * 3];
    p[0] = r, p[1] = g, p[2] = b;
  }
};

// How a PNG's 8-bit values come from the floats: linear radiance gets the sRGB curve; colours that
// are already display values (plots) are stored as they are.
enum class PngEncoding { Srgb, AsIs };

// 8-bit PNG (or any format OpenImageIO knows by the file's extension) of the values × scale,
// clamped to [0, 1]. Throws Error naming the path when it cannot be written.
void write_png(const Image& img, const std::string& path, float scale = 1.0f, PngEncoding encoding = PngEncoding::Srgb);
// 32-bit float RGB (OpenEXR), the values as they are. Throws Error naming the path.
void write_exr(const Image& img, const std::string& path);

}  // namespace raysort
