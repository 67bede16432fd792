// Cut boxes in the layouts the key kernels read (see cut_tables.h).
#include "encode/cut_tables.h"

#include <string>

#include "util/error.h"

namespace raysort {

static_assert(sizeof(RsBox) == 24 && sizeof(RsEncodeFrame) == 48 && sizeof(RsCutGroup) == 384 &&
                  sizeof(RsRegionSplit) == 8,
              "device struct layouts (cl/keys.h, cl/keys_cut.h)");

RsBox to_rs_box(const Aabb& b) {
  RsBox r{};
  for (int a = 0; a < 3; ++a) {
    r.bmin[a] = b.min[a];
    r.bmax[a] = b.max[a];
  }
  return r;
}

std::vector<RsCutGroup> rs_cut_groups(const RsBox* boxes, std::size_t n) {
  if (n > RS_MAX_KEY_BITS) throw Error("rs_cut_groups: more boxes than key bits");
  const std::size_t lanes = RS_CUT_LANES;
  std::vector<RsCutGroup> groups(rs_cut_group_count(static_cast<rs_u32>(n)), RsCutGroup{});
  for (std::size_t i = 0; i < n; ++i) {
    const RsBox& b = boxes[i];
    for (int a = 0; a < 3; ++a)
      if (!(b.bmin[a] <= b.bmax[a]))  // also NaN: the sign-picked slab test needs lo <= hi
        throw Error("rs_cut_groups: box " + std::to_string(i) + " is empty or not a number on axis " +
                    std::to_string(a));
    RsCutGroup& g = groups[i / lanes];
    const std::size_t l = lanes - 1 - i % lanes;  // box j of a group in lane 15 − j (keys.h, RsCutGroup)
    g.lo_x.s[l] = b.bmin[0], g.hi_x.s[l] = b.bmax[0];
    g.lo_y.s[l] = b.bmin[1], g.hi_y.s[l] = b.bmax[1];
    g.lo_z.s[l] = b.bmin[2], g.hi_z.s[l] = b.bmax[2];
  }
  return groups;
}

CutRows cut_rows(const Bvh& bvh, const std::vector<std::vector<std::uint32_t>>& cuts, unsigned row) {
  CutRows rows;
  rows.boxes.assign(cuts.size() * row, RsBox{});
  for (std::size_t i = 0; i < cuts.size(); ++i) {
    if (cuts[i].size() > row)
      throw Error("cut_rows: a cut of " + std::to_string(cuts[i].size()) + " nodes in a row of " + std::to_string(row));
    for (std::size_t j = 0; j < cuts[i].size(); ++j) rows.boxes[i * row + j] = to_rs_box(node_box(bvh.nodes[cuts[i][j]]));
    rows.counts.push_back(static_cast<rs_u32>(cuts[i].size()));
    // Row i: its counts[i] boxes, then zero groups up to `row`. The kernels test the whole row and
    // keep the bits of its first counts[i] boxes (cl/keys_cut.h, rs_row_kept).
    auto groups = rs_cut_groups(rows.boxes.data() + i * row, cuts[i].size());
    groups.resize(rs_cut_group_count(row), RsCutGroup{});
    rows.groups.insert(rows.groups.end(), groups.begin(), groups.end());
  }
  return rows;
}

TwoLevelTables two_level_tables(const Bvh& bvh, const TwoLevelCut& cut, unsigned row) {
  TwoLevelTables t;
  for (std::uint32_t n : cut.top) t.top.push_back(to_rs_box(node_box(bvh.nodes[n])));
  t.top_groups = rs_cut_groups(t.top.data(), t.top.size());
  CutRows low = cut_rows(bvh, cut.low, row);
  t.low = std::move(low.boxes);
  t.low_groups = std::move(low.groups);
  t.low_count = std::move(low.counts);
  if (t.low_count.empty()) {  // no top node: keys read row 0 (and keep none of its bits), so there is one
    t.low_count.push_back(0);
    t.low_groups.resize(rs_cut_group_count(row), RsCutGroup{});
  }
  return t;
}

}  // namespace raysort
