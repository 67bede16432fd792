#pragma once
// One record per benchmark cell (scene × batch × encoder × bits): the single record type behind
// every table, plot, CSV/JSON row and comparison (no figure is computed a second way).
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "util/timing.h"

namespace raysort {

// Bump when the meaning or layout of a field changes; readers refuse other versions clearly.
constexpr int kResultFormatVersion = 1;

// The encoder name of the baseline cells (rays traced in generation order): encoder_name(NoSort).
inline constexpr const char* kBaselineEncoder = "nosort";


struct CellRecord {
  // Identity of the cell.
  std::string scene, batch, encoder;
  unsigned bits = 0;       // key bits (0 for NoSort)
  unsigned top_bits = 0;   // sort by the highest top_bits only (0: all bits)
  std::string variant = "robust";  // trace variant ("robust" default, "fast")
  std::string access = "gather";   // rays read through the order (gather) or permuted
  std::uint64_t rays = 0;

  // Outcome.
  std::string status = "ok";  // "ok", "failed", "timeout"
  std::string error;          // why, when not ok

  // Timings (OpenCL profiling events; median and range over repetitions after warm-up).
  Timing encode, sort, trace;

  // Derived figures (the paper's Tables 2-7 columns).
  double trace_mrays = 0.0;      // rays / trace median
  double speedup = 0.0;          // NoSort trace median / this trace median (same batch)
  double net_speedup = 0.0;      // NoSort trace / (encode + sort + trace)
  double overhead_pct = 0.0;     // (encode + sort) / trace · 100
  double anc = 0.0;              // distinct keys per 32 consecutive sorted rays
  double simt_lane_efficiency = 0.0;
  double simt_distinct_per_visit = 0.0;
  double simt_lane_efficiency_ratio = 0.0;      // vs NoSort on the same batch
  double simt_distinct_per_visit_ratio = 0.0;   // vs NoSort (lower is better)

  // NoSort cells of a run with both trace variants: rays this variant misses that the other one
  // hits, per million rays (for the fast variant: its leaks through shared edges and vertices).
  // -1 when not measured.
  double leaks_per_million = -1.0;

  // Checks and fingerprints (deterministic: equal on every device for the same command).
  bool hits_match_nosort = false;  // sorted trace scattered back == NoSort hits, bit for bit
  bool order_is_permutation = false;
  std::string keys_hash;   // FNV-1a 64 of the key array (generation order), hex
  std::string order_hash;  // FNV-1a 64 of the sorted order, hex

  std::string id() const;  // "scene/batch/encoder/bits[/topK]"
  bool ok() const { return status == "ok"; }
};

void to_json(nlohmann::json& j, const CellRecord& r);
void from_json(const nlohmann::json& j, CellRecord& r);

// FNV-1a 64 over raw bytes, as 16 hex digits.
std::string fnv1a_hex(const void* data, std::size_t bytes);

// CSV header and row, in one column order.
std::string csv_header();
std::string csv_row(const CellRecord& r);

}  // namespace raysort
