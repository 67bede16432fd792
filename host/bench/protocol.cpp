#include "bench/protocol.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <numeric>

#include "util/fnv.h"

namespace raysort {

std::string interval_text(const Estimate& e, int decimals) {
  if (!e.has_value()) return "–";
  if (!e.has_interval()) return fmt::format("{:.{}f}", e.value, decimals);
  return fmt::format("{:.{}f} [{:.{}f}, {:.{}f}]", e.value, decimals, e.lo, decimals, e.hi, decimals);
}

double Estimate::relative_half_width() const {
  if (!has_interval() || !has_value() || value == 0.0) return std::numeric_limits<double>::infinity();
  return (hi - lo) / (2.0 * std::abs(value));
}

namespace {

// P(Binomial(n, 1/2) <= j), summed in the log domain so that n in the thousands does not underflow.
double binomial_half_cdf(std::size_t n, std::size_t j) {
  const double log_half_n = -static_cast<double>(n) * std::log(2.0);
  double p = 0.0;
  for (std::size_t i = 0; i <= j && i <= n; ++i) {
    const double log_choose = std::lgamma(static_cast<double>(n) + 1) - std::lgamma(static_cast<double>(i) + 1) -
                              std::lgamma(static_cast<double>(n - i) + 1);
    p += std::exp(log_choose + log_half_n);
  }
  return std::min(1.0, p);
}

double median_of_sorted(const std::vector<double>& s) {
  const std::size_t n = s.size();
  return n % 2 ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
}

}  // namespace

double median_coverage(std::size_t n, std::size_t k) {
  if (k == 0 || 2 * k > n + 1) return 0.0;
  return 1.0 - 2.0 * binomial_half_cdf(n, k - 1);
}

std::size_t median_interval_rank(std::size_t n, double confidence) {
  // Coverage falls as k grows; take the largest k that still reaches the confidence.
  std::size_t k = 0;
  for (std::size_t c = 1; 2 * c <= n + 1; ++c) {
    if (median_coverage(n, c) + 1e-12 < confidence) break;
    k = c;
  }
  return k;
}

Estimate median_interval(std::vector<double> samples, double confidence) {
  Estimate e;
  e.n = samples.size();
  if (samples.empty()) return e;
  for (double x : samples)
    if (!std::isfinite(x)) throw Error(fmt::format("a timing sample is {} (a broken profiling event?)", x));
  std::sort(samples.begin(), samples.end());
  e.value = median_of_sorted(samples);
  if (const std::size_t k = median_interval_rank(samples.size(), confidence); k > 0) {
    e.lo = samples[k - 1];
    e.hi = samples[samples.size() - k];
  }
  return e;
}

namespace {

// P(W <= j) for j = 0 .. n(n+1)/2, W the signed-rank statistic of n samples: the distribution of
// the sum of a random subset of {1, ..., n}, built one element at a time in probabilities.
std::vector<double> signed_rank_cdf(std::size_t n) {
  const std::size_t m = n * (n + 1) / 2;
  std::vector<double> p(m + 1, 0.0);
  p[0] = 1.0;
  for (std::size_t i = 1; i <= n; ++i) {
    const std::size_t top = i * (i + 1) / 2;  // the largest sum of a subset of {1, ..., i}
    for (std::size_t w = top + 1; w-- > 0;) p[w] = 0.5 * (p[w] + (w >= i ? p[w - i] : 0.0));
  }
  for (std::size_t w = 1; w <= m; ++w) p[w] += p[w - 1];
  return p;
}

constexpr std::size_t kExactSignedRankUpTo = 100;

// P(W <= j) under the normal approximation with continuity correction.
double signed_rank_cdf_normal(std::size_t n, double j) {
  const double nn = static_cast<double>(n);
  const double mean = nn * (nn + 1) / 4, sd = std::sqrt(nn * (nn + 1) * (2 * nn + 1) / 24);
  return 0.5 * std::erfc(-((j + 0.5 - mean) / sd) / std::sqrt(2.0));
}

}  // namespace

std::size_t signed_rank_interval_rank(std::size_t n, double confidence) {
  const double tail = (1.0 - confidence) / 2.0;
  if (n == 0) return 0;
  if (n <= kExactSignedRankUpTo) {
    const std::vector<double> cdf = signed_rank_cdf(n);
    std::size_t k = 0;
    while (k < cdf.size() && cdf[k] <= tail + 1e-12) ++k;  // P(W <= k - 1) <= tail for this k
    return k;
  }
  // Above: bisect the largest j with P(W <= j) <= tail; k = j + 1.
  std::size_t lo = 0, hi = n * (n + 1) / 4;
  if (signed_rank_cdf_normal(n, 0) > tail) return 0;
  while (lo < hi) {
    const std::size_t mid = (lo + hi + 1) / 2;
    if (signed_rank_cdf_normal(n, static_cast<double>(mid)) <= tail) lo = mid;
    else hi = mid - 1;
  }
  return lo + 1;
}

double signed_rank_coverage(std::size_t n, std::size_t k) {
  if (k == 0) return 0.0;
  if (n <= kExactSignedRankUpTo) {
    const std::vector<double> cdf = signed_rank_cdf(n);
    return k - 1 < cdf.size() ? 1.0 - 2.0 * cdf[k - 1] : 0.0;
  }
  return 1.0 - 2.0 * signed_rank_cdf_normal(n, static_cast<double>(k - 1));
}

Estimate hodges_lehmann_interval(const std::vector<double>& samples, double confidence) {
  Estimate e;
  const std::size_t n = samples.size();
  e.n = n;
  if (n == 0) return e;
  for (double x : samples)
    if (!std::isfinite(x)) throw Error(fmt::format("a paired sample is {} (a broken profiling event?)", x));
  std::vector<double> walsh;
  walsh.reserve(n * (n + 1) / 2);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i; j < n; ++j) walsh.push_back(0.5 * (samples[i] + samples[j]));
  const std::size_t m = walsh.size();
  // Order statistics by selection, not a full sort: the stopping rule asks after every round.
  auto at = [&](std::size_t rank) {  // 0-based
    std::nth_element(walsh.begin(), walsh.begin() + static_cast<std::ptrdiff_t>(rank), walsh.end());
    return walsh[rank];
  };
  e.value = m % 2 ? at(m / 2) : 0.5 * (at(m / 2 - 1) + at(m / 2));
  if (const std::size_t k = signed_rank_interval_rank(n, confidence); k > 0 && 2 * k <= m) {
    e.lo = at(k - 1);
    e.hi = at(m - k);
  }
  return e;
}

std::vector<double> per_round_ratios(const std::vector<double>& num, const std::vector<double>& den) {
  if (num.size() != den.size())
    throw Error(fmt::format("per_round_ratios: {} numerators against {} denominators", num.size(), den.size()));
  std::vector<double> r(num.size());
  for (std::size_t i = 0; i < num.size(); ++i) r[i] = den[i] > 0 ? num[i] / den[i] : std::numeric_limits<double>::infinity();
  return r;
}

Estimate ratio_interval(const std::vector<double>& num, const std::vector<double>& den, double confidence) {
  std::vector<double> r = per_round_ratios(num, den);
  Estimate e;
  e.n = r.size();
  // A zero time (an empty batch) has no ratio; report none rather than 0 or infinity.
  if (std::any_of(r.begin(), r.end(), [](double x) { return !std::isfinite(x) || !(x > 0); })) return e;
  for (double& x : r) x = std::log(x);
  const Estimate l = hodges_lehmann_interval(r, confidence);
  e.value = std::exp(l.value);
  if (l.has_interval()) e.lo = std::exp(l.lo), e.hi = std::exp(l.hi);
  return e;
}

std::vector<double> per_round_sums(const std::vector<const std::vector<double>*>& series) {
  std::vector<double> sum;
  for (const auto* s : series) {
    if (sum.empty()) sum.assign(s->size(), 0.0);
    if (s->size() != sum.size()) throw Error("per_round_sums: series of different lengths");
    for (std::size_t i = 0; i < s->size(); ++i) sum[i] += (*s)[i];
  }
  return sum;
}

Timing Timing::of(const std::vector<double>& samples) {
  Timing t;
  if (samples.empty()) return t;
  const Estimate e = median_interval(samples);
  t.median_ms = e.value, t.lo_ms = e.lo, t.hi_ms = e.hi, t.n = e.n;
  t.min_ms = *std::min_element(samples.begin(), samples.end());
  t.max_ms = *std::max_element(samples.begin(), samples.end());
  return t;
}

const char* stop_reason_name(StopReason r) {
  switch (r) {
    case StopReason::Noise: return "noise";
    case StopReason::Time: return "time";
    case StopReason::Rounds: return "rounds";
  }
  return "?";
}

std::uint64_t protocol_seed(const std::string& key) { return fnv1a(key); }

std::vector<std::size_t> round_order(std::size_t count, std::uint64_t seed, std::uint64_t round) {
  // SplitMix64 (Steele et al. 2014) on (seed, round): a fixed, portable stream per round.
  std::uint64_t state = seed * 0x9E3779B97F4A7C15ull + round * 0xD1B54A32D192ED03ull;
  auto next = [&state] {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  };
  std::vector<std::size_t> order(count);
  std::iota(order.begin(), order.end(), std::size_t{0});
  for (std::size_t i = count; i > 1; --i) std::swap(order[i - 1], order[next() % i]);
  return order;
}

Outcome measure(const Measurement& m, const ProtocolSettings& s) {
  return measure_shared({{}, {{m.prologue, m.arms, m.targets}}}, s).front();
}

namespace {

// A group's view of the series: its own stages and the common ones cut to its rounds.
Series group_view(const Series& own, const Series& common, unsigned rounds) {
  Series view = own;
  for (const auto& [stage, samples] : common)
    view[stage].assign(samples.begin(), samples.begin() + std::min<std::size_t>(rounds, samples.size()));
  return view;
}

}  // namespace

std::vector<Outcome> measure_shared(const SharedMeasurement& m, const ProtocolSettings& s) {
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  const Clock::time_point start = Clock::now();
  const std::size_t groups = m.groups.size();
  std::vector<Outcome> out(groups);
  std::vector<Series> own(groups);
  Series common;
  std::vector<bool> active(groups, true);
  const double hard_limit_s = s.hard_limit_s * static_cast<double>(std::max<std::size_t>(1, groups));
  auto check_hard_limit = [&] {
    if (s.interrupted && s.interrupted->load()) throw Interrupted("interrupted");
    if (s.hard_limit_s > 0 && seconds_since(start) > hard_limit_s)
      throw TimedOut(fmt::format("timed out: {:.3f} s, over --timeout {} s{} (remaining rounds skipped)",
                                 seconds_since(start), s.hard_limit_s,
                                 groups > 1 ? fmt::format(" per group × {} groups sharing the rounds", groups) : ""));
  };
  // Each group's share of the sampling time (the stopping rule's budget is per group): its own
  // prologue and arms, plus an equal share of the rest of its rounds (the common arms, the checks).
  std::vector<double> spent_s(groups, 0.0), round_own_s(groups, 0.0);
  auto run_arm = [&](const Arm& arm, Series* into, std::size_t group) {
    check_hard_limit();
    const Clock::time_point t0 = Clock::now();
    const std::vector<double> ms = arm.run();
    if (group < groups) round_own_s[group] += seconds_since(t0);
    if (ms.size() != arm.stages.size())
      throw Error(fmt::format("measure: an arm returned {} stage times for {} stages", ms.size(), arm.stages.size()));
    if (into)
      for (std::size_t i = 0; i < ms.size(); ++i) (*into)[arm.stages[i]].push_back(ms[i]);
  };
  std::uint64_t round = 0;
  auto run_round = [&](bool timed) {
    // The prologues of the active groups, then every arm of the round (common ones and the active
    // groups') in one order; the prologue order is drawn from a stream of its own.
    std::vector<std::size_t> live;
    for (std::size_t g = 0; g < groups; ++g)
      if (active[g]) live.push_back(g);
    for (std::size_t i : round_order(live.size(), ~s.seed, round))
      if (m.groups[live[i]].prologue.run)
        run_arm(m.groups[live[i]].prologue, timed ? &own[live[i]] : nullptr, live[i]);
    struct RoundArm {
      const Arm* arm;
      Series* into;
      std::size_t group;  // groups: a common arm
    };
    std::vector<RoundArm> arms;
    for (const Arm& a : m.common) arms.push_back({&a, timed ? &common : nullptr, groups});
    for (std::size_t g : live)
      for (const Arm& a : m.groups[g].arms) arms.push_back({&a, timed ? &own[g] : nullptr, g});
    for (std::size_t i : round_order(arms.size(), s.seed, round)) run_arm(*arms[i].arm, arms[i].into, arms[i].group);
    ++round;
  };

  for (unsigned w = 0; w < s.warmup; ++w) run_round(false);
  const Clock::time_point sampling = Clock::now();
  Clock::time_point mark = sampling;
  const unsigned min_rounds = std::max(1u, s.min_rounds);
  auto retire = [&](std::size_t g, StopReason why) {
    active[g] = false;
    out[g].stop = why;
  };
  for (std::size_t live = groups; live > 0;) {
    std::fill(round_own_s.begin(), round_own_s.end(), 0.0);
    run_round(true);
    // The round's wall clock since the last one ended (the checks between them included), shared:
    // with one group, its spent time is the sampling wall clock, as before shared rounds.
    const double round_s = seconds_since(mark);
    mark = Clock::now();
    double own_s = 0.0;
    for (std::size_t g = 0; g < groups; ++g) own_s += round_own_s[g];
    for (std::size_t g = 0; g < groups; ++g)
      if (active[g]) spent_s[g] += round_own_s[g] + std::max(0.0, round_s - own_s) / static_cast<double>(live);
    for (std::size_t g = 0; g < groups; ++g) {
      if (!active[g]) continue;
      const bool over_time = spent_s[g] >= s.max_time_s;
      Outcome& o = out[g];
      ++o.rounds;
      if (o.rounds < min_rounds) continue;
      // The targets cost O(rounds²) (Walsh averages): past 64 rounds, ask about 32 times per doubling.
      if (o.rounds > 64 && o.rounds % (o.rounds / 32) != 0 && !over_time && o.rounds < s.max_rounds) continue;
      const Series view = group_view(own[g], common, o.rounds);
      o.noise = 0.0;
      for (const auto& target : m.groups[g].targets) o.noise = std::max(o.noise, target(view).relative_half_width());
      if (o.noise <= s.max_noise)
        retire(g, StopReason::Noise);
      else if (o.rounds >= std::max(min_rounds, s.max_rounds))
        retire(g, StopReason::Rounds);
      else if (over_time)
        retire(g, StopReason::Time);
    }
    live = static_cast<std::size_t>(std::count(active.begin(), active.end(), true));
    if (s.on_round) s.on_round(static_cast<unsigned>(round - s.warmup), live, groups);
  }
  const double sampling_s = seconds_since(sampling);
  for (std::size_t g = 0; g < groups; ++g) {
    out[g].series = group_view(own[g], common, out[g].rounds);
    out[g].sampling_s = sampling_s;
  }
  return out;
}

}  // namespace raysort
