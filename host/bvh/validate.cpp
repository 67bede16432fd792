// BVH invariants the kernels rely on. See bvh.h.
#include <fmt/format.h>

#include <vector>

#include "bvh/bvh.h"

namespace raysort {

std::string validate_bvh(const Bvh& bvh, std::size_t triangle_count, const BvhBuildOptions& opts) {
  if (bvh.nodes.empty()) return "no nodes";
  if (bvh.triangles.size() != triangle_count)
    return fmt::format("{} triangles in leaves, scene has {}", bvh.triangles.size(), triangle_count);
  std::vector<std::uint8_t> seen_slot(bvh.triangles.size(), 0);
  std::vector<std::uint8_t> seen_id(triangle_count, 0);
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
        if (seen_id[t.id]++) return fmt::format("triangle {} appears twice", t.id);
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

}  // namespace raysort
