// raysort trace: load a scene, build its BVH, generate the batches its effects imply, trace each
// on the device and check every hit against the host reference (the same traversal source).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <numeric>

#include "app/commands.h"
#include "app/options.h"
#include "bvh/bvh.h"
#include "cl/runtime.h"
#include "render/batches.h"
#include "scene/load.h"
#include "trace/tracer.h"

namespace raysort {

namespace {

struct TraceArgs {
  std::vector<std::string> scenes;
  CommonOptions common;
  unsigned reps = 3;
  unsigned warmup = 1;
};

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

int run_trace(const TraceArgs& args) {
  Runtime rt(select_device(args.common.device));
  fmt::print("device   {} ({}, {})\n", rt.info().name, rt.info().platform_name, rt.info().driver_version);
  std::size_t total_mismatches = 0;
  for (const auto& scene_name : args.scenes) {
    auto t0 = std::chrono::steady_clock::now();
    Scene scene = load_scene(scene_name, args.common.scene_options());
    Scene::Flat tris = scene.flatten();
    double load_ms = ms_since(t0);
    Bvh bvh = build_bvh(tris);
    RayGenOptions gen = args.common.raygen_options();
    const std::uint32_t w = gen.width ? gen.width : scene.camera.width;
    const std::uint32_t h = gen.height ? gen.height : scene.camera.height;
    const std::uint32_t spp = gen.spp ? gen.spp : scene.effects.samples_per_pixel;
    fmt::print("\nscene    {}: {} triangles, loaded in {:.0f} ms; {}x{} x {} spp\n", scene.name, tris.size(), load_ms, w, h,
               spp);
    fmt::print("bvh      {} nodes, {} leaves, depth {}, built in {:.0f} ms\n", bvh.nodes.size(), bvh.leaf_count, bvh.depth,
               bvh.build_ms);
    double build_before = rt.build_ms();
    Tracer tracer(rt, bvh);
    fmt::print("kernels  built in {:.0f} ms (reported apart from trace times)\n", rt.build_ms() - build_before);
    fmt::print("{:<10} {:>10} {:>10} {:>10} {:>10} {:>11}\n", "batch", "rays", "ms", "MRays/s", "hits", "mismatches");

    // The pipeline of DESIGN.md section 1, as far as the scene's effects ask.
    for (const ReferencedBatch& rb : generate_batches(scene, tris, bvh, gen)) {
      const RayBatch& b = rb.batch;
      Tracer::Run run = tracer.run(b.rays, nullptr, b.any_hit(), args.warmup, args.reps);
      std::size_t mismatches = count_hit_mismatches(run.hits, rb.reference_hits);
      std::size_t hit_count = std::count_if(rb.reference_hits.begin(), rb.reference_hits.end(),
                                            [](const RsHit& x) { return x.tri != RS_NO_HIT; });
      double mrays = run.median_ms > 0 ? static_cast<double>(b.size()) / (run.median_ms * 1e3) : 0.0;
      fmt::print("{:<10} {:>10} {:>10.2f} {:>10.2f} {:>10} {:>11}\n", b.name, b.size(), run.median_ms, mrays, hit_count,
                 mismatches);
      std::fflush(stdout);
      total_mismatches += mismatches;
    }
  }
  if (total_mismatches > 0) {
    fmt::print(stderr, "raysort: {} hits differ from the host reference\n", total_mismatches);
    return 1;
  }
  return 0;
}

}  // namespace

void register_trace_command(CLI::App& app) {
  auto args = std::make_shared<TraceArgs>();
  auto* cmd = app.add_subcommand("trace", "trace a scene's ray batches on the device and verify every hit");
  cmd->add_option("--scene", args->scenes, "scene name, .toml or .obj path (comma-separated for several)")
      ->required()
      ->delimiter(',');
  add_common_options(*cmd, args->common);
  cmd->add_option("--reps", args->reps, "timed repetitions per batch (median reported)")->check(CLI::Range(1u, 1000u));
  cmd->add_option("--warmup", args->warmup, "untimed runs before timing");
  cmd->callback([args] { set_command_exit_code(run_trace(*args)); });
}

}  // namespace raysort
