#include "bvh/had.h"

namespace raysort {

double node_surface_area(const RsBvhNode& n) {
  double e[3];
  for (int a = 0; a < 3; ++a) {
    e[a] = static_cast<double>(n.bmax[a]) - static_cast<double>(n.bmin[a]);
    if (e[a] < 0.0) return 0.0;
  }
  return 2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]);
}

namespace {
// Nodes reachable from the root, parents before children; walked backwards it visits children
// before their parents (no assumption about how a builder numbers nodes).
std::vector<std::uint32_t> preorder(const Bvh& bvh) {
  std::vector<std::uint32_t> out, stack;
  if (bvh.nodes.empty()) return out;
  out.reserve(bvh.nodes.size());
  stack.push_back(0);
  while (!stack.empty()) {
    std::uint32_t k = stack.back();
    stack.pop_back();
    out.push_back(k);
    const RsBvhNode& n = bvh.nodes[k];
    if (n.count == 0) {
      stack.push_back(n.first + 1);
      stack.push_back(n.first);
    }
  }
  return out;
}
}  // namespace

std::vector<double> hierarchically_accumulated_density(const Bvh& bvh, double lambda) {
  std::vector<double> had(bvh.nodes.size(), 0.0);
  const auto order = preorder(bvh);
  for (std::size_t i = order.size(); i-- > 0;) {
    const std::uint32_t k = order[i];
    const RsBvhNode& n = bvh.nodes[k];
    const double sa = node_surface_area(n);
    if (n.count > 0)
      had[k] = static_cast<double>(n.count) * sa;
    else
      had[k] = had[n.first] + had[n.first + 1] + lambda * sa;
  }
  return had;
}

std::vector<std::uint32_t> subtree_leaf_counts(const Bvh& bvh) {
  std::vector<std::uint32_t> leaves(bvh.nodes.size(), 0);
  const auto order = preorder(bvh);
  for (std::size_t i = order.size(); i-- > 0;) {
    const std::uint32_t k = order[i];
    const RsBvhNode& n = bvh.nodes[k];
    leaves[k] = n.count > 0 ? 1u : leaves[n.first] + leaves[n.first + 1];
  }
  return leaves;
}

}  // namespace raysort
