#pragma once
// What the 4-wide and 8-wide collapses of the binary BVH share (host/bvh/wide.cpp, wide8.cpp): the
// leaf packets (W triangles, one coordinate per lane) and the validator. Templates over the lane
// count W, so both widths write and check their trees with one piece of code; the collapses differ
// only in which binary nodes become a wide node's children (their slot rules).
#include <algorithm>
#include <array>
#include <initializer_list>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "bvh/bvh.h"
#include "bvh/had.h"
#include "util/error.h"
#include "util/huge_pages.h"

namespace raysort::wide_tree {

// Per binary subtree: its triangle range in leaf order and the summed surface area of its binary
// leaves, for the collapses' merge rule (a small subtree becomes one wide leaf when SAH agrees).
class Subtrees {
 public:
  explicit Subtrees(const Bvh& bvh) : bvh_(bvh) {
    // The builder keeps a subtree's triangles contiguous; a subtree where they are not is never merged.
    first_.assign(bvh.nodes.size(), 0);
    count_.assign(bvh.nodes.size(), 0);
    leaf_area_.assign(bvh.nodes.size(), 0.0);
    small_and_sah_agrees_.assign(bvh.nodes.size(), 0);
    if (!bvh.triangles.empty() && !bvh.nodes.empty()) ranges(0);
  }
  // A binary leaf, or a subtree of at most max_triangles whose box's surface area is at most the
  // sum of its binary leaves' (SAH: a random ray then tests no more packets than before).
  bool leafish(std::uint32_t n, std::uint32_t max_triangles) const {
    if (bvh_.is_leaf(n)) return true;
    if (count_[n] > max_triangles) return false;
    return max_triangles <= kKnownMerge ? small_and_sah_agrees_[n] != 0 : sah_agrees(n);
  }
  // Subtree n as one leaf: its box over all its triangles.
  RsBvhNode as_leaf(std::uint32_t n) const {
    RsBvhNode b = bvh_.nodes[n];
    b.first = first_[n];
    b.count = count_[n];
    return b;
  }

 private:
  void ranges(std::uint32_t n) {
    const RsBvhNode& b = bvh_.nodes[n];
    if (b.count > 0) {
      first_[n] = b.first, count_[n] = b.count;
      leaf_area_[n] = node_surface_area(b);
      return;
    }
    ranges(b.first), ranges(b.first + 1);
    const std::uint32_t l = b.first, r = b.first + 1;
    first_[n] = std::min(first_[l], first_[r]);
    count_[n] = count_[l] + count_[r];
    leaf_area_[n] = leaf_area_[l] + leaf_area_[r];
    const std::uint32_t end = std::max(first_[l] + count_[l], first_[r] + count_[r]);
    if (end - first_[n] != count_[n]) count_[n] = 0xffffffffu;  // not contiguous: never merged
    small_and_sah_agrees_[n] = count_[n] <= kKnownMerge && sah_agrees(n);
  }
  bool sah_agrees(std::uint32_t n) const { return node_surface_area(bvh_.nodes[n]) <= leaf_area_[n]; }

  // leafish() asks each slot several times during a collapse: below this many triangles the
  // answer is worked out once, here (the 8-wide packet's size, the largest merge of the collapses).
  static constexpr std::uint32_t kKnownMerge = 8;
  const Bvh& bvh_;
  std::vector<std::uint32_t> first_, count_;
  std::vector<double> leaf_area_;  // sum of the surface areas of a subtree's binary leaves
  std::vector<std::uint8_t> small_and_sah_agrees_;  // inner node of at most kKnownMerge triangles, sah_agrees
};

// The binary nodes a wide node holds, one per lane (at most eight): a fixed array, so that the
// collapse allocates nothing per node.
class Slots {
 public:
  Slots() = default;
  Slots(std::initializer_list<std::uint32_t> nodes) {
    for (std::uint32_t n : nodes) push_back(n);
  }
  void push_back(std::uint32_t n) { node_.at(size_++) = n; }
  // Puts n at position i, the slots from i on moving up by one.
  void insert(std::size_t i, std::uint32_t n) {
    node_.at(size_);  // room for one more (throws past eight)
    for (std::size_t k = size_; k > i; --k) node_[k] = node_[k - 1];
    node_[i] = n;
    ++size_;
  }
  void clear() { size_ = 0; }
  std::size_t size() const { return size_; }
  std::uint32_t& operator[](std::size_t i) { return node_[i]; }
  std::uint32_t operator[](std::size_t i) const { return node_[i]; }
  const std::uint32_t* begin() const { return node_.data(); }
  const std::uint32_t* end() const { return node_.data() + size_; }

 private:
  std::array<std::uint32_t, 8> node_{};
  std::size_t size_ = 0;
};

// Appends the W-lane packets of binary leaf `leaf` (triangles [first, first + count) of bvh's leaf
// order) and returns the leaf reference (RS_WIDE_LEAF | first packet << 2 | packets - 1, as in
// cl/bvh_layout.h). Lanes past the last triangle stay invalid (valid = 0, id RS_NO_HIT).
template <int W, class Packet>
std::uint32_t append_leaf(const Bvh& bvh, const RsBvhNode& leaf, std::vector<Packet>& packets) {
  const auto first = static_cast<std::uint32_t>(packets.size());
  const std::uint32_t count = (leaf.count + W - 1) / W;
  if (count > 4)
    throw Error("BVH leaf of " + std::to_string(leaf.count) + " triangles does not fit the " + std::to_string(W) +
                "-wide layout (at most " + std::to_string(4 * W) + " per leaf: lower max_leaf_size)");
  if (first >= (1u << 29)) throw Error("scene too large for the wide BVH layout (2^29 leaf packets)");
  for (std::uint32_t p = 0; p < count; ++p) {
    Packet pk{};
    for (int lane = 0; lane < W; ++lane) {
      const std::uint32_t k = leaf.first + W * p + static_cast<std::uint32_t>(lane);
      if (k >= leaf.first + leaf.count) {
        pk.id[lane] = RS_NO_HIT;  // valid = 0: never hit
        continue;
      }
      const RsTriangle& t = bvh.triangles[k];
      pk.v0x.s[lane] = t.v0[0], pk.v0y.s[lane] = t.v0[1], pk.v0z.s[lane] = t.v0[2];
      pk.v1x.s[lane] = t.v1[0], pk.v1y.s[lane] = t.v1[1], pk.v1z.s[lane] = t.v1[2];
      pk.v2x.s[lane] = t.v2[0], pk.v2y.s[lane] = t.v2[1], pk.v2z.s[lane] = t.v2[2];
      pk.valid.s[lane] = -1;
      pk.nondegenerate.s[lane] = exactly_degenerate(t) ? 0 : -1;
      pk.id[lane] = t.id;
    }
    packets.push_back(pk);
  }
  return RS_WIDE_LEAF | (first << 2) | (count - 1);
}

// Writes binary node b's box into lane `lane` of wide node w.
template <class Node>
void set_box(Node& w, int lane, const RsBvhNode& b) {
  w.lo_x.s[lane] = b.bmin[0], w.hi_x.s[lane] = b.bmax[0];
  w.lo_y.s[lane] = b.bmin[1], w.hi_y.s[lane] = b.bmax[1];
  w.lo_z.s[lane] = b.bmin[2], w.hi_z.s[lane] = b.bmax[2];
}

// The collapse from the root, for both widths: an empty tree gets a root with no valid child (every
// ray misses), a one-leaf tree still an inner root, any other the wide node over the binary root's
// slots; a tree whose nodes, each pushing up to W - 1 children, could overflow the kernels' stack
// of stack_size entries is refused. Wide nodes are numbered depth first (a node before its
// children, its slots in order), and a leaf's packets are appended when the walk meets the leaf.
// slots_of(n): the binary nodes a wide node over inner binary node n holds; a slot becomes one wide
// leaf (sub.as_leaf) when sub.leafish(slot, merge_triangles). The collapses differ only in these two.
//
// (Tried: the subtrees below the top collapsed by all threads, each into a tree of its own, then
// copied into place. On a 322 K-triangle scene the collapse went from 15-27 ms to 70-93 ms: a
// subtree's own vectors fault their pages in again, 2 MiB pages or 4 KiB ones.)
template <int W, class Tree, class SlotsOfFn>
Tree collapse(const Bvh& bvh, const Subtrees& sub, std::uint32_t stack_size, std::uint32_t merge_triangles,
              SlotsOfFn slots_of) {
  using Node = std::decay_t<decltype(std::declval<Tree&>().nodes[0])>;
  Tree out;
  if (bvh.triangles.empty() || bvh.nodes.empty()) {
    out.nodes.emplace_back();
    out.depth = 1;
    return out;
  }
  // Room for the largest possible tree up front (at most a wide node per binary node, a packet per
  // W triangles plus one per leaf), so that growing never copies the packets nor faults their pages
  // in twice; 2 MiB pages where the kernel lends them (util/huge_pages.h). Untouched room costs
  // address space only.
  reserve_huge(out.nodes, bvh.nodes.size() + 1);
  reserve_huge(out.packets, bvh.triangles.size() / W + std::min<std::size_t>(bvh.leaf_count, bvh.nodes.size()) + 1);
  auto make_node = [&](auto& self, const Slots& slots, std::uint32_t depth) -> std::uint32_t {
    out.depth = std::max(out.depth, depth);
    const auto index = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes.push_back(Node{});
    Node w{};  // lanes past slots.size(): valid = 0, empty boxes, child 0 (never read)
    for (std::size_t i = 0; i < slots.size(); ++i) {
      set_box(w, static_cast<int>(i), bvh.nodes[slots[i]]);
      w.valid.s[i] = -1;
      w.child[i] = sub.leafish(slots[i], merge_triangles) ? append_leaf<W>(bvh, sub.as_leaf(slots[i]), out.packets)
                                     : self(self, slots_of(slots[i]), depth + 1);
    }
    out.nodes[index] = w;  // after the children: the vector may have grown meanwhile
    return index;
  };
  make_node(make_node, bvh.is_leaf(0) ? Slots{0u} : slots_of(0), 1u);
  if ((W - 1) * out.depth > stack_size)
    throw Error(std::to_string(W) + "-wide BVH of depth " + std::to_string(out.depth) +
                " could overflow the trace stack (" + std::to_string(stack_size) +
                " entries); the binary BVH is deeper than its bound");
  return out;
}

// The checks of validate_wide / validate_wide8 (bvh.h) on a W-wide tree whose nodes push at most
// W - 1 children each into a stack of stack_size entries.
template <int W, class Tree>
std::string validate(const Tree& wide, const Bvh& bvh, std::uint32_t stack_size) {
  if (wide.nodes.empty()) return "no root";
  if ((W - 1) * wide.depth > stack_size) return "depth " + std::to_string(wide.depth) + " exceeds the stack bound";
  std::vector<std::uint32_t> seen_tri(bvh.triangles.size(), 0), seen_node(wide.nodes.size(), 0);
  // Binary boxes, to check that each wide child box is one of them.
  auto same_box = [](const auto& w, int lane, const RsBvhNode& b) {
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
    const auto& w = wide.nodes[ni];
    for (int lane = 0; lane < W; ++lane) {
      if (w.valid.s[lane] == 0) continue;
      const std::uint32_t ref = w.child[lane];
      if (!(ref & RS_WIDE_LEAF)) {
        if (ref >= wide.nodes.size() || seen_node[ref]++) return "inner reference " + std::to_string(ref) + " bad or shared";
        const auto& c = wide.nodes[ref];
        for (int k = 0; k < W; ++k)  // the child's boxes lie inside the lane's box
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
        for (int k = 0; k < W; ++k) {
          const auto& pk = wide.packets[p];
          if (pk.valid.s[k] == 0) continue;
          const std::uint32_t id = pk.id[k];
          if (id >= seen_tri.size() || seen_tri[id]++) return "triangle " + std::to_string(id) + " bad or in two lanes";
          const RsTriangle& t = bvh.triangles[index_of_tri[id]];
          const float lanes[9] = {pk.v0x.s[k], pk.v0y.s[k], pk.v0z.s[k], pk.v1x.s[k], pk.v1y.s[k],
                                  pk.v1z.s[k], pk.v2x.s[k], pk.v2y.s[k], pk.v2z.s[k]};
          const float verts[9] = {t.v0[0], t.v0[1], t.v0[2], t.v1[0], t.v1[1], t.v1[2], t.v2[0], t.v2[1], t.v2[2]};
          if (std::memcmp(lanes, verts, sizeof lanes) != 0)
            return "vertices of triangle " + std::to_string(id) + " not copied exactly";
          if ((pk.nondegenerate.s[k] == 0) != exactly_degenerate(t))
            return "degenerate flag of triangle " + std::to_string(id) + " wrong";
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

}  // namespace raysort::wide_tree
