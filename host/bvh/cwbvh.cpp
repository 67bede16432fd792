// The compressed 8-wide BVH of the cwbvh trace class (cl/bvh_layout.h, RsCwbvhNode; cl/traverse_cwbvh.h
// walks it), collapsed from the binary tree as Ylitie, Karras and Laine (HPG 2017) describe it,
// with the wide8 collapse's greedy rule for which binary nodes a node holds:
// - Slots: a node over binary node n starts from n's two children and opens the slot of largest
//   surface area until eight are used (an inner binary node opens into its two children; a binary
//   leaf of more than three triangles into its triangles three at a time). A slot that stays a
//   binary inner node, or a leaf of more than three triangles, becomes an inner child; a leaf of at
//   most three triangles, or a subtree of at most three that SAH lets merge (wide_tree::Subtrees),
//   a leaf child.
// - Fewer, fuller nodes (the node memory the paper's format is for): an inner child whose own
//   slots fit the node's free ones is pulled up into the node, and two inner children whose slots
//   fit one node's eight become one child node over both, smallest first. Without this the subtrees
//   at the bottom become nodes of two or three children (sibenik: 4.5 children per node, node
//   memory 45 % of the 4-wide tree's; breakfast_room 52 %).
// - Slot order by octant (section 3.1 of the paper): child c goes to slot s so that a ray of octant
//   s meets it early: the cost of (s, c) is the child's centroid offset along the octant's diagonal,
//   and the pairs are taken greedily, cheapest first (the paper's auction, made greedy).
// - Quantisation: per axis the grid origin is the node's lower bound and the step the smallest power
//   of two with 255 steps covering the node; each child's 8-bit bounds are rounded outward and then
//   checked in the kernels' float arithmetic (p + q * step), so the dequantised box contains the
//   child's exact box.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "bvh/bvh.h"
#include "bvh/had.h"
#include "bvh/wide_tree.h"
#include "util/error.h"

namespace raysort {

namespace {

// At most this many triangles in a leaf slot (meta's three count bits, in the paper unary).
constexpr std::uint32_t kLeafTriangles = 3;

struct Box {
  std::array<float, 3> lo{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                          std::numeric_limits<float>::max()};
  std::array<float, 3> hi{-std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(),
                          -std::numeric_limits<float>::max()};
  void add(const float* v) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
  }
  void add(const Box& b) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], b.lo[a]), hi[a] = std::max(hi[a], b.hi[a]);
  }
  double area() const {
    const double x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return 2.0 * (x * y + y * z + z * x);
  }
};

Box triangle_box(const RsTriangle& t) {
  Box b;
  b.add(t.v0), b.add(t.v1), b.add(t.v2);
  return b;
}

// A slot's content: binary node `node`, or (chunk) triangles [first, first + count) of the leaf order.
struct Item {
  std::uint32_t node = 0;
  bool chunk = false;
  std::uint32_t first = 0, count = 0;
};

// A slot of a node under construction: a leaf child (item), or an inner child whose node will hold
// `child` (already widened). box: everything below it.
struct Slot {
  Box box;
  bool leaf = false;
  Item item;
  std::vector<Item> child;
};

// The dequantised bound p + q * step, in the kernels' float arithmetic (q * step is exact).
float dequantised(float p, std::uint32_t q, float step) { return p + static_cast<float>(q) * step; }

class CwbvhCollapser {
 public:
  explicit CwbvhCollapser(const Bvh& bvh) : bvh_(bvh), sub_(bvh) {}

  CwBvh run() {
    out_.nodes.emplace_back();  // the root; an empty tree keeps it empty (every ray misses)
    if (bvh_.triangles.empty() || bvh_.nodes.empty()) {
      out_.depth = 1;
      return std::move(out_);
    }
    Item root;
    root.node = 0;
    fill_node(0, slots_of(opened(root)), 1);
    if (out_.depth + 1 > RS_CWBVH_STACK_SIZE)
      throw Error("compressed 8-wide BVH of depth " + std::to_string(out_.depth) + " could overflow the trace stack (" +
                  std::to_string(RS_CWBVH_STACK_SIZE) + " entries)");
    return std::move(out_);
  }

 private:
  bool is_leaf_slot(const Item& it) const {
    if (it.chunk) return true;
    const RsBvhNode as_leaf = sub_.as_leaf(it.node);
    return as_leaf.count <= kLeafTriangles && sub_.leafish(it.node, kLeafTriangles);
  }
  // The triangles of a leaf slot (a chunk, a binary leaf or a merged subtree: contiguous in leaf order).
  std::pair<std::uint32_t, std::uint32_t> triangles_of(const Item& it) const {
    if (it.chunk) return {it.first, it.count};
    const RsBvhNode b = sub_.as_leaf(it.node);
    return {b.first, b.count};
  }
  Box box_of(const Item& it) const {
    Box b;
    if (it.chunk) {
      for (std::uint32_t k = it.first; k < it.first + it.count; ++k) b.add(triangle_box(bvh_.triangles[k]));
      return b;
    }
    const RsBvhNode& n = bvh_.nodes[it.node];
    b.lo = {n.bmin[0], n.bmin[1], n.bmin[2]};
    b.hi = {n.bmax[0], n.bmax[1], n.bmax[2]};
    return b;
  }
  // What an item that is not a leaf slot opens into: a binary inner node's two children, or a
  // binary leaf's triangles three at a time.
  std::vector<Item> opened(const Item& it) const {
    std::vector<Item> items;
    const RsBvhNode& n = bvh_.nodes[it.node];
    if (n.count == 0) {
      Item l, r;
      l.node = n.first, r.node = n.first + 1;
      return {l, r};
    }
    for (std::uint32_t k = 0; k < n.count; k += kLeafTriangles) {
      Item c;
      c.chunk = true, c.first = n.first + k, c.count = std::min(kLeafTriangles, n.count - k);
      items.push_back(c);
    }
    return items;
  }
  // Opens the largest slot that fits until eight are used (see the top of the file).
  void widen(std::vector<Item>& items) const {
    for (;;) {
      std::size_t best = items.size();
      double best_area = -1.0;
      std::vector<Item> best_open;
      for (std::size_t i = 0; i < items.size(); ++i) {
        if (is_leaf_slot(items[i])) continue;
        const double a = box_of(items[i]).area();
        if (a <= best_area) continue;
        std::vector<Item> o = opened(items[i]);
        if (items.size() - 1 + o.size() > 8) continue;
        best = i, best_area = a, best_open = std::move(o);
      }
      if (best == items.size()) return;
      items.erase(items.begin() + static_cast<std::ptrdiff_t>(best));
      items.insert(items.begin() + static_cast<std::ptrdiff_t>(best), best_open.begin(), best_open.end());
    }
  }
  Slot slot_for(const Item& it) const {
    Slot s;
    if (is_leaf_slot(it)) {
      s.leaf = true, s.item = it, s.box = box_of(it);
      return s;
    }
    s.child = opened(it);
    widen(s.child);
    for (const Item& c : s.child) s.box.add(box_of(c));
    return s;
  }
  // A node's slots over `items`: widened, then inner children pulled up or paired (see the top).
  std::vector<Slot> slots_of(std::vector<Item> items) const {
    widen(items);
    std::vector<Slot> slots;
    for (const Item& it : items) slots.push_back(slot_for(it));
    for (;;) {
      const std::size_t free = 8 - slots.size();
      std::size_t pull = slots.size();
      for (std::size_t i = 0; i < slots.size(); ++i)
        if (!slots[i].leaf && slots[i].child.size() - 1 <= free &&
            (pull == slots.size() || slots[i].child.size() < slots[pull].child.size()))
          pull = i;
      if (pull < slots.size()) {
        const std::vector<Item> up = std::move(slots[pull].child);
        slots.erase(slots.begin() + static_cast<std::ptrdiff_t>(pull));
        for (const Item& it : up) slots.push_back(slot_for(it));
        continue;
      }
      std::size_t a = slots.size(), b = slots.size(), best = 9;
      for (std::size_t i = 0; i < slots.size(); ++i)
        for (std::size_t j = i + 1; j < slots.size(); ++j)
          if (!slots[i].leaf && !slots[j].leaf && slots[i].child.size() + slots[j].child.size() < best)
            a = i, b = j, best = slots[i].child.size() + slots[j].child.size();
      if (best > 8) return slots;
      slots[a].child.insert(slots[a].child.end(), slots[b].child.begin(), slots[b].child.end());
      slots[a].box.add(slots[b].box);
      slots.erase(slots.begin() + static_cast<std::ptrdiff_t>(b));
    }
  }
  // slot_of[c]: the slot of item c, cheapest (slot, item) pairs first (see the top of the file).
  static std::array<int, 8> assign_slots(const std::vector<Box>& boxes, const Box& parent) {
    std::array<int, 8> slot_of{};
    slot_of.fill(-1);
    std::array<bool, 8> slot_used{};
    double centre[3];
    for (int a = 0; a < 3; ++a) centre[a] = 0.5 * (static_cast<double>(parent.lo[a]) + parent.hi[a]);
    for (std::size_t placed = 0; placed < boxes.size(); ++placed) {
      double best = std::numeric_limits<double>::infinity();
      int best_s = -1, best_c = -1;
      for (int s = 0; s < 8; ++s) {
        if (slot_used[s]) continue;
        for (std::size_t c = 0; c < boxes.size(); ++c) {
          if (slot_of[c] >= 0) continue;
          double cost = 0.0;
          for (int a = 0; a < 3; ++a) {
            const double offset = 0.5 * (static_cast<double>(boxes[c].lo[a]) + boxes[c].hi[a]) - centre[a];
            cost += ((s >> a) & 1 ? -offset : offset);  // the octant's direction: negative along set bits
          }
          if (cost < best) best = cost, best_s = s, best_c = static_cast<int>(c);
        }
      }
      slot_of[best_c] = best_s;
      slot_used[best_s] = true;
    }
    return slot_of;
  }
  // Node `index`'s grid and child bounds (see the top of the file).
  static void quantise(RsCwbvhNode& node, const Box& parent, const std::vector<Box>& boxes, const std::array<int, 8>& slot_of) {
    float step[3];
    for (int a = 0; a < 3; ++a) {
      const float lo = parent.lo[a], hi = parent.hi[a];
      int e = -126;
      if (hi > lo) e = std::max(-126, static_cast<int>(std::ceil(std::log2((static_cast<double>(hi) - lo) / 255.0))));
      while (e > -126 && dequantised(lo, 255, std::ldexp(1.0f, e - 1)) >= hi) --e;
      while (dequantised(lo, 255, std::ldexp(1.0f, e)) < hi) ++e;
      if (e > 127) throw Error("scene coordinates too large for the compressed BVH's 8-bit exponents");
      node.p[a] = lo;
      node.e[a] = static_cast<rs_u8>(e + 127);
      step[a] = std::ldexp(1.0f, e);
    }
    rs_u8* q_lo[3] = {node.q_lo_x, node.q_lo_y, node.q_lo_z};
    rs_u8* q_hi[3] = {node.q_hi_x, node.q_hi_y, node.q_hi_z};
    for (std::size_t c = 0; c < boxes.size(); ++c) {
      const int s = slot_of[c];
      for (int a = 0; a < 3; ++a) {
        const float p = node.p[a], lo = boxes[c].lo[a], hi = boxes[c].hi[a];
        double ql = std::floor((static_cast<double>(lo) - p) / step[a]);
        double qh = std::ceil((static_cast<double>(hi) - p) / step[a]);
        auto l = static_cast<std::uint32_t>(std::clamp(ql, 0.0, 255.0));
        auto h = static_cast<std::uint32_t>(std::clamp(qh, 0.0, 255.0));
        while (l > 0 && dequantised(p, l, step[a]) > lo) --l;
        while (h < 255 && dequantised(p, h, step[a]) < hi) ++h;
        q_lo[a][s] = static_cast<rs_u8>(l);
        q_hi[a][s] = static_cast<rs_u8>(h);
      }
    }
  }
  // Writes node `index` over `slots`, then its inner children.
  void fill_node(std::uint32_t index, const std::vector<Slot>& slots, std::uint32_t depth) {
    out_.depth = std::max(out_.depth, depth);
    std::vector<Box> boxes;
    Box parent;
    for (const Slot& s : slots) boxes.push_back(s.box), parent.add(s.box);
    const std::array<int, 8> slot_of = assign_slots(boxes, parent);
    RsCwbvhNode node{};
    quantise(node, parent, boxes, slot_of);
    // Inner children contiguous in slot order, then the leaves' triangles in slot order.
    std::array<int, 8> in_slot{};
    in_slot.fill(-1);
    for (std::size_t c = 0; c < slots.size(); ++c) in_slot[slot_of[c]] = static_cast<int>(c);
    node.child_base = static_cast<std::uint32_t>(out_.nodes.size());
    node.triangle_base = static_cast<std::uint32_t>(out_.triangles.size());
    std::vector<std::pair<std::uint32_t, const Slot*>> inner;  // (node index, slot)
    for (int s = 0; s < 8; ++s) {
      if (in_slot[s] < 0) continue;
      const Slot& slot = slots[in_slot[s]];
      if (!slot.leaf) {
        node.imask = static_cast<rs_u8>(node.imask | (1u << s));
        inner.emplace_back(static_cast<std::uint32_t>(out_.nodes.size()), &slot);
        out_.nodes.emplace_back();
        continue;
      }
      const auto [first, count] = triangles_of(slot.item);
      const auto offset = static_cast<std::uint32_t>(out_.triangles.size()) - node.triangle_base;
      node.meta[s] = static_cast<rs_u8>((count << 5) | offset);
      for (std::uint32_t k = first; k < first + count; ++k) out_.triangles.push_back(bvh_.triangles[k]);
    }
    out_.nodes[index] = node;
    for (const auto& [child, slot] : inner) fill_node(child, slots_of(slot->child), depth + 1);
  }

  const Bvh& bvh_;
  const wide_tree::Subtrees sub_;
  CwBvh out_;
};

// The exact box of everything below slot s of node n (its triangles), and the checks of validate_cwbvh.
struct CwbvhChecker {
  const CwBvh& cw;
  std::vector<std::uint32_t> seen_node;
  std::vector<std::uint32_t> seen_triangle;
  std::string error;

  Box check_node(std::uint32_t index) {
    Box all;
    if (!error.empty()) return all;
    if (index >= cw.nodes.size()) return fail("node index " + std::to_string(index) + " out of range"), all;
    if (seen_node[index]++) return fail("node " + std::to_string(index) + " reached twice"), all;
    const RsCwbvhNode& n = cw.nodes[index];
    std::uint32_t inner_rank = 0;
    for (int s = 0; s < 8 && error.empty(); ++s) {
      Box under;
      if ((n.imask >> s) & 1) {
        under = check_node(n.child_base + inner_rank++);
      } else if (n.meta[s]) {
        const std::uint32_t count = n.meta[s] >> 5, offset = n.meta[s] & 31u;
        if (count < 1 || count > kLeafTriangles || offset + count > 24 ||
            n.triangle_base + offset + count > cw.triangles.size())
          return fail("node " + std::to_string(index) + " slot " + std::to_string(s) + ": bad leaf"), all;
        for (std::uint32_t k = n.triangle_base + offset; k < n.triangle_base + offset + count; ++k) {
          if (seen_triangle[k]++) return fail("triangle slot " + std::to_string(k) + " in two leaves"), all;
          under.add(triangle_box(cw.triangles[k]));
        }
      } else {
        continue;
      }
      const rs_u8* q_lo[3] = {n.q_lo_x, n.q_lo_y, n.q_lo_z};
      const rs_u8* q_hi[3] = {n.q_hi_x, n.q_hi_y, n.q_hi_z};
      for (int a = 0; a < 3; ++a) {
        const float step = std::ldexp(1.0f, static_cast<int>(n.e[a]) - 127);
        if (n.e[a] < 1 || n.e[a] > 254 || dequantised(n.p[a], q_lo[a][s], step) > under.lo[a] ||
            dequantised(n.p[a], q_hi[a][s], step) < under.hi[a])
          return fail("node " + std::to_string(index) + " slot " + std::to_string(s) + ": box does not contain its triangles"),
                 all;
      }
      all.add(under);
    }
    return all;
  }
  void fail(const std::string& what) {
    if (error.empty()) error = what;
  }
};

}  // namespace

CwBvh collapse_to_cwbvh(const Bvh& bvh) { return CwbvhCollapser(bvh).run(); }

std::string validate_cwbvh(const CwBvh& cw, const Bvh& bvh) {
  if (cw.nodes.empty()) return "no root";
  if (cw.depth + 1 > RS_CWBVH_STACK_SIZE) return "depth " + std::to_string(cw.depth) + " exceeds the stack bound";
  CwbvhChecker check{cw, std::vector<std::uint32_t>(cw.nodes.size(), 0), std::vector<std::uint32_t>(cw.triangles.size(), 0), {}};
  check.check_node(0);
  if (!check.error.empty()) return check.error;
  for (std::size_t i = 0; i < cw.nodes.size(); ++i)
    if (!check.seen_node[i]) return "node " + std::to_string(i) + " never reached";
  for (std::size_t k = 0; k < cw.triangles.size(); ++k)
    if (!check.seen_triangle[k]) return "triangle slot " + std::to_string(k) + " in no leaf";
  if (cw.triangles.size() != bvh.triangles.size())
    return std::to_string(cw.triangles.size()) + " triangles against the binary tree's " + std::to_string(bvh.triangles.size());
  // Every triangle once, with its vertices and id: compare the multisets by id.
  std::vector<const RsTriangle*> by_id(bvh.triangles.size(), nullptr);
  for (const RsTriangle& t : bvh.triangles)
    if (t.id < by_id.size()) by_id[t.id] = &t;
  std::vector<std::uint8_t> seen(bvh.triangles.size(), 0);
  for (const RsTriangle& t : cw.triangles) {
    if (t.id >= by_id.size() || !by_id[t.id] || seen[t.id]++) return "triangle id " + std::to_string(t.id) + " missing or twice";
    const RsTriangle& b = *by_id[t.id];
    for (int a = 0; a < 3; ++a)
      if (t.v0[a] != b.v0[a] || t.v1[a] != b.v1[a] || t.v2[a] != b.v2[a])
        return "triangle id " + std::to_string(t.id) + ": vertices differ from the binary tree's";
  }
  return {};
}

static_assert(sizeof(RsCwbvhNode) == 80, "RsCwbvhNode layout (cl/bvh_layout.h)");

}  // namespace raysort
