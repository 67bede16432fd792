// BVH invariants: every triangle in exactly one leaf, child boxes inside parents, bounded leaves
// and depth, on every procedural scene and on degenerate inputs.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>

#include <cstring>

#include "bvh/bvh.h"
#include "scene/load.h"

namespace raysort {

namespace {
Scene::Flat flat_from(const std::vector<std::array<Vec3, 3>>& tris) {
  Scene::Flat f;
  for (auto& t : tris) {
    f.v0.push_back(t[0]);
    f.v1.push_back(t[1]);
    f.v2.push_back(t[2]);
    f.material.push_back(0);
  }
  return f;
}
}  // namespace

class ProceduralBvh : public ::testing::TestWithParam<std::string> {};

TEST_P(ProceduralBvh, Invariants) {
  Scene scene = load_scene(GetParam());
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  EXPECT_EQ(validate_bvh(bvh, tris.size()), "");
  EXPECT_LT(bvh.depth, static_cast<std::uint32_t>(RS_STACK_SIZE));
  // The root box is the scene's box.
  Aabb a = bvh.bounds(), b = scene.bounds();
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(a.min[i], b.min[i]);
    EXPECT_EQ(a.max[i], b.max[i]);
  }
}

INSTANTIATE_TEST_SUITE_P(AllProcedural, ProceduralBvh,
                         ::testing::Values("cornell", "detail-room", "landscape", "multi-instance"));

TEST(Bvh, SingleTriangleIsOneLeaf) {
  auto f = flat_from({{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}}});
  Bvh bvh = build_bvh(f);
  EXPECT_EQ(bvh.nodes.size(), 1u);
  EXPECT_EQ(bvh.nodes[0].count, 1u);
  EXPECT_EQ(validate_bvh(bvh, 1), "");
}

TEST(Bvh, IdenticalTrianglesStillSplitToBoundedLeaves) {
  // All centroids equal: no SAH split exists; the builder must fall back to median splits.
  std::vector<std::array<Vec3, 3>> tris(1000, {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}});
  Bvh bvh = build_bvh(flat_from(tris));
  EXPECT_EQ(validate_bvh(bvh, tris.size()), "");
}

TEST(Bvh, FlatSceneAndDegenerateTriangles) {
  std::vector<std::array<Vec3, 3>> tris;
  for (int i = 0; i < 500; ++i) {
    float x = static_cast<float>(i % 25), y = static_cast<float>(i / 25);
    tris.push_back({Vec3{x, y, 0}, Vec3{x + 1, y, 0}, Vec3{x, y + 1, 0}});  // all in z = 0
  }
  tris.push_back({Vec3{3, 3, 0}, Vec3{3, 3, 0}, Vec3{3, 3, 0}});  // a point
  tris.push_back({Vec3{0, 0, 0}, Vec3{1, 1, 0}, Vec3{2, 2, 0}});  // collinear
  Bvh bvh = build_bvh(flat_from(tris));
  EXPECT_EQ(validate_bvh(bvh, tris.size()), "");
  EXPECT_EQ(bvh.bounds().extent()[2], 0.0f);
}

TEST(Bvh, ValidatorCatchesABrokenTree) {
  auto f = flat_from({{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}}, {Vec3{5, 0, 0}, Vec3{6, 0, 0}, Vec3{5, 1, 0}}});
  Bvh bvh = build_bvh(f);
  ASSERT_EQ(validate_bvh(bvh, 2), "");
  Bvh broken = bvh;
  broken.nodes[1].bmax[0] += 100.0f;  // child pokes out of its parent
  EXPECT_NE(validate_bvh(broken, 2), "");
  broken = bvh;
  broken.triangles[1].id = broken.triangles[0].id;  // a triangle in two leaves, one missing
  EXPECT_NE(validate_bvh(broken, 2), "");
}

TEST(Bvh, Deterministic) {
  Scene scene = load_scene("cornell");
  auto f = scene.flatten();
  Bvh a = build_bvh(f), b = build_bvh(f);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  EXPECT_EQ(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(RsBvhNode)), 0);
}

}  // namespace raysort

// The 4-wide tree the trace kernels walk (host/bvh/wide.cpp): same leaves and boxes, bounded stack.
namespace raysort {

class ProceduralWideBvh : public ::testing::TestWithParam<std::string> {};

TEST_P(ProceduralWideBvh, CollapseKeepsEveryTriangleAndBox) {
  Scene::Flat tris = load_scene(GetParam()).flatten();
  Bvh bvh = build_bvh(tris);
  EXPECT_EQ(validate_wide(bvh.wide, bvh), "");
  // Two binary levels per wide level: the bound the kernels' stack relies on.
  EXPECT_LE(bvh.wide.depth, (bvh.depth + 1) / 2 + 1);
  EXPECT_LE(3 * bvh.wide.depth, static_cast<std::uint32_t>(RS_WIDE_STACK_SIZE));
}

INSTANTIATE_TEST_SUITE_P(Scenes, ProceduralWideBvh,
                         ::testing::Values("cornell", "detail-room", "landscape", "multi-instance"));

TEST(WideBvh, OneLeafAndEmptyTrees) {
  Bvh one = build_bvh(flat_from({{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}}));
  ASSERT_TRUE(one.is_leaf(0));
  EXPECT_EQ(validate_wide(one.wide, one), "");
  EXPECT_EQ(one.wide.nodes.size(), 1u);
  EXPECT_EQ(one.wide.nodes[0].valid.s[0], -1);
  EXPECT_EQ(one.wide.nodes[0].valid.s[1], 0);

  Bvh none;  // build_bvh refuses an empty scene; the collapse still gives a root that misses
  none.nodes.push_back({});
  none.wide = collapse_to_wide(none);
  ASSERT_EQ(none.wide.nodes.size(), 1u);
  for (int lane = 0; lane < 4; ++lane) EXPECT_EQ(none.wide.nodes[0].valid.s[lane], 0);
}

// A binary subtree of at most four triangles becomes one wide leaf (one full packet) when its box's
// surface area is at most the sum of its leaves' (host/bvh/wide.cpp, leafish): an inner wide lane
// over four triangles or fewer only remains where merging would grow the area, and merging happens.
TEST(WideBvh, SmallSubtreesBecomeOnePacketWhereSahAgrees) {
  for (const char* name : {"cornell", "detail-room"}) {
    Scene::Flat tris = load_scene(name).flatten();
    Bvh bvh = build_bvh(tris);
    ASSERT_EQ(validate_wide(bvh.wide, bvh), "") << name;
    auto area = [](const RsWideNode& w, int lane) {
      const double dx = double(w.hi_x.s[lane]) - w.lo_x.s[lane], dy = double(w.hi_y.s[lane]) - w.lo_y.s[lane],
                   dz = double(w.hi_z.s[lane]) - w.lo_z.s[lane];
      return 2.0 * (dx * dy + dy * dz + dz * dx);
    };
    // (triangles, summed area of the leaf lanes) below an inner wide node.
    std::function<std::pair<std::uint32_t, double>(std::uint32_t)> below = [&](std::uint32_t node) {
      std::pair<std::uint32_t, double> sum{0u, 0.0};
      const RsWideNode& w = bvh.wide.nodes[node];
      for (int lane = 0; lane < 4; ++lane) {
        if (!w.valid.s[lane]) continue;
        const std::uint32_t ref = w.child[lane];
        if (ref & RS_WIDE_LEAF) {
          const std::uint32_t first = (ref & ~RS_WIDE_LEAF) >> 2, end = first + (ref & 3u) + 1u;
          for (std::uint32_t p = first; p < end; ++p)
            for (int k = 0; k < 4; ++k) sum.first += bvh.wide.packets[p].valid.s[k] != 0;
          sum.second += area(w, lane);
        } else {
          auto [n, a] = below(ref);
          sum.first += n, sum.second += a;
        }
      }
      return sum;
    };
    std::size_t small_inner = 0;
    for (const RsWideNode& w : bvh.wide.nodes)
      for (int lane = 0; lane < 4; ++lane)
        if (w.valid.s[lane] && !(w.child[lane] & RS_WIDE_LEAF)) {
          auto [n, leaf_area] = below(w.child[lane]);
          if (n > 4) continue;
          ++small_inner;
          // Kept apart only when one box over all would be larger (within float rounding).
          EXPECT_GT(area(w, lane), leaf_area * (1.0 - 1e-6)) << name;
        }
    EXPECT_EQ(below(0).first, tris.v0.size()) << name;
    EXPECT_LT(bvh.wide.packets.size(), bvh.leaf_count) << name << ": no small subtree was merged";
    std::printf("[ wide     ] %-12s %zu packets for %u binary leaves; %zu small subtrees kept apart\n", name,
                bvh.wide.packets.size(), bvh.leaf_count, small_inner);
  }
}

TEST(WideBvh, ValidatorCatchesABrokenCollapse) {
  Scene::Flat tris = load_scene("cornell").flatten();
  Bvh bvh = build_bvh(tris);
  WideBvh broken = bvh.wide;
  for (auto& pk : broken.packets)
    if (pk.valid.s[0]) {
      pk.valid.s[0] = 0;  // drop one triangle
      break;
    }
  EXPECT_NE(validate_wide(broken, bvh), "");
  broken = bvh.wide;
  broken.nodes[0].lo_x.s[0] = broken.nodes[0].hi_x.s[0];  // a box too small for what it holds
  EXPECT_NE(validate_wide(broken, bvh), "");
  broken = bvh.wide;
  broken.depth = RS_WIDE_STACK_SIZE;  // past the stack bound
  EXPECT_NE(validate_wide(broken, bvh), "");
}

}  // namespace raysort

// The 8-wide tree of the wide8 trace class (host/bvh/wide8.cpp): every triangle in exactly one
// packet lane, every child box inside its parent's lane and equal to a binary node's box (the
// validator), inner children at least three binary levels down (the stack bound), and the lanes
// mostly used.
namespace raysort {

class ProceduralWide8Bvh : public ::testing::TestWithParam<std::string> {};

TEST_P(ProceduralWide8Bvh, CollapseKeepsEveryTriangleAndBox) {
  Scene::Flat tris = load_scene(GetParam()).flatten();
  Bvh bvh = build_bvh(tris);
  const Wide8Bvh w = collapse_to_wide8(bvh);
  EXPECT_EQ(validate_wide8(w, bvh), "");
  // Three binary levels per wide level at least: the bound the kernels' stack relies on.
  EXPECT_LE(w.depth, (bvh.depth + 2) / 3 + 1);
  EXPECT_LE(7 * w.depth, static_cast<std::uint32_t>(RS_WIDE8_STACK_SIZE));
  std::size_t lanes = 0, tri_lanes = 0;
  for (const RsWide8Node& n : w.nodes)
    for (int k = 0; k < 8; ++k) lanes += n.valid.s[k] != 0;
  for (const RsTriPacket8& p : w.packets)
    for (int k = 0; k < 8; ++k) tri_lanes += p.valid.s[k] != 0;
  EXPECT_EQ(tri_lanes, tris.v0.size());
  const double per_node = double(lanes) / double(w.nodes.size()), per_packet = double(tri_lanes) / double(w.packets.size());
  std::printf("[ wide8    ] %-14s %zu nodes (4-wide: %zu), depth %u (4-wide %u, binary %u), %.2f children per node, "
              "%.2f triangles per packet\n",
              GetParam().c_str(), w.nodes.size(), bvh.wide.nodes.size(), w.depth, bvh.wide.depth, bvh.depth, per_node,
              per_packet);
  EXPECT_GT(per_node, 4.0) << "the greedy fill should use more than half of the lanes";
}

INSTANTIATE_TEST_SUITE_P(Scenes, ProceduralWide8Bvh,
                         ::testing::Values("cornell", "detail-room", "landscape", "multi-instance"));

TEST(Wide8Bvh, OneLeafAndEmptyTrees) {
  Bvh one = build_bvh(flat_from({{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}}));
  const Wide8Bvh w = collapse_to_wide8(one);
  EXPECT_EQ(validate_wide8(w, one), "");
  ASSERT_EQ(w.nodes.size(), 1u);
  EXPECT_EQ(w.nodes[0].valid.s[0], -1);
  for (int lane = 1; lane < 8; ++lane) EXPECT_EQ(w.nodes[0].valid.s[lane], 0);

  Bvh none;
  none.nodes.push_back({});
  const Wide8Bvh empty = collapse_to_wide8(none);
  ASSERT_EQ(empty.nodes.size(), 1u);
  for (int lane = 0; lane < 8; ++lane) EXPECT_EQ(empty.nodes[0].valid.s[lane], 0);
}

TEST(Wide8Bvh, ValidatorCatchesABrokenCollapse) {
  Scene::Flat tris = load_scene("detail-room").flatten();  // cornell's 8-wide tree is one node
  Bvh bvh = build_bvh(tris);
  const Wide8Bvh good = collapse_to_wide8(bvh);
  ASSERT_EQ(validate_wide8(good, bvh), "");
  Wide8Bvh broken = good;
  for (auto& pk : broken.packets)
    if (pk.valid.s[0]) {
      pk.valid.s[0] = 0;  // drop one triangle
      break;
    }
  EXPECT_NE(validate_wide8(broken, bvh), "");
  broken = good;
  int inner = -1;
  for (int lane = 0; lane < 8 && inner < 0; ++lane)
    if (good.nodes[0].valid.s[lane] && !(good.nodes[0].child[lane] & RS_WIDE_LEAF)) inner = lane;
  ASSERT_GE(inner, 0);
  broken.nodes[0].lo_x.s[inner] = broken.nodes[0].hi_x.s[inner];  // a box too small for its child node
  EXPECT_NE(validate_wide8(broken, bvh), "");
  broken = good;
  for (RsWide8Node& n : broken.nodes)  // a leaf box that is no binary node's box
    if (n.valid.s[0] && (n.child[0] & RS_WIDE_LEAF)) {
      n.hi_y.s[0] += 1.0f;
      break;
    }
  EXPECT_NE(validate_wide8(broken, bvh), "");
  broken = good;
  broken.depth = RS_WIDE8_STACK_SIZE;  // past the stack bound
  EXPECT_NE(validate_wide8(broken, bvh), "");
  broken = good;
  broken.packets[0].v1x.s[0] += 1.0f;  // a vertex not copied exactly
  EXPECT_NE(validate_wide8(broken, bvh), "");
}

}  // namespace raysort
