// The SAH cost of a built tree (bvh.h), the figure `raysort trace` prints next to the build time.
#include "bvh/bvh.h"

namespace raysort {

namespace {
double area(const RsBvhNode& n) {
  const double e0 = double(n.bmax[0]) - n.bmin[0], e1 = double(n.bmax[1]) - n.bmin[1], e2 = double(n.bmax[2]) - n.bmin[2];
  return e0 < 0.0 ? 0.0 : 2.0 * (e0 * e1 + e1 * e2 + e2 * e0);
}
}  // namespace

double sah_cost(const Bvh& bvh, const BvhBuildOptions& opts) {
  if (bvh.nodes.empty()) return 0.0;
  double sum = 0.0;
  for (const RsBvhNode& n : bvh.nodes)
    sum += n.count > 0 ? opts.intersection_cost * n.count * area(n) : opts.traversal_cost * area(n);
  const double root = area(bvh.nodes[0]);
  // A flat or point-sized scene: every ray that reaches the root meets every node, so count the areas as 1.
  if (root <= 0.0) {
    sum = 0.0;
    for (const RsBvhNode& n : bvh.nodes) sum += n.count > 0 ? opts.intersection_cost * n.count : opts.traversal_cost;
    return sum;
  }
  return sum / root;
}

}  // namespace raysort
