#include "bench/matrix.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <regex>

#include "bench/batch_file.h"
#include "embree/embree_reference.h"  // kEmbreePaths and check_embree_isa only: the keys a matrix may name
#include "scene/load.h"
#include "util/error.h"

namespace raysort {

namespace {

template <class T, class Name>
std::string joined(const std::vector<T>& items, Name name) {
  std::string s;
  for (const T& x : items) {
    if (!s.empty()) s += ',';
    s += name(x);
  }
  return s;
}

}  // namespace

void MatrixSpec::add_params_json(nlohmann::json& j) const {
  // Each knob by its row (encode/encoder_params.h), under the field's own name and type. The knobs
  // of the encoders beyond the paper (issue 21) only in a matrix that runs one of their encoders
  // (cost_bits only when set): a set written before they existed keeps its entry (and resumes).
  auto runs = [&](Encoder e) { return std::find(encoders.begin(), encoders.end(), e) != encoders.end(); };
  for (const EncoderParam& row : encoder_params()) {
    if (!row.recorded_with.empty() && std::none_of(row.recorded_with.begin(), row.recorded_with.end(), runs)) continue;
    if (row.recorded_when_set && row.is_default(params)) continue;
    std::visit([&](auto member) { j[std::string(row.key)] = params.*member; }, row.field);
  }
}

nlohmann::json MatrixSpec::to_json() const {
  // The spelling of format version 2's meta.json: a set resumes only under an equal entry.
  nlohmann::json j = {{"preset", preset},
          {"scenes", scenes},
          {"batches", batches},
          {"encoders", [&] {
             std::vector<std::string> names;
             for (Encoder e : encoders) names.emplace_back(encoder_name(e));
             return names;
           }()},
          {"bits", bits},
          {"key_length_scenes", key_length_scenes},
          {"key_length_bits", key_length_bits},
          {"top_bits", top_bits},
          {"resolution", fmt::format("{}x{}", frame.width, frame.height)},
          {"spp", frame.spp},
          {"reps", reps},
          {"warmup", warmup},
          {"max_noise", max_noise},
          {"max_time_s", max_time_s},
          {"seed", seed},
          {"variant", joined(variants, trace_variant_name)},
          {"access", joined(accesses, ray_access_name)},
          {"baseline", joined(baselines, baseline_order_name)},
          {"layout", joined(layouts, trace_layout_name)}};
  add_params_json(j);
  // Only when on, so a set without the model keeps the entry it was written with (and resumes).
  if (!gpu_model.empty()) j["gpu_model"] = gpu_model;
  // Likewise Embree's paths: part of the matrix (a resume with other paths is another matrix).
  if (!embree_paths.empty()) j["embree_paths"] = embree_paths;
  if (embree_isa != "native") j["embree_isa"] = embree_isa;
  // Likewise the warp-granular sort: a set sorted in full has no entry.
  if (sort_warp_group) j["sort_warp_group"] = sort_warp_group;
  // Likewise the sampling overrides: a set that keeps the scenes' own shadow rays and depth has no entry.
  if (frame.shadow_rays) j["shadow_rays"] = frame.shadow_rays;
  if (frame.bounces) j["bounces"] = frame.bounces;
  return j;
}

void check_matrix_json(const nlohmann::json& matrix, const std::string& file) {
  // Every entry to_json writes, by the type it is written (and read) as. A value to_json writes as a
  // float (max_noise, had_lambda, ...) is written as null when it is not finite, so null is refused
  // as well: such a set can be neither resumed nor swept.
  enum Kind { Text, Count, Number, TextList, CountList };
  static const std::vector<std::pair<const char*, Kind>> kKeys = {
      {"preset", Text},       {"scenes", TextList},      {"batches", TextList},        {"encoders", TextList},
      {"bits", CountList},    {"key_length_scenes", TextList}, {"key_length_bits", CountList}, {"top_bits", CountList},
      {"resolution", Text},   {"spp", Count},            {"reps", Count},              {"warmup", Count},
      {"max_noise", Number},  {"max_time_s", Number},    {"seed", Count},              {"variant", Text},
      {"access", Text},       {"baseline", Text},        {"layout", Text},             {"gpu_model", Text},
      {"shadow_rays", Count}, {"bounces", Count},        {"embree_paths", TextList},   {"sort_warp_group", Count},
      {"embree_isa", Text}};
  auto is = [](const nlohmann::json& v, Kind k) {
    switch (k) {
      case Text: return v.is_string();
      case Count: return v.is_number_unsigned();
      case Number: return v.is_number();
      case TextList: return v.is_array() && std::all_of(v.begin(), v.end(), [](const auto& x) { return x.is_string(); });
      case CountList:
        return v.is_array() && std::all_of(v.begin(), v.end(), [](const auto& x) { return x.is_number_unsigned(); });
    }
    return false;
  };
  static const char* const kNames[] = {"a string", "a count (a whole number, 0 or more)", "a number",
                                       "a list of strings", "a list of counts"};
  if (!matrix.is_object())
    throw Error(fmt::format("{}: \"matrix\" is a JSON {}, not an object; restore the file (it was edited or damaged)",
                            file, matrix.type_name()));
  std::vector<std::pair<std::string, Kind>> keys(kKeys.begin(), kKeys.end());
  for (const EncoderParam& row : encoder_params()) keys.emplace_back(row.key, row.whole() ? Count : Number);
  for (const auto& [key, kind] : keys) {
    if (!matrix.contains(key) || is(matrix[key], kind)) continue;
    const nlohmann::json& v = matrix[key];
    std::string what = fmt::format("a JSON {}", v.type_name());
    if (v.is_array())  // a list of the wrong items: name the first
      for (std::size_t i = 0; i < v.size(); ++i)
        if (!is(nlohmann::json::array({v[i]}), kind)) {
          what = fmt::format("a list whose item {} is a JSON {}", i, v[i].type_name());
          break;
        }
    throw Error(fmt::format("{}: matrix.{} is {}, not {}; restore the file (it was edited or damaged)", file, key, what,
                            kNames[kind]));
  }
}

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

std::vector<std::string> preset_names() {
  return {"quick", "paper", "paper-1spp", "paper-viewport", "paper-hcc-dir", "paper-bounces"};
}

namespace {

// The paper's sampling (§5: "two shadow rays per bounce and eight samples per pixel") at its
// resolution: 16.6 M paths, so 16.6 M rays per bounce batch and 33.2 M per shadow batch at most.
constexpr FrameSize kPaperFrame{1920, 1080, 8, 2};

// The real scenes standing for the paper's (docs/paper.md, "Scenes"), then procedural ones.
const std::vector<std::string> kPaperScenes{"sibenik",   "breakfast_room", "grey_white_room", "sponza_dabrovic",
                                            "jacksboro_terrain", "multi-instance-real", "detail-room",
                                            "landscape", "multi-instance"};

}  // namespace

MatrixSpec matrix_preset(const std::string& name) {
  MatrixSpec m;
  m.preset = name;
  m.encoders = all_encoders();
  m.accesses = {RayAccess::Gather, RayAccess::Permute};
  if (name == "quick") {
    m.scenes = {"cornell", "detail-room", "landscape", "multi-instance"};
    m.batches = {"primary", "shadow0", "bounce1"};
    m.bits = {32};
    m.key_length_scenes = {"detail-room"};
    m.key_length_bits = {16, 64};
    m.frame = {320, 180, 1};
    // A cell's rounds stop after 0.25 s (or sooner, at the noise target), so that `make bench` stays
    // under three minutes on a busy 2-core machine with PoCL compiling the kernels in the same run;
    // 0.3 s did not, at the same A/A calibration (the figures: docs/measurement.md, "The quick
    // preset's time per cell").
    m.max_time_s = 0.25;
    // Single rays beside packets of the device's width (issue 40): on a CPU the packet class is
    // where an order changes SIMD divergence, not only cache hits.
    m.layouts = {TraceLayout::Wide, TraceLayout::Packet};
    return m;
  }
  if (name == "paper" || name == "paper-1spp") {
    // The paper's Tables 2, 3, 5, 6 and 7 (§5-6): secondary (bounce1) and primary shadow (shadow0)
    // rays, 32-bit keys for the overview tables, 16/32/64 on sibenik for the key-length tables,
    // λ = 0.125, TwoPoint length 0.25 of the largest extent. "paper" samples as the paper did;
    // "paper-1spp" is the same matrix at 1 spp with the scenes' own one shadow ray per bounce
    // (an eighth of the rays: the set committed before the paper's sampling was supported).
    m.scenes = kPaperScenes;
    m.batches = {"bounce1", "shadow0"};
    m.bits = {32};
    m.key_length_scenes = {"sibenik"};
    m.key_length_bits = {16, 64};
    m.frame = name == "paper" ? kPaperFrame : FrameSize{1920, 1080, 1};
    return m;
  }
  if (name == "paper-viewport") {
    // Table 4: secondary rays in a limited viewport (a narrow view of a detail: primary rays hit a
    // small area, then scatter into the whole scene), one per real interior.
    m.scenes = {"breakfast_room_limited", "grey_white_room_limited", "sibenik_limited",
                "japanese_classroom_limited", "wooden_staircase_limited"};
    m.batches = {"bounce1"};
    m.frame = kPaperFrame;
    return m;
  }
  if (name == "paper-hcc-dir") {
    // Appendix Table 8: HCC against HCC_DIR (31 cut bits + 1 direction bit) and HCC with 31 bits,
    // secondary rays, on the scenes standing for the paper's five.
    m.scenes = {"breakfast_room", "grey_white_room", "sibenik", "sponza_dabrovic", "landscape"};
    m.batches = {"bounce1"};
    m.encoders = {Encoder::HCC, Encoder::HCC_DIR};
    m.bits = {32};
    m.key_length_scenes = m.scenes;
    m.key_length_bits = {31};
    m.frame = kPaperFrame;
    return m;
  }
  if (name == "paper-bounces") {
    // Appendix "Reflection ray trace performance": Breakfast, bounce 1 to 5 (Russian roulette from
    // depth 3 thins the deeper batches, as in the paper).
    m.scenes = {"breakfast_room"};
    m.batches = {"bounce1", "bounce2", "bounce3", "bounce4", "bounce5"};
    m.frame = kPaperFrame;
    m.frame.bounces = 5;
    return m;
  }
  throw Error(fmt::format("unknown preset '{}'; presets are: {}", name, fmt::join(preset_names(), ", ")));
}

void validate_encoders(const std::vector<Encoder>& encoders, const std::vector<unsigned>& bits,
                       const EncoderParams& params) {
  if (const std::string problem = params_problem(params); !problem.empty()) throw Error(problem);
  for (Encoder e : encoders) {
    if (e == Encoder::NoSort) continue;
    for (unsigned b : bits) {
      std::string problem = key_bits_problem(e, b, params);
      if (!problem.empty()) throw Error(fmt::format("encoder {} with {}-bit keys: {}", encoder_name(e), b, problem));
    }
  }
}

void validate_matrix(const MatrixSpec& spec) {
  if (spec.frame.width == 0 || spec.frame.height == 0)
    throw Error(fmt::format("resolution {}x{}: both must be at least 1", spec.frame.width, spec.frame.height));
  if (spec.frame.spp == 0) throw Error("--spp must be at least 1");
  if (spec.scenes.empty()) throw Error("no scenes selected (--scenes NAME[,NAME...] or --preset)");
  for (const auto& scene : spec.scenes) check_scene_reference(scene);
  if (spec.bits.empty()) throw Error("no key bits selected (--bits N[,N...])");
  if (spec.reps == 0) throw Error("--reps must be at least 1");
  if (!(spec.max_noise > 0) || !std::isfinite(spec.max_noise))
    throw Error(fmt::format("--max-noise {}: must be a percentage above 0, e.g. 2", spec.max_noise * 100));
  if (!(spec.max_time_s >= 0) || !std::isfinite(spec.max_time_s))
    throw Error(fmt::format("--max-time {}: must be a number of seconds, 0 or more", spec.max_time_s));
  if (spec.accesses.empty()) throw Error("--access: name at least one access mode (gather, permute)");
  if (spec.variants.empty()) throw Error("--variant: name at least one trace variant (robust, fast)");
  if (spec.layouts.empty()) throw Error("--layout: name at least one trace class (wide, packet, ...)");
  if (spec.baselines.empty()) throw Error("--baseline: name at least one baseline order (pixel, shuffled)");
  if (!(spec.cell_timeout_s >= 0) || !std::isfinite(spec.cell_timeout_s))
    throw Error(fmt::format("--timeout {}: must be a number of seconds, 0 (none) or more", spec.cell_timeout_s));
#ifdef RAYSORT_HAVE_EMBREE
  constexpr bool have_embree = true;
#else
  constexpr bool have_embree = false;
#endif
  if (!have_embree && !spec.embree_paths.empty())
    throw Error("--embree-paths: this build has no Embree: install libembree-dev and reconfigure");
  for (const std::string& path : spec.embree_paths) {
    if (std::none_of(std::begin(kEmbreePaths), std::end(kEmbreePaths),
                     [&](const EmbreePathInfo& info) { return path == info.key; })) {
      std::string keys;
      for (const EmbreePathInfo& info : kEmbreePaths) keys += fmt::format("{}{}", keys.empty() ? "" : ", ", info.key);
      throw Error(fmt::format("unknown Embree path '{}' in --embree-paths; the paths are {}, or all", path, keys));
    }
  }
  check_embree_isa(spec.embree_isa);
  if (spec.embree_isa != "native" && spec.embree_paths.empty())
    throw Error(fmt::format("--embree-isa {} sets the instruction set of Embree's arms: give --embree-paths too",
                            spec.embree_isa));
  if (!spec.ray_file.empty() &&
      (spec.scenes.size() != 1 || spec.batches != std::vector<std::string>{ray_file_batch_name(spec.ray_file)}))
    throw Error(fmt::format("--rays {} is one batch of one scene: give that scene alone with --scene, and leave out "
                            "--batches",
                            spec.ray_file));
  std::regex batch_re("^(primary|shadow[0-9]+|bounce[1-9][0-9]*)$");
  for (auto& b : spec.batches)
    if (spec.ray_file.empty() && !std::regex_match(b, batch_re))
      throw Error(fmt::format("unknown batch '{}'; batches are primary, shadow<k> (k >= 0) and bounce<k> (k >= 1)", b));
  std::vector<unsigned> all_bits = spec.bits;
  all_bits.insert(all_bits.end(), spec.key_length_bits.begin(), spec.key_length_bits.end());
  validate_encoders(spec.encoders, all_bits, spec.params);
  for (unsigned k : spec.top_bits) {
    unsigned widest = *std::max_element(all_bits.begin(), all_bits.end());
    if (k == 0 || k > widest) throw Error(fmt::format("--top-bits {}: must be between 1 and the key length {}", k, widest));
  }
}

}  // namespace raysort
