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

  std::vector<Box> boxes(n);
  std::vector<std::array<float, 3>> centroids(n);
  for (std::size_t i = 0; i < n; ++i) {
    boxes[i].grow(tris.v0[i].data());
    boxes[i].grow(tris.v1[i].data());
    boxes[i].grow(tris.v2[i].data());
    for (int a = 0; a < 3; ++a) centroids[i][a] = (boxes[i].lo[a] + boxes[i].hi[a]) * 0.5f;
  }
  std::vector<std::uint32_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0u);

  Bvh bvh;
  bvh.nodes.reserve(2 * n / std::max<std::uint32_t>(1, opts.max_leaf_size / 2) + 1);
  bvh.nodes.push_back({});
  std::vector<Task> stack{{0, 0, static_cast<std::uint32_t>(n), 0}};

  const std::uint32_t nbins = std::max<std::uint32_t>(2, opts.bins);
  std::vector<Box> bin_box(3 * nbins);
  std::vector<std::uint32_t> bin_count(3 * nbins);
  std::vector<float> right_area(nbins);
  std::vector<std::uint32_t> right_count(nbins);

  while (!stack.empty()) {
    Task task = stack.back();
    stack.pop_back();
    const std::uint32_t count = task.end - task.begin;
    Box bounds, cbounds;
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      bounds.grow(boxes[idx[i]]);
      cbounds.grow(centroids[idx[i]].data());
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

    // Find the best binned SAH split over the three axes.
    int best_axis = -1;
    std::uint32_t best_bin = 0;
    float best_cost = 3.0e38f;
    if (task.depth < kMaxSahDepth) {
      std::fill(bin_box.begin(), bin_box.end(), Box{});
      std::fill(bin_count.begin(), bin_count.end(), 0u);
      float scale[3];
      for (int a = 0; a < 3; ++a) {
        float ext = cbounds.hi[a] - cbounds.lo[a];
        scale[a] = ext > 0.0f ? static_cast<float>(nbins) / ext : 0.0f;
      }
      for (std::uint32_t i = task.begin; i < task.end; ++i) {
        const std::uint32_t t = idx[i];
        for (int a = 0; a < 3; ++a) {
          if (scale[a] == 0.0f) continue;
          auto b = static_cast<std::uint32_t>((centroids[t][a] - cbounds.lo[a]) * scale[a]);
          b = std::min(b, nbins - 1);
          bin_box[a * nbins + b].grow(boxes[t]);
          ++bin_count[a * nbins + b];
        }
      }
      for (int a = 0; a < 3; ++a) {
        if (scale[a] == 0.0f) continue;
        Box acc;
        std::uint32_t acc_n = 0;
        for (std::uint32_t b = nbins - 1; b > 0; --b) {
          acc.grow(bin_box[a * nbins + b]);
          acc_n += bin_count[a * nbins + b];
          right_area[b] = acc.area();
          right_count[b] = acc_n;
        }
        Box left;
        std::uint32_t left_n = 0;
        for (std::uint32_t b = 0; b + 1 < nbins; ++b) {
          left.grow(bin_box[a * nbins + b]);
          left_n += bin_count[a * nbins + b];
          if (left_n == 0 || right_count[b + 1] == 0) continue;
          float cost = left.area() * static_cast<float>(left_n) + right_area[b + 1] * static_cast<float>(right_count[b + 1]);
          if (cost < best_cost) {
            best_cost = cost;
            best_axis = a;
            best_bin = b;
          }
        }
      }
    }

    std::uint32_t mid = 0;
    const float parent_area = bounds.area();
    const float leaf_cost = opts.intersection_cost * static_cast<float>(count);
    const float split_cost = best_axis >= 0 && parent_area > 0.0f
                                 ? opts.traversal_cost + opts.intersection_cost * best_cost / parent_area
                                 : 3.0e38f;
    if (best_axis >= 0 && (split_cost < leaf_cost || count > opts.max_leaf_size)) {
      const int a = best_axis;
      const float lo = cbounds.lo[a];
      const float sc = static_cast<float>(nbins) / (cbounds.hi[a] - cbounds.lo[a]);
      auto it = std::partition(idx.begin() + task.begin, idx.begin() + task.end, [&](std::uint32_t t) {
        auto b = static_cast<std::uint32_t>((centroids[t][a] - lo) * sc);
        return std::min(b, nbins - 1) <= best_bin;
      });
      mid = static_cast<std::uint32_t>(it - idx.begin());
    } else if (count <= opts.max_leaf_size) {
      make_leaf();
      continue;
    }
    if (mid <= task.begin || mid >= task.end) {
      // No usable SAH split (deep node, all centroids equal, or SAH prefers a too-large leaf):
      // split at the object median along the widest centroid axis; ties broken by index so
      // the result is deterministic.
      int axis = 0;
      for (int a = 1; a < 3; ++a)
        if (cbounds.hi[a] - cbounds.lo[a] > cbounds.hi[axis] - cbounds.lo[axis]) axis = a;
      mid = task.begin + count / 2;
      std::nth_element(idx.begin() + task.begin, idx.begin() + mid, idx.begin() + task.end,
                       [&](std::uint32_t x, std::uint32_t y) {
                         return centroids[x][axis] < centroids[y][axis] ||
                                (centroids[x][axis] == centroids[y][axis] && x < y);
                       });
    }
    const auto left = static_cast<std::uint32_t>(bvh.nodes.size());
    bvh.nodes.push_back({});
    bvh.nodes.push_back({});
    bvh.nodes[task.node].first = left;
    bvh.nodes[task.node].count = 0;
    // Right first on the stack so the left subtree is laid out first (depth-first order).
    stack.push_back({left + 1, mid, task.end, task.depth + 1});
    stack.push_back({left, task.begin, mid, task.depth + 1});
  }

  bvh.triangles.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t t = idx[k];
    RsTriangle& tri = bvh.triangles[k];
    for (int a = 0; a < 3; ++a) {
      tri.v0[a] = tris.v0[t][a];
      tri.v1[a] = tris.v1[t][a];
      tri.v2[a] = tris.v2[t][a];
    }
    tri.id = t;
    tri.pad0 = tri.pad1 = 0;
  }
  bvh.wide = collapse_to_wide(bvh);
  bvh.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return bvh;
}

}  // namespace raysort
