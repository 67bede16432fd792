#pragma once
// Options shared by the subcommands: the scene and frame options (every command that loads a
// scene), the device option (every command that runs kernels), the scene list (--scene and
// --scenes, one option), and the measurement protocol's knobs. Parsed here, at the command line's
// boundary, into typed values.
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "bench/protocol.h"
#include "encode/encoder_params.h"
#include "render/rays.h"
#include "scene/load.h"

namespace raysort {

struct CommonOptions {
  std::string device;       // --device; empty: RAYSORT_DEVICE, else first GPU, else first CPU
  std::string scene_root;   // --scene-root; empty: RAYSORT_SCENE_ROOT, else ../shared/scenes
  std::string resolution;   // --resolution WxH; empty: the scene's
  std::uint32_t spp = 0;    // --spp; 0: the scene's
  std::uint32_t shadow_rays = 0;  // --shadow-rays per bounce; 0: the scene's
  std::uint32_t bounces = 0;      // --bounces; 0: the scene's
  std::uint32_t seed = 1;   // --seed of the ray generator
  // The frame overrides (0: the scene's own); parses --resolution (throws Error on bad text).
  FrameSize frame() const;
  SceneOptions scene_options() const;  // scene root + frame
  RayGenOptions raygen_options() const;
};

// Numbers on the command line (issue 44). Every numeric option is checked as text where it is
// parsed, before CLI11 converts it: a negative count would otherwise wrap (-1 as 4294967295), a
// NaN or an out-of-range value was replaced by a default or stored as null, and CLI11's own
// conversion errors named neither the range nor the fix. A value outside the range throws Error
// "--lambda -1 is not valid: give a finite number, 0 or more".
// A whole number from lo to hi (digits only: no sign, no exponent); each item of a list option.
CLI::Option* whole_number(CLI::Option* opt, std::uint64_t lo, std::uint64_t hi);
// A finite number from lo to hi (above lo, when above_lo); hi infinite: no upper bound.
CLI::Option* finite_number(CLI::Option* opt, double lo, double hi, bool above_lo = false);
// Checks a WIDTHxHEIGHT text: two whole numbers from 1 to 4294967295 (throws Error naming `option`).
void check_resolution_text(const std::string& option, const std::string& text);

// --scene-root, --resolution, --spp, --shadow-rays, --bounces, --seed.
void add_scene_options(CLI::App& cmd, CommonOptions& o);
// --device.
void add_device_option(CLI::App& cmd, CommonOptions& o);
// Both of the above.
void add_common_options(CLI::App& cmd, CommonOptions& o);
// The scenes to work on: `--scene` and `--scenes` name the same option (names, .toml or .obj
// paths, comma-separated).
CLI::Option* add_scene_list_option(CLI::App& cmd, std::vector<std::string>& scenes, const std::string& help);
// What --scene takes, for --help: "scene name, .toml path, or a scene file (.obj, .ply, ...)"; the
// endings come from the one list of formats (scene/mesh_formats.h).
std::string scene_option_help();

// The command line as given ("raysort run --scene sibenik --out r"): recorded in meta.json and in
// the header of a ray file (render/ray_file.h).
std::string command_line_text(const CLI::App& cmd);

// --rays FILE of trace, run and encodebench: a ray batch file (docs/rays-format.md) to use instead
// of generating the batches; one scene only.
CLI::Option* add_rays_option(CLI::App& cmd, std::string& file);

// The encoders' knobs (encode/encoder_params.h): one option per row, with the row's range (checked
// as every number is, above) and meaning. `run` and `encodebench` both take them from here, so they
// take and refuse the same values with the same message. The values land in `given`.
void add_encoder_param_options(CLI::App& cmd, EncoderParams& given);
// `into` with the knobs given on `cmd`'s command line taken from `given`; the others keep their
// value (a preset's, or the default).
void apply_given_params(const CLI::App& cmd, const EncoderParams& given, EncoderParams& into);

// The measurement protocol's knobs (bench/protocol.h) for the commands that time one batch at a
// time (trace, encodebench); `run` keeps them in its matrix.
struct ProtocolOptions {
  unsigned reps = 7;          // --reps: the fewest timed rounds
  unsigned warmup = 1;        // --warmup: untimed rounds first
  double max_noise_pct = 2;   // --max-noise: target half-width of the intervals, percent
  double max_time_s = 3;      // --max-time: sampling budget per batch, seconds
  ProtocolSettings settings(std::uint64_t seed) const;
};

void add_protocol_options(CLI::App& cmd, ProtocolOptions& o);

// The bounds of the protocol's numbers, shared with `run`: at most 100000 rounds (timed or
// warm-up), at most a day (86400 s) of sampling per batch or cell.
inline constexpr std::uint64_t kMaxRounds = 100000;
inline constexpr double kMaxSeconds = 86400;
// --reps, --warmup, --max-noise (percent, above 0, at most 100) and --max-time, checked as above,
// with each command's help text.
void add_protocol_number_options(CLI::App& cmd, unsigned& reps, unsigned& warmup, double& max_noise_pct,
                                 double& max_time_s, const std::string& reps_help, const std::string& noise_help,
                                 const std::string& time_help);

}  // namespace raysort
