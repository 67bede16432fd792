// The Embree anchor (issue 9, docs/trace.md "Embree anchor"). With Embree (RAYSORT_HAVE_EMBREE):
// Embree's hits agree with ours on the same triangle for >= 99.9 % of the rays of every batch of
// the procedural scenes, for both traversal variants, and `raysort trace --reference embree` runs.
// Every Embree path (streams, packets; EmbreePath) reports the hits rtcIntersect1 does, up to ties,
// in the batch's order or through a permutation, including a last packet with padding lanes.
// `raysort run --embree-paths` (issue 40, item 2): every cell carries each path's figures on its
// order, read back by report and compare; a resume with other paths is refused.
// Without it: `--reference embree` and `run --embree-paths` fail with one clear message and a
// non-zero exit.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "bench/compare.h"
#include "bench/matrix.h"
#include "bench/result_set.h"
#include "bvh/bvh.h"
#include "render/batches.h"
#include "scene/load.h"
#include "test_util.h"
#include "trace/tracer.h"
#include "util/atomic_file.h"
#ifdef RAYSORT_HAVE_EMBREE
#include "embree/embree_reference.h"
#endif

namespace fs = std::filesystem;

namespace raysort {

namespace {

using raysort::testing::CliResult;
using raysort::testing::run_cli;

// `raysort run` on detail-room's bounce and shadow rays at 64x36 with HCC and Origin, both access
// modes, and `extra` (e.g. --embree-paths): 10 cells, seconds. Seven rounds each (then intervals).
std::vector<std::string> tiny_run(const std::string& out, std::vector<std::string> extra = {},
                                  const std::string& reps = "7") {
  std::vector<std::string> args{"run",     "--scenes", "detail-room",    "--resolution", "64x36",  "--batches",
                                "bounce1,shadow0", "--encoders", "hcc,origin", "--access", "gather,permute",
                                "--reps",  reps,       "--warmup",       "1",            "--max-time", "0",
                                "--out",   out};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

}  // namespace

#ifdef RAYSORT_HAVE_EMBREE

namespace {

using testing::ray;

// Every batch of the scene's pipeline, for both variants: same triangle for >= 99.9 % of rays.
void expect_agreement(const std::string& name, const FrameSize& frame) {
  SceneOptions opts;
  opts.frame = frame;
  const PreparedScene p = prepare_scene(name, opts);
  const Scene& scene = p.scene;
  const Scene::Flat& tris = p.tris;
  const Bvh& bvh = p.bvh;
  EmbreeScene embree(tris);
  bool primary = false, shadow = false, bounce = false;
  for (const ReferencedBatch& rb : generate_batches(scene, tris, bvh, {})) {
    const RayBatch& b = rb.batch;
    primary |= b.kind == BatchKind::Primary;
    shadow |= b.kind == BatchKind::Shadow;
    bounce |= b.kind == BatchKind::Bounce;
    ASSERT_GE(b.size(), 1000u) << scene.name << " " << b.name << ": too few rays for a 0.1 % tolerance";
    std::vector<RsHit> emb = embree.trace(b.rays, b.any_hit());
    for (TraceVariant v : {TraceVariant::Fast, TraceVariant::Robust}) {
      // generate_batches' reference hits are the fast variant's.
      std::vector<RsHit> ours = v == TraceVariant::Fast ? rb.reference_hits
                                                        : trace_reference(bvh, b.rays, nullptr, b.any_hit(), nullptr, v);
      HitAgreement a = compare_with_embree(ours, emb, b.any_hit());
      EXPECT_GE(a.fraction(), kEmbreeMinAgreement)
          << scene.name << " " << b.name << " " << trace_variant_name(v) << ": " << a.describe();
      // Same triangle, same distance: the ray semantics match (not just the triangle ids).
      if (!b.any_hit()) {
        EXPECT_LT(a.max_rel_dt, 1e-4) << scene.name << " " << b.name << " " << trace_variant_name(v);
      }
      std::size_t hits = 0;
      for (const RsHit& h : ours) hits += h.tri != RS_NO_HIT;
      if (!b.any_hit()) {
        EXPECT_GT(hits, 0u) << scene.name << " " << b.name << ": a batch that hits nothing tests little";
      }
    }
  }
  EXPECT_TRUE(primary && shadow && bounce) << scene.name << ": expected primary, shadow and bounce batches";
}

// A seeded permutation of 0..n-1: the order a sorted batch would be traced in.
std::vector<std::uint32_t> shuffled_order(std::size_t n, unsigned seed) {
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  return order;
}

// hits[i] belongs to rays[order[i]]: back into ray order.
std::vector<RsHit> in_ray_order(const std::vector<RsHit>& hits, const std::vector<std::uint32_t>& order) {
  std::vector<RsHit> out(hits.size());
  for (std::size_t i = 0; i < hits.size(); ++i) out[order[i]] = hits[i];
  return out;
}

// Every path's hits on every batch of the scene agree with rtcIntersect1's on the same triangle for
// >= 99.9 % of the rays (which triangle wins a tie may depend on the traversal), at the same t, in
// the batch's order and through a shuffled order. `frame` makes batches that are not a multiple of
// 16 rays, so that the last packet has padding lanes, and longer than one 4096-ray chunk.
void expect_paths_agree(const std::string& name, const FrameSize& frame) {
  SceneOptions opts;
  opts.frame = frame;
  const PreparedScene p = prepare_scene(name, opts);
  EmbreeScene embree(p.tris, 2);
  bool primary = false, shadow = false, bounce = false, padded = false;
  for (const ReferencedBatch& rb : generate_batches(p.scene, p.tris, p.bvh, {})) {
    const RayBatch& b = rb.batch;
    primary |= b.kind == BatchKind::Primary;
    shadow |= b.kind == BatchKind::Shadow;
    bounce |= b.kind == BatchKind::Bounce;
    padded |= b.size() % 16 != 0;
    ASSERT_GE(b.size(), 1000u) << p.scene.name << " " << b.name << ": too few rays for a 0.1 % tolerance";
    const std::vector<RsHit> single = embree.trace(b.rays, b.any_hit());
    const std::vector<std::uint32_t> order = shuffled_order(b.size(), 7);
    for (const EmbreePathInfo& info : kEmbreePaths) {
      for (bool permuted : {false, true}) {
        const std::string what = p.scene.name + " " + b.name + " " + embree_path_name(info.path, b.any_hit()) +
                                 (permuted ? " (shuffled order)" : "");
        const std::vector<RsHit> hits = permuted ? in_ray_order(embree.trace(b.rays, b.any_hit(), info.path, order), order)
                                                 : embree.trace(b.rays, b.any_hit(), info.path);
        ASSERT_EQ(hits.size(), b.size()) << what;
        const HitAgreement a = compare_with_embree(single, hits, b.any_hit());
        EXPECT_GE(a.fraction(), kEmbreeMinAgreement) << what << ": " << a.describe();
        if (!b.any_hit()) {
          EXPECT_LT(a.max_rel_dt, 1e-6) << what;
        }
        // A miss carries the ray's tmax, an occluded shadow ray t = 0, as rtcIntersect1's do.
        std::size_t wrong_t = 0, first_wrong = 0;
        for (std::size_t i = 0; i < hits.size(); ++i) {
          const bool ok = hits[i].tri == RS_NO_HIT         ? hits[i].t == b.rays[i].tmax
                          : hits[i].tri == kEmbreeOccluded ? hits[i].t == 0.0f
                                                           : true;
          if (!ok && wrong_t++ == 0) first_wrong = i;
        }
        EXPECT_EQ(wrong_t, 0u) << what << ": misses or occluded rays with another t, the first ray " << first_wrong;
      }
    }
  }
  EXPECT_TRUE(primary && shadow && bounce) << p.scene.name << ": expected primary, shadow and bounce batches";
  EXPECT_TRUE(padded) << p.scene.name << ": no batch with a partial last packet";
}

}  // namespace

TEST(Embree, PathTableParsesAndNames) {
  // One row per path, keys unique.
  for (std::size_t i = 0; i < std::size(kEmbreePaths); ++i)
    for (std::size_t j = i + 1; j < std::size(kEmbreePaths); ++j) {
      EXPECT_NE(kEmbreePaths[i].path, kEmbreePaths[j].path) << i << " " << j;
      EXPECT_NE(std::string(kEmbreePaths[i].key), kEmbreePaths[j].key) << i << " " << j;
    }
  const std::vector<EmbreePath> all = parse_embree_paths("all");
  ASSERT_EQ(all.size(), std::size(kEmbreePaths));
  for (std::size_t i = 0; i < all.size(); ++i) EXPECT_EQ(all[i], kEmbreePaths[i].path);
  EXPECT_EQ(parse_embree_paths("1"), std::vector<EmbreePath>{EmbreePath::Single});
  EXPECT_EQ(parse_embree_paths("16,1M-coherent,16,4"),
            (std::vector<EmbreePath>{EmbreePath::Packet16, EmbreePath::StreamCoherent, EmbreePath::Packet4}));
  EXPECT_EQ(embree_path_name(EmbreePath::Single, false), "rtcIntersect1");
  EXPECT_EQ(embree_path_name(EmbreePath::Single, true), "rtcOccluded1");
  EXPECT_EQ(embree_path_name(EmbreePath::StreamIncoherent, false), "rtcIntersect1M incoherent");
  EXPECT_EQ(embree_path_name(EmbreePath::StreamCoherent, true), "rtcOccluded1M coherent");
  EXPECT_EQ(embree_path_name(EmbreePath::Packet16, false), "rtcIntersect16 incoherent");
  EXPECT_EQ(embree_path_name(EmbreePath::Packet8Coherent, true), "rtcOccluded8 coherent");
  EXPECT_EQ(embree_path_calls(EmbreePath::Single), "rtcIntersect1 / rtcOccluded1");
  try {
    parse_embree_paths("1,17");
    ADD_FAILURE() << "17 is no Embree path";
  } catch (const Error& e) {
    const std::string msg = e.what();
    for (const char* part : {"unknown Embree path '17'", "1M-coherent (rtcIntersect1M coherent)", "16-coherent", "or all"})
      EXPECT_NE(msg.find(part), std::string::npos) << part << " not in " << msg;
  }
  EXPECT_THROW(parse_embree_paths(","), Error);
}

// 37 rays that all hit: the packets of 4, 8 and 16 rays each end with a partial one (1, 5 and 5
// real lanes, the rest padding), whose rays must be traced like the others. Every path gives
// rtcIntersect1's triangle, t, u and v for every ray, and its occluded answer; through a
// permutation too.
TEST(Embree, EveryPathTracesAPartialLastPacket) {
  Scene::Flat tris = testing::two_quads().flatten();
  EmbreeScene embree(tris, 2);
  std::vector<RsRay> rays;
  for (int i = 0; i < 37; ++i) {
    // Points of the front quad's triangles off their shared diagonal (x = y), alternating sides.
    const float a = 0.05f + 0.02f * static_cast<float>(i % 20), b = a + 0.3f;
    rays.push_back(i % 2 ? testing::ray(a, b, 1.0f, 0, 0, -1) : testing::ray(b, a, 1.0f, 0, 0, -1));
  }
  rays[36] = testing::ray(0.5f, 0.45f, -3.0f, 0, 0, 1);  // the last lane, from behind: the back quad at t = 2
  const std::vector<std::uint32_t> order = shuffled_order(rays.size(), 3);
  for (bool any_hit : {false, true}) {
    const std::vector<RsHit> single = embree.trace(rays, any_hit);
    for (const RsHit& h : single) ASSERT_NE(h.tri, RS_NO_HIT) << "every ray should hit";
    for (const EmbreePathInfo& info : kEmbreePaths) {
      for (bool permuted : {false, true}) {
        const std::vector<RsHit> hits = permuted ? in_ray_order(embree.trace(rays, any_hit, info.path, order), order)
                                                 : embree.trace(rays, any_hit, info.path);
        ASSERT_EQ(hits.size(), rays.size());
        for (std::size_t i = 0; i < rays.size(); ++i) {
          const std::string what = embree_path_name(info.path, any_hit) + (permuted ? " (shuffled)" : "") + " ray " +
                                   std::to_string(i);
          EXPECT_EQ(hits[i].tri, single[i].tri) << what;
          EXPECT_NEAR(hits[i].t, single[i].t, 1e-6f) << what;
          EXPECT_NEAR(hits[i].u, single[i].u, 1e-6f) << what;
          EXPECT_NEAR(hits[i].v, single[i].v, 1e-6f) << what;
        }
      }
    }
  }
  // An order that is not a permutation of the rays is refused, not read past.
  EXPECT_THROW(embree.trace(rays, false, EmbreePath::Packet8, std::vector<std::uint32_t>(36, 0u)), Error);
  std::vector<std::uint32_t> bad = order;
  bad[5] = 37;
  EXPECT_THROW(embree.trace(rays, false, EmbreePath::Packet8, bad), Error);
  EXPECT_TRUE(embree.trace({}, false, EmbreePath::Packet16).empty());
}

// --embree-isa: Embree held to an instruction set runs that set's kernels, not the widest the CPU
// has. Under SSE2 no packet wider than 4 rays is native (RTC_DEVICE_PROPERTY_NATIVE_RAY8/16), under
// AVX2 none of 16, whatever CPU runs the test; the hits stay rtcIntersect1's on a native device.
// An unknown set is refused with the list; a set the CPU lacks, with the set named.
TEST(Embree, InstructionSetIsHeldWhereAsked) {
  for (const char* isa : kEmbreeIsas) EXPECT_NO_THROW(check_embree_isa(isa)) << isa;
  try {
    check_embree_isa("avx3");
    ADD_FAILURE() << "avx3 is no instruction set of Embree's";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown Embree instruction set 'avx3' in --embree-isa; the sets are native, "
                                         "sse2, sse4.2, avx, avx2, avx512"),
              std::string::npos) << e.what();
  }
  EXPECT_THROW(EmbreeScene(Scene::Flat{}, 1, "avx3"), Error);
  const Scene::Flat tris = testing::two_quads().flatten();
  std::vector<RsRay> rays;
  for (int i = 0; i < 37; ++i) {
    const float a = 0.05f + 0.02f * static_cast<float>(i % 20), b = a + 0.3f;
    rays.push_back(i % 2 ? testing::ray(a, b, 1.0f, 0, 0, -1) : testing::ray(b, a, 1.0f, 0, 0, -1));
  }
  const EmbreeScene native(tris, 2);
  EXPECT_EQ(native.isa(), "native");
  const EmbreeScene sse2(tris, 2, "sse2");
  EXPECT_EQ(sse2.isa(), "sse2");
  EXPECT_TRUE(sse2.native_packets(4));
  EXPECT_FALSE(sse2.native_packets(8)) << "Embree held to SSE2 still runs 8-ray packets natively";
  EXPECT_FALSE(sse2.native_packets(16));
  const std::vector<RsHit> expected = native.trace(rays, false);
  for (const EmbreePathInfo& info : kEmbreePaths) {
    const std::vector<RsHit> hits = sse2.trace(rays, false, info.path);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      EXPECT_EQ(hits[i].tri, expected[i].tri) << info.key << " ray " << i;
      EXPECT_NEAR(hits[i].t, expected[i].t, 1e-6f) << info.key << " ray " << i;
    }
  }
  try {
    const EmbreeScene avx2(tris, 2, "avx2");
    EXPECT_FALSE(avx2.native_packets(16)) << "Embree held to AVX2 still runs 16-ray packets natively";
  } catch (const Error& e) {  // a CPU without AVX2: refused, naming the set
    EXPECT_NE(std::string(e.what()).find("--embree-isa avx2: this CPU does not run it"), std::string::npos) << e.what();
  }
}

TEST(Embree, EveryPathAgreesWithRtcIntersect1OnCornell) {
  expect_paths_agree("cornell", {97, 71, 2});
}

TEST(Embree, EveryPathAgreesWithRtcIntersect1OnDetailRoom) {
  expect_paths_agree("detail-room", {161, 89, 0});
}

TEST(Embree, HandCheckedRaysMatchOurs) {
  Scene::Flat tris = testing::two_quads().flatten();
  Bvh bvh = build_bvh(tris);
  EmbreeScene embree(tris, 2);
  EXPECT_EQ(embree.threads(), 2u);
  std::vector<RsRay> rays = {
      ray(0.3f, 0.6f, 1.0f, 0, 0, -1),             // front quad at t = 1
      ray(0.6f, 0.3f, -2.0f, 0, 0, 1),             // from behind (two-sided): back quad at t = 1
      ray(2.0f, 2.0f, 1.0f, 0, 0, -1),             // misses
      ray(0.3f, 0.6f, 1.0f, 0, 0, -1, 0.5f),       // tmax before the front quad: miss
      ray(0.3f, 0.6f, 1.0f, 0, 0, -1, RS_T_FAR, 1.5f),  // tmin past the front quad: the back one at t = 2
      ray(0.3f, 0.4f, 1.0f, 0, 0, -1, 1.8f, 1.5f),  // both quads outside (tmin, tmax): miss
      ray(0.1f, 0.9f, 5.0f, -0.0f, 0.0f, -1),      // axis-parallel with a -0 component
      ray(0.5f, 0.5f, 0.5f, 0, 0, 1),              // pointing away: miss
  };
  for (TraceVariant v : {TraceVariant::Fast, TraceVariant::Robust}) {
    std::vector<RsHit> ours = trace_reference(bvh, rays, nullptr, false, nullptr, v);
    std::vector<RsHit> emb = embree.trace(rays, false);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      EXPECT_EQ(ours[i].tri, emb[i].tri) << "ray " << i << " " << trace_variant_name(v);
      if (ours[i].tri != RS_NO_HIT && ours[i].tri == emb[i].tri) {
        EXPECT_NEAR(ours[i].t, emb[i].t, 1e-6f) << "ray " << i;
        EXPECT_NEAR(ours[i].u, emb[i].u, 1e-6f) << "ray " << i;
        EXPECT_NEAR(ours[i].v, emb[i].v, 1e-6f) << "ray " << i;
      }
    }
    // Within 4 ulps, not exactly: Embree 3.13.5's AVX2 kernels (the ISA it picks on an AMD EPYC
    // without AVX-512) give 1.99999988 here, one ulp below 2.
    EXPECT_FLOAT_EQ(emb[4].t, 2.0f);
    HitAgreement a = compare_with_embree(ours, emb, false);
    EXPECT_EQ(a.same, rays.size()) << a.describe();
    // Shadow rays: occluded or not, as ours says.
    std::vector<RsHit> ours_any = trace_reference(bvh, rays, nullptr, true, nullptr, v);
    std::vector<RsHit> emb_any = embree.trace(rays, true);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      EXPECT_EQ(ours_any[i].tri != RS_NO_HIT, emb_any[i].tri != RS_NO_HIT) << "shadow ray " << i;
      EXPECT_TRUE(emb_any[i].tri == RS_NO_HIT || emb_any[i].tri == kEmbreeOccluded);
    }
  }
}

TEST(Embree, AgreementCountsEveryKind) {
  // same; tie inside both triangles; tie on an edge (u or v or 1-u-v = 0); other triangle farther;
  // ours hit / Embree missed; Embree hit / ours missed; both missed.
  std::vector<RsHit> ours = {{1, 0, 0.2f, 0.2f}, {1, 1, 0.3f, 0.3f}, {1, 5, 0.0f, 0.5f}, {1, 1, 0.3f, 0.3f},
                             {1, 2, 0.2f, 0.2f}, {9, RS_NO_HIT, 0, 0},      {9, RS_NO_HIT, 0, 0}};
  std::vector<RsHit> emb = {{1, 0, 0.2f, 0.2f}, {1, 2, 0.3f, 0.3f}, {1, 6, 0.5f, 0.0f}, {2, 3, 0.3f, 0.3f},
                            {9, RS_NO_HIT, 0, 0}, {3, 4, 0.2f, 0.2f},     {9, RS_NO_HIT, 0, 0}};
  HitAgreement a = compare_with_embree(ours, emb, false);
  EXPECT_EQ(a.rays, 7u);
  EXPECT_EQ(a.same, 2u);
  EXPECT_EQ(a.tie_overlap, 1u);
  EXPECT_EQ(a.tie_edge, 1u);
  EXPECT_EQ(a.other_tri, 1u);
  EXPECT_EQ(a.ours_only, 1u);
  EXPECT_EQ(a.embree_only, 1u);
  EXPECT_EQ(a.differences(), 5u);
  EXPECT_DOUBLE_EQ(a.fraction_with_ties(), 4.0 / 7.0);
  EXPECT_NE(a.describe().find("shared edge"), std::string::npos) << a.describe();
  EXPECT_NE(a.describe().find("coplanar"), std::string::npos) << a.describe();
  HitAgreement s = compare_with_embree(ours, emb, true);  // shadow: only occluded vs free counts
  EXPECT_EQ(s.same, 5u);
  EXPECT_EQ(s.ours_only, 1u);
  EXPECT_EQ(s.embree_only, 1u);
}

TEST(Embree, CornellAgreesOnPrimaryShadowAndBounce) {
  expect_agreement("cornell", {96, 72, 2});
}

TEST(Embree, DetailRoomAgreesOnPrimaryShadowAndBounce) {
  expect_agreement("detail-room", {160, 90, 0});
}

TEST(Embree, TraceCommandComparesWithEmbree) {
  CliResult r = run_cli({"trace", "--scene", "cornell", "--resolution", "64x48", "--variant", "both", "--reps", "1",
                         "--reference", "embree"});
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("Embree 3."), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("+ties %"), std::string::npos) << r.out;
}

// run --embree-paths (issue 40, item 2): every cell's rounds hold each path's NoSort-order arm,
// every sorted cell its sorted-order arm too; the cells carry each path's figures (paired speedup
// with an interval around it, both arms' medians, the calls, flags and threads), reproduced from
// their own samples; cells.csv, tables.md and meta.json show them; report and compare read them.
TEST(EmbreeRun, CellsCarryEachPathsFiguresReadByReportAndCompare) {
  const std::string out = testing::temp_path("embree-run");
  CliResult r = run_cli(tiny_run(out, {"--embree-paths", "1,16-coherent"}));
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const ResultSet set = ResultSet::load(out);
  ASSERT_EQ(set.cells().size(), 10u);
  const std::vector<std::string> paths{"1", "16-coherent"};
  std::size_t sorted_cells = 0;
  for (const CellRecord& c : set.cells()) {
    ASSERT_TRUE(c.ok()) << c.id() << ": " << c.error;
    ASSERT_EQ(c.embree.size(), paths.size()) << c.id();
    const bool nosort = c.encoder == kBaselineEncoder;
    sorted_cells += !nosort;
    for (std::size_t k = 0; k < paths.size(); ++k) {
      const CellRecord::EmbreeFigures& e = c.embree[k];
      const std::string what = c.id() + " Embree " + paths[k];
      EXPECT_EQ(e.path, paths[k]) << what;
      EXPECT_EQ(e.call.rfind(c.batch == "shadow0" ? "rtcOccluded" : "rtcIntersect", 0), 0u) << what << ": " << e.call;
      EXPECT_EQ(e.call.find("coherent") != std::string::npos, paths[k] == "16-coherent") << what << ": " << e.call;
      EXPECT_GE(e.threads, 1u) << what;
      EXPECT_EQ(e.nosort.n, c.rounds) << what;
      EXPECT_GT(e.nosort.median_ms, 0.0) << what;
      EXPECT_GE(e.agreement_with_ours, kEmbreeMinAgreement) << what;
      EXPECT_EQ(c.samples.at("embree:" + paths[k] + ":nosort").size(), c.rounds) << what;
      if (nosort) {
        EXPECT_EQ(e.trace.n, 0u) << what;
        EXPECT_FALSE(e.speedup.has_value()) << what;
        continue;
      }
      EXPECT_EQ(e.trace.n, c.rounds) << what;
      EXPECT_EQ(e.differ, 0u) << what;
      EXPECT_EQ(c.samples.at("embree:" + paths[k] + ":trace").size(), c.rounds) << what;
      ASSERT_TRUE(e.speedup.has_interval()) << what;
      EXPECT_LE(e.speedup.lo, e.speedup.value) << what;
      EXPECT_LE(e.speedup.value, e.speedup.hi) << what;
      if (!c.same_order_as_nosort) {
        const Estimate again =
            ratio_interval(c.samples.at("embree:" + paths[k] + ":nosort"), c.samples.at("embree:" + paths[k] + ":trace"));
        EXPECT_DOUBLE_EQ(e.speedup.value, again.value) << what;
      }
    }
  }
  EXPECT_EQ(sorted_cells, 8u);
  // meta.json: the paths are part of the matrix; each path's calls, flag and threads beside it.
  const nlohmann::json meta = nlohmann::json::parse(read_file(out + "/meta.json"));
  EXPECT_EQ(meta["matrix"]["embree_paths"], nlohmann::json(paths));
  ASSERT_TRUE(meta.contains("embree")) << meta.dump(1);
  EXPECT_GE(meta["embree"]["threads"].get<unsigned>(), 1u);
  EXPECT_EQ(meta["embree"]["paths"][1]["closest_hit"], "rtcIntersect16 coherent");
  EXPECT_EQ(meta["embree"]["paths"][1]["context_flag"], "RTC_INTERSECT_CONTEXT_FLAG_COHERENT");
  // cells.csv: each path's columns, the values the records hold.
  const std::string csv = read_file(out + "/cells.csv");
  const std::string header = csv.substr(0, csv.find('\n')) + ",";
  for (const std::string column : {"embree_1_speedup", "embree_1_speedup_lo", "embree_1_speedup_hi", "embree_1_ms",
                                   "embree_1_nosort_ms", "embree_16-coherent_speedup", "embree_16-coherent_mrays",
                                   "embree_16-coherent_nosort_mrays"})
    EXPECT_NE(header.find("," + column + ","), std::string::npos) << column << " not in " << header;
  const CellRecord* hcc = set.find("detail-room/bounce1/hcc/32/permute");
  ASSERT_NE(hcc, nullptr);
  EXPECT_NE(csv.find(fmt::format("{:.4f}", hcc->embree_path("16-coherent")->speedup.value)), std::string::npos);
  // tables.md: the section, per access mode, a row per scene, batch and path.
  const std::string tables = read_file(out + "/tables.md");
  EXPECT_NE(tables.find("## Embree on sorted orders, 32-bit keys, access gather"), std::string::npos) << tables;
  EXPECT_NE(tables.find("## Embree on sorted orders, 32-bit keys, access permute"), std::string::npos) << tables;
  EXPECT_NE(tables.find("| detail-room bounce1 | 16-coherent |"), std::string::npos) << tables;
  EXPECT_NE(tables.find("rtcOccluded16 coherent"), std::string::npos) << tables;
  // report writes the same views from the cell files alone.
  std::filesystem::remove(out + "/tables.md");
  std::filesystem::remove(out + "/cells.csv");
  ASSERT_EQ(run_cli({"report", out}).code, 0);
  EXPECT_EQ(read_file(out + "/tables.md"), tables);
  EXPECT_EQ(read_file(out + "/cells.csv"), csv);
  // compare tabulates a path's speedup with its interval and checks rules on it.
  const std::string copy = testing::temp_path("embree-run-copy");
  std::filesystem::copy(out, copy, std::filesystem::copy_options::recursive);
  CliResult cmp = run_cli({"compare", out, copy, "--metrics", "embree_16-coherent_speedup,embree_1_nosort_ms",
                           "--fail-if", "embree_16-coherent_speedup<-5%", "--fail-if", "embree_1_ms!="});
  EXPECT_EQ(cmp.code, 0) << cmp.out << cmp.err;
  EXPECT_NE(cmp.out.find("## embree_16-coherent_speedup"), std::string::npos) << cmp.out;
  EXPECT_NE(cmp.out.find(fmt::format("| detail-room/bounce1/hcc/32/permute | {:.4g} [", hcc->embree_path("16-coherent")->speedup.value)),
            std::string::npos)
      << cmp.out;
}

// The paths are part of the matrix: a resume with other paths, or none, is refused as another
// matrix; the same paths in another order are the same matrix (nothing to run again).
TEST(EmbreeRun, ResumeWithOtherPathsIsRefused) {
  const std::string out = testing::temp_path("embree-resume");
  ASSERT_EQ(run_cli(tiny_run(out, {"--embree-paths", "1,16-coherent"}, "1")).code, 0);
  for (const std::vector<std::string>& other :
       {std::vector<std::string>{"--embree-paths", "1"}, std::vector<std::string>{},
        std::vector<std::string>{"--embree-paths", "1,16-coherent,8"}}) {
    CliResult r = run_cli(tiny_run(out, other, "1"));
    EXPECT_EQ(r.code, 1) << r.out << r.err;
    EXPECT_NE(r.err.find("different matrix configuration (embree_paths"), std::string::npos) << r.err;
  }
  CliResult same = run_cli(tiny_run(out, {"--embree-paths", "16-coherent,1"}, "1"));
  EXPECT_EQ(same.code, 0) << same.err;
  EXPECT_NE(same.out.find("0 cells run, 10 already done"), std::string::npos) << same.out;
}

// --embree-isa in run: the instruction set is part of the matrix (a resume with another is another
// matrix; native, the default, adds no entry) and meta.json's Embree section names it; without
// --embree-paths, or unknown, it is refused before any work.
TEST(EmbreeRun, InstructionSetIsPartOfTheMatrix) {
  const std::string out = testing::temp_path("embree-isa");
  CliResult r = run_cli(tiny_run(out, {"--embree-paths", "8", "--embree-isa", "sse2"}, "1"));
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE((r.out + r.err).find("(held to sse2)"), std::string::npos) << r.out << r.err;
  const nlohmann::json meta = nlohmann::json::parse(read_file(out + "/meta.json"));
  EXPECT_EQ(meta["matrix"]["embree_isa"], "sse2");
  EXPECT_NE(meta["embree"]["isa"].get<std::string>().find("isa=sse2"), std::string::npos) << meta["embree"].dump();
  EXPECT_EQ(meta["embree"]["paths"][0]["native"], false) << "8-ray packets under SSE2";
  CliResult other = run_cli(tiny_run(out, {"--embree-paths", "8"}, "1"));
  EXPECT_EQ(other.code, 1) << other.out << other.err;
  EXPECT_NE(other.err.find("different matrix configuration (embree_isa"), std::string::npos) << other.err;
  const std::string none = testing::temp_path("embree-isa-none");
  CliResult alone = run_cli(tiny_run(none, {"--embree-isa", "avx2"}));
  EXPECT_EQ(alone.code, 1);
  EXPECT_NE(alone.err.find("--embree-isa avx2 sets the instruction set of Embree's arms: give --embree-paths too"),
            std::string::npos) << alone.err;
  CliResult bad = run_cli(tiny_run(none, {"--embree-paths", "1", "--embree-isa", "avx3"}));
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find("unknown Embree instruction set 'avx3' in --embree-isa"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(none)) << "refused before the result set was made";
}

// An unknown path is refused before any work, naming the paths; the NoSort-only default adds no
// entry to the matrix (sets written without the option resume).
TEST(EmbreeRun, UnknownPathsAreRefusedBeforeWork) {
  const std::string out = testing::temp_path("embree-bad");
  CliResult r = run_cli(tiny_run(out, {"--embree-paths", "1,17"}));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("unknown Embree path '17' in --embree-paths; the paths are 1 (rtcIntersect1)"), std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(out)) << "refused before the result set was made";
}

#else  // no Embree in this build

TEST(Embree, TraceRefusesWithoutEmbree) {
  CliResult r = run_cli({"trace", "--scene", "cornell", "--resolution", "32x18", "--reference", "embree"});
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("this build has no Embree: install libembree-dev and reconfigure"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("batch"), std::string::npos) << "refused before any tracing:\n" << r.out;
}

TEST(EmbreeRun, RunRefusesEmbreePathsWithoutEmbree) {
  const std::string out = testing::temp_path("embree-none");
  CliResult r = run_cli(tiny_run(out, {"--embree-paths", "1"}));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("--embree-paths: this build has no Embree: install libembree-dev and reconfigure"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(out)) << "refused before the result set was made";
  // The same for a matrix made in code (run_matrix's own check).
  MatrixSpec spec;
  spec.scenes = {"cornell"};
  spec.embree_paths = {"1"};
  EXPECT_THROW(validate_matrix(spec), Error);
}

#endif

}  // namespace raysort
