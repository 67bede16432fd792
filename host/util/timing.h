#pragma once
// Median, min and max of repeated timings (OpenCL profiling events), the one summary every timed
// figure in raysort uses: result-set cells, `raysort trace`, `raysort encodebench`.
#include <algorithm>
#include <vector>

namespace raysort {

struct Timing {
  double median_ms = 0.0, min_ms = 0.0, max_ms = 0.0;
  // The median of an even number of samples is the mean of the two middle ones. No samples: zeros.
  static Timing of(std::vector<double> s) {
    Timing t;
    if (s.empty()) return t;
    std::sort(s.begin(), s.end());
    t.median_ms = s.size() % 2 ? s[s.size() / 2] : 0.5 * (s[s.size() / 2 - 1] + s[s.size() / 2]);
    t.min_ms = s.front();
    t.max_ms = s.back();
    return t;
  }
};

}  // namespace raysort
