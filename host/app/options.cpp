#include "app/options.h"

#include <fmt/format.h>

#include <cstdio>

#include "bench/matrix.h"  // parse_resolution

namespace raysort {


SceneOptions CommonOptions::scene_options() const {
  SceneOptions o;
  o.scene_root = scene_root;
  if (!resolution.empty()) parse_resolution(resolution, o.width, o.height);
  o.spp = spp;
  return o;
}

RayGenOptions CommonOptions::raygen_options() const {
  RayGenOptions o;
  if (!resolution.empty()) parse_resolution(resolution, o.width, o.height);
  o.spp = spp;
  o.seed = seed;
  return o;
}

void add_common_options(CLI::App& cmd, CommonOptions& o) {
  cmd.add_option("--device", o.device, "device index, 'cpu', 'gpu' or part of its name (env RAYSORT_DEVICE)");
  cmd.add_option("--scene-root", o.scene_root, "folder the scene files' OBJ paths are relative to (env RAYSORT_SCENE_ROOT)");
  cmd.add_option("--resolution", o.resolution, "image size WxH (default: the scene's)");
  cmd.add_option("--spp", o.spp, "samples per pixel (default: the scene's)");
  cmd.add_option("--seed", o.seed, "seed of the counter-based ray generator");
}

}  // namespace raysort
