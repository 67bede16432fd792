#include "bench/cell_measure.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <numeric>
#include <optional>

#include "trace/exact_oracle.h"
#include "trace/order_agreement.h"

namespace raysort {

namespace {

std::vector<std::uint32_t> identity_order(std::uint32_t n) {
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  return order;
}

// The GPU cost model's figures of a cell (bench/gpu_model.h): its counts, predicted time and the
// predicted speedup over the NoSort order of the same batch.
CellRecord::GpuModelFigures gpu_figures(const GpuProfile& p, const GpuCounts& cell, const GpuCounts& nosort) {
  CellRecord::GpuModelFigures g;
  g.profile = p.name;
  g.time_us = gpu_model_time(cell, p).total_s * 1e6;
  const double base_us = gpu_model_time(nosort, p).total_s * 1e6;
  g.speedup = g.time_us > 0 ? base_us / g.time_us : std::numeric_limits<double>::quiet_NaN();
  g.warp_steps = cell.warp_steps, g.idle_lanes = cell.idle_lanes, g.l1_hits = cell.l1_hits;
  g.l1_misses = cell.l1_misses, g.l2_hits = cell.l2_hits, g.l2_misses = cell.l2_misses;
  g.dram_bytes = cell.dram_bytes, g.warps = cell.warps, g.replayed_warps = cell.replayed_warps;
  g.steps_l2 = cell.steps_l2, g.steps_dram = cell.steps_dram, g.ww_steps = cell.ww_steps;
  return g;
}

Estimate scaled(Estimate e, double factor) {
  e.value *= factor, e.lo *= factor, e.hi *= factor;
  return e;
}

}  // namespace

BatchBench::BatchBench(const Stages& stages, const Bvh& bvh, const RayBatch& batch, const std::vector<RsHit>& reference)
    : s_(stages), bvh_(bvh), batch_(batch), n_(static_cast<std::uint32_t>(batch.size())) {
  try {
    const std::size_t n = std::max<std::size_t>(1, n_);
    rays_ = s_.rt.upload("rays of " + batch.name, batch.rays);
    identity_ = s_.rt.upload("identity order", identity_order(n_));
    values_ = s_.rt.buffer("sort values (ray order)", n * sizeof(std::uint32_t));
    keys32_ = s_.rt.buffer("32-bit keys", n * sizeof(std::uint32_t));
    keys64_ = s_.rt.buffer("64-bit keys", n * sizeof(std::uint64_t));
    nosort_hits_ = s_.rt.buffer("NoSort hits", n * sizeof(RsHit));
    gather_hits_ = s_.rt.buffer("hits in sorted order (gather)", n * sizeof(RsHit));
    permute_hits_ = s_.rt.buffer("hits in sorted order (permute)", n * sizeof(RsHit));
    cl::Event ev = trace(rays_, identity_, nosort_hits_);
    cl_call("waiting for the NoSort trace", [&] { ev.wait(); });
    s_.rt.download("NoSort hits", nosort_hits_, nosort_hits_host_, n_);
    if (count_hit_mismatches(nosort_hits_host_, reference) != 0)
      setup_error_ = "device NoSort hits differ from the host reference traversal";
  } catch (const Error& err) {
    setup_error_ = err.what();
  }
  nosort_simt_ = simt_model(bvh_, batch_.rays, nullptr, batch_.any_hit(), s_.tracer.variant(), s_.tracer.layout(),
                            s_.gpu, &nosort_gpu_);
}

cl::Event BatchBench::trace(const cl::Buffer& rays, const cl::Buffer& order, const cl::Buffer& hits) {
  return s_.tracer.enqueue(rays, order, n_, batch_.any_hit(), hits);
}

double BatchBench::timed_trace(const cl::Buffer& rays, const cl::Buffer& order, const cl::Buffer& hits,
                               const char* doing) {
  cl::Event ev = trace(rays, order, hits);
  cl_call(doing, [&] { ev.wait(); });
  return event_ms(ev);
}

std::vector<Arm> BatchBench::baseline_arms() {
  auto nosort_trace = [this] {
    return std::vector<double>{timed_trace(rays_, identity_, nosort_hits_, "waiting for the NoSort trace")};
  };
  return {{{"nosort"}, nosort_trace}, {{"aa"}, nosort_trace}};
}

const cl::Buffer& BatchBench::permuted_rays() {
  // Only cells of the permute access mode need the second copy of the rays.
  if (!permuted_()) permuted_ = s_.rt.buffer("rays in sorted order (permute)", std::max<std::size_t>(1, n_) * sizeof(RsRay));
  return permuted_;
}

CellRecord BatchBench::measure_nosort(CellRecord c, const ProtocolSettings& settings) {
  c.rays = n_;
  c.order_is_permutation = true;
  c.same_order_as_nosort = true;
  const std::vector<std::uint32_t> identity = identity_order(n_);
  c.keys_hash = fnv1a_hex(nullptr, 0);
  c.order_hash = fnv1a_hex(identity.data(), identity.size() * sizeof(std::uint32_t));
  c.simt_lane_efficiency = nosort_simt_.lane_efficiency;
  c.simt_distinct_per_visit = nosort_simt_.distinct_nodes_per_visit;
  c.simt_lane_efficiency_ratio = c.simt_distinct_per_visit_ratio = 1.0;
  if (s_.gpu) c.gpu = gpu_figures(*s_.gpu, nosort_gpu_, nosort_gpu_);
  c.hits_match_nosort = setup_error_.empty();
  if (!setup_error_.empty()) {
    c.status = "failed";
    c.error = setup_error_;
    return c;
  }
  try {
    Measurement m;
    m.arms = baseline_arms();
    m.targets = {[](const Series& s) { return ratio_interval(s.at("nosort"), s.at("aa")); }};
    add_embree_arms(m, {});
    const Outcome o = measure(m, settings);
    const auto &nosort = o.series.at("nosort"), &aa = o.series.at("aa");
    c.trace = c.nosort_trace = Timing::of(nosort);
    c.trace_mrays = c.trace.median_ms > 0 ? n_ / (c.trace.median_ms * 1e3) : 0.0;
    c.aa = ratio_interval(nosort, aa, settings.confidence);
    // NoSort against itself: 1 and no overhead by definition.
    c.speedup = c.net_speedup = Estimate::exact(1.0);
    c.overhead_pct = Estimate::exact(0.0);
    c.speedup.n = c.net_speedup.n = c.overhead_pct.n = o.rounds;
    c.rounds = o.rounds;
    c.stopped_by = stop_reason_name(o.stop);
    c.noise = c.aa.relative_half_width();
    c.samples = {{"nosort", nosort}, {"aa", aa}};
    if (const std::string why = fill_embree(c, o, nullptr, settings); !why.empty()) {
      c.status = "failed";
      c.error = why;
    }
  } catch (const TimedOut& t) {
    c.status = "timeout";
    c.error = t.what();
  } catch (const Error& err) {
    c.status = "failed";
    c.error = err.what();
  }
  return c;
}

Measurement BatchBench::sorted_measurement(const std::vector<CellRecord>& cells, Encoder encoder,
                                           const cl::Buffer& keys, const RadixSortConfig& cfg) {
  Measurement m;
  m.prologue = {{"encode", "sort"}, [this, encoder, &keys, cfg] {
                  const DeviceEncoder::Events ev =
                      s_.encoder.enqueue(encoder, cfg.key_bits, rays_, identity_, n_, keys, values_);
                  ev.wait();
                  cl::Buffer k = keys;
                  const SortStats st = s_.sorter.sort(k, values_, n_, cfg);
                  return std::vector<double>{ev.ms(), st.ms};
                }};
  m.arms = baseline_arms();
  for (const CellRecord& c : cells) {
    if (c.access == "gather") {
      m.arms.push_back({{"trace:gather"}, [this] {
                          return std::vector<double>{timed_trace(rays_, values_, gather_hits_, "waiting for the sorted trace")};
                        }});
    } else {
      m.arms.push_back({{"permute", "trace:permute"}, [this] {
                          cl::Event p = s_.permuter.enqueue(rays_, values_, n_, permuted_rays());
                          cl_call("waiting for the permute kernel", [&] { p.wait(); });
                          const double permute_ms = event_ms(p);
                          return std::vector<double>{permute_ms, timed_trace(permuted_rays(), identity_, permute_hits_,
                                                                             "waiting for the trace of the permuted rays")};
                        }});
    }
    m.targets.push_back([trace = "trace:" + c.access](const Series& s) { return ratio_interval(s.at("nosort"), s.at(trace)); });
  }
  add_embree_arms(m, cells);
  return m;
}

void BatchBench::add_embree_arms(Measurement& m, const std::vector<CellRecord>& sorted_cells) {
  embree_arms_.clear();
  embree_order_ready_ = embree_permuted_ready_ = false;
  if (!s_.embree) return;
#ifdef RAYSORT_HAVE_EMBREE
  for (EmbreePath path : s_.embree_paths) embree_arms_.push_back({path, embree_path_info(path).key, {}, {}});
  // Embree's time is the wall clock of its whole trace call (threads started and joined inside),
  // as in `trace --reference embree`; the hits are kept after the clock stops.
  using Clock = std::chrono::steady_clock;
  auto ms_since = [](Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); };
  for (std::size_t i = 0; i < embree_arms_.size(); ++i) {
    const std::string stage = "embree:" + embree_arms_[i].key + ":";
    m.arms.push_back({{stage + "nosort"}, [this, i, ms_since] {
                        EmbreeArm& arm = embree_arms_[i];
                        const auto t0 = Clock::now();
                        std::vector<RsHit> hits = s_.embree->trace(batch_.rays, batch_.any_hit(), arm.path);
                        const double ms = ms_since(t0);
                        arm.nosort_hits = std::move(hits);
                        return std::vector<double>{ms};
                      }});
    for (const CellRecord& c : sorted_cells) {
      const bool permute = c.access == "permute";
      m.arms.push_back({{stage + c.access}, [this, i, permute, access = c.access, ms_since] {
                          EmbreeArm& arm = embree_arms_[i];
                          // Untimed: the round's order on the host (gather), the rays in it (permute).
                          const std::vector<std::uint32_t>& order = embree_order();
                          if (permute) (void)embree_permuted_rays();
                          const auto t0 = Clock::now();
                          std::vector<RsHit> hits = permute ? s_.embree->trace(embree_permuted_, batch_.any_hit(), arm.path)
                                                            : s_.embree->trace(batch_.rays, batch_.any_hit(), arm.path, order);
                          const double ms = ms_since(t0);
                          arm.sorted_hits[access] = std::move(hits);
                          return std::vector<double>{ms};
                        }});
      m.targets.push_back([nosort = stage + "nosort", sorted = stage + c.access](const Series& s) {
        return ratio_interval(s.at(nosort), s.at(sorted));
      });
    }
  }
#else
  (void)m, (void)sorted_cells;
#endif
}

const std::vector<std::uint32_t>& BatchBench::embree_order() {
  // Every round sorts the same keys the same way (the checks after the rounds compare this order
  // with the last round's), so one download serves every round.
  if (!embree_order_ready_) {
    s_.rt.download("sorted order (for Embree)", values_, embree_order_, n_);
    embree_order_ready_ = true;
  }
  return embree_order_;
}

const std::vector<RsRay>& BatchBench::embree_permuted_rays() {
  if (!embree_permuted_ready_) {
    const std::vector<std::uint32_t>& order = embree_order();
    embree_permuted_.resize(n_);
    // An entry past the rays (an order that is no permutation, which fails the cell after the
    // rounds) must not be read past the batch.
    for (std::uint32_t i = 0; i < n_; ++i) embree_permuted_[i] = batch_.rays[order[i] < n_ ? order[i] : 0];
    embree_permuted_ready_ = true;
  }
  return embree_permuted_;
}

std::string BatchBench::fill_embree(CellRecord& c, const Outcome& o, const SortedOrder* so,
                                    const ProtocolSettings& settings) {
  if (embree_arms_.empty()) return "";
#ifdef RAYSORT_HAVE_EMBREE
  if (so && so->order != embree_order_)
    return "Embree traced another sorted order than the one checked (the sort's order changed between rounds)";
  const bool any_hit = batch_.any_hit();
  for (const EmbreeArm& arm : embree_arms_) {
    CellRecord::EmbreeFigures e;
    e.path = arm.key;
    e.call = embree_path_name(arm.path, any_hit);
    e.threads = s_.embree->threads();
    const std::vector<double>& nosort = o.series.at("embree:" + arm.key + ":nosort");
    e.nosort = Timing::of(nosort);
    c.samples["embree:" + arm.key + ":nosort"] = nosort;
    // The anchor: Embree traced the rays we traced (same triangle or a tie, trace's rule).
    const HitAgreement ours = compare_with_embree(nosort_hits_host_, arm.nosort_hits, any_hit);
    e.agreement_with_ours = ours.fraction_with_ties();
    if (e.agreement_with_ours < kEmbreeMinAgreement)
      return fmt::format("Embree {} ({}) agrees with our NoSort hits on {:.3f} % of rays (same triangle or a tie), below "
                         "the required {:.1f} %: {}",
                         arm.key, e.call, 100.0 * e.agreement_with_ours, 100.0 * kEmbreeMinAgreement, ours.describe());
    if (so) {
      const std::vector<double>& trace = o.series.at("embree:" + arm.key + ":" + c.access);
      e.trace = Timing::of(trace);
      c.samples["embree:" + arm.key + ":trace"] = trace;
      const Estimate measured = ratio_interval(nosort, trace, settings.confidence);
      // The same rays in the same order: whatever the clock says is noise (as our own speedup).
      e.speedup = so->identity ? Estimate{1.0, 1.0, 1.0, measured.n} : measured;
      // The sorted-order hits back in ray order, against the NoSort-order ones: an order may give
      // a ray the other triangle of a tie (a packet's companions decide which is met first), and
      // nothing else.
      const std::vector<RsHit>& sorted = arm.sorted_hits.at(c.access);
      std::vector<RsHit> back(n_);
      for (std::uint32_t i = 0; i < n_; ++i) back[so->order[i]] = sorted[i];
      const HitAgreement a = compare_with_embree(arm.nosort_hits, back, any_hit);
      e.ties = a.ties();
      e.differ = a.differences() - a.ties();
      if (e.differ > 0)
        return fmt::format("Embree {} ({}): {} of {} rays traced in the sorted order ({}) differ from the NoSort order "
                           "beyond ties ({} another triangle farther apart, {} hit only in NoSort order, {} hit only "
                           "in the sorted order)",
                           arm.key, e.call, e.differ, n_, c.access, a.other_tri, a.ours_only, a.embree_only);
    }
    c.embree.push_back(std::move(e));
  }
  return "";
#else
  (void)c, (void)o, (void)so, (void)settings;
  return "";
#endif
}

BatchBench::SortedOrder BatchBench::check_order(const cl::Buffer& keys, unsigned bits, unsigned top) {
  SortedOrder so;
  s_.rt.download("sorted order", values_, so.order, n_);
  std::vector<std::uint8_t> seen(n_, 0);
  so.permutation = true;
  for (auto v : so.order)
    if (v >= n_ || seen[v]++) {
      so.permutation = false;
      break;
    }
  so.identity = so.permutation;
  for (std::uint32_t i = 0; so.identity && i < n_; ++i) so.identity = so.order[i] == i;
  std::vector<std::uint64_t> sorted_keys = DeviceEncoder::download_keys(s_.rt, keys, bits, n_, "sorted keys");
  // ANC of the codes the sort used: a top-k sort orders by the highest k bits only.
  if (top > 0)
    for (auto& k : sorted_keys) k >>= (bits - top);
  so.anc = average_number_of_codes(sorted_keys);
  if (so.permutation) so.simt = simt_model(bvh_, batch_.rays, so.order.data(), batch_.any_hit(), s_.tracer.variant(),
                                         s_.tracer.layout(), s_.gpu, &so.gpu);
  return so;
}

void BatchBench::fill_sorted_cell(CellRecord& c, const Outcome& o, const SortedOrder& so,
                                  const ProtocolSettings& settings) {
  const auto &nosort = o.series.at("nosort"), &aa = o.series.at("aa");
  const auto &encode = o.series.at("encode"), &sort = o.series.at("sort");
  const std::vector<double>& trace = o.series.at("trace:" + c.access);
  std::vector<const std::vector<double>*> overhead_stages{&encode, &sort};
  if (c.access == "permute") overhead_stages.push_back(&o.series.at("permute"));
  const std::vector<double> overhead = per_round_sums(overhead_stages);
  c.encode = Timing::of(encode);
  c.sort = Timing::of(sort);
  if (c.access == "permute") c.permute = Timing::of(o.series.at("permute"));
  c.trace = Timing::of(trace);
  c.nosort_trace = Timing::of(nosort);
  c.trace_mrays = c.trace.median_ms > 0 ? n_ / (c.trace.median_ms * 1e3) : 0.0;
  const Estimate measured = ratio_interval(nosort, trace, settings.confidence);
  // The same rays in the same order as NoSort: whatever the clock says is noise, not a speedup.
  c.speedup = so.identity ? Estimate{1.0, 1.0, 1.0, measured.n} : measured;
  c.net_speedup = ratio_interval(nosort, per_round_sums({&overhead, &trace}), settings.confidence);
  c.overhead_pct = scaled(ratio_interval(overhead, trace, settings.confidence), 100.0);
  c.aa = ratio_interval(nosort, aa, settings.confidence);
  c.rounds = o.rounds;
  c.stopped_by = stop_reason_name(o.stop);
  c.noise = measured.relative_half_width();
  c.samples = {{"nosort", nosort}, {"aa", aa}, {"encode", encode}, {"sort", sort}, {"trace", trace}};
  if (c.access == "permute") c.samples["permute"] = o.series.at("permute");
  c.anc = so.anc;
  c.simt_lane_efficiency = so.simt.lane_efficiency;
  c.simt_distinct_per_visit = so.simt.distinct_nodes_per_visit;
  c.simt_lane_efficiency_ratio =
      nosort_simt_.lane_efficiency > 0 ? so.simt.lane_efficiency / nosort_simt_.lane_efficiency : 0;
  c.simt_distinct_per_visit_ratio = nosort_simt_.distinct_nodes_per_visit > 0
                                        ? so.simt.distinct_nodes_per_visit / nosort_simt_.distinct_nodes_per_visit
                                        : 0;
  if (s_.gpu && so.permutation) c.gpu = gpu_figures(*s_.gpu, so.gpu, nosort_gpu_);
}

std::string BatchBench::unrepeated_keys(Encoder encoder, unsigned bits, const cl::Buffer& keys,
                                        const std::vector<std::uint64_t>& first) {
  if (has_host_twin(encoder)) return "";
  s_.encoder.enqueue(encoder, bits, rays_, identity_, n_, keys, values_).wait();
  const std::vector<std::uint64_t> again = DeviceEncoder::download_keys(s_.rt, keys, bits, n_, "keys (second launch)");
  std::size_t differ = 0;
  for (std::uint32_t i = 0; i < n_; ++i) differ += first[i] != again[i];
  if (differ == 0) return "";
  return fmt::format("{} gave other keys on a second launch over the same rays ({} of {} differ); it has no host twin, "
                     "so its keys are checked against themselves: make its key a function of the ray and the scene "
                     "alone (no uninitialised variable, no other work-item's data)",
                     encoder_name(encoder), differ, n_);
}

std::vector<CellRecord> BatchBench::measure_sorted(std::vector<CellRecord> cells, Encoder encoder,
                                                   const ProtocolSettings& settings) {
  const unsigned bits = cells.front().bits, top = cells.front().top_bits;
  for (auto& c : cells) c.rays = n_;
  auto fail_all = [&](const std::string& status, const std::string& error) {
    for (auto& c : cells) c.status = status, c.error = error;
    return cells;
  };
  if (!setup_error_.empty()) return fail_all("failed", "the batch's setup failed: " + setup_error_);
  try {
    s_.encoder.prepare(encoder, bits);
    const cl::Buffer& keys = bits > 32 ? keys64_ : keys32_;
    RadixSortConfig cfg;
    cfg.key_bits = bits;
    cfg.top_bits = top;
    cfg.warp_group = s_.sort_warp_group;
    // The keys in generation order, for their fingerprint (untimed).
    s_.encoder.enqueue(encoder, bits, rays_, identity_, n_, keys, values_).wait();
    const std::vector<std::uint64_t> unsorted = DeviceEncoder::download_keys(s_.rt, keys, bits, n_, "keys");
    if (const std::string why = unrepeated_keys(encoder, bits, keys, unsorted); !why.empty()) return fail_all("failed", why);

    const Outcome o = measure(sorted_measurement(cells, encoder, keys, cfg), settings);

    // Checks: the order is a permutation, and each access mode's hits scattered back equal NoSort's.
    // Single rays: bit for bit. Packets, hybrids and streams: a ray's companions decide the order in which
    // its packet meets the nodes, so where two surfaces lie within float precision of each other
    // (shared edges, coplanar duplicates) one order may give it the other one. Such a ray agrees
    // when its answer agrees with NoSort's up to what the order may change (trace/order_agreement.h:
    // the exact oracle's ties, and in the fast variant the test's own near-edge hits); anything else
    // fails the cell (docs/trace.md, "Trace classes"). NoSort's own hits equal the host twin's.
    const SortedOrder so = check_order(keys, bits, top);
    const bool judge_ties = packet_width(s_.tracer.layout()) > 1 && s_.tris;
    std::optional<ExactOracle> oracle;
    auto agree = [&](const RsHit& sorted, const RsHit& nosort, std::uint32_t ray) {
      if (std::memcmp(&sorted, &nosort, sizeof(RsHit)) == 0) return true;
      if (!judge_ties) return false;
      if (!oracle) oracle.emplace(*s_.tris, bvh_);
      return answers_agree(sorted, nosort, batch_.rays[ray], batch_.any_hit(), s_.tracer.variant(), *oracle, *s_.tris);
    };
    for (CellRecord& c : cells) {
      std::vector<RsHit> hits;
      s_.rt.download("sorted hits", c.access == "gather" ? gather_hits_ : permute_hits_, hits, n_);
      std::size_t bad = 0;
      if (so.permutation)
        for (std::uint32_t i = 0; i < n_; ++i) bad += !agree(hits[i], nosort_hits_host_[so.order[i]], so.order[i]);
      c.order_is_permutation = so.permutation;
      c.hits_match_nosort = so.permutation && bad == 0;
      c.same_order_as_nosort = so.identity;
      c.keys_hash = fnv1a_hex(unsorted.data(), unsorted.size() * sizeof(std::uint64_t));
      c.order_hash = fnv1a_hex(so.order.data(), so.order.size() * sizeof(std::uint32_t));
      if (c.hits_match_nosort) {
        fill_sorted_cell(c, o, so, settings);
        if (const std::string why = fill_embree(c, o, &so, settings); !why.empty()) {
          c.status = "failed";
          c.error = why;
        }
      } else {
        c.status = "failed";
        c.error = so.permutation
                      ? fmt::format("{} of {} hits differ from NoSort after scattering back ({})", bad, n_, c.access)
                      : "the sorted order is not a permutation of the rays";
      }
    }
  } catch (const TimedOut& t) {
    return fail_all("timeout", t.what());
  } catch (const Error& err) {
    // A device fault (allocation, build, launch) fails these cells; the run goes on.
    return fail_all("failed", err.what());
  }
  return cells;
}

}  // namespace raysort
