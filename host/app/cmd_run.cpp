// raysort run: a scenario matrix into a result set (host/bench/runner.h).
#include <fmt/format.h>

#include <limits>

#include "app/commands.h"
#include "app/options.h"
#include "bench/batch_file.h"
#include "bench/gpu_model.h"
#include "bench/result_set.h"
#include "bench/runner.h"
#include "bench/shard.h"
#ifdef RAYSORT_HAVE_EMBREE
#include "embree/embree_reference.h"
#endif
#include "util/error.h"

namespace raysort {

namespace {
// The largest N of --shard i/N (ShardSpec::parse reads up to six digits).
constexpr std::uint64_t kMaxShards = 999999;
// --warp-sort's group: a warp of 32 lanes (the paper's GPUs, and the SIMT model's default width).
constexpr unsigned kWarpSortGroup = 32;

struct RunArgs {
  std::string preset;
  std::vector<std::string> scenes, batches, encoders;
  std::vector<unsigned> bits, top_bits;
  bool warp_sort = false;
  CommonOptions common;  // --device, --scene-root, --resolution, --spp, --seed
  std::string variant, access, baseline, layout, gpu_model, embree_paths, embree_isa;
  unsigned reps = 0, warmup = 0;
  double max_noise_pct = 0, max_time_s = 0;
  EncoderParams params;  // the knobs given (encode/encoder_params.h)
  double timeout_s = 0;
  std::string shard;
  unsigned shard_plan = 0;
  std::string rays;  // --rays FILE (bench/batch_file.h)
  RunOptions opts;
};

// The matrix the command line asks for: a preset (or the custom default) with the given axes and
// settings over it, every text parsed here into typed values.
MatrixSpec matrix_from(const RunArgs& a, const CLI::App& cmd) {
  MatrixSpec spec;
  if (!a.preset.empty()) {
    spec = matrix_preset(a.preset);
  } else {
    spec.encoders = all_encoders();
    spec.batches = {"primary", "shadow0", "bounce1"};
    spec.frame = {640, 360, 1};
  }
  auto is_all = [](const std::vector<std::string>& v) { return v.size() == 1 && v[0] == "all"; };
  if (!a.scenes.empty()) spec.scenes = a.scenes;
  if (!a.batches.empty()) spec.batches = is_all(a.batches) ? std::vector<std::string>{} : a.batches;
  if (!a.rays.empty()) {  // the file's batch alone (validate_matrix refuses --batches beside it)
    spec.ray_file = a.rays;
    if (a.batches.empty()) spec.batches = {ray_file_batch_name(a.rays)};
  }
  if (!a.encoders.empty()) spec.encoders = parse_encoders(a.encoders);
  if (!a.bits.empty()) {
    spec.bits = a.bits;
    spec.key_length_bits.clear();
    spec.key_length_scenes.clear();
  }
  if (!a.top_bits.empty()) spec.top_bits = a.top_bits;
  if (a.warp_sort) spec.sort_warp_group = kWarpSortGroup;
  const FrameSize frame = a.common.frame();
  if (frame.width) spec.frame.width = frame.width, spec.frame.height = frame.height;
  if (cmd.count("--spp")) spec.frame.spp = a.common.spp;  // given values are taken as given (0 is refused)
  if (frame.shadow_rays) spec.frame.shadow_rays = frame.shadow_rays;
  if (frame.bounces) spec.frame.bounces = frame.bounces;
  if (cmd.count("--seed")) spec.seed = a.common.seed;
  if (!a.variant.empty()) spec.variants = parse_trace_variants(a.variant);
  if (!a.access.empty()) spec.accesses = parse_ray_accesses(a.access);
  if (!a.baseline.empty()) spec.baselines = parse_baseline_orders(a.baseline);
  if (!a.layout.empty()) spec.layouts = parse_trace_layouts(a.layout);
  if (!a.gpu_model.empty()) {
    (void)load_gpu_profile(a.gpu_model);  // an unknown name or a bad file fails here, before any cell
    spec.gpu_model = a.gpu_model;
  }
  if (cmd.count("--embree-paths")) {
#ifdef RAYSORT_HAVE_EMBREE
    // The keys as the table spells them, each once ("all": every path in table order).
    for (EmbreePath path : parse_embree_paths(a.embree_paths)) spec.embree_paths.emplace_back(embree_path_info(path).key);
#else
    throw Error("--embree-paths: this build has no Embree: install libembree-dev and reconfigure");
#endif
  }
  if (cmd.count("--embree-isa")) spec.embree_isa = a.embree_isa;  // checked with the matrix (validate_matrix)
  if (cmd.count("--reps")) spec.reps = a.reps;
  if (cmd.count("--warmup")) spec.warmup = a.warmup;
  if (cmd.count("--max-noise")) spec.max_noise = a.max_noise_pct / 100.0;
  if (cmd.count("--max-time")) spec.max_time_s = a.max_time_s;
  // The encoder knobs were checked where they were parsed (add_encoder_param_options): a given
  // value is taken, none is replaced by the default.
  apply_given_params(cmd, a.params, spec.params);
  spec.cell_timeout_s = a.timeout_s;
  return spec;
}
// What a run did, on stdout (and on stderr why it did not finish), and its exit code: the state of
// the whole set.
void report_run(const RunSummary& s) {
  std::string again;
  if (s.cells_retried) again += fmt::format("{} of them retries of failed or timed-out cells", s.cells_retried);
  if (s.cells_remeasured)
    again += fmt::format("{}{} ok cells measured again with the rest of their batch", again.empty() ? "" : ", ",
                         s.cells_remeasured);
  fmt::print("{} cells run{}, {} already done (skipped), {} failed; results in {}\n", s.cells_run,
             again.empty() ? "" : " (" + again + ")", s.cells_skipped, s.cells_failed, s.out_dir);
  const NoiseSummary noise = summarize_noise(ResultSet::load(s.out_dir).cells());
  if (noise.aa_intervals > 0)
    fmt::print("noise: A/A calibration {} of {} intervals contain 1.00 ({:.1f} %); speedup interval half-width "
               "median {:.1f} %, 90th percentile {:.1f} %; cells stopped by time {}, by noise {}\n",
               noise.aa_containing_one, noise.aa_intervals, 100.0 * noise.aa_coverage(),
               100.0 * noise.median_half_width, 100.0 * noise.p90_half_width, noise.stopped_by_time,
               noise.stopped_by_noise);
  fmt::print("tables: {}/tables.md\n", s.out_dir);
  if (s.interrupted) {
    fmt::print(stderr, "interrupted: finished cells are saved; rerun the same command to resume\n");
    set_command_exit_code(s.signal > 0 ? 128 + s.signal : kExitInterrupted);
  } else if (s.cells_not_ok > 0 || s.cells_missing > 0) {
    // The exit code is the state of the whole set, not of this run's cells: a resumed run that
    // kept failed cells (--no-retry) or failed again does not report success.
    fmt::print(stderr, "raysort run: {} has {} cell(s) not ok (failed or timeout) and {} missing; rerun the command "
               "to retry them\n", s.out_dir, s.cells_not_ok, s.cells_missing);
    set_command_exit_code(kExitBadInput);
  }
}
}  // namespace

void register_run_command(CLI::App& app) {
  auto a = std::make_shared<RunArgs>();
  auto* cmd = app.add_subcommand("run", "run a scenario matrix (encoders x key bits x scenes x batches) into a result set");
  cmd->add_option("--preset", a->preset,
                  "quick (what `make bench` runs), paper (the paper's setup: 8 spp, 2 shadow rays per bounce), "
                  "paper-1spp, paper-viewport, paper-hcc-dir or paper-bounces (docs/paper.md)");
  add_scene_list_option(*cmd, a->scenes, "scenes, comma-separated: each a " + scene_option_help());
  cmd->add_option("--batches", a->batches, "batches: primary, shadow<k>, bounce<k>, or all")->delimiter(',');
  cmd->add_option("--encoders", a->encoders,
                  "encoders, or all; file:PATH is an encoder from an OpenCL C file, named file:<its stem> in the "
                  "result set (docs/encoders.md, \"An encoder from a file\")")
      ->delimiter(',');
  whole_number(cmd->add_option("--bits", a->bits, "key bits, e.g. 16,32,64")->delimiter(','), 1, 64);
  whole_number(cmd->add_option("--top-bits", a->top_bits, "also sort by only the highest k bits (top-k cells)")->delimiter(','),
               1, 64);
  cmd->add_flag("--warp-sort", a->warp_sort,
                "sort only down to groups of 32 rays (a warp), leaving each group in generation order: the paper's "
                "'terminate bucket sorting early' (docs/sort.md; CPU devices; off by default)");
  cmd->add_option("--sort-passes", a->opts.sort_passes,
                  "the GPU-shape sort's passes: auto (the device's: Onesweep on NVIDIA, else reduce-then-scan), "
                  "reduce-then-scan, or onesweep (GPU shape only); the orders are the same, meta.json says which ran "
                  "(docs/sort.md)")
      ->check(CLI::IsMember(kSortPassesValues))
      ->capture_default_str();
  add_common_options(*cmd, a->common);
  add_protocol_number_options(
      *cmd, a->reps, a->warmup, a->max_noise_pct, a->max_time_s,
      "the fewest timed rounds per cell (default 7: from 7 on the 95 % interval leaves out the extremes); "
      "more follow until --max-noise or --max-time is reached (docs/measurement.md)",
      "stop sampling a cell once its speedup's 95 % interval is within +-this many percent (default 2)",
      "stop sampling a cell after this many seconds of rounds (past --reps) even if --max-noise is not "
      "reached; the cell records that it stopped on time (default 5; quick preset 0.3)");
  cmd->get_option("--warmup")
      ->description("untimed rounds of every arm before timing (default 0: each batch's setup runs every kernel "
                    "once, untimed; docs/measurement.md)");
  cmd->add_option("--access", a->access,
                  "ray access modes, comma-separated: gather (trace through the sorted order), permute (move the "
                  "rays into sorted order first, timed as a stage), or all");
  cmd->add_option("--variant", a->variant,
                  "trace variants, comma-separated: robust (watertight, default), fast (Moller-Trumbore), or both");
  cmd->add_option("--baseline", a->baseline,
                  "NoSort's order, the baseline every speedup and SIMT-model ratio is against, comma-separated: pixel "
                  "(generation order, default) or shuffled (a fixed-seed permutation, as a path tracer compacting with "
                  "atomics produces), or all; shuffled cells end their id in /shuffled");
  cmd->add_option("--layout", a->layout,
                  "trace classes, comma-separated (docs/trace.md, \"Trace classes\"): " + trace_layouts_help() +
                      "; or all; the first is the tables' main one; a cell of another class than wide ends its id in "
                      "/<class>");
  cmd->add_option("--embree-paths", a->embree_paths,
                  "also trace every cell's rays with these Embree paths, each in NoSort order and in the cell's sorted "
                  "order, as arms of the cell's rounds (docs/measurement.md, \"Embree on sorted orders\"; needs a build "
                  "with libembree-dev): 1 (rtcIntersect1), 1M and 1M-coherent (rtcIntersect1M streams), 4, 8, 16 and "
                  "4-coherent, 8-coherent, 16-coherent (packets of consecutive rays), comma-separated, or all; off by "
                  "default");
  cmd->add_option("--embree-isa", a->embree_isa,
                  "with --embree-paths: the instruction set Embree's arms run: native (the widest this CPU has, the "
                  "default), sse2, sse4.2, avx, avx2 or avx512 (docs/trace.md, \"Embree anchor\")");
  cmd->add_option("--gpu-model", a->gpu_model,
                  "also replay every cell's traversal through a GPU's caches and predict its speedup (docs/gpu-model.md): "
                  "a profile in gpu/profiles/ (rtx3060, h100, h200) or a .toml path; off by default (it adds the replay's "
                  "time to each cell's SIMT model)");
  add_encoder_param_options(*cmd, a->params);
  finite_number(cmd->add_option("--timeout", a->timeout_s,
                                "per-cell wall-clock limit in seconds (0: none); a cell over it is recorded as \"timeout\" "
                                "(checked between the arms of a round: a kernel in flight runs to completion)"),
                0, kMaxSeconds);
  cmd->add_flag("--no-retry", a->opts.no_retry,
                "when resuming, keep cells recorded as failed or timeout as they are (by default they run again); "
                "the exit code still says whether every cell is ok");
  cmd->add_option("--out", a->opts.out, "result folder (default results/<device>/<preset>-<hash>)");
  auto* shard_opt = cmd->add_option("--shard", a->shard,
                                    "run only shard i of N (i/N, numbered from 1: 1/4 ... 4/4), a deterministic share "
                                    "of the cells balanced by estimated cost; merge the shards with raysort merge");
  // As many shards as --shard i/N can name.
  whole_number(cmd->add_option("--shard-plan", a->shard_plan,
                               "print which cells each of N shards would run, with their estimated costs, and exit")
                   ->excludes(shard_opt),
               1, kMaxShards);
  add_rays_option(*cmd, a->rays);
  cmd->callback([a, cmd] {
    MatrixSpec spec = matrix_from(*a, *cmd);
    a->opts.device = a->common.device;
    a->opts.scene_root = a->common.scene_root;
    a->opts.command = command_line_text(*cmd);  // for meta.json
    if (!a->shard.empty()) a->opts.shard = ShardSpec::parse(a->shard);
    if (cmd->count("--shard-plan")) {
      validate_matrix(spec);
      fmt::print("{}", format_plan(plan_matrix_shards(spec, a->opts.scene_root, a->shard_plan), a->shard_plan));
      return;
    }
    report_run(run_matrix(spec, a->opts));
  });
}

}  // namespace raysort
