// packet_study: what an order changes in a ray packet's own traversal (issue 40).
//
//   build/packet_study SCENE [WIDTHxHEIGHT] [BATCH]      (default 960x540 bounce1)
//
// The packet class's cost on a CPU is the union of its rays' paths: every node any active lane
// enters is one vector step for the packet (cl/traverse_packet.h). The SIMT model counts a warp's
// lockstep steps over each lane's own walk instead, so the two can disagree on what an order buys.
// For one batch, in NoSort's order and in the stable order of a few encoders' 32-bit keys (as the
// radix sort leaves them), and for packets of 16, 8 and 4 consecutive rays, this prints the packet
// class's steps per packet (inner nodes and leaves), its leaf steps per packet, and the active
// lanes per step: the robust variant's host twin of the packet kernels, counted through
// RS_PACKET_STEP_HOOK, so the figures are deterministic and need no OpenCL device. A step count
// that falls with an order is work the packet no longer does; a measured speedup beyond it is
// time per step (memory locality), not lanes.
//
// Self-check: the lanes the hook counts at each step sum to the per-ray visit counts the kernels
// themselves write (their `visits` output); where they differ the study fails (exit 2).
#include <fmt/format.h>

#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

#include "bvh/prepared_scene.h"
#include "encode/encode.h"
#include "intersect.h"
#include "lanes.h"
#include "render/batches.h"
#include "scene/load.h"
#include "study.h"
#include "trace/tracer.h"
#include "traverse_wide.h"
#include "traverse_wide8.h"

namespace {

// The packet's steps, counted by the traversal itself (one thread: the study runs packets in order).
struct PacketSteps {
  std::uint64_t steps = 0, leaf_steps = 0, lane_steps = 0;
};
PacketSteps g_counted;

}  // namespace

#define RS_PACKET_STEP_HOOK(lanes, ref)                                     \
  (++g_counted.steps, g_counted.leaf_steps += ((ref) & RS_WIDE_LEAF) != 0u, \
   g_counted.lane_steps += static_cast<std::uint64_t>(rs_popcount(lanes)))

#include "trace/packet_widths.inc"

using namespace raysort;

namespace {

int run_study(int argc, char** argv) {
  const study::Args args = study::parse_args("packet_study", argc, argv, "960x540");
  const PreparedScene p = prepare_scene(args.scene, args.options);
  RayGenOptions gen;  // the matrix's seed (1)
  const std::vector<ReferencedBatch> frame = generate_batches(p.scene, p.tris, p.bvh, gen);
  const ReferencedBatch& batch = study::find_batch(frame, args);
  const std::vector<RsRay>& rays = batch.batch.rays;
  const int any_hit = batch.batch.any_hit() ? 1 : 0;
  WideBvh scratch;
  const WideBvh& wide = wide_of(p.bvh, scratch);
  const EncodeScene es(p.bvh, p.scene.bounds(), {});
  const auto n = static_cast<rs_u32>(rays.size());

  std::vector<std::pair<std::string, std::vector<std::uint32_t>>> orders;
  std::vector<std::uint32_t> generation(n);
  std::iota(generation.begin(), generation.end(), 0u);
  orders.emplace_back("nosort", generation);
  for (Encoder e : {Encoder::HCC, Encoder::Origin, Encoder::Reis, Encoder::PPC, Encoder::Aila})
    orders.emplace_back(std::string(encoder_name(e)), study::stable_order(encode_on_host(e, 32, es, rays)));

  fmt::print("{} {} at {}x{}: {} rays, {} (robust variant; per packet: steps, leaf steps; active lanes per step)\n",
             args.scene, args.batch, args.options.frame.width, args.options.frame.height, n,
             any_hit ? "any hit" : "closest hit");
  std::vector<RsHit> hits(n);
  std::vector<rs_u32> visits(n);
  for (const auto& [name, order] : orders) {
    for (int width : {16, 8, 4}) {
      const PacketTraversal traverse = packet_traversal(width);
      g_counted = {};
      for (rs_u32 first = 0; first < n; first += static_cast<rs_u32>(width))
        traverse(wide.nodes.data(), wide.packets.data(), rays.data(), order.data(), first, n, 1, any_hit, 0,
                 hits.data(), visits.data());
      const std::uint64_t visited = std::accumulate(visits.begin(), visits.end(), std::uint64_t{0});
      if (visited != g_counted.lane_steps)
        throw Error(fmt::format("{} packets of {}: the hook counted {} lane steps, the kernels' visits sum to {}", name,
                                width, g_counted.lane_steps, visited));
      const double packets = (static_cast<double>(n) + width - 1) / width;
      fmt::print("  {:8} packet{:<2}  steps {:7.3f}  leaf steps {:6.3f}  lanes per step {:5.2f} ({:3.0f} %)\n", name,
                 width, static_cast<double>(g_counted.steps) / packets,
                 static_cast<double>(g_counted.leaf_steps) / packets,
                 static_cast<double>(g_counted.lane_steps) / static_cast<double>(g_counted.steps),
                 100.0 * static_cast<double>(g_counted.lane_steps) / static_cast<double>(g_counted.steps) / width);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return study::run("packet_study", run_study, argc, argv); }
