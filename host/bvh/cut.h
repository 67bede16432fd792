#pragma once
// Cuts of the BVH for the hierarchy cut codes, and the regular grid that stands in for a cut
// (Xiang et al., "Faster Ray Tracing through Hierarchy Cut Code", sections 4.2–4.3 and 5).
// A cut is a list of node indices in bit order: descending HAD, ties by node index; the first
// node gets the key's most significant bit.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bvh/bvh.h"

namespace raysort {

// HCC cut, Alg. 2: a priority queue (highest HAD first) starts with `root`; pop the head and push
// both children until the queue holds `size` nodes; a popped leaf cannot be split, so it moves to
// the cut and the target shrinks by one. Result: min(size, leaves under root) nodes forming a cut
// of root's subtree (every root-to-leaf path below `root` crosses it exactly once).
std::vector<std::uint32_t> hierarchy_cut(const Bvh& bvh, const std::vector<double>& had, std::uint32_t size,
                                         std::uint32_t root = 0);

// Alg. 2 generalised (issue 21, hcc-region and hcc-traffic): the queue orders nodes by `priority`
// (highest first; ties: `tie` when given, then the lower node index), and only nodes for which
// keep(n) holds are ever pushed, the root included (an empty `keep` keeps every node). A popped
// node that cannot be split any further, a leaf or an inner node none of whose children is kept,
// moves to the cut and the target shrinks by one. Bit order: descending priority (same ties).
// hierarchy_cut is this with priority = HAD, no tie vector and every node kept.
std::vector<std::uint32_t> priority_cut(const Bvh& bvh, const std::vector<double>& priority, std::uint32_t size,
                                        std::uint32_t root = 0, const std::vector<double>* tie = nullptr,
                                        const std::function<bool(std::uint32_t)>& keep = {});

// hcc-region's cut of one region: priority_cut by HAD keeping only the nodes whose box overlaps
// `region` (closed boxes: touching counts). Every node of the result overlaps the region.
std::vector<std::uint32_t> region_cut(const Bvh& bvh, const std::vector<double>& had, std::uint32_t size,
                                      const Aabb& region);

// hcc-traffic's priority: (1 − β)·HAD/HAD(root) + β·visits/visits(root), visits = rays whose
// traversal stepped through each node (trace/tracer.h, node_traffic). β = 0, no visits (empty) or
// no ray entering the root: HAD itself, so the cut is HCC's.
std::vector<double> traffic_priority(const std::vector<double>& had, const std::vector<std::uint64_t>& visits,
                                     double blend);

// Closed boxes a and b share a point (on every axis, a.min <= b.max and b.min <= a.max).
bool boxes_overlap(const Aabb& a, const Aabb& b);

// MLHCC cut, Alg. 3, for keys of 2·half bits: `top` holds at most `half` top-level nodes (bit
// order), low[i] the HCC cut of `half` nodes under top[i]. The top search expands only nodes whose
// subtree can still give `half` low-level nodes: popping node n pushes the children with at least
// `half` leaves and discards the others (the paper's "no empty low-level nodes"); when no child
// qualifies, n itself is final (like a leaf in Alg. 2). A tree with fewer than `half` leaves gets
// the root as its only top node.
struct TwoLevelCut {
  std::vector<std::uint32_t> top;
  std::vector<std::vector<std::uint32_t>> low;
};
TwoLevelCut two_level_cut(const Bvh& bvh, const std::vector<double>& had, std::uint32_t half);
// The same search for an uneven split of the key (tools/order_study): at most `top_count` top nodes,
// each with a low-level cut of `low_count` nodes, pushing only children with at least `low_count`
// leaves. two_level_cut(bvh, had, half) is two_level_cut(bvh, had, half, half).
TwoLevelCut two_level_cut(const Bvh& bvh, const std::vector<double>& had, std::uint32_t top_count,
                          std::uint32_t low_count);

// RegularGrid cells (Xiang et al. section 5): the largest power of two ≤ max_cells equal cells of
// `box`, made by doubling, one step at a time, the axis whose cells are longest (ties: lower axis),
// so 32 cells of a cube are 4×4×2. Order: row-major with the most-split axis most significant (ties:
// lower axis). Neighbouring cells share their boundary value exactly; the outer faces are the box's.
std::vector<Aabb> regular_grid_cells(const Aabb& box, std::uint32_t max_cells);
// The cells per axis regular_grid_cells uses.
std::array<std::uint32_t, 3> regular_grid_shape(const Aabb& box, std::uint32_t max_cells);

// "" when `cut` is a valid cut of root's subtree (every root-to-leaf path below root meets exactly
// one of its nodes, and no node appears twice), else a description of the first violation.
std::string validate_cut(const Bvh& bvh, const std::vector<std::uint32_t>& cut, std::uint32_t root = 0);

Aabb node_box(const RsBvhNode& n);

}  // namespace raysort
