// raysort scenes: every scene known by name, loaded once each, with its size and lights; or, with
// --describe NAME, the stages and ray batches that one scene's effects imply, with the ray count of
// each batch at the scene's resolution (one frame of the host twin of the path tracer).
#include <fmt/format.h>

#include <chrono>
#include <filesystem>

#include "app/commands.h"
#include "app/options.h"
#include "bvh/prepared_scene.h"
#include "render/batches.h"
#include "render/pathtrace.h"
#include "scene/load.h"
#include "util/error.h"

namespace raysort {

namespace {

struct ScenesArgs {
  CommonOptions common;
  std::string describe;  // scene name or path; empty: list every scene
};

int describe_scene(const ScenesArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const PreparedScene p = prepare_scene(args.describe, args.common.scene_options());
  const ShadeInputs in = make_shade_inputs(p.scene, p.tris, args.common.raygen_options());
  const Effects& e = p.scene.effects;
  fmt::print("scene    {} ({}): {} triangles\n", p.scene.name, p.scene.file, p.tris.size());
  fmt::print("frame    {}x{}, {} spp, seed {}\n", in.width, in.height, in.spp, args.common.seed);
  fmt::print("lights   {} sphere light{}{}\n", p.scene.sphere_lights.size(), p.scene.sphere_lights.size() == 1 ? "" : "s",
             p.scene.sky.enabled ? ", sky" : ", no sky");
  fmt::print("effects  max_bounces {}, shadow_rays_per_bounce {}, russian_roulette_start {} (survival {})\n\n",
             e.max_bounces, e.shadow_rays_per_bounce, e.russian_roulette_start, e.russian_roulette_survival);
  fmt::print("stages\n");
  for (const auto& line : describe_stages(p.scene)) fmt::print("  {}\n", line);

  // The batches the declarations imply, then their sizes from one traced frame.
  Frame frame = trace_frame_host(in, p.bvh, {});
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double primary = static_cast<double>(std::size_t{in.width} * in.height * in.spp);
  fmt::print("\n{:<10} {:<8} {:>5} {:>12} {:>10}\n", "batch", "trace", "depth", "rays", "% primary");
  std::size_t total = 0;
  for (const PossibleBatch& pb : possible_batches(p.scene)) {
    std::size_t rays = 0;
    for (const auto& b : frame.batches)
      if (b.kind == pb.kind && b.bounce == pb.bounce) rays = b.rays;
    total += rays;
    fmt::print("{:<10} {:<8} {:>5} {:>12} {:>9.1f}%\n", pb.name, pb.kind == BatchKind::Shadow ? "any" : "closest",
               pb.bounce, rays, 100.0 * static_cast<double>(rays) / primary);
  }
  fmt::print("{:<10} {:<8} {:>5} {:>12}\n", "total", "", "", total);
  fmt::print("\n(host twin of the path tracer, {:.0f} ms including loading and the BVH build)\n", ms);
  return 0;
}

}  // namespace

void register_scenes_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenes", "list the known scenes (embedded scene files) with triangle counts; "
                                           "--describe NAME: the stages and batches a scene implies");
  auto args = std::make_shared<ScenesArgs>();
  add_scene_options(*cmd, args->common);
  cmd->add_option("--describe", args->describe,
                  "scene name, .toml or .obj path: print the stages and ray batches its effects imply, with the ray "
                  "count of each (one frame traced on the host; --resolution, --spp, --seed apply to it)");
  cmd->callback([args] {
    if (!args->describe.empty()) {
      set_command_exit_code(describe_scene(*args));
      return;
    }
    if (!args->common.resolution.empty() || args->common.spp)
      throw Error("--resolution and --spp apply to --describe NAME only");
    const SceneOptions opts = args->common.scene_options();
    std::string root = resolve_scene_root(opts);
    fmt::print("scene root: {}\n\n", root);
    fmt::print("{:<22} {:>12} {:>6} {:>9} {:>7} {:>4} {:>8}  {}\n", "name", "triangles", "meshes", "instances",
               "spheres", "sky", "load ms", "source");
    bool failed = false;
    for (const auto& listing : list_scenes()) {
      std::string missing;
      for (const auto& obj : listing.obj_files) {
        std::filesystem::path p = std::filesystem::path(obj).is_absolute() ? std::filesystem::path(obj) : std::filesystem::path(root) / obj;
        std::error_code ec;
        if (!std::filesystem::is_regular_file(p, ec)) {
          missing = obj;
          break;
        }
      }
      std::string source = listing.needs_scene_root ? "obj" : "procedural";
      if (!missing.empty()) {
        fmt::print("{:<22} {:>12}  ({} not found under {})\n", listing.name, "-", missing, root);
        continue;
      }
      try {
        auto t0 = std::chrono::steady_clock::now();
        Scene s = load_scene(listing.name, opts);
        double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        fmt::print("{:<22} {:>12} {:>6} {:>9} {:>7} {:>4} {:>8.0f}  {}: {}\n", listing.name, s.triangle_count(),
                   s.meshes.size(), s.instances.empty() ? s.meshes.size() : s.instances.size(), s.sphere_lights.size(),
                   s.sky.enabled ? "yes" : "no", ms, source, listing.description);
      } catch (const Error& e) {
        fmt::print("{:<22} {:>12}  error: {}\n", listing.name, "-", e.what());
        failed = true;
      }
    }
    if (failed) set_command_exit_code(1);
  });
}

}  // namespace raysort
