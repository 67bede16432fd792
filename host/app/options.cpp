#include "app/options.h"

#include <fmt/format.h>

#include <cstdio>

namespace raysort {

FrameSize CommonOptions::frame() const {
  FrameSize f = resolution.empty() ? FrameSize{} : parse_resolution(resolution);
  f.spp = spp;
  f.shadow_rays = shadow_rays;
  f.bounces = bounces;
  return f;
}

SceneOptions CommonOptions::scene_options() const {
  SceneOptions o;
  o.scene_root = scene_root;
  o.frame = frame();
  return o;
}

RayGenOptions CommonOptions::raygen_options() const {
  RayGenOptions o;
  o.seed = seed;
  return o;
}

void add_scene_options(CLI::App& cmd, CommonOptions& o) {
  cmd.add_option("--scene-root", o.scene_root, "folder the scene files' OBJ paths are relative to (env RAYSORT_SCENE_ROOT)");
  cmd.add_option("--resolution", o.resolution, "image size WxH (default: the scene's)");
  cmd.add_option("--spp", o.spp, "samples per pixel (default: the scene's)");
  cmd.add_option("--shadow-rays", o.shadow_rays,
                 "shadow rays per bounce toward the sphere lights (default: the scene's; the paper used 2; 1 to 64)")
      ->check(CLI::Range(1u, 64u));
  cmd.add_option("--bounces", o.bounces,
                 "diffuse bounces after the primary hit, i.e. the deepest bounce<k> batch (default: the scene's; 1 to 64)")
      ->check(CLI::Range(1u, 64u));
  cmd.add_option("--seed", o.seed, "seed of the counter-based ray generator")->capture_default_str();
}

void add_device_option(CLI::App& cmd, CommonOptions& o) {
  cmd.add_option("--device", o.device, "device index, 'cpu', 'gpu' or part of its name (env RAYSORT_DEVICE)");
}

void add_common_options(CLI::App& cmd, CommonOptions& o) {
  add_device_option(cmd, o);
  add_scene_options(cmd, o);
}

CLI::Option* add_scene_list_option(CLI::App& cmd, std::vector<std::string>& scenes, const std::string& help) {
  return cmd.add_option("--scene,--scenes", scenes, help)->delimiter(',');
}

ProtocolSettings ProtocolOptions::settings(std::uint64_t seed) const {
  ProtocolSettings p;
  p.warmup = warmup;
  p.min_rounds = reps;
  p.max_noise = max_noise_pct / 100.0;
  p.max_time_s = max_time_s;
  p.seed = seed;
  return p;
}

void add_protocol_options(CLI::App& cmd, ProtocolOptions& o) {
  cmd.add_option("--reps", o.reps,
                 "the fewest timed rounds (default 7: from 7 on the 95 % interval leaves out the extremes); more follow until --max-noise or "
                 "--max-time (docs/measurement.md)")
      ->check(CLI::Range(1u, 100000u))
      ->capture_default_str();
  cmd.add_option("--warmup", o.warmup, "untimed rounds before timing")->capture_default_str();
  cmd.add_option("--max-noise", o.max_noise_pct,
                 "stop once every figure's 95 % interval is within +-this many percent")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd.add_option("--max-time", o.max_time_s, "stop after this many seconds of rounds per batch even if --max-noise is not met")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

}  // namespace raysort
