// Trace kernels on the device against the host reference, bit for bit, on every batch of real
// pipelines; plus hand-checked hits on tiny scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>
#include <tuple>

#include "bvh/bvh.h"
#include "render/batches.h"
#include "scene/load.h"
#include "test_util.h"
#include "trace/packet_twin.h"
#include "trace/stream_twin.h"
#include "trace/tracer.h"
#include "traverse_wide8.h"
#include "util/error.h"

namespace raysort {

namespace {

using testing::ray;
using testing::two_quads;

void expect_device_equals_reference(const Scene& scene, const RayGenOptions& gen, std::size_t min_batches) {
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  Tracer tracer(testing::runtime(), bvh);
  auto batches = generate_batches(scene, tris, bvh, gen);
  ASSERT_GE(batches.size(), min_batches) << scene.name;
  for (const auto& rb : batches) {
    ASSERT_FALSE(rb.batch.rays.empty()) << rb.batch.name;
    auto run = tracer.run(rb.batch.rays, nullptr, rb.batch.any_hit());
    EXPECT_EQ(count_hit_mismatches(run.hits, rb.reference_hits), 0u) << scene.name << " " << rb.batch.name;
    std::size_t hits = 0;
    for (auto& h : rb.reference_hits) hits += h.tri != RS_NO_HIT;
    // A batch that hits nothing (or everything, for shadows) would test little.
    if (!rb.batch.any_hit()) {
      EXPECT_GT(hits, 0u) << scene.name << " " << rb.batch.name;
    }
    // Sorted order: trace through a reversed order; hits come back in trace order.
    std::vector<std::uint32_t> reversed(rb.batch.size());
    for (std::size_t i = 0; i < reversed.size(); ++i) reversed[i] = static_cast<std::uint32_t>(reversed.size() - 1 - i);
    auto rev = tracer.run(rb.batch.rays, &reversed, rb.batch.any_hit());
    std::size_t bad = 0;
    for (std::size_t i = 0; i < reversed.size(); ++i)
      bad += std::memcmp(&rev.hits[i], &rb.reference_hits[reversed[i]], sizeof(RsHit)) != 0;
    EXPECT_EQ(bad, 0u) << "indirect order, " << scene.name << " " << rb.batch.name;
  }
}

}  // namespace

TEST(Trace, HandCheckedHitsOnTwoQuads) {
  Scene s = two_quads();
  Bvh bvh = build_bvh(s.flatten());
  std::vector<RsRay> rays = {
      ray(0.5f, 0.5f, 1.0f, 0, 0, -1),          // hits the front quad at t = 1
      ray(0.5f, 0.5f, -2.0f, 0, 0, 1),          // from behind: back quad at t = 1
      ray(2.0f, 2.0f, 1.0f, 0, 0, -1),          // misses
      ray(0.5f, 0.5f, 1.0f, 0, 0, -1, 0.5f),    // tmax before the quad: miss
      ray(0.1f, 0.9f, 5.0f, -0.0f, 0.0f, -1),   // axis-parallel with a -0 component
      ray(0.5f, 0.5f, 0.5f, 0, 0, 1),           // pointing away: miss
  };
  auto ref = trace_reference(bvh, rays, nullptr, false);
  EXPECT_EQ(ref[0].t, 1.0f);
  EXPECT_LT(ref[0].tri, 2u);
  EXPECT_EQ(ref[1].t, 1.0f);
  EXPECT_GE(ref[1].tri, 2u);
  EXPECT_EQ(ref[2].tri, RS_NO_HIT);
  EXPECT_EQ(ref[3].tri, RS_NO_HIT);
  EXPECT_EQ(ref[4].t, 5.0f);
  EXPECT_LT(ref[4].tri, 2u);
  EXPECT_EQ(ref[5].tri, RS_NO_HIT);
  Tracer tracer(testing::runtime(), bvh);
  auto dev = tracer.run(rays, nullptr, false);
  EXPECT_EQ(count_hit_mismatches(dev.hits, ref), 0u);
  auto any_ref = trace_reference(bvh, rays, nullptr, true);
  auto any_dev = tracer.run(rays, nullptr, true);
  EXPECT_EQ(count_hit_mismatches(any_dev.hits, any_ref), 0u);
  for (std::size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(any_ref[i].tri == RS_NO_HIT, ref[i].tri == RS_NO_HIT) << i;
}

TEST(Trace, BarycentricsReconstructTheHitPoint) {
  Scene s = two_quads();
  Scene::Flat tris = s.flatten();
  Bvh bvh = build_bvh(tris);
  std::vector<RsRay> rays;
  for (int i = 0; i < 50; ++i) rays.push_back(ray(0.02f * i, 0.3f + 0.01f * i, 2.0f, 0, 0, -1));
  auto hits = trace_reference(bvh, rays, nullptr, false);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (hits[i].tri == RS_NO_HIT) continue;
    auto t = hits[i].tri;
    float w = 1.0f - hits[i].u - hits[i].v;
    for (int a = 0; a < 2; ++a) {
      float p = w * tris.v0[t][a] + hits[i].u * tris.v1[t][a] + hits[i].v * tris.v2[t][a];
      EXPECT_NEAR(p, rays[i].o[a], 1e-5f);
    }
    EXPECT_NEAR(hits[i].t, 2.0f, 1e-6f);
  }
}

TEST(Trace, EmptyBatchIsFine) {
  Scene s = two_quads();
  Bvh bvh = build_bvh(s.flatten());
  Tracer tracer(testing::runtime(), bvh);
  auto run = tracer.run({}, nullptr, false);
  EXPECT_TRUE(run.hits.empty());
}

TEST(Trace, CornellEveryBatchMatchesReference) {
  Scene scene = load_scene("cornell", {"", {96, 72, 2}});
  RayGenOptions gen;
  // primary, shadow0, bounce1, shadow1 at least.
  expect_device_equals_reference(scene, gen, 4);
}

TEST(Trace, DetailRoomEveryBatchMatchesReference) {
  Scene scene = load_scene("detail-room", {"", {64, 36, 0}});
  RayGenOptions gen;
  expect_device_equals_reference(scene, gen, 3);
}

TEST(Trace, SameCommandSameBatches) {
  Scene scene = load_scene("cornell", {"", {32, 24, 0}});
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  RayGenOptions gen;
  auto a = generate_batches(scene, tris, bvh, gen);
  auto b = generate_batches(scene, tris, bvh, gen);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].batch.rays.size(), b[i].batch.rays.size());
    EXPECT_EQ(std::memcmp(a[i].batch.rays.data(), b[i].batch.rays.data(), a[i].batch.rays.size() * sizeof(RsRay)), 0);
  }
}

TEST(Trace, SibenikPrimaryMatchesReference) {
  RAYSORT_REQUIRE_REAL_SCENES();
  Scene scene = load_scene("sibenik", {"", {80, 45, 0}});
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  RayGenOptions gen;
  auto batches = generate_batches(scene, tris, bvh, gen);
  Tracer tracer(testing::runtime(), bvh);
  for (const auto& rb : batches) {
    auto run = tracer.run(rb.batch.rays, nullptr, rb.batch.any_hit());
    EXPECT_EQ(count_hit_mismatches(run.hits, rb.reference_hits), 0u) << rb.batch.name;
  }
}

}  // namespace raysort

// The binary layout (kept for A/B, raysort trace --layout binary) matches its own host twin bit for
// bit, and finds the same hits as the 4-wide layout: the same triangle, or for closest hits an
// equally near one (a tie whose winner depends on visiting order); for shadow rays the same
// occluded/free answer.
namespace raysort {
TEST(Trace, WideAndBinaryLayoutsAgree) {
  Scene scene = load_scene("detail-room", {"", {64, 36, 0}});
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  RayGenOptions gen;
  for (TraceVariant v : {TraceVariant::Fast, TraceVariant::Robust}) {
    Tracer wide(testing::runtime(), bvh, v, TraceLayout::Wide);
    Tracer binary(testing::runtime(), bvh, v, TraceLayout::Binary);
    EXPECT_EQ(binary.layout(), TraceLayout::Binary);
    for (const auto& rb : generate_batches(scene, tris, bvh, gen)) {
      const RayBatch& b = rb.batch;
      auto w = wide.run(b.rays, nullptr, b.any_hit()).hits;
      auto bin = binary.run(b.rays, nullptr, b.any_hit()).hits;
      auto bin_ref = trace_reference(bvh, b.rays, nullptr, b.any_hit(), nullptr, v, TraceLayout::Binary);
      EXPECT_EQ(count_hit_mismatches(bin, bin_ref), 0u) << b.name;
      std::size_t disagree = 0;
      for (std::size_t i = 0; i < w.size(); ++i) {
        const bool w_hit = w[i].tri != RS_NO_HIT, b_hit = bin[i].tri != RS_NO_HIT;
        if (b.any_hit())
          disagree += w_hit != b_hit;
        else
          disagree += w[i].tri != bin[i].tri && w[i].t != bin[i].t;
      }
      EXPECT_EQ(disagree, 0u) << trace_variant_name(v) << " " << b.name;
    }
  }
}
// The packet and hybrid classes (cl/traverse_packet.h), the coherent packets (cl/traverse_coherent.h)
// and the stream class (cl/traverse_stream.h): each kernel equals its host twin bit for bit, hits and
// per-ray step counts, with packets (streams) formed from a shuffled order and a batch whose size is no
// multiple of the width (a partial last packet); and every ray's hit equals the single-ray wide
// traversal's up to ties (another triangle at exactly the same t), as between the wide and binary
// classes. Shadow rays: the same occluded / free answer. Also in the batch's own order, where packets
// load their rays and store their hits a row at a time (cl/traverse_packet.h, RS_PACKET_ROWS) and the
// coherent packets' cameras share an origin and an octant, so the frustum alone decides the inner
// nodes; and in that order rotated by 5, whose rows start off a 64-byte boundary and one wraps.
TEST(Trace, PacketKernelsEqualTheirHostTwinAndSingleRays) {
  Scene scene = load_scene("detail-room", {"", {64, 36, 0}});
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  const auto batches = generate_batches(scene, tris, bvh, RayGenOptions{});
  ASSERT_GE(batches.size(), 3u);
  Runtime& rt = testing::runtime();
  for (TraceLayout layout : {TraceLayout::Packet4, TraceLayout::Packet8, TraceLayout::Packet16, TraceLayout::Hybrid8,
                             TraceLayout::Hybrid16, TraceLayout::Coherent8, TraceLayout::Coherent16,
                             TraceLayout::Stream}) {
    for (TraceVariant v : {TraceVariant::Fast, TraceVariant::Robust}) {
      Tracer packet(rt, bvh, v, layout);
      ASSERT_EQ(packet.layout(), layout);
      const std::string what = std::string(trace_layout_name(layout)) + " " + trace_variant_name(v);
      for (const auto& rb : batches) {
        for (const std::string arrangement : {"shuffled", "in order", "rotated"}) {
          const bool any = rb.batch.any_hit();
          std::vector<RsRay> rays = rb.batch.rays;
          rays.resize(rays.size() - 3);  // a partial last packet for every width
          std::vector<std::uint32_t> order(rays.size());
          std::iota(order.begin(), order.end(), 0u);
          if (arrangement == "shuffled") std::shuffle(order.begin(), order.end(), std::mt19937(7));
          // Rotated by 5: packets of rays in a row that start off a 64-byte boundary, and one that wraps
          // from the last ray to the first (not in a row).
          if (arrangement == "rotated") std::rotate(order.begin(), order.begin() + 5, order.end());
          const std::string where = rb.batch.name + " " + arrangement;
          const auto dev = packet.run(rays, &order, any).hits;
          const auto host = trace_reference(bvh, rays, order.data(), any, nullptr, v, layout);
          EXPECT_EQ(count_hit_mismatches(dev, host), 0u) << what << " " << where;
          const auto single = trace_reference(bvh, rays, order.data(), any, nullptr, v, TraceLayout::Wide);
          std::size_t disagree = 0, hits = 0;
          for (std::size_t i = 0; i < dev.size(); ++i) {
            const bool p_hit = dev[i].tri != RS_NO_HIT, s_hit = single[i].tri != RS_NO_HIT;
            hits += p_hit;
            if (any)
              disagree += p_hit != s_hit;
            else
              disagree += dev[i].tri != single[i].tri && dev[i].t != single[i].t;
          }
          EXPECT_EQ(disagree, 0u) << what << " " << where;
          EXPECT_GT(hits, 0u) << what << " " << where;
        }
      }
      // The counted kernel: the same hits, and per ray the steps its lane was active, as the twin.
      const RayBatch& b = batches[0].batch;
      const auto n = static_cast<std::uint32_t>(b.size());
      std::vector<std::uint32_t> identity(n);
      std::iota(identity.begin(), identity.end(), 0u);
      cl::Buffer rays_buf = rt.upload("rays", b.rays), order_buf = rt.upload("order", identity);
      cl::Buffer hits_buf = rt.buffer("hits", n * sizeof(RsHit)), visits_buf = rt.buffer("visits", n * sizeof(std::uint32_t));
      packet.enqueue_counted(rays_buf, order_buf, n, hits_buf, visits_buf).wait();
      std::vector<RsHit> dev_hits;
      std::vector<std::uint32_t> dev_visits, host_visits;
      rt.download("hits", hits_buf, dev_hits, n);
      rt.download("visits", visits_buf, dev_visits, n);
      const auto host_hits = trace_reference(bvh, b.rays, nullptr, false, &host_visits, v, layout);
      EXPECT_EQ(count_hit_mismatches(dev_hits, host_hits), 0u) << what << " counted";
      EXPECT_EQ(dev_visits, host_visits) << what << " counted";
      EXPECT_GT(*std::max_element(host_visits.begin(), host_visits.end()), 1u) << what;
    }
  }
}

// A single-ray class over a tree of its own (wide8: cl/traverse_wide8.h, the 8-wide tree of
// host/bvh/wide8.cpp; cwbvh: the compressed one): each kernel equals its host twin bit for bit, hits and per-ray visit counts, both variants, closest and any hit, with
// the rays in a shuffled order; and every ray's hit equals the 4-wide single-ray traversal's up to
// ties (another triangle at exactly the same t), as between the wide and binary classes. Shadow
// rays: the same occluded / free answer. Returns the rays compared, so a caller sees it tested some.
namespace {
std::size_t expect_class_equals_twin_and_wide(const Scene& scene, TraceLayout layout) {
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  const auto batches = generate_batches(scene, tris, bvh, RayGenOptions{});
  EXPECT_GE(batches.size(), 3u) << scene.name;
  Runtime& rt = testing::runtime();
  std::size_t compared = 0;
  for (TraceVariant v : {TraceVariant::Fast, TraceVariant::Robust}) {
    Tracer wide8(rt, bvh, v, layout);
    EXPECT_EQ(wide8.layout(), layout);
    const std::string what = scene.name + " " + trace_layout_name(layout) + " " + trace_variant_name(v);
    for (const auto& rb : batches) {
      const bool any = rb.batch.any_hit();
      const std::vector<RsRay>& rays = rb.batch.rays;
      std::vector<std::uint32_t> order(rays.size());
      std::iota(order.begin(), order.end(), 0u);
      std::shuffle(order.begin(), order.end(), std::mt19937(11));
      const auto dev = wide8.run(rays, &order, any).hits;
      const auto host = trace_reference(bvh, rays, order.data(), any, nullptr, v, layout);
      EXPECT_EQ(count_hit_mismatches(dev, host), 0u) << what << " " << rb.batch.name;
      const auto single = trace_reference(bvh, rays, order.data(), any, nullptr, v, TraceLayout::Wide);
      std::size_t disagree = 0, hits = 0;
      for (std::size_t i = 0; i < dev.size(); ++i) {
        const bool w8_hit = dev[i].tri != RS_NO_HIT, w_hit = single[i].tri != RS_NO_HIT;
        hits += w8_hit;
        if (any)
          disagree += w8_hit != w_hit;
        else
          disagree += dev[i].tri != single[i].tri && dev[i].t != single[i].t;
      }
      EXPECT_EQ(disagree, 0u) << what << " " << rb.batch.name;
      EXPECT_GT(hits, 0u) << what << " " << rb.batch.name;
      compared += dev.size();
    }
    // The counted kernel: the same hits, and per ray the nodes and leaves visited, as the twin.
    const RayBatch& b = batches[0].batch;
    const auto n = static_cast<std::uint32_t>(b.size());
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::shuffle(order.begin(), order.end(), std::mt19937(13));
    cl::Buffer rays_buf = rt.upload("rays", b.rays), order_buf = rt.upload("order", order);
    cl::Buffer hits_buf = rt.buffer("hits", n * sizeof(RsHit)), visits_buf = rt.buffer("visits", n * sizeof(std::uint32_t));
    wide8.enqueue_counted(rays_buf, order_buf, n, hits_buf, visits_buf).wait();
    std::vector<RsHit> dev_hits;
    std::vector<std::uint32_t> dev_visits, host_visits, wide_visits;
    rt.download("hits", hits_buf, dev_hits, n);
    rt.download("visits", visits_buf, dev_visits, n);
    const auto host_hits = trace_reference(bvh, b.rays, order.data(), false, &host_visits, v, layout);
    EXPECT_EQ(count_hit_mismatches(dev_hits, host_hits), 0u) << what << " counted";
    EXPECT_EQ(dev_visits, host_visits) << what << " counted";
    EXPECT_GT(*std::max_element(host_visits.begin(), host_visits.end()), 1u) << what;
    trace_reference(bvh, b.rays, order.data(), false, &wide_visits, v, TraceLayout::Wide);
    const double w8 = std::accumulate(host_visits.begin(), host_visits.end(), 0.0) / n;
    const double w4 = std::accumulate(wide_visits.begin(), wide_visits.end(), 0.0) / n;
    std::printf("[ %-8s ] %-12s %-6s %s: %.2f steps per ray (4-wide: %.2f)\n", trace_layout_name(layout),
                scene.name.c_str(), trace_variant_name(v), b.name.c_str(), w8, w4);
  }
  return compared;
}
}  // namespace

TEST(Trace, Wide8KernelsEqualTheirHostTwinAndWideRays) {
  EXPECT_GT(expect_class_equals_twin_and_wide(load_scene("detail-room", {"", {64, 36, 0}}), TraceLayout::Wide8), 0u);
}

// A leaf of the 8-wide tree names its lanes of a packet it may share (RS_WIDE8_LEAF_*, cl/bvh_layout.h):
// every class that walks that tree tests a leaf's own lanes only. A hand-made tree: the root's one
// child is lanes 0-1 of packet 0 (two triangles off every ray's path), and lanes 2-3 of the packet,
// valid but no leaf's, hold the quad every ray crosses at t = 1. Walked through the lanes 0-1 leaf,
// each class misses on every ray; through a reference to lanes 2-3, each hits the quad; both variants,
// closest and any hit. (The lanes a leaf does not name change no hit in a real tree, whose other
// leaves' triangles lie outside the leaf's box, only which of two equally near triangles a ray keeps;
// so this is where a leaf test that reads another leaf's lanes shows.)
TEST(Trace, EightWideLeavesTestOnlyTheirOwnLanes) {
  auto tree = [](std::uint32_t lane, std::uint32_t lanes) {
    Wide8Bvh w;
    w.nodes.resize(1);
    w.packets.resize(1);
    RsWide8Node& n = w.nodes[0];
    std::memset(&n, 0, sizeof n);
    n.lo_x.s[0] = n.lo_y.s[0] = n.lo_z.s[0] = -10.0f;
    n.hi_x.s[0] = n.hi_y.s[0] = n.hi_z.s[0] = 10.0f;
    n.valid.s[0] = -1;
    n.child[0] = RS_WIDE8_LEAF_REF(0u, lane, lanes, 1u);
    RsTriPacket8& p = w.packets[0];
    std::memset(&p, 0, sizeof p);
    const float tri[4][9] = {{5, 5, 5, 6, 5, 5, 5, 6, 5},      // lanes 0-1: beside every ray
                             {-5, -5, 5, -6, -5, 5, -5, -6, 5},
                             {-2, -2, 1, 2, -2, 1, 2, 2, 1},   // lanes 2-3: the quad z = 1, |x|, |y| <= 2
                             {-2, -2, 1, 2, 2, 1, -2, 2, 1}};
    for (int l = 0; l < 4; ++l) {
      p.v0x.s[l] = tri[l][0], p.v0y.s[l] = tri[l][1], p.v0z.s[l] = tri[l][2];
      p.v1x.s[l] = tri[l][3], p.v1y.s[l] = tri[l][4], p.v1z.s[l] = tri[l][5];
      p.v2x.s[l] = tri[l][6], p.v2y.s[l] = tri[l][7], p.v2z.s[l] = tri[l][8];
      p.valid.s[l] = p.nondegenerate.s[l] = -1;
      p.id[l] = 10u + static_cast<std::uint32_t>(l);
    }
    for (int l = 4; l < 8; ++l) p.id[l] = RS_NO_HIT;
    w.depth = 1;
    return w;
  };
  std::vector<RsRay> rays(48);
  for (std::size_t i = 0; i < rays.size(); ++i)  // from below the quad, up through it
    rays[i] = RsRay{{0.02f * static_cast<float>(i % 7), -0.03f * static_cast<float>(i % 5), 0.0f}, 0.0f,
                    {0.01f * static_cast<float>(i % 3), 0.02f * static_cast<float>(i % 4), 1.0f}, INFINITY};
  std::vector<std::uint32_t> order(rays.size());
  std::iota(order.begin(), order.end(), 0u);
  for (const auto& [lane, lanes, want_hit] : {std::tuple{0u, 2u, false}, std::tuple{2u, 2u, true}}) {
    const Wide8Bvh w = tree(lane, lanes);
    for (int robust : {0, 1})
      for (int any : {0, 1}) {
        const std::string what = std::string(want_hit ? "lanes 2-3" : "lanes 0-1") + (robust ? " robust" : " fast") +
                                 (any ? " any hit" : " closest hit");
        std::vector<std::pair<std::string, std::vector<RsHit>>> classes;
        std::vector<RsHit> hits(rays.size());
        for (std::size_t i = 0; i < rays.size(); ++i)
          hits[i] = rs_traverse_wide8(w.nodes.data(), w.packets.data(), rays[i], robust, any, nullptr);
        classes.emplace_back("wide8", hits);
        trace_streams_on_host(w, rays, order.data(), robust, any, hits, nullptr);
        classes.emplace_back("stream", hits);
        for (int width : {8, 16}) {
          trace_coherent_on_host(width, w, rays, order.data(), robust, any, hits, nullptr);
          classes.emplace_back("coherent" + std::to_string(width), hits);
        }
        for (const auto& [name, got] : classes)
          for (std::size_t i = 0; i < rays.size(); ++i) {
            ASSERT_EQ(got[i].tri != RS_NO_HIT, want_hit) << name << ", " << what << ", ray " << i << ": triangle " << got[i].tri;
            if (want_hit) {
              EXPECT_TRUE(got[i].tri == 12u || got[i].tri == 13u) << name << ", " << what << ", ray " << i;
              EXPECT_FLOAT_EQ(got[i].t, 1.0f) << name << ", " << what << ", ray " << i;
            }
          }
      }
  }
}

TEST(Trace, Wide8SibenikEqualsItsHostTwinAndWideRays) {
  RAYSORT_REQUIRE_REAL_SCENES();
  EXPECT_GT(expect_class_equals_twin_and_wide(load_scene("sibenik", {"", {80, 45, 0}}), TraceLayout::Wide8), 0u);
}

// The binary-ww class (cl/traverse_binary_ww.h): the binary class's traversal in the while-while loop
// form visits the same nodes in the same order, so its kernels give the binary kernels' hits and
// visit counts bit for bit, and equal their host twin, on every batch, both variants.
TEST(Trace, BinaryWhileWhileEqualsBinaryBitForBit) {
  const Scene scene = load_scene("detail-room", {"", {64, 36, 0}});
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  const auto batches = generate_batches(scene, tris, bvh, RayGenOptions{});
  Runtime& rt = testing::runtime();
  for (TraceVariant v : {TraceVariant::Fast, TraceVariant::Robust}) {
    Tracer ww(rt, bvh, v, TraceLayout::BinaryWw), binary(rt, bvh, v, TraceLayout::Binary);
    for (const auto& rb : batches) {
      const std::string what = std::string(trace_variant_name(v)) + " " + rb.batch.name;
      const bool any = rb.batch.any_hit();
      const auto dev = ww.run(rb.batch.rays, nullptr, any).hits;
      EXPECT_EQ(count_hit_mismatches(dev, binary.run(rb.batch.rays, nullptr, any).hits), 0u) << what;
      std::vector<std::uint32_t> visits_ww, visits_binary;
      const auto host = trace_reference(bvh, rb.batch.rays, nullptr, any, &visits_ww, v, TraceLayout::BinaryWw);
      trace_reference(bvh, rb.batch.rays, nullptr, any, &visits_binary, v, TraceLayout::Binary);
      EXPECT_EQ(count_hit_mismatches(dev, host), 0u) << what;
      EXPECT_EQ(visits_ww, visits_binary) << what;
      const auto n = static_cast<std::uint32_t>(rb.batch.size());
      std::vector<std::uint32_t> order(n);
      std::iota(order.begin(), order.end(), 0u);
      cl::Buffer rays_buf = rt.upload("rays", rb.batch.rays), order_buf = rt.upload("order", order);
      cl::Buffer hits_buf = rt.buffer("hits", n * sizeof(RsHit)), visits_buf = rt.buffer("visits", n * sizeof(std::uint32_t));
      ww.enqueue_counted(rays_buf, order_buf, n, hits_buf, visits_buf).wait();
      std::vector<std::uint32_t> dev_visits;
      rt.download("visits", visits_buf, dev_visits, n);
      if (!any) {
        EXPECT_EQ(dev_visits, visits_binary) << what << " counted";
      }
    }
  }
}

// The cwbvh class (cl/traverse_cwbvh.h, the compressed tree of host/bvh/cwbvh.cpp): the same checks.
TEST(Trace, CwbvhKernelsEqualTheirHostTwinAndWideRays) {
  EXPECT_GT(expect_class_equals_twin_and_wide(load_scene("detail-room", {"", {64, 36, 0}}), TraceLayout::Cwbvh), 0u);
}

TEST(Trace, CwbvhSibenikEqualsItsHostTwinAndWideRays) {
  RAYSORT_REQUIRE_REAL_SCENES();
  EXPECT_GT(expect_class_equals_twin_and_wide(load_scene("sibenik", {"", {80, 45, 0}}), TraceLayout::Cwbvh), 0u);
}

TEST(Trace, TraceClassNames) {
  for (const std::string& name : trace_layout_names()) EXPECT_EQ(trace_layout_name(parse_trace_layout(name)), name);
  EXPECT_EQ(packet_width(TraceLayout::Packet16), 16);
  EXPECT_EQ(packet_width(TraceLayout::Wide), 1);
  DeviceInfo avx512, avx, gpu;
  avx512.preferred_float_width = 16, avx.preferred_float_width = 8, gpu.preferred_float_width = 1;
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Packet, avx512), TraceLayout::Packet16);
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Packet, avx), TraceLayout::Packet8);
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Packet, gpu), TraceLayout::Packet4);
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Binary, avx512), TraceLayout::Binary);
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Hybrid, avx512), TraceLayout::Hybrid16);
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Hybrid, gpu), TraceLayout::Hybrid8);
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Coherent, avx512), TraceLayout::Coherent16);
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Coherent, avx), TraceLayout::Coherent8);
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Coherent, gpu), TraceLayout::Coherent8);
  EXPECT_EQ(packet_width(TraceLayout::Coherent8), 8);
  EXPECT_EQ(parse_trace_layouts("wide,packet8,wide").size(), 2u);
  EXPECT_EQ(parse_trace_layouts("all").size(), 13u);  // every class but the unresolved packet, hybrid, coherent
  EXPECT_TRUE(loops_while_while(TraceLayout::BinaryWw));
  EXPECT_FALSE(loops_while_while(TraceLayout::Binary));
  EXPECT_EQ(tree_kind(TraceLayout::BinaryWw), TreeKind::Binary);
  EXPECT_EQ(tree_kind(TraceLayout::Cwbvh), TreeKind::Compressed8);
  EXPECT_EQ(tree_width(TraceLayout::Cwbvh), 8);
  EXPECT_FALSE(walks_wide_tree(TraceLayout::Cwbvh));
  EXPECT_EQ(packet_width(TraceLayout::Stream), RS_STREAM_CHUNK);
  EXPECT_EQ(tree_width(TraceLayout::Stream), 8);
  EXPECT_TRUE(is_stream(TraceLayout::Stream));
  EXPECT_FALSE(is_stream(TraceLayout::Packet16));
  EXPECT_EQ(packet_width(TraceLayout::Wide8), 1);
  EXPECT_EQ(tree_width(TraceLayout::Wide8), 8);
  EXPECT_EQ(tree_width(TraceLayout::Wide), 4);
  EXPECT_EQ(tree_width(TraceLayout::Packet16), 4);
  EXPECT_EQ(tree_width(TraceLayout::Coherent16), 8);
  EXPECT_EQ(packet_width(TraceLayout::Coherent16), 16);
  EXPECT_FALSE(is_stream(TraceLayout::Coherent16));
  EXPECT_EQ(tree_width(TraceLayout::Binary), 2);
  EXPECT_FALSE(walks_wide_tree(TraceLayout::Wide8));
  EXPECT_EQ(resolve_trace_layout(TraceLayout::Wide8, avx512), TraceLayout::Wide8);
  EXPECT_STREQ(trace_class_kernel_suffix(TraceLayout::Wide8), "_wide8");
  try {
    parse_trace_layout("packet32");
    ADD_FAILURE() << "packet32 accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("packet16"), std::string::npos) << e.what();
  }
}
}  // namespace raysort
