#pragma once
// Side-by-side comparison of two result sets (two devices, or two commits) and regression rules,
// so PoCL runs can serve as regression tests in CI.
#include <string>
#include <vector>

#include "bench/result_set.h"

namespace raysort {

// A rule "METRIC OP THRESHOLD" checked per cell present in both sets (B against A):
//   speedup<-5%       fail if B is more than 5 % below A (relative)
//   overhead_pct>+10% fail if B is more than 10 % above A
//   anc!=             fail on any difference (exact; also for keys_hash, order_hash, status)
//   anc!=0.01         fail if |B − A| > 0.01
//   missing           fail if a cell of A is absent from B (or failed in B but not in A)
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
};

CompareResult compare_result_sets(const ResultSet& a, const ResultSet& b, const std::vector<std::string>& metrics,
                                  const std::vector<FailRule>& rules);

}  // namespace raysort
