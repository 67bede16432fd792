#pragma once
// Side-by-side comparison of two result sets (two devices, or two commits) and regression rules,
// so PoCL runs can serve as regression tests in CI.
#include <string>
#include <vector>

#include "bench/record_columns.h"
#include "bench/result_set.h"

namespace raysort {

// A rule "METRIC OP THRESHOLD" checked per cell present in both sets (B against A):
//   speedup<-5%       fail if B is more than 5 % below A (relative) and the change is significant
//   overhead_pct>+10% fail if B is more than 10 % above A and the change is significant
//   anc!=             fail on any difference (exact; every column, text ones too: keys_hash, status...)
//   anc!=0.01         fail if |B − A| > 0.01 (number columns)
//   status!=ok        fail if a cell of B has another value (text columns)
//   status==timeout   fail if a cell of B has this value (text columns)
//   missing           fail if a cell of A is absent from B (or failed in B but not in A)
// Every column of cells.csv is a metric (bench/record_columns.h, made from the record's field
// table); a text column whose values form a closed set (status, stopped_by, the true/false flags)
// refuses a value outside it.
// Significant (relative rules on the figures with an interval: speedup, net_speedup, overhead_pct,
// aa, trace_mrays, the stage times and Embree's): the change passes the threshold even between the nearest ends
// of the two cells' 95 % intervals (speedup<-5%: B's upper end is more than 5 % below A's lower
// end; with 0 % the intervals merely do not overlap), so a change inside the measurement noise does
// not fire (docs/measurement.md, "Comparing result sets").
// A figure without an interval in either set (a version 1 set, fewer than 6 rounds) falls back to
// the point rule, and the report says so. Deterministic figures (anc, simt_*) have no interval.
struct FailRule {
  std::string metric;
  enum Kind { RelativeDrop, RelativeRise, AnyChange, AbsoluteChange, Missing, ValueIs, ValueIsNot } kind = AnyChange;
  double threshold = 0.0;
  std::string value;  // ValueIs, ValueIsNot
  static FailRule parse(const std::string& text);  // throws Error with the grammar and metric names
  std::string text;
};

// Metric names compare knows: the columns of cells.csv (without an Embree path's).
std::vector<std::string> comparable_metrics();

struct CompareResult {
  std::string report;                  // markdown tables
  std::vector<std::string> violations; // one line per rule broken
  // Point changes past a relative rule's threshold whose intervals overlap: not fired.
  std::vector<std::string> within_noise;
  // The scene files the two sets traced, where their checksums differ (meta.json "scene_files",
  // scene/provenance.h): results on different files are not comparable, whatever the rules say.
  std::vector<std::string> scene_files;
  // Likewise the encoders from files (meta.json "encoder_files", bench/encoder_files.h) and the ray
  // batches from files ("ray_files").
  std::vector<std::string> encoder_files;
  std::vector<std::string> ray_files;
};

// The two sets must have run one matrix (scenes, batches, encoders, bits, resolution, spp, seed,
// variants, access modes, encoder parameters; the device and the measurement settings — reps,
// warm-up, noise and time targets — may differ), or Error lists what differs, unless
// allow_different_matrix (then the report says so).
CompareResult compare_result_sets(const ResultSet& a, const ResultSet& b, const std::vector<std::string>& metrics,
                                  const std::vector<FailRule>& rules, bool allow_different_matrix = false);

// What differs between the matrices of two sets, leaving out the measurement settings; "" if nothing.
std::string matrix_mismatch(const ResultSet& a, const ResultSet& b);

}  // namespace raysort
