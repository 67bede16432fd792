#pragma once
// How raysort measures time: the one protocol behind every timed figure of `raysort run`,
// `raysort trace` and `raysort encodebench`. docs/measurement.md explains it with its reasons and
// the figures that back them; this header is the reference.
//
// A measurement times a few *arms* against each other. For a matrix cell: the NoSort trace, a
// second NoSort trace (the A/A check) and the sorted trace; for `trace --variant both` the two
// variants; for encodebench an encode and a trace of the same batch.
//
//  1. Warm-up. `warmup` untimed rounds of every arm: kernels are compiled at their first launch
//     (PoCL), buffers are touched, caches and clocks settle.
//  2. Rounds. A round runs the prologue (the work every arm of the round depends on, e.g. encode
//     and sort) and then every arm once, in an order drawn from a seeded generator. Arms compared
//     with each other ran within one round, so the machine's drift is common to both, and no arm
//     always runs first or always right after the prologue.
//  3. Estimate. A figure that compares two arms (a speedup) is paired: per round the log of the
//     ratio of the two arms' times; the estimate is their Hodges–Lehmann location (the median of the
//     Walsh averages (l_i + l_j) / 2, i <= j) and the interval the Walsh averages at the ranks of the
//     exact Wilcoxon signed-rank distribution (ratio_interval). This needs independent rounds and
//     a log ratio symmetric about its centre, and nothing else: with the arms in a random order
//     their noise is alike, and the difference of two alike noises is symmetric however skewed
//     each is (trace times on a shared CPU are bimodal: two cores, or one while the host lends the
//     other away). One arm's time is the median of its samples, with the distribution-free
//     interval of a median: the order statistics x(k) and x(n+1-k) of the sign test
//     (median_interval), which needs no symmetry.
//  4. Stopping rule (after nvbench's). At least min_rounds rounds; then stop as soon as every
//     target figure's interval has a relative half-width of at most max_noise, or when max_time_s
//     of sampling has passed, or at max_rounds. Which of the three stopped it is recorded.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "util/error.h"

namespace raysort {

// ---- Step 3: the estimate and its interval ----------------------------------------------------

inline constexpr double kConfidence = 0.95;

// A median and its confidence interval. lo and hi are NaN when there are too few samples for an
// interval at the requested confidence (fewer than 6 at 95 %).
struct Estimate {
  double value = std::numeric_limits<double>::quiet_NaN();
  double lo = std::numeric_limits<double>::quiet_NaN();
  double hi = std::numeric_limits<double>::quiet_NaN();
  std::size_t n = 0;  // samples (rounds) it was estimated from

  bool has_value() const { return std::isfinite(value); }
  bool has_interval() const { return std::isfinite(lo) && std::isfinite(hi); }
  // (hi − lo) / 2 relative to the value: the "noise" the stopping rule compares with max_noise.
  // Infinite without an interval.
  double relative_half_width() const;
  bool contains(double x) const { return has_interval() && lo <= x && x <= hi; }
  // Both have intervals and they share a point.
  bool overlaps(const Estimate& o) const { return has_interval() && o.has_interval() && lo <= o.hi && o.lo <= hi; }
  // An exact value with no uncertainty (e.g. a speedup that is 1 by definition).
  static Estimate exact(double v) { return {v, v, v, 0}; }
};

// The sign-test rank: the largest k >= 1 with 2 · P(Binomial(n, 1/2) <= k − 1) <= 1 − confidence,
// so that [x(k), x(n+1−k)] of n sorted samples covers the median with probability at least
// `confidence` (exactly median_coverage(n, k) for a continuous distribution). 0 when no k qualifies.
std::size_t median_interval_rank(std::size_t n, double confidence = kConfidence);
// 1 − 2 · P(Binomial(n, 1/2) <= k − 1): the exact coverage of [x(k), x(n+1−k)].
double median_coverage(std::size_t n, std::size_t k);

// The sample median (the mean of the two middle values for an even count) with its interval.
// Non-finite samples are an Error (a time of NaN means a broken event, not noise).
Estimate median_interval(std::vector<double> samples, double confidence = kConfidence);

// The signed-rank rank: the largest k >= 1 with 2 · P(W <= k − 1) <= 1 − confidence, W the Wilcoxon
// signed-rank statistic of n samples (exact distribution up to n = 100, its normal approximation
// with continuity correction above), so that the Walsh averages w(k) and w(M+1−k), M = n(n+1)/2,
// bound the centre of a symmetric distribution with probability at least `confidence` (exactly
// signed_rank_coverage(n, k) for a continuous one). 0 when no k qualifies (n < 6 at 95 %).
std::size_t signed_rank_interval_rank(std::size_t n, double confidence = kConfidence);
double signed_rank_coverage(std::size_t n, std::size_t k);  // 1 − 2 · P(W <= k − 1)

// The Hodges–Lehmann location of samples from a symmetric distribution (the median of the Walsh
// averages) with its signed-rank interval.
Estimate hodges_lehmann_interval(const std::vector<double>& samples, double confidence = kConfidence);

// Per-round ratios num[i] / den[i] (equal lengths), and the paired estimate of their typical value:
// exp of the Hodges–Lehmann interval of the log ratios. No estimate when a ratio is not a positive
// finite number (an empty batch's zero times).
std::vector<double> per_round_ratios(const std::vector<double>& num, const std::vector<double>& den);
Estimate ratio_interval(const std::vector<double>& num, const std::vector<double>& den,
                        double confidence = kConfidence);
// Per-round sums of several series of equal length (e.g. encode + sort + trace).
std::vector<double> per_round_sums(const std::vector<const std::vector<double>*>& series);

// One timed quantity summarised: its median with the interval, and the range of its samples.
struct Timing {
  double median_ms = 0.0, min_ms = 0.0, max_ms = 0.0;
  double lo_ms = std::numeric_limits<double>::quiet_NaN(), hi_ms = std::numeric_limits<double>::quiet_NaN();
  std::size_t n = 0;
  static Timing of(const std::vector<double>& samples);  // no samples: zeros, no interval
  Estimate estimate() const { return {median_ms, lo_ms, hi_ms, n}; }
};

// An estimate as text: "value [lo, hi]", or the value alone without an interval, or "–" without a
// value. Speedups and ratios get three decimals, so that an interval printed next to 1 says on which
// side of 1 it lies ("0.984 [0.962, 0.996]", not "0.98 [0.96, 1.00]").
std::string interval_text(const Estimate& e, int decimals = 3);

// ---- Steps 1, 2 and 4: warm-up, rounds, stopping rule ------------------------------------------

struct ProtocolSettings {
  unsigned warmup = 1;       // untimed rounds first
  // The fewest timed rounds. 6 is the fewest with a 95 % interval at all (then [min, max]); from 7
  // on the signed-rank interval leaves out the extremes, so it narrows quickly.
  unsigned min_rounds = 7;
  unsigned max_rounds = 1000;
  double max_noise = 0.02;   // target relative half-width of every target's interval
  double max_time_s = 5.0;   // sampling budget; past it (and min_rounds) the measurement stops
  // A hard limit on the whole measurement, warm-up included (run --timeout; 0: none); shared rounds
  // get it once per group. Checked between arms: a kernel in flight runs to completion. Past it,
  // measure() throws TimedOut.
  double hard_limit_s = 0.0;
  std::uint64_t seed = 1;    // of the arm order
  double confidence = kConfidence;
  // Set by a signal handler (run's Ctrl-C): checked between arms, measure() then throws Interrupted.
  const std::atomic<bool>* interrupted = nullptr;
  // Called after every timed round of shared rounds with the rounds so far and the groups still
  // measuring (run's progress line while a batch's rounds go on); may be empty.
  std::function<void(unsigned rounds, std::size_t measuring, std::size_t groups)> on_round;
};

enum class StopReason { Noise, Time, Rounds };
const char* stop_reason_name(StopReason r);  // "noise", "time", "rounds"

// The samples of a measurement: one value per timed round for every stage name.
using Series = std::map<std::string, std::vector<double>>;

// Something timed once per round. run() does it once and returns the milliseconds of each of its
// stages, in the order of `stages` (names unique within a measurement: they key the Series).
struct Arm {
  std::vector<std::string> stages;
  std::function<std::vector<double>()> run;
};

struct Measurement {
  Arm prologue;           // runs first in every round when it has a run(); e.g. encode + sort
  std::vector<Arm> arms;  // then these, in a seeded random order
  // The figures the stopping rule watches; each is computed from the series so far.
  std::vector<std::function<Estimate(const Series&)>> targets;
};

struct Outcome {
  Series series;
  unsigned rounds = 0;
  StopReason stop = StopReason::Rounds;
  double noise = std::numeric_limits<double>::infinity();  // the largest target half-width at the stop
  double sampling_s = 0.0;                                 // wall clock of the timed rounds
};

// Thrown by measure() past ProtocolSettings::hard_limit_s.
struct TimedOut : Error {
  using Error::Error;
};

// Thrown by measure() once ProtocolSettings::interrupted is set: the measurement is abandoned (its
// cell is not recorded and runs again on resume). Not an Error, so no handler of bad input or
// device faults turns it into a failed cell.
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

Outcome measure(const Measurement& m, const ProtocolSettings& s);

// ---- Shared rounds: the cells of one batch measured together (issue 42) -----------------------
//
// A batch's cells all compare their trace with the same NoSort trace. Measured one cell at a time,
// each cell pays for its own NoSort and A/A traces every round: three traces per measured order.
// Shared, each round runs the batch's common arms (NoSort, A/A) once for every group still active:
//
//  - A round runs every active group's prologue (its encode + sort), in a seeded order, then the
//    common arms and every active group's arms in one seeded random order (step 2 over all of them).
//  - Each group has its own targets and stopping rule (step 4): it retires once its targets are
//    within max_noise after min_rounds, or at max_rounds; its arms stop, the others go on. So a
//    group's rounds are the first `rounds` of the batch, and its figures pair its arms with the
//    common arms of exactly those rounds: the estimates keep their guarantees.
//  - The sampling budget is max_time_s per group (a cell's budget, as before): a group's time is its
//    own prologue and arms plus an equal share, among the groups measuring in that round, of the
//    rest of the round (the common arms, the checks between rounds). So a noisy group stops after
//    its own budget, not the batch's, and with one group its time is the sampling wall clock. The
//    hard limit is hard_limit_s × groups (--timeout stays a cell's).
// measure() is the case of one group without common arms, round for round the same.
struct MeasurementGroup {
  Arm prologue;  // optional: runs first in every round the group is active
  std::vector<Arm> arms;
  std::vector<std::function<Estimate(const Series&)>> targets;  // over the group's and the common series
};

struct SharedMeasurement {
  std::vector<Arm> common;  // run in every round while any group is active
  std::vector<MeasurementGroup> groups;
};

// One Outcome per group: its own stages and the common ones over the rounds it was active, its
// rounds, stop and noise; sampling_s is the batch's. Stage names must be unique within a group and
// across the common arms (a group's may repeat another group's).
std::vector<Outcome> measure_shared(const SharedMeasurement& m, const ProtocolSettings& s);

// A measurement's seed from a text that names it (e.g. "1/sibenik/bounce1/hcc/32"): FNV-1a 64, the
// same on every platform, so the same command draws the same arm orders.
std::uint64_t protocol_seed(const std::string& key);

// The order of `count` arms in round `round` (0-based, warm-up rounds first) of a measurement
// seeded with `seed`: a Fisher–Yates shuffle driven by SplitMix64, the same on every platform.
std::vector<std::size_t> round_order(std::size_t count, std::uint64_t seed, std::uint64_t round);

}  // namespace raysort
