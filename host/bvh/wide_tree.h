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
#include "util/parallel.h"

namespace raysort::wide_tree {

// Per binary subtree: its triangle range in leaf order and the summed surface area of its binary
// leaves, for the collapses' merge rule (a small subtree becomes one wide leaf when SAH agrees).
class Subtrees {
 public:
  // On `threads` threads (0: host_threads()): the subtrees below the top binary levels in parallel,
  // then the top on this thread.
  explicit Subtrees(const Bvh& bvh, unsigned threads = 0) : bvh_(bvh) {
    // The builder keeps a subtree's triangles contiguous; a subtree where they are not is never merged.
    first_.assign(bvh.nodes.size(), 0);
    count_.assign(bvh.nodes.size(), 0);
    leaf_area_.assign(bvh.nodes.size(), 0.0);
    small_and_sah_agrees_.assign(bvh.nodes.size(), 0);
    if (bvh.triangles.empty() || bvh.nodes.empty()) return;
    threads = threads > 0 ? threads : host_threads();
    // The first binary level with enough nodes to keep every thread busy (or the leaves, below it).
    std::uint32_t split_depth = 0;
    for (std::vector<std::uint32_t> level{0u}, next; level.size() < 8 * threads; ++split_depth) {
      next.clear();
      for (std::uint32_t n : level)
        if (!bvh.is_leaf(n)) next.push_back(bvh.nodes[n].first), next.push_back(bvh.nodes[n].first + 1);
      if (next.empty()) break;
      level.swap(next);
    }
    std::vector<std::uint32_t> below;  // the subtrees at split_depth
    top_ranges(0, 0, split_depth, &below);
    for_each_job(threads, below.size(), [&](std::size_t i) { ranges(below[i]); });
    top_ranges(0, 0, split_depth, nullptr);
  }
  // A binary leaf, or a subtree of at most max_triangles whose box's surface area is at most the
  // sum of its binary leaves' (SAH: a random ray then tests no more packets than before).
  bool leafish(std::uint32_t n, std::uint32_t max_triangles) const {
    if (bvh_.is_leaf(n)) return true;
    if (count_[n] > max_triangles) return false;
    return max_triangles <= kKnownMerge ? small_and_sah_agrees_[n] != 0 : sah_agrees(n);
  }
  // The triangles of subtree n (for a leafish n: of its one wide leaf).
  std::uint32_t count(std::uint32_t n) const { return count_[n]; }
  // Subtree n as one leaf: its box over all its triangles.
  RsBvhNode as_leaf(std::uint32_t n) const {
    RsBvhNode b = bvh_.nodes[n];
    b.first = first_[n];
    b.count = count_[n];
    return b;
  }

 private:
  void ranges(std::uint32_t n) {
    if (!bvh_.is_leaf(n)) ranges(bvh_.nodes[n].first), ranges(bvh_.nodes[n].first + 1);
    combine(n);
  }
  // The top binary levels above split_depth: first collecting the subtrees below them (`below`),
  // then, once those are done, combining their own nodes.
  void top_ranges(std::uint32_t n, std::uint32_t depth, std::uint32_t split_depth, std::vector<std::uint32_t>* below) {
    if (depth == split_depth || bvh_.is_leaf(n)) {
      if (below) below->push_back(n);
      return;
    }
    top_ranges(bvh_.nodes[n].first, depth + 1, split_depth, below);
    top_ranges(bvh_.nodes[n].first + 1, depth + 1, split_depth, below);
    if (!below) combine(n);
  }
  // Node n's figures from its children's (a leaf's from itself).
  void combine(std::uint32_t n) {
    const RsBvhNode& b = bvh_.nodes[n];
    if (b.count > 0) {
      first_[n] = b.first, count_[n] = b.count;
      leaf_area_[n] = node_surface_area(b);
      return;
    }
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

// The packets a wide leaf over `count` triangles takes: W triangles to a packet.
template <int W>
std::uint32_t leaf_packets(std::uint32_t count) {
  return (count + W - 1) / W;
}

// Where the leaves among a wide node's slots go. Per slot that is a leaf (sub.leafish), in slot order:
// its first packet, numbered among the packets the node opens (0, 1, ... in the order the walk opens
// them), and its first lane. W = 8: a leaf of up to eight triangles goes into the first packet this
// node has opened with room for it (first fit), else into a new one, so a node's small leaves share
// packets (RS_WIDE8_LEAF_*, cl/bvh_layout.h: a third fewer packets on sibenik); a larger leaf opens
// packets of its own. W = 4: every leaf opens its own packets at lane 0 (RS_WIDE_LEAF_FIRST's
// layout, whose references name no lanes). The same plan for the count (collapse's Extent) and the
// writing walk, so they agree.
struct LeafPlan {
  std::array<std::uint32_t, 8> packet{}, lane{};
  std::uint32_t packets = 0;  // the node opens in all
  std::uint32_t largest = 0;  // triangles of its largest leaf
};

template <int W>
LeafPlan plan_leaves(const Subtrees& sub, const Slots& slots, std::uint32_t merge_triangles) {
  LeafPlan plan;
  std::array<std::uint32_t, 8> used{};    // W = 8: lanes taken in each packet opened for leaves of up to 8
  std::array<std::uint32_t, 8> shared{};  // those packets, numbered as plan.packet
  std::size_t open = 0;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (!sub.leafish(slots[i], merge_triangles)) continue;
    const std::uint32_t count = sub.count(slots[i]);
    plan.largest = std::max(plan.largest, count);
    std::size_t k = 0;
    if (W == 8 && count <= 8) {
      while (k < open && used[k] + count > 8) ++k;
      if (k == open) shared[open++] = plan.packets++;
      plan.packet[i] = shared[k], plan.lane[i] = used[k];
      used[k] += count;
      continue;
    }
    plan.packet[i] = plan.packets, plan.lane[i] = 0;
    plan.packets += leaf_packets<W>(count);
  }
  return plan;
}

// An empty packet: every lane invalid (valid = 0, id RS_NO_HIT), what a lane no leaf fills keeps.
template <int W, class Packet>
Packet empty_packet() {
  Packet pk{};
  for (int lane = 0; lane < W; ++lane) pk.id[lane] = RS_NO_HIT;
  return pk;
}

// Writes the triangles of leaf `leaf` (triangles [first, first + count) of bvh's leaf order) into the
// lanes from `lane` on of packets[at], then packets[at + 1], ... (already written empty: the lanes of
// other leaves and those past the last triangle are left as they are), and returns the leaf reference:
// RS_WIDE_LEAF | at << 2 | packets - 1 for W = 4, RS_WIDE8_LEAF_* for W = 8 (cl/bvh_layout.h). The
// collapse has checked that the leaf fits (at most four packets, `at` within the reference's bits).
template <int W, class Packet>
std::uint32_t write_leaf(const Bvh& bvh, const RsBvhNode& leaf, Packet* packets, std::uint64_t at, std::uint32_t lane) {
  for (std::uint32_t k = 0; k < leaf.count; ++k) {
    const std::uint32_t slot = lane + k;
    Packet& pk = packets[at + slot / W];
    const int l = static_cast<int>(slot % W);
    const RsTriangle& t = bvh.triangles[leaf.first + k];
    pk.v0x.s[l] = t.v0[0], pk.v0y.s[l] = t.v0[1], pk.v0z.s[l] = t.v0[2];
    pk.v1x.s[l] = t.v1[0], pk.v1y.s[l] = t.v1[1], pk.v1z.s[l] = t.v1[2];
    pk.v2x.s[l] = t.v2[0], pk.v2y.s[l] = t.v2[1], pk.v2z.s[l] = t.v2[2];
    pk.valid.s[l] = -1;
    pk.nondegenerate.s[l] = exactly_degenerate(t) ? 0 : -1;
    pk.id[l] = t.id;
  }
  const std::uint32_t count = leaf_packets<W>(leaf.count);
  if constexpr (W == 8) {
    const std::uint32_t lanes = std::min<std::uint32_t>(leaf.count, 8);
    return RS_WIDE8_LEAF_REF(static_cast<std::uint32_t>(at), lane, lanes, count);
  } else {
    return RS_WIDE_LEAF | static_cast<std::uint32_t>(at << 2) | (count - 1);
  }
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
// children, its slots in order), and a leaf's packets follow in the same depth-first order.
// slots_of(n): the binary nodes a wide node over inner binary node n holds; a slot becomes one wide
// leaf (sub.as_leaf) when sub.leafish(slot, merge_triangles). The collapses differ only in these two.
//
// On `threads` threads, the same tree for every count. Depth-first numbering puts each wide subtree
// in one contiguous run of nodes and one of packets, so the subtrees below the top (rooted at the
// task depth, the first wide level with 32 nodes per thread) are sized first (Extent, on all
// threads), the top then numbered on this thread, which gives each subtree its first node and
// packet, and the subtrees written in place on all threads, largest first. The arrays are sized
// once, so no page is touched twice.
// (Tried before: each subtree into a tree of its own, then copied into place: on a 322 K-triangle
// scene the collapse went from 15-27 ms to 70-93 ms, every subtree's own vectors faulting their
// pages in again.)
template <int W, class Tree, class SlotsOfFn>
Tree collapse(const Bvh& bvh, const Subtrees& sub, std::uint32_t stack_size, std::uint32_t merge_triangles,
              SlotsOfFn slots_of, unsigned threads) {
  using Node = std::decay_t<decltype(std::declval<Tree&>().nodes[0])>;
  using Packet = std::decay_t<decltype(std::declval<Tree&>().packets[0])>;
  Tree out;
  if (bvh.triangles.empty() || bvh.nodes.empty()) {
    out.nodes.push_back(Node{});
    out.depth = 1;
    return out;
  }
  // A wide subtree's size: its nodes and packets, its depth in wide levels, its largest leaf.
  struct Extent {
    std::uint64_t nodes = 0, packets = 0;
    std::uint32_t depth = 0, largest_leaf = 0;
    void add_leaves(const LeafPlan& plan) {  // a node's leaves (plan_leaves)
      packets += plan.packets;
      largest_leaf = std::max(largest_leaf, plan.largest);
    }
    void add_child(const Extent& c) {
      nodes += c.nodes, packets += c.packets;
      depth = std::max(depth, c.depth + 1);
      largest_leaf = std::max(largest_leaf, c.largest_leaf);
    }
  };
  struct Cursor {
    std::uint64_t node = 0, packet = 0;
  };
  struct Task {
    Slots slots;  // of its root, a wide node at task depth
    Extent extent;
    Cursor at;    // its root's index and its first packet
  };
  auto extent_of = [&](auto& self, const Slots& slots) -> Extent {
    Extent e{1, 0, 1, 0};
    e.add_leaves(plan_leaves<W>(sub, slots, merge_triangles));
    for (std::uint32_t s : slots)
      if (!sub.leafish(s, merge_triangles)) e.add_child(self(self, slots_of(s)));
    return e;
  };
  Node* nodes = nullptr;
  Packet* packets = nullptr;

  // The task depth: the first wide level with enough nodes to keep every thread busy.
  const Slots root = bvh.is_leaf(0) ? Slots{0u} : slots_of(0);
  threads = threads > 0 ? threads : host_threads();
  std::uint32_t task_depth = 1;
  for (std::vector<Slots> level{root}, next; !level.empty() && level.size() < 32 * threads; ++task_depth) {
    next.clear();
    for (const Slots& n : level)
      for (std::uint32_t s : n)
        if (!sub.leafish(s, merge_triangles)) next.push_back(slots_of(s));
    level.swap(next);
  }
  // The wide subtree over `slots`, a node at `depth`. Without a cursor (the top, walked first, on
  // this thread): counts the top's own nodes and packets into top_extent and collects the subtrees
  // at task depth as tasks. With one: writes the subtree from `at` on (its root at at.node), a
  // task's place where the top meets it (the tasks' extents known by then), and moves `at` past it.
  // The top is walked once each way on this thread; each task with a cursor on some thread.
  std::vector<Task> tasks;
  Extent top_extent;
  std::size_t next_task = 0;
  auto walk = [&](auto& self, const Slots& slots, std::uint32_t depth, Cursor* at) -> std::uint32_t {
    if (!at) {
      ++top_extent.nodes;
      top_extent.depth = std::max(top_extent.depth, depth);
    }
    const auto index = static_cast<std::uint32_t>(at ? at->node++ : 0);
    const LeafPlan plan = plan_leaves<W>(sub, slots, merge_triangles);
    if (!at) top_extent.add_leaves(plan);
    // The node's packets, placed where the walk opens them (a leaf that opens one: at the cursor),
    // written empty before any leaf fills its lanes.
    std::array<std::uint64_t, 32> placed{};
    std::uint32_t opened = 0;
    Node w{};  // lanes past slots.size(): valid = 0, empty boxes, child 0 (never read)
    for (std::size_t i = 0; i < slots.size(); ++i) {
      const std::uint32_t s = slots[i];
      set_box(w, static_cast<int>(i), bvh.nodes[s]);
      w.valid.s[i] = -1;
      if (sub.leafish(s, merge_triangles)) {
        if (!at) continue;
        const RsBvhNode leaf = sub.as_leaf(s);
        for (; opened < plan.packet[i] + leaf_packets<W>(leaf.count); ++opened) {
          placed[opened] = at->packet++;
          packets[placed[opened]] = empty_packet<W, Packet>();
        }
        w.child[i] = write_leaf<W>(bvh, leaf, packets, placed[plan.packet[i]], plan.lane[i]);
      } else if (depth + 1 != task_depth) {
        w.child[i] = self(self, slots_of(s), depth + 1, at);
      } else if (!at) {
        tasks.push_back({slots_of(s), {}, {}});
      } else {
        Task& t = tasks[next_task++];
        t.at = *at;
        w.child[i] = static_cast<std::uint32_t>(at->node);
        at->node += t.extent.nodes, at->packet += t.extent.packets;
      }
    }
    if (at) nodes[index] = w;
    return index;
  };
  walk(walk, root, 1u, nullptr);
  for_each_job(threads, tasks.size(), [&](std::size_t i) { tasks[i].extent = extent_of(extent_of, tasks[i].slots); });
  Extent whole = top_extent;
  for (const Task& t : tasks) {
    whole.nodes += t.extent.nodes, whole.packets += t.extent.packets;
    whole.depth = std::max(whole.depth, task_depth - 1 + t.extent.depth);
    whole.largest_leaf = std::max(whole.largest_leaf, t.extent.largest_leaf);
  }
  if (leaf_packets<W>(whole.largest_leaf) > 4)
    throw Error("BVH leaf of " + std::to_string(whole.largest_leaf) + " triangles does not fit the " +
                std::to_string(W) + "-wide layout (at most " + std::to_string(4 * W) +
                " per leaf: lower max_leaf_size)");
  // The leaf reference's bits for the first packet (cl/bvh_layout.h): 29 at 4 lanes, 23 at 8 (lanes named too).
  const std::uint64_t max_packets = W == 8 ? RS_WIDE8_MAX_PACKETS : (1u << 29);
  if (whole.packets > max_packets)
    throw Error("scene too large for the " + std::to_string(W) + "-wide BVH layout (" + std::to_string(whole.packets) +
                " leaf packets, at most " + std::to_string(max_packets) + ")" +
                (W == 8 ? ": the wide8, stream and coherent classes cannot hold it; trace it with --layout wide, packet16 or binary"
                        : ""));
  if ((W - 1) * whole.depth > stack_size)
    throw Error(std::to_string(W) + "-wide BVH of depth " + std::to_string(whole.depth) +
                " could overflow the trace stack (" + std::to_string(stack_size) +
                " entries); the binary BVH is deeper than its bound");
  // 2 MiB pages where the kernel lends them (util/huge_pages.h): the arrays are tens of MB, filled
  // fresh; resize() leaves them unwritten (UninitVector), so each thread first touches what it
  // writes. Reserved for the largest possible tree (a wide node per binary node, a packet per W
  // triangles plus one per leaf), not the exact size: untouched room costs address space only, and
  // the exact sizes (8 and 24 MB on a 322 K-triangle scene) fall under glibc's mmap threshold once
  // it has risen, so they came from the heap on 4 KiB pages: twice the page faults per build.
  reserve_huge(out.nodes, bvh.nodes.size() + 1);
  reserve_huge(out.packets, bvh.triangles.size() / W + std::min<std::size_t>(bvh.leaf_count, bvh.nodes.size()) + 1);
  out.nodes.resize(whole.nodes);
  out.packets.resize(whole.packets);
  out.depth = whole.depth;
  nodes = out.nodes.data(), packets = out.packets.data();
  Cursor at;
  walk(walk, root, 1u, &at);
  std::vector<std::size_t> largest_first(tasks.size());
  for (std::size_t i = 0; i < tasks.size(); ++i) largest_first[i] = i;
  std::stable_sort(largest_first.begin(), largest_first.end(),
                   [&](std::size_t a, std::size_t b) { return tasks[a].extent.nodes > tasks[b].extent.nodes; });
  for_each_job(threads, tasks.size(), [&](std::size_t k) {
    const std::size_t i = largest_first[k];
    Cursor task_at = tasks[i].at;
    walk(walk, tasks[i].slots, task_depth, &task_at);
  });
  return out;
}

// The checks of validate_wide / validate_wide8 (bvh.h) on a W-wide tree whose nodes push at most
// W - 1 children each into a stack of stack_size entries.
template <int W, class Tree>
std::string validate(const Tree& wide, const Bvh& bvh, std::uint32_t stack_size) {
  if (wide.nodes.empty()) return "no root";
  if ((W - 1) * wide.depth > stack_size) return "depth " + std::to_string(wide.depth) + " exceeds the stack bound";
  std::vector<std::uint32_t> seen_node(wide.nodes.size(), 0);
  // Binary boxes, to check that each wide child box is one of them.
  auto same_box = [](const auto& w, int lane, const RsBvhNode& b) {
    return w.lo_x.s[lane] == b.bmin[0] && w.lo_y.s[lane] == b.bmin[1] && w.lo_z.s[lane] == b.bmin[2] &&
           w.hi_x.s[lane] == b.bmax[0] && w.hi_y.s[lane] == b.bmax[1] && w.hi_z.s[lane] == b.bmax[2];
  };
  // Per triangle id: its references in the binary leaf order (one, or one per part in a tree with
  // spatial splits, build_spatial_bvh), as [ref_begin[id], ref_begin[id + 1]) of refs_of, each
  // reference's binary leaf (to match a leaf reference to its box), and how many lanes hold it.
  std::uint32_t ids = 0;
  for (const RsTriangle& t : bvh.triangles) ids = std::max(ids, t.id + 1);
  std::vector<std::uint32_t> ref_begin(static_cast<std::size_t>(ids) + 1, 0), refs_of(bvh.triangles.size(), 0);
  for (const RsTriangle& t : bvh.triangles) ++ref_begin[t.id + 1];
  for (std::uint32_t id = 0; id < ids; ++id) ref_begin[id + 1] += ref_begin[id];
  {
    std::vector<std::uint32_t> at(ref_begin.begin(), ref_begin.end() - 1);
    for (std::uint32_t k = 0; k < bvh.triangles.size(); ++k) refs_of[at[bvh.triangles[k].id]++] = k;
  }
  std::vector<std::uint32_t> leaf_of_ref(bvh.triangles.size(), 0), seen_tri(ids, 0);
  for (std::uint32_t n = 0; n < bvh.nodes.size(); ++n)
    if (bvh.is_leaf(n))
      for (std::uint32_t k = bvh.nodes[n].first; k < bvh.nodes[n].first + bvh.nodes[n].count; ++k) leaf_of_ref[k] = n;
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
      const WideLeaf leaf = wide_leaf(ref, W == 8);
      const std::uint32_t first = leaf.first, end = leaf.end;
      const int own = leaf.lanes;  // the leaf's lanes of each packet
      if (W == 8 && RS_WIDE8_LEAF_LANE(ref) + RS_WIDE8_LEAF_LANE_COUNT(ref) > 8u) return "leaf lanes past the packet's eighth";
      if (W == 8 && end - first > 1 && own != 0xff) return "a leaf of several packets that shares them";
      if (end > wide.packets.size()) return "leaf packets out of range";
      for (std::uint32_t p = first; p < end; ++p)
        for (int k = 0; k < W; ++k) {
          const auto& pk = wide.packets[p];
          if (!((own >> k) & 1)) continue;  // another leaf's lane
          if (pk.valid.s[k] == 0) {
            if (W == 8 && end - first == 1)  // an 8-wide leaf's lanes in one packet are its triangles
              return "leaf of node " + std::to_string(ni) + " lane " + std::to_string(lane) + " names an empty lane";
            continue;
          }
          const std::uint32_t id = pk.id[k];
          if (id >= ids || seen_tri[id]++ == ref_begin[id + 1] - ref_begin[id])
            return "triangle " + std::to_string(id) + " bad or in more lanes than it has references";
          const RsTriangle& t = bvh.triangles[refs_of[ref_begin[id]]];
          const float lanes[9] = {pk.v0x.s[k], pk.v0y.s[k], pk.v0z.s[k], pk.v1x.s[k], pk.v1y.s[k],
                                  pk.v1z.s[k], pk.v2x.s[k], pk.v2y.s[k], pk.v2z.s[k]};
          const float verts[9] = {t.v0[0], t.v0[1], t.v0[2], t.v1[0], t.v1[1], t.v1[2], t.v2[0], t.v2[1], t.v2[2]};
          if (std::memcmp(lanes, verts, sizeof lanes) != 0)
            return "vertices of triangle " + std::to_string(id) + " not copied exactly";
          if ((pk.nondegenerate.s[k] == 0) != exactly_degenerate(t))
            return "degenerate flag of triangle " + std::to_string(id) + " wrong";
          // A wide leaf is a binary leaf or a merged small subtree: its box is that of one of the
          // triangle's binary leaves or of one of their ancestors (so it holds the triangle's part).
          bool boxed = false;
          for (std::uint32_t r = ref_begin[id]; r < ref_begin[id + 1] && !boxed; ++r) {
            std::uint32_t b = leaf_of_ref[refs_of[r]];
            while (!same_box(w, lane, bvh.nodes[b]) && b != 0) b = parent[b];
            boxed = same_box(w, lane, bvh.nodes[b]);
          }
          if (!boxed)
            return "leaf box of node " + std::to_string(ni) + " lane " + std::to_string(lane) +
                   " is not the box of triangle " + std::to_string(id) + "'s leaf or of an ancestor";
        }
    }
  }
  for (std::uint32_t id = 0; id < ids; ++id)
    if (seen_tri[id] != ref_begin[id + 1] - ref_begin[id])
      return "triangle " + std::to_string(id) + " in " + std::to_string(seen_tri[id]) + " lanes for " +
             std::to_string(ref_begin[id + 1] - ref_begin[id]) + " references";
  return "";
}

}  // namespace raysort::wide_tree
