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
#include <vector>

#include "bvh/bvh.h"
#include "bvh/had.h"
#include "bvh/wide_tree.h"
#include "util/error.h"

namespace raysort {

namespace {

class Collapser8 {
 public:
  Collapser8(const Bvh& bvh, int merge) : bvh_(bvh), sub_(bvh), merge_(merge) {}

  Wide8Bvh run() {
    wide_tree::collapse_from_root<8>(
        bvh_, out_, RS_WIDE8_STACK_SIZE,
        [&](const std::vector<std::uint32_t>& slots, std::uint32_t depth) { make_node(plan(slots), depth); },
        [&](std::uint32_t n) { return slots_of(n); });
    return std::move(out_);
  }

 private:
  // A subtree of at most eight triangles becomes one leaf (one full packet) when SAH agrees: the
  // 4-wide collapse's rule (wide.cpp) at the 8-wide packet's size. The SAH builder's leaves hold
  // about two triangles; merged, a leaf test fills more of the eight lanes.
  static constexpr std::uint32_t kMergeTriangles = 8;
  bool leafish(std::uint32_t n) const { return sub_.leafish(n, kMergeTriangles); }

  // The binary nodes an 8-wide node over inner binary node n holds (see the top of the file).
  std::vector<std::uint32_t> slots_of(std::uint32_t n) const {
    std::vector<std::uint32_t> slots{bvh_.nodes[n].first, bvh_.nodes[n].first + 1}, deeper;
    for (int level = 2; level <= 3; ++level) {  // every inner slot down to three levels below n
      deeper.clear();
      for (std::uint32_t s : slots) {
        if (leafish(s)) {
          deeper.push_back(s);
        } else {
          deeper.push_back(bvh_.nodes[s].first);
          deeper.push_back(bvh_.nodes[s].first + 1);
        }
      }
      slots.swap(deeper);
    }
    while (slots.size() < 8) {  // free lanes: open the largest inner slot, its children in its place
      std::size_t best = slots.size();
      double best_area = -1.0;
      for (std::size_t i = 0; i < slots.size(); ++i) {
        if (leafish(slots[i])) continue;
        const double a = node_surface_area(bvh_.nodes[slots[i]]);
        if (a > best_area) best = i, best_area = a;
      }
      if (best == slots.size()) break;
      const std::uint32_t c = bvh_.nodes[slots[best]].first;
      slots[best] = c;
      slots.insert(slots.begin() + static_cast<std::ptrdiff_t>(best) + 1, c + 1);
    }
    return slots;
  }

  // A child of a node under construction: a leaf slot (binary node `leaf`), or an inner child whose
  // node will have `children` under `box` (the union of the binary boxes it stands for). The tree is
  // planned bottom-up before it is written, so a child's lane count is final when its parent merges.
  struct Child {
    bool is_leaf = false;
    std::uint32_t leaf = 0;
    std::vector<Child> children;
    RsBvhNode box{};
  };

  // The children of the node over `slots`, each inner one planned in turn, merged (merge_pairs).
  std::vector<Child> plan(const std::vector<std::uint32_t>& slots) const {
    std::vector<Child> children(slots.size());
    for (std::size_t i = 0; i < slots.size(); ++i) {
      children[i].box = bvh_.nodes[slots[i]];
      children[i].is_leaf = leafish(slots[i]);
      if (children[i].is_leaf)
        children[i].leaf = slots[i];
      else
        children[i].children = plan(slots_of(slots[i]));
    }
    if (merge_) merge_pairs(children);
    return children;
  }

  // Two inner children whose lanes together fit in eight become one child node over both, the
  // pair of fewest lanes first, while a pair fits (the cwbvh collapse's rule, cwbvh.cpp). The greedy
  // fill leaves the bottom of the tree sparse: a node of fewer than eight slots holds only leaf
  // slots, so a parent of two inner children of three leaves each had two nodes of three children
  // where one of six does. The merged node stays one level below the parent and its children two,
  // so the depth (and RS_WIDE8_STACK_SIZE's bound) cannot grow; its own inner children (from both)
  // are merged in turn.
  // Experiment arm wide8s: merge only where the union's surface area is at most the two boxes'
  // (a random ray then enters no more nodes than before).
  bool sah_agrees(const Child& a, const Child& b) const {
    if (merge_ != 2) return true;
    RsBvhNode u = a.box;
    for (int k = 0; k < 3; ++k) u.bmin[k] = std::min(u.bmin[k], b.box.bmin[k]), u.bmax[k] = std::max(u.bmax[k], b.box.bmax[k]);
    return node_surface_area(u) <= node_surface_area(a.box) + node_surface_area(b.box);
  }
  void merge_pairs(std::vector<Child>& children) const {
    for (;;) {
      std::size_t a = children.size(), b = children.size(), fewest = 9;
      for (std::size_t i = 0; i < children.size(); ++i)
        for (std::size_t j = i + 1; j < children.size(); ++j)
          if (!children[i].is_leaf && !children[j].is_leaf &&
              children[i].children.size() + children[j].children.size() < fewest && sah_agrees(children[i], children[j]))
            a = i, b = j, fewest = children[i].children.size() + children[j].children.size();
      if (fewest > 8) return;
      Child& m = children[a];
      for (Child& c : children[b].children) m.children.push_back(std::move(c));
      for (int k = 0; k < 3; ++k) {
        m.box.bmin[k] = std::min(m.box.bmin[k], children[b].box.bmin[k]);
        m.box.bmax[k] = std::max(m.box.bmax[k], children[b].box.bmax[k]);
      }
      merge_pairs(m.children);
      children.erase(children.begin() + static_cast<std::ptrdiff_t>(b));
    }
  }

  std::uint32_t make_node(const std::vector<Child>& children, std::uint32_t depth) {
    out_.depth = std::max(out_.depth, depth);
    const auto index = static_cast<std::uint32_t>(out_.nodes.size());
    out_.nodes.push_back(RsWide8Node{});
    RsWide8Node w{};  // lanes past the children: valid = 0, empty boxes, child 0 (never read)
    for (std::size_t i = 0; i < children.size(); ++i) {
      const Child& c = children[i];
      wide_tree::set_box(w, static_cast<int>(i), c.box);
      w.valid.s[i] = -1;
      w.child[i] = c.is_leaf ? wide_tree::append_leaf<8>(bvh_, sub_.as_leaf(c.leaf), out_.packets)
                             : make_node(c.children, depth + 1);
    }
    out_.nodes[index] = w;  // after the children: the vector may have grown meanwhile
    return index;
  }

  const Bvh& bvh_;
  const wide_tree::Subtrees sub_;
  const int merge_;  // 0 none, 1 pairs, 2 pairs where SAH agrees (issue 40 experiment)
  Wide8Bvh out_;
};

}  // namespace

Wide8Bvh collapse_to_wide8(const Bvh& bvh, int merge_pairs) { return Collapser8(bvh, merge_pairs).run(); }

std::string validate_wide8(const Wide8Bvh& wide, const Bvh& bvh) {
  return wide_tree::validate<8>(wide, bvh, RS_WIDE8_STACK_SIZE);
}

static_assert(sizeof(RsWide8Node) == 256, "RsWide8Node layout (cl/bvh_layout.h)");
static_assert(sizeof(RsTriPacket8) == 384, "RsTriPacket8 layout (cl/bvh_layout.h)");

}  // namespace raysort
