#pragma once
// Options shared by the subcommands that load a scene and run on a device.
#include <CLI/CLI.hpp>

#include <string>

#include "bench/protocol.h"
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

// The measurement protocol's knobs (bench/protocol.h) for the commands that time one batch at a
// time (trace, encodebench); `run` has its own, stored in the matrix.
struct ProtocolOptions {
  unsigned reps = 7;          // --reps: the fewest timed rounds
  unsigned warmup = 1;        // --warmup: untimed rounds first
  double max_noise_pct = 2;   // --max-noise: target half-width of the intervals, percent
  double max_time_s = 3;      // --max-time: sampling budget per batch, seconds
  ProtocolSettings settings(std::uint64_t seed) const;
};

void add_protocol_options(CLI::App& cmd, ProtocolOptions& o);

}  // namespace raysort
