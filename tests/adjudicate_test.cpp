// The exact oracle (issue 23): hand-made cases with known truths, and the replay of the rays on
// which the variants and Embree disagreed on the real scenes at 1920×1080 (tests/data/
// disagreements, written by `raysort trace --adjudicate --disagreements`): the robust variant,
// on the device and its host twin, on both BVH layouts, must give no wrong answer on them.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "bvh/prepared_scene.h"
#include "test_util.h"
#include "trace/adjudicate.h"
#include "trace/exact_oracle.h"
#include "trace/order_agreement.h"
#include "trace/tracer.h"
#include "util/atomic_file.h"

namespace fs = std::filesystem;
using namespace raysort;

namespace {

RsHit answer(std::uint32_t tri, float t = 1.0f) { return RsHit{t, tri, 0.0f, 0.0f}; }

}  // namespace

// two_quads (test_util.h): the unit quad at z = 0 (triangles 0 and 1, split along the diagonal
// (0,0)-(1,1)) and a smaller quad at z = -1 (triangles 2 and 3).
TEST(ExactOracle, HandMadeTruths) {
  const Scene scene = raysort::testing::two_quads();
  const Scene::Flat tris = scene.flatten();
  const Bvh bvh = build_bvh(tris);
  const ExactOracle oracle(tris, bvh);
  using raysort::testing::ray;

  // Through the middle of triangle 0 ((0,0),(1,0),(1,1)): right only for triangle 0.
  const ExactTruth inside = oracle.truth(ray(0.75f, 0.25f, 1, 0, 0, -1), false);
  ASSERT_TRUE(inside.hit());
  EXPECT_EQ(inside.nearest_count(), 1u);
  EXPECT_EQ(inside.nearest_t(), 1.0);
  EXPECT_EQ(ExactOracle::judge(inside, answer(0)), Verdict::Right);
  EXPECT_EQ(ExactOracle::judge(inside, answer(2, 2.0f)), Verdict::Wrong);  // the quad behind it
  EXPECT_EQ(ExactOracle::judge(inside, answer(RS_NO_HIT)), Verdict::Wrong);
  EXPECT_EQ(ExactOracle::judge(inside, answer(1)), Verdict::Wrong);  // the neighbour, clearly missed

  // Exactly through the shared diagonal: both triangles at the same t, either is a tie; slipping
  // through the crack onto the quad behind is a leak: wrong.
  const ExactTruth diagonal = oracle.truth(ray(0.5f, 0.5f, 1, 0, 0, -1), false);
  EXPECT_EQ(diagonal.nearest_count(), 2u);
  EXPECT_EQ(ExactOracle::judge(diagonal, answer(0)), Verdict::Tie);
  EXPECT_EQ(ExactOracle::judge(diagonal, answer(1)), Verdict::Tie);
  EXPECT_EQ(ExactOracle::judge(diagonal, answer(3, 2.0f)), Verdict::Wrong);
  EXPECT_EQ(ExactOracle::judge(diagonal, answer(RS_NO_HIT)), Verdict::Wrong);

  // Outside everything: a miss is right, any hit wrong.
  const ExactTruth outside = oracle.truth(ray(2, 2, 1, 0, 0, -1), false);
  EXPECT_FALSE(outside.hit());
  EXPECT_EQ(ExactOracle::judge(outside, answer(RS_NO_HIT)), Verdict::Right);
  EXPECT_EQ(ExactOracle::judge(outside, answer(0)), Verdict::Wrong);

  // Grazing the quad's outer edge x = 1 from outside by one float ulp: a hit there is a tie.
  const ExactTruth graze = oracle.truth(ray(std::nextafter(1.0f, 2.0f), 0.5f, 1, 0, 0, -1), false);
  EXPECT_FALSE(graze.hit());
  EXPECT_EQ(ExactOracle::judge(graze, answer(0)), Verdict::Tie);
  EXPECT_EQ(ExactOracle::judge(graze, answer(RS_NO_HIT)), Verdict::Right);

  // tmax before the quad: nothing in (tmin, tmax). A shadow ray's occluded/free answer.
  const ExactTruth short_ray = oracle.truth(ray(0.75f, 0.25f, 1, 0, 0, -1, 0.5f), true);
  EXPECT_FALSE(short_ray.hit());
  EXPECT_EQ(ExactOracle::judge(short_ray, answer(RS_NO_HIT)), Verdict::Right);
  EXPECT_EQ(ExactOracle::judge(short_ray, answer(0)), Verdict::Wrong);
  const ExactTruth shadow = oracle.truth(ray(0.75f, 0.25f, 1, 0, 0, -1, 1.5f), true);
  EXPECT_EQ(ExactOracle::judge(shadow, answer(7)), Verdict::Right);  // occluded (any id)
  EXPECT_EQ(ExactOracle::judge(shadow, answer(RS_NO_HIT)), Verdict::Wrong);

  // A ray in the quad's plane: no area to hit.
  EXPECT_FALSE(oracle.truth(ray(-1, 0.5f, 0, 1, 0, 0), false).hit());
}

// Rays are stored as exact hexadecimal floats.
TEST(ExactOracle, RaysRoundTripThroughJson) {
  std::vector<RsRay> rays{raysort::testing::ray(0.1f, -3e-38f, 1e30f, 0x1.cf93c6p+0f, -0.0f, 1, RS_T_FAR, 1e-7f)};
  const std::vector<RsRay> back = rays_from_json(rays_to_json(rays));
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(std::memcmp(&back[0], &rays[0], sizeof(RsRay)), 0);
  EXPECT_THROW(rays_from_json(nlohmann::json::array({"1 2 3"})), Error);
}

// The replay: every telling ray of the 1920×1080 adjudication of sibenik and breakfast_room, on the
// single-ray classes (4-wide, 8-wide, binary) and in packets of 8 and 16 of those rays.
TEST(ExactOracle, RobustHasNoWrongAnswerOnTheRecordedDisagreements) {
  RAYSORT_REQUIRE_REAL_SCENES();
  const fs::path dir = fs::path(RAYSORT_SOURCE_DIR) / "tests" / "data" / "disagreements";
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    const nlohmann::json record = nlohmann::json::parse(read_file(entry.path().string()));
    SceneOptions opts;
    opts.frame = {16, 16, 1};  // the rays are stored; the frame only sizes what is not used here
    const PreparedScene p = prepare_scene(record.at("scene").get<std::string>(), opts);
    const ExactOracle oracle(p.tris, p.bvh);
    for (const auto& batch : record.at("batches")) {
      const std::vector<RsRay> rays = rays_from_json(batch.at("rays"));
      const bool any_hit = batch.at("any_hit").get<bool>();
      for (TraceLayout layout :
           {TraceLayout::Wide, TraceLayout::Wide8, TraceLayout::Binary, TraceLayout::Packet8, TraceLayout::Packet16,
            TraceLayout::Coherent16, TraceLayout::Stream, TraceLayout::Cwbvh}) {
        const auto host = trace_reference(p.bvh, rays, nullptr, any_hit, nullptr, TraceVariant::Robust, layout);
        const auto dev =
            Tracer(raysort::testing::runtime(), p.bvh, TraceVariant::Robust, layout).run(rays, nullptr, any_hit).hits;
        EXPECT_EQ(count_hit_mismatches(dev, host), 0u) << entry.path() << " " << batch.at("name");
        VerdictCounts c;
        for (std::size_t i = 0; i < rays.size(); ++i) {
          const Verdict v = ExactOracle::judge(oracle.truth(rays[i], any_hit), dev[i]);
          c.add(v);
          if (v == Verdict::Wrong && c.wrong <= 3)
            ADD_FAILURE() << record["scene"] << " " << batch["name"] << " ray " << i << " (" << trace_layout_name(layout)
                          << "): robust answered tri " << dev[i].tri << "; exactly:\n"
                          << oracle.truth(rays[i], any_hit).describe();
        }
        std::printf("[ replay   ] %-15s %-8s %-6s %5zu rays: right %zu, tie %zu, wrong %zu\n",
                    record["scene"].get<std::string>().c_str(), batch["name"].get<std::string>().c_str(),
                    trace_layout_name(layout), rays.size(), c.right, c.tie, c.wrong);
        EXPECT_EQ(c.wrong, 0u);
      }
    }
  }
  EXPECT_GE(files, 2u) << "no recorded disagreements in " << dir;
}

// run's check that a sorted trace reproduces NoSort's hits (trace/order_agreement.h), on the one ray
// that failed it: breakfast_room's primary ray 1768807 at 1920x1080, packet16, fast variant, in HCC
// order. Its packet in pixel order found tri 81323 (right); in HCC order its lane also met the
// sliver tri 81226 and Möller–Trumbore reported a hit 2.7e-4 nearer (u + v = 1 - 4e-5), which exact
// arithmetic misses. Fast: the variant's own answer, nearer, so it agrees; robust: wrong, so it
// does not; the same answer with t one ulp off, or farther than NoSort's, does not either.
TEST(OrderAgreement, FastNearEdgeHitOfASliverAgreesOnlyInTheFastVariant) {
  RAYSORT_REQUIRE_REAL_SCENES();
  SceneOptions opts;
  opts.frame = {16, 16, 1};  // the ray is stored; the frame only sizes what is not used here
  const PreparedScene p = prepare_scene("breakfast_room", opts);
  const ExactOracle oracle(p.tris, p.bvh);
  RsRay r{};
  r.o[0] = -0x1.2cb4dp-1f, r.o[1] = 0x1.61930cp+1f, r.o[2] = 0x1.36db76p+3f;
  r.d[0] = -0x1.050bd4p-2f, r.d[1] = -0x1.199594p-2f, r.d[2] = -0x1.daa46ap-1f;
  r.tmin = 0.0f, r.tmax = 0x1.c363ccp+127f;
  const RsHit nosort{0x1.8b4d9cp+3f, 81323u, 0x1.3d4f8cp-5f, 0x1.d0204ap-4f};
  const RsHit hcc{0x1.8b4b6cp+3f, 81226u, 0x1.aaf2cp-1f, 0x1.542ae6p-3f};
  EXPECT_EQ(ExactOracle::judge(oracle.truth(r, false), nosort), Verdict::Right);
  EXPECT_EQ(ExactOracle::judge(oracle.truth(r, false), hcc), Verdict::Wrong);
  EXPECT_TRUE(fast_test_gives(p.tris, r, hcc));
  EXPECT_TRUE(answers_agree(hcc, nosort, r, false, TraceVariant::Fast, oracle, p.tris));
  EXPECT_FALSE(answers_agree(hcc, nosort, r, false, TraceVariant::Robust, oracle, p.tris));
  RsHit off = hcc;
  off.t = std::nextafter(off.t, 0.0f);
  EXPECT_FALSE(fast_test_gives(p.tris, r, off));
  EXPECT_FALSE(answers_agree(off, nosort, r, false, TraceVariant::Fast, oracle, p.tris));
  // Farther than NoSort's answer: the fast test's own hit, but not one an order can explain.
  RsHit nearer_nosort = nosort;
  nearer_nosort.t = 12.0f;
  EXPECT_FALSE(answers_agree(hcc, nearer_nosort, r, false, TraceVariant::Fast, oracle, p.tris));
  // And the right answer always agrees.
  EXPECT_TRUE(answers_agree(nosort, hcc, r, false, TraceVariant::Robust, oracle, p.tris));
}
