// The tree with spatial splits the 8-wide classes walk (host/bvh/build_spatial.cpp, split_tree):
// its invariants, that the parts of every triangle cover it (so no ray can miss a triangle it hits),
// that without a budget it is build_bvh's tree, the same bytes on every thread count, and the SAH
// cost it buys.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "bvh/bvh.h"
#include "scene/load.h"
#include "test_util.h"

namespace raysort {

namespace {

Scene::Flat flat_from(const std::vector<std::array<Vec3, 3>>& tris) {
  Scene::Flat f;
  for (const auto& t : tris) {
    f.v0.push_back(t[0]);
    f.v1.push_back(t[1]);
    f.v2.push_back(t[2]);
    f.material.push_back(0);
  }
  return f;
}

// Long thin triangles crossing a field of small ones: the case spatial splits are for (Stich et al.
// 2009, figure 1): every object split's children overlap along the long triangles.
Scene::Flat crossing_scene(std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 100.0f), s(-0.5f, 0.5f);
  std::vector<std::array<Vec3, 3>> tris;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 c{u(rng), u(rng), u(rng)};
    tris.push_back({c, Vec3{c[0] + s(rng), c[1] + s(rng), c[2]}, Vec3{c[0], c[1] + s(rng), c[2] + s(rng)}});
  }
  for (int i = 0; i < 200; ++i) {
    const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
    tris.push_back({a, b, Vec3{b[0] + 0.3f, b[1], b[2] + 0.2f}});
  }
  return flat_from(tris);
}

// Per triangle id, the boxes of the leaves that reference it.
std::vector<std::vector<RsBvhNode>> leaf_boxes_by_id(const Bvh& split, std::size_t ids) {
  std::vector<std::vector<RsBvhNode>> boxes(ids);
  for (std::uint32_t n = 0; n < split.nodes.size(); ++n)
    if (split.is_leaf(n))
      for (std::uint32_t k = split.nodes[n].first; k < split.nodes[n].first + split.nodes[n].count; ++k)
        boxes[split.triangles[k].id].push_back(split.nodes[n]);
  return boxes;
}

bool inside(const RsBvhNode& box, const long double p[3]) {
  for (int a = 0; a < 3; ++a)
    if (p[a] < box.bmin[a] || p[a] > box.bmax[a]) return false;
  return true;
}

// The first point of a triangle outside the boxes of all its references, or "": its vertices, and
// where each edge crosses each face plane of those boxes (the points clipping computes, in long
// double), and interior points. A reference box that clips a crossing by a rounding step fails here.
std::string uncovered_point(const Bvh& split, std::size_t ids) {
  const auto boxes = leaf_boxes_by_id(split, ids);
  std::vector<bool> done(ids, false);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const RsTriangle& t : split.triangles) {
    if (done[t.id]) continue;
    done[t.id] = true;
    const auto& mine = boxes[t.id];
    if (mine.empty()) return "triangle " + std::to_string(t.id) + " in no leaf";
    auto covered = [&](const long double p[3]) {
      return std::any_of(mine.begin(), mine.end(), [&](const RsBvhNode& b) { return inside(b, p); });
    };
    const float* v[3] = {t.v0, t.v1, t.v2};
    std::vector<std::array<long double, 3>> points;
    for (const float* p : v) points.push_back({p[0], p[1], p[2]});
    for (int e = 0; e < 3; ++e) {
      const float* a = v[e];
      const float* b = v[(e + 1) % 3];
      for (const RsBvhNode& box : mine)
        for (int axis = 0; axis < 3; ++axis)
          for (float plane : {box.bmin[axis], box.bmax[axis]}) {
            if (!((a[axis] < plane && plane < b[axis]) || (b[axis] < plane && plane < a[axis]))) continue;
            const long double s = (static_cast<long double>(plane) - a[axis]) / (static_cast<long double>(b[axis]) - a[axis]);
            std::array<long double, 3> p;
            for (int k = 0; k < 3; ++k) p[k] = k == axis ? plane : a[k] + s * (static_cast<long double>(b[k]) - a[k]);
            points.push_back(p);
          }
    }
    for (int i = 0; i < 16; ++i) {
      double x = u(rng), y = u(rng);
      if (x + y > 1.0) x = 1.0 - x, y = 1.0 - y;
      std::array<long double, 3> p;
      for (int k = 0; k < 3; ++k)
        p[k] = v[0][k] + x * (static_cast<long double>(v[1][k]) - v[0][k]) + y * (static_cast<long double>(v[2][k]) - v[0][k]);
      points.push_back(p);
    }
    for (const auto& p : points)
      if (!covered(p.data()))
        return "a point of triangle " + std::to_string(t.id) + " (" + std::to_string(static_cast<double>(p[0])) + ", " +
               std::to_string(static_cast<double>(p[1])) + ", " + std::to_string(static_cast<double>(p[2])) +
               ") lies in none of its " + std::to_string(mine.size()) + " reference boxes";
  }
  return "";
}

}  // namespace

class ProceduralSpatialBvh : public ::testing::TestWithParam<std::string> {};

// Valid (validate_spatial_bvh, and the 8-wide collapse's validator against it), every triangle
// covered by its parts, and a SAH cost at most 1 % above the plain tree's (the build is greedy: a
// split cheaper at its node can cost more below it; multi-instance: 37.13 -> 37.33).
TEST_P(ProceduralSpatialBvh, ValidCoveredAndNoCostlier) {
  const Scene::Flat tris = GetParam() == "crossing" ? crossing_scene(1) : load_scene(GetParam()).flatten();
  const Bvh plain = build_bvh(tris);
  for (double budget : {kSpatialSplitBudget, 2.0}) {
    SCOPED_TRACE("budget " + std::to_string(budget));
    const Bvh split = build_spatial_bvh(plain, {}, budget);
    ASSERT_EQ(validate_spatial_bvh(split, plain, budget), "");
    EXPECT_EQ(uncovered_point(split, tris.size()), "");
    EXPECT_LE(split.sah_cost, plain.sah_cost * 1.01);
    const Wide8Bvh wide8 = collapse_to_wide8(split);
    EXPECT_EQ(validate_wide8(wide8, split), "");
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ProceduralSpatialBvh,
                         ::testing::Values("cornell", "detail-room", "landscape", "multi-instance", "crossing"));

// Where large triangles cross small ones, splits pay: references added within the budget, SAH cost
// down by a fifth.
TEST(SpatialBvh, SplitsWhereLongTrianglesCrossSmallOnes) {
  const Scene::Flat tris = crossing_scene(2);
  const Bvh plain = build_bvh(tris);
  const Bvh split = build_spatial_bvh(plain);
  EXPECT_GT(split.triangles.size(), tris.size());
  EXPECT_LE(split.triangles.size(), static_cast<std::size_t>(tris.size() * (1.0 + kSpatialSplitBudget)));
  EXPECT_LT(split.sah_cost, 0.8 * plain.sah_cost) << "plain " << plain.sah_cost << ", split " << split.sah_cost;
}

// The validator rejects a reference that is not the plain tree's triangle, a triangle in no leaf,
// and more references than the budget allows.
TEST(SpatialBvh, ValidatorCatchesABrokenTree) {
  const Scene::Flat tris = crossing_scene(3);
  const Bvh plain = build_bvh(tris);
  const Bvh split = build_spatial_bvh(plain);
  ASSERT_EQ(validate_spatial_bvh(split, plain, kSpatialSplitBudget), "");
  Bvh moved = split;
  moved.triangles[0].v0[0] += 1.0f;
  EXPECT_NE(validate_spatial_bvh(moved, plain, kSpatialSplitBudget), "");
  Bvh renamed = split;
  for (RsTriangle& t : renamed.triangles)
    if (t.id == 7) t = plain.triangles[t.id == plain.triangles[0].id ? 1 : 0];  // triangle 7 in no leaf
  EXPECT_NE(validate_spatial_bvh(renamed, plain, kSpatialSplitBudget), "");
  EXPECT_NE(validate_spatial_bvh(split, plain, 0.01), "");
}

// With no references to add, no node splits spatially: the tree is build_bvh's (the same nodes, boxes
// equal, each leaf the same triangles), so the object splits follow build_bvh's rules exactly.
TEST(SpatialBvh, NoBudgetIsThePlainTree) {
  for (const char* name : {"detail-room", "multi-instance"}) {
    const Bvh plain = build_bvh(load_scene(name).flatten());
    const Bvh split = build_spatial_bvh(plain, {}, 0.0);
    ASSERT_EQ(split.nodes.size(), plain.nodes.size()) << name;
    ASSERT_EQ(split.triangles.size(), plain.triangles.size()) << name;
    for (std::size_t n = 0; n < plain.nodes.size(); ++n) {
      const RsBvhNode &a = plain.nodes[n], &b = split.nodes[n];
      ASSERT_EQ(a.count, b.count) << name << " node " << n;
      for (int k = 0; k < 3; ++k) ASSERT_TRUE(a.bmin[k] == b.bmin[k] && a.bmax[k] == b.bmax[k]) << name << " node " << n;
      if (a.count == 0) {
        ASSERT_EQ(a.first, b.first) << name << " node " << n;
        continue;
      }
      std::vector<std::uint32_t> x, y;
      for (std::uint32_t k = 0; k < a.count; ++k) x.push_back(plain.triangles[a.first + k].id), y.push_back(split.triangles[b.first + k].id);
      std::sort(x.begin(), x.end());
      std::sort(y.begin(), y.end());
      ASSERT_EQ(x, y) << name << " leaf " << n;
    }
    EXPECT_EQ(split.sah_cost, plain.sah_cost) << name;
  }
}

// The build splits its work over threads (top nodes and subtree jobs): on 1, 2 and 5 threads the
// same bytes, nodes and references.
TEST(SpatialBvh, SameTreeOnEveryThreadCount) {
  const Scene::Flat tris = load_scene("multi-instance").flatten();
  ASSERT_GT(tris.size(), 5u * 4096u) << "too small to split the top on 5 threads";
  const Bvh plain = build_bvh(tris);
  BvhBuildOptions opts;
  opts.threads = 1;
  const Bvh one = build_spatial_bvh(plain, opts, 1.0);
  ASSERT_GT(one.triangles.size(), tris.size()) << "no spatial split: the test would not see their order";
  for (unsigned threads : {2u, 5u}) {
    opts.threads = threads;
    const Bvh other = build_spatial_bvh(plain, opts, 1.0);
    EXPECT_TRUE(other.nodes.size() == one.nodes.size() &&
                std::memcmp(other.nodes.data(), one.nodes.data(), one.nodes.size() * sizeof(RsBvhNode)) == 0)
        << threads << " threads: nodes differ from 1 thread's";
    EXPECT_TRUE(other.triangles.size() == one.triangles.size() &&
                std::memcmp(other.triangles.data(), one.triangles.data(), one.triangles.size() * sizeof(RsTriangle)) == 0)
        << threads << " threads: references differ from 1 thread's";
  }
}

// split_tree builds once and keeps the tree with its Bvh; a copy of the Bvh builds its own, the same.
TEST(SpatialBvh, SplitTreeIsBuiltOnceAndNotSharedWithACopy) {
  const Bvh plain = build_bvh(load_scene("detail-room").flatten());
  const SplitTree& first = split_tree(plain);
  EXPECT_EQ(&split_tree(plain), &first);
  EXPECT_EQ(validate_wide8(first.wide8, first.binary), "");
  const Bvh copy = plain;
  const SplitTree& own = split_tree(copy);
  EXPECT_NE(&own, &first);
  EXPECT_TRUE(own.wide8.nodes.size() == first.wide8.nodes.size() &&
              std::memcmp(own.wide8.nodes.data(), first.wide8.nodes.data(), own.wide8.nodes.size() * sizeof(RsWide8Node)) == 0);
}

// The paper's scenes: a lower SAH cost than the plain tree's, within the budget (sibenik: 47.41 -> 43.97).
TEST(SpatialBvh, LowerSahCostOnSibenikAndBreakfastRoom) {
  RAYSORT_REQUIRE_REAL_SCENES();
  for (const char* name : {"sibenik", "breakfast_room"}) {
    const Bvh plain = build_bvh(load_scene(name).flatten());
    const SplitTree& split = split_tree(plain);
    ASSERT_EQ(validate_spatial_bvh(split.binary, plain, kSpatialSplitBudget), "") << name;
    EXPECT_EQ(validate_wide8(split.wide8, split.binary), "") << name;
    EXPECT_LT(split.binary.sah_cost, 0.97 * plain.sah_cost) << name << ": plain " << plain.sah_cost;
  }
}

}  // namespace raysort
