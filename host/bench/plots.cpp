#include "bench/plots.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

namespace raysort {

namespace {

namespace IBA = OIIO::ImageBufAlgo;

// A small chart: a white RGB canvas, a plot area with axes and ticks, data mapped into it.
class Chart {
 public:
  Chart(int w, int h, double x0, double x1, double y0, double y1)
      : buf_(OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::FLOAT)), w_(w), h_(h), x0_(x0), x1_(x1), y0_(y0), y1_(y1) {
    const float white[3] = {1, 1, 1};
    IBA::fill(buf_, white);
    if (std::filesystem::exists(kFont)) font_ = kFont;
  }
  int px(double x) const { return left_ + static_cast<int>((x - x0_) / (x1_ - x0_) * (w_ - left_ - right_)); }
  int py(double y) const { return h_ - bottom_ - static_cast<int>((y - y0_) / (y1_ - y0_) * (h_ - top_ - bottom_)); }
  void line(double xa, double ya, double xb, double yb, const float* c, int width = 2) {
    for (int d = 0; d < width; ++d) IBA::render_line(buf_, px(xa), py(ya) + d, px(xb), py(yb) + d, {c, 3});
  }
  void marker(double x, double y, const float* c) { IBA::render_box(buf_, px(x) - 4, py(y) - 4, px(x) + 4, py(y) + 4, {c, 3}, true); }
  void text(int x, int y, const std::string& s, int size = 14, const float* c = kBlack,
            OIIO::ImageBufAlgo::TextAlignX ax = OIIO::ImageBufAlgo::TextAlignX::Left) {
    if (font_.empty()) return;
    IBA::render_text(buf_, x, y, s, size, font_, {c, 3}, ax);
  }
  void axes(const std::string& title, const std::string& xlabel, const std::string& ylabel, const std::vector<double>& xticks,
            int yticks = 5) {
    line(x0_, y0_, x1_, y0_, kBlack, 1);
    line(x0_, y0_, x0_, y1_, kBlack, 1);
    for (double xt : xticks) {
      IBA::render_line(buf_, px(xt), py(y0_), px(xt), py(y0_) + 5, {kBlack, 3});
      text(px(xt), py(y0_) + 20, fmt::format("{:g}", xt), 13, kBlack, OIIO::ImageBufAlgo::TextAlignX::Center);
    }
    for (int i = 0; i <= yticks; ++i) {
      double yt = y0_ + (y1_ - y0_) * i / yticks;
      IBA::render_line(buf_, px(x0_) - 5, py(yt), px(x0_), py(yt), {kBlack, 3});
      const float grid[3] = {0.9f, 0.9f, 0.9f};
      IBA::render_line(buf_, px(x0_) + 1, py(yt), px(x1_), py(yt), {grid, 3});
      text(px(x0_) - 8, py(yt) + 5, fmt::format("{:.2f}", yt), 13, kBlack, OIIO::ImageBufAlgo::TextAlignX::Right);
    }
    text(w_ / 2, 24, title, 16, kBlack, OIIO::ImageBufAlgo::TextAlignX::Center);
    text((px(x0_) + px(x1_)) / 2, h_ - 12, xlabel, 14, kBlack, OIIO::ImageBufAlgo::TextAlignX::Center);
    text(8, top_ - 10, ylabel, 14);
  }
  bool write(const std::string& path) { return buf_.write(path); }

  static constexpr const char* kFont = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  static constexpr float kBlack[3] = {0, 0, 0};

 private:
  OIIO::ImageBuf buf_;
  int w_, h_;
  double x0_, x1_, y0_, y1_;
  int left_ = 70, right_ = 170, top_ = 50, bottom_ = 50;
  std::string font_;
};

const float* color(std::size_t i) {
  static const float palette[][3] = {{0.12f, 0.47f, 0.71f}, {1.0f, 0.50f, 0.05f}, {0.17f, 0.63f, 0.17f},
                                     {0.84f, 0.15f, 0.16f}, {0.58f, 0.40f, 0.74f}, {0.55f, 0.34f, 0.29f},
                                     {0.89f, 0.47f, 0.76f}, {0.50f, 0.50f, 0.50f}, {0.74f, 0.74f, 0.13f},
                                     {0.09f, 0.75f, 0.81f}, {0.0f, 0.0f, 0.0f}};
  return palette[i % 11];
}

std::string file_safe(std::string s) {
  for (auto& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  return s;
}

}  // namespace

std::vector<std::string> write_plots(const std::vector<CellRecord>& cells, const std::string& dir) {
  std::vector<std::string> written;
  std::vector<std::string> encoders;
  std::set<std::pair<std::string, std::string>> scene_batches;
  std::set<std::string> batches;
  for (auto& c : cells) {
    if (c.encoder != kBaselineEncoder && std::find(encoders.begin(), encoders.end(), c.encoder) == encoders.end())
      encoders.push_back(c.encoder);
    scene_batches.insert({c.scene, c.batch});
    batches.insert(c.batch);
  }

  // Speedup against key bits, per scene and batch with more than one key length.
  for (auto& [scene, batch] : scene_batches) {
    std::map<std::string, std::map<unsigned, double>> series;
    std::set<unsigned> bits;
    double ymax = 1.0, ymin = 1.0;
    for (auto& c : cells)
      if (c.scene == scene && c.batch == batch && c.ok() && c.encoder != kBaselineEncoder && c.top_bits == 0) {
        series[c.encoder][c.bits] = c.speedup;
        bits.insert(c.bits);
        ymax = std::max(ymax, c.speedup);
        ymin = std::min(ymin, c.speedup);
      }
    if (bits.size() < 2) continue;
    Chart ch(900, 560, *bits.begin() - 4.0, *bits.rbegin() + 4.0, std::floor(ymin * 10) / 10, std::ceil(ymax * 10) / 10 + 0.05);
    ch.axes(fmt::format("{} {}: trace speedup vs NoSort against key bits", scene, batch), "key bits", "speedup",
            std::vector<double>(bits.begin(), bits.end()));
    std::size_t i = 0;
    for (auto& e : encoders) {
      auto it = series.find(e);
      if (it == series.end()) {
        ++i;
        continue;
      }
      const float* col = color(i);
      double px = 0, py = 0;
      bool first = true;
      for (auto& [b, s] : it->second) {
        if (!first) ch.line(px, py, b, s, col);
        ch.marker(b, s, col);
        px = b, py = s, first = false;
      }
      ch.text(900 - 160, 70 + 20 * static_cast<int>(i), e, 14, col);
      ++i;
    }
    std::string name = fmt::format("speed-vs-bits-{}-{}.png", file_safe(scene), file_safe(batch));
    if (ch.write((std::filesystem::path(dir) / name).string())) written.push_back(name);
  }

  // Overhead against gain, per batch, at every key length run.
  for (auto& batch : batches) {
    double xmax = 10, ymax = 1.0, ymin = 1.0;
    for (auto& c : cells)
      if (c.batch == batch && c.ok() && c.encoder != kBaselineEncoder) {
        // Overhead relative to the NoSort trace time: (encode + sort) / (trace · speedup).
        double rel = c.speedup > 0 ? c.overhead_pct / c.speedup : 0;
        xmax = std::max(xmax, rel);
        ymax = std::max(ymax, c.speedup);
        ymin = std::min(ymin, c.speedup);
      }
    xmax = std::ceil(xmax / 10) * 10;
    Chart ch(900, 560, 0, xmax, std::floor(ymin * 10) / 10, std::ceil(ymax * 10) / 10 + 0.05);
    std::vector<double> xt;
    for (int k = 0; k <= 5; ++k) xt.push_back(xmax * k / 5);
    ch.axes(fmt::format("{}: what ordering costs (x) against what it buys (y)", batch),
            "encode + sort, % of NoSort trace time", "trace speedup", xt);
    // Break-even: net speedup = 1 where overhead/T0 = 1 - 1/s, i.e. s = 1 / (1 - x/100).
    const float grey[3] = {0.6f, 0.6f, 0.6f};
    double lx = 0, ly = 1;
    for (int k = 1; k <= 100; ++k) {
      double x = xmax * k / 100;
      if (x >= 99) break;
      double s = 1.0 / (1.0 - x / 100.0);
      if (s > std::ceil(ymax * 10) / 10 + 0.05) break;
      ch.line(lx, ly, x, s, grey, 1);
      lx = x, ly = s;
    }
    ch.text(900 - 160, 70 + 20 * static_cast<int>(encoders.size()) + 10, "net speedup = 1", 13, grey);
    std::size_t i = 0;
    for (auto& e : encoders) {
      const float* col = color(i);
      for (auto& c : cells)
        if (c.batch == batch && c.ok() && c.encoder == e) ch.marker(c.speedup > 0 ? c.overhead_pct / c.speedup : 0, c.speedup, col);
      ch.text(900 - 160, 70 + 20 * static_cast<int>(i), e, 14, col);
      ++i;
    }
    std::string name = fmt::format("overhead-vs-gain-{}.png", file_safe(batch));
    if (ch.write((std::filesystem::path(dir) / name).string())) written.push_back(name);
  }
  return written;
}

}  // namespace raysort
