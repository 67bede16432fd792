#pragma once
// Hierarchically accumulated density (Xiang et al., "Faster Ray Tracing through Hierarchy Cut
// Code", section 4.2.2, Eq. 1): the priority of the HCC / MLHCC cut search.
//   HAD(leaf)  = TC · SA                       (TC: triangles in the leaf, SA: its box's area)
//   HAD(inner) = HAD(left) + HAD(right) + λ · SA
// λ = 0.125 in the paper. Computed bottom-up after the BVH is built; host only (the cut, not HAD,
// goes to the device), in double precision.
#include <cstdint>
#include <vector>

#include "bvh/bvh.h"

namespace raysort {

// Surface area of a node's box (0 for an inverted box).
double node_surface_area(const RsBvhNode& n);

// HAD of every node, indexed like bvh.nodes.
std::vector<double> hierarchically_accumulated_density(const Bvh& bvh, double lambda = 0.125);

// Number of leaves in every node's subtree, indexed like bvh.nodes.
std::vector<std::uint32_t> subtree_leaf_counts(const Bvh& bvh);

}  // namespace raysort
