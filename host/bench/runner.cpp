// The matrix runner: a short loop over plan → scene → batch → cell → record. What happens to one
// cell (its rounds, checks and figures) lives in bench/cell_measure.cpp, and how a time is taken
// in bench/protocol.h.
#include "bench/runner.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <tuple>

#include "bench/batch_file.h"
#include "bench/cell_measure.h"
#include "bench/result_set.h"
#include "bench/scene_bench.h"
#include "bvh/prepared_scene.h"
#include "embree/embree_reference.h"
#include "encode/encoder_file.h"
#include "render/batches.h"
#include "render/frame_memory.h"
#include "util/build_commit.h"
#include "runtime/runtime.h"
#include "scene/load.h"
#include "scene/provenance.h"
#include "util/error.h"

namespace raysort {

namespace {

std::atomic<bool> g_interrupted{false};
std::atomic<int> g_signal{0};  // which signal: the exit code is 128 + it, as the shell's would be
extern "C" void on_sigint(int sig) {
  g_signal = sig;
  g_interrupted = true;
}

// SIGINT/SIGTERM end the run at the next arm of the cell in flight (that cell is not recorded; a
// resume measures it), restored on exit.
struct InterruptGuard {
  using Handler = void (*)(int);
  Handler previous_int = std::signal(SIGINT, on_sigint);
  Handler previous_term = std::signal(SIGTERM, on_sigint);
  ~InterruptGuard() {
    std::signal(SIGINT, previous_int);
    std::signal(SIGTERM, previous_term);
  }
};

std::string host_cpu() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

std::string utc_now() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

// The trees the cells traced and modelled: how they were built, and per trace class the tree's width
// and the rays per work-item ("layout", "width" and "rays_per_work_item": the first class's).
nlohmann::json bvh_meta(const std::vector<TraceLayout>& layouts) {
  const BvhBuildOptions build;  // prepare_scene builds with the defaults
  nlohmann::json classes = nlohmann::json::array();
  for (TraceLayout l : layouts)
    classes.push_back({{"class", trace_layout_name(l)},
                       {"width", tree_width(l)},
                       {"rays_per_work_item", packet_width(l)}});
  return {{"layout", trace_layout_name(layouts.front())},
          {"width", tree_width(layouts.front())},
          {"rays_per_work_item", packet_width(layouts.front())},
          {"classes", classes},
          {"builder", "binned SAH (Wald 2007), object median past the depth bound"},
          {"bins", build.bins},
          {"max_leaf_size", build.max_leaf_size},
          {"traversal_cost", build.traversal_cost},
          {"intersection_cost", build.intersection_cost},
          {"simt_model", "walks the same tree as the trace kernel, one ray per lane of a 32-wide warp (bench/metrics.h)"}};
}

// The sort the cells' orders came from (sort/radix_sort.h, docs/sort.md): its shape on this device
// and which kind of passes it runs (on NVIDIA the Onesweep passes, elsewhere reduce-then-scan or
// the CPU shape's), as it stands after fitting its launches to the device's kernels.
nlohmann::json sort_meta(const RadixSortTuning& t) {
  const bool cpu = t.work_group == 1;
  nlohmann::json m = {{"doc", "docs/sort.md"},
                      {"shape", cpu ? "cpu" : "gpu"},
                      {"digit_bits", t.radix_bits},
                      {"work_group", t.work_group},
                      {"passes", cpu ? (t.hybrid() ? fmt::format("MSD-first hybrid from {} pairs, else LSD", t.hybrid_min)
                                                   : std::string("LSD"))
                                     : t.onesweep ? "onesweep (below 2^30 pairs)"
                                                  : "reduce-then-scan"}};
  if (cpu)
    m["tile"] = fmt::format(">= {} keys, {} tiles per compute unit", t.min_tile, t.tiles_per_unit);
  else
    m["tile"] = fmt::format("{} x {} keys", t.work_group, t.items);
  return m;
}

// What the kernels were built from (runtime/runtime.h): a resume and compare check it.
nlohmann::json kernels_meta() {
  const KernelProvenance k = kernel_provenance();
  return {{"source", k.source}, {"hash", k.hash}, {"cl_options", k.cl_options}};
}

// The encoders from files among `encoders` (encode/encoder_file.h), for meta.json "encoder_files"
// (bench/encoder_files.h): each file's path and SHA-256 (a resume with another file is refused);
// null when there is none.
nlohmann::json encoder_files_meta(const std::vector<Encoder>& encoders) {
  nlohmann::json files = nlohmann::json::object();
  for (Encoder e : encoders)
    if (const EncoderFile* f = encoder_file(e))
      files[f->name] = {{"path", f->path},
                        {"sha256", f->sha256},
                        {"host_twin", false},
                        {"keys_checked", "no host twin: in every cell a second launch over the batch must give the "
                                         "same keys (bench/cell_measure.h)"}};
  return files.empty() ? nlohmann::json() : files;
}

// The ray file of run --rays (bench/batch_file.h), for meta.json "ray_files": its batch's name in
// the cells, the file's path and SHA-256 (a resume with another file is refused, as with an encoder
// file), and what its header says; null without one.
nlohmann::json ray_files_meta(const MatrixSpec& spec) {
  if (spec.ray_file.empty()) return nullptr;
  const RayFile f = read_ray_file(spec.ray_file);
  return {{ray_file_batch_name(spec.ray_file),
           {{"path", spec.ray_file},
            {"sha256", sha256_file(spec.ray_file)},
            {"batch", f.batch_name},
            {"rays", f.rays.size()},
            {"any_hit", f.any_hit},
            {"hits", f.has_hits},
            {"scene_sha256", sha256_hex(f.scene_sha256)},
            {"command", f.command},
            {"doc", "docs/rays-format.md"}}}};
}

// Embree's arms (run --embree-paths): which call and context flag each path makes, on how many
// threads, and how an arm is timed. Empty without paths (and in a build without Embree, which
// refuses them in validate_matrix).
nlohmann::json embree_meta(const std::vector<std::string>& keys, const std::string& isa) {
#ifdef RAYSORT_HAVE_EMBREE
  if (keys.empty()) return nullptr;
  const EmbreeScene probe(Scene::Flat{}, 0, isa);  // the device each scene's EmbreeScene gets: its threads, native widths
  nlohmann::json paths = nlohmann::json::array();
  for (const std::string& key : keys) {
    const EmbreePath path = parse_embree_paths(key).front();
    const EmbreePathInfo& info = embree_path_info(path);
    paths.push_back({{"path", key},
                     {"closest_hit", embree_path_name(path, false)},
                     {"any_hit", embree_path_name(path, true)},
                     {"rays_per_call", info.packet == 0 ? "a thread's chunk of up to 4096 (a stream)" : std::to_string(info.packet)},
                     {"context_flag", path == EmbreePath::Single ? "default (RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT)"
                                      : info.coherent            ? "RTC_INTERSECT_CONTEXT_FLAG_COHERENT"
                                                                 : "RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT"},
                     {"native", info.packet >= 4 ? nlohmann::json(probe.native_packets(info.packet)) : nlohmann::json(nullptr)}});
  }
  return {{"doc", "docs/measurement.md, \"Embree on sorted orders\"; docs/trace.md, \"Embree anchor\""},
          {"version", EmbreeScene::version()},
          {"threads", probe.threads()},
          {"isa", isa == "native" ? "native (the widest this CPU runs)" : isa + " (rtcNewDevice \"isa=" + isa + "\", --embree-isa)"},
          {"paths", paths},
          {"scene", "one triangle geometry per scene (built once), RTC_SCENE_FLAG_NONE, RTC_BUILD_QUALITY_HIGH"},
          {"chunks", "each thread takes contiguous chunks of 4096 rays of the order traced; a packet is consecutive rays"},
          {"arms", "per round and path: embree:<path>:nosort (the batch in NoSort order) and, in a sorted cell, "
                   "embree:<path>:trace (gather: rays[order[i]]; permute: the rays moved into sorted order on the "
                   "host before the rounds, untimed, traced in identity order)"},
          {"timing", "wall clock of the whole trace call (threads started and joined inside, rays copied into "
                     "Embree's layout and hits back inside it)"},
          {"speedup", "paired: embree:<path>:nosort / embree:<path>:trace per round, as the cell's own speedup"}};
#else
  (void)keys, (void)isa;
  return nullptr;
#endif
}

nlohmann::json run_meta(const MatrixSpec& spec, const RunOptions& opts, const DeviceInfo& dev,
                        const RadixSortTuning& sort) {
  nlohmann::json meta = {
      {"format_version", kResultFormatVersion},
      {"raysort_version", RAYSORT_VERSION},
      {"matrix", spec.to_json()},
      {"protocol",
       {{"doc", "docs/measurement.md"},
        {"arms", "a batch's cells share their rounds: per round, every measuring group's encode + sort, then nosort and "
                 "aa (nosort again) once for the batch and every measuring group's trace(s), in one seeded random order"},
        {"rounds", "shared per batch (docs/measurement.md, \"Shared rounds\"): a group leaves them when it stops"},
        {"estimate", "paired: Hodges-Lehmann location of the per-round log ratios; one arm's time: the median"},
        {"interval", fmt::format("{:.0f} %: exact Wilcoxon signed-rank interval of the Walsh averages (ratios), exact "
                                 "order-statistic (sign-test) interval of the median (times)",
                                 kConfidence * 100)},
        {"stop", "per group: min rounds (reps), then relative half-width <= max_noise, or max_time_s of sampling per "
                 "group of the batch"}}},
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
      {"git_commit", build_commit()},  // the binary's, not the checkout's at run time
      {"kernels", kernels_meta()},
      {"command", opts.command},
      {"date", utc_now()},
      {"seeds", {{"rays", spec.seed}}},
      {"bvh", bvh_meta(spec.layouts)},
      {"sort", sort_meta(sort)},
      {"baseline",
       {{"orders", spec.to_json().at("baseline")},
        {"pixel", "generation order: pixel-major, terminated paths compacted out in order"},
        {"shuffled", "Fisher-Yates over the generation order; j = (mt19937_64() * (i + 1)) >> 64, the engine seeded "
                     "with FNV-1a(batch name) ^ seed * 0x9e3779b97f4a7c15 (render/batches.h)"}}},
  };
  if (!spec.embree_paths.empty()) meta["embree"] = embree_meta(spec.embree_paths, spec.embree_isa);
  if (nlohmann::json files = encoder_files_meta(spec.encoders); !files.is_null()) meta["encoder_files"] = std::move(files);
  if (nlohmann::json files = ray_files_meta(spec); !files.is_null()) meta["ray_files"] = std::move(files);
  return meta;
}

struct Progress {
  std::size_t total = 0, done = 0;
  // The ETA's rate is that of the cells measured by this run: not those a resume skipped (`skipped`,
  // in `done`), and a batch's cells count from its first line on (`arriving`: recorded together
  // when its shared rounds end, they were one estimate of 1000 minutes, then 999, ...).
  std::size_t skipped = 0, arriving = 0;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  void line(const std::string& what) {
    double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::string eta = "?";
    const std::size_t finished = done + arriving;
    if (finished > skipped) {
      double left = elapsed / static_cast<double>(finished - skipped) * static_cast<double>(total - finished);
      eta = left >= 60 ? fmt::format("{:.0f}m{:02.0f}s", std::floor(left / 60), std::fmod(left, 60.0))
                       : fmt::format("{:.0f}s", left);
    }
    fmt::print(stderr, "[{}/{}] {}  (elapsed {:.0f}s, ETA {})\n", done, total, what, elapsed, eta);
  }
};

// "; Embree 1 12.3 MRays/s, 16-coherent 20.1 MRays/s" (NoSort) or "; Embree 1 1.05 [1.01, 1.09], ..."
// (each path's speedup on the cell's order): nothing without Embree's arms.
std::string embree_progress(const CellRecord& c) {
  std::string s;
  for (const auto& e : c.embree) {
    const std::string figure =
        e.trace.n == 0 ? fmt::format("{:.2f} MRays/s", e.nosort.median_ms > 0 ? c.rays / (e.nosort.median_ms * 1e3) : 0.0)
                       : interval_text(e.speedup, 2);
    s += fmt::format("{} {} {}", s.empty() ? "; Embree" : ",", e.path, figure);
  }
  return s;
}

std::string progress_text(const CellRecord& c) {
  if (!c.ok()) return fmt::format("{}: {}: {}", c.id(), c.status == "timeout" ? "TIMEOUT" : "FAILED", c.error);
  const std::string rounds = fmt::format("{} rounds, stopped by {}", c.rounds, c.stopped_by);
  if (c.encoder == kBaselineEncoder)
    return fmt::format("{}: NoSort {:.2f} MRays/s, A/A {}{}  ({})", c.id(), c.trace_mrays, interval_text(c.aa, 2),
                       embree_progress(c), rounds);
  const std::string speed =
      c.same_order_as_nosort
          ? fmt::format("same order as NoSort, no speedup (measured {})",
                        interval_text(ratio_interval(c.samples.at("nosort"), c.samples.at("trace")), 2))
          : fmt::format("speedup {}", interval_text(c.speedup, 2));
  return fmt::format("{}: {:.2f} MRays/s, {}, net {}, encode {:.2f} + sort {:.2f}{} ms{}, ANC {:.2f}{}  ({})", c.id(),
                     c.trace_mrays, speed, interval_text(c.net_speedup, 2), c.encode.median_ms, c.sort.median_ms,
                     c.access == "permute" ? fmt::format(" + permute {:.2f}", c.permute.median_ms) : "",
                     c.cut_ms >= 0 ? fmt::format(" (host cut {:.1f} ms)", c.cut_ms) : "", c.anc, embree_progress(c),
                     rounds);
}

CellRecord cell_of(const PlannedCell& p) {
  CellRecord c;
  c.scene = p.scene, c.batch = p.batch, c.encoder = p.encoder, c.bits = p.bits, c.top_bits = p.top_bits;
  c.variant = p.variant, c.access = p.access, c.baseline = p.baseline, c.layout = p.layout;
  return c;
}

// Consecutive runs of cells that agree on key(cell): the plan is ordered scene, batch, variant, class,
// then NoSort and each encoder × key length × top-k with its access modes side by side.
template <class Key>
std::vector<std::vector<PlannedCell>> runs_of(const std::vector<PlannedCell>& cells, Key key) {
  std::vector<std::vector<PlannedCell>> out;
  for (const auto& c : cells) {
    if (out.empty() || key(out.back().front()) != key(c)) out.emplace_back();
    out.back().push_back(c);
  }
  return out;
}

// The cells of a batch the scene's frame does not have: said on stderr, counted as absent (a shard
// records them for raysort merge) and out of the progress total.
void skip_absent_batch(const std::vector<PlannedCell>& batch_cells, std::vector<std::string>& absent, Progress& progress) {
  fmt::print(stderr, "note: scene {} has no batch {} (its effects do not imply it, or it is empty); skipped\n",
             batch_cells.front().scene, batch_cells.front().batch);
  for (const auto& c : batch_cells) absent.push_back(c.id);
  progress.total -= batch_cells.size();
}

// Scene problems a run can find before any work starts: a scene file or OBJ given by path is
// parsed (it is small next to a run); an embedded scene's OBJ files must exist under the root; a
// ray file (--rays) is read and checked against its scene (bench/batch_file.h).
void check_scenes_before_work(const MatrixSpec& spec, const RunOptions& opts) {
  SceneOptions scene_opts;
  scene_opts.scene_root = opts.scene_root;
  scene_opts.frame = {1, 1, 1};
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
  if (!spec.ray_file.empty())  // a bad file, or one of another scene, is refused before the result set is touched
    (void)read_ray_file_for_scene(spec.ray_file, spec.scenes.at(0), resolve_scene_root(scene_opts));
}

// Each scene's facts (size, effects), loaded once: the plan and the memory check both read them.
std::map<std::string, SceneFacts> scene_facts(const MatrixSpec& spec, const std::string& scene_root) {
  std::map<std::string, SceneFacts> facts;
  for (const auto& scene : spec.scenes)
    if (!facts.count(scene)) facts.emplace(scene, load_scene_facts(scene, spec, scene_root));
  return facts;
}

std::vector<PlannedCell> plan_from(const MatrixSpec& spec, const std::map<std::string, SceneFacts>& facts,
                                   unsigned count) {
  return plan_shards(matrix_cells(spec, [&](const std::string& scene) { return facts.at(scene); }), count);
}

// Each scene's frame at the matrix's resolution and spp must fit the device and the host.
void check_matrix_memory(const MatrixSpec& spec, const std::map<std::string, SceneFacts>& facts,
                         const DeviceInfo& device) {
  for (const auto& [scene, f] : facts) check_scene_memory(spec, scene, f, device);
}

// Every cell the set holds must be one the matrix plans: a cell file of another matrix (copied in,
// or left from a plan whose scene files changed) would be reported as if this run measured it.
void check_cells_planned(const ResultSet& results, const std::vector<PlannedCell>& full_plan) {
  std::set<std::string> planned;
  for (const auto& c : full_plan) planned.insert(c.id);
  for (const auto& c : results.cells())
    if (!planned.count(c.id()))
      throw Error(fmt::format("{}/cells/{}: cell {} is not a cell this matrix plans (its scene has no such batch, or "
                              "the file came from another run); delete the file",
                              results.dir(), cell_file_name(c.id()), c.id()));
}

// After the loop: a shard's absent cells (for raysort merge), the views and plots, and the counts
// of planned cells that are not ok or not there.
void finish_run(ResultSet& results, const std::vector<PlannedCell>& plan, const std::vector<std::string>& absent,
                const RunOptions& opts, RunSummary& summary) {
  if (!absent.empty() && opts.shard.active()) {
    // raysort merge counts these as accounted for (no shard can produce them).
    std::set<std::string> all(absent.begin(), absent.end());
    for (const auto& id : results.meta().value("absent_cells", std::vector<std::string>{})) all.insert(id);
    results.set_meta("absent_cells", std::vector<std::string>(all.begin(), all.end()));
  }
  results.write_views();
  results.write_plots();
  const std::set<std::string> absent_ids(absent.begin(), absent.end());
  for (const auto& c : plan) {
    const CellRecord* r = results.find(c.id);
    summary.cells_not_ok += r && !r->ok();
    summary.cells_missing += !r && !absent_ids.count(c.id);
  }
}

// --layout packet is the device's packet width: planned, recorded (and resumed) as the width it
// runs; "packet,packet8" on an AVX device is one class.
std::vector<TraceLayout> resolved_layouts(const std::vector<TraceLayout>& layouts, const DeviceInfo& device) {
  std::vector<TraceLayout> resolved;
  for (TraceLayout l : layouts)
    if (const TraceLayout r = resolve_trace_layout(l, device); std::find(resolved.begin(), resolved.end(), r) == resolved.end())
      resolved.push_back(r);
  return resolved;
}

// The result set of this run (a resume's, or a new one) with its meta.json, checked to hold only
// cells the matrix plans; says on stderr what runs where.
ResultSet open_results(const MatrixSpec& spec, const RunOptions& opts, const DeviceInfo& device,
                       const RadixSortTuning& sort, std::size_t planned, const std::vector<PlannedCell>& full_plan,
                       const std::string& out_dir) {
  nlohmann::json meta = run_meta(spec, opts, device, sort);
  if (opts.shard.active()) meta["shard"] = shard_meta(spec, opts.shard, full_plan);
  // What files the scenes were made from (scene/provenance.h): compare says when two sets differ.
  meta["scene_files"] = scene_file_checksums(spec.scenes, resolve_scene_root(SceneOptions{opts.scene_root, {}}));
  ResultSet results = ResultSet::open_for_run(out_dir, meta);
  check_cells_planned(results, full_plan);
  fmt::print(stderr, "raysort run: {}{} on {}; results in {}\n", spec.preset.empty() ? "custom matrix" : spec.preset,
             opts.shard.active() ? fmt::format(", shard {} ({} of {} cells)", opts.shard.str(), planned, full_plan.size())
                                 : "",
             device.name, out_dir);
  return results;
}

}  // namespace

std::string default_result_dir(const MatrixSpec& spec, const std::string& device_slug, const ShardSpec& shard) {
  // The same cells give the same folder however the lists were written (canonical_matrix).
  const std::string matrix = canonical_matrix(spec.to_json()).dump();
  std::string hash = fnv1a_hex(matrix.data(), matrix.size()).substr(0, 8);
  std::string dir = fmt::format("results/{}/{}-{}", device_slug, spec.preset.empty() ? "run" : spec.preset, hash);
  return shard.active() ? fmt::format("{}-shard{}of{}", dir, shard.index, shard.count) : dir;
}

std::vector<PlannedCell> plan_matrix_shards(const MatrixSpec& spec, const std::string& scene_root, unsigned count) {
  return plan_from(spec, scene_facts(spec, scene_root), count);
}

RunSummary run_matrix(const MatrixSpec& requested, const RunOptions& opts) {
  MatrixSpec spec = requested;
  validate_matrix(spec);
  check_scenes_before_work(spec, opts);

  Runtime rt(select_device(opts.device));
  build_own_programs(rt, spec.encoders);  // an encoder file that does not compile: refused before any work
  spec.layouts = resolved_layouts(spec.layouts, rt.info());

  // Plan: every cell of the matrix in visiting order; a shard keeps its own (bench/shard.h).
  const std::map<std::string, SceneFacts> facts = scene_facts(spec, opts.scene_root);
  std::vector<PlannedCell> plan = plan_from(spec, facts, opts.shard.active() ? opts.shard.count : 1);
  const std::vector<PlannedCell> full_plan = plan;
  if (opts.shard.active())
    std::erase_if(plan, [&](const PlannedCell& c) { return c.shard != opts.shard.index; });

  check_matrix_memory(spec, facts, rt.info());  // before the result set is written
  RunSummary summary;
  summary.out_dir = opts.out.empty() ? default_result_dir(spec, rt.info().slug(), opts.shard) : opts.out;
  // The sort, before the result set: its meta.json records the sort's shape, and a shape refused
  // here leaves no folder behind.
  RadixSortTuning sort_tuning = RadixSortTuning::for_device(rt.info());
  if (opts.sort_passes == "onesweep" && sort_tuning.work_group == 1)
    throw Error(fmt::format("--sort-passes onesweep: the sort on device '{}' has the CPU shape (one work-item per "
                            "tile); Onesweep runs in the GPU shape only; use auto or reduce-then-scan (docs/sort.md)",
                            rt.info().name));
  if (opts.sort_passes != "auto") sort_tuning.onesweep = opts.sort_passes == "onesweep";
  RadixSort sorter(rt, sort_tuning, RadixSortFit::ShrinkToKernels);
  ResultSet results = open_results(spec, opts, rt.info(), sorter.tuning(), plan.size(), full_plan, summary.out_dir);

  InterruptGuard interrupt_guard;
  const char* kill_env = std::getenv("RAYSORT_TEST_KILL_AFTER_CELLS");
  const std::size_t kill_after = kill_env ? std::strtoul(kill_env, nullptr, 10) : 0;
  Progress progress;
  progress.total = plan.size();
  sorter.warm_up();
  RayPermuter permuter(rt);
  permuter.warm_up();
  const bool both_variants = spec.variants.size() > 1;
  // The GPU cost model (run --gpu-model): one profile for every cell.
  const std::optional<GpuProfile> gpu =
      spec.gpu_model.empty() ? std::nullopt : std::optional<GpuProfile>(load_gpu_profile(spec.gpu_model));
  std::vector<std::string> absent;  // planned cells whose batch turned out empty

  // A cell's file is written as it is recorded; the views once per batch, whose cells arrive
  // together (ResultSet::write_views), and again at the end (finish_run).
  auto record = [&](const CellRecord& c) {
    results.write_cell(c);
    ++summary.cells_run;
    summary.cells_failed += !c.ok();
    ++progress.done;
    if (progress.arriving > 0) --progress.arriving;
    // Test hook (tests/bench_test.cpp): die by SIGKILL right after the N-th new cell, a
    // deterministic kill point for the resume test.
    if (kill_after > 0 && summary.cells_run >= kill_after) std::raise(SIGKILL);
    progress.line(progress_text(c));
  };

  for (auto& scene_cells : runs_of(plan, [](const PlannedCell& c) { return c.scene; })) {  // → scene
    if (g_interrupted) break;
    // A batch's cells share their rounds (bench/cell_measure.h), so a batch is measured whole or not
    // at all: one with a cell missing (or failed, unless --no-retry) runs again, every cell of it.
    std::set<std::string> complete;
    for (const auto& batch_cells : runs_of(scene_cells, round_group)) {
      const bool whole = std::all_of(batch_cells.begin(), batch_cells.end(), [&](const PlannedCell& c) {
        const CellRecord* had = results.find(c.id);
        return had && (had->ok() || opts.no_retry);  // failed and timed-out cells run again
      });
      if (whole) complete.insert(round_group(batch_cells.front()));
      for (const auto& c : batch_cells) {
        summary.cells_skipped += whole, progress.done += whole, progress.skipped += whole;
        const CellRecord* had = whole ? nullptr : results.find(c.id);
        summary.cells_retried += had && !had->ok();
        summary.cells_remeasured += had && had->ok();
      }
    }
    std::erase_if(scene_cells, [&](const PlannedCell& c) { return complete.count(round_group(c)) > 0; });
    if (scene_cells.empty()) continue;
    SceneBench scene(rt, prepare_scene(scene_cells.front().scene, SceneOptions{opts.scene_root, spec.frame}), spec,
                     [&](const std::string& line) { progress.line(line); });
    for (const auto& batch_cells : runs_of(scene_cells, round_group)) {
      if (g_interrupted) break;
      const PlannedCell& first = batch_cells.front();
      const ReferencedBatch* rb = scene.batch(first.batch, first.baseline);
      if (!rb) {  // every ray of an earlier bounce missed, or a requested batch the effects do not imply
        skip_absent_batch(batch_cells, absent, progress);
        continue;
      }
      BatchBench bench({rt, *scene.encoder, sorter, permuter, *scene.tracers.at({first.variant, first.layout}),
                        gpu ? &*gpu : nullptr, &scene.prepared.tris, scene.embree_scene(), scene.embree_paths,
                        spec.sort_warp_group},
                       scene.bvh, rb->batch, scene.reference(*rb, first.variant, first.layout));
      std::vector<std::vector<CellRecord>> groups;  // → cell: NoSort, then each encoder × key length × top-k
      for (const auto& group : runs_of(batch_cells, sort_group)) {
        groups.emplace_back();
        for (const auto& p : group) groups.back().push_back(cell_of(p));
      }
      ProtocolSettings settings = spec.protocol(round_group(first));
      settings.interrupted = &g_interrupted;  // Ctrl-C stops the rounds between two arms
      // A batch's cells are recorded when its rounds end: until then, a line every 30 s.
      auto last_line = std::chrono::steady_clock::now();
      settings.on_round = [&](unsigned rounds, std::size_t measuring, std::size_t total) {
        if (std::chrono::steady_clock::now() - last_line < std::chrono::seconds(30)) return;
        last_line = std::chrono::steady_clock::now();
        progress.line(fmt::format("{}: round {}, {} of {} cell groups still measuring", round_group(first), rounds,
                                  measuring, total));
      };
      // The inputs of an encoder that learns (hcc-traffic's cut, hcc-region's regions, mlhcc-cost's
      // table) are per batch: SceneBench readies them, and their cells record cut_ms, the host time
      // of that input plus the cut's build and upload (outside the timed rounds).
      auto prepare = [&](Encoder e, unsigned bits) { return scene.prepare_encoder(e, bits, first.batch); };
      try {
        std::vector<CellRecord> measured = bench.measure_batch(groups, settings, prepare);
        progress.arriving = measured.size();
        for (CellRecord& c : measured) {
          if (c.encoder == kBaselineEncoder)
            c.leaks_per_million = scene.leaks_per_million(*rb, first.variant, first.layout, both_variants);
          record(c);
        }
      } catch (const Interrupted&) {
        break;  // the batch in flight is not recorded: a resume measures it
      }
      results.write_views();
    }
  }

  finish_run(results, plan, absent, opts, summary);
  summary.interrupted = g_interrupted;
  summary.signal = g_signal;
  return summary;
}

}  // namespace raysort
