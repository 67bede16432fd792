#pragma once
// The encoders' knobs as data (issue 41): one row per knob, with its flag, default, range and
// meaning. `raysort run` and `raysort encodebench` make their options from these rows (app/options.h,
// add_encoder_param_options), so they take and refuse the same values with the same message;
// meta.json's matrix records them by the rows (bench/matrix.cpp), `raysort sweep` varies exactly these
// (bench/sweep.cpp), and validate_matrix checks their ranges. A new knob is a field here and a row in
// encoder_params().
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "encode/encoder.h"

namespace raysort {

// The values; each default is the field's initializer.
struct EncoderParams {
  double had_lambda = 0.125;               // λ of HAD, Eq. 1 (paper §4.2.2)
  float twopoint_length_fraction = 0.25f;  // TwoPoint ray length, × largest scene extent (paper §5)
  unsigned direction_bits = 1;             // HCC_DIR: d direction bits after b − d cut bits (appendix)
  unsigned region_bits = 4;                // hcc-region: r bits of the origin's region (2^r regions)
  double traffic_blend = 0.5;              // hcc-traffic, hcc-region: β of (1 − β)·HAD + β·traffic
  unsigned cost_bits = 0;                  // mlhcc-cost: bits of the cost estimate; 0: an eighth of the key
};

// The most region bits hcc-region takes (256 regions).
inline constexpr unsigned kMaxRegionBits = 8;

// One knob.
struct EncoderParam {
  using Field = std::variant<double EncoderParams::*, float EncoderParams::*, unsigned EncoderParams::*>;
  std::string_view key;      // the field's name: meta.json's matrix entry and what `sweep` names
  std::string_view flag;     // the option of `run` and `encodebench`
  Field field;
  double lo, hi;             // the values the option takes (an unsigned field: whole numbers)
  std::string_view meaning;  // the option's help text
  std::string_view label;    // `sweep`'s title for it
  // meta.json's matrix records it only when the matrix runs one of these encoders (empty: always,
  // as sets written before the issue-21 knobs existed had it; a set without the entry resumes).
  std::vector<Encoder> recorded_with;
  // ... and only when it is not the default (whose meaning depends on the key: cost_bits 0).
  bool recorded_when_set = false;

  bool whole() const { return std::holds_alternative<unsigned EncoderParams::*>(field); }
  double value(const EncoderParams& p) const;
  bool is_default(const EncoderParams& p) const;
  // "a whole number from 0 to 8", as the option's refusal says it.
  std::string valid_values() const;
};

// Every knob, in the order `sweep` and the help list them.
inline const std::vector<EncoderParam>& encoder_params() {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  static const std::vector<EncoderParam> rows = {
      {"had_lambda", "--lambda", &EncoderParams::had_lambda, 0, kInf, "HAD lambda (paper Eq. 1; default 0.125)",
       "λ (HAD, Eq. 1)", {}},
      // Stored as a float, so bounded by the float range.
      {"twopoint_length_fraction", "--twopoint-length", &EncoderParams::twopoint_length_fraction, 0,
       std::numeric_limits<float>::max(), "TwoPoint ray length as a fraction of the largest extent (0.25)",
       "TwoPoint average distance (× largest extent)", {}},
      {"direction_bits", "--direction-bits", &EncoderParams::direction_bits, 0, 2 * RS_DIRECTION_LEVELS,
       "HCC_DIR direction bits (fewer than the key's; at most 42; more than 1 runs its two-pass kernels)",
       "HCC_DIR direction bits", {}},
      {"region_bits", "--region-bits", &EncoderParams::region_bits, 0, kMaxRegionBits,
       "hcc-region: key bits that pick the ray origin's region, 2^N regions split at a previous frame's median "
       "origins (0-8, default 4; docs/encoders.md)",
       "hcc-region region bits", {Encoder::HCC_REGION}},
      {"traffic_blend", "--traffic-blend", &EncoderParams::traffic_blend, 0, 1,
       "hcc-traffic and hcc-region: beta of the cut priority (1 - beta) HAD + beta traffic (hcc-traffic: of the "
       "previous batch; hcc-region: of the region's rays in a previous frame; 0-1, default 0.5; docs/encoders.md)",
       "hcc-traffic and hcc-region blend β", {Encoder::HCC_TRAFFIC, Encoder::HCC_REGION}},
      {"cost_bits", "--cost-bits", &EncoderParams::cost_bits, 1, 31,
       "mlhcc-cost: key bits of the traversal-cost estimate from a previous frame (1-31 and fewer than half the "
       "key; default an eighth of the key; docs/encoders.md)",
       "mlhcc-cost cost bits", {Encoder::MLHCC_COST}, true},
  };
  return rows;
}

// The row of a knob by its key; throws Error for another key.
const EncoderParam& encoder_param(std::string_view key);
// Sets the field of `row` in `to` to its value in `from`.
void copy_param(const EncoderParam& row, const EncoderParams& from, EncoderParams& to);
// "" when every knob is its default or in its range, else the refusal of the first that is not, as
// the option would refuse it ("--region-bits 9 is not valid: give a whole number from 0 to 8").
std::string params_problem(const EncoderParams& p);

}  // namespace raysort
