#include "bench/matrix.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <regex>

#include "scene/load.h"
#include "util/error.h"

namespace raysort {

void parse_resolution(const std::string& s, std::uint32_t& w, std::uint32_t& h) {
  unsigned a = 0, b = 0;
  char x = 0;
  if (std::sscanf(s.c_str(), "%u%c%u", &a, &x, &b) != 3 || (x != 'x' && x != 'X') || a == 0 || b == 0)
    throw Error(fmt::format("resolution '{}': expected WIDTHxHEIGHT with both at least 1, e.g. 1920x1080", s));
  w = a;
  h = b;
}

nlohmann::json MatrixSpec::to_json() const {
  return {{"preset", preset},
          {"scenes", scenes},
          {"batches", batches},
          {"encoders", encoders},
          {"bits", bits},
          {"key_length_scenes", key_length_scenes},
          {"key_length_bits", key_length_bits},
          {"top_bits", top_bits},
          {"resolution", resolution},
          {"spp", spp},
          {"reps", reps},
          {"warmup", warmup},
          {"max_noise", max_noise},
          {"max_time_s", max_time_s},
          {"seed", seed},
          {"variant", variant},
          {"access", access},
          {"twopoint_length_fraction", params.twopoint_length_fraction},
          {"had_lambda", params.had_lambda},
          {"direction_bits", params.direction_bits}};
}

namespace {
// "a,b,,a" -> {"a", "b"}: the items of a comma-separated list, first occurrence kept.
std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t comma = text.find(',', start);
    std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!item.empty() && std::find(out.begin(), out.end(), item) == out.end()) out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}
}  // namespace

std::vector<std::string> MatrixSpec::variant_list() const { return split_list(variant); }
std::vector<std::string> MatrixSpec::access_list() const { return split_list(access); }

ProtocolSettings MatrixSpec::protocol(const std::string& cell_id) const {
  ProtocolSettings p;
  p.warmup = warmup;
  p.min_rounds = reps;
  p.max_noise = max_noise;
  p.max_time_s = max_time_s;
  p.hard_limit_s = cell_timeout_s;
  p.seed = protocol_seed(fmt::format("{}/{}", seed, cell_id));
  return p;
}

std::vector<unsigned> MatrixSpec::bits_for(const std::string& scene) const {
  std::vector<unsigned> out = bits;
  if (std::find(key_length_scenes.begin(), key_length_scenes.end(), scene) != key_length_scenes.end())
    for (unsigned b : key_length_bits)
      if (std::find(out.begin(), out.end(), b) == out.end()) out.push_back(b);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> preset_names() { return {"quick", "paper"}; }

MatrixSpec matrix_preset(const std::string& name) {
  MatrixSpec m;
  m.preset = name;
  for (Encoder e : all_encoders()) m.encoders.emplace_back(encoder_name(e));
  if (name == "quick") {
    m.scenes = {"cornell", "detail-room", "landscape", "multi-instance"};
    m.batches = {"primary", "shadow0", "bounce1"};
    m.bits = {32};
    m.key_length_scenes = {"detail-room"};
    m.key_length_bits = {16, 64};
    m.resolution = "320x180";
    m.access = "gather,permute";
    m.max_time_s = 0.3;
    return m;
  }
  if (name == "paper") {
    // The paper's setup (§5-6): 1920×1080, secondary (bounce1) and primary shadow (shadow0) rays,
    // 32-bit keys for the overview tables, 16/32/64 on sibenik for the key-length tables,
    // λ = 0.125, TwoPoint length 0.25 of the largest extent.
    m.scenes = {"sibenik",        "breakfast_room", "grey_white_room", "sponza_dabrovic", "jacksboro_terrain",
                "multi-instance-real", "detail-room", "landscape",      "multi-instance"};
    m.batches = {"bounce1", "shadow0"};
    m.bits = {32};
    m.key_length_scenes = {"sibenik"};
    m.key_length_bits = {16, 64};
    m.resolution = "1920x1080";
    m.access = "gather,permute";
    return m;
  }
  throw Error(fmt::format("unknown preset '{}'; presets are: quick, paper", name));
}

void validate_matrix(const MatrixSpec& spec) {
  std::uint32_t w, h;
  parse_resolution(spec.resolution, w, h);
  if (spec.scenes.empty()) throw Error("no scenes selected (--scenes NAME[,NAME...] or --preset)");
  for (const auto& scene : spec.scenes) check_scene_reference(scene);
  if (spec.bits.empty()) throw Error("no key bits selected (--bits N[,N...])");
  if (spec.spp == 0) throw Error("--spp must be at least 1");
  if (spec.reps == 0) throw Error("--reps must be at least 1");
  if (!(spec.max_noise > 0) || !std::isfinite(spec.max_noise))
    throw Error(fmt::format("--max-noise {}: must be a percentage above 0, e.g. 2", spec.max_noise * 100));
  if (!(spec.max_time_s >= 0) || !std::isfinite(spec.max_time_s))
    throw Error(fmt::format("--max-time {}: must be a number of seconds, 0 or more", spec.max_time_s));
  if (spec.access_list().empty()) throw Error("--access: name at least one access mode (gather, permute)");
  for (const auto& a : spec.access_list())
    if (a != "gather" && a != "permute")
      throw Error(fmt::format("--access '{}': the access modes are gather and permute", a));
  if (spec.variant_list().empty()) throw Error("--variant: name at least one trace variant (robust, fast)");
  for (const auto& v : spec.variant_list())
    if (v != "robust" && v != "fast")
      throw Error(fmt::format("--variant '{}': the trace variants are robust and fast", v));
  if (!(spec.cell_timeout_s >= 0) || !std::isfinite(spec.cell_timeout_s))
    throw Error(fmt::format("--timeout {}: must be a number of seconds, 0 (none) or more", spec.cell_timeout_s));
  std::string valid;
  for (Encoder e : all_encoders()) valid += (valid.empty() ? "" : ", ") + std::string(encoder_name(e));
  std::regex batch_re("^(primary|shadow[0-9]+|bounce[1-9][0-9]*)$");
  for (auto& b : spec.batches)
    if (!std::regex_match(b, batch_re))
      throw Error(fmt::format("unknown batch '{}'; batches are primary, shadow<k> (k >= 0) and bounce<k> (k >= 1)", b));
  std::vector<unsigned> all_bits = spec.bits;
  all_bits.insert(all_bits.end(), spec.key_length_bits.begin(), spec.key_length_bits.end());
  for (auto& name : spec.encoders) {
    auto e = parse_encoder(name);
    if (!e) throw Error(fmt::format("unknown encoder '{}'; encoders are: {}", name, valid));
    if (*e == Encoder::NoSort) continue;
    for (unsigned b : all_bits) {
      std::string problem = key_bits_problem(*e, b, spec.params);
      if (!problem.empty()) throw Error(fmt::format("encoder {} with {}-bit keys: {}", name, b, problem));
    }
  }
  for (unsigned k : spec.top_bits) {
    unsigned widest = *std::max_element(all_bits.begin(), all_bits.end());
    if (k == 0 || k > widest) throw Error(fmt::format("--top-bits {}: must be between 1 and the key length {}", k, widest));
  }
}

}  // namespace raysort
