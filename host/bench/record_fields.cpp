// The field tables of a cell record: every field once, with its JSON key, cells.csv column, type
// (its member's), when it is absent, the format version from which every record holds it, and its
// CSV digits. What each field means: bench/record.h; how the tables are walked: record_field.h.
#include "bench/record_fields.h"

#include "trace/trace_class.h"

namespace raysort {

namespace {

using C = CellRecord;
using G = CellRecord::GpuModelFigures;
using E = CellRecord::EmbreeFigures;

// Format versions (bench/record.h): 2 brought the paired protocol's fields, 3 the baseline and the
// layout; the fields added within version 3, and the keys an older writer left out when absent,
// are held by every record from version 4.
constexpr int kV2 = 2, kV3 = 3, kV4 = 4;

// The closed vocabularies of text fields.
const std::vector<std::string>& variants() {
  static const std::vector<std::string> words{"robust", "fast"};
  return words;
}
const std::vector<std::string>& access_modes() {
  static const std::vector<std::string> words{"gather", "permute"};
  return words;
}
const std::vector<std::string>& baselines() {
  static const std::vector<std::string> words{"pixel", "shuffled"};
  return words;
}
const std::vector<std::string>& stop_reasons() {  // "" in a cell that failed before it measured
  static const std::vector<std::string> words{"noise", "time", "rounds", ""};
  return words;
}

std::vector<Field<C>> make_cell_fields() {
  return {
      {.json = "id", .member = +[](const C& r) { return r.id(); }},
      {.json = "scene", .member = &C::scene},
      {.json = "batch", .member = &C::batch},
      {.json = "encoder", .member = &C::encoder},
      {.json = "bits", .member = &C::bits},
      {.json = "top_bits", .member = &C::top_bits},
      {.json = "variant", .member = &C::variant, .vocabulary = variants},
      {.json = "access", .member = &C::access, .vocabulary = access_modes},
      {.json = "baseline", .member = &C::baseline, .required_from = kV3,
       .vocabulary = baselines},
      {.json = "layout", .member = &C::layout, .required_from = kV3,
       .vocabulary = trace_layout_names},
      {.json = "rays", .member = &C::rays},
      {.json = "status", .member = &C::status, .vocabulary = cell_statuses},
      // Version 1 had no permute or nosort_trace timing; the reader never required any timing.
      {.json = "encode_ms", .column = "encode", .member = &C::encode, .required_from = kV4},
      {.json = "sort_ms", .column = "sort", .member = &C::sort, .required_from = kV4},
      {.json = "permute_ms", .column = "permute", .member = &C::permute, .required_from = kV4},
      {.json = "trace_ms", .column = "trace", .member = &C::trace, .required_from = kV4},
      {.json = "nosort_trace_ms", .column = "nosort_trace", .member = &C::nosort_trace, .required_from = kV4},
      {.json = "cut_ms", .member = &C::cut_ms, .absent = Absent::WhenNegative,
       .required_from = kV4, .decimals = 3},
      {.json = "trace_mrays", .member = &C::trace_mrays, .interval_of = &C::trace},
      {.json = "speedup", .member = &C::speedup},
      {.json = "net_speedup", .member = &C::net_speedup},
      {.json = "overhead_pct", .member = &C::overhead_pct, .decimals = 3},
      {.json = "aa", .member = &C::aa, .required_from = kV2},
      {.json = "same_order_as_nosort", .member = &C::same_order_as_nosort,
       .required_from = kV2},
      {.json = "rounds", .member = &C::rounds, .required_from = kV2},
      {.json = "stopped_by", .member = &C::stopped_by, .required_from = kV2,
       .vocabulary = stop_reasons},
      {.json = "noise", .member = &C::noise, .required_from = kV2, .decimals = 5},
      {.json = "samples", .member = &C::samples, .required_from = kV2},
      {.json = "anc", .member = &C::anc},
      {.json = "simt_lane_efficiency", .member = &C::simt_lane_efficiency,
       .decimals = 6},
      {.json = "simt_distinct_per_visit", .member = &C::simt_distinct_per_visit, .decimals = 6},
      {.json = "simt_lane_efficiency_ratio", .member = &C::simt_lane_efficiency_ratio, .decimals = 6},
      {.json = "simt_distinct_per_visit_ratio", .member = &C::simt_distinct_per_visit_ratio, .decimals = 6},
      // Added within version 1: older records may lack it.
      {.json = "leaks_per_million", .member = &C::leaks_per_million,
       .absent = Absent::WhenNegative, .required_from = kV4, .decimals = 3},
      {.json = kGpuModelKey, .member = Group{}, .required_from = kGroupsRequiredFrom},
      {.json = "hits_match_nosort", .member = &C::hits_match_nosort},
      {.json = "order_is_permutation", .member = &C::order_is_permutation},
      {.json = "keys_hash", .member = &C::keys_hash},
      {.json = "order_hash", .member = &C::order_hash},
      {.json = "error", .member = &C::error, .quoted = true},
      {.json = kEmbreeKey, .member = Group{}, .required_from = kGroupsRequiredFrom},
  };
}

// The GPU cost model (bench/gpu_model.h): the whole group is absent (null) when the model was off.
std::vector<Field<G>> make_gpu_model_fields() {
  return {
      {.json = "profile", .column = "gpu_model", .member = &G::profile},
      {.json = "speedup", .column = "gpu_model_speedup", .member = &G::speedup},
      {.json = "time_us", .column = "gpu_model_time_us", .member = &G::time_us, .decimals = 3},
      {.json = "warp_steps", .column = "gpu_warp_steps", .member = &G::warp_steps},
      {.json = "idle_lanes", .column = "gpu_idle_lanes", .member = &G::idle_lanes},
      {.json = "l1_hits", .column = "gpu_l1_hits", .member = &G::l1_hits},
      {.json = "l1_misses", .column = "gpu_l1_misses", .member = &G::l1_misses},
      {.json = "l2_hits", .column = "gpu_l2_hits", .member = &G::l2_hits},
      {.json = "l2_misses", .column = "gpu_l2_misses", .member = &G::l2_misses},
      {.json = "dram_bytes", .column = "gpu_dram_bytes", .member = &G::dram_bytes},
      {.json = "warps", .column = "gpu_warps", .member = &G::warps},
      {.json = "replayed_warps", .column = "gpu_replayed_warps", .member = &G::replayed_warps},
      // Added within version 3.
      {.json = "steps_l2", .column = "gpu_steps_l2", .member = &G::steps_l2, .required_from = kV4},
      {.json = "steps_dram", .column = "gpu_steps_dram", .member = &G::steps_dram, .required_from = kV4},
      {.json = "ww_steps", .column = "gpu_ww_steps", .member = &G::ww_steps, .required_from = kV4},
  };
}

// One Embree path's figures (its key, "path", names the element and its columns: embree_<path>_...).
// The sorted arm's figures are absent in a NoSort cell, which has no sorted order; version 3 left
// their keys out there.
std::vector<Field<E>> make_embree_fields() {
  constexpr Absent sorted_only = Absent::WithoutSamples;
  return {
      {.json = "speedup", .member = &E::speedup, .absent = sorted_only,
       .samples_of = &E::trace, .required_from = kV4},
      {.json = "trace_ms", .column = kNoStem, .member = &E::trace, .absent = sorted_only, .samples_of = &E::trace,
       .required_from = kV4},
      {.json = "nosort_ms", .column = "nosort", .member = &E::nosort},
      {.json = "trace_mrays", .column = "mrays", .member = DerivedRate{}, .absent = sorted_only,
       .samples_of = &E::trace, .interval_of = &E::trace},
      {.json = "nosort_mrays", .member = DerivedRate{}, .interval_of = &E::nosort},
      {.json = "call", .member = &E::call},
      {.json = "threads", .member = &E::threads},
      {.json = "ties", .member = &E::ties, .absent = sorted_only, .samples_of = &E::trace,
       .required_from = kV4},
      {.json = "differ", .member = &E::differ, .absent = sorted_only, .samples_of = &E::trace,
       .required_from = kV4},
      {.json = "agreement_with_ours", .member = &E::agreement_with_ours,
       .decimals = 6},
  };
}

}  // namespace

const std::vector<Field<C>>& cell_fields() {
  static const std::vector<Field<C>> fields = make_cell_fields();
  return fields;
}

const std::vector<Field<G>>& gpu_model_fields() {
  static const std::vector<Field<G>> fields = make_gpu_model_fields();
  return fields;
}

const std::vector<Field<E>>& embree_fields() {
  static const std::vector<Field<E>> fields = make_embree_fields();
  return fields;
}

}  // namespace raysort
