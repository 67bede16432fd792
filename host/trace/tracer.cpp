#include "trace/tracer.h"

#include <algorithm>
#include <cstring>
#include <numeric>

#include "trace/packet_twin.h"
#include "trace/stream_twin.h"
#include "traverse_binary.h"
#include "traverse_binary_ww.h"
#include "traverse_cwbvh.h"
#include "traverse_wide.h"
#include "traverse_wide8.h"
#include "util/error.h"
#include "util/parallel.h"
#include "util/text.h"

namespace raysort {

TraceVariant parse_trace_variant(std::string_view name) {
  if (name == "fast") return TraceVariant::Fast;
  if (name == "robust") return TraceVariant::Robust;
  throw Error("unknown trace variant '" + std::string(name) + "' (expected robust or fast)");
}

const char* trace_variant_name(TraceVariant v) { return v == TraceVariant::Robust ? "robust" : "fast"; }

std::vector<TraceVariant> parse_trace_variants(const std::string& list) {
  static const ListAxis<TraceVariant> axis{
      "--variant", "trace variants", "trace variant", {{"robust", TraceVariant::Robust}, {"fast", TraceVariant::Fast}},
      {"both", "all"}};
  return parse_list_axis(axis, list);
}

Tracer::Tracer(Runtime& rt, const Bvh& bvh, TraceVariant variant, TraceLayout layout)
    : rt_(rt), variant_(variant), layout_(resolve_trace_layout(layout, rt.info())) {
  if (walks_wide_tree(layout_)) {
    WideBvh scratch;
    const WideBvh& wide = wide_of(bvh, scratch);
    nodes_ = rt.upload("4-wide bvh nodes", wide.nodes);
    triangles_ = rt.upload("triangle packets", wide.packets);
  } else if (tree_kind(layout_) == TreeKind::Wide8) {
    const Wide8Bvh& wide8 = split_tree(bvh).wide8;
    nodes_ = rt.upload("8-wide bvh nodes", wide8.nodes);
    triangles_ = rt.upload("8-triangle packets", wide8.packets);
  } else if (tree_kind(layout_) == TreeKind::Compressed8) {
    const CwBvh cw = collapse_to_cwbvh(bvh);
    nodes_ = rt.upload("compressed 8-wide bvh nodes", cw.nodes);
    triangles_ = rt.upload("compressed bvh triangles", cw.triangles);
  } else {
    nodes_ = rt.upload("bvh nodes", bvh.nodes);
    triangles_ = rt.upload("triangles", bvh.triangles);
  }
  width_ = static_cast<std::uint32_t>(packet_width(layout_));
  cl::Program program = rt.build({"cl/trace.cl"}, trace_class_define(layout_));
  cl_call("creating the trace kernels", [&] {
    // Kernel names: trace_{closest,any,closest_counted}[_binary|_wide8|_packet][_robust] (cl/trace.cl).
    const std::string suffix = std::string(trace_class_kernel_suffix(layout_)) + (variant == TraceVariant::Robust ? "_robust" : "");
    closest_ = cl::Kernel(program, ("trace_closest" + suffix).c_str());
    any_ = cl::Kernel(program, ("trace_any" + suffix).c_str());
    counted_ = cl::Kernel(program, ("trace_closest_counted" + suffix).c_str());
  });
  // PoCL: the work-group is a loop over work-items (docs/design.md, "Device facts"), and its threads take
  // work-groups in turn, and groups of many rays leave a thread idle (streams dealt from 256 rays per
  // work-item traced sibenik's primary rays at 1.75-1.78x wide8 in groups of 64, 1.95-1.97x in groups of 8);
  // GPUs want a few warps per group. 64 work-items of up to 32 rays suit both and stay within every
  // device's limit.
  local_ = std::min<std::size_t>({64, std::max<std::size_t>(1, 2048 / width_), rt.info().max_work_group_size});
}

cl::Event Tracer::launch(cl::Kernel& k, std::uint32_t count, const std::string& doing) {
  cl::Event ev;
  // One work-item per ray, or per packet of width_ consecutive rays.
  const std::size_t items = (static_cast<std::size_t>(count) + width_ - 1) / width_;
  cl_call(doing, [&] {
    if (count > 0)
      rt_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(Runtime::padded(items, local_)), cl::NDRange(local_),
                                       nullptr, &ev);
    else
      rt_.queue().enqueueMarkerWithWaitList(nullptr, &ev);
  });
  return ev;
}

// Arguments 0-5 of every trace kernel: nodes, triangles, rays, order, count, hits.
static void set_trace_args(cl::Kernel& k, const cl::Buffer& nodes, const cl::Buffer& triangles, const cl::Buffer& rays,
                           const cl::Buffer& order, std::uint32_t count, const cl::Buffer& hits) {
  k.setArg(0, nodes);
  k.setArg(1, triangles);
  k.setArg(2, rays);
  k.setArg(3, order);
  k.setArg(4, count);
  k.setArg(5, hits);
}

cl::Event Tracer::enqueue(const cl::Buffer& rays, const cl::Buffer& order, std::uint32_t count, bool any_hit,
                          const cl::Buffer& hits) {
  cl::Kernel& k = any_hit ? any_ : closest_;
  std::string doing = std::string("tracing ") + std::to_string(count) + (any_hit ? " shadow rays" : " rays");
  cl_call(doing, [&] { set_trace_args(k, nodes_, triangles_, rays, order, count, hits); });
  return launch(k, count, doing);
}

cl::Event Tracer::enqueue_counted(const cl::Buffer& rays, const cl::Buffer& order, std::uint32_t count,
                                  const cl::Buffer& hits, const cl::Buffer& visits) {
  std::string doing = "tracing " + std::to_string(count) + " rays (instrumented)";
  cl_call(doing, [&] {
    set_trace_args(counted_, nodes_, triangles_, rays, order, count, hits);
    counted_.setArg(6, visits);
  });
  return launch(counted_, count, doing);
}

Tracer::Run Tracer::run(const std::vector<RsRay>& rays, const std::vector<std::uint32_t>* order, bool any_hit) {
  const auto n = static_cast<std::uint32_t>(rays.size());
  std::vector<std::uint32_t> identity;
  if (!order) {
    identity.resize(n);
    std::iota(identity.begin(), identity.end(), 0u);
    order = &identity;
  }
  cl::Buffer ray_buf = rt_.upload("rays", rays);
  cl::Buffer order_buf = rt_.upload("ray order", *order);
  cl::Buffer hit_buf = rt_.buffer("hits", std::max<std::size_t>(1, n) * sizeof(RsHit));
  cl::Event ev = enqueue(ray_buf, order_buf, n, any_hit, hit_buf);
  cl_call("waiting for a trace of " + std::to_string(n) + " rays", [&] { ev.wait(); });
  Run r;
  rt_.download("hits", hit_buf, r.hits, n);
  return r;
}

std::vector<RsHit> trace_reference(const Bvh& bvh, const std::vector<RsRay>& rays, const std::uint32_t* order,
                                   bool any_hit, std::vector<std::uint32_t>* node_visits, TraceVariant variant,
                                   TraceLayout layout) {
  const std::size_t n = rays.size();
  std::vector<RsHit> hits(n);
  if (node_visits) node_visits->assign(n, 0);
  WideBvh scratch;
  const WideBvh& wide = walks_wide_tree(layout) ? wide_of(bvh, scratch) : scratch;
  const Wide8Bvh no_wide8;
  const Wide8Bvh& wide8 = tree_kind(layout) == TreeKind::Wide8 ? split_tree(bvh).wide8 : no_wide8;
  const CwBvh cw = tree_kind(layout) == TreeKind::Compressed8 ? collapse_to_cwbvh(bvh) : CwBvh{};
  const int robust = variant == TraceVariant::Robust ? 1 : 0;
  // The classes that trace several consecutive rays at once read them through an order.
  std::vector<std::uint32_t> identity;
  if (!order && packet_width(layout) > 1) {
    identity.resize(n);
    std::iota(identity.begin(), identity.end(), 0u);
    order = identity.data();
  }
  if (is_stream(layout)) {
    trace_streams_on_host(wide8, rays, order, robust, any_hit ? 1 : 0, hits, node_visits ? node_visits->data() : nullptr);
    return hits;
  }
  if (is_coherent(layout)) {
    trace_coherent_on_host(packet_width(layout), wide8, rays, order, robust, any_hit ? 1 : 0, hits,
                           node_visits ? node_visits->data() : nullptr);
    return hits;
  }
  if (const int width = packet_width(layout); width > 1) {
    trace_packets_on_host(width, packet_single_at(layout), wide, rays, order, robust, any_hit ? 1 : 0, hits,
                          node_visits ? node_visits->data() : nullptr);
    return hits;
  }
  if (packet_width(layout) == 0) throw Error("internal: trace_reference needs a resolved packet width");
  auto work = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      rs_u32 visits = 0;
      const RsRay& ray = rays[order ? order[i] : i];
      rs_u32* v = node_visits ? &visits : nullptr;
      if (layout == TraceLayout::Wide)
        hits[i] = rs_traverse_wide(wide.nodes.data(), wide.packets.data(), ray, robust, any_hit ? 1 : 0, v);
      else if (layout == TraceLayout::Wide8)
        hits[i] = rs_traverse_wide8(wide8.nodes.data(), wide8.packets.data(), ray, robust, any_hit ? 1 : 0, v);
      else if (layout == TraceLayout::Cwbvh)
        hits[i] = rs_traverse_cwbvh(cw.nodes.data(), cw.triangles.data(), ray, robust, any_hit ? 1 : 0, v);
      else if (layout == TraceLayout::BinaryWw)
        hits[i] = rs_traverse_binary_ww(bvh.nodes.data(), bvh.triangles.data(), ray, robust, any_hit ? 1 : 0, v);
      else
        hits[i] = robust ? rs_traverse_robust(bvh.nodes.data(), bvh.triangles.data(), ray, any_hit ? 1 : 0, v)
                         : rs_traverse(bvh.nodes.data(), bvh.triangles.data(), ray, any_hit ? 1 : 0, v);
      if (node_visits) (*node_visits)[i] = visits;
    }
  };
  for_each_block(n, n < 4096, work);
  return hits;
}

std::vector<std::uint64_t> node_traffic(const Bvh& bvh, const std::vector<RsRay>& rays, bool any_hit) {
  if (bvh.nodes.empty()) return {};
  const std::size_t n = rays.size();
  const unsigned threads = host_threads();
  const unsigned used = n < 4096 ? 1u : threads;
  std::vector<std::vector<std::uint64_t>> counts(used, std::vector<std::uint64_t>(bvh.nodes.size(), 0));
  auto work = [&](unsigned t, std::size_t begin, std::size_t end) {
    std::vector<rs_u32> trail(256);
    std::vector<std::uint64_t>& c = counts[t];
    // The fast walk with the encoders' box test (cl/traverse_binary.h, RS_VARIANT_FAST_UNFUSED).
    auto walk = [&](std::size_t i, rs_u32* len) {
      rs_traverse_variant_recorded(bvh.nodes.data(), bvh.triangles.data(), rays[i], RS_VARIANT_FAST_UNFUSED,
                                   any_hit ? 1 : 0, nullptr, trail.data(), static_cast<rs_u32>(trail.size()), len);
    };
    for (std::size_t i = begin; i < end; ++i) {
      rs_u32 len = 0;
      walk(i, &len);
      if (len > trail.size()) {  // a longer walk than the trail holds: again with room for all of it
        trail.resize(len);
        walk(i, &len);
      }
      for (rs_u32 k = 0; k < len; ++k) ++c[trail[k]];
    }
  };
  for_each_block_on(used, n, 1024, work);
  for (unsigned t = 1; t < used; ++t)
    for (std::size_t k = 0; k < counts[0].size(); ++k) counts[0][k] += counts[t][k];
  return counts.empty() ? std::vector<std::uint64_t>{} : std::move(counts[0]);
}

std::size_t count_hit_mismatches(const std::vector<RsHit>& a, const std::vector<RsHit>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size());
  std::size_t bad = 0;
  for (std::size_t i = 0; i < a.size(); ++i) bad += std::memcmp(&a[i], &b[i], sizeof(RsHit)) != 0;
  return bad;
}

}  // namespace raysort
