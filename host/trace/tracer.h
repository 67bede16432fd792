#pragma once
// Tracing a ray batch on the device (cl/trace.cl) and on the host (the reference twin, which
// runs the same traversal source: cl/traverse_wide.h, traverse_wide8.h, traverse_binary.h, traverse_packet.h).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "bvh/bvh.h"
#include "runtime/runtime.h"
#include "trace/trace_class.h"
#include "shared.h"

namespace raysort {

// Which traversal arithmetic runs (docs/trace.md). Fast: Möller–Trumbore and a plain slab test.
// Robust: watertight triangle test (Woop et al. 2013) and a conservative slab test (Ize 2013).
enum class TraceVariant { Fast, Robust };

// "fast" / "robust"; parse throws an Error naming the accepted values.
TraceVariant parse_trace_variant(std::string_view name);
const char* trace_variant_name(TraceVariant v);
// A command line's variant list: "robust,fast" (in that order), "both" or "all" for robust,fast.
// Throws Error naming an unknown variant.
std::vector<TraceVariant> parse_trace_variants(const std::string& list);

// Packet (Hybrid) resolved for this device (trace/trace_class.h).
inline TraceLayout resolve_trace_layout(TraceLayout l, const DeviceInfo& device) {
  return resolve_trace_layout(l, device.preferred_float_width);
}

// The scene's BVH on one device, with the trace kernels built. Upload once per scene; trace
// many batches and orders.
class Tracer {
 public:
  // The default stays Fast until every caller chooses (the benchmark runner, the encoders).
  // layout Packet is resolved for rt's device (layout() returns the resolved class).
  Tracer(Runtime& rt, const Bvh& bvh, TraceVariant variant = TraceVariant::Fast,
         TraceLayout layout = TraceLayout::Wide);

  TraceVariant variant() const { return variant_; }
  TraceLayout layout() const { return layout_; }

  // Traces rays[order[i]] for i < count into hits[i] (trace order). any_hit: shadow rays.
  // Enqueues and returns the kernel's event without waiting.
  cl::Event enqueue(const cl::Buffer& rays, const cl::Buffer& order, std::uint32_t count, bool any_hit,
                    const cl::Buffer& hits);
  // Same, also writing per-ray BVH node visit counts (instrumented kernel).
  cl::Event enqueue_counted(const cl::Buffer& rays, const cl::Buffer& order, std::uint32_t count,
                            const cl::Buffer& hits, const cl::Buffer& visits);

  std::size_t local_size() const { return local_; }

  struct Run {
    std::vector<RsHit> hits;  // hits[i] of rays[order[i]]
  };
  // Uploads rays (and order; null = identity), traces them once and returns the hits. Untimed:
  // timed traces go through the measurement protocol (bench/protocol.h) with enqueue().
  Run run(const std::vector<RsRay>& rays, const std::vector<std::uint32_t>* order, bool any_hit);

 private:
  cl::Event launch(cl::Kernel& k, std::uint32_t count, const std::string& doing);

  Runtime& rt_;
  cl::Buffer nodes_, triangles_;
  cl::Kernel closest_, any_, counted_;
  std::size_t local_ = 64;
  std::uint32_t width_ = 1;  // rays per work-item (packet_width of the class)
  TraceVariant variant_ = TraceVariant::Fast;
  TraceLayout layout_ = TraceLayout::Wide;
};

// Host reference: the same traversal (cl/traverse_wide.h, cl/traverse_wide8.h, cl/traverse_binary.h,
// cl/traverse_packet.h) on host threads. order may be null (identity). hits[i] belongs to rays[order[i]]. node_visits: per
// ray, the nodes visited (wide nodes and leaves for the wide layouts and, for the packets, those at
// which the ray's lane was active; boxes fetched for the binary one). layout must be resolved (not
// Packet): the packets are formed from consecutive rays of the order, as on the device.
std::vector<RsHit> trace_reference(const Bvh& bvh, const std::vector<RsRay>& rays, const std::uint32_t* order,
                                   bool any_hit, std::vector<std::uint32_t>* node_visits = nullptr,
                                   TraceVariant variant = TraceVariant::Fast, TraceLayout layout = TraceLayout::Wide);

// Node traffic of a batch (hcc-traffic's priority, issue 21): for every node of the binary BVH, the
// number of rays whose host traversal (cl/traverse_binary.h, fast variant with the encoders' unfused box
// test, RS_VARIANT_FAST_UNFUSED, so the learned keys keep their bits; closest or any hit) stepped through it (the SIMT model's trail: its box was hit when its parent was tested, and the
// walk reached it). Indexed like bvh.nodes; the root's count is the rays that hit the scene box, and
// no node has more than its parent. Independent of the rays' order; host threads, deterministic.
std::vector<std::uint64_t> node_traffic(const Bvh& bvh, const std::vector<RsRay>& rays, bool any_hit);

// Number of positions whose hit records differ in any bit.
std::size_t count_hit_mismatches(const std::vector<RsHit>& a, const std::vector<RsHit>& b);

}  // namespace raysort
