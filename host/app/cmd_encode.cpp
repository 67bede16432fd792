// raysort encodebench: time every encoder × key length on one ray batch of a scene (device kernel
// time from profiling events), check the keys against the host twin, and compare with a trace of
// the same batch (the paper: PPC's encode costs about a trace).
#include <fmt/format.h>

#include <algorithm>

#include "app/commands.h"
#include "app/options.h"
#include "bvh/bvh.h"
#include "encode/encode.h"
#include "render/batches.h"
#include "scene/load.h"
#include "trace/tracer.h"
#include "util/error.h"

namespace raysort {

namespace {

struct EncodeBenchArgs {
  std::string scene;
  std::string batch = "bounce1";
  std::vector<std::string> encoders;  // empty: all
  std::vector<unsigned> bits{16, 32, 64};
  unsigned reps = 5;
  unsigned warmup = 1;
  bool verify = true;
  CommonOptions common;
};

int run_encodebench(const EncodeBenchArgs& args) {
  Runtime rt(select_device(args.common.device));
  Scene scene = load_scene(args.scene, args.common.scene_options());
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  RayGenOptions gen = args.common.raygen_options();
  auto batches = generate_batches(scene, tris, bvh, gen);
  const ReferencedBatch* rb = nullptr;
  std::string names;
  for (const auto& b : batches) {
    names += (names.empty() ? "" : ", ") + b.batch.name;
    if (b.batch.name == args.batch) rb = &b;
  }
  if (!rb) throw Error(fmt::format("scene '{}' has no batch '{}'; it has: {}", scene.name, args.batch, names));
  std::vector<Encoder> encoders;
  for (const auto& name : args.encoders) {
    auto e = parse_encoder(name);
    if (!e) throw Error(fmt::format("--encoders: unknown encoder '{}'", name));
    encoders.push_back(*e);
  }
  if (encoders.empty()) encoders = all_encoders();

  const RayBatch& batch = rb->batch;
  fmt::print("device   {} ({})\n", rt.info().name, rt.info().platform_name);
  fmt::print("scene    {}: {} triangles; batch {}: {} rays\n", scene.name, tris.size(), batch.name, batch.size());
  DeviceEncoder enc(rt, bvh, bvh.bounds());
  Tracer tracer(rt, bvh);
  enc.warm_up();
  Tracer::Run trace = tracer.run(batch.rays, nullptr, batch.any_hit(), args.warmup, args.reps);
  fmt::print("trace    {:.2f} ms ({:.2f} MRays/s)\n\n", trace.median_ms, batch.size() / (trace.median_ms * 1e3));
  fmt::print("{:<9} {:>4} {:>10} {:>10} {:>10} {:>10} {:>8}\n", "encoder", "bits", "ms", "MRays/s", "% trace", "distinct",
             "host==");
  int failures = 0;
  for (Encoder e : encoders)
    for (unsigned bits : args.bits) {
      if (!key_bits_problem(e, bits, enc.scene().params()).empty()) continue;
      auto run = enc.run(e, bits, batch.rays, nullptr, args.warmup, args.reps);
      std::string check = "-";
      if (args.verify) {
        auto host = encode_on_host(e, bits, enc.scene(), batch.rays);
        const bool same = host == run.keys;
        check = same ? "yes" : "NO";
        failures += !same;
      }
      std::vector<std::uint64_t> sorted = run.keys;
      std::sort(sorted.begin(), sorted.end());
      const auto distinct = static_cast<std::size_t>(std::unique(sorted.begin(), sorted.end()) - sorted.begin());
      fmt::print("{:<9} {:>4} {:>10.3f} {:>10.1f} {:>9.1f}% {:>10} {:>8}\n", encoder_name(e), bits, run.median_ms,
                 run.median_ms > 0 ? batch.size() / (run.median_ms * 1e3) : 0.0, 100.0 * run.median_ms / trace.median_ms,
                 distinct, check);
      std::fflush(stdout);
    }
  if (failures) {
    fmt::print(stderr, "raysort: {} encoder runs differ from the host twin\n", failures);
    return 1;
  }
  return 0;
}

}  // namespace

void register_encode_command(CLI::App& app) {
  auto args = std::make_shared<EncodeBenchArgs>();
  auto* cmd = app.add_subcommand("encodebench", "time every encoder and key length on one ray batch of a scene");
  cmd->add_option("--scene", args->scene, "scene name, .toml or .obj path")->required();
  cmd->add_option("--batch", args->batch, "batch name: primary, shadow<k>, bounce<k>")->capture_default_str();
  cmd->add_option("--encoders", args->encoders, "comma-separated encoders (default: all)")->delimiter(',');
  cmd->add_option("--bits", args->bits, "comma-separated key lengths")->delimiter(',')->capture_default_str();
  cmd->add_option("--reps", args->reps, "timed repetitions (median reported)")->check(CLI::Range(1u, 1000u));
  cmd->add_option("--warmup", args->warmup, "untimed runs before timing");
  cmd->add_flag("!--no-verify", args->verify, "skip the comparison with the host twin");
  add_common_options(*cmd, args->common);
  cmd->callback([args] { set_command_exit_code(run_encodebench(*args)); });
}

}  // namespace raysort
