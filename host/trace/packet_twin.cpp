// The host twin of the packet kernels: cl/traverse_packet.h (and cl/traverse_coherent.h) compiled for each packet width, each in
// a namespace of its own (the header has no include guard for that reason; packet_lanes.h).
#include "trace/packet_twin.h"

#include "intersect.h"
#include "lanes.h"
#include "traverse_wide.h"
#include "traverse_wide8.h"
#include "util/error.h"
#include "util/parallel.h"

namespace raysort {

#include "trace/packet_widths.inc"

void trace_packets_on_host(int width, int single_at, const WideBvh& wide, const std::vector<RsRay>& rays,
                           const std::uint32_t* order, int robust, int any_hit, std::vector<RsHit>& hits,
                           std::uint32_t* visits) {
  const PacketTraversal trace = packet_traversal(width);
  if (!trace) throw Error("internal: no packet traversal of width " + std::to_string(width) + " (4, 8 or 16)");
  const auto n = static_cast<rs_u32>(rays.size());
  hits.resize(n);
  const std::size_t packets = (static_cast<std::size_t>(n) + width - 1) / width;
  auto work = [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p)
      trace(wide.nodes.data(), wide.packets.data(), rays.data(), order, static_cast<rs_u32>(p * width), n, robust,
            any_hit, single_at, hits.data(), visits);
  };
  for_each_block(packets, n < 4096, work, 64);
}

void trace_coherent_on_host(int width, const Wide8Bvh& wide8, const std::vector<RsRay>& rays, const std::uint32_t* order,
                            int robust, int any_hit, std::vector<RsHit>& hits, std::uint32_t* visits) {
  const CoherentTraversal trace = coherent_traversal(width);
  if (!trace) throw Error("internal: no coherent packet traversal of width " + std::to_string(width) + " (16)");
  const auto n = static_cast<rs_u32>(rays.size());
  hits.resize(n);
  const std::size_t packets = (static_cast<std::size_t>(n) + width - 1) / width;
  auto work = [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p)
      trace(wide8.nodes.data(), wide8.packets.data(), rays.data(), order, static_cast<rs_u32>(p * width), n, robust,
            any_hit, hits.data(), visits);
  };
  for_each_block(packets, n < 4096, work, 64);
}

}  // namespace raysort
