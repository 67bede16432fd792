// raysort rays: one batch of a scene's frame out to a ray file (render/ray_file.h,
// docs/rays-format.md), for another tracer to trace exactly the suite's rays. The frame is the one
// trace, run and encodebench generate from the same scene options (resolution, spp, shadow rays,
// bounces, seed); `--rays FILE` brings such a batch back in.
#include <fmt/format.h>

#include <chrono>
#include <filesystem>

#include "app/commands.h"
#include "app/options.h"
#include "bench/batch_file.h"
#include "bench/scene_checksum.h"
#include "bvh/prepared_scene.h"
#include "render/frame_memory.h"
#include "util/error.h"

namespace raysort {

namespace {

struct RaysArgs {
  std::string scene;
  std::string batch = "bounce1";
  std::string export_file;
  bool hits = false;
  CommonOptions common;
};

int run_rays(const RaysArgs& args, const CLI::App& cmd) {
  // A folder that is not there is refused before the frame is made (seconds at 1920x1080).
  const std::filesystem::path folder = std::filesystem::absolute(args.export_file).parent_path();
  if (std::error_code ec; !std::filesystem::is_directory(folder, ec))
    throw Error(fmt::format("--export {}: the folder {} does not exist; create it or give another path", args.export_file,
                            folder.string()));
  const SceneOptions options = args.common.scene_options();
  // The scene's checksum first: a scene with a missing file is refused before the frame is made.
  const std::string scene_sha = scene_sha256(args.scene, resolve_scene_root(options));
  const PreparedScene p = prepare_scene(args.scene, options);
  const FrameSize frame = p.frame();
  check_frame_memory(estimate_frame_memory(p.scene), nullptr,
                     fmt::format("scene {} at {}x{}, {} spp", p.scene.name, frame.width, frame.height, frame.spp));
  const auto start = std::chrono::steady_clock::now();
  const std::vector<ReferencedBatch> batches = generate_batches(p.scene, p.tris, p.bvh, args.common.raygen_options());
  const ReferencedBatch* chosen = nullptr;
  std::string names;
  for (const ReferencedBatch& rb : batches) {
    names += (names.empty() ? "" : ", ") + rb.batch.name;
    if (rb.batch.name == args.batch) chosen = &rb;
  }
  if (!chosen)
    throw Error(fmt::format("scene '{}' has no batch '{}' at this frame; it has: {}; choose one with --batch", p.scene.name,
                            args.batch, names));
  const double generate_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const auto write_start = std::chrono::steady_clock::now();
  write_ray_file(args.export_file, ray_file_of(*chosen, scene_sha, command_line_text(cmd), args.hits));
  const double write_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - write_start).count();
  fmt::print("scene    {}: {} triangles; {}x{} x {} spp, seed {}; scene sha256 {}\n", p.scene.name, p.tris.size(),
             frame.width, frame.height, frame.spp, args.common.seed, scene_sha);
  fmt::print("batch    {}: {} rays ({}), {} hits; rays hash {}, hits hash {}; frame generated in {:.0f} ms\n",
             chosen->batch.name, chosen->batch.size(), chosen->batch.any_hit() ? "any hit" : "closest hit",
             args.hits ? "with" : "without", rays_hash(chosen->batch.rays), hits_hash(chosen->reference_hits), generate_ms);
  fmt::print("exported {} ({} bytes) in {:.0f} ms; trace it with `raysort trace --scene {} --rays {}`\n", args.export_file,
             std::filesystem::file_size(args.export_file), write_ms, args.scene, args.export_file);
  return 0;
}

}  // namespace

void register_rays_command(CLI::App& app) {
  auto args = std::make_shared<RaysArgs>();
  auto* cmd = app.add_subcommand("rays", "write one ray batch of a scene's frame to a file (docs/rays-format.md)");
  cmd->add_option("--scene", args->scene, scene_option_help() + " (one)")->required();
  cmd->add_option("--batch", args->batch, "batch name: primary, shadow<k>, bounce<k>")->capture_default_str();
  cmd->add_option("--export", args->export_file, "the ray file to write (replaced only once complete)")->required();
  cmd->add_flag("--hits", args->hits, "also write each ray's hit (t, triangle id) as the host reference traces it");
  add_scene_options(*cmd, args->common);
  cmd->callback([args, cmd] { set_command_exit_code(run_rays(*args, *cmd)); });
}

}  // namespace raysort
