#pragma once
// The host twin of the ray-packet trace kernels (cl/traverse_packet.h): the same source, compiled
// once per packet width, on host threads.
#include <cstdint>
#include <vector>

#include "bvh/bvh.h"
#include "shared.h"

namespace raysort {

// Traces rays[order[i]] (order: as many entries as rays) into hits[i] in packets of `width` (4, 8 or 16)
// consecutive positions, exactly as the packet kernels do; visits (null: not counted) receives per
// position the steps at which the ray's lane was active. single_at > 0: the hybrid classes (lanes
// walk a subtree alone once at most single_at reach it). Throws Error for another width.
void trace_packets_on_host(int width, int single_at, const WideBvh& wide, const std::vector<RsRay>& rays,
                           const std::uint32_t* order, int robust, int any_hit, std::vector<RsHit>& hits,
                           std::uint32_t* visits);

// The same for the coherent packets over the 8-wide tree (cl/traverse_coherent.h, the coherent8 and coherent16 classes):
// packets of `width` (8 or 16) consecutive positions, exactly as the coherent kernels trace them.
void trace_coherent_on_host(int width, const Wide8Bvh& wide8, const std::vector<RsRay>& rays, const std::uint32_t* order,
                            int robust, int any_hit, std::vector<RsHit>& hits, std::uint32_t* visits);

}  // namespace raysort
