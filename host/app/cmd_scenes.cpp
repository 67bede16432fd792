// raysort scenes: every scene known by name, loaded once each, with its size and lights; or, with
// --describe NAME, the stages and ray batches that one scene's effects imply, with the ray count of
// each batch at the scene's resolution (one frame of the host twin of the path tracer).
#include <fmt/format.h>

#include <chrono>
#include <filesystem>

#include "app/commands.h"
#include "bench/matrix.h"  // parse_resolution
#include "bvh/bvh.h"
#include "render/pathtrace.h"
#include "scene/load.h"
#include "util/error.h"

namespace raysort {

namespace {

struct ScenesArgs {
  SceneOptions scene;
  std::string describe;    // scene name or path; empty: list every scene
  std::string resolution;  // WxH for --describe; empty: the scene's
  std::uint32_t spp = 0;
  std::uint32_t seed = 1;
};

int describe_scene(const ScenesArgs& args) {
  SceneOptions so = args.scene;
  if (!args.resolution.empty()) parse_resolution(args.resolution, so.width, so.height);
  so.spp = args.spp;
  Scene scene = load_scene(args.describe, so);
  const auto t0 = std::chrono::steady_clock::now();
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  RayGenOptions gen;
  gen.seed = args.seed;
  const ShadeInputs in = make_shade_inputs(scene, tris, gen);
  const Effects& e = scene.effects;
  fmt::print("scene    {} ({}): {} triangles\n", scene.name, scene.file, tris.size());
  fmt::print("frame    {}x{}, {} spp, seed {}\n", in.width, in.height, in.spp, args.seed);
  fmt::print("lights   {} sphere light{}{}\n", scene.sphere_lights.size(), scene.sphere_lights.size() == 1 ? "" : "s",
             scene.sky.enabled ? ", sky" : ", no sky");
  fmt::print("effects  max_bounces {}, shadow_rays_per_bounce {}, russian_roulette_start {} (survival {})\n\n",
             e.max_bounces, e.shadow_rays_per_bounce, e.russian_roulette_start, e.russian_roulette_survival);
  fmt::print("stages\n");
  for (const auto& line : describe_stages(scene)) fmt::print("  {}\n", line);

  // The batches the declarations imply, then their sizes from one traced frame.
  std::vector<std::pair<BatchKind, std::uint32_t>> declared{{BatchKind::Primary, 0}};
  const bool nee = in.params.shadow_per_hit > 0;
  for (std::uint32_t k = 0; k <= e.max_bounces; ++k) {
    if (k > 0) declared.push_back({BatchKind::Bounce, k});
    if (nee) declared.push_back({BatchKind::Shadow, k});
  }
  Frame frame = trace_frame_host(in, bvh, {});
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double primary = static_cast<double>(std::size_t{in.width} * in.height * in.spp);
  fmt::print("\n{:<10} {:<8} {:>5} {:>12} {:>10}\n", "batch", "trace", "depth", "rays", "% primary");
  std::size_t total = 0;
  for (auto [kind, bounce] : declared) {
    std::size_t rays = 0;
    for (const auto& b : frame.batches)
      if (b.kind == kind && b.bounce == bounce) rays = b.rays;
    total += rays;
    fmt::print("{:<10} {:<8} {:>5} {:>12} {:>9.1f}%\n", batch_name(kind, bounce),
               kind == BatchKind::Shadow ? "any" : "closest", bounce, rays, 100.0 * static_cast<double>(rays) / primary);
  }
  fmt::print("{:<10} {:<8} {:>5} {:>12}\n", "total", "", "", total);
  fmt::print("\n(host twin of the path tracer, {:.0f} ms including the BVH build)\n", ms);
  return 0;
}

}  // namespace

void register_scenes_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenes", "list the known scenes (embedded scene files) with triangle counts; "
                                           "--describe NAME: the stages and batches a scene implies");
  auto args = std::make_shared<ScenesArgs>();
  auto opts = std::shared_ptr<SceneOptions>(args, &args->scene);
  cmd->add_option("--scene-root", opts->scene_root,
                  "folder the real scenes' OBJ paths are relative to (default: env RAYSORT_SCENE_ROOT, else "
                  "../shared/scenes beside the source tree)");
  cmd->add_option("--describe", args->describe,
                  "scene name, .toml or .obj path: print the stages and ray batches its effects imply, with the ray "
                  "count of each (one frame traced on the host)");
  cmd->add_option("--resolution", args->resolution, "with --describe: image size WxH (default: the scene's)");
  cmd->add_option("--spp", args->spp, "with --describe: samples per pixel (default: the scene's)");
  cmd->add_option("--seed", args->seed, "with --describe: seed of the counter-based ray generator")->capture_default_str();
  cmd->callback([args, opts] {
    if (!args->describe.empty()) {
      set_command_exit_code(describe_scene(*args));
      return;
    }
    if (!args->resolution.empty() || args->spp)
      throw Error("--resolution and --spp apply to --describe NAME only");
    std::string root = resolve_scene_root(*opts);
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
        Scene s = load_scene(listing.name, *opts);
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
