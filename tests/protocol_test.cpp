// The measurement protocol (host/bench/protocol.h) on synthetic samples, no device: the interval
// of a median covers the true median as often as its exact coverage says, for skewed and bimodal
// distributions too; so does the paired (Hodges–Lehmann, signed-rank) interval of a ratio whose arms
// share a skewed noise; the paired ratio is immune to drift that moves both arms; the stopping rule
// stops for the reason it reports; warm-up rounds are not recorded; the arm order is a seeded
// permutation that puts every arm first about equally often.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <thread>

#include "bench/protocol.h"

namespace raysort {
namespace {

// Exact ranks and coverages of the sign-test interval, from the binomial distribution.
TEST(Protocol, MedianIntervalRankIsTheExactSignTestRank) {
  const std::pair<std::size_t, std::size_t> ranks[] = {{1, 0}, {5, 0}, {6, 1}, {8, 1},  {9, 2},
                                                       {11, 2}, {12, 3}, {20, 6}, {40, 14}, {100, 40}};
  for (auto [n, k] : ranks) {
    EXPECT_EQ(median_interval_rank(n), k) << "n = " << n;
    if (k > 0) {
      EXPECT_GE(median_coverage(n, k), 0.95) << "n = " << n;
      EXPECT_LT(median_coverage(n, k + 1), 0.95) << "n = " << n;  // k is the largest that qualifies
    }
  }
  EXPECT_DOUBLE_EQ(median_coverage(6, 1), 1.0 - 2.0 / 64.0);
  EXPECT_NEAR(median_coverage(12, 3), 0.96142578125, 1e-12);
  // Thousands of rounds do not underflow.
  EXPECT_GT(median_interval_rank(5000), 2400u);
}

TEST(Protocol, MedianIntervalOfKnownSamples) {
  const Estimate e = median_interval({5, 1, 4, 2, 3, 6, 7, 9, 8});  // n = 9: k = 2
  EXPECT_DOUBLE_EQ(e.value, 5.0);
  EXPECT_DOUBLE_EQ(e.lo, 2.0);
  EXPECT_DOUBLE_EQ(e.hi, 8.0);
  EXPECT_EQ(e.n, 9u);
  EXPECT_TRUE(e.contains(5.0));
  EXPECT_FALSE(e.contains(8.5));
  EXPECT_DOUBLE_EQ(e.relative_half_width(), 0.6);
  const Estimate even = median_interval({4, 1, 3, 2, 6, 5});  // n = 6: [min, max]
  EXPECT_DOUBLE_EQ(even.value, 3.5);
  EXPECT_DOUBLE_EQ(even.lo, 1.0);
  EXPECT_DOUBLE_EQ(even.hi, 6.0);
  // Too few samples: a median, but no interval, and a noise the stopping rule never accepts.
  const Estimate few = median_interval({1, 2, 3});
  EXPECT_DOUBLE_EQ(few.value, 2.0);
  EXPECT_FALSE(few.has_interval());
  EXPECT_TRUE(std::isinf(few.relative_half_width()));
  EXPECT_FALSE(median_interval({}).has_value());
  EXPECT_THROW(median_interval({1, 2, NAN, 3, 4, 5}), Error);
  const Timing t = Timing::of({3, 1, 2, 5, 4, 6});
  EXPECT_DOUBLE_EQ(t.median_ms, 3.5);
  EXPECT_DOUBLE_EQ(t.min_ms, 1.0);
  EXPECT_DOUBLE_EQ(t.max_ms, 6.0);
  EXPECT_DOUBLE_EQ(t.lo_ms, 1.0);
  EXPECT_DOUBLE_EQ(t.hi_ms, 6.0);
}

// Coverage on known distributions: over many simulated measurements, the interval contains the
// true median as often as median_coverage says (within 4 standard errors), at least 95 %.
void expect_coverage(const char* name, double true_median, const std::function<double(std::mt19937_64&)>& draw) {
  std::mt19937_64 rng(20261125);
  const int trials = 4000;
  for (std::size_t n : {6u, 9u, 12u, 20u, 40u}) {
    int covered = 0;
    for (int t = 0; t < trials; ++t) {
      std::vector<double> x(n);
      for (auto& v : x) v = draw(rng);
      covered += median_interval(x).contains(true_median);
    }
    const double expected = median_coverage(n, median_interval_rank(n));
    const double observed = static_cast<double>(covered) / trials;
    const double se = std::sqrt(expected * (1 - expected) / trials);
    EXPECT_GE(expected, 0.95);
    EXPECT_NEAR(observed, expected, 4 * se) << name << ", n = " << n;
  }
}

TEST(Protocol, IntervalCoverageMatchesTheExactCoverage) {
  // Log-normal (right-skewed, like a slowdown-only noise), median e^0.2.
  std::lognormal_distribution<double> lognormal(0.2, 0.3);
  expect_coverage("lognormal", std::exp(0.2), [&](std::mt19937_64& r) { return lognormal(r); });
  // Exponential, median ln 2.
  std::exponential_distribution<double> expo(1.0);
  expect_coverage("exponential", std::log(2.0), [&](std::mt19937_64& r) { return expo(r); });
  // Bimodal, as trace times on a shared 2-core machine: 70 % fast (both cores), 30 % twice as slow.
  // The median lies in the fast mode, at 2 + 0.1 · (0.5 / 0.7).
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  expect_coverage("bimodal", 2.0 + 0.1 * (0.5 / 0.7), [&](std::mt19937_64& r) {
    const double pick = u01(r), x = u01(r);
    return pick < 0.7 ? 2.0 + 0.1 * x : 4.0 + 0.2 * x;
  });
}

// The signed-rank ranks are the classic two-sided 5 % critical values plus one (n = 6: 0, 7: 2,
// 8: 3, 10: 8, 12: 13, 20: 52); the normal approximation takes over above 100 rounds without a jump.
TEST(Protocol, SignedRankRankIsTheExactWilcoxonRank) {
  const std::pair<std::size_t, std::size_t> ranks[] = {{5, 0}, {6, 1}, {7, 3}, {8, 4}, {10, 9}, {12, 14}, {20, 53}};
  for (auto [n, k] : ranks) {
    EXPECT_EQ(signed_rank_interval_rank(n), k) << "n = " << n;
    if (k > 0) {
      EXPECT_GE(signed_rank_coverage(n, k), 0.95) << "n = " << n;
      EXPECT_LT(signed_rank_coverage(n, k + 1), 0.95) << "n = " << n;
    }
  }
  EXPECT_DOUBLE_EQ(signed_rank_coverage(6, 1), 1.0 - 2.0 / 64.0);
  EXPECT_LT(signed_rank_interval_rank(100), signed_rank_interval_rank(101));  // exact, then normal
  EXPECT_LT(signed_rank_interval_rank(101), signed_rank_interval_rank(102));
  EXPECT_GE(signed_rank_coverage(101, signed_rank_interval_rank(101)), 0.95);
  EXPECT_LT(signed_rank_coverage(101, signed_rank_interval_rank(101)), 0.952);
  EXPECT_GE(signed_rank_coverage(500, signed_rank_interval_rank(500)), 0.95);
  EXPECT_LT(signed_rank_coverage(500, signed_rank_interval_rank(500)), 0.952);
  // Hodges–Lehmann of known samples: Walsh averages of {1, 2, 4} are 1, 1.5, 2, 2.5, 3, 4.
  const Estimate hl = hodges_lehmann_interval({4, 1, 2});
  EXPECT_DOUBLE_EQ(hl.value, 2.25);
  EXPECT_FALSE(hl.has_interval());
  const Estimate six = hodges_lehmann_interval({3, 1, 2, 6, 5, 4});  // n = 6: [min, max] of the Walsh averages
  EXPECT_DOUBLE_EQ(six.value, 3.5);
  EXPECT_DOUBLE_EQ(six.lo, 1.0);
  EXPECT_DOUBLE_EQ(six.hi, 6.0);
  // A ratio is estimated on the log scale: ratios 2 and 8 give their geometric centre 4.
  EXPECT_NEAR(ratio_interval({2, 8}, {1, 1}).value, 4.0, 1e-12);
  EXPECT_FALSE(ratio_interval({1, 2, 3, 4, 5, 6}, {1, 0, 1, 1, 1, 1}).has_value());  // a zero time
}

// Coverage of the paired interval: per round, the ratio of two arms whose times have the same
// (here bimodal, very skewed) distribution, times a true speedup. The log ratio is symmetric, so
// the interval covers the true speedup as often as signed_rank_coverage says.
TEST(Protocol, PairedIntervalCoverageOnSkewedArmNoise) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto arm = [&](double ms) {  // 70 %: both cores; 30 %: one core, twice as slow
    const double jitter = 1.0 + 0.03 * u01(rng);
    return (u01(rng) < 0.7 ? ms : 2.0 * ms) * jitter;
  };
  const double speedup = 1.15;
  const int trials = 4000;
  for (std::size_t n : {6u, 7u, 9u, 12u, 25u}) {
    int covered = 0;
    for (int t = 0; t < trials; ++t) {
      std::vector<double> nosort(n), sorted(n);
      for (std::size_t i = 0; i < n; ++i) nosort[i] = arm(10.0), sorted[i] = arm(10.0 / speedup);
      covered += ratio_interval(nosort, sorted).contains(speedup);
    }
    const double expected = signed_rank_coverage(n, signed_rank_interval_rank(n));
    const double observed = static_cast<double>(covered) / trials;
    EXPECT_NEAR(observed, expected, 4 * std::sqrt(expected * (1 - expected) / trials)) << "n = " << n;
  }
}

// Pairing: a drift that moves both arms of a round (the machine slowing down and speeding up)
// leaves the per-round ratio alone, while each arm's own times spread over a factor of three.
TEST(Protocol, PairedRatioCancelsDriftCommonToBothArms) {
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> jitter(0.0, 0.01);
  std::uniform_real_distribution<double> drift(1.0, 3.0);
  std::vector<double> nosort, sorted;
  for (int i = 0; i < 30; ++i) {
    const double machine = drift(rng);
    nosort.push_back(10.0 * machine * jitter(rng));
    sorted.push_back(10.0 / 1.25 * machine * jitter(rng));
  }
  const Estimate paired = ratio_interval(nosort, sorted);
  EXPECT_NEAR(paired.value, 1.25, 0.01);
  EXPECT_NEAR(paired.lo, 1.25, 0.025);
  EXPECT_NEAR(paired.hi, 1.25, 0.025);
  EXPECT_LT(paired.relative_half_width(), 0.02);
  EXPECT_GT(median_interval(nosort).relative_half_width(), 0.2);  // each arm alone is all drift
  EXPECT_THROW(per_round_ratios({1, 2}, {1}), Error);
  const std::vector<double> sums = per_round_sums({&nosort, &sorted});
  EXPECT_DOUBLE_EQ(sums[3], nosort[3] + sorted[3]);
}

TEST(Protocol, RoundOrderIsASeededPermutation) {
  std::vector<int> first(4, 0);
  for (std::uint64_t round = 0; round < 4000; ++round) {
    const auto order = round_order(4, 42, round);
    EXPECT_EQ(std::set<std::size_t>(order.begin(), order.end()).size(), 4u);
    EXPECT_EQ(order, round_order(4, 42, round));  // deterministic
    ++first[order[0]];
  }
  for (int f : first) EXPECT_NEAR(f, 1000, 120);  // every arm first about a quarter of the time
  int differ = 0;
  for (std::uint64_t round = 0; round < 50; ++round) differ += round_order(4, 1, round) != round_order(4, 2, round);
  EXPECT_GT(differ, 25);  // another seed, other orders
}

// measure(): arms run once a round after the prologue, warm-up rounds are not recorded, and the
// stopping rule stops for the reason it reports.
TEST(Protocol, MeasureStopsOnNoiseTimeOrRounds) {
  int prologue_runs = 0, a_runs = 0;
  std::vector<std::string> calls;
  Measurement m;
  m.prologue = {{"prep"}, [&] {
                  ++prologue_runs;
                  calls.push_back("prep");
                  return std::vector<double>{1.0};
                }};
  m.arms = {{{"a"}, [&] {
               ++a_runs;
               calls.push_back("a");
               return std::vector<double>{2.0};
             }},
            {{"b", "c"}, [&] {
               calls.push_back("b");
               return std::vector<double>{4.0, 5.0};
             }}};
  m.targets = {[](const Series& s) { return ratio_interval(s.at("b"), s.at("a")); }};
  ProtocolSettings s;
  s.warmup = 2;
  s.min_rounds = 6;
  s.max_time_s = 10;
  Outcome o = measure(m, s);
  // Constant times: the interval has zero width once it exists (6 rounds).
  EXPECT_EQ(o.stop, StopReason::Noise);
  EXPECT_EQ(o.rounds, 6u);
  EXPECT_EQ(prologue_runs, 8);
  EXPECT_EQ(a_runs, 8);
  EXPECT_EQ(o.series.at("a").size(), 6u);
  EXPECT_EQ(o.series.at("c").size(), 6u);
  EXPECT_DOUBLE_EQ(o.series.at("c")[0], 5.0);
  for (std::size_t i = 0; i < calls.size(); i += 3) EXPECT_EQ(calls[i], "prep");  // the prologue leads every round
  EXPECT_DOUBLE_EQ(o.noise, 0.0);

  // Noisy arms that never reach the target: the budget stops it.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> wild(1.0, 10.0);
  Measurement noisy;
  noisy.arms = {{{"x"}, [&] { return std::vector<double>{wild(rng)}; }}, {{"y"}, [&] { return std::vector<double>{wild(rng)}; }}};
  noisy.targets = {[](const Series& s) { return ratio_interval(s.at("x"), s.at("y")); }};
  ProtocolSettings budget;
  budget.min_rounds = 6;
  budget.max_noise = 0.001;
  budget.max_time_s = 0.0;
  o = measure(noisy, budget);
  EXPECT_EQ(o.stop, StopReason::Time);
  EXPECT_EQ(o.rounds, 6u);
  EXPECT_GT(o.noise, 0.001);
  budget.max_time_s = 100;
  budget.max_rounds = 9;
  o = measure(noisy, budget);
  EXPECT_EQ(o.stop, StopReason::Rounds);
  EXPECT_EQ(o.rounds, 9u);

  // The hard limit (run --timeout) throws between arms.
  Measurement slow;
  slow.arms = {{{"z"}, [] {
                 std::this_thread::sleep_for(std::chrono::milliseconds(20));
                 return std::vector<double>{1.0};
               }}};
  ProtocolSettings hard;
  hard.min_rounds = 1000;
  hard.hard_limit_s = 0.05;
  EXPECT_THROW(measure(slow, hard), TimedOut);
}

// measure_shared(): the common arms run every round while any group is active; each group retires
// on its own stopping rule, its prologue and arms stop with it, and its outcome holds the common
// series of exactly its rounds (the first ones), so its paired figures pair the same rounds.
TEST(Protocol, SharedRoundsRetireEachGroupOnItsOwnRule) {
  int common_calls = 0;
  std::map<std::string, int> runs;
  std::vector<std::string> calls;
  auto arm = [&](const std::string& name, std::function<double()> ms) {
    return Arm{{name}, [&, name, ms] {
                 ++runs[name];
                 calls.push_back(name);
                 return std::vector<double>{ms()};
               }};
  };
  SharedMeasurement m;
  // The common arm's n-th call returns n (warm-up calls included), to check the alignment.
  m.common = {{{"base"}, [&] {
                 calls.push_back("base");
                 return std::vector<double>{static_cast<double>(common_calls++ + 1)};
               }}};
  // Group 0: constant times, within any noise bar once it has an interval (6 rounds).
  MeasurementGroup quiet;
  quiet.prologue = arm("quiet:prep", [] { return 1.0; });
  quiet.arms = {arm("quiet:trace", [] { return 2.0; })};
  quiet.targets = {[](const Series& s) { return ratio_interval(s.at("trace"), s.at("trace")); }};
  // Group 1: wild times, never within the bar: stopped at max_rounds.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> wild(1.0, 10.0);
  MeasurementGroup noisy;
  noisy.prologue = arm("noisy:prep", [&] { return 1.0; });
  noisy.arms = {arm("noisy:trace", [&] { return wild(rng); })};
  noisy.targets = {[](const Series& s) { return ratio_interval(s.at("base"), s.at("trace")); }};
  // The stages are named without the group's prefix inside a group: rename the series keys.
  for (MeasurementGroup* g : {&quiet, &noisy}) {
    g->prologue.stages = {"prep"};
    for (Arm& a : g->arms) a.stages = {"trace"};
  }
  m.groups = {quiet, noisy};
  ProtocolSettings s;
  s.warmup = 1;
  s.min_rounds = 6;
  s.max_rounds = 15;
  s.max_noise = 0.01;
  s.max_time_s = 100;
  const std::vector<Outcome> o = measure_shared(m, s);
  ASSERT_EQ(o.size(), 2u);
  EXPECT_EQ(o[0].stop, StopReason::Noise);
  EXPECT_EQ(o[0].rounds, 6u);
  EXPECT_EQ(o[1].stop, StopReason::Rounds);
  EXPECT_EQ(o[1].rounds, 15u);
  // Each group's prologue and arm ran in its rounds and the warm-up round only; the common arm in
  // every round of the batch.
  EXPECT_EQ(runs["quiet:prep"], 7);
  EXPECT_EQ(runs["quiet:trace"], 7);
  EXPECT_EQ(runs["noisy:prep"], 16);
  EXPECT_EQ(runs["noisy:trace"], 16);
  EXPECT_EQ(common_calls, 16);
  // A group's view: its own series and the common one cut to its rounds, the same rounds.
  EXPECT_EQ(o[0].series.at("trace").size(), 6u);
  EXPECT_EQ(o[0].series.at("base"), (std::vector<double>{2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(o[1].series.at("base").size(), 15u);
  EXPECT_EQ(o[1].series.at("base").front(), 2.0);
  EXPECT_EQ(o[1].series.at("trace").size(), 15u);
  // Every round: the active groups' prologues first, then the arms.
  std::size_t i = 0;
  for (int round = 0; round < 16; ++round) {
    const std::size_t prologues = round < 7 ? 2 : 1, arms = round < 7 ? 3 : 2;
    for (std::size_t k = 0; k < prologues; ++k, ++i) EXPECT_NE(calls[i].find(":prep"), std::string::npos) << i;
    for (std::size_t k = 0; k < arms; ++k, ++i) EXPECT_EQ(calls[i].find(":prep"), std::string::npos) << i;
  }
  EXPECT_EQ(i, calls.size());
}

// The arms of a shared round run in one seeded order over the common arms and every group's: each
// comes first about equally often, so no group's trace always follows the NoSort trace.
TEST(Protocol, SharedRoundsShuffleCommonAndGroupArmsTogether) {
  std::vector<std::string> firsts;
  std::string last_prologue;
  bool round_start = true;
  auto arm = [&](const std::string& name) {
    return Arm{{name}, [&, name] {
                 if (round_start) firsts.push_back(name), round_start = false;
                 return std::vector<double>{1.0};
               }};
  };
  SharedMeasurement m;
  m.common = {arm("nosort"), arm("aa")};
  for (const char* g : {"g0", "g1"}) {
    MeasurementGroup group;
    group.prologue = {{"prep"}, [&] {
                        round_start = true;
                        return std::vector<double>{1.0};
                      }};
    group.arms = {arm(std::string(g) + ":trace")};
    m.groups.push_back(group);
  }
  ProtocolSettings s;
  s.warmup = 0;
  s.min_rounds = 2000;
  s.max_rounds = 2000;
  s.max_time_s = 100;
  s.seed = 5;
  measure_shared(m, s);
  std::map<std::string, int> count;
  for (const auto& f : firsts) ++count[f];
  ASSERT_EQ(count.size(), 4u);
  for (const auto& [name, c] : count) EXPECT_NEAR(c, 500, 90) << name;
}

// The budget is a group's own: a slow group that never meets the noise bar stops after its own
// --max-time, while a fast one beside it (which pays only its share of the rest of each round) goes on
// to max_rounds. A budget pooled over the batch stopped both at the same round.
TEST(Protocol, SharedRoundsBudgetIsEachGroupsOwn) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> wild(1.0, 10.0);
  auto group = [&](int sleep_ms) {
    MeasurementGroup g;
    g.arms = {{{"trace"}, [&, sleep_ms] {
                 if (sleep_ms) std::this_thread::sleep_for(std::chrono::milliseconds(sleep_ms));
                 return std::vector<double>{wild(rng)};
               }}};
    g.targets = {[](const Series& s) { return ratio_interval(s.at("base"), s.at("trace")); }};
    return g;
  };
  SharedMeasurement m;
  m.common = {{{"base"}, [&] { return std::vector<double>{wild(rng)}; }}};
  m.groups = {group(20), group(0)};
  ProtocolSettings s;
  s.warmup = 0;
  s.min_rounds = 6;
  s.max_rounds = 60;
  s.max_noise = 0.0001;
  s.max_time_s = 0.5;
  const std::vector<Outcome> o = measure_shared(m, s);
  EXPECT_EQ(o[0].stop, StopReason::Time);
  EXPECT_GE(o[0].rounds, 6u);
  EXPECT_LE(o[0].rounds, 26u);  // 0.5 s of its own 20 ms arms
  EXPECT_EQ(o[1].stop, StopReason::Rounds);
  EXPECT_EQ(o[1].rounds, 60u);
}

}  // namespace
}  // namespace raysort