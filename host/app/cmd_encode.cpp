// raysort encodebench: time every encoder × key length on one ray batch of a scene (device kernel
// time from profiling events), check the keys against the host twin, and compare with a trace of
// the same batch (the paper: PPC's encode costs about a trace). The scene, its batches, the memory
// check, the encoders and what the learning ones are given are the runner's (bench/scene_bench.h),
// for a matrix of one scene and one batch that is checked as `run` checks its own; the
// measurement of one encoder is bench/encode_cost.h.
#include <fmt/format.h>

#include <algorithm>
#include <optional>

#include "app/commands.h"
#include "app/options.h"
#include "bench/batch_file.h"
#include "bench/encode_cost.h"
#include "bench/matrix.h"
#include "bench/scene_bench.h"
#include "encode/encoder_file.h"
#include "util/error.h"

namespace raysort {

namespace {

struct EncodeBenchArgs {
  std::string scene;
  std::string batch = "bounce1";
  std::vector<std::string> encoders;  // empty: all
  std::vector<unsigned> bits{16, 32, 64};
  ProtocolOptions protocol;
  bool verify = true;
  EncoderParams params;  // the knobs given (encode/encoder_params.h)
  // Each encoder's encode is also paired with this encoder's, in the same rounds (empty: none), for
  // a cost ratio with its interval (issue 21's "encode within 1.5× HCC").
  std::string versus;
  CommonOptions common;
  std::string rays;  // --rays FILE: the batch from this ray file (bench/batch_file.h) instead of --batch
};

// encodebench's matrix: one scene and batch, the encoders (the reference among them: its own
// input, e.g. hcc-traffic's traffic, is made as the others' are) at the key lengths, traced by the
// fast variant on the wide tree. Its encoders, key lengths and knobs are refused as `run` refuses
// them (validate_encoders), before any work.
struct EncodeBenchPlan {
  MatrixSpec spec;
  std::optional<Encoder> versus;
  // The encoders from files among spec.encoders (encode/encoder_file.h): no host twin, so host== says
  // so, in a wider column.
  std::vector<const EncoderFile*> files;
  int check_width() const { return files.empty() ? 8 : 12; }
  int name_width() const {  // the list's names fit 11; a file's stem may be longer
    std::size_t width = 11;
    for (const EncoderFile* f : files) width = std::max(width, f->name.size());
    return static_cast<int>(width);
  }
};

EncodeBenchPlan plan_of(const EncodeBenchArgs& args, const CLI::App& cmd) {
  EncodeBenchPlan plan;
  MatrixSpec& spec = plan.spec;
  spec.scenes = {args.scene};
  spec.batches = {args.rays.empty() ? args.batch : ray_file_batch_name(args.rays)};
  spec.ray_file = args.rays;
  if (!args.rays.empty() && cmd.count("--batch"))
    throw Error(fmt::format("--rays {} gives the batch: leave out --batch", args.rays));
  spec.encoders = args.encoders.empty() ? all_encoders() : parse_encoders(args.encoders);
  if (!args.versus.empty()) plan.versus = parse_encoders({args.versus}).at(0);
  if (plan.versus && std::find(spec.encoders.begin(), spec.encoders.end(), *plan.versus) == spec.encoders.end())
    spec.encoders.insert(spec.encoders.begin(), *plan.versus);
  spec.bits = args.bits;
  apply_given_params(cmd, args.params, spec.params);
  spec.seed = args.common.seed;
  spec.variants = {TraceVariant::Fast};
  spec.layouts = {TraceLayout::Wide};
  validate_encoders(spec.encoders, spec.bits, spec.params);
  for (Encoder e : spec.encoders)
    if (const EncoderFile* f = encoder_file(e)) plan.files.push_back(f);
  return plan;
}

const ReferencedBatch& batch_of(SceneBench& scene, const std::string& name) {
  if (const ReferencedBatch* rb = scene.batch(name, baseline_order_name(BaselineOrder::Pixel))) return *rb;
  std::string names;
  for (const auto& b : scene.batches) names += (names.empty() ? "" : ", ") + b.batch.name;
  throw Error(fmt::format("scene '{}' has no batch '{}'; it has: {}", scene.prepared.scene.name, name, names));
}

void print_header(const Runtime& rt, const SceneBench& scene, const RayBatch& batch, const EncodeBenchPlan& plan) {
  const std::optional<Encoder> versus = plan.versus;
  fmt::print("device   {} ({})\n", rt.info().name, rt.info().platform_name);
  fmt::print("scene    {}: {} triangles; batch {}: {} rays\n", scene.prepared.scene.name, scene.prepared.tris.size(),
             batch.name, batch.size());
  fmt::print("timing   each encode paired with a trace of the same batch in the same rounds (docs/measurement.md): "
             "ms = median [95 % interval], % trace = paired estimate of encode / trace per round\n");
  if (versus)
    fmt::print("         and with {}'s encode at the same key length: x {} = paired estimate of encode / {}'s per round\n",
               encoder_name(*versus), encoder_name(*versus), encoder_name(*versus));
  for (const EncoderFile* f : plan.files)
    fmt::print("file     {} = {} (sha256 {}): no host twin; host== says \"no host twin\" when a second launch gave the "
               "same keys, NO when not\n",
               f->name, f->path, f->sha256);
  fmt::print("\n");
  const std::string versus_header = versus ? fmt::format("x {}", encoder_name(*versus)) : "";
  fmt::print("{:<{}} {:>4} {:>28} {:>9} {:>24}{:>{}} {:>10} {:>{}} {:>7}\n", "encoder", plan.name_width(), "bits",
             "encode ms", "MRays/s", "% trace", versus_header, versus ? 24 : 0, "distinct", "host==", plan.check_width(),
             "rounds");
}

// One row of the table: e at `bits` bits measured, its keys checked against the host twin (unless
// --no-verify). Returns false when they differ.
bool measure_row(const EncodeBenchArgs& args, const EncodeBenchPlan& plan, SceneBench& scene, EncodeCostBench& bench,
                 const RayBatch& batch, Encoder e, unsigned bits) {
  scene.prepare_encoder(e, bits, batch.name);
  if (plan.versus && *plan.versus != e) scene.prepare_encoder(*plan.versus, bits, batch.name);
  const EncodeCost c = bench.measure(e, bits, plan.versus, args.protocol.settings(protocol_seed(fmt::format(
                                                               "{}/{}/{}/{}", scene.prepared.scene.name, batch.name,
                                                               encoder_name(e), bits))));
  std::string check = "-";
  bool same = true;
  if (args.verify && has_host_twin(e)) {
    same = encode_on_host(e, bits, scene.encoder->scene(), batch.rays) == c.keys;
    check = same ? "yes" : "NO";
  } else if (args.verify) {  // an encoder from a file: checked against a second launch
    same = scene.encoder->run(e, bits, batch.rays).keys == c.keys;
    check = same ? "no host twin" : "NO";
  }
  std::vector<std::uint64_t> sorted = c.keys;
  std::sort(sorted.begin(), sorted.end());
  const auto distinct = static_cast<std::size_t>(std::unique(sorted.begin(), sorted.end()) - sorted.begin());
  const Estimate& share = c.share;
  const std::string share_text =
      share.has_interval() ? fmt::format("{:.1f}% [{:.1f}, {:.1f}]", 100 * share.value, 100 * share.lo, 100 * share.hi)
                           : fmt::format("{:.1f}%", 100 * share.value);
  const std::string versus_text = c.versus ? interval_text(*c.versus) : plan.versus ? "-" : "";
  fmt::print("{:<{}} {:>4} {:>28} {:>9.1f} {:>24}{:>{}} {:>10} {:>{}} {:>6}{}\n", encoder_name(e), plan.name_width(), bits,
             interval_text(c.encode.estimate()), c.encode.median_ms > 0 ? batch.size() / (c.encode.median_ms * 1e3) : 0.0,
             share_text, versus_text, plan.versus ? 24 : 0, distinct, check, plan.check_width(), c.rounds,
             c.stop == StopReason::Noise ? " " : "*");
  std::fflush(stdout);
  return same;
}

int run_encodebench(const EncodeBenchArgs& args, const CLI::App& cmd) {
  EncodeBenchPlan plan = plan_of(args, cmd);
  if (!args.rays.empty())  // a bad file, or one of another scene, is refused before any work
    (void)read_ray_file_for_scene(args.rays, args.scene, resolve_scene_root(args.common.scene_options()));
  Runtime rt(select_device(args.common.device));
  build_own_programs(rt, plan.spec.encoders);  // an encoder file that does not compile: refused before any work
  PreparedScene prepared = prepare_scene(args.scene, args.common.scene_options());
  plan.spec.frame = prepared.frame();
  check_scene_memory(plan.spec, prepared.scene.name, scene_facts_of(prepared.scene, plan.spec.frame), rt.info());
  SceneBench scene(rt, std::move(prepared), plan.spec);
  const ReferencedBatch& rb = batch_of(scene, plan.spec.batches.at(0));
  print_header(rt, scene, rb.batch, plan);
  EncodeCostBench bench(rt, *scene.encoder, *scene.tracers.begin()->second, rb.batch);
  int failures = 0;
  for (Encoder e : plan.spec.encoders)
    for (unsigned bits : plan.spec.bits) failures += !measure_row(args, plan, scene, bench, rb.batch, e, bits);
  fmt::print("rounds * = stopped by --max-time before the % trace{} interval was within --max-noise\n",
             plan.versus ? fmt::format(" or x {}", encoder_name(*plan.versus)) : std::string());
  if (failures) {
    fmt::print(stderr, "raysort: {} encoder runs differ from the host twin{}\n", failures,
               plan.files.empty() ? "" : " (or, with no host twin, from a second launch)");
    return 1;
  }
  return 0;
}

}  // namespace

void register_encode_command(CLI::App& app) {
  auto args = std::make_shared<EncodeBenchArgs>();
  auto* cmd = app.add_subcommand("encodebench", "time every encoder and key length on one ray batch of a scene");
  cmd->add_option("--scene,--scenes", args->scene, scene_option_help() + " (one)")->required();
  cmd->add_option("--batch", args->batch, "batch name: primary, shadow<k>, bounce<k>")->capture_default_str();
  cmd->add_option("--encoders", args->encoders,
                  "comma-separated encoders (default: all); file:PATH is an encoder from an OpenCL C file "
                  "(docs/encoders.md, \"An encoder from a file\")")
      ->delimiter(',');
  // The same ranges as run's options of the same names.
  whole_number(cmd->add_option("--bits", args->bits, "comma-separated key lengths")->delimiter(',')->capture_default_str(),
               1, 64);
  add_encoder_param_options(*cmd, args->params);
  cmd->add_option("--versus", args->versus,
                  "also time this encoder's encode in the same rounds as each other encoder's, and print the paired "
                  "cost ratio with its 95 % interval (e.g. --versus hcc)");
  add_protocol_options(*cmd, args->protocol);
  cmd->add_flag("!--no-verify", args->verify, "skip the comparison with the host twin");
  add_common_options(*cmd, args->common);
  add_rays_option(*cmd, args->rays);
  cmd->callback([args, cmd] { set_command_exit_code(run_encodebench(*args, *cmd)); });
}

}  // namespace raysort
