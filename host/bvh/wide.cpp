// Collapsing the binary BVH into the 4-wide layout of the trace kernels (cl/bvh_layout.h, RsWideNode).
// Each wide node takes the two levels below a binary node: a child that is a leaf (or a small
// subtree that becomes one leaf packet, see leafish) fills one slot, an inner child gives its
// two children. So every wide level spans two binary levels, which is
// what bounds the kernels' stack (RS_WIDE_STACK_SIZE): depth <= ceil(binary depth / 2) and at
// most three pending siblings per level.
#include <algorithm>
#include <cstring>
#include <string>

#include "bvh/bvh.h"
#include "bvh/had.h"
#include "util/error.h"

namespace raysort {

namespace {

// Zero area in exact arithmetic: differences and products of floats are exact in double, so this
// is the robust test's degenerate-triangle check (cl/intersect.h), decided once here.
bool exactly_degenerate(const RsTriangle& t) {
  const double a1x = double(t.v1[0]) - t.v0[0], a1y = double(t.v1[1]) - t.v0[1], a1z = double(t.v1[2]) - t.v0[2];
  const double a2x = double(t.v2[0]) - t.v0[0], a2y = double(t.v2[1]) - t.v0[1], a2z = double(t.v2[2]) - t.v0[2];
  return a1y * a2z - a1z * a2y == 0.0 && a1z * a2x - a1x * a2z == 0.0 && a1x * a2y - a1y * a2x == 0.0;
}

void set_lane(rs_f4& v, int lane, float x) { v.s[lane] = x; }

class Collapser {
 public:
  explicit Collapser(const Bvh& bvh) : bvh_(bvh) {
    // Triangle range of every binary subtree (the builder keeps a subtree's triangles contiguous).
    sub_first_.assign(bvh.nodes.size(), 0);
    sub_count_.assign(bvh.nodes.size(), 0);
    leaf_area_.assign(bvh.nodes.size(), 0.0);
    if (!bvh.triangles.empty() && !bvh.nodes.empty()) ranges(0);
  }

  WideBvh run() {
    if (bvh_.triangles.empty() || bvh_.nodes.empty()) {
      out_.nodes.push_back(RsWideNode{});  // a root with no valid child: every ray misses
      out_.depth = 1;
      return std::move(out_);
    }
    if (bvh_.is_leaf(0))
      make_node({0u}, 1);  // a one-leaf tree still gets an inner root
    else
      make_node(slots_of(0), 1);
    if (3 * out_.depth > RS_WIDE_STACK_SIZE)
      throw Error("4-wide BVH of depth " + std::to_string(out_.depth) + " could overflow the trace stack (" +
                  std::to_string(RS_WIDE_STACK_SIZE) + " entries); the binary BVH is deeper than its bound");
    return std::move(out_);
  }

 private:
  void ranges(std::uint32_t n) {
    const RsBvhNode& b = bvh_.nodes[n];
    if (b.count > 0) {
      sub_first_[n] = b.first, sub_count_[n] = b.count;
      leaf_area_[n] = node_surface_area(b);
      return;
    }
    ranges(b.first), ranges(b.first + 1);
    const std::uint32_t l = b.first, r = b.first + 1;
    sub_first_[n] = std::min(sub_first_[l], sub_first_[r]);
    sub_count_[n] = sub_count_[l] + sub_count_[r];
    leaf_area_[n] = leaf_area_[l] + leaf_area_[r];
    const std::uint32_t end = std::max(sub_first_[l] + sub_count_[l], sub_first_[r] + sub_count_[r]);
    if (end - sub_first_[n] != sub_count_[n]) sub_count_[n] = 0xffffffffu;  // not contiguous: never merged
  }
  // A binary subtree of at most four triangles becomes one wide leaf, a single full packet under
  // the subtree's box, when that box's surface area is at most the sum of its binary leaves' (SAH:
  // a random ray then tests no more packets than before, and the wide node keeps its lanes for
  // other subtrees). The SAH builder's leaves hold about two triangles, so their packets were half
  // empty. Without the area condition breakfast_room's shadow rays were 13-15 % slower; with it,
  // side by side (ours/Embree, median of 5): sibenik bounce1 +7 %, shadow1 +5 %, breakfast_room
  // shadow0 +7 %, shadow1 +9 %, no batch slower beyond noise (results/history/trace-kernels.md).
  static constexpr std::uint32_t kMergeTriangles = 4;
  bool leafish(std::uint32_t n) const {
    return bvh_.is_leaf(n) ||
           (sub_count_[n] <= kMergeTriangles && node_surface_area(bvh_.nodes[n]) <= leaf_area_[n]);
  }
  RsBvhNode as_leaf(std::uint32_t n) const {
    RsBvhNode b = bvh_.nodes[n];
    b.first = sub_first_[n];
    b.count = sub_count_[n];
    return b;
  }

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
      const RsBvhNode& b = bvh_.nodes[slots[i]];
      const int lane = static_cast<int>(i);
      set_lane(w.lo_x, lane, b.bmin[0]), set_lane(w.hi_x, lane, b.bmax[0]);
      set_lane(w.lo_y, lane, b.bmin[1]), set_lane(w.hi_y, lane, b.bmax[1]);
      set_lane(w.lo_z, lane, b.bmin[2]), set_lane(w.hi_z, lane, b.bmax[2]);
      w.valid.s[i] = -1;
      w.child[i] = leafish(slots[i]) ? make_leaf(as_leaf(slots[i])) : make_node(slots_of(slots[i]), depth + 1);
    }
    out_.nodes[index] = w;  // after the children: the vector may have grown meanwhile
    return index;
  }

  std::uint32_t make_leaf(const RsBvhNode& leaf) {
    const auto first = static_cast<std::uint32_t>(out_.packets.size());
    const std::uint32_t packets = (leaf.count + 3) / 4;
    if (packets > 4)
      throw Error("BVH leaf of " + std::to_string(leaf.count) +
                  " triangles does not fit the 4-wide layout (at most 16 per leaf: lower max_leaf_size)");
    if (first >= (1u << 29)) throw Error("scene too large for the 4-wide BVH layout (2^31 triangles)");
    for (std::uint32_t p = 0; p < packets; ++p) {
      RsTriPacket pk{};
      for (int lane = 0; lane < 4; ++lane) {
        const std::uint32_t k = leaf.first + 4 * p + static_cast<std::uint32_t>(lane);
        if (k >= leaf.first + leaf.count) {
          pk.id[lane] = RS_NO_HIT;  // valid = 0: never hit
          continue;
        }
        const RsTriangle& t = bvh_.triangles[k];
        set_lane(pk.v0x, lane, t.v0[0]), set_lane(pk.v0y, lane, t.v0[1]), set_lane(pk.v0z, lane, t.v0[2]);
        set_lane(pk.v1x, lane, t.v1[0]), set_lane(pk.v1y, lane, t.v1[1]), set_lane(pk.v1z, lane, t.v1[2]);
        set_lane(pk.v2x, lane, t.v2[0]), set_lane(pk.v2y, lane, t.v2[1]), set_lane(pk.v2z, lane, t.v2[2]);
        pk.valid.s[lane] = -1;
        pk.nondegenerate.s[lane] = exactly_degenerate(t) ? 0 : -1;
        pk.id[lane] = t.id;
      }
      out_.packets.push_back(pk);
    }
    return RS_WIDE_LEAF | (first << 2) | (packets - 1);
  }

  const Bvh& bvh_;
  WideBvh out_;
  std::vector<std::uint32_t> sub_first_, sub_count_;
  std::vector<double> leaf_area_;  // sum of the surface areas of a subtree's binary leaves
};

}  // namespace

WideBvh collapse_to_wide(const Bvh& bvh) { return Collapser(bvh).run(); }

const WideBvh& wide_of(const Bvh& bvh, WideBvh& scratch) {
  if (!bvh.wide.empty()) return bvh.wide;
  scratch = collapse_to_wide(bvh);
  return scratch;
}

std::string validate_wide(const WideBvh& wide, const Bvh& bvh) {
  if (wide.nodes.empty()) return "no root";
  if (3 * wide.depth > RS_WIDE_STACK_SIZE) return "depth " + std::to_string(wide.depth) + " exceeds the stack bound";
  std::vector<std::uint32_t> seen_tri(bvh.triangles.size(), 0), seen_node(wide.nodes.size(), 0);
  // Binary boxes, to check that each wide child box is one of them.
  auto same_box = [](const RsWideNode& w, int lane, const RsBvhNode& b) {
    return w.lo_x.s[lane] == b.bmin[0] && w.lo_y.s[lane] == b.bmin[1] && w.lo_z.s[lane] == b.bmin[2] &&
           w.hi_x.s[lane] == b.bmax[0] && w.hi_y.s[lane] == b.bmax[1] && w.hi_z.s[lane] == b.bmax[2];
  };
  // Each triangle id's binary leaf (to match a leaf reference to its box) and leaf-order index
  // (to compare its vertices).
  std::vector<std::uint32_t> leaf_of_tri(bvh.triangles.size(), 0), index_of_tri(bvh.triangles.size(), 0);
  for (std::uint32_t n = 0; n < bvh.nodes.size(); ++n)
    if (bvh.is_leaf(n))
      for (std::uint32_t k = bvh.nodes[n].first; k < bvh.nodes[n].first + bvh.nodes[n].count; ++k) {
        leaf_of_tri[bvh.triangles[k].id] = n;
        index_of_tri[bvh.triangles[k].id] = k;
      }
  std::vector<std::uint32_t> parent(bvh.nodes.size(), 0);
  for (std::uint32_t n = 0; n < bvh.nodes.size(); ++n)
    if (!bvh.is_leaf(n)) parent[bvh.nodes[n].first] = parent[bvh.nodes[n].first + 1] = n;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> todo{{0u, 1u}};  // (node, depth)
  seen_node[0] = 1;
  while (!todo.empty()) {
    auto [ni, depth] = todo.back();
    todo.pop_back();
    if (depth > wide.depth) return "node " + std::to_string(ni) + " deeper than the recorded depth";
    const RsWideNode& w = wide.nodes[ni];
    for (int lane = 0; lane < 4; ++lane) {
      if (w.valid.s[lane] == 0) continue;
      const std::uint32_t ref = w.child[lane];
      if (!(ref & RS_WIDE_LEAF)) {
        if (ref >= wide.nodes.size() || seen_node[ref]++) return "inner reference " + std::to_string(ref) + " bad or shared";
        const RsWideNode& c = wide.nodes[ref];
        for (int k = 0; k < 4; ++k)  // the child's boxes lie inside the lane's box
          if (c.valid.s[k] && (c.lo_x.s[k] < w.lo_x.s[lane] || c.lo_y.s[k] < w.lo_y.s[lane] ||
                               c.lo_z.s[k] < w.lo_z.s[lane] || c.hi_x.s[k] > w.hi_x.s[lane] ||
                               c.hi_y.s[k] > w.hi_y.s[lane] || c.hi_z.s[k] > w.hi_z.s[lane]))
            return "node " + std::to_string(ref) + " sticks out of its parent's box";
        todo.push_back({ref, depth + 1});
        continue;
      }
      const std::uint32_t first = (ref & ~RS_WIDE_LEAF) >> 2, end = first + (ref & 3u) + 1u;
      if (end > wide.packets.size()) return "leaf packets out of range";
      for (std::uint32_t p = first; p < end; ++p)
        for (int k = 0; k < 4; ++k) {
          const RsTriPacket& pk = wide.packets[p];
          if (pk.valid.s[k] == 0) continue;
          const std::uint32_t id = pk.id[k];
          if (id >= seen_tri.size() || seen_tri[id]++) return "triangle " + std::to_string(id) + " bad or in two lanes";
          const RsTriangle& t = bvh.triangles[index_of_tri[id]];
          const float lanes[9] = {pk.v0x.s[k], pk.v0y.s[k], pk.v0z.s[k], pk.v1x.s[k], pk.v1y.s[k],
                                  pk.v1z.s[k], pk.v2x.s[k], pk.v2y.s[k], pk.v2z.s[k]};
          const float verts[9] = {t.v0[0], t.v0[1], t.v0[2], t.v1[0], t.v1[1], t.v1[2], t.v2[0], t.v2[1], t.v2[2]};
          if (std::memcmp(lanes, verts, sizeof lanes) != 0)
            return "vertices of triangle " + std::to_string(id) + " not copied exactly";
          // A wide leaf is a binary leaf or a merged small subtree: its box is that of the
          // triangle's binary leaf or of one of the leaf's ancestors (so it holds the triangle).
          std::uint32_t b = leaf_of_tri[id];
          while (!same_box(w, lane, bvh.nodes[b]) && b != 0) b = parent[b];
          if (!same_box(w, lane, bvh.nodes[b]))
            return "leaf box of node " + std::to_string(ni) + " lane " + std::to_string(lane) +
                   " is not the box of triangle " + std::to_string(id) + "'s leaf or of an ancestor";
        }
    }
  }
  for (std::size_t i = 0; i < seen_tri.size(); ++i)
    if (seen_tri[i] != 1) return "triangle " + std::to_string(i) + " in no packet";
  return "";
}

static_assert(sizeof(RsWideNode) == 128, "RsWideNode layout (cl/bvh_layout.h)");
static_assert(sizeof(RsTriPacket) == 192, "RsTriPacket layout (cl/bvh_layout.h)");

}  // namespace raysort
