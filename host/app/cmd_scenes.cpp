// raysort scenes: every scene known by name, loaded once each, with its size and lights.
#include <fmt/format.h>

#include <chrono>
#include <filesystem>

#include "app/commands.h"
#include "scene/load.h"
#include "util/error.h"

namespace raysort {

void register_scenes_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenes", "list the known scenes (embedded scene files) with triangle counts");
  auto opts = std::make_shared<SceneOptions>();
  cmd->add_option("--scene-root", opts->scene_root,
                  "folder the real scenes' OBJ paths are relative to (default: env RAYSORT_SCENE_ROOT, else "
                  "../shared/scenes beside the source tree)");
  cmd->callback([opts] {
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
