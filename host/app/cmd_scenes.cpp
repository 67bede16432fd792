// raysort scenes: every scene known by name, loaded once each, with its size and lights, and each
// real scene file checked against its checksum in scenes/sources.toml (scene/provenance.h); or, with
// --describe NAME, the stages and ray batches that one scene's effects imply, with the ray count of
// each batch at the scene's resolution (one frame of the host twin of the path tracer); or, with
// --lights, the paper's Table 1 (light index and relative radius per scene) from the scene files.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <map>

#include "app/commands.h"
#include "app/options.h"
#include "render/frame_memory.h"
#include "bvh/prepared_scene.h"
#include "render/batches.h"
#include "render/pathtrace.h"
#include "scene/load.h"
#include "scene/provenance.h"
#include "util/error.h"

namespace raysort {

namespace {

struct ScenesArgs {
  CommonOptions common;
  std::string describe;  // scene name or path; empty: list every scene
  bool verify = false;   // exit 1 when a real scene file is missing or different
  bool lights = false;   // print the light setup (paper Table 1) of `scenes`
  std::vector<std::string> scenes;
};

// The paper's Table 1 from the scene files: per scene, its sphere lights grouped into runs of equal
// relative radius ("1-2  1.60 %"), the radius as a percentage of the scene's largest extent (as the
// paper gives it), and whether a sky lights it too. Markdown, so it goes into results as printed.
int print_light_table(const ScenesArgs& args) {
  const std::vector<std::string> names = args.scenes.empty()
      ? std::vector<std::string>{"breakfast_room", "grey_white_room", "sibenik", "sponza_dabrovic",
                                 "jacksboro_terrain", "multi-instance-real", "landscape"}
      : args.scenes;
  fmt::print("| scene | light index | relative radius | power | sky |\n|---|---|---:|---:|---|\n");
  for (const auto& name : names) {
    const Scene s = load_scene(name, args.common.scene_options());
    const auto& lights = s.sphere_lights;
    const char* sky = s.sky.enabled ? "yes" : "no";
    if (lights.empty()) fmt::print("| {} | – | – | – | {} |\n", name, sky);
    for (std::size_t i = 0; i < lights.size();) {
      std::size_t j = i;
      while (j + 1 < lights.size() && lights[j + 1].radius_relative == lights[i].radius_relative &&
             lights[j + 1].power == lights[i].power)
        ++j;
      const std::string index = i == j ? fmt::format("{}", i) : fmt::format("{}-{}", i, j);
      fmt::print("| {} | {} | {:.2f} % | {:g} | {} |\n", i == 0 ? name : "", index,
                 100.0 * lights[i].radius_relative, lights[i].power, i == 0 ? sky : "");
      i = j + 1;
    }
  }
  return 0;
}

int describe_scene(const ScenesArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const PreparedScene p = prepare_scene(args.describe, args.common.scene_options());
  // The frame traced below on the host (its batches and hits), sized before anything is printed or
  // allocated, as trace sizes its frame.
  check_frame_memory(estimate_frame_memory(p.scene), nullptr,
                     fmt::format("scene {} at {}x{}, {} spp", p.scene.name, p.scene.camera.width, p.scene.camera.height,
                                 p.scene.effects.samples_per_pixel));
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

// The short licence ("CC-BY 3.0", "unknown", "public domain") and source ("github.com/o/r@6a79398")
// of a catalogued file, for one line of the listing; the catalogue has the full text.
std::string licence_and_source(const CatalogueEntry& e) {
  std::string licence = e.licence.substr(0, std::min(e.licence.find(':'), e.licence.find(" (")));
  if (!e.credit.empty()) licence += ", credit required";
  const std::string at = e.source.commit.empty() ? " " + e.source.version : "@" + e.source.commit.substr(0, 7);
  return fmt::format("{}; {}{}", licence, e.source.origin, at);
}

// The checks of the files one scene uses, each file checked once per listing (scenes share files).
class FileChecks {
 public:
  explicit FileChecks(std::string root) : root_(std::move(root)) {}

  // One line per file: its status, and the licence and source of a catalogued OBJ.
  void print(const std::vector<std::string>& files) {
    for (const auto& f : files) {
      const FileCheck& c = check(f);
      const CatalogueEntry* e = find_catalogued(f);
      std::string about = !e ? std::string() : e->material_of.empty() ? licence_and_source(*e) : std::string("material file of the OBJ above");
      if (c.status == FileStatus::Different || c.status == FileStatus::Uncatalogued) {
        const std::string d = describe_check(c);  // "different: expected ..., found ..."
        about += fmt::format("{}({})", about.empty() ? "" : " ", d.substr(d.find(':') + 2));
      }
      fmt::print("    {:<10} {:<42} {}\n", status_name(c.status), f, about);
    }
  }
  std::size_t count(FileStatus s) const {
    return static_cast<std::size_t>(
        std::count_if(checks_.begin(), checks_.end(), [s](const auto& kv) { return kv.second.status == s; }));
  }
  // Throws Error for a file that exists but cannot be read.
  const FileCheck& check(const std::string& f) {
    auto it = checks_.find(f);
    if (it == checks_.end()) it = checks_.emplace(f, check_scene_file(f, root_)).first;
    return it->second;
  }

 private:
  std::string root_;
  std::map<std::string, FileCheck> checks_;
};

// What to do about missing and different files, after the table.
void print_file_summary(const FileChecks& checks) {
  const std::size_t present = checks.count(FileStatus::Present), missing = checks.count(FileStatus::Missing),
                    different = checks.count(FileStatus::Different);
  fmt::print("\nscene files: {} present, {} missing, {} different (checked against {}: sha256)\n", present, missing,
             different, kSceneCatalogue);
  if (missing)
    fmt::print("missing: obtain them as {} says, into the scene root (or pass --scene-root DIR / set "
               "RAYSORT_SCENE_ROOT); the scenes that use them are not listed with triangle counts\n",
               kObtainScenesHint);
  if (different)
    fmt::print("different: not the catalogued file, so results on these scenes are not comparable with results on "
               "the catalogued files; obtain the catalogued file as {} says, or accept that\n",
               kObtainScenesHint);
}

// One scene's row: loaded (with its size) when its files are there; false when it fails to load.
bool print_scene_row(const SceneListing& listing, const SceneOptions& opts, std::size_t missing,
                     std::size_t files) {
  if (missing) {
    fmt::print("{:<22} {:>12}  ({} of {} files missing; {})\n", listing.name, "-", missing, files, listing.description);
    return true;
  }
  try {
    auto t0 = std::chrono::steady_clock::now();
    Scene s = load_scene(listing.name, opts);
    double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    fmt::print("{:<22} {:>12} {:>6} {:>9} {:>7} {:>4} {:>8.0f}  {}: {}\n", listing.name, s.triangle_count(),
               s.meshes.size(), s.instances.empty() ? s.meshes.size() : s.instances.size(), s.sphere_lights.size(),
               s.sky.enabled ? "yes" : "no", ms, listing.needs_scene_root ? "obj" : "procedural", listing.description);
    return true;
  } catch (const Error& e) {
    fmt::print("{:<22} {:>12}  error: {}\n", listing.name, "-", e.what());
    return false;
  }
}

// Every scene with its size, and the files of real scenes checked against the catalogue. Exit code:
// 1 when a scene fails to load (or, with --verify, a file is missing or different), else 0.
int list_all_scenes(const ScenesArgs& args) {
  const SceneOptions opts = args.common.scene_options();
  const std::string root = resolve_scene_root(opts);
  fmt::print("scene root: {}\n\n", root);
  fmt::print("{:<22} {:>12} {:>6} {:>9} {:>7} {:>4} {:>8}  {}\n", "name", "triangles", "meshes", "instances",
             "spheres", "sky", "load ms", "source");
  FileChecks checks(root);
  bool failed = false;
  for (const auto& listing : list_scenes()) {
    const std::vector<std::string> files = files_with_materials(listing.obj_files);
    std::size_t missing = 0;
    std::string unreadable;
    // The file lines go after the scene's row, which needs the missing count first.
    for (const auto& f : files) {
      try {
        missing += checks.check(f).status == FileStatus::Missing;
      } catch (const Error& e) {
        unreadable = e.what();
      }
    }
    if (!unreadable.empty()) {
      fmt::print("{:<22} {:>12}  error: {}\n", listing.name, "-", unreadable);
      failed = true;
      continue;
    }
    failed |= !print_scene_row(listing, opts, missing, files.size());
    checks.print(files);
  }
  if (checks.count(FileStatus::Present) + checks.count(FileStatus::Missing) + checks.count(FileStatus::Different) > 0)
    print_file_summary(checks);
  const bool files_off = checks.count(FileStatus::Missing) + checks.count(FileStatus::Different) > 0;
  return failed || (args.verify && files_off) ? 1 : 0;
}

}  // namespace

void register_scenes_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenes", "list the known scenes (embedded scene files) with triangle counts, and "
                                           "check real scene files against scenes/sources.toml; --describe NAME: "
                                           "the stages and batches a scene implies");
  auto args = std::make_shared<ScenesArgs>();
  add_scene_options(*cmd, args->common);
  cmd->add_option("--describe", args->describe,
                  scene_option_help() +
                      ": print the stages and ray batches its effects imply, with the ray count of each (one frame "
                      "traced on the host; --resolution, --spp, --seed apply to it)");
  cmd->add_flag("--lights", args->lights,
                "print the light setup of the scenes named by --scenes (default: the paper preset's real scenes and "
                "landscape) as the paper's Table 1: light index, radius relative to the largest extent, power, sky");
  add_scene_list_option(*cmd, args->scenes, "scenes for --lights, comma-separated: each a " + scene_option_help());
  cmd->add_flag("--verify", args->verify,
                "exit 1 when a real scene file is missing or differs from its checksum in scenes/sources.toml");
  cmd->footer(
      "Real scene files are checked against scenes/sources.toml (SHA-256): each is listed as present, missing or "
      "different, with its licence and source. Exit status: 0 when every scene whose files are there loads, even if "
      "files are missing or different (the listing is informational); 1 when a scene fails to load, or, with "
      "--verify, when a file is missing or different.");
  cmd->callback([args] {
    if (!args->describe.empty()) {
      set_command_exit_code(describe_scene(*args));
      return;
    }
    if (args->lights) {
      set_command_exit_code(print_light_table(*args));
      return;
    }
    if (!args->scenes.empty()) throw Error("--scenes applies to --lights only (--describe takes one scene)");
    if (!args->common.resolution.empty() || args->common.spp)
      throw Error("--resolution and --spp apply to --describe NAME only");
    set_command_exit_code(list_all_scenes(*args));
  });
}

}  // namespace raysort
