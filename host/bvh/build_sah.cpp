// Binned SAH BVH builder. See bvh.h.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numeric>

#include "bvh/bvh.h"
#include "util/error.h"

namespace raysort {

namespace {

// Past this depth nodes split at the object median, so depth <= kMaxSahDepth + log2(N) < 64.
constexpr std::uint32_t kMaxSahDepth = 32;

struct Box {
  float lo[3] = {3.0e38f, 3.0e38f, 3.0e38f};
  float hi[3] = {-3.0e38f, -3.0e38f, -3.0e38f};
  void grow(const float* p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  void grow(const Box& b) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], b.lo[a]);
      hi[a] = std::max(hi[a], b.hi[a]);
    }
  }
  float area() const {
    float e0 = hi[0] - lo[0], e1 = hi[1] - lo[1], e2 = hi[2] - lo[2];
    if (e0 < 0.0f) return 0.0f;
    return 2.0f * (e0 * e1 + e1 * e2 + e2 * e0);
  }
};

struct Task {
  std::uint32_t node, begin, end, depth;
};

// The triangles' boxes and centroids, and the order the builder partitions (idx).
struct Primitives {
  std::vector<Box> boxes;
  std::vector<std::array<float, 3>> centroids;
  std::vector<std::uint32_t> idx;
};

struct Split {
  int axis = -1;  // -1: no SAH split found
  std::uint32_t bin = 0;
  float cost = 3.0e38f;  // left area · count + right area · count
};

// Binned SAH (Wald 2007): the best split plane among `bins` equal bins of the centroid bounds on
// each axis, with scratch space kept between nodes.
class SahBinner {
 public:
  explicit SahBinner(std::uint32_t bins)
      : nbins_(std::max<std::uint32_t>(2, bins)), bin_box_(3 * nbins_), bin_count_(3 * nbins_), right_area_(nbins_),
        right_count_(nbins_) {}
  std::uint32_t bins() const { return nbins_; }

  Split best(const Primitives& p, const Task& task, const Box& cbounds) {
    Split best;
    std::fill(bin_box_.begin(), bin_box_.end(), Box{});
    std::fill(bin_count_.begin(), bin_count_.end(), 0u);
    float scale[3];
    for (int a = 0; a < 3; ++a) {
      float ext = cbounds.hi[a] - cbounds.lo[a];
      scale[a] = ext > 0.0f ? static_cast<float>(nbins_) / ext : 0.0f;
    }
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      const std::uint32_t t = p.idx[i];
      for (int a = 0; a < 3; ++a) {
        if (scale[a] == 0.0f) continue;
        auto b = static_cast<std::uint32_t>((p.centroids[t][a] - cbounds.lo[a]) * scale[a]);
        b = std::min(b, nbins_ - 1);
        bin_box_[a * nbins_ + b].grow(p.boxes[t]);
        ++bin_count_[a * nbins_ + b];
      }
    }
    for (int a = 0; a < 3; ++a) {
      if (scale[a] == 0.0f) continue;
      Box acc;
      std::uint32_t acc_n = 0;
      for (std::uint32_t b = nbins_ - 1; b > 0; --b) {
        acc.grow(bin_box_[a * nbins_ + b]);
        acc_n += bin_count_[a * nbins_ + b];
        right_area_[b] = acc.area();
        right_count_[b] = acc_n;
      }
      Box left;
      std::uint32_t left_n = 0;
      for (std::uint32_t b = 0; b + 1 < nbins_; ++b) {
        left.grow(bin_box_[a * nbins_ + b]);
        left_n += bin_count_[a * nbins_ + b];
        if (left_n == 0 || right_count_[b + 1] == 0) continue;
        float cost = left.area() * static_cast<float>(left_n) + right_area_[b + 1] * static_cast<float>(right_count_[b + 1]);
        if (cost < best.cost) best = {a, b, cost};
      }
    }
    return best;
  }

 private:
  std::uint32_t nbins_;
  std::vector<Box> bin_box_;
  std::vector<std::uint32_t> bin_count_;
  std::vector<float> right_area_;
  std::vector<std::uint32_t> right_count_;
};

// Partitions idx[begin, end) at the SAH split; returns the middle.
std::uint32_t partition_at(Primitives& p, const Task& task, const Box& cbounds, const Split& split,
                           std::uint32_t nbins) {
  const int a = split.axis;
  const float lo = cbounds.lo[a];
  const float sc = static_cast<float>(nbins) / (cbounds.hi[a] - cbounds.lo[a]);
  auto it = std::partition(p.idx.begin() + task.begin, p.idx.begin() + task.end, [&](std::uint32_t t) {
    auto b = static_cast<std::uint32_t>((p.centroids[t][a] - lo) * sc);
    return std::min(b, nbins - 1) <= split.bin;
  });
  return static_cast<std::uint32_t>(it - p.idx.begin());
}

// No usable SAH split (deep node, all centroids equal, or SAH prefers a too-large leaf): the object
// median along the widest centroid axis, ties broken by index so the result is deterministic.
std::uint32_t median_split(Primitives& p, const Task& task, const Box& cbounds) {
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (cbounds.hi[a] - cbounds.lo[a] > cbounds.hi[axis] - cbounds.lo[axis]) axis = a;
  const std::uint32_t mid = task.begin + (task.end - task.begin) / 2;
  std::nth_element(p.idx.begin() + task.begin, p.idx.begin() + mid, p.idx.begin() + task.end,
                   [&](std::uint32_t x, std::uint32_t y) {
                     return p.centroids[x][axis] < p.centroids[y][axis] ||
                            (p.centroids[x][axis] == p.centroids[y][axis] && x < y);
                   });
  return mid;
}

Primitives primitives_of(const Scene::Flat& tris) {
  const std::size_t n = tris.size();
  Primitives p;
  p.boxes.resize(n);
  p.centroids.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.boxes[i].grow(tris.v0[i].data());
    p.boxes[i].grow(tris.v1[i].data());
    p.boxes[i].grow(tris.v2[i].data());
    for (int a = 0; a < 3; ++a) p.centroids[i][a] = (p.boxes[i].lo[a] + p.boxes[i].hi[a]) * 0.5f;
  }
  p.idx.resize(n);
  std::iota(p.idx.begin(), p.idx.end(), 0u);
  return p;
}

// The triangles in leaf order (what the nodes' first/count index), with their original ids.
std::vector<RsTriangle> leaf_ordered(const Scene::Flat& tris, const std::vector<std::uint32_t>& idx) {
  std::vector<RsTriangle> out(idx.size());
  for (std::size_t k = 0; k < idx.size(); ++k) {
    const std::uint32_t t = idx[k];
    RsTriangle& tri = out[k];
    for (int a = 0; a < 3; ++a) {
      tri.v0[a] = tris.v0[t][a];
      tri.v1[a] = tris.v1[t][a];
      tri.v2[a] = tris.v2[t][a];
    }
    tri.id = t;
    tri.pad0 = tri.pad1 = 0;
  }
  return out;
}

}  // namespace

Aabb Bvh::bounds() const {
  Aabb b;
  if (nodes.empty()) return b;
  b.min = {nodes[0].bmin[0], nodes[0].bmin[1], nodes[0].bmin[2]};
  b.max = {nodes[0].bmax[0], nodes[0].bmax[1], nodes[0].bmax[2]};
  return b;
}

Bvh build_bvh(const Scene::Flat& tris, const BvhBuildOptions& opts) {
  auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = tris.size();
  if (n == 0) throw Error("cannot build a BVH over a scene with no triangles");
  if (n >= 0xFFFFFFF0u) throw Error("scene has too many triangles for 32-bit indices");
  Primitives p = primitives_of(tris);
  SahBinner binner(opts.bins);

  Bvh bvh;
  bvh.nodes.reserve(2 * n / std::max<std::uint32_t>(1, opts.max_leaf_size / 2) + 1);
  bvh.nodes.push_back({});
  std::vector<Task> stack{{0, 0, static_cast<std::uint32_t>(n), 0}};
  while (!stack.empty()) {
    Task task = stack.back();
    stack.pop_back();
    const std::uint32_t count = task.end - task.begin;
    Box bounds, cbounds;
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      bounds.grow(p.boxes[p.idx[i]]);
      cbounds.grow(p.centroids[p.idx[i]].data());
    }
    RsBvhNode& node = bvh.nodes[task.node];
    for (int a = 0; a < 3; ++a) {
      node.bmin[a] = bounds.lo[a];
      node.bmax[a] = bounds.hi[a];
    }
    bvh.depth = std::max(bvh.depth, task.depth);
    auto make_leaf = [&] {
      RsBvhNode& leaf = bvh.nodes[task.node];
      leaf.first = task.begin;
      leaf.count = count;
      ++bvh.leaf_count;
    };
    if (count == 1) {
      make_leaf();
      continue;
    }
    const Split split = task.depth < kMaxSahDepth ? binner.best(p, task, cbounds) : Split{};
    std::uint32_t mid = 0;
    const float parent_area = bounds.area();
    const float leaf_cost = opts.intersection_cost * static_cast<float>(count);
    const float split_cost = split.axis >= 0 && parent_area > 0.0f
                                 ? opts.traversal_cost + opts.intersection_cost * split.cost / parent_area
                                 : 3.0e38f;
    if (split.axis >= 0 && (split_cost < leaf_cost || count > opts.max_leaf_size)) {
      mid = partition_at(p, task, cbounds, split, binner.bins());
    } else if (count <= opts.max_leaf_size) {
      make_leaf();
      continue;
    }
    if (mid <= task.begin || mid >= task.end) mid = median_split(p, task, cbounds);
    const auto left = static_cast<std::uint32_t>(bvh.nodes.size());
    bvh.nodes.push_back({});
    bvh.nodes.push_back({});
    bvh.nodes[task.node].first = left;
    bvh.nodes[task.node].count = 0;
    // Right first on the stack so the left subtree is laid out first (depth-first order).
    stack.push_back({left + 1, mid, task.end, task.depth + 1});
    stack.push_back({left, task.begin, mid, task.depth + 1});
  }
  bvh.triangles = leaf_ordered(tris, p.idx);
  bvh.wide = collapse_to_wide(bvh);
  bvh.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return bvh;
}

}  // namespace raysort
