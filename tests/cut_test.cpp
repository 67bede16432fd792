// HAD (Eq. 1), the HCC cut (Alg. 2), the MLHCC two-level cut (Alg. 3) and the regular grid:
// hand-checked on a small hand-made BVH, invariants on procedural scenes.
#include <gtest/gtest.h>

#include <algorithm>

#include "bvh/bvh.h"
#include "bvh/cut.h"
#include "bvh/had.h"
#include "scene/load.h"

namespace raysort {

namespace {

RsBvhNode node(float x0, float y0, float z0, float x1, float y1, float z1, rs_u32 first, rs_u32 count) {
  RsBvhNode n{};
  n.bmin[0] = x0, n.bmin[1] = y0, n.bmin[2] = z0, n.first = first;
  n.bmax[0] = x1, n.bmax[1] = y1, n.bmax[2] = z1, n.count = count;
  return n;
}

// Root 0 → (1, 2); 1 → leaves (3, 4); 2 → leaves (5, 6). Leaf boxes are flat (z extent 0).
// Leaf areas .32 .18 .08 .02 (one triangle each); node 1 area .98, node 2 .46, root 2.46.
Bvh four_leaf_bvh() {
  Bvh b;
  b.nodes = {node(0, 0, .1f, .9f, .8f, .4f, 1, 0),   node(0, 0, .1f, .9f, .4f, .2f, 3, 0),
             node(0, .6f, .3f, .7f, .8f, .4f, 5, 0), node(0, 0, .1f, .4f, .4f, .1f, 0, 1),
             node(.6f, 0, .2f, .9f, .3f, .2f, 1, 1), node(0, .6f, .3f, .2f, .8f, .3f, 2, 1),
             node(.6f, .6f, .4f, .7f, .7f, .4f, 3, 1)};
  b.leaf_count = 4;
  b.depth = 2;
  return b;
}

bool descending_had(const std::vector<std::uint32_t>& cut, const std::vector<double>& had) {
  for (std::size_t i = 1; i < cut.size(); ++i)
    if (had[cut[i - 1]] < had[cut[i]]) return false;
  return true;
}

bool is_ancestor(const Bvh& bvh, std::uint32_t a, std::uint32_t b) {
  // Is a an ancestor of (or equal to) b?
  std::vector<std::uint32_t> stack{a};
  while (!stack.empty()) {
    auto k = stack.back();
    stack.pop_back();
    if (k == b) return true;
    if (!bvh.is_leaf(k)) {
      stack.push_back(bvh.nodes[k].first);
      stack.push_back(bvh.nodes[k].first + 1);
    }
  }
  return false;
}

}  // namespace

TEST(Had, MatchesEquationOneByHand) {
  Bvh bvh = four_leaf_bvh();
  auto had = hierarchically_accumulated_density(bvh, 0.125);
  EXPECT_NEAR(had[3], 0.32, 1e-6);
  EXPECT_NEAR(had[4], 0.18, 1e-6);
  EXPECT_NEAR(had[5], 0.08, 1e-6);
  EXPECT_NEAR(had[6], 0.02, 1e-6);
  EXPECT_NEAR(had[1], 0.5 + 0.125 * 0.98, 1e-6);
  EXPECT_NEAR(had[2], 0.1 + 0.125 * 0.46, 1e-6);
  EXPECT_NEAR(had[0], 0.6225 + 0.1575 + 0.125 * 2.46, 1e-6);
  auto leaves = subtree_leaf_counts(bvh);
  EXPECT_EQ(leaves, (std::vector<std::uint32_t>{4, 2, 2, 1, 1, 1, 1}));
  // Triangle count multiplies a leaf's area.
  bvh.nodes[3].count = 3;
  EXPECT_NEAR(hierarchically_accumulated_density(bvh)[3], 0.96, 1e-6);
}

TEST(Cut, HandCheckedHierarchyCut) {
  Bvh bvh = four_leaf_bvh();
  auto had = hierarchically_accumulated_density(bvh);
  EXPECT_EQ(hierarchy_cut(bvh, had, 1), (std::vector<std::uint32_t>{0}));
  EXPECT_EQ(hierarchy_cut(bvh, had, 2), (std::vector<std::uint32_t>{1, 2}));
  // Pop 1 (HAD .6225): queue {3 (.32), 4 (.18), 2 (.1575)}, in HAD order.
  EXPECT_EQ(hierarchy_cut(bvh, had, 3), (std::vector<std::uint32_t>{3, 4, 2}));
  // Size 4: the leaves 3 and 4 are popped (Alg. 2's leaf case, the target shrinks), then 2 splits.
  EXPECT_EQ(hierarchy_cut(bvh, had, 4), (std::vector<std::uint32_t>{3, 4, 5, 6}));
  // More than the tree has: every leaf, once.
  EXPECT_EQ(hierarchy_cut(bvh, had, 64), (std::vector<std::uint32_t>{3, 4, 5, 6}));
  EXPECT_TRUE(hierarchy_cut(bvh, had, 0).empty());
  // Under a subtree root.
  EXPECT_EQ(hierarchy_cut(bvh, had, 8, 2), (std::vector<std::uint32_t>{5, 6}));
  for (unsigned n = 1; n <= 6; ++n) EXPECT_EQ(validate_cut(bvh, hierarchy_cut(bvh, had, n)), "") << n;
}

TEST(Cut, ValidateCutRejectsNonCuts) {
  Bvh bvh = four_leaf_bvh();
  EXPECT_EQ(validate_cut(bvh, {1, 5, 6}), "");
  EXPECT_NE(validate_cut(bvh, {1, 5}), "");     // leaf 6 not covered
  EXPECT_NE(validate_cut(bvh, {1, 3, 2}), "");  // 3 below 1
  EXPECT_NE(validate_cut(bvh, {1, 1, 2}), "");  // twice
  EXPECT_NE(validate_cut(bvh, {1, 2, 9}), "");  // not a node
}

TEST(Cut, HandCheckedTwoLevelCut) {
  Bvh bvh = four_leaf_bvh();
  auto had = hierarchically_accumulated_density(bvh);
  // half = 2: the root's children have 2 leaves each, so both qualify; each splits into 2 leaves.
  TwoLevelCut t = two_level_cut(bvh, had, 2);
  EXPECT_EQ(t.top, (std::vector<std::uint32_t>{1, 2}));
  ASSERT_EQ(t.low.size(), 2u);
  EXPECT_EQ(t.low[0], (std::vector<std::uint32_t>{3, 4}));
  EXPECT_EQ(t.low[1], (std::vector<std::uint32_t>{5, 6}));
  // half = 3: no child of the root has 3 leaves: the root is the only top node.
  t = two_level_cut(bvh, had, 3);
  EXPECT_EQ(t.top, (std::vector<std::uint32_t>{0}));
  EXPECT_EQ(t.low[0], (std::vector<std::uint32_t>{3, 4, 2}));
  // half = 8 (16-bit keys): fewer leaves than half; the root, and all four leaves below it.
  t = two_level_cut(bvh, had, 8);
  EXPECT_EQ(t.top, (std::vector<std::uint32_t>{0}));
  EXPECT_EQ(t.low[0], (std::vector<std::uint32_t>{3, 4, 5, 6}));
}

TEST(Cut, UnevenTwoLevelSplit) {
  Bvh bvh = four_leaf_bvh();
  auto had = hierarchically_accumulated_density(bvh);
  // The even split is the half form.
  EXPECT_EQ(two_level_cut(bvh, had, 2, 2).top, two_level_cut(bvh, had, 2).top);
  EXPECT_EQ(two_level_cut(bvh, had, 2, 2).low, two_level_cut(bvh, had, 2).low);
  // One top node: the root stays whole, its low cut has three nodes (HCC's cut of 3).
  TwoLevelCut t = two_level_cut(bvh, had, 1, 3);
  EXPECT_EQ(t.top, (std::vector<std::uint32_t>{0}));
  EXPECT_EQ(t.low.at(0), hierarchy_cut(bvh, had, 3, 0));
  // Four top nodes with one low node each: the four leaves, each its own low cut.
  t = two_level_cut(bvh, had, 4, 1);
  ASSERT_EQ(t.top.size(), 4u);
  for (std::size_t i = 0; i < t.top.size(); ++i) EXPECT_EQ(t.low[i], std::vector<std::uint32_t>{t.top[i]});
  // Two top nodes that need three leaves each: no child qualifies, the root is the only top node.
  t = two_level_cut(bvh, had, 2, 3);
  EXPECT_EQ(t.top, (std::vector<std::uint32_t>{0}));
  EXPECT_TRUE(two_level_cut(bvh, had, 0, 3).top.empty());
}

TEST(Cut, SingleLeafBvh) {
  Bvh bvh;
  bvh.nodes = {node(0, 0, 0, 1, 1, 1, 0, 1)};
  bvh.leaf_count = 1;
  auto had = hierarchically_accumulated_density(bvh);
  EXPECT_EQ(hierarchy_cut(bvh, had, 32), std::vector<std::uint32_t>{0});
  EXPECT_EQ(validate_cut(bvh, {0}), "");
  auto t = two_level_cut(bvh, had, 16);
  EXPECT_EQ(t.top, std::vector<std::uint32_t>{0});
  EXPECT_EQ(t.low.at(0), std::vector<std::uint32_t>{0});
}

TEST(Cut, InvariantsOnProceduralScenes) {
  for (const char* name : {"cornell", "detail-room"}) {
    Scene scene = load_scene(name);
    Bvh bvh = build_bvh(scene.flatten());
    auto had = hierarchically_accumulated_density(bvh);
    auto leaves = subtree_leaf_counts(bvh);
    ASSERT_EQ(leaves[0], bvh.leaf_count);
    // HAD grows towards the root: a parent's HAD is at least each child's.
    for (std::size_t k = 0; k < bvh.nodes.size(); ++k)
      if (!bvh.is_leaf(static_cast<std::uint32_t>(k))) {
        EXPECT_GE(had[k], had[bvh.nodes[k].first]);
        EXPECT_GE(had[k], had[bvh.nodes[k].first + 1]);
      }
    for (unsigned b : {1u, 2u, 3u, 8u, 15u, 16u, 31u, 32u, 64u}) {
      auto cut = hierarchy_cut(bvh, had, b);
      EXPECT_EQ(validate_cut(bvh, cut), "") << name << " " << b;
      EXPECT_EQ(cut.size(), std::min<std::size_t>(b, bvh.leaf_count)) << name << " " << b;
      EXPECT_TRUE(descending_had(cut, had)) << name << " " << b;
    }
    for (unsigned half : {8u, 16u, 32u}) {
      TwoLevelCut t = two_level_cut(bvh, had, half);
      ASSERT_FALSE(t.top.empty());
      EXPECT_LE(t.top.size(), half);
      EXPECT_TRUE(descending_had(t.top, had));
      if (bvh.leaf_count < half) {
        // Too small a tree for one full low-level cut: the root is the only top node.
        EXPECT_EQ(t.top, std::vector<std::uint32_t>{0}) << name << " half " << half;
        EXPECT_EQ(t.low.at(0).size(), bvh.leaf_count);
        continue;
      }
      // Top nodes: disjoint subtrees, each big enough for a full low-level cut.
      for (std::size_t i = 0; i < t.top.size(); ++i) {
        EXPECT_GE(leaves[t.top[i]], half) << name << " top " << i;
        for (std::size_t j = 0; j < t.top.size(); ++j) {
          if (i != j) {
            EXPECT_FALSE(is_ancestor(bvh, t.top[i], t.top[j]));
          }
        }
        EXPECT_EQ(t.low[i].size(), half) << name << " top " << i;
        EXPECT_EQ(validate_cut(bvh, t.low[i], t.top[i]), "") << name << " top " << i;
        EXPECT_TRUE(descending_had(t.low[i], had));
      }
      if (bvh.leaf_count >= 4 * half) {
        EXPECT_EQ(t.top.size(), half) << name << " half " << half;
      }
    }
  }
}

TEST(Grid, ShapesAndCells) {
  const Aabb cube{{0, 0, 0}, {1, 1, 1}};
  EXPECT_EQ(regular_grid_shape(cube, 16), (std::array<std::uint32_t, 3>{4, 2, 2}));
  EXPECT_EQ(regular_grid_shape(cube, 32), (std::array<std::uint32_t, 3>{4, 4, 2}));
  EXPECT_EQ(regular_grid_shape(cube, 64), (std::array<std::uint32_t, 3>{4, 4, 4}));
  // The longest axis is split most.
  const Aabb room{{0, 0, 0}, {1, 4, 2}};
  EXPECT_EQ(regular_grid_shape(room, 32), (std::array<std::uint32_t, 3>{2, 8, 2}));
  // A flat axis is never split; non-powers of two use the largest power of two below.
  const Aabb flat{{0, 0, 5}, {2, 1, 5}};
  EXPECT_EQ(regular_grid_shape(flat, 32), (std::array<std::uint32_t, 3>{8, 4, 1}));
  EXPECT_EQ(regular_grid_cells(cube, 24).size(), 16u);
  // Cells tile the box: volumes add up, outer faces are the box's, neighbours share boundaries.
  const Aabb box{{-1.5f, 0.25f, 3}, {2.5f, 1.75f, 3.5f}};
  auto cells = regular_grid_cells(box, 32);
  ASSERT_EQ(cells.size(), 32u);
  double volume = 0;
  for (const auto& c : cells) {
    auto e = c.extent();
    volume += double(e[0]) * e[1] * e[2];
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(c.min[a], box.min[a]);
      EXPECT_LE(c.max[a], box.max[a]);
    }
  }
  auto e = box.extent();
  EXPECT_NEAR(volume, double(e[0]) * e[1] * e[2], 1e-5);
  // 8 × 4 × 1 cells; the most split axis (x) varies slowest, then y.
  EXPECT_EQ(regular_grid_shape(box, 32), (std::array<std::uint32_t, 3>{8, 4, 1}));
  EXPECT_EQ(cells[0].min[0], box.min[0]);
  EXPECT_EQ(cells[31].max[0], box.max[0]);
  EXPECT_EQ(cells[0].max[1], cells[1].min[1]);
  EXPECT_EQ(cells[0].max[0], cells[4].min[0]);
}

}  // namespace raysort
