// The wavefront path tracer (render/pathtrace.h, cl/shade.cl): radiance against analytic values
// (white furnace, a sphere light over a plane, a mirror), the batches a scene's effects imply, and
// the device against the host twin bit for bit. Scenes are built in the tests from TOML text with
// procedural meshes, at small resolutions.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "bvh/bvh.h"
#include "render/batches.h"
#include "render/pathtrace.h"
#include "render/preview.h"
#include "scene/load.h"
#include "test_util.h"
#include "util/error.h"

namespace raysort {

namespace {

// A unit sphere (amplitude 0: every vertex on the sphere, so the mesh is convex) of material
// "ball" in front of the camera, under a sky; `extra` is appended (materials, effects, lights).
std::string sphere_scene(double amplitude, const std::string& ball, const std::string& extra) {
  return R"(name = "furnace"
[camera]
position = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 35.0
resolution = [48, 48]

[[material]]
name = "ball"
)" + ball + R"(

[[mesh]]
name = "ball"
generator = "displaced_sphere"
material = "ball"
seed = 5
[mesh.params]
subdivisions = 48
frequency = 4.0
amplitude = )" + std::to_string(amplitude) +
         "\n\n" + extra;
}

struct Traced {
  ShadeInputs in;
  Frame frame;
  std::vector<ReferencedBatch> batches;  // rays, path ids (in .pixel as path), hits
  std::vector<std::vector<RsPathState>> states;
};

struct Prepared {
  Scene scene;
  Scene::Flat tris;
  Bvh bvh;
};

Prepared prepare(const std::string& toml) {
  Prepared p;
  p.scene = parse_scene_toml(toml, "test.toml", {});
  p.tris = p.scene.flatten();
  p.bvh = build_bvh(p.tris);
  return p;
}

BatchSink capture(Traced& t) {
  return [&t](const TracedBatch& b) {
    ReferencedBatch rb;
    rb.batch.name = batch_name(b.kind, b.bounce);
    rb.batch.kind = b.kind;
    rb.batch.bounce = b.bounce;
    rb.batch.rays = b.rays;
    rb.reference_hits = b.hits;
    t.batches.push_back(std::move(rb));
    t.states.push_back(b.states);
  };
}

// The embedded cornell scene at a frame size of the test's choosing.
Prepared prepare_cornell(const FrameSize& frame) {
  Prepared p;
  p.scene = load_scene("cornell");
  p.tris = p.scene.flatten();
  p.bvh = build_bvh(p.tris);
  apply_frame_size(p.scene, frame);
  return p;
}

Traced trace_host(const Prepared& p, const RayGenOptions& gen = {}, FrameOptions fo = {}) {
  Traced t;
  t.in = make_shade_inputs(p.scene, p.tris, gen);
  fo.sink = capture(t);
  t.frame = trace_frame_host(t.in, p.bvh, fo);
  return t;
}

// Mean of one channel of the radiance over the paths whose primary ray hit (or missed) the scene.
struct Stats {
  double mean = 0.0, stderr_ = 0.0;
  std::size_t n = 0, exact = 0;
};
Stats radiance_stats(const Traced& t, bool hit, double expect) {
  const auto& primary = t.batches.at(0);
  double sum = 0.0, sum2 = 0.0;
  Stats s;
  for (std::size_t i = 0; i < primary.reference_hits.size(); ++i) {
    if ((primary.reference_hits[i].tri != RS_NO_HIT) != hit) continue;
    const double v = t.frame.radiance[3 * t.states[0][i].path];
    sum += v, sum2 += v * v;
    s.exact += std::fabs(v - expect) < 1e-6;
    ++s.n;
  }
  s.mean = sum / std::max<std::size_t>(1, s.n);
  s.stderr_ = std::sqrt(std::max(0.0, sum2 / std::max<std::size_t>(1, s.n) - s.mean * s.mean) / std::max<std::size_t>(1, s.n));
  return s;
}

const char* kWhiteSky = "[sky]\ncolor = [1.0, 1.0, 1.0]\n";

// The sphere scene inside a room without a ceiling (the sky comes in from above), so that paths
// live through several bounces.
std::string room_scene(const std::string& ball, const std::string& room_material, const std::string& extra) {
  return sphere_scene(0.3, ball,
                      "[[material]]\nname = \"room\"\n" + room_material +
                          "\n[[mesh]]\nname = \"room\"\ngenerator = \"box\"\nmaterial = \"room\"\n"
                          "[mesh.params]\nmin = [-3.0, -1.5, -3.0]\nmax = [3.0, 3.0, 5.0]\ninverted = 1\nopen_top = 1\n" +
                          extra);
}

}  // namespace

// White furnace (a diffuse object under a uniform sky of radiance 1): with albedo 1 no energy is
// lost, so every pixel is 1. On the convex sphere every bounce ray escapes to the sky, so each
// path is exactly 1 (tolerance 1e-6 per path, at least 99.5 % of the sphere's paths: a ray that
// grazes a facet edge may hit the sphere again; the mean must still be within 1e-3).
TEST(WhiteFurnace, ConvexSphereAlbedoOneIsOne) {
  Prepared p = prepare(sphere_scene(0.0, "albedo = [1.0, 1.0, 1.0]", std::string(kWhiteSky) +
                                                                        "[effects]\nmax_bounces = 8\n"));
  apply_frame_size(p.scene, {0, 0, 4});
  Traced t = trace_host(p);
  Stats ball = radiance_stats(t, true, 1.0), sky = radiance_stats(t, false, 1.0);
  ASSERT_GT(ball.n, 2000u);
  EXPECT_EQ(sky.exact, sky.n);
  EXPECT_GE(ball.exact, ball.n * 995 / 1000) << "of " << ball.n;
  EXPECT_NEAR(ball.mean, 1.0, 1e-3);
  std::printf("white furnace, convex, albedo 1: mean %.6f over %zu sphere paths, %zu exactly 1\n", ball.mean, ball.n,
              ball.exact);
}

// The same with a bumpy (non-convex) sphere: paths bounce between the bumps, and with enough
// bounces (16, Russian roulette from bounce 3, survival 0.8) the mean is still 1. Tolerance: 4
// standard errors of the estimate plus 0.5 % (the energy of paths cut at bounce 16).
TEST(WhiteFurnace, BumpySphereAlbedoOneWithEnoughBouncesIsOne) {
  Prepared p = prepare(sphere_scene(0.6, "albedo = [1.0, 1.0, 1.0]",
                                    std::string(kWhiteSky) +
                                        "[effects]\nmax_bounces = 16\nrussian_roulette_start = 3\n"
                                        "russian_roulette_survival = 0.8\n"));
  apply_frame_size(p.scene, {0, 0, 8});
  Traced t = trace_host(p);
  Stats ball = radiance_stats(t, true, 1.0);
  std::size_t deep = 0;  // paths that did bounce more than once: the test would be the convex one otherwise
  for (const auto& b : t.batches)
    if (b.batch.kind == BatchKind::Bounce && b.batch.bounce >= 2) deep += b.batch.size();
  EXPECT_GT(deep, ball.n / 20);
  EXPECT_NEAR(ball.mean, 1.0, 4.0 * ball.stderr_ + 0.005);
  std::printf("white furnace, bumpy, albedo 1: mean %.5f +- %.5f (stderr) over %zu paths, %zu rays past bounce 1\n",
              ball.mean, ball.stderr_, ball.n, deep);
}

// Albedo 0.5 on the convex sphere: outgoing radiance = albedo x the sky radiance = 0.5 exactly
// (every direction of the hemisphere sees the sky). Without Russian roulette each path is 0.5; with
// it from bounce 1 (survival 0.5) each path is 0 or 1 and the mean is 0.5 within 4 standard errors.
TEST(WhiteFurnace, AlbedoHalfMatchesTheAnalyticValue) {
  {
    Prepared p = prepare(sphere_scene(0.0, "albedo = [0.5, 0.5, 0.5]", std::string(kWhiteSky) +
                                                                          "[effects]\nmax_bounces = 4\n"));
    Traced t = trace_host(p);
    Stats ball = radiance_stats(t, true, 0.5);
    EXPECT_GE(ball.exact, ball.n * 995 / 1000) << "of " << ball.n;
    EXPECT_NEAR(ball.mean, 0.5, 1e-3);
  }
  Prepared p = prepare(sphere_scene(0.0, "albedo = [0.5, 0.5, 0.5]",
                                    std::string(kWhiteSky) +
                                        "[effects]\nmax_bounces = 4\nrussian_roulette_start = 1\n"
                                        "russian_roulette_survival = 0.5\n"));
  apply_frame_size(p.scene, {0, 0, 8});
  Traced t = trace_host(p);
  Stats ball = radiance_stats(t, true, 0.5);
  EXPECT_NEAR(ball.mean, 0.5, 4.0 * ball.stderr_);
  EXPECT_LT(ball.stderr_, 0.01);
  // Russian roulette halved bounce 1: its batch holds about half the sphere's paths.
  ASSERT_GE(t.batches.size(), 2u);
  EXPECT_NEAR(static_cast<double>(t.batches[1].batch.size()) / static_cast<double>(ball.n), 0.5, 0.03);
  std::printf("white furnace, convex, albedo 0.5 with roulette: mean %.5f +- %.5f over %zu paths\n", ball.mean,
              ball.stderr_, ball.n);
}

// Next-event estimation against the analytic irradiance of a Lambertian sphere light of power P at
// distance d above a plane: E = P / (4 pi d^2), so a plane of albedo a shows a E / pi. With
// P = 4 pi^2, d = 1, a = 0.5 that is 0.5 (the camera sees a small patch right under the light).
TEST(NextEventEstimation, SphereLightOverAPlaneMatchesTheAnalyticRadiance) {
  Prepared p = prepare(R"([camera]
position = [0.0, 0.5, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, 1.0]
fov_y = 2.0
resolution = [16, 16]
[[material]]
name = "grey"
albedo = [0.5, 0.5, 0.5]
[[mesh]]
name = "floor"
generator = "plane"
material = "grey"
[mesh.params]
size_x = 100.0
size_z = 100.0
[[sphere_light]]
center = [0.0, 1.0, 0.0]
radius = 0.001
power = 39.47841760435743
[effects]
max_bounces = 0
shadow_rays_per_bounce = 4
)");
  apply_frame_size(p.scene, {0, 0, 64});
  Traced t = trace_host(p);
  ASSERT_EQ(t.batches.size(), 2u);  // primary, shadow0: no bounce at max_bounces = 0
  Stats floor = radiance_stats(t, true, 0.5);
  ASSERT_EQ(floor.n, 16u * 16u * 64u);
  EXPECT_NEAR(floor.mean, 0.5, 4.0 * floor.stderr_ + 0.002);
  std::printf("sphere light over a plane: %.5f +- %.5f (analytic 0.5)\n", floor.mean, floor.stderr_);
}

// A perfect mirror of albedo 1 under a white sky shows the sky: exactly 1, and casts no shadow rays.
TEST(Mirror, ReflectsTheSkyAndCastsNoShadowRays) {
  Prepared p = prepare(sphere_scene(0.0, "albedo = [1.0, 1.0, 1.0]\nmirror = true",
                                    std::string(kWhiteSky) +
                                        "[[sphere_light]]\ncenter = [0.0, 3.0, 0.0]\nradius = 0.05\n"
                                        "[effects]\nmax_bounces = 2\n"));
  Traced t = trace_host(p);
  for (const auto& b : t.batches) EXPECT_NE(b.batch.kind, BatchKind::Shadow) << b.batch.name;
  Stats ball = radiance_stats(t, true, 1.0);
  EXPECT_GE(ball.exact, ball.n * 995 / 1000) << "of " << ball.n;
}

// Derived batches: no lights, no shadow batches; depth 3, bounce 1..3; sky only, no NEE.
TEST(Batches, FollowTheDeclaredEffects) {
  const std::string room = R"([camera]
position = [0.0, 1.0, 1.5]
look_at = [0.0, 1.0, 0.0]
resolution = [32, 24]
[[mesh]]
name = "room"
generator = "box"
[mesh.params]
min = [-2.0, 0.0, -2.0]
max = [2.0, 2.5, 2.0]
inverted = 1
)";
  // The batches the path tracer produces are the ones possible_batches states (the shard planner
  // and `scenes --describe` read that statement), here where no batch is empty.
  auto names = [](const Prepared& p) {
    std::vector<std::string> out, stated;
    for (const auto& b : generate_batches(p.scene, p.tris, p.bvh, {})) out.push_back(b.batch.name);
    for (const auto& b : possible_batches(p.scene)) stated.push_back(b.name);
    EXPECT_EQ(out, stated);
    return out;
  };
  using V = std::vector<std::string>;
  EXPECT_EQ(names(prepare(room + "[effects]\nmax_bounces = 3\n")), (V{"primary", "bounce1", "bounce2", "bounce3"}));
  EXPECT_EQ(names(prepare(room + std::string(kWhiteSky) + "[effects]\nmax_bounces = 1\n")), (V{"primary", "bounce1"}));
  const std::string light = "[[sphere_light]]\ncenter = [0.0, 2.0, 0.0]\nradius = 0.02\n";
  EXPECT_EQ(names(prepare(room + light + "[effects]\nmax_bounces = 3\n")),
            (V{"primary", "shadow0", "bounce1", "shadow1", "bounce2", "shadow2", "bounce3", "shadow3"}));
  EXPECT_EQ(names(prepare(room + light + "[effects]\nmax_bounces = 0\n")), (V{"primary", "shadow0"}));
  EXPECT_EQ(names(prepare(room + light + "[effects]\nmax_bounces = 2\nshadow_rays_per_bounce = 0\n")),
            (V{"primary", "bounce1", "bounce2"}));
}

// Batch sizes are the live paths: bounce k+1 holds exactly the hits of batch k that survive Russian
// roulette (recomputed here from the RNG), shadow k at most shadow_rays_per_bounce per hit; sizes
// shrink with depth once roulette starts.
TEST(Batches, SizesEqualLivePathCounts) {
  Prepared p = prepare(room_scene("albedo = [0.8, 0.8, 0.8]", "albedo = [0.6, 0.6, 0.6]",
                                    "[sky]\nzenith = [0.5, 0.6, 0.9]\nhorizon = [1.0, 1.0, 1.0]\n"
                                    "[[sphere_light]]\ncenter = [0.0, 3.0, 2.0]\nradius = 0.05\n"
                                    "[effects]\nmax_bounces = 5\nshadow_rays_per_bounce = 2\n"
                                    "russian_roulette_start = 2\nrussian_roulette_survival = 0.7\n"));
  Traced t = trace_host(p);
  std::size_t previous_hits = 0, previous_survivors = 0;
  const RsShadeParams& params = t.in.params;
  for (std::size_t b = 0; b < t.batches.size(); ++b) {
    const RayBatch& batch = t.batches[b].batch;
    const auto& hits = t.batches[b].reference_hits;
    EXPECT_EQ(t.frame.batches[b].rays, batch.size()) << batch.name;
    if (batch.kind == BatchKind::Shadow) {
      EXPECT_LE(batch.size(), 2 * previous_hits) << batch.name;
      EXPECT_GT(batch.size(), 0u) << batch.name;
      continue;
    }
    if (batch.kind == BatchKind::Bounce) {
      EXPECT_EQ(batch.size(), previous_survivors) << batch.name;
    }
    previous_hits = previous_survivors = 0;
    for (std::size_t i = 0; i < hits.size(); ++i) {
      if (hits[i].tri == RS_NO_HIT) continue;
      ++previous_hits;
      const std::uint32_t next = batch.bounce + 1;
      previous_survivors += next < params.rr_start ||
                            rs_random(params, t.states[b][i].path, next, RS_DIM_ROULETTE) < params.rr_survival;
    }
  }
  EXPECT_EQ(t.batches.back().batch.name, "shadow5");
  // Terminated paths are compacted out: bounce 5 is well below the primary batch.
  EXPECT_LT(t.frame.batches.back().rays * 2, t.frame.batches.front().rays);
}

TEST(Batches, SameCommandSameBatches) {
  Scene scene = load_scene("cornell", {"", {48, 27, 2}});
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  RayGenOptions gen;
  auto a = generate_batches(scene, tris, bvh, gen), b = generate_batches(scene, tris, bvh, gen);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), 4u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].batch.name, b[i].batch.name);
    ASSERT_EQ(a[i].batch.size(), b[i].batch.size());
    EXPECT_EQ(std::memcmp(a[i].batch.rays.data(), b[i].batch.rays.data(), a[i].batch.size() * sizeof(RsRay)), 0);
    EXPECT_EQ(a[i].batch.pixel, b[i].batch.pixel);
    EXPECT_EQ(a[i].batch.sample, b[i].batch.sample);
    EXPECT_EQ(count_hit_mismatches(a[i].reference_hits, b[i].reference_hits), 0u);
  }
  // Pixel-major primary rays: all samples of a pixel together.
  EXPECT_EQ(a[0].batch.pixel[3], 1u);
  EXPECT_EQ(a[0].batch.sample[3], 1u);
}

// The device pipeline (every stage a kernel on PoCL) against the host twin: every batch's rays,
// path states and hits, the radiance and the node visits, bit for bit.
void expect_device_equals_host(const Prepared& p, const RayGenOptions& gen, FrameOptions fo, std::size_t min_batches) {
  Traced host = trace_host(p, gen, fo);
  Traced dev;
  dev.in = make_shade_inputs(p.scene, p.tris, gen);
  DevicePathTracer tracer(testing::runtime(), p.bvh, dev.in);
  fo.sink = capture(dev);
  dev.frame = tracer.trace_frame(fo);
  ASSERT_GE(host.batches.size(), min_batches);
  ASSERT_EQ(dev.batches.size(), host.batches.size());
  for (std::size_t b = 0; b < host.batches.size(); ++b) {
    const auto& hb = host.batches[b];
    const auto& db = dev.batches[b];
    ASSERT_EQ(db.batch.name, hb.batch.name);
    ASSERT_EQ(db.batch.size(), hb.batch.size()) << hb.batch.name;
    EXPECT_EQ(std::memcmp(db.batch.rays.data(), hb.batch.rays.data(), hb.batch.size() * sizeof(RsRay)), 0)
        << hb.batch.name;
    EXPECT_EQ(std::memcmp(dev.states[b].data(), host.states[b].data(), hb.batch.size() * sizeof(RsPathState)), 0)
        << hb.batch.name;
    EXPECT_EQ(count_hit_mismatches(db.reference_hits, hb.reference_hits), 0u) << hb.batch.name;
  }
  ASSERT_EQ(dev.frame.radiance.size(), host.frame.radiance.size());
  EXPECT_EQ(std::memcmp(dev.frame.radiance.data(), host.frame.radiance.data(), host.frame.radiance.size() * 4), 0);
  EXPECT_EQ(dev.frame.visits, host.frame.visits);
  double sum = 0.0;
  for (float v : host.frame.radiance) sum += v;
  EXPECT_GT(sum, 0.0);  // something was lit
}

TEST(DevicePathTracer, EqualsHostTwinOnCornell) {
  Prepared p = prepare_cornell({64, 36, 2});
  RayGenOptions gen;
  FrameOptions fo;
  fo.count_visits = true;
  expect_device_equals_host(p, gen, fo, 4);
}

// Every effect at once: a mirror, a gradient sky, two lights chosen by power, two shadow rays per
// hit, Russian roulette, four bounces; and a sample pass that starts past sample 0, over the whole
// frame and over pixels [37, 537).
TEST(DevicePathTracer, EqualsHostTwinWithEveryEffect) {
  Prepared p = prepare(room_scene("albedo = [0.9, 0.7, 0.5]", "albedo = [0.5, 0.6, 0.7]",
                                    "[[material]]\nname = \"mirror\"\nalbedo = [0.9, 0.9, 0.9]\nmirror = true\n"
                                    "[[mesh]]\nname = \"floor\"\ngenerator = \"plane\"\nmaterial = \"mirror\"\n"
                                    "[mesh.params]\nsize_x = 8.0\nsize_z = 8.0\n"
                                    "[[instance]]\nmesh = \"floor\"\ntranslate = [0.0, -1.3, 0.0]\n"
                                    "[sky]\nzenith = [0.3, 0.5, 0.9]\nhorizon = [1.0, 0.9, 0.8]\n"
                                    "[[sphere_light]]\ncenter = [2.0, 3.0, 2.0]\nradius = 0.05\npower = 30.0\n"
                                    "[[sphere_light]]\ncenter = [-2.0, 1.0, 2.0]\nradius = 0.02\npower = 5.0\n"
                                    "[effects]\nmax_bounces = 4\nshadow_rays_per_bounce = 2\n"
                                    "russian_roulette_start = 2\nrussian_roulette_survival = 0.6\n"));
  apply_frame_size(p.scene, {40, 30, 3});
  RayGenOptions gen;
  FrameOptions fo;
  fo.count_visits = true;
  fo.sample_begin = 1;
  fo.sample_count = 2;
  expect_device_equals_host(p, gen, fo, 10);
  fo.pixel_begin = 37;  // and a pass of pixels starting inside a row (a render's row pass)
  fo.pixel_count = 500;
  expect_device_equals_host(p, gen, fo, 10);
}

// Pixel passes partition the frame too: pixels [0, 37) and [37, 144), the second starting inside a
// row, give the paths of the whole frame (the RNG is keyed by the absolute pixel).
TEST(PathTracer, PixelPassesPartitionTheFrame) {
  Prepared p = prepare_cornell({16, 9, 2});
  ShadeInputs in = make_shade_inputs(p.scene, p.tris, RayGenOptions{});
  Frame whole = trace_frame_host(in, p.bvh, {});
  FrameOptions a, b;
  a.pixel_count = 37;
  b.pixel_begin = 37;
  Frame fa = trace_frame_host(in, p.bvh, a), fb = trace_frame_host(in, p.bvh, b);
  ASSERT_EQ(fa.pixels, 37u);
  ASSERT_EQ(fb.pixels, 16u * 9u - 37u);
  EXPECT_EQ(fb.pixel_begin, 37u);
  ASSERT_EQ(fa.radiance.size() + fb.radiance.size(), whole.radiance.size());
  EXPECT_EQ(std::memcmp(fa.radiance.data(), whole.radiance.data(), fa.radiance.size() * 4), 0);
  EXPECT_EQ(std::memcmp(fb.radiance.data(), whole.radiance.data() + fa.radiance.size(), fb.radiance.size() * 4), 0);
  FrameOptions past;
  past.pixel_begin = 16 * 9;
  EXPECT_THROW(trace_frame_host(in, p.bvh, past), Error);
}

// A render's passes cover every (pixel, sample) once, sample-major, within the path budget: whole
// frames of several samples while the frame is smaller than the budget, else rows of one sample.
TEST(RenderPasses, PlanCoversEveryPixelAndSampleOnce) {
  struct Case {
    std::uint32_t w, h, spp;
    std::uint64_t budget;
    std::size_t passes;
  };
  for (Case c : {Case{16, 9, 5, 1000, 1}, Case{16, 9, 5, 300, 3}, Case{16, 9, 5, 144, 5}, Case{16, 9, 3, 100, 6}, Case{16, 9, 2, 40, 10},
                 Case{16, 9, 1, 7, 9}, Case{1920, 1080, 8, kRenderPassPaths, 8}, Case{7680, 4320, 1, kRenderPassPaths, 16}}) {
    const auto plan = plan_render_passes(c.w, c.h, c.spp, c.budget);
    EXPECT_EQ(plan.size(), c.passes) << c.w << "x" << c.h << " budget " << c.budget;
    std::vector<std::uint32_t> seen(std::size_t{c.w} * c.h, 0);  // samples added per pixel, in order
    std::uint64_t largest = 0;
    for (const RenderPass& pass : plan) {
      largest = std::max<std::uint64_t>(largest, std::uint64_t{pass.pixel_count} * pass.sample_count);
      EXPECT_EQ(pass.pixel_begin % c.w, 0u);  // whole rows
      for (std::uint32_t px = pass.pixel_begin; px < pass.pixel_begin + pass.pixel_count; ++px) {
        ASSERT_EQ(seen[px], pass.sample_begin) << "pixel " << px << " gets its samples out of order";
        seen[px] += pass.sample_count;
      }
    }
    for (std::uint32_t n : seen) ASSERT_EQ(n, c.spp);
    EXPECT_LE(largest, std::max<std::uint64_t>(c.budget, c.w));
    EXPECT_EQ(largest, largest_render_pass(c.w, c.h, c.spp, c.budget));
  }
}

// Splitting a render into row passes changes nothing: the image and the cost heatmap's data are
// the same bit for bit as one pass, on the host twin and on the device.
TEST(RenderPasses, RowPassesRenderTheSameImage) {
  PreparedScene p = prepare_scene("cornell", [] {
    SceneOptions o;
    o.frame = {24, 10, 3};
    return o;
  }());
  for (Runtime* rt : {static_cast<Runtime*>(nullptr), &testing::runtime()}) {
    const RenderedFrame one = render_frame(p, RayGenOptions{}, rt, 24 * 10 * 3);
    const RenderedFrame rows = render_frame(p, RayGenOptions{}, rt, 50);  // two rows of one sample
    EXPECT_EQ(one.passes, 1u);
    EXPECT_EQ(rows.passes, 15u);
    EXPECT_EQ(one.rays, rows.rays);
    ASSERT_EQ(one.image.rgb.size(), rows.image.rgb.size());
    EXPECT_EQ(std::memcmp(one.image.rgb.data(), rows.image.rgb.data(), one.image.rgb.size() * 4), 0)
        << (rt ? "device" : "host twin");
    EXPECT_EQ(one.cost, rows.cost);
    ASSERT_EQ(one.first_pass.size(), rows.first_pass.size());
    for (std::size_t i = 0; i < one.first_pass.size(); ++i) EXPECT_EQ(one.first_pass[i].name, rows.first_pass[i].name);
    EXPECT_EQ(one.first_pass[0].rays, 3 * rows.first_pass[0].rays);  // primary: one pass held all 3 samples
  }
}

// Sample passes partition the frame: passes [0,1) and [1,3) give the paths of one 3-spp frame.
TEST(PathTracer, SamplePassesPartitionTheFrame) {
  Prepared p = prepare_cornell({16, 9, 3});
  RayGenOptions gen;
  ShadeInputs in = make_shade_inputs(p.scene, p.tris, gen);
  Frame whole = trace_frame_host(in, p.bvh, {});
  FrameOptions a, b;
  a.sample_count = 1;
  b.sample_begin = 1;
  Frame fa = trace_frame_host(in, p.bvh, a), fb = trace_frame_host(in, p.bvh, b);
  ASSERT_EQ(fa.spp, 1u);
  ASSERT_EQ(fb.spp, 2u);
  for (std::size_t pixel = 0; pixel < 16u * 9u; ++pixel)
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(whole.radiance[3 * (pixel * 3) + c], fa.radiance[3 * pixel + c]);
      EXPECT_EQ(whole.radiance[3 * (pixel * 3 + 2) + c], fb.radiance[3 * (pixel * 2 + 1) + c]);
    }
}

}  // namespace raysort

// Issue 44, item 7: `render` names its files after the scene, and a scene's name comes from its
// input (a scene file's `name`, a bare OBJ's file name): it is made one plain file name, so the
// files land in the current folder, not hidden and not elsewhere. A bare ".hidden.obj" wrote the
// hidden ".hidden.png" before.
TEST(RenderOutput, FilesNamedAfterTheSceneStayPlainNamesInTheCurrentFolder) {
  namespace fs = std::filesystem;
  const fs::path dir = raysort::testing::temp_path("render_names");
  fs::create_directories(dir);
  std::ofstream(dir / ".hidden.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const fs::path before = fs::current_path();
  fs::current_path(dir);
  const auto r = raysort::testing::run_cli({"render", "--scene", (dir / ".hidden.obj").string(), "--host",
                                            "--resolution", "8x8"});
  fs::current_path(before);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "_hidden.png")) << r.out;
  EXPECT_TRUE(fs::exists(dir / "_hidden.exr")) << r.out;
  EXPECT_FALSE(fs::exists(dir / ".hidden.png"));
}

// Issue 44, item 15/17: kernel files read from --kernels DIR go through the bounded input reader:
// an empty file is named (OpenCL said only CL_INVALID_KERNEL_NAME), a FIFO is refused by its type
// (it blocked the read forever).
TEST(KernelFiles, EmptyOrFifoKernelFilesUnderKernelsDirAreNamed) {
  namespace fs = std::filesystem;
  const fs::path cl = fs::path(__FILE__).parent_path().parent_path() / "cl";
  ASSERT_TRUE(fs::is_directory(cl)) << cl;
  const fs::path empty = raysort::testing::temp_path("kernels_empty"), fifo = raysort::testing::temp_path("kernels_fifo");
  fs::create_directories(empty);
  fs::create_directories(fifo);
  for (const auto& e : fs::directory_iterator(cl)) {
    const std::string name = e.path().filename().string();
    fs::copy_file(e.path(), empty / name);
    ASSERT_EQ(::mkfifo((fifo / name).c_str(), 0600), 0);
  }
  std::ofstream(empty / "shade.cl", std::ios::trunc);  // render's kernels
  const fs::path out = raysort::testing::temp_path("kernels_out");
  auto r = raysort::testing::run_cli({"--kernels", empty.string(), "render", "--scene", "cornell", "--resolution",
                                      "8x8", "--out", (out / "x.png").string()});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("raysort: error: kernel file " + empty.string() + "/shade.cl (for cl/shade.cl) is empty; point "
                       "--kernels at the repository's cl/ folder, or restore the file"),
            std::string::npos)
      << r.err;
  r = raysort::testing::run_cli({"--kernels", fifo.string(), "render", "--scene", "cornell", "--resolution", "8x8",
                                 "--out", (out / "x.png").string()});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("raysort: error: kernel file " + fifo.string() + "/"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" is a FIFO (named pipe), not a regular file; point --kernels at the repository's cl/ folder"),
            std::string::npos)
      << r.err;
}
