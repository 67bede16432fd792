#pragma once
// Options shared by the subcommands that load a scene and run on a device.
#include <CLI/CLI.hpp>

#include <string>

#include "render/rays.h"
#include "scene/load.h"

namespace raysort {

struct CommonOptions {
  std::string device;       // --device; empty: RAYSORT_DEVICE, else first GPU, else first CPU
  std::string scene_root;   // --scene-root; empty: RAYSORT_SCENE_ROOT, else ../shared/scenes
  std::string resolution;   // --resolution WxH; empty: the scene's
  std::uint32_t spp = 0;    // --spp; 0: the scene's
  std::uint32_t seed = 1;   // --seed of the ray generator
  SceneOptions scene_options() const;
  RayGenOptions raygen_options() const;
};

void add_common_options(CLI::App& cmd, CommonOptions& o);

}  // namespace raysort
