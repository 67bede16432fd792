#pragma once
// Side-by-side comparison of two result sets (two devices, or two commits) and regression rules,
// so PoCL runs can serve as regression tests in CI.
#include <string>
#include <vector>

#include "bench/result_set.h"

namespace raysort {

// A rule "METRIC OP THRESHOLD" checked per cell present in both sets (B against A):
//   speedup<-5%       fail if B is more than 5 % below A (relative) and the change is significant
//   overhead_pct>+10% fail if B is more than 10 % above A and the change is significant
//   anc!=             fail on any difference (exact; also for keys_hash, order_hash, status)
//   anc!=0.01         fail if |B − A| > 0.01
//   missing           fail if a cell of A is absent from B (or failed in B but not in A)
// Significant (relative rules on timed figures: speedup, net_speedup, overhead_pct, aa,
// trace_mrays and the stage times): the change passes the threshold even between the nearest ends
// of the two cells' 95 % intervals (speedup<-5%: B's upper end is more than 5 % below A's lower
// end; with 0 % the intervals merely do not overlap), so a change inside the measurement noise does
// not fire (docs/measurement.md, "Comparing result sets").
// A figure without an interval in either set (a version 1 set, fewer than 6 rounds) falls back to
// the point rule, and the report says so. Deterministic figures (anc, simt_*) have no interval.
struct FailRule {
  std::string metric;
  enum Kind { RelativeDrop, RelativeRise, AnyChange, AbsoluteChange, Missing } kind = AnyChange;
  double threshold = 0.0;
  static FailRule parse(const std::string& text);  // throws Error with the grammar and metric names
  std::string text;
};

// Metric names compare knows: numeric fields and fingerprints of CellRecord.
std::vector<std::string> comparable_metrics();

struct CompareResult {
  std::string report;                  // markdown tables
  std::vector<std::string> violations; // one line per rule broken
  // Point changes past a relative rule's threshold whose intervals overlap: not fired.
  std::vector<std::string> within_noise;
};

CompareResult compare_result_sets(const ResultSet& a, const ResultSet& b, const std::vector<std::string>& metrics,
                                  const std::vector<FailRule>& rules);

}  // namespace raysort
