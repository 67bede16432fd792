// The compressed 8-wide BVH (host/bvh/cwbvh.cpp, cl/bvh_layout.h RsCwbvhNode): every triangle kept,
// every dequantised box containing what lies below it (the validator), the validator catching a
// broken tree, and the node memory the issue bounds (at most 45 % of the 4-wide nodes').
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "bvh/bvh.h"
#include "scene/load.h"
#include "test_util.h"

namespace raysort {

namespace {

// Children per node, and node bytes against the 4-wide tree's nodes (and leaf packets).
struct CwbvhFigures {
  double children_per_node, node_share, total_share;
};

CwbvhFigures figures_of(const std::string& name, const Bvh& bvh, const CwBvh& cw) {
  std::size_t children = 0;
  for (const RsCwbvhNode& n : cw.nodes)
    for (int s = 0; s < 8; ++s) children += ((n.imask >> s) & 1) || n.meta[s];
  const double node_bytes = double(cw.nodes.size() * sizeof(RsCwbvhNode));
  const double wide_nodes = double(bvh.wide.nodes.size() * sizeof(RsWideNode));
  const double wide_all = wide_nodes + double(bvh.wide.packets.size() * sizeof(RsTriPacket));
  const double all = node_bytes + double(cw.triangles.size() * sizeof(RsTriangle));
  const CwbvhFigures f{double(children) / double(cw.nodes.size()), node_bytes / wide_nodes, all / wide_all};
  std::printf("[ cwbvh    ] %-14s %zu nodes of 80 B (4-wide: %zu of 128 B), depth %u (binary %u), %.2f children per "
              "node; node bytes %.1f %% of the 4-wide nodes', nodes and triangles %.1f %% of the 4-wide nodes and packets\n",
              name.c_str(), cw.nodes.size(), bvh.wide.nodes.size(), cw.depth, bvh.depth, f.children_per_node,
              100.0 * f.node_share, 100.0 * f.total_share);
  return f;
}

}  // namespace

class ProceduralCwbvh : public ::testing::TestWithParam<std::string> {};

TEST_P(ProceduralCwbvh, CollapseKeepsEveryTriangleInsideItsBoxes) {
  Scene::Flat tris = load_scene(GetParam()).flatten();
  Bvh bvh = build_bvh(tris);
  const CwBvh cw = collapse_to_cwbvh(bvh);
  EXPECT_EQ(validate_cwbvh(cw, bvh), "");
  EXPECT_EQ(cw.triangles.size(), tris.v0.size());
  const CwbvhFigures f = figures_of(GetParam(), bvh, cw);
  if (GetParam() != "cornell") {
    EXPECT_GT(f.children_per_node, 4.0) << "the greedy fill should use more than half the slots";
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ProceduralCwbvh, ::testing::Values("cornell", "detail-room", "landscape", "multi-instance"));

// Issue 46: CWBVH node memory at most 45 % of the 4-wide layout's, on the paper's two scenes here.
TEST(Cwbvh, NodeMemoryOnSibenikAndBreakfastRoom) {
  RAYSORT_REQUIRE_REAL_SCENES();
  for (const char* name : {"sibenik", "breakfast_room"}) {
    Scene::Flat tris = load_scene(name).flatten();
    Bvh bvh = build_bvh(tris);
    const CwBvh cw = collapse_to_cwbvh(bvh);
    ASSERT_EQ(validate_cwbvh(cw, bvh), "") << name;
    EXPECT_LE(figures_of(name, bvh, cw).node_share, 0.45) << name;
  }
}

TEST(Cwbvh, OneTriangleAndEmptyTrees) {
  Scene::Flat triangle;
  triangle.v0 = {Vec3{0, 0, 0}}, triangle.v1 = {Vec3{1, 0, 0}}, triangle.v2 = {Vec3{0, 1, 0}}, triangle.material = {0};
  Bvh one = build_bvh(triangle);
  const CwBvh cw = collapse_to_cwbvh(one);
  EXPECT_EQ(validate_cwbvh(cw, one), "");
  ASSERT_EQ(cw.nodes.size(), 1u);
  EXPECT_EQ(cw.nodes[0].imask, 0);
  int leaves = 0;
  for (int s = 0; s < 8; ++s) leaves += cw.nodes[0].meta[s] != 0;
  EXPECT_EQ(leaves, 1);

  Bvh none;
  none.nodes.push_back({});
  const CwBvh empty = collapse_to_cwbvh(none);
  ASSERT_EQ(empty.nodes.size(), 1u);
  EXPECT_EQ(empty.nodes[0].imask, 0);
  for (int s = 0; s < 8; ++s) EXPECT_EQ(empty.nodes[0].meta[s], 0);
}

TEST(Cwbvh, ValidatorCatchesABrokenCollapse) {
  Scene::Flat tris = load_scene("detail-room").flatten();
  Bvh bvh = build_bvh(tris);
  const CwBvh good = collapse_to_cwbvh(bvh);
  ASSERT_EQ(validate_cwbvh(good, bvh), "");
  // A leaf whose box shrinks to its lower bound on x: its triangles stick out.
  CwBvh broken = good;
  bool shrunk = false;
  for (RsCwbvhNode& n : broken.nodes)
    for (int s = 0; s < 8 && !shrunk; ++s)
      if (!((n.imask >> s) & 1) && n.meta[s] && n.q_hi_x[s] > n.q_lo_x[s]) n.q_hi_x[s] = n.q_lo_x[s], shrunk = true;
  ASSERT_TRUE(shrunk);
  EXPECT_NE(validate_cwbvh(broken, bvh), "");
  // An inner child's box shrunk on the low side past the triangles below it.
  broken = good;
  shrunk = false;
  for (RsCwbvhNode& n : broken.nodes)
    for (int s = 0; s < 8 && !shrunk; ++s)
      if (((n.imask >> s) & 1) && n.q_hi_y[s] > n.q_lo_y[s]) n.q_lo_y[s] = n.q_hi_y[s], shrunk = true;
  ASSERT_TRUE(shrunk);
  EXPECT_NE(validate_cwbvh(broken, bvh), "");
  // A leaf that loses its last triangle.
  broken = good;
  bool dropped = false;
  for (RsCwbvhNode& n : broken.nodes)
    for (int s = 0; s < 8 && !dropped; ++s)
      if (!((n.imask >> s) & 1) && (n.meta[s] >> 5) >= 2) n.meta[s] = static_cast<rs_u8>(n.meta[s] - 32), dropped = true;
  ASSERT_TRUE(dropped);
  EXPECT_NE(validate_cwbvh(broken, bvh), "");
  // A vertex not copied exactly.
  broken = good;
  broken.triangles[0].v1[0] += 1.0f;
  EXPECT_NE(validate_cwbvh(broken, bvh), "");
  // Past the stack bound.
  broken = good;
  broken.depth = RS_CWBVH_STACK_SIZE;
  EXPECT_NE(validate_cwbvh(broken, bvh), "");
}

}  // namespace raysort
