// The host twin of the stream kernels: cl/traverse_stream.h compiled as C++ (docs/trace.md).
#include "trace/stream_twin.h"

#include "traverse_stream.h"
#include "util/parallel.h"

namespace raysort {

void trace_streams_on_host(const Wide8Bvh& wide8, const std::vector<RsRay>& rays, const std::uint32_t* order,
                           int robust, int any_hit, std::vector<RsHit>& hits, std::uint32_t* visits) {
  const auto n = static_cast<rs_u32>(rays.size());
  hits.resize(n);
  const std::size_t chunks = (static_cast<std::size_t>(n) + RS_STREAM_CHUNK - 1) / RS_STREAM_CHUNK;
  auto work = [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c)
      rs_traverse_stream(wide8.nodes.data(), wide8.packets.data(), rays.data(), order,
                         static_cast<rs_u32>(c * RS_STREAM_CHUNK), n, robust, any_hit, hits.data(), visits);
  };
  for_each_block(chunks, n < 4096, work, 8);
}

}  // namespace raysort
