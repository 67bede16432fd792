#pragma once
// The trace classes, once (docs/trace.md, "Trace classes"): their names, widths and kernel builds.
// No OpenCL here: the result-set reader (host/bench/record.cpp) and the fuzzers need the names too.
#include <string>
#include <string_view>
#include <vector>

namespace raysort {

// The trace class: which tree the kernels walk, and how many rays walk it together (docs/trace.md,
// "Trace classes"). Wide: one ray per work-item over the 4-wide collapse of the BVH (the default,
// host/bvh/wide.cpp). Wide8: one ray per work-item over the 8-wide collapse (host/bvh/wide8.cpp,
// cl/traverse_wide8.h: eight boxes or triangles per float8 test). Binary: one ray over the binary BVH itself (kept to measure what the wide
// layout gains). PacketN: N consecutive rays of the order per work-item over the 4-wide tree, one
// ray per vector lane (cl/traverse_packet.h). HybridN: the same packets, but a subtree that at most
// N/4 lanes reach is walked by each of them alone (single rays). Packet, Hybrid: the width the device
// prefers, resolved by resolve_trace_layout before anything runs. CoherentN: packets of N over the 8-wide
// collapse, a node's children tested against the packet's frustum before its lanes (cl/traverse_coherent.h,
// Embree's coherent packets); Coherent: the preferred width's. Stream: RS_STREAM_CHUNK (2048)
// consecutive rays of the order per work-item, dealt into streams of RS_STREAM_RAYS (64) rays of one
// direction octant, each walking the 8-wide collapse node by node, each ray tested alone against a
// node's eight boxes (cl/traverse_stream.h): a stream's rays share each node's fetch.
// Cwbvh: one ray per work-item over the compressed 8-wide BVH (host/bvh/cwbvh.cpp,
// cl/traverse_cwbvh.h; Ylitie et al. 2017), the GPU-class kernel. BinaryWw: the binary BVH in the
// while-while loop form of Aila and Laine 2009 (cl/traverse_binary_ww.h; Binary is their if-if form).
enum class TraceLayout {
  Wide,
  Wide8,
  Binary,
  Packet4,
  Packet8,
  Packet16,
  Packet,
  Hybrid8,
  Hybrid16,
  Hybrid,
  Coherent8,
  Coherent16,
  Coherent,
  Stream,
  Cwbvh,
  BinaryWw
};

// The classes' names, in the order help and errors list them: wide, wide8, binary, packet4, packet8,
// packet16, packet, hybrid8, hybrid16, hybrid, coherent8, coherent16, coherent, stream, cwbvh, binary-ww. parse throws an Error naming the accepted values.
const std::vector<std::string>& trace_layout_names();
TraceLayout parse_trace_layout(std::string_view name);
const char* trace_layout_name(TraceLayout l);
// Every class with what it is, for --help: "wide (one ray per work-item over ...), wide8 (...), ...".
std::string trace_layouts_help();
// A command line's class list: "wide,packet" (in that order, repeats dropped), or "all" for every
// class but the unresolved packet. Throws Error naming an unknown class.
std::vector<TraceLayout> parse_trace_layouts(const std::string& list);
// Rays per work-item: 1 for the single-ray classes, N for PacketN and HybridN, RS_STREAM_CHUNK for Stream (0 for
// the unresolved Packet and Hybrid).
int packet_width(TraceLayout l);
// The hybrid's switch: a subtree reached by at most this many lanes is walked by each alone (0: never).
int packet_single_at(TraceLayout l);
// The class walks ray streams (cl/traverse_stream.h), not packets in vector lanes.
bool is_stream(TraceLayout l);
// The class walks coherent packets (cl/traverse_coherent.h): packets over the 8-wide tree, not a stream.
bool is_coherent(TraceLayout l);
// Packet (Hybrid, Coherent) becomes the packet (hybrid, coherent) class of a device's preferred float
// vector width (16 on AVX-512, 8 on AVX; packets: else 4, hybrids and coherent packets: else 8); every
// other class is returned as it is.
// trace/tracer.h has the overload that takes the device.
TraceLayout resolve_trace_layout(TraceLayout l, unsigned preferred_float_width);
// The kernel build's define and the kernels' name suffix (cl/trace.cl) of a resolved class.
const char* trace_class_define(TraceLayout l);
const char* trace_class_kernel_suffix(TraceLayout l);
// The tree a class walks: the binary BVH itself, its 4-wide collapse (bvh.wide), its 8-wide collapse
// (wide8, stream) or its compressed 8-wide collapse (cwbvh).
enum class TreeKind { Binary, Wide4, Wide8, Compressed8 };
TreeKind tree_kind(TraceLayout l);
// The branching factor of the tree a class walks: 2, 4 or 8.
int tree_width(TraceLayout l);
// The kernel's loop is while-while (an inner-node loop, then a leaf loop; Aila and Laine 2009): the
// GPU model issues its while-while step count (GpuCounts::ww_steps) instead of the lockstep one.
bool loops_while_while(TraceLayout l);
// The class walks the 4-wide tree (bvh.wide).
inline bool walks_wide_tree(TraceLayout l) { return tree_kind(l) == TreeKind::Wide4; }

}  // namespace raysort
