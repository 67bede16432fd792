#pragma once
// One record per benchmark cell (scene × batch × encoder × bits × variant × access): the single
// record type behind every table, plot, CSV/JSON row and comparison (no figure is computed a
// second way). How each field is written, read, tabulated and compared is data, in one table per
// part of the record: bench/record_fields.h. A new field is a member here and a row there.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "bench/protocol.h"
#include "util/fnv.h"  // keys_hash and order_hash are FNV-1a

namespace raysort {

// Bump when the meaning or layout of a field changes; readers refuse versions they do not know.
//   1: point speedups, timings as median/min/max.
//   2: paired measurement (bench/protocol.h): speedups with 95 % intervals, the A/A check, the
//      stopping rule's outcome and the raw per-round samples. Version 1 records are still read
//      (their figures have no intervals).
//   3: each cell records its baseline order (pixel, shuffled: an axis, in the id when shuffled)
//      and the BVH layout its trace and SIMT model walk (wide, binary); NoSort's ANC is null.
//      Version 1-2 records read as pixel and wide, but their SIMT model walked the binary tree
//      while their trace walked the wide one (docs/design.md, "SIMT model").
//      Within version 3, the trace class became an axis (several per set): it is in the id when not
//      wide (".../packet8"). Files written before name their cell without it and are still read.
//   4: one way to write an absent field (bench/record_field.h, Absent): JSON null, the key always
//      written. Version 3 wrote -1 for leaks_per_million, left out cut_ms, the "gpu_model" object,
//      the "embree" list and an Embree path's sorted-arm figures, and may lack the keys added within
//      it; such records read as before (bench/record_json.cpp). From version 4 every key is required.
constexpr int kResultFormatVersion = 4;
constexpr int kOldestReadableFormatVersion = 1;

// The encoder name of the baseline cells (rays traced in generation order): encoder_name(NoSort).
inline constexpr const char* kBaselineEncoder = "nosort";

struct CellRecord {
  // Identity of the cell.
  std::string scene, batch, encoder;
  unsigned bits = 0;       // key bits (0 for NoSort)
  unsigned top_bits = 0;   // sort by the highest top_bits only (0: all bits)
  std::string variant = "robust";  // trace variant ("robust" default, "fast")
  std::string access = "gather";   // rays read through the order (gather) or permuted first
  std::string baseline = "pixel";  // NoSort's order, the one the sort starts from (render/batches.h)
  std::string layout = "wide";     // the trace class: the tree the kernel and SIMT model walk, rays per work-item
  std::uint64_t rays = 0;

  // Outcome.
  std::string status = "ok";  // "ok", "failed", "timeout"
  std::string error;          // why, when not ok

  // Timings (OpenCL profiling events, one sample per round of the protocol): median, its 95 %
  // interval and the range. trace is this cell's trace (of the permuted rays in a permute cell);
  // nosort_trace the NoSort trace measured in the same rounds.
  Timing encode, sort, permute, trace, nosort_trace;

  // Derived figures (the paper's Tables 2-7 columns), each a paired estimate over the rounds.
  double trace_mrays = 0.0;  // rays / trace median
  Estimate speedup;          // NoSort trace / trace, per round. Exactly 1 when same_order_as_nosort
  Estimate net_speedup;      // NoSort trace / (encode + sort + permute + trace), per round
  Estimate overhead_pct;     // (encode + sort + permute) / trace · 100, per round
  // The A/A check: a second NoSort trace of the same rounds / the NoSort trace. Its interval
  // should contain 1 in about 95 % of cells; the result set reports how often it does.
  Estimate aa;
  // The sorted order equals the generation order (e.g. Origin on primary rays, whose origins are
  // all the camera): the same rays in the same order were traced, so no speedup is reported.
  bool same_order_as_nosort = false;

  // The stopping rule (bench/protocol.h): timed rounds, what ended them ("noise", "time",
  // "rounds") and the speedup interval's relative half-width then.
  unsigned rounds = 0;
  std::string stopped_by;
  double noise = 0.0;
  // Raw samples, one per round: "nosort", "aa", "encode", "sort", "permute", "trace" (ms).
  Series samples;

  // Distinct keys per 32 consecutive sorted rays. NaN (JSON null, an empty CSV field) for NoSort,
  // which has no keys, and for a cell that failed before its order was checked. (Sets written
  // before this was fixed stored 0 for NoSort; they are read as null.)
  double anc = std::numeric_limits<double>::quiet_NaN();
  double simt_lane_efficiency = 0.0;
  double simt_distinct_per_visit = 0.0;
  double simt_lane_efficiency_ratio = 0.0;      // vs NoSort on the same batch
  double simt_distinct_per_visit_ratio = 0.0;   // vs NoSort (lower is better)

  // The GPU cost model (bench/gpu_model.h, docs/gpu-model.md; `run --gpu-model NAME`): the
  // profile's name ("" when the model was off: then every figure below is absent), the replay's
  // counts and the predicted trace time and speedup over NoSort on the same batch. Deterministic.
  struct GpuModelFigures {
    std::string profile;
    double time_us = std::numeric_limits<double>::quiet_NaN();
    double speedup = std::numeric_limits<double>::quiet_NaN();
    std::uint64_t warp_steps = 0, idle_lanes = 0, l1_hits = 0, l1_misses = 0, l2_hits = 0, l2_misses = 0;
    std::uint64_t dram_bytes = 0, warps = 0, replayed_warps = 0;
    std::uint64_t steps_l2 = 0, steps_dram = 0;  // warp steps whose slowest read reached L2 / DRAM
    std::uint64_t ww_steps = 0;  // a while-while kernel's issued steps (GpuCounts::ww_steps)
  } gpu;

  // NoSort cells of a run with both trace variants: rays this variant misses that the other one
  // hits, per million rays (for the fast variant: its leaks through shared edges and vertices).
  // -1 when not measured (absent: null in the file).
  double leaks_per_million = -1.0;

  // hcc-traffic, hcc-region and mlhcc-cost cells (issue 21): the host time, ms, of the per-batch
  // input (docs/measurement.md): counting the traffic or statistics it learns from, plus building
  // and uploading its cut or tables for this key length. Not part of encode (the kernel time) or of
  // net_speedup. -1 for other cells (absent: null in the file).
  double cut_ms = -1.0;

  // Embree's paths on this cell's rays (`run --embree-paths`, docs/measurement.md "Embree on
  // sorted orders"): per path, Embree tracing the batch in NoSort order and, in a sorted cell, in
  // the cell's sorted order (gather: through the order; permute: the rays moved into sorted order
  // on the host first, outside the timed arm), both arms of the cell's own rounds, by wall clock.
  // Empty (an empty list in the file, no columns in cells.csv) when the run named no path: every
  // older set reads so.
  struct EmbreeFigures {
    std::string path;      // its --embree-paths key: "16-coherent"
    std::string call;      // the call and flag it made on this batch: "rtcIntersect16 coherent"
    unsigned threads = 0;  // EmbreeScene::threads(): each arm's threads, the calling one included
    Timing nosort;         // the NoSort-order arm (samples "embree:<path>:nosort")
    Timing trace;          // the sorted-order arm (samples "embree:<path>:trace"); n == 0 in a NoSort cell
    // nosort / trace, per round (Hodges-Lehmann, signed-rank interval): what the cell's order buys
    // this path. Exactly 1 when same_order_as_nosort; no value (NaN) in a NoSort cell.
    Estimate speedup;
    // The sorted-order hits scattered back against the NoSort-order ones, ray by ray: rays with
    // another triangle at the same t (a tie), and rays that differ otherwise (a cell with any of
    // these fails). Both 0 in a NoSort cell.
    std::uint64_t ties = 0, differ = 0;
    // Embree's NoSort hits against our NoSort hits (same triangle or a tie, as `trace --reference
    // embree` counts them): the anchor that both traced the same rays.
    double agreement_with_ours = std::numeric_limits<double>::quiet_NaN();
  };
  std::vector<EmbreeFigures> embree;
  const EmbreeFigures* embree_path(const std::string& key) const;

  // Checks and fingerprints (deterministic: equal on every device for the same command).
  bool hits_match_nosort = false;  // sorted trace scattered back == NoSort hits, bit for bit
  bool order_is_permutation = false;
  std::string keys_hash;   // FNV-1a 64 of the key array (generation order), hex
  std::string order_hash;  // FNV-1a 64 of the sorted order, hex

  std::string id() const;  // "scene/batch/encoder/bits[/topK][/variant][/class][/access][/baseline]"
  // The id a cell had before the trace class was an axis (one per set): without the class.
  std::string id_before_class_axis() const;
  bool ok() const { return status == "ok"; }
};

void to_json(nlohmann::json& j, const CellRecord& r);
void from_json(const nlohmann::json& j, CellRecord& r);

// Why a record read from disk cannot be a cell this raysort wrote, or "" when it can: a status
// outside the vocabulary (ok, failed, timeout), a negative or non-finite time or count, a trace
// variant, access mode or stopping reason this raysort does not know.
std::string cell_record_problem(const CellRecord& r);
inline const std::vector<std::string>& cell_statuses() {
  static const std::vector<std::string> s{"ok", "failed", "timeout"};
  return s;
}

}  // namespace raysort
