#include "trace/trace_class.h"

#include <algorithm>

#include "shared.h"
#include "util/error.h"
#include "util/text.h"

// The stream's sizes spelt in its --help line from the constants themselves.
#define RS_STREAM_TEXT_(x) #x
#define RS_STREAM_TEXT(x) RS_STREAM_TEXT_(x)

namespace raysort {

namespace {

// The trace classes, once: name, rays per work-item, the hybrids' switch, whether the rays walk as a
// stream, the tree walked, the kernel build's define and the kernels' name suffix (cl/trace.cl),
// whether its loop is while-while, and what it is (--help). The hybrids switch to single rays at a
// quarter of the packet's lanes.
struct TraceClass {
  TraceLayout layout;
  const char* name;
  int width;
  int single_at;
  bool stream;
  TreeKind tree;
  const char* define;
  const char* suffix;
  bool while_while;
  const char* meaning;  // for --help
};
constexpr TraceClass kTraceClasses[] = {
    {TraceLayout::Wide, "wide", 1, 0, false, TreeKind::Wide4, "", "", false,
     "one ray per work-item over the 4-wide BVH, the default"},
    {TraceLayout::Wide8, "wide8", 1, 0, false, TreeKind::Wide8, "-DRS_TRACE_WIDE8", "_wide8", false,
     "one ray over the 8-wide BVH"},
    {TraceLayout::Binary, "binary", 1, 0, false, TreeKind::Binary, "-DRS_TRACE_BINARY", "_binary", false,
     "one ray over the binary BVH, if-if loop"},
    {TraceLayout::Packet4, "packet4", 4, 0, false, TreeKind::Wide4, "-DRS_TRACE_PACKET=4", "_packet", false,
     "packets of 4 consecutive rays over the 4-wide BVH, one ray per vector lane"},
    {TraceLayout::Packet8, "packet8", 8, 0, false, TreeKind::Wide4, "-DRS_TRACE_PACKET=8", "_packet", false,
     "packets of 8"},
    {TraceLayout::Packet16, "packet16", 16, 0, false, TreeKind::Wide4, "-DRS_TRACE_PACKET=16", "_packet", false,
     "packets of 16"},
    {TraceLayout::Packet, "packet", 0, 0, false, TreeKind::Wide4, "", "", false,
     "packets of the device's preferred vector width, `raysort devices`"},
    {TraceLayout::Hybrid8, "hybrid8", 8, 2, false, TreeKind::Wide4, "-DRS_TRACE_PACKET=8 -DRS_PACKET_SINGLE_AT=2", "_packet", false,
     "packets of 8 that hand subtrees reached by 2 lanes to single rays"},
    {TraceLayout::Hybrid16, "hybrid16", 16, 4, false, TreeKind::Wide4, "-DRS_TRACE_PACKET=16 -DRS_PACKET_SINGLE_AT=4", "_packet", false,
     "packets of 16, single rays from 4 lanes"},
    {TraceLayout::Hybrid, "hybrid", 0, 0, false, TreeKind::Wide4, "", "", false,
     "hybrids of the device's preferred width"},
    {TraceLayout::Coherent8, "coherent8", 8, 0, false, TreeKind::Wide8, "-DRS_TRACE_PACKET=8 -DRS_TRACE_COHERENT",
     "_coherent", false,
     "packets of 8 over the 8-wide BVH, a node's children tested against the packet's frustum before its lanes "
     "(Embree's coherent packets; the fastest on a camera's rays)"},
    {TraceLayout::Coherent16, "coherent16", 16, 0, false, TreeKind::Wide8, "-DRS_TRACE_PACKET=16 -DRS_TRACE_COHERENT",
     "_coherent", false, "coherent packets of 16"},
    {TraceLayout::Coherent, "coherent", 0, 0, false, TreeKind::Wide8, "", "", false,
     "coherent packets of the device's preferred width"},
    {TraceLayout::Stream, "stream", RS_STREAM_CHUNK, 0, true, TreeKind::Wide8, "-DRS_TRACE_STREAM", "_stream", false,
     "streams of " RS_STREAM_TEXT(RS_STREAM_RAYS) " rays of one direction octant (dealt from " RS_STREAM_TEXT(RS_STREAM_CHUNK)
     " consecutive rays) over the 8-wide BVH, node by node"},
    {TraceLayout::Cwbvh, "cwbvh", 1, 0, false, TreeKind::Compressed8, "-DRS_TRACE_CWBVH", "_cwbvh", false,
     "one ray over the compressed 8-wide BVH of Ylitie et al. 2017, a GPU kernel"},
    {TraceLayout::BinaryWw, "binary-ww", 1, 0, false, TreeKind::Binary, "-DRS_TRACE_BINARY_WW", "_binary_ww", true,
     "one ray over the binary BVH, the while-while loop of Aila and Laine 2009"},
};

const TraceClass& trace_class(TraceLayout l) {
  for (const TraceClass& c : kTraceClasses)
    if (c.layout == l) return c;
  throw Error("internal: a trace class without a row in kTraceClasses");
}

}  // namespace

const std::vector<std::string>& trace_layout_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const TraceClass& c : kTraceClasses) v.emplace_back(c.name);
    return v;
  }();
  return names;
}

TraceLayout parse_trace_layout(std::string_view name) {
  for (const TraceClass& c : kTraceClasses)
    if (name == c.name) return c.layout;
  std::string names;
  for (const std::string& n : trace_layout_names()) names += (names.empty() ? "" : ", ") + n;
  throw Error("unknown trace class '" + std::string(name) + "' (expected " + names + ")");
}

const char* trace_layout_name(TraceLayout l) { return trace_class(l).name; }

std::string trace_layouts_help() {
  std::string text;
  for (const TraceClass& c : kTraceClasses) text += (text.empty() ? "" : ", ") + std::string(c.name) + " (" + c.meaning + ")";
  return text;
}

std::vector<TraceLayout> parse_trace_layouts(const std::string& list) {
  std::vector<TraceLayout> out;
  if (list == "all") {
    for (const TraceClass& c : kTraceClasses)
      if (c.width > 0) out.push_back(c.layout);
    return out;
  }
  for (const auto& name : split_list(list)) {
    const TraceLayout l = parse_trace_layout(name);
    if (std::find(out.begin(), out.end(), l) == out.end()) out.push_back(l);
  }
  if (out.empty()) throw Error("--layout: name at least one trace class (" + std::string(kTraceClasses[0].name) + ", ...)");
  return out;
}

int packet_width(TraceLayout l) { return trace_class(l).width; }

int packet_single_at(TraceLayout l) { return trace_class(l).single_at; }

bool is_stream(TraceLayout l) { return trace_class(l).stream; }

bool is_coherent(TraceLayout l) {
  const TraceClass& c = trace_class(l);
  return c.tree == TreeKind::Wide8 && c.width > 1 && !c.stream;
}

TreeKind tree_kind(TraceLayout l) { return trace_class(l).tree; }

bool loops_while_while(TraceLayout l) { return trace_class(l).while_while; }

int tree_width(TraceLayout l) {
  switch (tree_kind(l)) {
    case TreeKind::Binary: return 2;
    case TreeKind::Wide4: return 4;
    case TreeKind::Wide8:
    case TreeKind::Compressed8: return 8;
  }
  return 4;
}

const char* trace_class_define(TraceLayout l) { return trace_class(l).define; }

const char* trace_class_kernel_suffix(TraceLayout l) { return trace_class(l).suffix; }

TraceLayout resolve_trace_layout(TraceLayout l, unsigned preferred_float_width) {
  const bool wide16 = preferred_float_width >= 16, wide8 = preferred_float_width >= 8;
  if (l == TraceLayout::Packet) return wide16 ? TraceLayout::Packet16 : wide8 ? TraceLayout::Packet8 : TraceLayout::Packet4;
  if (l == TraceLayout::Hybrid) return wide16 ? TraceLayout::Hybrid16 : TraceLayout::Hybrid8;
  if (l == TraceLayout::Coherent) return wide16 ? TraceLayout::Coherent16 : TraceLayout::Coherent8;
  return l;
}

}  // namespace raysort
