#include "bench/cell_measure.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <deque>
#include <limits>
#include <numeric>
#include <optional>

#include "render/frame_memory.h"
#include "trace/exact_oracle.h"
#include "trace/order_agreement.h"
#include "util/host_memory.h"

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
  // The NoSort model records every ray's trail for the sorted orders' models (bench/metrics.h),
  // within an eighth of the host's free memory (sibenik's 2 M bounce rays: about 0.3 GB).
  trails_.budget_bytes = available_host_memory() / 8;
  nosort_simt_ = simt_model(bvh_, batch_.rays, nullptr, batch_.any_hit(), s_.tracer.variant(), s_.tracer.layout(),
                            s_.gpu, &nosort_gpu_, &trails_);
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

const cl::Buffer& BatchBench::permuted_rays() {
  // Only cells of the permute access mode need the second copy of the rays.
  if (!permuted_()) permuted_ = s_.rt.buffer("rays in sorted order (permute)", std::max<std::size_t>(1, n_) * sizeof(RsRay));
  return permuted_;
}

std::size_t BatchBench::groups_per_round() const {
  const std::uint64_t per_group = std::max<std::uint64_t>(1, std::uint64_t{n_} * sizeof(std::uint32_t));
  const DeviceInfo& d = s_.rt.info();
  // A CPU device's buffers are host memory (render/frame_memory.h says why its reported size is no
  // limit): a quarter of what the host has free. A GPU: half of what the frame leaves.
  const std::uint64_t frame = std::uint64_t{n_} * FrameMemory::kDevicePerRay;
  const std::uint64_t spare = d.type == "CPU" ? available_host_memory() / 4
                              : d.global_mem_bytes > frame ? (d.global_mem_bytes - frame) / 2
                                                           : 0;
  return static_cast<std::size_t>(std::clamp<std::uint64_t>(spare / per_group, 1, kGroupsPerRound));
}

std::vector<Arm> BatchBench::common_arms() {
  auto nosort_trace = [this] {
    return std::vector<double>{timed_trace(rays_, identity_, nosort_hits_, "waiting for the NoSort trace")};
  };
  std::vector<Arm> arms{{{"nosort"}, nosort_trace}, {{"aa"}, nosort_trace}};
#ifdef RAYSORT_HAVE_EMBREE
  // Embree's time is the wall clock of its whole trace call (threads started and joined inside),
  // as in `trace --reference embree`.
  for (const EmbreeArm& arm : embree_arms_)
    arms.push_back({{"embree:" + arm.key + ":nosort"}, [this, path = arm.path] {
                      const auto t0 = std::chrono::steady_clock::now();
                      (void)s_.embree->trace(batch_.rays, batch_.any_hit(), path);
                      return std::vector<double>{
                          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count()};
                    }});
#endif
  return arms;
}

void BatchBench::ready_embree() {
  if (embree_ready_) return;
  embree_ready_ = true;
  if (!s_.embree) return;
#ifdef RAYSORT_HAVE_EMBREE
  const bool any_hit = batch_.any_hit();
  for (EmbreePath path : s_.embree_paths) {
    EmbreeArm arm{path, embree_path_info(path).key, s_.embree->trace(batch_.rays, any_hit, path), "", 1.0};
    // The anchor: Embree traced the rays we traced (same triangle or a tie, trace's rule).
    const HitAgreement ours = compare_with_embree(nosort_hits_host_, arm.nosort_hits, any_hit);
    arm.agreement = ours.fraction_with_ties();
    if (arm.agreement < kEmbreeMinAgreement)
      arm.agreement_error = fmt::format(
          "Embree {} ({}) agrees with our NoSort hits on {:.3f} % of rays (same triangle or a tie), below the required "
          "{:.1f} %: {}",
          arm.key, embree_path_name(path, any_hit), 100.0 * arm.agreement, 100.0 * kEmbreeMinAgreement, ours.describe());
    embree_arms_.push_back(std::move(arm));
  }
#endif
}

std::size_t BatchBench::disagreeing_rays(const std::vector<RsHit>& hits, const std::vector<std::uint32_t>& order) {
  // Single rays: bit for bit. Packets, hybrids and streams: a ray's companions decide the order in
  // which its packet meets the nodes, so where two surfaces lie within float precision of each other
  // (shared edges, coplanar duplicates) one order may give it the other one. Such a ray agrees when
  // its answer agrees with NoSort's up to what the order may change (trace/order_agreement.h: the
  // exact oracle's ties, and in the fast variant the test's own near-edge hits); anything else fails
  // the cell (docs/trace.md, "Trace classes"). NoSort's own hits equal the host twin's.
  const bool judge_ties = packet_width(s_.tracer.layout()) > 1 && s_.tris;
  std::optional<ExactOracle> oracle;
  std::size_t bad = 0;
  for (std::uint32_t i = 0; i < n_; ++i) {
    const std::uint32_t ray = order[i];
    if (ray >= n_) return n_;  // no permutation: check_order says so
    const RsHit& nosort = nosort_hits_host_[ray];
    if (std::memcmp(&hits[i], &nosort, sizeof(RsHit)) == 0) continue;
    if (!judge_ties) {
      ++bad;
      continue;
    }
    if (!oracle) oracle.emplace(*s_.tris, bvh_);
    bad += !answers_agree(hits[i], nosort, batch_.rays[ray], batch_.any_hit(), s_.tracer.variant(), *oracle, *s_.tris);
  }
  return bad;
}

void BatchBench::ready_group(SortedGroup& g, const PrepareEncoder& prepare) {
  const unsigned bits = g.cells.front().bits;
  for (auto& c : g.cells) c.rays = n_;
  try {
    g.cut_ms = prepare ? prepare(g.encoder, bits) : -1.0;
    s_.encoder.prepare(g.encoder, bits);
    g.cfg.key_bits = bits;
    g.cfg.top_bits = g.cells.front().top_bits;
    g.cfg.warp_group = s_.sort_warp_group;
    g.order = s_.rt.buffer("sorted order of " + g.cells.front().id(), std::max<std::size_t>(1, n_) * sizeof(std::uint32_t));
    const cl::Buffer& keys = bits > 32 ? keys64_ : keys32_;
    // The keys in generation order, for their fingerprint and the ANC (untimed).
    s_.encoder.enqueue(g.encoder, bits, rays_, identity_, n_, keys, g.order).wait();
    g.unsorted = DeviceEncoder::download_keys(s_.rt, keys, bits, n_, "keys");
    g.error = unrepeated_keys(g.encoder, bits, keys, g.unsorted);
  } catch (const Error& err) {
    g.error = err.what();
  }
}

void BatchBench::warm_sort_and_permute(SortedGroup& g) {
  (void)sorted_group(g).prologue.run();
  if (std::none_of(g.cells.begin(), g.cells.end(), [](const CellRecord& c) { return c.access == "permute"; })) return;
  cl::Event p = s_.permuter.enqueue(rays_, g.order, n_, permuted_rays());
  cl_call("waiting for the permute kernel", [&] { p.wait(); });
}

MeasurementGroup BatchBench::sorted_group(SortedGroup& g) {
  MeasurementGroup m;
  m.prologue = {{"encode", "sort"}, [this, &g] {
                  const cl::Buffer& keys = g.cfg.key_bits > 32 ? keys64_ : keys32_;
                  const DeviceEncoder::Events ev = s_.encoder.enqueue(g.encoder, g.cfg.key_bits, rays_, identity_, n_, keys, g.order);
                  ev.wait();
                  cl::Buffer k = keys;
                  const SortStats st = s_.sorter.sort(k, g.order, n_, g.cfg);
                  // The order of the first sort, for the checks (untimed: after both clocks stopped).
                  if (g.first_order.empty()) s_.rt.download("sorted order", g.order, g.first_order, n_);
                  return std::vector<double>{ev.ms(), st.ms};
                }};
  for (const CellRecord& c : g.cells) {
    const bool permute = c.access == "permute";
    // Each arm checks its hits the first time it runs (untimed, after its clock stopped): the
    // groups share the hit buffers.
    auto check = [this, &g, access = c.access](const cl::Buffer& hits) {
      if (g.bad.count(access)) return;
      std::vector<RsHit> h;
      s_.rt.download("sorted hits", hits, h, n_);
      g.bad[access] = disagreeing_rays(h, g.first_order);
    };
    if (!permute) {
      m.arms.push_back({{"trace:gather"}, [this, &g, check] {
                          const double ms = timed_trace(rays_, g.order, gather_hits_, "waiting for the sorted trace");
                          check(gather_hits_);
                          return std::vector<double>{ms};
                        }});
    } else {
      m.arms.push_back({{"permute", "trace:permute"}, [this, &g, check] {
                          cl::Event p = s_.permuter.enqueue(rays_, g.order, n_, permuted_rays());
                          cl_call("waiting for the permute kernel", [&] { p.wait(); });
                          const double permute_ms = event_ms(p);
                          const double trace_ms = timed_trace(permuted_rays(), identity_, permute_hits_,
                                                              "waiting for the trace of the permuted rays");
                          check(permute_hits_);
                          return std::vector<double>{permute_ms, trace_ms};
                        }});
    }
    m.targets.push_back([trace = "trace:" + c.access](const Series& s) { return ratio_interval(s.at("nosort"), s.at(trace)); });
  }
  add_embree_arms(m, g);
  return m;
}

void BatchBench::add_embree_arms(MeasurementGroup& m, SortedGroup& g) {
#ifdef RAYSORT_HAVE_EMBREE
  using Clock = std::chrono::steady_clock;
  for (const EmbreeArm& arm : embree_arms_) {
    const std::string stage = "embree:" + arm.key + ":";
    for (const CellRecord& c : g.cells) {
      const bool permute = c.access == "permute";
      m.arms.push_back({{stage + c.access}, [this, &g, &arm, permute, access = c.access] {
                          const bool any_hit = batch_.any_hit();
                          // Untimed: the rays in the group's order (permute), made once.
                          if (permute && g.embree_permuted.empty()) {
                            g.embree_permuted.resize(n_);
                            // An entry past the rays (an order that is no permutation, which fails the
                            // cell after the rounds) must not be read past the batch.
                            for (std::uint32_t i = 0; i < n_; ++i)
                              g.embree_permuted[i] = batch_.rays[g.first_order[i] < n_ ? g.first_order[i] : 0];
                          }
                          const auto t0 = Clock::now();
                          std::vector<RsHit> hits = permute ? s_.embree->trace(g.embree_permuted, any_hit, arm.path)
                                                            : s_.embree->trace(batch_.rays, any_hit, arm.path, g.first_order);
                          const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
                          // The first run's hits back in ray order, against Embree's NoSort-order ones:
                          // an order may give a ray the other triangle of a tie (a packet's companions
                          // decide which is met first), and nothing else.
                          const std::string key = arm.key + ":" + access;
                          if (!g.embree_checked.count(key)) {
                            std::vector<RsHit> back(n_);
                            for (std::uint32_t i = 0; i < n_; ++i)
                              if (g.first_order[i] < n_) back[g.first_order[i]] = hits[i];
                            const HitAgreement a = compare_with_embree(arm.nosort_hits, back, any_hit);
                            const std::size_t differ = a.differences() - a.ties();
                            g.embree_checked[key].error =
                                differ == 0 ? ""
                                            : fmt::format("Embree {} ({}): {} of {} rays traced in the sorted order ({}) "
                                                          "differ from the NoSort order beyond ties ({} another triangle "
                                                          "farther apart, {} hit only in NoSort order, {} hit only in the "
                                                          "sorted order)",
                                                          arm.key, embree_path_name(arm.path, any_hit), differ, n_, access,
                                                          a.other_tri, a.ours_only, a.embree_only);
                            g.embree_checked[key].ties = a.ties();
                          }
                          return std::vector<double>{ms};
                        }});
      m.targets.push_back([nosort = stage + "nosort", sorted = stage + c.access](const Series& s) {
        return ratio_interval(s.at(nosort), s.at(sorted));
      });
    }
  }
#else
  (void)m, (void)g;
#endif
}

std::string BatchBench::fill_embree(CellRecord& c, const Outcome& o, const SortedOrder* so, const SortedGroup* g,
                                    const ProtocolSettings& settings) {
  if (embree_arms_.empty()) return "";
#ifdef RAYSORT_HAVE_EMBREE
  const bool any_hit = batch_.any_hit();
  for (const EmbreeArm& arm : embree_arms_) {
    if (!arm.agreement_error.empty()) return arm.agreement_error;
    CellRecord::EmbreeFigures e;
    e.path = arm.key;
    e.call = embree_path_name(arm.path, any_hit);
    e.threads = s_.embree->threads();
    e.agreement_with_ours = arm.agreement;
    const std::vector<double>& nosort = o.series.at("embree:" + arm.key + ":nosort");
    e.nosort = Timing::of(nosort);
    c.samples["embree:" + arm.key + ":nosort"] = nosort;
    if (so && g) {
      const std::string key = arm.key + ":" + c.access;
      const SortedGroup::EmbreeCheck& check = g->embree_checked.at(key);
      if (!check.error.empty()) return check.error;
      const std::vector<double>& trace = o.series.at("embree:" + key);
      e.trace = Timing::of(trace);
      c.samples["embree:" + arm.key + ":trace"] = trace;
      const Estimate measured = ratio_interval(nosort, trace, settings.confidence);
      // The same rays in the same order: whatever the clock says is noise (as our own speedup).
      e.speedup = so->identity ? Estimate{1.0, 1.0, 1.0, measured.n} : measured;
      e.ties = check.ties;
      e.differ = 0;
    }
    c.embree.push_back(std::move(e));
  }
  return "";
#else
  (void)c, (void)o, (void)so, (void)g, (void)settings;
  return "";
#endif
}

std::string BatchBench::check_order(const SortedGroup& g, SortedOrder& so) {
  s_.rt.download("sorted order", g.order, so.order, n_);
  std::vector<std::uint8_t> seen(n_, 0);
  so.permutation = true;
  for (auto v : so.order)
    if (v >= n_ || seen[v]++) {
      so.permutation = false;
      break;
    }
  if (!so.permutation) return "the sorted order is not a permutation of the rays";
  if (so.order != g.first_order) return "the sort gave another order in a later round than in the first";
  so.identity = true;
  for (std::uint32_t i = 0; so.identity && i < n_; ++i) so.identity = so.order[i] == i;
  // The codes the sort ordered by (a top-k sort: the highest k bits only), in sorted order.
  const unsigned shift = g.cfg.top_bits > 0 ? g.cfg.key_bits - g.cfg.top_bits : 0;
  std::vector<std::uint64_t> sorted_keys(n_);
  for (std::uint32_t i = 0; i < n_; ++i) sorted_keys[i] = g.unsorted[so.order[i]] >> shift;
  // A sort that stops at warp granularity (run --warp-sort) leaves ranges of up to warp_group pairs in
  // their input order: its own tests check it against its host twin (tests/sort_test.cpp).
  if (g.cfg.warp_group == 0 && !std::is_sorted(sorted_keys.begin(), sorted_keys.end()))
    return "the sorted order does not sort the keys";
  so.anc = average_number_of_codes(sorted_keys);
  so.simt = simt_model(bvh_, batch_.rays, so.order.data(), batch_.any_hit(), s_.tracer.variant(), s_.tracer.layout(),
                       s_.gpu, &so.gpu, &trails_);
  return "";
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
  cl::Buffer values = s_.rt.buffer("values (second launch)", std::max<std::size_t>(1, n_) * sizeof(std::uint32_t));
  s_.encoder.enqueue(encoder, bits, rays_, identity_, n_, keys, values).wait();
  const std::vector<std::uint64_t> again = DeviceEncoder::download_keys(s_.rt, keys, bits, n_, "keys (second launch)");
  std::size_t differ = 0;
  for (std::uint32_t i = 0; i < n_; ++i) differ += first[i] != again[i];
  if (differ == 0) return "";
  return fmt::format("{} gave other keys on a second launch over the same rays ({} of {} differ); it has no host twin, "
                     "so its keys are checked against themselves: make its key a function of the ray and the scene "
                     "alone (no uninitialised variable, no other work-item's data)",
                     encoder_name(encoder), differ, n_);
}

void BatchBench::finish_nosort(CellRecord& c, const Outcome& o, const ProtocolSettings& settings) {
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
  if (const std::string why = fill_embree(c, o, nullptr, nullptr, settings); !why.empty()) {
    c.status = "failed";
    c.error = why;
  }
}

void BatchBench::finish_group(SortedGroup& g, const Outcome& o, const ProtocolSettings& settings) {
  SortedOrder so;
  std::string why = check_order(g, so);
  const std::string keys_hash = fnv1a_hex(g.unsorted.data(), g.unsorted.size() * sizeof(std::uint64_t));
  for (CellRecord& c : g.cells) {
    c.cut_ms = g.cut_ms;
    c.keys_hash = keys_hash;
    c.order_hash = fnv1a_hex(so.order.data(), so.order.size() * sizeof(std::uint32_t));
    c.order_is_permutation = so.permutation;
    c.same_order_as_nosort = so.identity;
    const std::size_t bad = g.bad.count(c.access) ? g.bad.at(c.access) : n_;
    c.hits_match_nosort = why.empty() && bad == 0;
    if (!why.empty()) {
      c.status = "failed", c.error = why;
      continue;
    }
    if (bad != 0) {
      c.status = "failed";
      c.error = fmt::format("{} of {} hits differ from NoSort after scattering back ({})", bad, n_, c.access);
      continue;
    }
    fill_sorted_cell(c, o, so, settings);
    if (const std::string embree_why = fill_embree(c, o, &so, &g, settings); !embree_why.empty())
      c.status = "failed", c.error = embree_why;
  }
}

std::vector<Outcome> BatchBench::measure_chunk(bool with_nosort, const std::vector<SortedGroup*>& sorted,
                                               const ProtocolSettings& settings) {
  SharedMeasurement m;
  m.common = common_arms();
  if (with_nosort) {
    MeasurementGroup nosort;
    nosort.targets = {[](const Series& s) { return ratio_interval(s.at("nosort"), s.at("aa")); }};
    m.groups.push_back(std::move(nosort));
  }
  for (SortedGroup* g : sorted) m.groups.push_back(sorted_group(*g));
  return measure_shared(m, settings);
}

std::vector<CellRecord> BatchBench::measure_batch(const std::vector<std::vector<CellRecord>>& groups,
                                                  const ProtocolSettings& settings, const PrepareEncoder& prepare) {
  // The NoSort cell and the sorted groups (a deque: the arms hold references to their group).
  std::optional<CellRecord> nosort;
  std::deque<SortedGroup> sorted;
  for (const auto& cells : groups) {
    if (cells.front().encoder == kBaselineEncoder) {
      nosort = cells.front();
    } else {
      sorted.emplace_back();
      sorted.back().cells = cells;
      sorted.back().encoder = *parse_encoder(cells.front().encoder);
    }
  }
  if (nosort) {
    CellRecord& c = *nosort;
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
  }
  auto collect = [&] {
    std::vector<CellRecord> out;
    std::size_t next = 0;
    for (const auto& cells : groups) {
      if (cells.front().encoder == kBaselineEncoder) {
        out.push_back(*nosort);
      } else {
        const SortedGroup& g = sorted[next++];
        out.insert(out.end(), g.cells.begin(), g.cells.end());
      }
    }
    return out;
  };
  auto fail = [](std::vector<CellRecord>& cells, const std::string& status, const std::string& error) {
    for (CellRecord& c : cells) c.status = status, c.error = error;
  };
  if (!setup_error_.empty()) {
    if (nosort) nosort->status = "failed", nosort->error = setup_error_;
    for (SortedGroup& g : sorted) {
      for (CellRecord& c : g.cells) c.rays = n_;
      fail(g.cells, "failed", "the batch's setup failed: " + setup_error_);
    }
    return collect();
  }

  ready_embree();
  std::vector<SortedGroup*> ready;
  for (SortedGroup& g : sorted) {
    ready_group(g, prepare);
    if (g.error.empty())
      ready.push_back(&g);
    else
      fail(g.cells, "failed", g.error);
  }
  // The rounds have no warm-up round by default (MatrixSpec::warmup says why): before them, the
  // sort and the permute run once, untimed, so that their buffers (the sort's scratch, the permuted
  // rays) are touched outside every clock. The trace and the encoders ran above.
  if (!ready.empty()) {
    try {
      warm_sort_and_permute(*ready.front());
    } catch (const Error& err) {
      fail(ready.front()->cells, "failed", err.what());
      ready.erase(ready.begin());
    }
  }
  // Chunks of groups that share rounds (groups_per_round says why a bound); the first one holds the
  // NoSort cell.
  const std::size_t chunk = groups_per_round();
  bool with_nosort = nosort.has_value();
  for (std::size_t begin = 0; begin < ready.size() || with_nosort; begin += chunk) {
    const std::vector<SortedGroup*> part(ready.begin() + static_cast<std::ptrdiff_t>(std::min(begin, ready.size())),
                                         ready.begin() + static_cast<std::ptrdiff_t>(std::min(begin + chunk, ready.size())));
    try {
      const std::vector<Outcome> o = measure_chunk(with_nosort, part, settings);
      if (with_nosort) finish_nosort(*nosort, o.front(), settings);
      for (std::size_t i = 0; i < part.size(); ++i) finish_group(*part[i], o[i + with_nosort], settings);
    } catch (const TimedOut& t) {
      if (with_nosort) nosort->status = "timeout", nosort->error = t.what();
      for (SortedGroup* g : part) fail(g->cells, "timeout", t.what());
    } catch (const Error& err) {
      // A device fault (allocation, build, launch) fails these cells; the run goes on.
      if (with_nosort) nosort->status = "failed", nosort->error = err.what();
      for (SortedGroup* g : part) fail(g->cells, "failed", err.what());
    }
    with_nosort = false;
    for (SortedGroup* g : part) g->embree_permuted = {}, g->order = cl::Buffer();  // free as we go
  }
  return collect();
}

}  // namespace raysort
