// BVH invariants the kernels rely on. See bvh.h.
#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "bvh/bvh.h"

namespace raysort {

namespace {

// validate_bvh's walk. plain: null, or the tree `bvh` rebuilt with spatial splits from (a triangle
// may then be in several leaves, each copy exactly plain's, and a leaf's box holds its parts only).
std::string validate_tree(const Bvh& bvh, std::size_t triangle_count, const BvhBuildOptions& opts, const Bvh* plain) {
  if (bvh.nodes.empty()) return "no nodes";
  if (plain ? bvh.triangles.size() < triangle_count : bvh.triangles.size() != triangle_count)
    return fmt::format("{} triangles in leaves, scene has {}", bvh.triangles.size(), triangle_count);
  std::vector<std::uint8_t> seen_slot(bvh.triangles.size(), 0);
  std::vector<std::uint8_t> seen_id(triangle_count, 0);
  std::vector<std::uint32_t> plain_index(plain ? triangle_count : 0, 0);  // a triangle id's slot in plain
  if (plain)
    for (std::uint32_t k = 0; k < plain->triangles.size(); ++k)
      if (plain->triangles[k].id < triangle_count) plain_index[plain->triangles[k].id] = k;
  struct Item {
    std::uint32_t node, depth;
  };
  std::vector<Item> stack{{0, 0}};
  std::size_t visited = 0;
  std::uint32_t depth = 0;
  while (!stack.empty()) {
    auto [n, d] = stack.back();
    stack.pop_back();
    if (n >= bvh.nodes.size()) return fmt::format("node index {} out of range", n);
    ++visited;
    depth = std::max(depth, d);
    if (d + 1 >= RS_STACK_SIZE) return fmt::format("depth {} reaches the traversal stack bound {}", d, RS_STACK_SIZE);
    const RsBvhNode& node = bvh.nodes[n];
    for (int a = 0; a < 3; ++a)
      if (!(node.bmin[a] <= node.bmax[a])) return fmt::format("node {} has an inverted or NaN box on axis {}", n, a);
    if (node.count > 0) {
      if (node.count > opts.max_leaf_size)
        return fmt::format("leaf {} holds {} triangles, more than the limit {}", n, node.count, opts.max_leaf_size);
      if (static_cast<std::size_t>(node.first) + node.count > bvh.triangles.size())
        return fmt::format("leaf {} triangle range out of bounds", n);
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
        if (seen_slot[k]++) return fmt::format("triangle slot {} is in two leaves", k);
        const RsTriangle& t = bvh.triangles[k];
        if (t.id >= triangle_count) return fmt::format("triangle slot {} has id {} out of range", k, t.id);
        if (seen_id[t.id]++ && !plain) return fmt::format("triangle {} appears twice", t.id);
        if (plain) {
          // A part of the triangle: the triangle itself, exactly, and a box that meets the leaf's.
          const RsTriangle& p = plain->triangles[plain_index[t.id]];
          if (std::memcmp(p.v0, t.v0, sizeof p.v0) != 0 || std::memcmp(p.v1, t.v1, sizeof p.v1) != 0 ||
              std::memcmp(p.v2, t.v2, sizeof p.v2) != 0)
            return fmt::format("triangle slot {} (id {}) is not the plain tree's triangle {}", k, t.id, t.id);
          for (int a = 0; a < 3; ++a)
            if (std::max({t.v0[a], t.v1[a], t.v2[a]}) < node.bmin[a] || std::min({t.v0[a], t.v1[a], t.v2[a]}) > node.bmax[a])
              return fmt::format("triangle {} lies outside its leaf {} (axis {})", t.id, n, a);
          continue;
        }
        for (const float* v : {t.v0, t.v1, t.v2})
          for (int a = 0; a < 3; ++a)
            if (v[a] < node.bmin[a] || v[a] > node.bmax[a])
              return fmt::format("triangle {} sticks out of its leaf {}", t.id, n);
      }
    } else {
      if (node.first + 1 >= bvh.nodes.size()) return fmt::format("inner node {} has children out of range", n);
      for (std::uint32_t c = node.first; c <= node.first + 1; ++c) {
        const RsBvhNode& child = bvh.nodes[c];
        for (int a = 0; a < 3; ++a)
          if (child.bmin[a] < node.bmin[a] || child.bmax[a] > node.bmax[a])
            return fmt::format("child {} box is not inside its parent {} (axis {})", c, n, a);
        stack.push_back({c, d + 1});
      }
    }
  }
  for (std::size_t k = 0; k < seen_id.size(); ++k)
    if (!seen_id[k]) return fmt::format("triangle {} is in no leaf", k);
  if (visited != bvh.nodes.size()) return fmt::format("{} nodes unreachable from the root", bvh.nodes.size() - visited);
  if (depth != bvh.depth) return fmt::format("recorded depth {} but the tree is {} deep", bvh.depth, depth);
  return {};
}

}  // namespace

std::string validate_bvh(const Bvh& bvh, std::size_t triangle_count, const BvhBuildOptions& opts) {
  return validate_tree(bvh, triangle_count, opts, nullptr);
}

std::string validate_spatial_bvh(const Bvh& split, const Bvh& plain, double budget, const BvhBuildOptions& opts) {
  const std::size_t n = plain.triangles.size();
  const auto most = static_cast<std::size_t>(static_cast<double>(n) * (1.0 + budget));
  if (split.triangles.size() > most)
    return fmt::format("{} references to {} triangles, more than the budget's {}", split.triangles.size(), n, most);
  return validate_tree(split, n, opts, &plain);
}

}  // namespace raysort
