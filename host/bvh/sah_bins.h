#pragma once
// The binned SAH split search (Wald 2007, "On fast Construction of SAH-based Bounding Volume
// Hierarchies"): the best split plane among `bins` equal bins of a node's centroid bounds on each
// axis. Used by the builder (host/bvh/build_sah.cpp) only; inline because its loops are the build.
//
// Bins of disjoint parts of a node merge exactly (boxes by min/max, counts by sums), so a node
// binned by several threads, each over its own chunk, gets the very bins, and the very split, of
// one thread binning it all: the parallel build stays bit-for-bit the serial one.
#include <emmintrin.h>

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "bvh_layout.h"
#include "util/error.h"

namespace raysort::sah {

struct Box {
  float lo[3] = {3.0e38f, 3.0e38f, 3.0e38f};
  float hi[3] = {-3.0e38f, -3.0e38f, -3.0e38f};
  void grow(const float* p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  void grow(const float* l, const float* h) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], l[a]);
      hi[a] = std::max(hi[a], h[a]);
    }
  }
  void grow(const Box& b) { grow(b.lo, b.hi); }
  float area() const {
    float e0 = hi[0] - lo[0], e1 = hi[1] - lo[1], e2 = hi[2] - lo[2];
    if (e0 < 0.0f) return 0.0f;
    return 2.0f * (e0 * e1 + e1 * e2 + e2 * e0);
  }
};

// Writes a box into a binary node (both builders, build_sah.cpp and build_spatial.cpp).
inline void set_box(RsBvhNode& node, const Box& b) {
  for (int a = 0; a < 3; ++a) {
    node.bmin[a] = b.lo[a];
    node.bmax[a] = b.hi[a];
  }
}

// One triangle as the builder moves it: its box and its index in the scene's flat list. The
// builder partitions these 32-byte records themselves rather than indices to them, so every pass
// over a node reads memory in order instead of gathering boxes from all over the scene.
struct PrimRef {
  float lo[3];
  std::uint32_t id;
  float hi[3];
  std::uint32_t pad;
  // The same arithmetic the builder always used for a centroid: (box.lo + box.hi) / 2.
  float centroid(int a) const { return (lo[a] + hi[a]) * 0.5f; }
};

// The builder's inner loops on SSE (x86-64's baseline; no -march): a box is two float4 (x, y, z and
// an unused lane). Exactly the scalar arithmetic lane by lane: adds, multiplies and truncation are
// IEEE single precision either way, and min/max take their operands in the order of std::min /
// std::max (minps(a, b) = a < b ? a : b, so std::min(acc, p) = p < acc ? p : acc is minps(p, acc)),
// so the bins, the splits and the tree are those of the scalar builder bit for bit.
struct Box4 {
  __m128 lo = _mm_set1_ps(3.0e38f);
  __m128 hi = _mm_set1_ps(-3.0e38f);
  void grow(__m128 l, __m128 h) {
    lo = _mm_min_ps(l, lo);
    hi = _mm_max_ps(h, hi);
  }
  void grow(const Box4& b) { grow(b.lo, b.hi); }
  // Box::area() on the float4s: the same products, summed in the same order.
  float area() const {
    alignas(16) float e[4];
    _mm_store_ps(e, _mm_sub_ps(hi, lo));
    if (e[0] < 0.0f) return 0.0f;
    return 2.0f * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]);
  }
  Box box() const {
    alignas(16) float l[4], h[4];
    _mm_store_ps(l, lo);
    _mm_store_ps(h, hi);
    Box b;
    for (int a = 0; a < 3; ++a) b.lo[a] = l[a], b.hi[a] = h[a];
    return b;
  }
};

// A record's box as two float4, the fourth lanes (its id and padding) zeroed so that no lane ever
// holds a denormal or NaN pattern.
inline void load(const PrimRef& r, __m128& lo, __m128& hi) {
  const __m128 xyz = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
  lo = _mm_and_ps(_mm_loadu_ps(r.lo), xyz);
  hi = _mm_and_ps(_mm_loadu_ps(r.hi), xyz);
}
inline __m128 centroid(__m128 lo, __m128 hi) { return _mm_mul_ps(_mm_add_ps(lo, hi), _mm_set1_ps(0.5f)); }

// A node's boxes: of its triangles, and of their centroids (what the bins divide).
struct NodeBounds {
  Box bounds, centroids;
  void add(const PrimRef* begin, const PrimRef* end) {
    Box4 b, c;
    for (const PrimRef* r = begin; r != end; ++r) {
      __m128 lo, hi;
      load(*r, lo, hi);
      b.grow(lo, hi);
      const __m128 m = centroid(lo, hi);
      c.grow(m, m);
    }
    merge({b.box(), c.box()});
  }
  void merge(const NodeBounds& o) {
    bounds.grow(o.bounds);
    centroids.grow(o.centroids);
  }
};

// Which bin a centroid falls in, per axis: floor((c − lo) · bins / extent), clamped. An axis with no
// extent has scale 0 and no bins. The split search and the partition both use this one mapping,
// so a triangle lands on the side its bin was counted on. Coordinates are finite (the scene
// loader refuses others), so (c − lo) · scale lies in [0, bins · (1 + ε)].
struct BinMap {
  float lo[3];
  float scale[3];
  std::uint32_t bins;
  BinMap(const Box& centroids, std::uint32_t nbins) : bins(nbins) {
    for (int a = 0; a < 3; ++a) {
      const float ext = centroids.hi[a] - centroids.lo[a];
      lo[a] = centroids.lo[a];
      scale[a] = ext > 0.0f ? static_cast<float>(nbins) / ext : 0.0f;
    }
  }
  std::uint32_t bin(const PrimRef& r, int a) const {
    const auto b = static_cast<std::uint32_t>((r.centroid(a) - lo[a]) * scale[a]);
    return std::min(b, bins - 1);
  }
  // bin() on all three axes at once.
  void bins3(__m128 lo4, __m128 hi4, std::uint32_t out[4]) const {
    const __m128 x = _mm_mul_ps(_mm_sub_ps(centroid(lo4, hi4), _mm_set_ps(0.0f, lo[2], lo[1], lo[0])),
                                _mm_set_ps(0.0f, scale[2], scale[1], scale[0]));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(x));
    for (int a = 0; a < 3; ++a) out[a] = std::min(out[a], bins - 1);
  }
};

struct Split {
  int axis = -1;  // -1: no SAH split found
  std::uint32_t bin = 0;
  float cost = 3.0e38f;  // left area · count + right area · count
};

// The bins of one node (or of one chunk of it), all three axes.
class SahBins {
 public:
  explicit SahBins(std::uint32_t bins)
      : nbins_(bins), box_(3 * nbins_), count_(3 * nbins_), box2_(3 * nbins_), count2_(3 * nbins_), right_area_(nbins_) {
    if (bins > 64) throw Error("SAH bins: " + std::to_string(bins) + " per axis, at most 64 (BvhBuildOptions::bins)");
  }
  SahBins(const SahBins&) = default;
  std::uint32_t bins() const { return nbins_; }

  // Empty bins: only the occupied ones are reset. A bin whose count is 0 still has the empty box (a
  // record grows a box and counts it together; merging an empty bin changes nothing), and small
  // nodes, most of the tree, occupy a few of the 3 x bins.
  void clear() {
    for (std::size_t i = 0; i < count_.size(); ++i)
      if (count_[i] != 0) {
        box_[i] = Box4{};
        count_[i] = 0;
      }
  }
  void add(const PrimRef* begin, const PrimRef* end, const BinMap& map) {
    if (end - begin < kSplitAbove) {
      add_to(begin, end, map, box_.data(), count_.data());
      return;
    }
    // Two records at a time, the second into a second set of bins merged at the end: records in a
    // row often fall in the same bins, and one set made each wait for the last one's stores.
    // Merging is exact for the split (see merge()).
    std::fill(box2_.begin(), box2_.end(), Box4{});
    std::fill(count2_.begin(), count2_.end(), 0u);
    const PrimRef* r = begin;
    for (; r + 1 < end; r += 2) {
      add_one(r[0], map, box_.data(), count_.data());
      add_one(r[1], map, box2_.data(), count2_.data());
    }
    add_to(r, end, map, box_.data(), count_.data());
    for (std::size_t i = 0; i < box_.size(); ++i) {
      box_[i].grow(box2_[i]);
      count_[i] += count2_[i];
    }
  }
  // Bins merge exactly for what they decide: a box's coordinates are the same whichever record
  // came first except for the sign of a zero, which no area, cost or comparison of best() sees
  // (a zero extent or product is a zero of either sign, and adding it changes no sum).
  void merge(const SahBins& o) {
    for (std::size_t i = 0; i < box_.size(); ++i) {
      box_[i].grow(o.box_[i]);
      count_[i] += o.count_[i];
    }
  }

  // The cheapest split over all axes (the first found among equal costs: axis x before y before
  // z, lower bins first), or none when every axis has no extent or leaves one side empty.
  Split best(const BinMap& map) {
    Split best;
    for (int a = 0; a < 3; ++a) {
      if (map.scale[a] == 0.0f) continue;
      const Box4* box = &box_[a * nbins_];
      const std::uint32_t* count = &count_[a * nbins_];
      // Only occupied bins: an empty bin changes neither box nor count, so the plane after it costs
      // what the plane before it cost (not less, so never a new best). right_area_[b] is the area of
      // the occupied bins from b up, grown from the top down, for each occupied b > 0: the plane
      // after occupied bin b reads it at the next occupied bin. (The same grows in the same order as
      // a sweep over every bin, so the same costs bit for bit.)
      std::uint64_t occupied = 0;  // bit b: bin b holds a record
      for (std::uint32_t b = 0; b < nbins_; ++b) occupied |= std::uint64_t{count[b] != 0} << b;
      Box4 acc;
      for (std::uint64_t m = occupied & ~std::uint64_t{1}; m != 0;) {
        const int b = 63 - std::countl_zero(m);
        acc.grow(box[b]);
        right_area_[b] = acc.area();
        m &= ~(std::uint64_t{1} << b);
      }
      std::uint32_t total = 0;
      for (std::uint64_t m = occupied; m != 0; m &= m - 1) total += count[std::countr_zero(m)];
      Box4 left;
      std::uint32_t left_n = 0;
      for (std::uint64_t m = occupied; m != 0; m &= m - 1) {
        const int b = std::countr_zero(m);
        const std::uint64_t above = m & (m - 1);  // the occupied bins after b
        if (above == 0) break;                    // nothing right of this plane
        left.grow(box[b]);
        left_n += count[b];
        const std::uint32_t right_n = total - left_n;
        const float cost =
            left.area() * static_cast<float>(left_n) + right_area_[std::countr_zero(above)] * static_cast<float>(right_n);
        if (cost < best.cost) best = {a, static_cast<std::uint32_t>(b), cost};
      }
    }
    return best;
  }

 private:
  static constexpr std::ptrdiff_t kSplitAbove = 64;
  // One record into one set of bins (box, count: box_/count_ or the second set).
  void add_one(const PrimRef& r, const BinMap& map, Box4* box, std::uint32_t* count) const {
    alignas(16) std::uint32_t b[4];
    __m128 lo, hi;
    load(r, lo, hi);
    map.bins3(lo, hi, b);
    for (std::uint32_t a = 0; a < 3; ++a) {
      box[a * nbins_ + b[a]].grow(lo, hi);
      ++count[a * nbins_ + b[a]];
    }
  }
  void add_to(const PrimRef* begin, const PrimRef* end, const BinMap& map, Box4* box, std::uint32_t* count) const {
    for (const PrimRef* r = begin; r != end; ++r) add_one(*r, map, box, count);
  }

  std::uint32_t nbins_;
  std::vector<Box4> box_;
  std::vector<std::uint32_t> count_;
  std::vector<Box4> box2_;  // add()'s second set
  std::vector<std::uint32_t> count2_;
  std::vector<float> right_area_;
};

}  // namespace raysort::sah
