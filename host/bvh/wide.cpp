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

class Collapser {
 public:
  explicit Collapser(const Bvh& bvh) : bvh_(bvh), sub_(bvh) {}

  WideBvh run() {
    // Room for the largest possible tree up front (at most a wide node per binary node, a packet
    // per four triangles plus one per leaf), so that growing never copies the packets nor faults
    // their pages in twice. Untouched room costs address space only.
    out_.nodes.reserve(bvh_.nodes.size() + 1);
    out_.packets.reserve(bvh_.triangles.size() / 4 + std::min<std::size_t>(bvh_.leaf_count, bvh_.nodes.size()) + 1);
    wide_tree::collapse_from_root<4>(
        bvh_, out_, RS_WIDE_STACK_SIZE,
        [&](const std::vector<std::uint32_t>& slots, std::uint32_t depth) { make_node(slots, depth); },
        [&](std::uint32_t n) { return slots_of(n); });
    return std::move(out_);
  }

 private:
  // A binary subtree of at most four triangles becomes one wide leaf, a single full packet under
  // the subtree's box, when that box's surface area is at most the sum of its binary leaves' (SAH:
  // a random ray then tests no more packets than before, and the wide node keeps its lanes for
  // other subtrees). The SAH builder's leaves hold about two triangles, so their packets were half
  // empty. Without the area condition breakfast_room's shadow rays were 13-15 % slower; with it,
  // side by side (ours/Embree, median of 5): sibenik bounce1 +7 %, shadow1 +5 %, breakfast_room
  // shadow0 +7 %, shadow1 +9 %, no batch slower beyond noise (results/history/trace-kernels.md).
  static constexpr std::uint32_t kMergeTriangles = 4;
  bool leafish(std::uint32_t n) const { return sub_.leafish(n, kMergeTriangles); }

  // The binary nodes a wide node over inner binary node n holds: its children, or their children.
  std::vector<std::uint32_t> slots_of(std::uint32_t n) const {
    std::vector<std::uint32_t> slots;
    for (std::uint32_t c = bvh_.nodes[n].first; c < bvh_.nodes[n].first + 2; ++c) {
      if (leafish(c)) {
        slots.push_back(c);
      } else {
        slots.push_back(bvh_.nodes[c].first);
        slots.push_back(bvh_.nodes[c].first + 1);
      }
    }
    return slots;
  }

  std::uint32_t make_node(const std::vector<std::uint32_t>& slots, std::uint32_t depth) {
    out_.depth = std::max(out_.depth, depth);
    const auto index = static_cast<std::uint32_t>(out_.nodes.size());
    out_.nodes.push_back(RsWideNode{});
    RsWideNode w{};  // lanes past slots.size(): valid = 0, empty boxes, child 0 (never read)
    for (std::size_t i = 0; i < slots.size(); ++i) {
      wide_tree::set_box(w, static_cast<int>(i), bvh_.nodes[slots[i]]);
      w.valid.s[i] = -1;
      w.child[i] = leafish(slots[i]) ? wide_tree::append_leaf<4>(bvh_, sub_.as_leaf(slots[i]), out_.packets)
                                     : make_node(slots_of(slots[i]), depth + 1);
    }
    out_.nodes[index] = w;  // after the children: the vector may have grown meanwhile
    return index;
  }

  const Bvh& bvh_;
  const wide_tree::Subtrees sub_;
  WideBvh out_;
};

}  // namespace

WideBvh collapse_to_wide(const Bvh& bvh) { return Collapser(bvh).run(); }

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
