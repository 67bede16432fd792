// ANC on known key sequences and the SIMT model on hand-built traversal trails.
#include <gtest/gtest.h>
#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <string>

#include "bench/gpu_model.h"
#include "bench/metrics.h"
#include "traverse_binary.h"
#include "traverse_cwbvh.h"
#include "traverse_wide.h"
#include "traverse_wide8.h"

namespace raysort {

TEST(Anc, KnownSequences) {
  std::vector<std::uint64_t> same(64, 7);
  EXPECT_DOUBLE_EQ(average_number_of_codes(same), 1.0);
  std::vector<std::uint64_t> all_distinct(64);
  std::iota(all_distinct.begin(), all_distinct.end(), 0u);
  EXPECT_DOUBLE_EQ(average_number_of_codes(all_distinct), 32.0);
  // Two groups: first has keys {0,1} (16 each), second all 5 except one 6 -> (2 + 2) / 2.
  std::vector<std::uint64_t> mixed(64, 0);
  for (int i = 16; i < 32; ++i) mixed[i] = 1;
  for (int i = 32; i < 64; ++i) mixed[i] = 5;
  mixed[40] = 6;
  EXPECT_DOUBLE_EQ(average_number_of_codes(mixed), 2.0);
  // A short last group counts as a group: 32 equal keys then 3 distinct ones -> (1 + 3) / 2.
  std::vector<std::uint64_t> tail(35, 9);
  tail[32] = 1, tail[33] = 2, tail[34] = 3;
  EXPECT_DOUBLE_EQ(average_number_of_codes(tail), 2.0);
  EXPECT_DOUBLE_EQ(average_number_of_codes({}), 0.0);
  // Order within a group does not matter; order across groups does.
  std::vector<std::uint64_t> interleaved(64);
  for (int i = 0; i < 64; ++i) interleaved[i] = i % 2;
  EXPECT_DOUBLE_EQ(average_number_of_codes(interleaved), 2.0);
}

TEST(SimtModel, HandBuiltTrails) {
  // One warp of 32 lanes, all the same path of 4 nodes: efficiency 1, 4 distinct / 128 visits.
  std::vector<std::vector<std::uint32_t>> same(32, {0, 1, 3, 7});
  auto m = simt_model_from_trails(same);
  EXPECT_DOUBLE_EQ(m.lane_efficiency, 1.0);
  EXPECT_DOUBLE_EQ(m.distinct_nodes_per_visit, 4.0 / 128.0);
  EXPECT_EQ(m.total_steps, 128u);
  EXPECT_EQ(m.warps, 1u);

  // Lane 0 takes 8 steps, the other 31 take 1: Σ = 39 of 32·8 = 256 issued.
  std::vector<std::vector<std::uint32_t>> skewed(32, {0});
  skewed[0] = {0, 1, 2, 3, 4, 5, 6, 7};
  m = simt_model_from_trails(skewed);
  EXPECT_DOUBLE_EQ(m.lane_efficiency, 39.0 / 256.0);
  EXPECT_DOUBLE_EQ(m.distinct_nodes_per_visit, 8.0 / 39.0);

  // Two warps, every lane a different path: distinct == visits.
  std::vector<std::vector<std::uint32_t>> divergent(64);
  for (std::uint32_t i = 0; i < 64; ++i) divergent[i] = {1000 + 2 * i, 1001 + 2 * i};
  m = simt_model_from_trails(divergent);
  EXPECT_DOUBLE_EQ(m.lane_efficiency, 1.0);
  EXPECT_DOUBLE_EQ(m.distinct_nodes_per_visit, 1.0);
  EXPECT_EQ(m.warps, 2u);

  // A partial last warp issues only its own lanes.
  std::vector<std::vector<std::uint32_t>> partial(33, {0, 1});
  partial[32] = {0, 1, 2, 3};
  m = simt_model_from_trails(partial);
  EXPECT_DOUBLE_EQ(m.lane_efficiency, (64.0 + 4.0) / (64.0 + 4.0));
}

TEST(SimtModel, TracedModelMatchesTrailsAndOrderMatters) {
  // A row of 64 separated unit quads along x; rays straight down onto each.
  Scene::Flat f;
  for (int i = 0; i < 64; ++i) {
    float x = static_cast<float>(i) * 2.0f;
    f.v0.push_back({x, 0, 0}), f.v1.push_back({x + 1, 0, 0}), f.v2.push_back({x, 0, 1}), f.material.push_back(0);
    f.v0.push_back({x + 1, 0, 0}), f.v1.push_back({x + 1, 0, 1}), f.v2.push_back({x, 0, 1}), f.material.push_back(0);
  }
  Bvh bvh = build_bvh(f);
  std::vector<RsRay> rays;
  for (int i = 0; i < 256; ++i) {
    RsRay r{};
    r.o[0] = static_cast<float>(i % 64) * 2.0f + 0.5f, r.o[1] = 1.0f, r.o[2] = 0.5f;
    r.d[1] = -1.0f;
    r.tmax = RS_T_FAR;
    rays.push_back(r);
  }
  // Interleaved (i % 64) vs sorted by position: sorted warps share far more nodes.
  std::vector<std::uint32_t> sorted(rays.size());
  std::iota(sorted.begin(), sorted.end(), 0u);
  std::stable_sort(sorted.begin(), sorted.end(), [&](auto a, auto b) { return rays[a].o[0] < rays[b].o[0]; });
  for (TraceLayout layout : {TraceLayout::Wide, TraceLayout::Wide8, TraceLayout::Binary, TraceLayout::Cwbvh}) {
    SCOPED_TRACE(trace_layout_name(layout));
    auto interleaved_model = simt_model(bvh, rays, nullptr, false, TraceVariant::Fast, layout);
    auto sorted_model = simt_model(bvh, rays, sorted.data(), false, TraceVariant::Fast, layout);
    EXPECT_LT(sorted_model.distinct_nodes_per_visit, interleaved_model.distinct_nodes_per_visit);
    EXPECT_EQ(sorted_model.total_steps, interleaved_model.total_steps);  // same rays, same work
    EXPECT_GT(sorted_model.total_steps, 0u);
  }
  // The wide model walks what the kernels walk: its steps are the wide traversal's node and leaf
  // visits (the kernels' cost counter), ray by ray, and fewer than the binary tree's.
  std::vector<std::uint32_t> visits;
  (void)trace_reference(bvh, rays, nullptr, false, &visits, TraceVariant::Fast, TraceLayout::Wide);
  const std::uint64_t wide_visits = std::accumulate(visits.begin(), visits.end(), std::uint64_t{0});
  const SimtModel wide = simt_model(bvh, rays, nullptr, false, TraceVariant::Fast, TraceLayout::Wide);
  const SimtModel binary = simt_model(bvh, rays, nullptr, false, TraceVariant::Fast, TraceLayout::Binary);
  EXPECT_EQ(wide.total_steps, wide_visits);
  EXPECT_LT(wide.total_steps, binary.total_steps);
  // The wide8 model walks the 8-wide tree: its steps are the wide8 traversal's visits.
  (void)trace_reference(bvh, rays, nullptr, false, &visits, TraceVariant::Fast, TraceLayout::Wide8);
  const SimtModel wide8 = simt_model(bvh, rays, nullptr, false, TraceVariant::Fast, TraceLayout::Wide8);
  EXPECT_EQ(wide8.total_steps, std::accumulate(visits.begin(), visits.end(), std::uint64_t{0}));
  EXPECT_LE(wide8.total_steps, wide.total_steps);
  // The cwbvh model walks the compressed tree: its steps are the cwbvh traversal's (nodes and
  // triangle tests).
  (void)trace_reference(bvh, rays, nullptr, false, &visits, TraceVariant::Fast, TraceLayout::Cwbvh);
  const SimtModel cw = simt_model(bvh, rays, nullptr, false, TraceVariant::Fast, TraceLayout::Cwbvh);
  EXPECT_EQ(cw.total_steps, std::accumulate(visits.begin(), visits.end(), std::uint64_t{0}));
}

namespace {

// `count` small triangles scattered in an 8-unit cube, and rays from points in it in random
// directions: warps that share some nodes and miss others.
Scene::Flat scattered_triangles(int count, std::mt19937& rng) {
  Scene::Flat f;
  std::uniform_real_distribution<float> u(0.0f, 8.0f);
  for (int i = 0; i < count; ++i) {
    const float x = u(rng), y = u(rng), z = u(rng);
    f.v0.push_back({x, y, z}), f.v1.push_back({x + 0.5f, y, z}), f.v2.push_back({x, y + 0.5f, z + 0.3f});
    f.material.push_back(0);
  }
  return f;
}

std::vector<RsRay> scattered_rays(int count, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 8.0f);
  std::normal_distribution<float> n(0.0f, 1.0f);
  std::vector<RsRay> rays;
  for (int i = 0; i < count; ++i) {
    RsRay r{};
    for (int a = 0; a < 3; ++a) r.o[a] = u(rng), r.d[a] = n(rng);
    r.tmax = RS_T_FAR;
    rays.push_back(r);
  }
  return rays;
}

}  // namespace

// The binary-ww class's GPU model: the same trails as the binary class's (the same traversal order),
// so the same SIMT figures and while-while count, but it issues the while-while steps, which are
// more than the lockstep steps where lanes interleave inner and leaf steps differently.
TEST(SimtModel, WhileWhileClassIssuesItsWhileWhileSteps) {
  std::mt19937 rng(7);
  const Bvh bvh = build_bvh(scattered_triangles(400, rng));
  const std::vector<RsRay> rays = scattered_rays(2048, rng);
  const GpuProfile gpu = load_gpu_profile("rtx3060");
  GpuCounts binary_counts, ww_counts;
  const SimtModel binary = simt_model(bvh, rays, nullptr, false, TraceVariant::Fast, TraceLayout::Binary, &gpu, &binary_counts);
  const SimtModel ww = simt_model(bvh, rays, nullptr, false, TraceVariant::Fast, TraceLayout::BinaryWw, &gpu, &ww_counts);
  EXPECT_EQ(ww.total_steps, binary.total_steps);
  EXPECT_EQ(ww.lane_efficiency, binary.lane_efficiency);
  EXPECT_EQ(ww_counts.ww_steps, binary_counts.ww_steps);
  EXPECT_EQ(ww_counts.warp_steps, binary_counts.ww_steps);
  EXPECT_GT(ww_counts.warp_steps, binary_counts.warp_steps);
  EXPECT_EQ(ww_counts.dram_bytes, binary_counts.dram_bytes);
}

// The traced model counts a warp's distinct nodes by stamping node slots (metrics.cpp,
// DistinctNodes); it must give exactly what sorting the union of the same trails gives, on every
// layout, for closest and any hit, rays in a shuffled order, where leaves are shared and missed.
TEST(SimtModel, TracedDistinctNodesEqualTheSortedUnion) {
  std::mt19937 rng(5);
  const Bvh bvh = build_bvh(scattered_triangles(300, rng));
  const std::vector<RsRay> rays = scattered_rays(1000, rng);
  std::vector<std::uint32_t> order(rays.size());
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), rng);
  WideBvh wide_scratch;
  const WideBvh& wide = wide_of(bvh, wide_scratch);
  const Wide8Bvh& wide8 = split_tree(bvh).wide8;  // the tree the model and kernels walk
  const CwBvh cw = collapse_to_cwbvh(bvh);
  for (TraceLayout layout : {TraceLayout::Wide, TraceLayout::Wide8, TraceLayout::Binary, TraceLayout::Cwbvh})
    for (int any : {0, 1}) {
      SCOPED_TRACE(std::string(trace_layout_name(layout)) + (any ? " any hit" : " closest hit"));
      std::vector<std::vector<std::uint32_t>> trails(rays.size());
      std::vector<std::uint32_t> buffer(1u << 16);
      for (std::size_t i = 0; i < rays.size(); ++i) {
        rs_u32 len = 0;
        const RsRay& r = rays[order[i]];
        const rs_u32 cap = static_cast<rs_u32>(buffer.size());
        if (layout == TraceLayout::Wide)
          rs_traverse_wide_recorded(wide.nodes.data(), wide.packets.data(), r, 0, any, nullptr, buffer.data(), cap, &len);
        else if (layout == TraceLayout::Wide8)
          rs_traverse_wide8_recorded(wide8.nodes.data(), wide8.packets.data(), r, 0, any, nullptr, buffer.data(), cap,
                                     &len);
        else if (layout == TraceLayout::Cwbvh)
          rs_traverse_cwbvh_recorded(cw.nodes.data(), cw.triangles.data(), r, 0, any, nullptr, buffer.data(), cap, &len);
        else
          rs_traverse_variant_recorded(bvh.nodes.data(), bvh.triangles.data(), r, 0, any, nullptr, buffer.data(), cap,
                                       &len);
        trails[i].assign(buffer.begin(), buffer.begin() + len);
      }
      const SimtModel want = simt_model_from_trails(trails);
      const SimtModel got = simt_model(bvh, rays, order.data(), any != 0, TraceVariant::Fast, layout);
      EXPECT_GT(want.total_steps, 0u);
      EXPECT_EQ(got.total_steps, want.total_steps);
      EXPECT_EQ(got.warps, want.warps);
      EXPECT_EQ(got.lane_efficiency, want.lane_efficiency);
      EXPECT_EQ(got.distinct_nodes_per_visit, want.distinct_nodes_per_visit);
    }
}

// The trails recorded once in ray order (bench/metrics.h, RayTrails) give every other order the
// model, GPU counts included, that walking the rays again gives; over its budget nothing is kept
// and the model is the same. Any hit too (its last leaf reads are kept with the trails).
TEST(SimtModel, TrailsRecordedOnceGiveEveryOrderTheSameModel) {
  std::mt19937 rng(11);
  const Bvh bvh = build_bvh(scattered_triangles(400, rng));
  const std::vector<RsRay> rays = scattered_rays(3000, rng);
  std::vector<std::uint32_t> shuffled(rays.size());
  std::iota(shuffled.begin(), shuffled.end(), 0u);
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  const GpuProfile gpu = load_gpu_profile("rtx3060");
  for (TraceLayout layout : {TraceLayout::Wide, TraceLayout::Wide8, TraceLayout::Binary, TraceLayout::Cwbvh})
    for (bool any_hit : {false, true}) {
      SCOPED_TRACE(fmt::format("{} any_hit {}", trace_layout_name(layout), any_hit));
      RayTrails trails;
      trails.budget_bytes = std::uint64_t{1} << 30;
      GpuCounts walked_counts, read_counts;
      const SimtModel nosort = simt_model(bvh, rays, nullptr, any_hit, TraceVariant::Robust, layout, &gpu, nullptr, &trails);
      ASSERT_TRUE(trails.filled());
      EXPECT_EQ(trails.begin.size(), rays.size() + 1);
      EXPECT_EQ(trails.steps.size(), nosort.total_steps);
      const SimtModel walked = simt_model(bvh, rays, shuffled.data(), any_hit, TraceVariant::Robust, layout, &gpu, &walked_counts);
      const SimtModel read =
          simt_model(bvh, rays, shuffled.data(), any_hit, TraceVariant::Robust, layout, &gpu, &read_counts, &trails);
      EXPECT_EQ(read.total_steps, walked.total_steps);
      EXPECT_EQ(read.lane_efficiency, walked.lane_efficiency);
      EXPECT_EQ(read.distinct_nodes_per_visit, walked.distinct_nodes_per_visit);
      EXPECT_EQ(read_counts.warp_steps, walked_counts.warp_steps);
      EXPECT_EQ(read_counts.dram_bytes, walked_counts.dram_bytes);
      EXPECT_EQ(read_counts.l1_hits, walked_counts.l1_hits);
      RayTrails small;
      small.budget_bytes = 1000;
      (void)simt_model(bvh, rays, nullptr, any_hit, TraceVariant::Robust, layout, nullptr, nullptr, &small);
      EXPECT_FALSE(small.filled());
      EXPECT_TRUE(small.over_budget);
      EXPECT_EQ(simt_model(bvh, rays, shuffled.data(), any_hit, TraceVariant::Robust, layout, nullptr, nullptr, &small)
                    .lane_efficiency,
                walked.lane_efficiency);
    }
}

}  // namespace raysort
