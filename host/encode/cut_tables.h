#pragma once
// Boxes as the cut-based key kernels read them (cl/keys_cut.h): sixteen-box SoA groups, per-ray
// rows of them, and the two-level tables of MLHCC and mlhcc-cost. Shared by the box-set, two-level,
// region-cut and cost-cut families.
#include <cstdint>
#include <vector>

#include "bvh/bvh.h"
#include "bvh/cut.h"
#include "keys_cut.h"

namespace raysort {

RsBox to_rs_box(const Aabb& b);
// Boxes [0, n ≤ 64) transposed into ceil(n / 16) RsCutGroups (cl/keys_cut.h): box i in lane 15 − i % 16
// of group i / 16 (rs_cut_bits places it at code bit 63 − first_bit − i); missing lanes are zero
// boxes. Throws Error for a box with lo > hi or NaN bounds.
std::vector<RsCutGroup> rs_cut_groups(const RsBox* boxes, std::size_t n);

// Rows of cut boxes as the kernels read them per ray (rs_cut_bits_g on row i, at groups + i ·
// ceil(row / 16)): for each cut, its nodes' boxes zero-padded to `row` boxes ([cuts × row]), the
// same as sixteen-box groups (rs_cut_groups), and its box count. MLHCC's and mlhcc-cost's low
// levels and hcc-region's regions are such rows.
struct CutRows {
  std::vector<RsBox> boxes;
  std::vector<RsCutGroup> groups;
  std::vector<rs_u32> counts;
};
CutRows cut_rows(const Bvh& bvh, const std::vector<std::vector<std::uint32_t>>& cuts, unsigned row);

// The tables the two-level kernels read (cl/keys_cut.h, rs_two_level_split_code) for a two-level
// cut: the top boxes, and boxes [top.size() × row] (row i: the low cut of top i, zero-padded to
// `row` boxes), both also as sixteen-box groups (rs_cut_groups: ceil(row / 16) groups per row);
// the low counts per top node. MLHCC's rows are half the key, mlhcc-cost's its low_bits.
struct TwoLevelTables {
  std::vector<RsBox> top, low;
  std::vector<rs_u32> low_count;
  std::vector<RsCutGroup> top_groups, low_groups;
};
TwoLevelTables two_level_tables(const Bvh& bvh, const TwoLevelCut& cut, unsigned row);

}  // namespace raysort
