#include "app/options.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>

#include "scene/mesh_formats.h"
#include "util/error.h"
#include "util/text.h"

namespace raysort {

namespace {

[[noreturn]] void refuse(const std::string& option, const std::string& text, const std::string& valid) {
  throw Error(fmt::format("{} {} is not valid: give {}", option, text.empty() ? "''" : text, valid));
}

// CLI11 runs a check on each item of the option's text (each comma-separated one of a list)
// before it converts it. The check throws raysort::Error, not a CLI11 ValidationError, so the
// message is ours as written (main prints it as every other bad input).
CLI::Option* check_text(CLI::Option* opt, std::function<void(const std::string&, const std::string&)> check,
                        const std::string& description) {
  const std::string name = opt->get_name();
  opt->check(CLI::Validator(
      [name, check](std::string& text) {
        check(name, text);
        return std::string();
      },
      description));
  return opt;
}

bool parse_whole(const std::string& text, std::uint64_t& v) {
  const char* end = text.data() + text.size();
  const auto [p, ec] = std::from_chars(text.data(), end, v);
  return !text.empty() && ec == std::errc() && p == end;
}

}  // namespace

CLI::Option* whole_number(CLI::Option* opt, std::uint64_t lo, std::uint64_t hi) {
  return check_text(
      opt,
      [lo, hi](const std::string& name, const std::string& text) {
        std::uint64_t v = 0;
        if (!parse_whole(text, v) || v < lo || v > hi)
          refuse(name, text, number_range_text(static_cast<double>(lo), static_cast<double>(hi), true));
      },
      fmt::format("{}..{}", lo, hi));
}

CLI::Option* finite_number(CLI::Option* opt, double lo, double hi, bool above_lo) {
  const std::string valid = number_range_text(lo, hi, false, above_lo);
  return check_text(
      opt,
      [lo, hi, above_lo, valid](const std::string& name, const std::string& text) {
        double v = 0;
        const char* end = text.data() + text.size();
        const auto [p, ec] = std::from_chars(text.data(), end, v);  // no "0x" prefix, no leading '+'
        if (text.empty() || ec != std::errc() || p != end || !std::isfinite(v) || (above_lo ? !(v > lo) : !(v >= lo)) ||
            !(v <= hi))
          refuse(name, text, valid);
      },
      std::isinf(hi) ? fmt::format("{}{:g}", above_lo ? ">" : ">=", lo)
                     : fmt::format("{}{:g}..{:g}", above_lo ? ">" : "", lo, hi));
}

void add_encoder_param_options(CLI::App& cmd, EncoderParams& given) {
  for (const EncoderParam& row : encoder_params())
    std::visit(
        [&](auto member) {
          CLI::Option* opt = cmd.add_option(std::string(row.flag), given.*member, std::string(row.meaning));
          if (row.whole())
            whole_number(opt, static_cast<std::uint64_t>(row.lo), static_cast<std::uint64_t>(row.hi));
          else
            finite_number(opt, row.lo, row.hi);
        },
        row.field);
}

void apply_given_params(const CLI::App& cmd, const EncoderParams& given, EncoderParams& into) {
  for (const EncoderParam& row : encoder_params())
    if (cmd.count(std::string(row.flag))) copy_param(row, given, into);
}

void check_resolution_text(const std::string& option, const std::string& text) {
  // By hand, not sscanf("%u"): that reads "-48" as 4294967248 and "4294967344" as 48.
  const std::size_t x = text.find_first_of("xX");
  std::uint64_t w = 0, h = 0;
  const std::uint64_t most = std::numeric_limits<std::uint32_t>::max();
  if (x == std::string::npos || !parse_whole(text.substr(0, x), w) || !parse_whole(text.substr(x + 1), h) || w < 1 ||
      h < 1 || w > most || h > most)
    throw Error(fmt::format("{} '{}': expected WIDTHxHEIGHT, two whole numbers from 1 to {}, e.g. 1920x1080", option,
                            text, most));
}

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
  check_text(cmd.add_option("--resolution", o.resolution, "image size WxH (default: the scene's)"),
             check_resolution_text, "WxH");
  // 0 given is the scene's own count, as the default is; `run` refuses it (validate_matrix).
  whole_number(cmd.add_option("--spp", o.spp, "samples per pixel (default: the scene's)"), 0,
               std::numeric_limits<std::uint32_t>::max());
  whole_number(cmd.add_option("--shadow-rays", o.shadow_rays,
                              "shadow rays per bounce toward the sphere lights (default: the scene's; the paper used 2; 1 to 64)"),
               1, 64);
  whole_number(cmd.add_option("--bounces", o.bounces,
                              "diffuse bounces after the primary hit, i.e. the deepest bounce<k> batch (default: the scene's; 1 to 64)"),
               1, 64);
  whole_number(cmd.add_option("--seed", o.seed, "seed of the counter-based ray generator")->capture_default_str(), 0,
               std::numeric_limits<std::uint32_t>::max());
}

void add_device_option(CLI::App& cmd, CommonOptions& o) {
  cmd.add_option("--device", o.device, "device index, 'cpu', 'gpu' or part of its name (env RAYSORT_DEVICE)");
}

std::string command_line_text(const CLI::App& cmd) {
  std::string line = "raysort " + cmd.get_name();
  for (auto* opt : cmd.get_options())
    if (opt->count() > 0 && opt->get_name() != "--help")
      for (auto& r : opt->results()) line += " " + opt->get_name() + " " + r;
  return line;
}

CLI::Option* add_rays_option(CLI::App& cmd, std::string& file) {
  return cmd.add_option("--rays", file,
                        "trace this ray batch file (written by `raysort rays --export`, docs/rays-format.md) instead of "
                        "generating the scene's batches; it must come from the same scene (its SHA-256 is checked); its "
                        "batch is named file:<stem>");
}

void add_common_options(CLI::App& cmd, CommonOptions& o) {
  add_device_option(cmd, o);
  add_scene_options(cmd, o);
}

CLI::Option* add_scene_list_option(CLI::App& cmd, std::vector<std::string>& scenes, const std::string& help) {
  return cmd.add_option("--scene,--scenes", scenes, help)->delimiter(',');
}

void add_protocol_number_options(CLI::App& cmd, unsigned& reps, unsigned& warmup, double& max_noise_pct,
                                 double& max_time_s, const std::string& reps_help, const std::string& noise_help,
                                 const std::string& time_help) {
  whole_number(cmd.add_option("--reps", reps, reps_help), 1, kMaxRounds);
  whole_number(cmd.add_option("--warmup", warmup, "untimed rounds before timing"), 0, kMaxRounds);
  finite_number(cmd.add_option("--max-noise", max_noise_pct, noise_help), 0, 100, true);
  // A day per batch or cell is more than any measurement here needs; the bound keeps a typo (a
  // number of milliseconds) from holding a machine.
  finite_number(cmd.add_option("--max-time", max_time_s, time_help), 0, kMaxSeconds);
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
  add_protocol_number_options(cmd, o.reps, o.warmup, o.max_noise_pct, o.max_time_s,
                              "the fewest timed rounds (default 7: from 7 on the 95 % interval leaves out the extremes); "
                              "more follow until --max-noise or --max-time (docs/measurement.md)",
                              "stop once every figure's 95 % interval is within +-this many percent",
                              "stop after this many seconds of rounds per batch even if --max-noise is not met");
  for (const char* name : {"--reps", "--warmup", "--max-noise", "--max-time"}) cmd.get_option(name)->capture_default_str();
}

std::string scene_option_help() {
  return "scene name, .toml path, or a scene file (" + mesh_format_endings() + ")";
}

}  // namespace raysort
