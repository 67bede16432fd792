#include "bench/runner.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "bench/metrics.h"
#include "bench/result_set.h"
#include "bvh/bvh.h"
#include "cl/runtime.h"
#include "render/batches.h"
#include "scene/load.h"
#include "sort/radix_sort.h"
#include "trace/tracer.h"
#include "util/error.h"

namespace raysort {

namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted = true; }

std::string host_cpu() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

std::string git_commit() {
  std::string cmd = std::string("git -C '") + RAYSORT_SOURCE_DIR + "' rev-parse --short=12 HEAD 2>/dev/null";
  std::string out;
  if (FILE* p = popen(cmd.c_str(), "r")) {
    char buf[64];
    while (fgets(buf, sizeof buf, p)) out += buf;
    pclose(p);
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out.empty() ? "unknown" : out;
}

std::string utc_now() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

struct Progress {
  std::size_t total = 0, done = 0;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  void line(const std::string& what) {
    double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::string eta = "?";
    if (done > 0) {
      double left = elapsed / static_cast<double>(done) * static_cast<double>(total - done);
      eta = left >= 60 ? fmt::format("{:.0f}m{:02.0f}s", std::floor(left / 60), std::fmod(left, 60.0))
                       : fmt::format("{:.0f}s", left);
    }
    fmt::print(stderr, "[{}/{}] {}  (elapsed {:.0f}s, ETA {})\n", done, total, what, elapsed, eta);
  }
};

struct BatchBuffers {
  cl::Buffer rays, identity, hits, keys32, keys64, values;
};

// Thrown inside a cell when it has run longer than MatrixSpec::cell_timeout_s.
struct CellTimedOut {};

// The per-cell wall-clock limit (--timeout). Checked between repetitions: an OpenCL kernel cannot
// be interrupted portably, so a kernel in flight runs to completion, and the cell's remaining
// repetitions are skipped.
struct CellClock {
  double limit_s;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double elapsed_s() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); }
  bool over() const { return limit_s > 0 && elapsed_s() > limit_s; }
  std::string message() const {
    return fmt::format("timed out: {:.3f} s, over --timeout {} s (remaining repetitions skipped)", elapsed_s(), limit_s);
  }
};

template <class T>
std::vector<std::uint64_t> widen(const std::vector<T>& v) {
  return std::vector<std::uint64_t>(v.begin(), v.end());
}

}  // namespace

std::string default_result_dir(const MatrixSpec& spec, const std::string& device_slug, const ShardSpec& shard) {
  const std::string matrix = spec.to_json().dump();
  std::string hash = fnv1a_hex(matrix.data(), matrix.size()).substr(0, 8);
  std::string dir = fmt::format("results/{}/{}-{}", device_slug, spec.preset.empty() ? "run" : spec.preset, hash);
  return shard.active() ? fmt::format("{}-shard{}of{}", dir, shard.index, shard.count) : dir;
}

std::vector<PlannedCell> plan_matrix_shards(const MatrixSpec& spec, const std::string& scene_root, unsigned count) {
  return plan_shards(matrix_cells(spec, [&](const std::string& scene) { return load_scene_facts(scene, spec, scene_root); }),
                     count);
}

namespace {
// Scene problems a run can find before any work starts: a scene file or OBJ given by path is
// parsed (it is small next to a run); an embedded scene's OBJ files must exist under the root.
void check_scenes_before_work(const MatrixSpec& spec, const RunOptions& opts) {
  SceneOptions scene_opts;
  scene_opts.scene_root = opts.scene_root;
  scene_opts.width = scene_opts.height = 1;
  std::vector<SceneListing> listed = list_scenes();
  for (const auto& name : spec.scenes) {
    auto it = std::find_if(listed.begin(), listed.end(), [&](const SceneListing& l) { return l.name == name; });
    if (it == listed.end()) {
      (void)load_scene(name, scene_opts);
      continue;
    }
    const std::string root = resolve_scene_root(scene_opts);
    for (const auto& rel : it->obj_files) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(std::filesystem::path(root) / rel, ec))
        throw Error(fmt::format("scene {} needs {} under the scene root {}, which is not there; pass --scene-root DIR "
                                "or set RAYSORT_SCENE_ROOT",
                                name, rel, root));
    }
  }
}
}  // namespace

RunSummary run_matrix(const MatrixSpec& spec, const RunOptions& opts) {
  validate_matrix(spec);
  check_scenes_before_work(spec, opts);
  // A shard plans the whole matrix (every shard computes the same plan) and keeps its own cells;
  // the baseline of a batch is measured by every shard that has a cell of it (speedups compare
  // with a NoSort trace on the same machine), and recorded by the shard that owns the NoSort cell.
  std::vector<PlannedCell> plan;
  std::set<std::string> mine, mine_scenes, mine_batches;  // cell ids; scenes; "scene/batch/variant"
  if (opts.shard.active()) {
    plan = plan_matrix_shards(spec, opts.scene_root, opts.shard.count);
    for (const auto& c : plan)
      if (c.shard == opts.shard.index) {
        mine.insert(c.id);
        mine_scenes.insert(c.scene);
        mine_batches.insert(c.scene + "/" + c.batch + "/" + c.variant);
      }
  }
  auto in_shard = [&](const std::string& id) { return !opts.shard.active() || mine.count(id) > 0; };
  Runtime rt(select_device(opts.device));
  const DeviceInfo& dev = rt.info();
  RunSummary summary;
  summary.out_dir = opts.out.empty() ? default_result_dir(spec, dev.slug(), opts.shard) : opts.out;

  nlohmann::json meta = {
      {"format_version", kResultFormatVersion},
      {"raysort_version", RAYSORT_VERSION},
      {"matrix", spec.to_json()},
      {"device",
       {{"name", dev.name},
        {"type", dev.type},
        {"platform", dev.platform_name},
        {"platform_version", dev.platform_version},
        {"opencl", dev.version},
        {"opencl_c", dev.opencl_c_version},
        {"driver", dev.driver_version},
        {"pocl_version", dev.is_pocl() ? dev.platform_version : ""},
        {"compute_units", dev.compute_units},
        {"slug", dev.slug()}}},
      {"host_cpu", host_cpu()},
      {"git_commit", git_commit()},
      {"command", opts.command},
      {"date", utc_now()},
      {"seeds", {{"rays", spec.seed}}},
  };
  if (opts.shard.active()) meta["shard"] = shard_meta(spec, opts.shard, plan);
  ResultSet results = ResultSet::open_for_run(summary.out_dir, meta);
  fmt::print(stderr, "raysort run: {}{} on {}; results in {}\n", spec.preset.empty() ? "custom matrix" : spec.preset,
             opts.shard.active() ? fmt::format(", shard {} ({} of {} cells)", opts.shard.str(), mine.size(), plan.size())
                                 : "",
             dev.name, summary.out_dir);

  // Cells per scene (the batch list is only known after generation; count requested ones).
  std::vector<Encoder> encoders;
  for (auto& n : spec.encoders)
    if (auto e = parse_encoder(n); e && *e != Encoder::NoSort) encoders.push_back(*e);
  const std::vector<std::string> variant_names = spec.variant_list();
  Progress progress;
  for (auto& s : spec.scenes)
    progress.total += (spec.batches.empty() ? 3 : spec.batches.size()) * variant_names.size() *
                      (1 + encoders.size() * (spec.bits_for(s).size() + spec.top_bits.size()));
  if (opts.shard.active()) progress.total = mine.size();
  std::vector<std::string> absent;  // a shard's planned cells whose batch turned out not to exist

  const char* kill_env = std::getenv("RAYSORT_TEST_KILL_AFTER_CELLS");
  const std::size_t kill_after = kill_env ? std::strtoul(kill_env, nullptr, 10) : 0;
  auto previous = std::signal(SIGINT, on_sigint);
  std::signal(SIGTERM, on_sigint);
  RadixSort sorter(rt);
  sorter.warm_up();

  SceneOptions scene_opts;
  scene_opts.scene_root = opts.scene_root;
  parse_resolution(spec.resolution, scene_opts.width, scene_opts.height);
  scene_opts.spp = spec.spp;
  RayGenOptions gen;
  gen.width = scene_opts.width;
  gen.height = scene_opts.height;
  gen.spp = spec.spp;
  gen.seed = spec.seed;

  for (const auto& scene_name : spec.scenes) {
    if (g_interrupted) break;
    if (opts.shard.active() && !mine_scenes.count(scene_name)) continue;
    Scene scene = load_scene(scene_name, scene_opts);
    Scene::Flat tris = scene.flatten();
    Bvh bvh = build_bvh(tris);
    progress.line(fmt::format("{}: {} triangles, BVH {:.0f} ms; generating batches", scene_name, tris.size(), bvh.build_ms));
    auto batches = generate_batches(scene, tris, bvh, gen);
    // Both trace variants see the same rays: batches come from the fast host reference (render/
    // batches.h); each cell checks the device against the host reference of its own variant.
    std::map<std::string, std::unique_ptr<Tracer>> tracers;
    for (const auto& v : variant_names) tracers[v] = std::make_unique<Tracer>(rt, bvh, parse_trace_variant(v));
    DeviceEncoder encoder(rt, bvh, scene.bounds(), spec.params);
    encoder.warm_up();

    std::vector<std::string> wanted = spec.batches;
    if (wanted.empty())
      for (auto& b : batches) wanted.push_back(b.batch.name);
    for (const auto& batch_name : wanted) {
      if (g_interrupted) break;
      auto it = std::find_if(batches.begin(), batches.end(), [&](const ReferencedBatch& b) { return b.batch.name == batch_name; });
      if (it == batches.end()) {
        fmt::print(stderr, "note: scene {} has no batch {} (its effects do not imply it); skipped\n", scene_name, batch_name);
        if (opts.shard.active()) {
          std::size_t lost = 0;
          for (const auto& c : plan)
            if (c.shard == opts.shard.index && c.scene == scene_name && c.batch == batch_name) {
              absent.push_back(c.id);
              ++lost;
            }
          progress.total -= std::min(progress.total - progress.done, lost);
          continue;
        }
        progress.total -= std::min(progress.total - progress.done,
                                   variant_names.size() * (1 + encoders.size() * (spec.bits_for(scene_name).size() +
                                                                                  spec.top_bits.size())));
        continue;
      }
      const RayBatch& batch = it->batch;
      const auto n = static_cast<std::uint32_t>(batch.size());
      const bool any_hit = batch.any_hit();
      BatchBuffers buf;
      std::vector<std::uint32_t> identity(n);
      std::iota(identity.begin(), identity.end(), 0u);
      // Fast and robust references (the leak rate: rays one variant misses that the other hits).
      // The batch's own reference is the fast one (render/batches.h); the robust one is traced once
      // here when a robust variant runs. variant_names holds only "fast" and "robust" (validated).
      std::vector<RsHit> robust_reference;
      std::map<std::string, const std::vector<RsHit>*> references{{"fast", &it->reference_hits}};
      if (std::find(variant_names.begin(), variant_names.end(), "robust") != variant_names.end()) {
        robust_reference = trace_reference(bvh, batch.rays, nullptr, any_hit, nullptr, TraceVariant::Robust);
        references["robust"] = &robust_reference;
      }
      auto leaks_per_million = [&](const std::string& v) {
        if (references.size() < 2 || n == 0) return -1.0;
        const auto& mine = *references.at(v);
        const auto& other = *references.at(v == "fast" ? "robust" : "fast");
        std::size_t leaks = 0;
        for (std::uint32_t i = 0; i < n; ++i) leaks += mine[i].tri == RS_NO_HIT && other[i].tri != RS_NO_HIT;
        return static_cast<double>(leaks) * 1e6 / static_cast<double>(n);
      };
      for (const std::string& variant_name : variant_names) {
        if (opts.shard.active() && !mine_batches.count(scene_name + "/" + batch_name + "/" + variant_name)) continue;
        const TraceVariant variant = parse_trace_variant(variant_name);
        Tracer& tracer = *tracers.at(variant_name);
        const std::vector<RsHit>& variant_reference = *references.at(variant_name);
        // NoSort: the baseline every speedup on this batch is measured against, in this run.
        std::vector<double> nosort_times;
        std::vector<RsHit> nosort_hits;
        CellClock nosort_clock{spec.cell_timeout_s};
        std::string batch_error;  // a device fault in the batch's setup or baseline fails all its cells
        try {
          buf.rays = rt.upload("rays of " + batch.name, batch.rays);
          buf.identity = rt.upload("identity order", identity);
          buf.hits = rt.buffer("hits", std::max<std::size_t>(1, n) * sizeof(RsHit));
          buf.values = rt.buffer("sort values (ray order)", std::max<std::size_t>(1, n) * 4);
          buf.keys32 = rt.buffer("32-bit keys", std::max<std::size_t>(1, n) * 4);
          buf.keys64 = rt.buffer("64-bit keys", std::max<std::size_t>(1, n) * 8);
          for (unsigned i = 0; i < spec.warmup + spec.reps; ++i) {
            cl::Event ev = tracer.enqueue(buf.rays, buf.identity, n, any_hit, buf.hits);
            cl_call("waiting for the NoSort trace", [&] { ev.wait(); });
            if (i >= spec.warmup) nosort_times.push_back(event_ms(ev));
            if (nosort_clock.over()) break;
          }
          rt.download("NoSort hits", buf.hits, nosort_hits, n);
        } catch (const Error& err) {
          batch_error = err.what();
        }
        const Timing nosort_trace = Timing::of(nosort_times);
        const SimtModel nosort_simt = simt_model(bvh, batch.rays, nullptr, any_hit, variant);
        {
          CellRecord c;
          c.scene = scene_name, c.batch = batch_name, c.encoder = kBaselineEncoder, c.bits = 0, c.rays = n;
          c.variant = variant_name;
          c.trace = nosort_trace;
          c.trace_mrays = nosort_trace.median_ms > 0 ? n / (nosort_trace.median_ms * 1e3) : 0;
          c.speedup = c.net_speedup = 1.0;
          c.anc = 0;
          c.simt_lane_efficiency = nosort_simt.lane_efficiency;
          c.simt_distinct_per_visit = nosort_simt.distinct_nodes_per_visit;
          c.simt_lane_efficiency_ratio = c.simt_distinct_per_visit_ratio = 1.0;
          c.leaks_per_million = leaks_per_million(variant_name);
          c.hits_match_nosort = batch_error.empty() && count_hit_mismatches(nosort_hits, variant_reference) == 0;
          c.order_is_permutation = true;
          c.keys_hash = fnv1a_hex(nullptr, 0);
          c.order_hash = fnv1a_hex(identity.data(), identity.size() * 4);
          if (!batch_error.empty()) {
            c.status = "failed";
            c.error = batch_error;
          } else if (!c.hits_match_nosort) {
            c.status = "failed";
            c.error = "device NoSort hits differ from the host reference traversal";
          } else if (nosort_clock.over()) {
            c.status = "timeout";
            c.error = nosort_clock.message();
          }
          if (in_shard(c.id())) {
            ++progress.done;
            if (!results.has(c.id())) {
              results.add(c);
              ++summary.cells_run;
              summary.cells_failed += !c.ok();
            }
            progress.line(c.ok() ? fmt::format("{} {} NoSort: {:.2f} MRays/s", scene_name, batch_name, c.trace_mrays)
                                 : fmt::format("{}: {}: {}", c.id(), c.status == "timeout" ? "TIMEOUT" : "FAILED", c.error));
          }
        }

        for (Encoder e : encoders) {
          std::vector<std::pair<unsigned, unsigned>> variants;  // (bits, top_bits)
          auto bits_list = spec.bits_for(scene_name);
          for (unsigned b : bits_list) variants.push_back({b, 0});
          for (unsigned k : spec.top_bits) variants.push_back({bits_list.back(), k});
          for (auto [bits, top] : variants) {
            if (g_interrupted) break;
            CellRecord c;
            c.scene = scene_name, c.batch = batch_name, c.encoder = std::string(encoder_name(e)), c.bits = bits;
            c.top_bits = top, c.rays = n, c.variant = variant_name;
            if (!in_shard(c.id())) continue;
            ++progress.done;
            if (results.has(c.id())) {
              ++summary.cells_skipped;
              continue;
            }
            CellClock clock{spec.cell_timeout_s};
            try {
              if (!batch_error.empty()) throw Error("the batch's setup failed: " + batch_error);
              encoder.prepare(e, bits);
              cl::Buffer& keys = bits > 32 ? buf.keys64 : buf.keys32;
              RadixSortConfig cfg;
              cfg.key_bits = bits;
              cfg.top_bits = top;
              std::vector<double> te, ts, tt;
              std::vector<std::uint64_t> unsorted;
              for (unsigned i = 0; i < spec.warmup + spec.reps; ++i) {
                const DeviceEncoder::Events ev_e = encoder.enqueue(e, bits, buf.rays, buf.identity, n, keys, buf.values);
                ev_e.wait();
                if (i == 0) {  // fingerprint of the keys in generation order (outside timing)
                  if (bits > 32) {
                    std::vector<std::uint64_t> k;
                    rt.download("keys", keys, k, n);
                    unsorted = k;
                  } else {
                    std::vector<std::uint32_t> k;
                    rt.download("keys", keys, k, n);
                    unsorted = widen(k);
                  }
                }
                SortStats st = sorter.sort(keys, buf.values, n, cfg);
                cl::Event ev_t = tracer.enqueue(buf.rays, buf.values, n, any_hit, buf.hits);
                cl_call("waiting for the sorted trace", [&] { ev_t.wait(); });
                if (i >= spec.warmup) {
                  te.push_back(ev_e.ms());
                  ts.push_back(st.ms);
                  tt.push_back(event_ms(ev_t));
                }
                if (clock.over()) throw CellTimedOut{};
              }
              std::vector<std::uint32_t> order;
              std::vector<RsHit> hits;
              std::vector<std::uint64_t> sorted_keys;
              rt.download("sorted order", buf.values, order, n);
              rt.download("sorted hits", buf.hits, hits, n);
              if (bits > 32) {
                rt.download("sorted keys", keys, sorted_keys, n);
              } else {
                std::vector<std::uint32_t> k;
                rt.download("sorted keys", keys, k, n);
                sorted_keys = widen(k);
              }
              // Checks: the order is a permutation, and hits scattered back equal NoSort's.
              std::vector<std::uint8_t> seen(n, 0);
              bool perm = true;
              for (auto v : order) {
                if (v >= n || seen[v]++) {
                  perm = false;
                  break;
                }
              }
              std::size_t bad = 0;
              if (perm)
                for (std::uint32_t i = 0; i < n; ++i)
                  bad += std::memcmp(&hits[i], &nosort_hits[order[i]], sizeof(RsHit)) != 0;
              c.order_is_permutation = perm;
              c.hits_match_nosort = perm && bad == 0;
              c.keys_hash = fnv1a_hex(unsorted.data(), unsorted.size() * 8);
              c.order_hash = fnv1a_hex(order.data(), order.size() * 4);
              if (!c.hits_match_nosort) {
                c.status = "failed";
                c.error = perm ? fmt::format("{} of {} hits differ from NoSort after scattering back", bad, n)
                               : "the sorted order is not a permutation of the rays";
              } else {
                c.encode = Timing::of(te);
                c.sort = Timing::of(ts);
                c.trace = Timing::of(tt);
                double t = c.trace.median_ms;
                c.trace_mrays = t > 0 ? n / (t * 1e3) : 0;
                c.speedup = t > 0 ? nosort_trace.median_ms / t : 0;
                double total = c.encode.median_ms + c.sort.median_ms + t;
                c.net_speedup = total > 0 ? nosort_trace.median_ms / total : 0;
                c.overhead_pct = t > 0 ? (c.encode.median_ms + c.sort.median_ms) / t * 100.0 : 0;
                // ANC of the codes the sort used: a top-k sort orders by the highest k bits only.
                if (top > 0)
                  for (auto& k : sorted_keys) k >>= (bits - top);
                c.anc = average_number_of_codes(sorted_keys);
                SimtModel m = simt_model(bvh, batch.rays, order.data(), any_hit, variant);
                c.simt_lane_efficiency = m.lane_efficiency;
                c.simt_distinct_per_visit = m.distinct_nodes_per_visit;
                c.simt_lane_efficiency_ratio =
                    nosort_simt.lane_efficiency > 0 ? m.lane_efficiency / nosort_simt.lane_efficiency : 0;
                c.simt_distinct_per_visit_ratio = nosort_simt.distinct_nodes_per_visit > 0
                                                      ? m.distinct_nodes_per_visit / nosort_simt.distinct_nodes_per_visit
                                                      : 0;
              }
            } catch (const Error& err) {
              // A device fault (allocation, build, launch) fails this cell; the run goes on.
              c.status = "failed";
              c.error = err.what();
            } catch (const CellTimedOut&) {
              c.status = "timeout";
              c.error = clock.message();
            }
            results.add(c);
            ++summary.cells_run;
            summary.cells_failed += !c.ok();
            // Test hook (tests/bench_test.cpp): die by SIGKILL right after the N-th new cell, a
            // deterministic kill point for the resume test.
            if (kill_after > 0 && summary.cells_run >= kill_after) std::raise(SIGKILL);
            progress.line(c.ok() ? fmt::format("{}: {:.2f} MRays/s ({:.2f}x), encode {:.2f} + sort {:.2f} ms, ANC {:.2f}",
                                               c.id(), c.trace_mrays, c.speedup, c.encode.median_ms, c.sort.median_ms, c.anc)
                                 : fmt::format("{}: {}: {}", c.id(), c.status == "timeout" ? "TIMEOUT" : "FAILED", c.error));
          }
        }
      }
    }
  }
  std::signal(SIGINT, previous);
  std::signal(SIGTERM, SIG_DFL);
  if (!absent.empty()) {
    // raysort merge counts these as accounted for (no shard can produce them).
    std::set<std::string> all(absent.begin(), absent.end());
    for (const auto& id : results.meta().value("absent_cells", std::vector<std::string>{})) all.insert(id);
    results.set_meta("absent_cells", std::vector<std::string>(all.begin(), all.end()));
  }
  results.write_views();
  results.write_plots();
  summary.interrupted = g_interrupted;
  return summary;
}

}  // namespace raysort
