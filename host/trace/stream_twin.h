#pragma once
// The host twin of the ray-stream trace kernels (cl/traverse_stream.h): the same source, on host
// threads.
#include <cstdint>
#include <vector>

#include "bvh/bvh.h"
#include "shared.h"

namespace raysort {

// Traces rays[order[i]] (order: as many entries as rays) into hits[i] in streams of up to
// RS_STREAM_RAYS rays of one octant, dealt from RS_STREAM_CHUNK consecutive positions, over the 8-wide
// tree, exactly as the stream kernels do; visits (null: not counted) receives per position the steps
// at which the ray was in its stream's mask.
void trace_streams_on_host(const Wide8Bvh& wide8, const std::vector<RsRay>& rays, const std::uint32_t* order,
                           int robust, int any_hit, std::vector<RsHit>& hits, std::uint32_t* visits);

}  // namespace raysort
