#include "app/options.h"

#include <fmt/format.h>

#include <cstdio>

#include "util/error.h"

namespace raysort {

namespace {
void parse_resolution(const std::string& s, std::uint32_t& w, std::uint32_t& h) {
  unsigned a = 0, b = 0;
  char x = 0;
  if (std::sscanf(s.c_str(), "%u%c%u", &a, &x, &b) != 3 || (x != 'x' && x != 'X') || a == 0 || b == 0)
    throw Error(fmt::format("--resolution '{}': expected WIDTHxHEIGHT with both at least 1, e.g. 1920x1080", s));
  w = a;
  h = b;
}
}  // namespace

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
