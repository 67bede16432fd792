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
      {.json = "id", .column = "id", .member = +[](const C& r) { return r.id(); }},
      {.json = "scene", .column = "scene", .member = &C::scene},
      {.json = "batch", .column = "batch", .member = &C::batch},
      {.json = "encoder", .column = "encoder", .member = &C::encoder},
      {.json = "bits", .column = "bits", .member = &C::bits},
      {.json = "top_bits", .column = "top_bits", .member = &C::top_bits},
      {.json = "variant", .column = "variant", .member = &C::variant, .vocabulary = variants},
      {.json = "access", .column = "access", .member = &C::access, .vocabulary = access_modes},
      {.json = "baseline", .column = "baseline", .member = &C::baseline, .required_from = kV3,
       .vocabulary = baselines},
      {.json = "layout", .column = "layout", .member = &C::layout, .required_from = kV3,
       .vocabulary = trace_layout_names},
      {.json = "rays", .column = "rays", .member = &C::rays},
      {.json = "status", .column = "status", .member = &C::status, .vocabulary = cell_statuses},
      // Version 1 had no permute or nosort_trace timing; the reader never required any timing.
      {.json = "encode_ms", .column = "encode", .member = &C::encode, .required_from = kV4},
      {.json = "sort_ms", .column = "sort", .member = &C::sort, .required_from = kV4},
      {.json = "permute_ms", .column = "permute", .member = &C::permute, .required_from = kV4},
      {.json = "trace_ms", .column = "trace", .member = &C::trace, .required_from = kV4},
      {.json = "nosort_trace_ms", .column = "nosort_trace", .member = &C::nosort_trace, .required_from = kV4},
      {.json = "cut_ms", .column = "cut_ms", .member = &C::cut_ms, .absent = Absent::WhenNegative,
       .required_from = kV4, .decimals = 3},
      {.json = "trace_mrays", .column = "trace_mrays", .member = &C::trace_mrays, .interval_of = &C::trace},
      {.json = "speedup", .column = "speedup", .member = &C::speedup},
      {.json = "net_speedup", .column = "net_speedup", .member = &C::net_speedup},
      {.json = "overhead_pct", .column = "overhead_pct", .member = &C::overhead_pct, .decimals = 3},
      {.json = "aa", .column = "aa", .member = &C::aa, .required_from = kV2},
      {.json = "same_order_as_nosort", .column = "same_order_as_nosort", .member = &C::same_order_as_nosort,
       .required_from = kV2},
      {.json = "rounds", .column = "rounds", .member = &C::rounds, .required_from = kV2},
      {.json = "stopped_by", .column = "stopped_by", .member = &C::stopped_by, .required_from = kV2,
       .vocabulary = stop_reasons},
      {.json = "noise", .column = "noise", .member = &C::noise, .required_from = kV2, .decimals = 5},
      {.json = "samples", .column = "", .member = &C::samples, .required_from = kV2},
      {.json = "anc", .column = "anc", .member = &C::anc},
      {.json = "simt_lane_efficiency", .column = "simt_lane_efficiency", .member = &C::simt_lane_efficiency,
       .decimals = 6},
      {.json = "simt_distinct_per_visit", .column = "simt_distinct_per_visit",
       .member = &C::simt_distinct_per_visit, .decimals = 6},
      {.json = "simt_lane_efficiency_ratio", .column = "simt_lane_efficiency_ratio",
       .member = &C::simt_lane_efficiency_ratio, .decimals = 6},
      {.json = "simt_distinct_per_visit_ratio", .column = "simt_distinct_per_visit_ratio",
       .member = &C::simt_distinct_per_visit_ratio, .decimals = 6},
      // Added within version 1: older records may lack it.
      {.json = "leaks_per_million", .column = "leaks_per_million", .member = &C::leaks_per_million,
       .absent = Absent::WhenNegative, .required_from = kV4, .decimals = 3},
      {.json = kGpuModelKey, .column = "", .member = Group{}, .required_from = kGroupsRequiredFrom},
      {.json = "hits_match_nosort", .column = "hits_match_nosort", .member = &C::hits_match_nosort},
      {.json = "order_is_permutation", .column = "order_is_permutation", .member = &C::order_is_permutation},
      {.json = "keys_hash", .column = "keys_hash", .member = &C::keys_hash},
      {.json = "order_hash", .column = "order_hash", .member = &C::order_hash},
      {.json = "error", .column = "error", .member = &C::error, .quoted = true},
      {.json = kEmbreeKey, .column = "", .member = Group{}, .required_from = kGroupsRequiredFrom},
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
      {.json = "speedup", .column = "speedup", .member = &E::speedup, .absent = sorted_only,
       .samples_of = &E::trace, .required_from = kV4},
      {.json = "trace_ms", .column = "", .member = &E::trace, .absent = sorted_only, .samples_of = &E::trace,
       .required_from = kV4},
      {.json = "nosort_ms", .column = "nosort", .member = &E::nosort},
      {.json = "trace_mrays", .column = "mrays", .member = DerivedRate{}, .absent = sorted_only,
       .samples_of = &E::trace, .interval_of = &E::trace},
      {.json = "nosort_mrays", .column = "nosort_mrays", .member = DerivedRate{}, .interval_of = &E::nosort},
      {.json = "call", .column = "call", .member = &E::call},
      {.json = "threads", .column = "threads", .member = &E::threads},
      {.json = "ties", .column = "ties", .member = &E::ties, .absent = sorted_only, .samples_of = &E::trace,
       .required_from = kV4},
      {.json = "differ", .column = "differ", .member = &E::differ, .absent = sorted_only, .samples_of = &E::trace,
       .required_from = kV4},
      {.json = "agreement_with_ours", .column = "agreement_with_ours", .member = &E::agreement_with_ours,
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
