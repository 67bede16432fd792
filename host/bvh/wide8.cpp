// Collapsing the binary BVH into the 8-wide layout of the wide8 trace class (cl/bvh_layout.h,
// RsWide8Node / RsTriPacket8; cl/traverse_wide8.h walks it).
// An 8-wide node over inner binary node n takes the binary nodes three levels below n (2^3 = 8
// slots), stopping early at a leaf or at a small subtree that becomes one leaf packet (leafish);
// lanes left free are then filled by opening the slot of largest surface area, as Embree's BVH8
// collapse does (a big box is the one most rays enter). Every inner slot thus lies at least three
// binary levels below n, which bounds the tree's depth and so the kernels' stack
// (RS_WIDE8_STACK_SIZE): depth <= RS_WIDE8_MAX_DEPTH and at most seven pending siblings per level.
#include <algorithm>
#include <string>

#include "bvh/bvh.h"
#include "bvh/had.h"
#include "bvh/wide_tree.h"
#include "util/error.h"

namespace raysort {

namespace {

// A subtree of at most eight triangles becomes one leaf (one full packet) when SAH agrees: the
// 4-wide collapse's rule (wide.cpp) at the 8-wide packet's size. The SAH builder's leaves hold
// about two triangles; merged, a leaf test fills more of the eight lanes.
constexpr std::uint32_t kWide8MergeTriangles = 8;

// The binary nodes an 8-wide node over inner binary node n holds (see the top of the file).
wide_tree::Slots wide8_slots(const Bvh& bvh, const wide_tree::Subtrees& sub, std::uint32_t n) {
  wide_tree::Slots slots{bvh.nodes[n].first, bvh.nodes[n].first + 1}, deeper;
  for (int level = 2; level <= 3; ++level) {  // every inner slot down to three levels below n
    deeper.clear();
    for (std::uint32_t s : slots) {
      if (sub.leafish(s, kWide8MergeTriangles)) {
        deeper.push_back(s);
      } else {
        deeper.push_back(bvh.nodes[s].first);
        deeper.push_back(bvh.nodes[s].first + 1);
      }
    }
    std::swap(slots, deeper);
  }
  while (slots.size() < 8) {  // free lanes: open the largest inner slot, its children in its place
    std::size_t best = slots.size();
    double best_area = -1.0;
    for (std::size_t i = 0; i < slots.size(); ++i) {
      if (sub.leafish(slots[i], kWide8MergeTriangles)) continue;
      const double a = node_surface_area(bvh.nodes[slots[i]]);
      if (a > best_area) best = i, best_area = a;
    }
    if (best == slots.size()) break;
    const std::uint32_t c = bvh.nodes[slots[best]].first;
    slots[best] = c;
    slots.insert(best + 1, c + 1);
  }
  // Largest box first: an any-hit walk takes the children in slot order, and the child whose box is
  // largest is the one a ray most likely enters and the likeliest to hold its occluder, so a shadow
  // ray stops sooner (the order of Ize and Hansen's occlusion heuristic, RTSAH, 2011, by area alone).
  // Nearest-first walks only break ties by slot. Ties keep the tree's order: the same tree every run.
  std::stable_sort(&slots[0], &slots[0] + slots.size(), [&](std::uint32_t a, std::uint32_t b) {
    return node_surface_area(bvh.nodes[a]) > node_surface_area(bvh.nodes[b]);
  });
  return slots;
}

}  // namespace

Wide8Bvh collapse_to_wide8(const Bvh& bvh, unsigned threads) {
  const wide_tree::Subtrees sub(bvh, threads);
  return wide_tree::collapse<8, Wide8Bvh>(
      bvh, sub, RS_WIDE8_STACK_SIZE, kWide8MergeTriangles, [&](std::uint32_t n) { return wide8_slots(bvh, sub, n); }, threads);
}

std::string validate_wide8(const Wide8Bvh& wide, const Bvh& bvh) {
  return wide_tree::validate<8>(wide, bvh, RS_WIDE8_STACK_SIZE);
}

static_assert(sizeof(RsWide8Node) == 256, "RsWide8Node layout (cl/bvh_layout.h)");
static_assert(sizeof(RsTriPacket8) == 384, "RsTriPacket8 layout (cl/bvh_layout.h)");

}  // namespace raysort
