// The GPU cost model's cache replay (bench/gpu_model.h) on hand-built trails.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "bench/gpu_model.h"
#include "bvh_layout.h"

namespace raysort {
namespace {

// A tiny GPU: `sms` SMs, an L1 of 4 lines (fully associative) and an L2 of 8 lines' worth of
// 32-byte sectors (4 sets of 8), 128-byte lines, so that a few wide nodes (128 bytes each, one
// line, four sectors) fill them.
GpuProfile tiny_gpu(unsigned sms, unsigned resident_warps = 1, unsigned dynamic_fetch_threshold = 0) {
  return parse_gpu_profile(fmt::format(R"(name = "tiny"
sms = {}
resident_warps_per_sm = {}
dynamic_fetch_threshold = {}
l1_bytes = 512
l1_ways = 4
l2_bytes = 1024
l2_ways = 8
line_bytes = 128
sector_bytes = 32
dram_gbps = 1.0
l2_gbps = 2.0
clock_ghz = 1.0
step_cycles = 10.0
)",
                                       sms, resident_warps, dynamic_fetch_threshold),
                           "test");
}

// 64 wide nodes, no packets: node k is line k.
WideBvh nodes_only() {
  WideBvh w;
  w.nodes.resize(64, RsWideNode{});
  return w;
}

// A warp whose 32 lanes follow the same trail (no ray loads, to count node lines only).
WarpTrails warp_of(std::vector<std::uint32_t> trail, std::size_t lanes = 32) {
  WarpTrails w;
  w.lanes.assign(lanes, trail);
  return w;
}

TEST(GpuModel, EmbeddedProfilesParse) {
  for (const char* name : {"rtx3060", "h100", "h200"}) {
    const GpuProfile p = load_gpu_profile(name);
    EXPECT_EQ(p.name, name);
    EXPECT_GT(p.sms, 0u);
    EXPECT_EQ(p.line_bytes, 128u);
    EXPECT_GT(p.l2_bytes, p.l1_bytes);
  }
  EXPECT_EQ(load_gpu_profile("rtx3060").sms, 28u);
  EXPECT_THROW(load_gpu_profile("no-such-gpu"), std::exception);
}

TEST(GpuModel, WarpFetchingOneLineMakesOneRequestPerStep) {
  const GpuProfile p = tiny_gpu(1);
  const WideBvh wide = nodes_only();
  const GpuAddressMap map(wide, 0);
  GpuReplay replay(p, map);
  const std::vector<WarpTrails> wave{warp_of({0, 0, 0})};  // three steps on node 0
  replay.replay_wave(wave);
  const GpuCounts& c = replay.counts();
  EXPECT_EQ(c.warp_steps, 3u);
  EXPECT_EQ(c.idle_lanes, 0u);
  EXPECT_EQ(c.requests, 3u);  // 32 lanes on one line: one coalesced request per step
  EXPECT_EQ(c.l1_misses, 1u);
  EXPECT_EQ(c.l1_hits, 2u);
  EXPECT_EQ(c.l2_misses, 4u);  // the line's four sectors
  EXPECT_EQ(c.dram_bytes, 128u);
  EXPECT_EQ(c.steps_dram, 1u);  // the first step waits for DRAM, the other two hit L1
  EXPECT_EQ(c.steps_l2, 0u);
}

TEST(GpuModel, IdleLanesAreCountedPerStep) {
  const GpuProfile p = tiny_gpu(1);
  const WideBvh wide = nodes_only();
  const GpuAddressMap map(wide, 0);
  GpuReplay replay(p, map);
  std::vector<WarpTrails> wave{warp_of({0}, 31)};
  wave[0].lanes.push_back({0, 1, 2, 3});  // one long lane: 4 steps, 31 lanes idle in the last 3
  replay.replay_wave(wave);
  EXPECT_EQ(replay.counts().warp_steps, 4u);
  EXPECT_EQ(replay.counts().idle_lanes, 3u * 31u);
}

TEST(GpuModel, ThrashingWarpMissesEveryTime) {
  const GpuProfile p = tiny_gpu(1);
  const WideBvh wide = nodes_only();
  const GpuAddressMap map(wide, 0);
  GpuReplay replay(p, map);
  // Cycling over 16 lines with LRU caches of 4 and 8 lines: each line is evicted before its reuse.
  std::vector<std::uint32_t> trail;
  for (int round = 0; round < 3; ++round)
    for (std::uint32_t k = 0; k < 16; ++k) trail.push_back(k);
  const std::vector<WarpTrails> wave{warp_of(trail)};
  replay.replay_wave(wave);
  const GpuCounts& c = replay.counts();
  EXPECT_EQ(c.requests, 48u);
  EXPECT_EQ(c.l1_hits, 0u);
  EXPECT_EQ(c.l2_hits, 0u);
  EXPECT_EQ(c.dram_bytes, 48u * 128u);
  // Cycling over 3 lines instead: all but the first touches hit in L1.
  GpuReplay fits(p, map);
  const std::vector<WarpTrails> small{warp_of({0, 1, 2, 0, 1, 2, 0, 1, 2})};
  fits.replay_wave(small);
  EXPECT_EQ(fits.counts().l1_misses, 3u);
  EXPECT_EQ(fits.counts().l1_hits, 6u);
}

TEST(GpuModel, WarmL2ServesAnotherSmsMisses) {
  const GpuProfile p = tiny_gpu(2);
  const WideBvh wide = nodes_only();
  const GpuAddressMap map(wide, 0);
  const WarpTrails reader = warp_of({0, 1, 2, 3});
  // Warm: SM 0 reads lines 0-3 in the first wave; in the second, SM 1 reads them again: its own L1
  // is cold, the shared L2 is warm.
  GpuReplay warm(p, map);
  const std::vector<WarpTrails> first{reader}, second{warp_of({}), reader};
  warm.replay_wave(first);
  warm.replay_wave(second);
  EXPECT_EQ(warm.counts().l1_misses, 8u);
  EXPECT_EQ(warm.counts().l2_misses, 16u);  // sectors
  EXPECT_EQ(warm.counts().l2_hits, 16u);
  EXPECT_EQ(warm.counts().steps_dram, 4u);  // SM 0's steps
  EXPECT_EQ(warm.counts().steps_l2, 4u);    // SM 1's steps: L1 misses served by the warm L2
  // Cold: SM 1 alone, every line from DRAM.
  GpuReplay cold(p, map);
  cold.replay_wave(second);
  EXPECT_EQ(cold.counts().l2_hits, 0u);
  EXPECT_EQ(cold.counts().l2_misses, 16u);
  EXPECT_EQ(cold.counts().dram_bytes, 4u * 128u);
}

TEST(GpuModel, LeafStepsReadTheirPacketsAndRayLoadsCoalesce) {
  const GpuProfile p = tiny_gpu(1);
  WideBvh wide = nodes_only();  // nodes: 64 x 128 bytes = 8 KB, so packets start at 8192
  wide.packets.resize(8, RsTriPacket{});
  const GpuAddressMap map(wide, 64);
  std::vector<std::uint64_t> lines;
  map.step_blocks(RS_WIDE_LEAF | (0u << 2) | 1u, 128, lines);  // packets 0-1: bytes 8192-8575
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{64, 65, 66}));
  GpuReplay replay(p, map);
  WarpTrails w = warp_of({0});
  for (std::uint32_t i = 0; i < 32; ++i) w.rays.push_back(i);  // consecutive rays: few lines
  replay.replay_wave(std::vector<WarpTrails>{w});
  const std::uint64_t ray_lines = (32 * sizeof(RsRay) + 127) / 128;
  EXPECT_EQ(replay.counts().requests, 1u + ray_lines);
}

// The wide8 class's tree: a node step reads its 256 bytes (two 128-byte lines), a leaf step its
// 384-byte packets, the whole packet where the leaf has some of its lanes (RS_WIDE8_LEAF_*).
TEST(GpuModel, Wide8StepsReadTheirNodesAndPackets) {
  Wide8Bvh wide8;
  wide8.nodes.resize(32, RsWide8Node{});  // 32 x 256 bytes = 8 KB, so packets start at 8192
  wide8.packets.resize(4, RsTriPacket8{});
  const GpuAddressMap map(wide8, 64);
  std::vector<std::uint64_t> lines;
  map.step_blocks(3, 128, lines);  // node 3: bytes 768-1023
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{6, 7}));
  lines.clear();
  map.step_blocks(RS_WIDE8_LEAF_REF(1u, 0u, 8u, 1u), 128, lines);  // packet 1: bytes 8576-8959
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{67, 68, 69}));
  lines.clear();
  map.step_blocks(RS_WIDE8_LEAF_REF(1u, 4u, 3u, 1u), 128, lines);  // its lanes 4-6: the same rows
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{67, 68, 69}));
  lines.clear();
  map.step_blocks(RS_WIDE8_LEAF_REF(1u, 0u, 8u, 2u), 128, lines);  // packets 1-2: bytes 8576-9343
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{67, 68, 69, 70, 71, 72}));
  EXPECT_TRUE(map.is_leaf(RS_WIDE8_LEAF_REF(1u, 0u, 1u, 1u)));
  EXPECT_FALSE(map.is_leaf(3));
}

// The cwbvh class's tree: a node step reads its 80 bytes, a leaf step one 48-byte triangle.
TEST(GpuModel, CwbvhStepsReadTheirNodesAndTriangles) {
  CwBvh cw;
  cw.nodes.resize(100);  // 8,000 bytes: triangles start at 8192
  cw.triangles.resize(10);
  const GpuAddressMap map(cw, 64);
  std::vector<std::uint64_t> lines;
  map.step_blocks(3, 128, lines);  // node 3: bytes 240-319
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{1, 2}));
  lines.clear();
  map.step_blocks(RS_WIDE_LEAF | (5u << 2), 128, lines);  // triangle 5: bytes 8432-8479
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{65, 66}));
  EXPECT_TRUE(map.is_leaf(RS_WIDE_LEAF | (5u << 2)));
  EXPECT_FALSE(map.is_leaf(3));
}

// A while-while kernel's issued steps (while_while_steps): per outer iteration the longest run of
// inner-node steps over the lanes, then the longest run of leaf steps. Lanes whose node and leaf
// steps interleave differently wait for each other, where lockstep lets them advance together.
TEST(GpuModel, WhileWhileStepsWaitForTheOtherKindOfStep) {
  WideBvh wide = nodes_only();
  wide.packets.resize(8, RsTriPacket{});
  const GpuAddressMap map(wide, 64);
  const std::uint32_t L = RS_WIDE_LEAF;  // a leaf of one packet
  EXPECT_TRUE(map.is_leaf(L));
  EXPECT_FALSE(map.is_leaf(5));
  // Coherent lanes: every step counts once, as in lockstep.
  EXPECT_EQ(while_while_steps(warp_of({0, 1, L, 2, L}), map), 5u);
  WarpTrails w;
  w.lanes = {{0, L, 1, L}, {L, 0, L, 1}};
  // Lane 0: node, leaf, node, leaf. Lane 1 starts at a leaf (a root that is a leaf), then the same.
  // Iteration 1: inner runs 1 and 0, leaf runs 1 and 1; iteration 2: inner 1 and 1, leaf 1 and 1;
  // iteration 3: inner 0 and 1, leaf 0 and 0. Lockstep would issue 4.
  EXPECT_EQ(while_while_steps(w, map), 2u + 2u + 1u);
  // One long lane and one finished: the long lane's trail alone.
  w.lanes = {{0, 1, 2, L, L, 3}, {}};
  EXPECT_EQ(while_while_steps(w, map), 6u);
  // The replay adds them up over its warps.
  GpuReplay replay(tiny_gpu(1), map);
  std::vector<WarpTrails> warps{warp_of({0, 1, L}), w};
  replay.replay_wave(warps);
  EXPECT_EQ(replay.counts().ww_steps, 3u + 6u);
  EXPECT_EQ(replay.counts().warp_steps, 3u + 6u);
  // On the binary layout a node is a leaf when it holds primitives.
  Bvh binary;
  binary.nodes.resize(3, RsBvhNode{});
  binary.nodes[1].count = 2;
  binary.triangles.resize(2, RsTriangle{});
  const GpuAddressMap bmap(binary, 64);
  EXPECT_FALSE(bmap.is_leaf(0));
  EXPECT_TRUE(bmap.is_leaf(1));
  WarpTrails b;
  b.lanes = {{0, 1}, {0, 2, 1}};
  EXPECT_EQ(while_while_steps(b, bmap), 2u + 1u);
}

// An any-hit ray stops in the leaf it hits, after the packet holding the hit: its last step reads
// only those packets (WarpTrails::last_reads), where the model used to read the whole leaf.
TEST(GpuModel, AnyHitLanesReadTheirLastLeafOnlyUpToTheHit) {
  const GpuProfile p = tiny_gpu(1);
  WideBvh wide = nodes_only();  // packets start at byte 8192 = line 64
  wide.packets.resize(8, RsTriPacket{});
  const GpuAddressMap map(wide, 64);
  const std::uint32_t leaf = RS_WIDE_LEAF | (0u << 2) | 3u;  // packets 0-3: bytes 8192-8959, lines 64-69
  std::vector<std::uint64_t> lines;
  map.step_blocks(leaf, 128, lines);
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{64, 65, 66, 67, 68, 69}));
  lines.clear();
  map.step_blocks(leaf, 128, lines, 1);  // stopped in packet 0: bytes 8192-8383
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{64, 65}));
  lines.clear();
  map.step_blocks(leaf, 128, lines, 9);  // more than the leaf holds: the whole leaf
  EXPECT_EQ(lines.size(), 6u);
  lines.clear();
  map.step_blocks(5, 128, lines, 1);  // an inner node has no leaf to cut short
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{5}));

  auto requests = [&](const WarpTrails& w) {
    GpuReplay replay(p, map);
    replay.replay_wave(std::vector<WarpTrails>{w});
    return replay.counts().requests;
  };
  WarpTrails full = warp_of({0, leaf});
  EXPECT_EQ(requests(full), 1u + 6u);
  WarpTrails stopped = full;
  stopped.last_reads.assign(32, 1);
  EXPECT_EQ(requests(stopped), 1u + 2u);
  // Lanes that stop at different packets: the warp reads the union; a lane whose last step is not
  // its leaf step (reads only apply to the last step) still reads the whole leaf.
  WarpTrails mixed = full;
  mixed.last_reads.assign(32, 1);
  mixed.last_reads[7] = 3;  // packets 0-2: lines 64-68
  EXPECT_EQ(requests(mixed), 1u + 5u);
  WarpTrails longer = full;
  longer.lanes[0] = {0, leaf, 1};
  longer.last_reads.assign(32, 1);
  EXPECT_EQ(requests(longer), 1u + 6u + 1u);
}

// Dynamic fetch (Aila and Laine's persistent warps): one warp, 64 rays, ray 0 takes 10 steps and
// every other ray one. Static warps wait for ray 0: 10 + 1 steps. With threshold 32 the finished
// lanes take rays 32-62 at the second step and ray 63 at the third, beside ray 0: 10 steps.
TEST(GpuModel, DynamicFetchRefillsFinishedLanes) {
  const WideBvh wide = nodes_only();
  const GpuAddressMap map(wide, 0);
  std::vector<WarpTrails> rays{warp_of({0}), warp_of({0})};
  rays[0].lanes[0] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  GpuReplay fixed(tiny_gpu(1), map);
  fixed.replay_wave(std::span(rays).first(1));
  fixed.replay_wave(std::span(rays).last(1));
  EXPECT_EQ(fixed.counts().warp_steps, 11u);
  EXPECT_EQ(fixed.counts().idle_lanes, 9u * 31u);

  GpuReplay refill(tiny_gpu(1, 1, 32), map);
  std::vector<WarpTrails> copy = rays;
  refill.replay_stream(copy, true);
  EXPECT_EQ(refill.counts().warp_steps, 10u);
  EXPECT_EQ(refill.counts().idle_lanes, 30u + 7u * 31u);  // step 3: ray 0 and ray 63; steps 4-10: ray 0
  EXPECT_EQ(refill.counts().replayed_warps, 2u);
  // Threshold 1: a warp fetches only when all its lanes have finished, which is the static schedule.
  GpuReplay empty_only(tiny_gpu(1, 1, 1), map);
  copy = rays;
  empty_only.replay_stream(copy, true);
  EXPECT_EQ(empty_only.counts().warp_steps, 11u);
  EXPECT_EQ(empty_only.counts().idle_lanes, 9u * 31u);
}

// raysort run hands the rays over a wave at a time; the counts must not depend on the chunking.
TEST(GpuModel, DynamicFetchCountsDoNotDependOnChunks) {
  const WideBvh wide = nodes_only();
  const GpuAddressMap map(wide, 1024);
  std::vector<WarpTrails> rays(37);
  std::uint32_t seed = 12345;
  auto next = [&] { return seed = seed * 1664525u + 1013904223u; };
  for (std::size_t k = 0; k < rays.size(); ++k) {
    rays[k].lanes.resize(32);
    for (std::uint32_t l = 0; l < 32; ++l) {
      rays[k].rays.push_back(static_cast<std::uint32_t>(k * 32 + l));
      for (std::uint32_t s = 0, len = 1 + (next() >> 28); s < len; ++s) rays[k].lanes[l].push_back((next() >> 16) % 64);
    }
  }
  const GpuProfile p = tiny_gpu(2, 3, 20);
  GpuReplay whole(p, map);
  std::vector<WarpTrails> copy = rays;
  whole.replay_stream(copy, true);
  for (std::size_t chunk : {1u, 5u, 6u, 11u}) {
    GpuReplay parts(p, map);
    copy = rays;
    for (std::size_t k = 0; k < copy.size(); k += chunk) {
      const std::size_t n = std::min(chunk, copy.size() - k);
      parts.replay_stream(std::span(copy).subspan(k, n), k + n == copy.size());
    }
    const GpuCounts &a = whole.counts(), &b = parts.counts();
    SCOPED_TRACE(fmt::format("chunks of {} warps", chunk));
    EXPECT_EQ(a.warp_steps, b.warp_steps);
    EXPECT_EQ(a.idle_lanes, b.idle_lanes);
    EXPECT_EQ(a.requests, b.requests);
    EXPECT_EQ(a.l1_hits, b.l1_hits);
    EXPECT_EQ(a.l2_hits, b.l2_hits);
    EXPECT_EQ(a.dram_bytes, b.dram_bytes);
    EXPECT_EQ(b.replayed_warps, rays.size());
  }
  EXPECT_GT(whole.counts().warp_steps, 0u);
  EXPECT_THROW(tiny_gpu(1, 1, 33), std::exception);  // a threshold above the warp's 32 lanes
}

TEST(GpuModel, PredictedTimeIsIssuePlusMemory) {
  const GpuProfile p = tiny_gpu(1);  // 1 SM at 1 GHz, 10 cycles a step; 1 GB/s DRAM, 2 GB/s L2
  GpuCounts c;
  c.warps = c.replayed_warps = 1;
  c.warp_steps = 100;  // 1000 cycles = 1 us
  c.l1_misses = 10, c.l2_misses = 40, c.dram_bytes = 1280;  // 1.28 us + 40 sectors through L2: 0.64 us
  const GpuTime t = gpu_model_time(c, p);
  EXPECT_NEAR(t.issue_s, 1e-6, 1e-12);
  EXPECT_NEAR(t.memory_s, 1.92e-6, 1e-12);
  EXPECT_NEAR(t.total_s, 2.92e-6, 1e-12);
  c.warps = 4;  // a quarter of the warps replayed: the time stands for all of them
  EXPECT_NEAR(gpu_model_time(c, p).total_s, 4 * 2.92e-6, 1e-12);
}

}  // namespace
}  // namespace raysort
