// The host twin of the packet kernels: cl/traverse_packet.h compiled for each packet width (and
// cl/traverse_coherent.h for 8 and 16), each in a namespace of its own (the headers have no include guard
// for that reason; packet_lanes.h).
#include "trace/packet_twin.h"

#include "intersect.h"
#include "lanes.h"
#include "traverse_wide.h"
#include "traverse_wide8.h"
#include "util/error.h"
#include "util/parallel.h"

namespace raysort {

#include "trace/packet_widths.inc"

namespace {

// Calls trace(first) for every packet of `width` consecutive positions among n, on host threads.
template <typename TracePacket>
void for_each_packet(int width, rs_u32 n, const TracePacket& trace) {
  const std::size_t packets = (static_cast<std::size_t>(n) + width - 1) / width;
  auto work = [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) trace(static_cast<rs_u32>(p * width));
  };
  for_each_block(packets, n < 4096, work, 64);
}

}  // namespace

void trace_packets_on_host(int width, int single_at, const WideBvh& wide, const std::vector<RsRay>& rays,
                           const std::uint32_t* order, int robust, int any_hit, std::vector<RsHit>& hits,
                           std::uint32_t* visits) {
  const PacketTraversal trace = packet_traversal(width);
  if (!trace) throw Error("internal: no packet traversal of width " + std::to_string(width) + " (4, 8 or 16)");
  const auto n = static_cast<rs_u32>(rays.size());
  hits.resize(n);
  for_each_packet(width, n, [&](rs_u32 first) {
    trace(wide.nodes.data(), wide.packets.data(), rays.data(), order, first, n, robust, any_hit, single_at, hits.data(),
          visits);
  });
}

void trace_coherent_on_host(int width, const Wide8Bvh& wide8, const std::vector<RsRay>& rays, const std::uint32_t* order,
                            int robust, int any_hit, std::vector<RsHit>& hits, std::uint32_t* visits) {
  const CoherentTraversal trace = coherent_traversal(width);
  if (!trace) throw Error("internal: no coherent packet traversal of width " + std::to_string(width) + " (8 or 16)");
  const auto n = static_cast<rs_u32>(rays.size());
  hits.resize(n);
  for_each_packet(width, n, [&](rs_u32 first) {
    trace(wide8.nodes.data(), wide8.packets.data(), rays.data(), order, first, n, robust, any_hit, hits.data(), visits);
  });
}

}  // namespace raysort
