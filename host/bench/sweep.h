#pragma once
// A hyperparameter sweep side by side (paper appendix, "Hyperparameters Selection": HAD's λ for HCC,
// the average distance for TwoPoint): result sets that ran one matrix at different values of one
// encoder parameter (`raysort run --lambda`, `--twopoint-length`, `--direction-bits`), read back
// and laid out one column per value. The parameter is found, not named: it is the one matrix entry
// in which the sets differ; sets that differ in anything else (scenes, spp, protocol) are refused,
// since their columns would not be comparable.
#include <string>
#include <vector>

#include "bench/record.h"

namespace raysort {

struct SweepPoint {
  std::string dir;
  double value = 0;                 // the swept parameter in this set
  std::vector<CellRecord> cells;
};

struct Sweep {
  std::string parameter;            // the matrix key: "had_lambda", "twopoint_length_fraction", "direction_bits",
                                    // "region_bits", "traffic_blend", "cost_bits"
  std::vector<SweepPoint> points;   // by ascending value
};

// Loads the sets and finds the swept parameter. Throws Error naming the sets and the entries in
// which they differ when that is not exactly one sweepable parameter, or when two sets share a value.
Sweep load_sweep(const std::vector<std::string>& dirs);

// Markdown: per batch and encoder, one row per scene and one column per value, each cell "SIMT
// lane-efficiency ratio · PoCL speedup" with the row's best ratio in bold (deterministic: no
// interval decides it), and a last row with the mean ratio over the scenes.
std::string render_sweep(const Sweep& sweep);

}  // namespace raysort
