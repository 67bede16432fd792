// Collapsing the binary BVH into the 4-wide layout of the trace kernels (cl/bvh_layout.h, RsWideNode).
// Each wide node takes the two levels below a binary node: a child that is a leaf (or a small
// subtree that becomes one leaf packet, see leafish) fills one slot, an inner child gives its
// two children. So every wide level spans two binary levels, which is
// what bounds the kernels' stack (RS_WIDE_STACK_SIZE): depth <= ceil(binary depth / 2) and at
// most three pending siblings per level.
#include <algorithm>
#include <string>

#include "bvh/bvh.h"
#include "bvh/wide_tree.h"
#include "util/error.h"

namespace raysort {

bool exactly_degenerate(const RsTriangle& t) {
  const double a1x = double(t.v1[0]) - t.v0[0], a1y = double(t.v1[1]) - t.v0[1], a1z = double(t.v1[2]) - t.v0[2];
  const double a2x = double(t.v2[0]) - t.v0[0], a2y = double(t.v2[1]) - t.v0[1], a2z = double(t.v2[2]) - t.v0[2];
  return a1y * a2z - a1z * a2y == 0.0 && a1z * a2x - a1x * a2z == 0.0 && a1x * a2y - a1y * a2x == 0.0;
}

namespace {

// A binary subtree of at most four triangles becomes one wide leaf, a single full packet under
// the subtree's box, when that box's surface area is at most the sum of its binary leaves' (SAH:
// a random ray then tests no more packets than before, and the wide node keeps its lanes for
// other subtrees). The SAH builder's leaves hold about two triangles, so their packets were half
// empty. Without the area condition breakfast_room's shadow rays were 13-15 % slower; with it,
// side by side (ours/Embree, median of 5): sibenik bounce1 +7 %, shadow1 +5 %, breakfast_room
// shadow0 +7 %, shadow1 +9 %, no batch slower beyond noise (results/history/trace-kernels.md).
constexpr std::uint32_t kMergeTriangles = 4;

// The binary nodes a wide node over inner binary node n holds: its children, or their children.
wide_tree::Slots slots_of(const Bvh& bvh, const wide_tree::Subtrees& sub, std::uint32_t n) {
  wide_tree::Slots slots;
  for (std::uint32_t c = bvh.nodes[n].first; c < bvh.nodes[n].first + 2; ++c) {
    if (sub.leafish(c, kMergeTriangles)) {
      slots.push_back(c);
    } else {
      slots.push_back(bvh.nodes[c].first);
      slots.push_back(bvh.nodes[c].first + 1);
    }
  }
  return slots;
}

}  // namespace

WideBvh collapse_to_wide(const Bvh& bvh, unsigned threads) {
  const wide_tree::Subtrees sub(bvh, threads);
  return wide_tree::collapse<4, WideBvh>(
      bvh, sub, RS_WIDE_STACK_SIZE, kMergeTriangles, [&](std::uint32_t n) { return slots_of(bvh, sub, n); }, threads);
}

const WideBvh& wide_of(const Bvh& bvh, WideBvh& scratch) {
  if (!bvh.wide.empty()) return bvh.wide;
  scratch = collapse_to_wide(bvh);
  return scratch;
}

std::string validate_wide(const WideBvh& wide, const Bvh& bvh) {
  return wide_tree::validate<4>(wide, bvh, RS_WIDE_STACK_SIZE);
}

static_assert(sizeof(RsWideNode) == 128, "RsWideNode layout (cl/bvh_layout.h)");
static_assert(sizeof(RsTriPacket) == 192, "RsTriPacket layout (cl/bvh_layout.h)");

}  // namespace raysort
