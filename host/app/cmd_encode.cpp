// raysort encodebench: time every encoder × key length on one ray batch of a scene (device kernel
// time from profiling events), check the keys against the host twin, and compare with a trace of
// the same batch (the paper: PPC's encode costs about a trace).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "app/commands.h"
#include "app/options.h"
#include "bench/protocol.h"
#include "bench/runner.h"
#include "bvh/prepared_scene.h"
#include "encode/encode.h"
#include "render/batches.h"
#include "render/frame_memory.h"
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
  ProtocolOptions protocol;
  bool verify = true;
  int direction_bits = -1;  // HCC_DIR's direction bits; -1: the default (EncoderParams)
  int region_bits = -1;     // hcc-region's region bits; -1: the default
  double traffic_blend = -1;  // hcc-traffic's and hcc-region's blend; -1: the default
  int cost_bits = -1;         // mlhcc-cost's cost bits; -1: the default
  // Each encoder's encode is also paired with this encoder's, in the same rounds (empty: none), for
  // a cost ratio with its interval (issue 21's "encode within 1.5× HCC").
  std::string versus;
  CommonOptions common;
};

int run_encodebench(const EncodeBenchArgs& args) {
  Runtime rt(select_device(args.common.device));
  const PreparedScene prepared = prepare_scene(args.scene, args.common.scene_options());
  const Scene& scene = prepared.scene;
  const Scene::Flat& tris = prepared.tris;
  const Bvh& bvh = prepared.bvh;
  check_frame_memory(estimate_frame_memory(scene), &rt.info(),
                     fmt::format("scene {} at {}x{}, {} spp", scene.name, scene.camera.width, scene.camera.height,
                                 scene.effects.samples_per_pixel));
  auto batches = generate_batches(scene, tris, bvh, args.common.raygen_options());
  const ReferencedBatch* rb = nullptr;
  std::string names;
  for (const auto& b : batches) {
    names += (names.empty() ? "" : ", ") + b.batch.name;
    if (b.batch.name == args.batch) rb = &b;
  }
  if (!rb) throw Error(fmt::format("scene '{}' has no batch '{}'; it has: {}", scene.name, args.batch, names));
  std::vector<Encoder> encoders = args.encoders.empty() ? all_encoders() : parse_encoders(args.encoders);
  const std::optional<Encoder> versus =
      args.versus.empty() ? std::nullopt : std::optional<Encoder>(parse_encoders({args.versus}).at(0));
  // The reference's own preparation (hcc-traffic's traffic, hcc-region's statistics) happens below
  // only for the encoders listed, so list it too; it is timed like the others.
  if (versus && std::find(encoders.begin(), encoders.end(), *versus) == encoders.end())
    encoders.insert(encoders.begin(), *versus);

  const RayBatch& batch = rb->batch;
  const auto n = static_cast<std::uint32_t>(batch.size());
  fmt::print("device   {} ({})\n", rt.info().name, rt.info().platform_name);
  fmt::print("scene    {}: {} triangles; batch {}: {} rays\n", scene.name, tris.size(), batch.name, batch.size());
  fmt::print("timing   each encode paired with a trace of the same batch in the same rounds (docs/measurement.md): "
             "ms = median [95 % interval], % trace = paired estimate of encode / trace per round\n");
  if (versus)
    fmt::print("         and with {}'s encode at the same key length: x {} = paired estimate of encode / {}'s per round\n",
               encoder_name(*versus), encoder_name(*versus), encoder_name(*versus));
  fmt::print("\n");
  EncoderParams params;
  if (args.direction_bits >= 0) params.direction_bits = static_cast<unsigned>(args.direction_bits);
  if (args.region_bits >= 0) params.region_bits = static_cast<unsigned>(args.region_bits);
  if (args.traffic_blend >= 0) params.traffic_blend = args.traffic_blend;
  if (args.cost_bits > 0) params.cost_bits = static_cast<unsigned>(args.cost_bits);
  DeviceEncoder enc(rt, bvh, bvh.bounds(), params);
  // hcc-traffic: its cut from the traffic of the batch traced before this one, as raysort run makes it.
  if (std::find(encoders.begin(), encoders.end(), Encoder::HCC_TRAFFIC) != encoders.end())
    enc.set_node_traffic(traffic_before(bvh, batches, args.batch));
  // mlhcc-cost and hcc-region: their input from the same batch of a previous frame, as raysort run
  // makes it.
  auto runs = [&](Encoder e) { return std::find(encoders.begin(), encoders.end(), e) != encoders.end(); };
  if (runs(Encoder::MLHCC_COST) || runs(Encoder::HCC_REGION)) {
    auto previous = previous_frame_statistics(prepared, args.common.raygen_options(), enc.scene(),
                                              runs(Encoder::MLHCC_COST), runs(Encoder::HCC_REGION), {args.batch});
    if (auto it = previous.find(args.batch); it != previous.end()) {
      if (runs(Encoder::MLHCC_COST)) enc.set_cost_estimates(std::move(it->second.cost_means));
      if (runs(Encoder::HCC_REGION)) enc.set_region_statistics(std::move(it->second.regions));
    }
  }
  Tracer tracer(rt, bvh);
  enc.warm_up();
  std::vector<std::uint32_t> identity(n);
  std::iota(identity.begin(), identity.end(), 0u);
  cl::Buffer rays = rt.upload("rays of " + batch.name, batch.rays);
  cl::Buffer order = rt.upload("identity order", identity);
  cl::Buffer hits = rt.buffer("hits", std::max<std::size_t>(1, n) * sizeof(RsHit));
  cl::Buffer keys = rt.buffer("keys", std::max<std::size_t>(1, n) * sizeof(std::uint64_t));
  cl::Buffer values = rt.buffer("values", std::max<std::size_t>(1, n) * sizeof(std::uint32_t));
  // The reference's keys go to buffers of their own, so the keys checked below are the encoder's.
  cl::Buffer versus_keys = rt.buffer("reference keys", std::max<std::size_t>(1, n) * sizeof(std::uint64_t));
  cl::Buffer versus_values = rt.buffer("reference values", std::max<std::size_t>(1, n) * sizeof(std::uint32_t));
  const std::string versus_header = versus ? fmt::format("x {}", encoder_name(*versus)) : "";
  fmt::print("{:<11} {:>4} {:>28} {:>9} {:>24}{:>{}} {:>10} {:>8} {:>7}\n", "encoder", "bits", "encode ms", "MRays/s",
             "% trace", versus_header, versus ? 24 : 0, "distinct", "host==", "rounds");
  int failures = 0;
  for (Encoder e : encoders)
    for (unsigned bits : args.bits) {
      if (!key_bits_problem(e, bits, enc.scene().params()).empty()) continue;
      enc.prepare(e, bits);
      Measurement m;
      m.arms = {{{"encode"}, [&] {
                   const DeviceEncoder::Events ev = enc.enqueue(e, bits, rays, order, n, keys, values);
                   ev.wait();
                   return std::vector<double>{ev.ms()};
                 }},
                {{"trace"}, [&] {
                   cl::Event ev = tracer.enqueue(rays, order, n, batch.any_hit(), hits);
                   cl_call("waiting for the trace", [&] { ev.wait(); });
                   return std::vector<double>{event_ms(ev)};
                 }}};
      m.targets = {[](const Series& s) { return ratio_interval(s.at("encode"), s.at("trace")); }};
      const bool paired = versus && *versus != e && key_bits_problem(*versus, bits, enc.scene().params()).empty();
      if (paired) {
        enc.prepare(*versus, bits);
        m.arms.push_back({{"versus"}, [&] {
                            const DeviceEncoder::Events ev =
                                enc.enqueue(*versus, bits, rays, order, n, versus_keys, versus_values);
                            ev.wait();
                            return std::vector<double>{ev.ms()};
                          }});
        m.targets.push_back([](const Series& s) { return ratio_interval(s.at("encode"), s.at("versus")); });
      }
      const Outcome o = measure(m, args.protocol.settings(protocol_seed(fmt::format(
                                       "{}/{}/{}/{}", scene.name, batch.name, encoder_name(e), bits))));
      const Timing encode = Timing::of(o.series.at("encode"));
      const Estimate share = ratio_interval(o.series.at("encode"), o.series.at("trace"));
      // The keys of the last round (every round computes the same keys).
      std::vector<std::uint64_t> device_keys;
      if (bits > 32) {
        rt.download("keys", keys, device_keys, n);
      } else {
        std::vector<std::uint32_t> k32;
        rt.download("keys", keys, k32, n);
        device_keys.assign(k32.begin(), k32.end());
      }
      std::string check = "-";
      if (args.verify) {
        auto host = encode_on_host(e, bits, enc.scene(), batch.rays);
        const bool same = host == device_keys;
        check = same ? "yes" : "NO";
        failures += !same;
      }
      std::vector<std::uint64_t> sorted = device_keys;
      std::sort(sorted.begin(), sorted.end());
      const auto distinct = static_cast<std::size_t>(std::unique(sorted.begin(), sorted.end()) - sorted.begin());
      const std::string share_text =
          share.has_interval() ? fmt::format("{:.1f}% [{:.1f}, {:.1f}]", 100 * share.value, 100 * share.lo, 100 * share.hi)
                               : fmt::format("{:.1f}%", 100 * share.value);
      const std::string versus_text =
          paired ? interval_text(ratio_interval(o.series.at("encode"), o.series.at("versus"))) : versus ? "-" : "";
      fmt::print("{:<11} {:>4} {:>28} {:>9.1f} {:>24}{:>{}} {:>10} {:>8} {:>6}{}\n", encoder_name(e), bits,
                 interval_text(encode.estimate()), encode.median_ms > 0 ? batch.size() / (encode.median_ms * 1e3) : 0.0, share_text,
                 versus_text, versus ? 24 : 0, distinct, check, o.rounds, o.stop == StopReason::Noise ? " " : "*");
      std::fflush(stdout);
    }
  fmt::print("rounds * = stopped by --max-time before the % trace{} interval was within --max-noise\n",
             versus ? fmt::format(" or x {}", encoder_name(*versus)) : std::string());
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
  cmd->add_option("--scene,--scenes", args->scene, "scene name, .toml or .obj path (one)")->required();
  cmd->add_option("--batch", args->batch, "batch name: primary, shadow<k>, bounce<k>")->capture_default_str();
  cmd->add_option("--encoders", args->encoders, "comma-separated encoders (default: all)")->delimiter(',');
  // The same ranges as run's options of the same names.
  whole_number(cmd->add_option("--bits", args->bits, "comma-separated key lengths")->delimiter(',')->capture_default_str(),
               1, 64);
  whole_number(cmd->add_option("--direction-bits", args->direction_bits,
                               "HCC_DIR direction bits (more than 1 runs its two-pass kernels, as `run --direction-bits` does)"),
               0, 64);
  whole_number(cmd->add_option("--region-bits", args->region_bits, "hcc-region region bits (as `run --region-bits`)"), 0,
               kMaxRegionBits);
  finite_number(cmd->add_option("--traffic-blend", args->traffic_blend,
                                "hcc-traffic and hcc-region blend (as `run --traffic-blend`)"),
                0, 1);
  whole_number(cmd->add_option("--cost-bits", args->cost_bits, "mlhcc-cost cost bits (as `run --cost-bits`)"), 1, 31);
  cmd->add_option("--versus", args->versus,
                  "also time this encoder's encode in the same rounds as each other encoder's, and print the paired "
                  "cost ratio with its 95 % interval (e.g. --versus hcc)");
  add_protocol_options(*cmd, args->protocol);
  cmd->add_flag("!--no-verify", args->verify, "skip the comparison with the host twin");
  add_common_options(*cmd, args->common);
  cmd->callback([args] { set_command_exit_code(run_encodebench(*args)); });
}

}  // namespace raysort
