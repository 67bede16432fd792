#pragma once
// The cost-cut family, mlhcc-cost (issue 21; docs/encoders.md): MLHCC's two-level cut with a shorter
// low level, then the quantised mean traversal steps that rays like this one took in a previous
// frame (cl/keys_cut.h, rs_cost_cut_code).
#include <cstdint>
#include <vector>

#include "bvh/cut.h"
#include "encode/cut_tables.h"
#include "encode/encode_scene.h"
#include "encode/encoder_family.h"

namespace raysort {

// mlhcc-cost's split of a key of `bits` bits (cl/keys_cut.h, rs_cost_cut_code): the top-level
// cut's bits (half the key, as MLHCC), the cost estimate's (params.cost_bits, or an eighth of the
// key and at least 1) and the low-level cut's (the rest).
struct CostSplit {
  unsigned top_bits = 0, low_bits = 0, cost_bits = 0;
};
CostSplit cost_split(unsigned bits, const EncoderParams& params);

// mlhcc-cost's statistics of one batch (a previous frame's, the same batch name): per cost bin
// (rs_cost_bin in `frame`), the mean of `steps` (each ray's traversal steps, trace_reference's
// node_visits) in sixteenths of a step, rounded down; a bin no ray fell in takes its origin cell's
// mean over every direction, and a cell with no rays the batch's mean. Deterministic.
std::vector<std::uint64_t> cost_statistics(const RsEncodeFrame& frame, const std::vector<RsRay>& rays,
                                           const std::vector<std::uint32_t>& steps);

// mlhcc-cost's input: the mean traversal steps per cost bin (cl/keys_cut.h, rs_cost_bin) of a
// previous frame's batch, in sixteenths of a step (cost_statistics). Empty (the default): no
// estimate, the cost field is 0 and the key is the cut alone. Setting it drops mlhcc-cost's
// cached tables; the other encoders' inputs stay.
void set_cost_estimates(EncodeScene& scene, std::vector<std::uint64_t> mean_steps);

// mlhcc-cost for keys of `bits` bits: the two-level cut of top_bits top nodes with low-level cuts
// of low_bits nodes (two_level_cut), its tables (two_level_tables, rows of low_bits boxes), and
// per bin the estimate quantised to cost_bits: mean · 2^cost_bits / (largest mean + 1).
struct CostCutInputs : TwoLevelTables {
  CostSplit split;
  TwoLevelCut cut;
  std::vector<rs_u32> cost;  // RS_COST_BINS entries
};
const CostCutInputs& cost_cut_inputs(const EncodeScene& scene, unsigned bits);

// What mlhcc-cost learns from the same batch of a previous frame (LearnsFrom::PreviousFrame).
struct CostEstimates : LearnedInput {
  std::vector<std::uint64_t> mean_steps;
};

}  // namespace raysort
