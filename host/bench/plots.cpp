#include "bench/plots.h"

#ifdef RAYSORT_NO_IMAGES
namespace raysort {
// Built with -DRAYSORT_IMAGES=OFF (CMakeLists.txt): no plots; the tables and CSV are what a result
// set must have, as when a plot cannot be written.
std::vector<std::string> write_plots(const std::vector<CellRecord>&, const std::string&) { return {}; }
}  // namespace raysort
#else
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>

#include "util/error.h"
#include "util/image.h"

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
  // A marker of one of kShapes shapes at data (x, y); shapes tell scenes apart where colours tell
  // encoders apart.
  void marker(double x, double y, const float* c, int shape = 0) { marker_px(px(x), py(y), c, shape); }
  void marker_px(int x, int y, const float* c, int shape) {
    auto seg = [&](int xa, int ya, int xb, int yb) {
      for (int d = 0; d < 2; ++d) IBA::render_line(buf_, xa + d, ya, xb + d, yb, {c, 3});
    };
    const int r = 5;
    switch (shape % kShapes) {
      case 0: IBA::render_box(buf_, x - r + 1, y - r + 1, x + r - 1, y + r - 1, {c, 3}, true); break;  // square
      case 1: seg(x, y - r, x - r, y + r), seg(x - r, y + r, x + r, y + r), seg(x + r, y + r, x, y - r); break;  // triangle
      case 2: seg(x, y - r, x + r, y), seg(x + r, y, x, y + r), seg(x, y + r, x - r, y), seg(x - r, y, x, y - r); break;  // diamond
      case 3: seg(x - r, y - r, x + r, y + r), seg(x - r, y + r, x + r, y - r); break;  // x
      case 4: seg(x - r, y, x + r, y), seg(x, y - r, x, y + r); break;                  // +
      case 5: IBA::render_box(buf_, x - r, y - r, x + r, y + r, {c, 3}, false); break;  // hollow square
      case 6:  // filled triangle
        for (int dy = 0; dy <= 2 * r; ++dy) IBA::render_line(buf_, x - dy / 2, y - r + dy, x + dy / 2, y - r + dy, {c, 3});
        break;
      case 7:  // filled diamond
        for (int dy = -r; dy <= r; ++dy) IBA::render_line(buf_, x - (r - std::abs(dy)), y + dy, x + (r - std::abs(dy)), y + dy, {c, 3});
        break;
      case 8:  // octagon
        seg(x - 2, y - r, x + 2, y - r), seg(x + 2, y - r, x + r, y - 2), seg(x + r, y - 2, x + r, y + 2),
            seg(x + r, y + 2, x + 2, y + r), seg(x + 2, y + r, x - 2, y + r), seg(x - 2, y + r, x - r, y + 2),
            seg(x - r, y + 2, x - r, y - 2), seg(x - r, y - 2, x - 2, y - r);
        break;
      case 9: seg(x - r, y - r, x + r, y + r), seg(x - r, y + r, x + r, y - r), seg(x - r, y, x + r, y); break;  // asterisk
    }
  }
  // A vertical error bar from y0 to y1 at x, with caps.
  void error_bar(double x, double y0, double y1, const float* c) {
    IBA::render_line(buf_, px(x), py(y0), px(x), py(y1), {c, 3});
    IBA::render_line(buf_, px(x) - 3, py(y0), px(x) + 3, py(y0), {c, 3});
    IBA::render_line(buf_, px(x) - 3, py(y1), px(x) + 3, py(y1), {c, 3});
  }
  static constexpr int kShapes = 10;
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
  // Through util/image.h, as every picture raysort writes; a plot that cannot be written is left
  // out (the tables and CSV are what a result set must have).
  bool write(const std::string& path) {
    Image img(static_cast<std::uint32_t>(w_), static_cast<std::uint32_t>(h_));
    if (!buf_.get_pixels(OIIO::ROI(0, w_, 0, h_, 0, 1, 0, 3), OIIO::TypeDesc::FLOAT, img.rgb.data())) return false;
    try {
      write_png(img, path, 1.0f, PngEncoding::AsIs);
      return true;
    } catch (const Error&) {
      return false;
    }
  }

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

// The speedup a plot shows for a cell: only ok encoder cells whose order differs from NoSort's.
bool plotted(const CellRecord& c) {
  return c.ok() && c.encoder != kBaselineEncoder && !c.same_order_as_nosort && c.speedup.has_value();
}
double low_of(const Estimate& e) { return e.has_interval() ? e.lo : e.value; }
double high_of(const Estimate& e) { return e.has_interval() ? e.hi : e.value; }

// "-fast", "-packet8", "-permute", "-shuffled": the parts of a cell's identity a plot file name
// carries beyond scene, batch and bits (as CellRecord::id does: nothing for the defaults).
std::string facet_suffix(const std::string& variant, const std::string& layout, const std::string& access,
                         const std::string& baseline) {
  return (variant != "robust" ? "-" + variant : std::string()) + (layout != "wide" ? "-" + layout : std::string()) +
         (access != "gather" ? "-" + access : std::string()) + (baseline != "pixel" ? "-" + baseline : std::string());
}
// ", fast, packet8, permute, shuffled": the same facets in a title.
std::string facet_title(const std::string& variant, const std::string& layout, const std::string& access,
                        const std::string& baseline) {
  return (variant != "robust" ? ", " + variant : std::string()) + (layout != "wide" ? ", " + layout : std::string()) +
         (access != "gather" ? ", " + access : std::string()) +
         (baseline != "pixel" ? ", " + baseline + " baseline" : std::string());
}

// What both kinds of plot read: the plotted cells' encoders (one colour each) and scenes (one
// marker shape each), in the order they come.
struct PlotLegend {
  std::vector<std::string> encoders, scenes;
  explicit PlotLegend(const std::vector<CellRecord>& cells) {
    for (auto& c : cells) {
      if (!plotted(c)) continue;
      if (std::find(encoders.begin(), encoders.end(), c.encoder) == encoders.end()) encoders.push_back(c.encoder);
      if (std::find(scenes.begin(), scenes.end(), c.scene) == scenes.end()) scenes.push_back(c.scene);
    }
  }
  int shape_of(const std::string& scene) const {
    return static_cast<int>(std::find(scenes.begin(), scenes.end(), scene) - scenes.begin());
  }
};

// Speedup against key bits with 95 % intervals, per scene, batch, variant, class and access mode with
// more than one key length.
void speed_vs_bits_plots(const std::vector<CellRecord>& cells, const PlotLegend& legend, const std::string& dir,
                         std::vector<std::string>& written) {
  const auto& encoders = legend.encoders;
  // scene, batch, variant, class, access, baseline
  std::set<std::tuple<std::string, std::string, std::string, std::string, std::string, std::string>> facets;
  for (auto& c : cells)
    if (plotted(c)) facets.insert({c.scene, c.batch, c.variant, c.layout, c.access, c.baseline});
  for (auto& [scene, batch, variant, layout, access, baseline] : facets) {
    std::map<std::string, std::map<unsigned, const CellRecord*>> series;
    std::set<unsigned> bits;
    double ymax = 1.0, ymin = 1.0;
    for (auto& c : cells)
      if (plotted(c) && c.scene == scene && c.batch == batch && c.variant == variant && c.layout == layout &&
          c.access == access && c.baseline == baseline && c.top_bits == 0) {
        series[c.encoder][c.bits] = &c;
        bits.insert(c.bits);
        ymax = std::max(ymax, high_of(c.speedup));
        ymin = std::min(ymin, low_of(c.speedup));
      }
    if (bits.size() < 2) continue;
    Chart ch(900, 560, *bits.begin() - 4.0, *bits.rbegin() + 4.0, std::floor(ymin * 10) / 10, std::ceil(ymax * 10) / 10 + 0.05);
    ch.axes(fmt::format("{} {}{}: trace speedup vs NoSort (95 % interval) against key bits", scene, batch,
                        facet_title(variant, layout, access, baseline)),
            "key bits", "speedup", std::vector<double>(bits.begin(), bits.end()));
    std::size_t i = 0;
    for (auto& e : encoders) {
      auto it = series.find(e);
      if (it == series.end()) {
        ++i;
        continue;
      }
      const float* col = color(i);
      // Encoders side by side within a key length, so that their error bars do not hide each other.
      const double dx = (static_cast<double>(i) - 0.5 * static_cast<double>(encoders.size() - 1)) * 0.5;
      double px = 0, py = 0;
      bool first = true;
      for (auto& [b, c] : it->second) {
        const double x = b + dx, y = c->speedup.value;
        if (!first) ch.line(px, py, x, y, col);
        if (c->speedup.has_interval()) ch.error_bar(x, c->speedup.lo, c->speedup.hi, col);
        ch.marker(x, y, col, static_cast<int>(i));
        px = x, py = y, first = false;
      }
      ch.marker_px(900 - 165, 65 + 20 * static_cast<int>(i), col, static_cast<int>(i));
      ch.text(900 - 152, 70 + 20 * static_cast<int>(i), e, 14, col);
      ++i;
    }
    std::string name =
        fmt::format("speed-vs-bits-{}-{}{}.png", file_safe(scene), file_safe(batch),
                    facet_suffix(variant, layout, access, baseline));
    if (ch.write((std::filesystem::path(dir) / name).string())) written.push_back(name);
  }

}

// Overhead against gain, per batch, key length, variant, class and access mode: colour = encoder, shape =
// scene, error bar = the speedup's 95 % interval.
void overhead_vs_gain_plots(const std::vector<CellRecord>& cells, const PlotLegend& legend, const std::string& dir,
                            std::vector<std::string>& written) {
  const auto& encoders = legend.encoders;
  // batch, bits, variant, class, access, baseline
  std::set<std::tuple<std::string, unsigned, std::string, std::string, std::string, std::string>> facets;
  for (auto& c : cells)
    if (plotted(c) && c.top_bits == 0) facets.insert({c.batch, c.bits, c.variant, c.layout, c.access, c.baseline});
  for (const auto& facet : facets) {
    // Named copies, not structured bindings: clang 14 (the fuzz build) cannot capture those.
    const auto& [batch, bits, variant, layout, access, baseline] = facet;
    auto in_facet = [&, batch = batch, bits = bits, variant = variant, layout = layout, access = access,
                     baseline = baseline](const CellRecord& c) {
      return plotted(c) && c.batch == batch && c.bits == bits && c.top_bits == 0 && c.variant == variant &&
             c.layout == layout && c.access == access && c.baseline == baseline;
    };
    // Overhead relative to the NoSort trace time: (encode + sort [+ permute]) / (trace · speedup).
    auto overhead_x = [](const CellRecord& c) { return c.speedup.value > 0 ? c.overhead_pct.value / c.speedup.value : 0; };
    double xmax = 10, ymax = 1.0, ymin = 1.0;
    for (auto& c : cells)
      if (in_facet(c)) {
        xmax = std::max(xmax, overhead_x(c));
        ymax = std::max(ymax, high_of(c.speedup));
        ymin = std::min(ymin, low_of(c.speedup));
      }
    xmax = std::ceil(xmax / 10) * 10;
    Chart ch(900, 560, 0, xmax, std::floor(ymin * 10) / 10, std::ceil(ymax * 10) / 10 + 0.05);
    std::vector<double> xt;
    for (int k = 0; k <= 5; ++k) xt.push_back(xmax * k / 5);
    ch.axes(fmt::format("{}, {}-bit keys{}: what ordering costs (x) against what it buys (y)", batch, bits,
                        facet_title(variant, layout, access, baseline)),
            access == "permute" ? "encode + sort + permute, % of NoSort trace time" : "encode + sort, % of NoSort trace time",
            "trace speedup", xt);
    // Break-even: net speedup = 1 where overhead/T0 = 1 - 1/s, i.e. s = 1 / (1 - x/100).
    const float grey[3] = {0.6f, 0.6f, 0.6f};
    double lx = 0, ly = 1;
    for (int k = 1; k <= 100; ++k) {
      double x = xmax * k / 100;
      if (x >= 99) break;
      double sp = 1.0 / (1.0 - x / 100.0);
      if (sp > std::ceil(ymax * 10) / 10 + 0.05) break;
      ch.line(lx, ly, x, sp, grey, 1);
      lx = x, ly = sp;
    }
    int legend_y = 70;
    std::size_t i = 0;
    for (auto& e : encoders) {
      const float* col = color(i);
      for (auto& c : cells)
        if (in_facet(c) && c.encoder == e) {
          if (c.speedup.has_interval()) ch.error_bar(overhead_x(c), c.speedup.lo, c.speedup.hi, col);
          ch.marker(overhead_x(c), c.speedup.value, col, legend.shape_of(c.scene));
        }
      ch.text(900 - 160, legend_y, e, 14, col);
      legend_y += 20;
      ++i;
    }
    legend_y += 10;
    for (auto& sc : legend.scenes) {
      ch.marker_px(900 - 155, legend_y - 5, Chart::kBlack, legend.shape_of(sc));
      ch.text(900 - 143, legend_y, sc, 13);
      legend_y += 18;
    }
    ch.text(900 - 160, legend_y + 10, "net speedup = 1", 13, grey);
    std::string name = fmt::format("overhead-vs-gain-{}-{}b{}.png", file_safe(batch), bits,
                                   facet_suffix(variant, layout, access, baseline));
    if (ch.write((std::filesystem::path(dir) / name).string())) written.push_back(name);
  }
}

}  // namespace

std::vector<std::string> write_plots(const std::vector<CellRecord>& cells, const std::string& dir) {
  std::vector<std::string> written;
  const PlotLegend legend(cells);
  speed_vs_bits_plots(cells, legend, dir, written);
  overhead_vs_gain_plots(cells, legend, dir, written);
  return written;
}

}  // namespace raysort
#endif
