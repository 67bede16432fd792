// BVH invariants: every triangle in exactly one leaf, child boxes inside parents, bounded leaves
// and depth, on every procedural scene and on degenerate inputs.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>

#include <algorithm>
#include <array>
#include <cstring>
#include <string>
#include <utility>

#include "bvh/bvh.h"
#include "bvh/had.h"
#include "scene/load.h"
#include "test_util.h"

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
          const std::uint32_t first = RS_WIDE_LEAF_FIRST(ref), end = RS_WIDE_LEAF_END(ref);
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

// A node's small leaves share packets (host/bvh/wide_tree.h, plan_leaves; RS_WIDE8_LEAF_*): each leaf
// of up to eight triangles is the lanes of its triangles in one packet of its node's, first fit in
// slot order, so no packet of a node could have taken a leaf that opened a later one; fewer packets
// than leaves, and more triangles per packet than a packet per leaf gave.
TEST_P(ProceduralWide8Bvh, SmallLeavesOfANodeSharePackets) {
  const Bvh bvh = build_bvh(load_scene(GetParam()).flatten());
  const Wide8Bvh w = collapse_to_wide8(bvh);
  ASSERT_EQ(validate_wide8(w, bvh), "");
  std::size_t leaves = 0, shared = 0;
  for (std::size_t i = 0; i < w.nodes.size(); ++i) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> used;  // (packet, lanes taken so far), in the order opened
    for (int lane = 0; lane < 8; ++lane) {
      const std::uint32_t ref = w.nodes[i].child[lane];
      if (!w.nodes[i].valid.s[lane] || !(ref & RS_WIDE_LEAF)) continue;
      ++leaves;
      const std::uint32_t first = RS_WIDE8_LEAF_FIRST(ref), at = RS_WIDE8_LEAF_LANE(ref), count = RS_WIDE8_LEAF_LANE_COUNT(ref);
      if (RS_WIDE8_LEAF_COUNT(ref) > 1) continue;  // a large leaf has packets of its own
      auto it = std::find_if(used.begin(), used.end(), [&](const auto& u) { return u.first == first; });
      for (auto f = used.begin(); f != it; ++f)
        EXPECT_GT(f->second + count, 8u) << GetParam() << " node " << i << " lane " << lane
                                         << ": an earlier packet of the node had room (first fit)";
      if (it == used.end()) {
        EXPECT_EQ(at, 0u) << GetParam() << " node " << i << " lane " << lane << ": a new packet starts at lane 0";
        used.push_back({first, count});
      } else {
        EXPECT_EQ(at, it->second) << GetParam() << " node " << i << " lane " << lane << ": right after the last leaf";
        it->second += count;
        ++shared;
      }
    }
  }
  std::size_t tri_lanes = 0;
  for (const RsTriPacket8& p : w.packets)
    for (int k = 0; k < 8; ++k) tri_lanes += p.valid.s[k] != 0;
  std::printf("[ wide8    ] %-14s %zu leaves in %zu packets (%zu leaves in a packet opened before them), "
              "%.2f triangles per packet\n",
              GetParam().c_str(), leaves, w.packets.size(), shared, double(tri_lanes) / double(w.packets.size()));
  EXPECT_EQ(leaves, w.packets.size() + shared) << "every other leaf opened one packet";
  if (w.nodes.size() > 1) {
    EXPECT_GT(shared, 0u) << GetParam();
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ProceduralWide8Bvh,
                         ::testing::Values("cornell", "detail-room", "landscape", "multi-instance"));

// The lanes of every 8-wide node hold its children largest box first (host/bvh/wide8.cpp): the
// order an any-hit walk takes them in, so that a shadow ray meets its likeliest occluder soonest.
TEST_P(ProceduralWide8Bvh, ChildrenLargestBoxFirst) {
  const Bvh bvh = build_bvh(load_scene(GetParam()).flatten());
  const Wide8Bvh w = collapse_to_wide8(bvh);
  auto area = [](const RsWide8Node& n, int lane) {
    RsBvhNode box{};
    box.bmin[0] = n.lo_x.s[lane], box.bmin[1] = n.lo_y.s[lane], box.bmin[2] = n.lo_z.s[lane];
    box.bmax[0] = n.hi_x.s[lane], box.bmax[1] = n.hi_y.s[lane], box.bmax[2] = n.hi_z.s[lane];
    return node_surface_area(box);
  };
  std::size_t ordered_pairs = 0;
  for (std::size_t i = 0; i < w.nodes.size(); ++i)
    for (int lane = 1; lane < 8 && w.nodes[i].valid.s[lane] != 0; ++lane, ++ordered_pairs)
      ASSERT_GE(area(w.nodes[i], lane - 1), area(w.nodes[i], lane)) << "node " << i << " lane " << lane;
  EXPECT_GT(ordered_pairs, w.nodes.size()) << "nodes with several children";
}

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

// "" when a W-wide tree is laid out depth first, else the first place it is not: node 0 the root,
// each inner child's subtree right after the node's earlier children's, in lane order, and the leaf
// packets in the order the same walk meets them (an 8-wide leaf in a packet its node opened for an
// earlier leaf meets none: RS_WIDE8_LEAF_*). The layout the collapses promise on any number of
// threads (wide_tree::collapse).
template <int W, class Tree>
std::string depth_first_layout(const Tree& t) {
  std::uint64_t next_node = 0, next_packet = 0;
  std::string err;
  auto walk = [&](auto& self, std::uint32_t n) -> void {
    if (n != next_node) {
      err = "node " + std::to_string(n) + " where depth-first order puts node " + std::to_string(next_node);
      return;
    }
    ++next_node;
    std::vector<std::uint32_t> opened;  // the packets this node's leaves opened
    for (int lane = 0; lane < W && err.empty(); ++lane) {
      if (t.nodes[n].valid.s[lane] == 0) continue;
      const std::uint32_t ref = t.nodes[n].child[lane];
      if (!(ref & RS_WIDE_LEAF)) {
        self(self, ref);
        continue;
      }
      const std::uint32_t first = wide_leaf(ref, W == 8).first;
      if (W == 8 && std::find(opened.begin(), opened.end(), first) != opened.end()) continue;
      if (first != next_packet)
        err = "node " + std::to_string(n) + " lane " + std::to_string(lane) + ": packet " + std::to_string(first) +
              " where depth-first order puts packet " + std::to_string(next_packet);
      opened.push_back(first);
      next_packet += (ref & 3u) + 1;
    }
  };
  walk(walk, 0);
  if (err.empty() && (next_node != t.nodes.size() || next_packet != t.packets.size()))
    err = "nodes or packets the walk does not reach";
  return err;
}

// The collapses split their work over threads (wide_tree::collapse): on 1, 2, 3 and 7 threads the
// same bytes, laid out depth first, valid; the build's own 4-wide tree is the same too.
TEST(WideBvh, SameCollapseOnEveryThreadCount) {
  for (const char* name : {"multi-instance", "landscape", "detail-room"}) {
    BvhBuildOptions opts;
    opts.threads = 1;
    const Bvh bvh = build_bvh(load_scene(name).flatten(), opts);
    const WideBvh wide = collapse_to_wide(bvh, 1);
    const Wide8Bvh wide8 = collapse_to_wide8(bvh, 1);
    ASSERT_EQ(validate_wide(wide, bvh), "") << name;
    ASSERT_EQ(validate_wide8(wide8, bvh), "") << name;
    EXPECT_EQ(depth_first_layout<4>(wide), "") << name;
    EXPECT_EQ(depth_first_layout<8>(wide8), "") << name;
    auto same_bytes = [](const auto& x, const auto& y) {
      return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
    };
    EXPECT_TRUE(same_bytes(bvh.wide.nodes, wide.nodes) && same_bytes(bvh.wide.packets, wide.packets)) << name;
    for (unsigned threads : {2u, 3u, 7u}) {
      const WideBvh w = collapse_to_wide(bvh, threads);
      EXPECT_TRUE(same_bytes(w.nodes, wide.nodes) && same_bytes(w.packets, wide.packets) && w.depth == wide.depth)
          << name << ": 4-wide on " << threads << " threads differs from 1 thread's";
      const Wide8Bvh w8 = collapse_to_wide8(bvh, threads);
      EXPECT_TRUE(same_bytes(w8.nodes, wide8.nodes) && same_bytes(w8.packets, wide8.packets) && w8.depth == wide8.depth)
          << name << ": 8-wide on " << threads << " threads differs from 1 thread's";
    }
  }
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
  // Leaves that share a packet (RS_WIDE8_LEAF_*): one naming a lane of its neighbour's, or an empty lane.
  bool overlapped = false, widened = false;
  for (std::size_t i = 0; i < good.nodes.size() && !(overlapped && widened); ++i)
    for (int lane = 0; lane < 8; ++lane) {
      const std::uint32_t ref = good.nodes[i].child[lane];
      if (!good.nodes[i].valid.s[lane] || !(ref & RS_WIDE_LEAF) || RS_WIDE8_LEAF_COUNT(ref) > 1) continue;
      const std::uint32_t at = RS_WIDE8_LEAF_LANE(ref), end = at + RS_WIDE8_LEAF_LANE_COUNT(ref);
      broken = good;
      if (!overlapped && at > 0) {  // one lane earlier: the last lane of the leaf before it
        broken.nodes[i].child[lane] = ref - (1u << 2);
        EXPECT_NE(validate_wide8(broken, bvh), "") << "node " << i << " lane " << lane;
        overlapped = true;
      } else if (!widened && end < 8 && good.packets[RS_WIDE8_LEAF_FIRST(ref)].valid.s[end] == 0) {
        broken.nodes[i].child[lane] = ref + (1u << 5);  // one lane more, an empty one
        EXPECT_NE(validate_wide8(broken, bvh), "") << "node " << i << " lane " << lane;
        widened = true;
      }
    }
  EXPECT_TRUE(overlapped && widened) << "detail-room has leaves after others in a packet, and packets with room";
}

}  // namespace raysort

// The parallel build (host/bvh/build_sah.cpp) against the serial build it replaced: the same
// tree, bit for bit, at any thread count.
namespace raysort {

namespace serial_reference {

// The serial binned SAH build as it was before the build used every core (main e549fcc,
// host/bvh/build_sah.cpp), kept here verbatim but for names: one stack, one index array, one
// thread. The parallel build must give exactly its nodes and triangle order.
struct Box {
  float lo[3] = {3.0e38f, 3.0e38f, 3.0e38f};
  float hi[3] = {-3.0e38f, -3.0e38f, -3.0e38f};
  void grow(const float* p) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  }
  void grow(const Box& b) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], b.lo[a]), hi[a] = std::max(hi[a], b.hi[a]);
  }
  float area() const {
    float e0 = hi[0] - lo[0], e1 = hi[1] - lo[1], e2 = hi[2] - lo[2];
    if (e0 < 0.0f) return 0.0f;
    return 2.0f * (e0 * e1 + e1 * e2 + e2 * e0);
  }
};

struct Tree {
  std::vector<RsBvhNode> nodes;
  std::vector<std::uint32_t> order;  // triangle ids in leaf order
};

Tree build(const Scene::Flat& tris, const BvhBuildOptions& opts = {}) {
  const std::size_t n = tris.size();
  std::vector<Box> boxes(n);
  std::vector<std::array<float, 3>> cent(n);
  for (std::size_t i = 0; i < n; ++i) {
    boxes[i].grow(tris.v0[i].data());
    boxes[i].grow(tris.v1[i].data());
    boxes[i].grow(tris.v2[i].data());
    for (int a = 0; a < 3; ++a) cent[i][a] = (boxes[i].lo[a] + boxes[i].hi[a]) * 0.5f;
  }
  std::vector<std::uint32_t> idx(n);
  for (std::size_t i = 0; i < n; ++i) idx[i] = static_cast<std::uint32_t>(i);
  const std::uint32_t nb = std::max<std::uint32_t>(2, opts.bins);
  struct Task {
    std::uint32_t node, begin, end, depth;
  };
  Tree t;
  t.nodes.push_back({});
  std::vector<Task> stack{{0, 0, static_cast<std::uint32_t>(n), 0}};
  while (!stack.empty()) {
    Task task = stack.back();
    stack.pop_back();
    const std::uint32_t count = task.end - task.begin;
    Box bounds, cb;
    for (std::uint32_t i = task.begin; i < task.end; ++i) bounds.grow(boxes[idx[i]]), cb.grow(cent[idx[i]].data());
    for (int a = 0; a < 3; ++a) t.nodes[task.node].bmin[a] = bounds.lo[a], t.nodes[task.node].bmax[a] = bounds.hi[a];
    auto make_leaf = [&] { t.nodes[task.node].first = task.begin, t.nodes[task.node].count = count; };
    if (count == 1) {
      make_leaf();
      continue;
    }
    int best_axis = -1;
    std::uint32_t best_bin = 0;
    float best_cost = 3.0e38f;
    float scale[3];
    for (int a = 0; a < 3; ++a) scale[a] = cb.hi[a] - cb.lo[a] > 0.0f ? static_cast<float>(nb) / (cb.hi[a] - cb.lo[a]) : 0.0f;
    if (task.depth < 32) {
      std::vector<Box> bin_box(3 * nb);
      std::vector<std::uint32_t> bin_n(3 * nb), right_n(nb);
      std::vector<float> right_area(nb);
      for (std::uint32_t i = task.begin; i < task.end; ++i)
        for (int a = 0; a < 3; ++a) {
          if (scale[a] == 0.0f) continue;
          auto b = std::min(static_cast<std::uint32_t>((cent[idx[i]][a] - cb.lo[a]) * scale[a]), nb - 1);
          bin_box[a * nb + b].grow(boxes[idx[i]]);
          ++bin_n[a * nb + b];
        }
      for (int a = 0; a < 3; ++a) {
        if (scale[a] == 0.0f) continue;
        Box acc, left;
        std::uint32_t acc_n = 0, left_n = 0;
        for (std::uint32_t b = nb - 1; b > 0; --b) {
          acc.grow(bin_box[a * nb + b]);
          acc_n += bin_n[a * nb + b];
          right_area[b] = acc.area();
          right_n[b] = acc_n;
        }
        for (std::uint32_t b = 0; b + 1 < nb; ++b) {
          left.grow(bin_box[a * nb + b]);
          left_n += bin_n[a * nb + b];
          if (left_n == 0 || right_n[b + 1] == 0) continue;
          float cost = left.area() * static_cast<float>(left_n) + right_area[b + 1] * static_cast<float>(right_n[b + 1]);
          if (cost < best_cost) best_axis = a, best_bin = b, best_cost = cost;
        }
      }
    }
    std::uint32_t mid = 0;
    const float parent_area = bounds.area();
    const float leaf_cost = opts.intersection_cost * static_cast<float>(count);
    const float split_cost = best_axis >= 0 && parent_area > 0.0f
                                 ? opts.traversal_cost + opts.intersection_cost * best_cost / parent_area
                                 : 3.0e38f;
    if (best_axis >= 0 && (split_cost < leaf_cost || count > opts.max_leaf_size)) {
      const int a = best_axis;
      auto it = std::partition(idx.begin() + task.begin, idx.begin() + task.end, [&](std::uint32_t x) {
        return std::min(static_cast<std::uint32_t>((cent[x][a] - cb.lo[a]) * scale[a]), nb - 1) <= best_bin;
      });
      mid = static_cast<std::uint32_t>(it - idx.begin());
    } else if (count <= opts.max_leaf_size) {
      make_leaf();
      continue;
    }
    if (mid <= task.begin || mid >= task.end) {
      int axis = 0;
      for (int a = 1; a < 3; ++a)
        if (cb.hi[a] - cb.lo[a] > cb.hi[axis] - cb.lo[axis]) axis = a;
      mid = task.begin + count / 2;
      std::nth_element(idx.begin() + task.begin, idx.begin() + mid, idx.begin() + task.end,
                       [&](std::uint32_t x, std::uint32_t y) {
                         return cent[x][axis] < cent[y][axis] || (cent[x][axis] == cent[y][axis] && x < y);
                       });
    }
    const auto left = static_cast<std::uint32_t>(t.nodes.size());
    t.nodes.push_back({});
    t.nodes.push_back({});
    t.nodes[task.node].first = left;
    t.nodes[task.node].count = 0;
    stack.push_back({left + 1, mid, task.end, task.depth + 1});
    stack.push_back({left, task.begin, mid, task.depth + 1});
  }
  t.order = idx;
  return t;
}

}  // namespace serial_reference

namespace {
std::vector<std::uint32_t> leaf_order(const Bvh& bvh) {
  std::vector<std::uint32_t> ids;
  for (const RsTriangle& t : bvh.triangles) ids.push_back(t.id);
  return ids;
}

// Byte-for-byte equality of two trees: nodes, triangles (vertices, ids, padding), wide nodes and packets.
void expect_same_tree(const Bvh& a, const Bvh& b, const std::string& what) {
  auto same_bytes = [](const auto& x, const auto& y) {
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
  };
  EXPECT_TRUE(same_bytes(a.nodes, b.nodes)) << what << ": nodes differ";
  EXPECT_TRUE(same_bytes(a.triangles, b.triangles)) << what << ": triangles differ";
  EXPECT_TRUE(same_bytes(a.wide.nodes, b.wide.nodes)) << what << ": wide nodes differ";
  EXPECT_TRUE(same_bytes(a.wide.packets, b.wide.packets)) << what << ": wide packets differ";
  EXPECT_EQ(a.depth, b.depth) << what;
  EXPECT_EQ(a.leaf_count, b.leaf_count) << what;
  EXPECT_EQ(a.sah_cost, b.sah_cost) << what;
}

// A scene large enough that 2 and 5 threads split its top levels together (more than 8192
// triangles per thread at the root) and its subtrees are several jobs: `copies` copies of the
// landscape, each moved along x, plus runs of identical triangles that force median splits and a
// wall of signed zeros.
Scene::Flat large_scene(int copies) {
  const Scene landscape = load_scene("landscape");
  const Scene::Flat one = landscape.flatten();
  const float width = landscape.bounds().extent()[0];
  Scene::Flat f;
  for (int c = 0; c < copies; ++c)
    for (std::size_t i = 0; i < one.size(); ++i) {
      const float dx = 1.25f * width * static_cast<float>(c);
      f.v0.push_back({one.v0[i][0] + dx, one.v0[i][1], one.v0[i][2]});
      f.v1.push_back({one.v1[i][0] + dx, one.v1[i][1], one.v1[i][2]});
      f.v2.push_back({one.v2[i][0] + dx, one.v2[i][1], one.v2[i][2]});
      f.material.push_back(0);
    }
  for (int i = 0; i < 3000; ++i) {
    f.v0.push_back({0, 0, 0});
    f.v1.push_back({1, 0, 0});
    f.v2.push_back({0, 1, 0});
    f.material.push_back(0);
  }
  // A wall in the plane x = 0 whose vertices carry +0 and -0 in a scattered pattern: a box's min or
  // max over both zeros is the first one met (std::min keeps the earlier of equals), so the node
  // boxes are only byte-equal if the build meets the triangles in the serial build's order.
  for (int i = 0; i < 4000; ++i) {
    auto zero = [&](int k) { return (i * 7 + k) % 3 == 0 ? -0.0f : 0.0f; };
    const float y = static_cast<float>(i % 64), z = static_cast<float>(i / 64);
    f.v0.push_back({zero(0), y, z});
    f.v1.push_back({zero(1), y + 1, z});
    f.v2.push_back({zero(2), y, z + 1});
    f.material.push_back(0);
  }
  return f;
}
}  // namespace

TEST(BvhThreads, SameTreeOnOneTwoAndFiveThreadsAsTheSerialBuild) {
  for (const auto& [name, tris] : {std::pair<std::string, Scene::Flat>{"multi-instance", load_scene("multi-instance").flatten()},
                                   {"landscape x3 + 3000 equal + a wall of +-0", large_scene(3)}}) {
    ASSERT_GT(tris.size(), 5u * 8192u) << name << " is too small to split its root on 5 threads";
    const serial_reference::Tree ref = serial_reference::build(tris);
    BvhBuildOptions opts;
    opts.threads = 1;
    const Bvh one = build_bvh(tris, opts);
    ASSERT_EQ(validate_bvh(one, tris.size()), "") << name;
    EXPECT_TRUE(one.nodes.size() == ref.nodes.size() &&
                std::memcmp(one.nodes.data(), ref.nodes.data(), ref.nodes.size() * sizeof(RsBvhNode)) == 0)
        << name << ": 1 thread's nodes differ from the serial build's";
    EXPECT_EQ(leaf_order(one), ref.order) << name << ": 1 thread's triangle order differs from the serial build's";
    Bvh serial_bvh;
    serial_bvh.nodes.assign(ref.nodes.begin(), ref.nodes.end());
    EXPECT_EQ(one.sah_cost, sah_cost(serial_bvh)) << name;
    for (unsigned threads : {2u, 5u}) {
      opts.threads = threads;
      expect_same_tree(build_bvh(tris, opts), one, name + " on " + std::to_string(threads) + " threads");
    }
  }
}

// The SAH cost by hand: two unit squares in z = 0 (area 2 each, box faces counted twice over),
// 3 apart in x: root box 4 x 1 x 0, area 8; cost 1 + (1 · 2 + 1 · 2) / 8 = 1.5. (nodes[1] is the
// left leaf: the builder lays the left child out first.)
TEST(BvhThreads, SahCostOfATwoLeafTree) {
  auto f = flat_from({{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{1, 1, 0}}, {Vec3{3, 0, 0}, Vec3{4, 0, 0}, Vec3{4, 1, 0}}});
  BvhBuildOptions opts;
  opts.max_leaf_size = 1;
  Bvh bvh = build_bvh(f, opts);
  ASSERT_EQ(bvh.nodes.size(), 3u);
  EXPECT_DOUBLE_EQ(bvh.sah_cost, 1.5);
  EXPECT_DOUBLE_EQ(sah_cost(bvh, opts), 1.5);
  // By hand, with a leaf of two triangles and other constants: the same root over a leaf of 2
  // (area 2) and one of 1 (area 2), traversal 2, intersection 3: (2 · 8 + 3 · 2 · 2 + 3 · 1 · 2) / 8.
  bvh.nodes[1].count = 2;
  opts.traversal_cost = 2.0f;
  opts.intersection_cost = 3.0f;
  EXPECT_DOUBLE_EQ(sah_cost(bvh, opts), 34.0 / 8.0);
}

// `raysort trace --build-rounds N` (host/app/build_timing.h): the build timed in N rounds, with
// Embree's beside it under --reference embree, the SAH cost on the line, nothing traced; options
// that only a trace uses are refused in one line before any work.
TEST(BvhThreads, TraceBuildRoundsTimesTheBuildsAndStops) {
  using raysort::testing::CliResult;
  using raysort::testing::run_cli;
  CliResult r = run_cli({"trace", "--scene", "cornell", "--build-rounds", "6"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("build    6 rounds alternated, medians with 95 % intervals: ours "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("SAH cost "), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("kernels  built"), std::string::npos) << "nothing is traced:\n" << r.out;
#ifdef RAYSORT_HAVE_EMBREE
  r = run_cli({"trace", "--scene", "cornell", "--build-rounds", "6", "--reference", "embree"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("build quality high, "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("; ours/Embree "), std::string::npos) << r.out;
#endif
  r = run_cli({"trace", "--scene", "cornell", "--build-rounds", "6", "--variant", "both", "--adjudicate"});
  EXPECT_NE(r.code, 0);
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "not one line:\n" << r.err;
  EXPECT_NE(r.err.find("--build-rounds times the BVH builds alone"), std::string::npos) << r.err;
  r = run_cli({"trace", "--scene", "cornell", "--build-rounds", "0"});
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("--build-rounds"), std::string::npos) << r.err;
}

}  // namespace raysort
