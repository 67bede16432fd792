// Binned SAH BVH builder on every host thread, deterministic. See bvh.h.
//
// How the threads share the build without changing the tree. A node's split depends only on the
// set of triangles in its range, and a node's partition reorders only its own range; so subtrees
// build independently of each other, in any order, on any thread. The builder therefore
//  1. splits the top of the tree, each node a task of one thread (the root's bins computed by all
//     threads over chunks of its range and merged in chunk order: exact, min/max keep the first
//     of equal values, +0 or -0, as one pass in range order does; counts are sums), partitioned
//     in std::partition's order, the one the serial build always used (partition_bounded, which
//     bounds both sides on the way), so the triangle order is the same;
//  2. builds each subtree below the top (a node of at most `job_size` triangles) as a job of its
//     own, numbered locally; tasks and jobs are taken by the threads as soon as a split makes
//     them, largest first (JobStream);
//  3. lays the tree out exactly as the serial depth-first build numbers it: children allocated in
//     pairs when their parent is visited, the left subtree before the right. A subtree built with
//     local numbering (root 0, the k-th inner node's children at 1 + 2k) lands unchanged but for
//     one offset: its nodes 1.. go to next, next + 1, ..., where next is the global pair counter
//     when the serial build would have reached its root.
// One thread (or a scene below the first job size) is the serial build itself, a single job.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>

#include "bvh/bvh.h"
#include "bvh/sah_bins.h"
#include "util/error.h"
#include "util/huge_pages.h"
#include "util/parallel.h"

namespace raysort {

namespace {

using sah::BinMap;
using sah::Box;
using sah::Box4;
using sah::NodeBounds;
using sah::PrimRef;
using sah::SahBins;
using sah::Split;
using sah::set_box;

// Past this depth nodes split at the object median, so depth <= kMaxSahDepth + log2(N) < 64.
constexpr std::uint32_t kMaxSahDepth = 32;
// Nodes above this many triangles per thread are split by all threads together; smaller ones are
// a job for one thread. Per thread, so a subtree's bins cost more than the threads' start.
constexpr std::uint32_t kMinParallelPerThread = 8192;

struct Range {
  std::uint32_t begin, end, depth;
  std::uint32_t count() const { return end - begin; }
};

// The bounds of both sides of a split, found by the partition that made it (partition_bounded):
// the children's NodeBounds without a pass of their own over their ranges. Empty when the object
// median split the node (its sides were not bounded).
struct SideBounds {
  std::optional<NodeBounds> side[2];
};

// Whether a box has a coordinate equal to zero. Of equal values a box keeps the first it meets
// (the builder's rule: +0 or -0, as a pass in range order), and only for zero can two equal floats
// differ in their bits; so a box with no zero coordinate is the same whatever order its records
// were met in.
bool has_zero(const Box& b) {
  for (int a = 0; a < 3; ++a)
    if (b.lo[a] == 0.0f || b.hi[a] == 0.0f) return true;
  return false;
}

// std::partition as libstdc++ writes it (bits/stl_algo.h, the bidirectional __partition: Hoare's
// scheme, the one that built every tree so far), written out so that the same pass bounds both
// sides: each record is tested once, and is then known to stay on its side or to move to the other
// in one swap. The records end in std::partition's order on any standard library. The sides'
// boxes are those of passes in range order over them unless a coordinate is zero (has_zero); such
// a side is bounded again by that pass, so the tree is the one of separate passes, bit for bit.
// Fusing the pass saved a read of every record of every node (docs/trace.md, "BVH build").
static_assert(sizeof(PrimRef) == 32 && offsetof(PrimRef, hi) == 16, "a record is two float4 rows: lo + id, hi + pad");

template <class Pred>
PrimRef* partition_bounded(PrimRef* first, PrimRef* last, Pred pred, SideBounds& sides) {
  PrimRef* const begin = first;
  PrimRef* const end = last;
  Box4 box[2], cen[2];
  const __m128 xyz = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));  // as sah::load
  auto add_rows = [&](__m128 lo_row, __m128 hi_row, int side) {
    const __m128 lo = _mm_and_ps(lo_row, xyz), hi = _mm_and_ps(hi_row, xyz);
    box[side].grow(lo, hi);
    const __m128 m = sah::centroid(lo, hi);
    cen[side].grow(m, m);
  };
  auto rows = [](const PrimRef* r, __m128& lo_row, __m128& hi_row) {
    lo_row = _mm_loadu_ps(reinterpret_cast<const float*>(r));
    hi_row = _mm_loadu_ps(reinterpret_cast<const float*>(r) + 4);
  };
  auto add = [&](const PrimRef& r, int side) {
    __m128 lo_row, hi_row;
    rows(&r, lo_row, hi_row);
    add_rows(lo_row, hi_row, side);
  };
  PrimRef* mid = nullptr;
  while (!mid) {
    while (first != last && pred(*first)) add(*first++, 0);
    if (first == last) {
      mid = first;
      break;
    }
    --last;  // *first is on the right side (not yet counted), as std::partition found it
    while (first != last && !pred(*last)) add(*last--, 1);
    if (first == last) {
      add(*first, 1);
      mid = first;
      break;
    }
    // std::iter_swap through registers, each record bounded from the rows it was swapped with: a
    // record read back right after its swap waited on store forwarding (one instruction after it
    // held 21 % of the partition's samples).
    __m128 f_lo, f_hi, l_lo, l_hi;
    rows(first, f_lo, f_hi);
    rows(last, l_lo, l_hi);
    _mm_storeu_ps(reinterpret_cast<float*>(first), l_lo);
    _mm_storeu_ps(reinterpret_cast<float*>(first) + 4, l_hi);
    _mm_storeu_ps(reinterpret_cast<float*>(last), f_lo);
    _mm_storeu_ps(reinterpret_cast<float*>(last) + 4, f_hi);
    add_rows(l_lo, l_hi, 0);
    add_rows(f_lo, f_hi, 1);
    ++first;
  }
  const PrimRef* range[2][2] = {{begin, mid}, {mid, end}};
  for (int k = 0; k < 2; ++k) {
    NodeBounds nb{box[k].box(), cen[k].box()};
    if (has_zero(nb.bounds) || has_zero(nb.centroids)) {
      nb = NodeBounds{};
      nb.add(range[k][0], range[k][1]);
    }
    sides.side[k] = nb;
  }
  return mid;
}

// What a node becomes once its bounds and best split are known: a leaf (nullopt), or an inner
// node whose range is now partitioned at the returned middle, with its sides' bounds in `sides`
// when the SAH split made it. The serial builder's rules: SAH split when it is cheaper than a leaf
// or the leaf would be too big; the object median when no SAH split exists or it leaves a side
// empty.
std::optional<std::uint32_t> split_or_leaf(std::vector<PrimRef>& refs, const Range& r, const NodeBounds& nb,
                                           const Split& split, std::uint32_t nbins, const BvhBuildOptions& opts,
                                           SideBounds& sides) {
  sides = SideBounds{};
  const std::uint32_t count = r.count();
  if (count == 1) return std::nullopt;
  const float parent_area = nb.bounds.area();
  const float leaf_cost = opts.intersection_cost * static_cast<float>(count);
  const float split_cost = split.axis >= 0 && parent_area > 0.0f
                               ? opts.traversal_cost + opts.intersection_cost * split.cost / parent_area
                               : 3.0e38f;
  std::uint32_t mid = 0;
  if (split.axis >= 0 && (split_cost < leaf_cost || count > opts.max_leaf_size)) {
    const BinMap map(nb.centroids, nbins);
    const int a = split.axis;
    PrimRef* it = partition_bounded(refs.data() + r.begin, refs.data() + r.end,
                                    [&](const PrimRef& p) { return map.bin(p, a) <= split.bin; }, sides);
    mid = static_cast<std::uint32_t>(it - refs.data());
  } else if (count <= opts.max_leaf_size) {
    return std::nullopt;
  }
  if (mid <= r.begin || mid >= r.end) {
    sides = SideBounds{};
    // The object median along the widest centroid axis, ties broken by id so the result is deterministic.
    const Box& cb = nb.centroids;
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (cb.hi[a] - cb.lo[a] > cb.hi[axis] - cb.lo[axis]) axis = a;
    mid = r.begin + count / 2;
    std::nth_element(refs.begin() + r.begin, refs.begin() + mid, refs.begin() + r.end,
                     [&](const PrimRef& x, const PrimRef& y) {
                       const float cx = x.centroid(axis), cy = y.centroid(axis);
                       return cx < cy || (cx == cy && x.id < y.id);
                     });
  }
  return mid;
}

// A subtree built by one thread, numbered as the serial build numbers a tree: root 0, children in
// pairs, depth first, left first. Leaves index the global triangle order.
struct Subtree {
  std::vector<RsBvhNode> nodes;
  std::uint32_t depth = 0, leaves = 0;
};

// A node waiting to be split: where it goes, its triangles and, when its parent's partition found
// them, their bounds.
struct Task {
  std::uint32_t node;
  Range range;
  std::optional<NodeBounds> bounds;
};

// root_bounds: the root's bounds when known (else computed here).
Subtree build_subtree(std::vector<PrimRef>& refs, const Range& root, const std::optional<NodeBounds>& root_bounds,
                      std::uint32_t nbins, const BvhBuildOptions& opts) {
  Subtree t;
  reserve_huge(t.nodes, 2 * root.count() / std::max<std::uint32_t>(1, opts.max_leaf_size / 2) + 1);
  t.nodes.push_back({});
  SahBins bins(nbins);
  SideBounds sides;
  std::vector<Task> stack{{0, root, root_bounds}};
  while (!stack.empty()) {
    const Task task = stack.back();
    stack.pop_back();
    const Range& r = task.range;
    // In range order, as the serial build: of equal values (+0 and -0) a box keeps the first met.
    NodeBounds nb;
    if (task.bounds)
      nb = *task.bounds;
    else
      nb.add(refs.data() + r.begin, refs.data() + r.end);
    set_box(t.nodes[task.node], nb.bounds);
    t.depth = std::max(t.depth, r.depth);
    Split split;
    if (r.count() > 1 && r.depth < kMaxSahDepth) {
      const BinMap map(nb.centroids, nbins);
      bins.clear();
      bins.add(refs.data() + r.begin, refs.data() + r.end, map);
      split = bins.best(map);
    }
    const std::optional<std::uint32_t> mid = split_or_leaf(refs, r, nb, split, nbins, opts, sides);
    if (!mid) {
      t.nodes[task.node].first = r.begin;
      t.nodes[task.node].count = r.count();
      ++t.leaves;
      continue;
    }
    const auto left = static_cast<std::uint32_t>(t.nodes.size());
    t.nodes.push_back({});
    t.nodes.push_back({});
    t.nodes[task.node].first = left;
    t.nodes[task.node].count = 0;
    // Right first on the stack so the left subtree is laid out first (depth-first order).
    stack.push_back({left + 1, {*mid, r.end, r.depth + 1}, sides.side[1]});
    stack.push_back({left, {r.begin, *mid, r.depth + 1}, sides.side[0]});
  }
  return t;
}

// A node of the top of the tree (split by all threads): an inner node with its two children among
// the top nodes, a leaf, or the root of a job's subtree.
struct TopNode {
  Range range;
  std::optional<NodeBounds> bounds;  // from the parent's partition, or computed when the node is split
  std::int32_t left = -1;  // inner: the left child's index among the top nodes, the right one next to it
  std::int32_t job = -1;   // the root of subtree `job`
};

// The bounds of refs[begin, end), computed by `threads` threads over chunks and merged in chunk
// order (grow keeps the earlier of equal values): those of one pass in range order, bit for bit.
NodeBounds bounds_of(const std::vector<PrimRef>& refs, std::uint32_t begin, std::uint32_t end, unsigned threads) {
  std::vector<NodeBounds> part(threads);
  const std::size_t chunk = (end - begin + threads - 1) / threads;
  for_each_chunk_on(threads, end - begin, [&](std::size_t b, std::size_t e) {
    part[b / chunk].add(refs.data() + begin + b, refs.data() + begin + e);
  });
  NodeBounds nb;
  for (const NodeBounds& p : part) nb.merge(p);
  return nb;
}

// A top node's split: its bins computed by `threads` threads over chunks and merged. Returns its
// children (range and bounds), none for a leaf.
std::optional<std::pair<TopNode, TopNode>> split_top_node(std::vector<PrimRef>& refs, const TopNode& t, unsigned threads,
                                                          std::uint32_t nbins, const BvhBuildOptions& opts) {
  const Range r = t.range;
  const NodeBounds nb = *t.bounds;
  const PrimRef* base = refs.data() + r.begin;
  std::vector<SahBins> bins(threads, SahBins(nbins));
  auto chunk_of = [&](std::size_t b) { return static_cast<unsigned>(b / ((r.count() + threads - 1) / threads)); };
  Split split;
  if (r.depth < kMaxSahDepth) {
    const BinMap map(nb.centroids, nbins);
    for (SahBins& b : bins) b.clear();
    for_each_chunk_on(threads, r.count(), [&](std::size_t b, std::size_t e) { bins[chunk_of(b)].add(base + b, base + e, map); });
    for (unsigned k = 1; k < threads; ++k) bins[0].merge(bins[k]);
    split = bins[0].best(map);
  }
  SideBounds sides;
  const std::optional<std::uint32_t> mid = split_or_leaf(refs, r, nb, split, nbins, opts, sides);
  if (!mid) return std::nullopt;
  return std::pair<TopNode, TopNode>{TopNode{{r.begin, *mid, r.depth + 1}, sides.side[0]},
                                     TopNode{{*mid, r.end, r.depth + 1}, sides.side[1]}};
}

struct Layout {
  UninitVector<RsBvhNode>& nodes;
  const std::deque<TopNode>& top;
  std::vector<std::uint32_t>& job_offset;  // per job: where its nodes 1.. start (`next` at its root)
  std::vector<std::uint32_t>& job_slot;    // per job: where its root goes
  const std::deque<Subtree>& jobs;
  std::uint32_t next = 1;
  std::uint32_t leaves = 0;

  // Writes top node i at `slot` and numbers what lies below it, as the serial build would.
  void place(std::size_t i, std::uint32_t slot) {
    const TopNode& t = top[i];
    if (t.job >= 0) {
      job_slot[t.job] = slot;
      job_offset[t.job] = next;
      next += static_cast<std::uint32_t>(jobs[t.job].nodes.size()) - 1;
      return;
    }
    set_box(nodes[slot], t.bounds->bounds);
    if (t.left < 0) {
      nodes[slot].first = t.range.begin;
      nodes[slot].count = t.range.count();
      ++leaves;
      return;
    }
    const std::uint32_t pair = next;
    next += 2;
    nodes[slot].first = pair;
    nodes[slot].count = 0;
    place(static_cast<std::size_t>(t.left), pair);
    place(static_cast<std::size_t>(t.left) + 1, pair + 1);
  }
};

// Copies a job's subtree into the tree: root at its slot, nodes 1.. from its offset on, children
// references moved by the same offset.
void copy_job(UninitVector<RsBvhNode>& nodes, const Subtree& s, std::uint32_t slot, std::uint32_t offset) {
  for (std::size_t k = 0; k < s.nodes.size(); ++k) {
    RsBvhNode n = s.nodes[k];
    if (n.count == 0) n.first = n.first - 1 + offset;
    nodes[k == 0 ? slot : offset + static_cast<std::uint32_t>(k) - 1] = n;
  }
}

std::vector<PrimRef> primitives_of(const Scene::Flat& tris, unsigned threads) {
  std::vector<PrimRef> refs = huge_vector<PrimRef>(tris.size());
  for_each_chunk_on(threads, tris.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      Box box;
      box.grow(tris.v0[i].data());
      box.grow(tris.v1[i].data());
      box.grow(tris.v2[i].data());
      PrimRef& r = refs[i];
      for (int a = 0; a < 3; ++a) {
        r.lo[a] = box.lo[a];
        r.hi[a] = box.hi[a];
      }
      r.id = static_cast<std::uint32_t>(i);
      r.pad = 0;
    }
  });
  return refs;
}

// The triangles in leaf order (what the nodes' first/count index), with their original ids; every
// one written here, on all threads (UninitVector: not zeroed first on this one).
UninitVector<RsTriangle> leaf_ordered(const Scene::Flat& tris, const std::vector<PrimRef>& refs, unsigned threads) {
  UninitVector<RsTriangle> out = huge_vector<RsTriangle, DefaultInitAllocator<RsTriangle>>(refs.size());
  for_each_chunk_on(threads, refs.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const std::uint32_t t = refs[k].id;
      RsTriangle& tri = out[k];
      for (int a = 0; a < 3; ++a) {
        tri.v0[a] = tris.v0[t][a];
        tri.v1[a] = tris.v1[t][a];
        tri.v2[a] = tris.v2[t][a];
      }
      tri.id = t;
      tri.pad0 = tri.pad1 = 0;
    }
  });
  return out;
}

// Steps 1-3 of the file comment: the binary tree over refs, which it leaves in leaf order.
void build_binary(Bvh& bvh, std::vector<PrimRef>& refs, unsigned threads, const BvhBuildOptions& opts) {
  const std::uint32_t nbins = std::max<std::uint32_t>(2, opts.bins);
  const auto n = static_cast<std::uint32_t>(refs.size());
  const std::uint32_t job_size = threads > 1 ? std::max(kMinParallelPerThread * threads, n / (8 * threads)) : n;
  // Every split is a task: a node above job_size is split by the thread that takes it, which then
  // adds its children as tasks, and a node of at most job_size is a job (its whole subtree). So
  // both threads split the top as soon as the root's children exist, and build subtrees as soon
  // as the first ones exist (JobStream: the largest pending first). The root alone is binned by
  // all threads. Partitions keep std::partition's order, one thread each; which thread split what
  // never shows in the tree (the layout walks the top by its links, below). Deques: their elements
  // stay where they are while others are added (under `mutex`).
  std::deque<TopNode> top{{{0, n, 0}, std::nullopt}};
  std::deque<Subtree> jobs;
  std::mutex mutex;
  {
    JobStream stream(threads);
    std::function<void(std::size_t)> add_task;
    auto split_task = [&](std::size_t i) {
      TopNode t;
      {
        std::lock_guard<std::mutex> lock(mutex);
        t = top[i];
      }
      const unsigned split_threads = i == 0 ? threads : 1;
      if (!t.bounds) t.bounds = bounds_of(refs, t.range.begin, t.range.end, split_threads);
      const auto children = split_top_node(refs, t, split_threads, nbins, opts);
      std::size_t left = 0;
      {
        std::lock_guard<std::mutex> lock(mutex);
        top[i].bounds = t.bounds;
        if (!children) return;  // a leaf: left and job stay -1
        left = top.size();
        top[i].left = static_cast<std::int32_t>(left);
        top.push_back(children->first);
        top.push_back(children->second);
      }
      add_task(left);
      add_task(left + 1);
    };
    add_task = [&](std::size_t i) {
      std::unique_lock<std::mutex> lock(mutex);
      TopNode& t = top[i];
      const std::uint32_t count = t.range.count();
      if (count > job_size) {
        lock.unlock();
        stream.add(count, [&split_task, i] { split_task(i); });
        return;
      }
      t.job = static_cast<std::int32_t>(jobs.size());
      Subtree& out = jobs.emplace_back();
      const Range range = t.range;
      const std::optional<NodeBounds> bounds = t.bounds;
      lock.unlock();
      stream.add(count, [&refs, &out, &opts, nbins, range, bounds] { out = build_subtree(refs, range, bounds, nbins, opts); });
    };
    add_task(0);
    stream.finish();
  }
  std::vector<std::uint32_t> offset(jobs.size()), slot(jobs.size());
  std::size_t total = 0;
  for (const TopNode& t : top) total += t.job >= 0 ? jobs[t.job].nodes.size() : 1;
  bvh.nodes = huge_vector<RsBvhNode, DefaultInitAllocator<RsBvhNode>>(total);  // every node written below
  Layout layout{bvh.nodes, top, offset, slot, jobs};
  layout.place(0, 0);
  bvh.leaf_count = layout.leaves;
  for (const TopNode& t : top) bvh.depth = std::max(bvh.depth, t.range.depth);
  for (const Subtree& s : jobs) {
    bvh.leaf_count += s.leaves;
    bvh.depth = std::max(bvh.depth, s.depth);
  }
  for_each_job(threads, jobs.size(), [&](std::size_t j) { copy_job(bvh.nodes, jobs[j], slot[j], offset[j]); });
}

}  // namespace

Aabb Bvh::bounds() const {
  Aabb b;
  if (nodes.empty()) return b;
  b.min = {nodes[0].bmin[0], nodes[0].bmin[1], nodes[0].bmin[2]};
  b.max = {nodes[0].bmax[0], nodes[0].bmax[1], nodes[0].bmax[2]};
  return b;
}

Bvh build_bvh(const Scene::Flat& tris, const BvhBuildOptions& opts) {
  auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = tris.size();
  if (n == 0) throw Error("cannot build a BVH over a scene with no triangles");
  if (n >= 0xFFFFFFF0u) throw Error("scene has too many triangles for 32-bit indices");
  const unsigned threads = opts.threads > 0 ? opts.threads : host_threads();
  std::vector<PrimRef> refs = primitives_of(tris, threads);
  Bvh bvh;
  build_binary(bvh, refs, threads, opts);
  bvh.triangles = leaf_ordered(tris, refs, threads);
  bvh.wide = collapse_to_wide(bvh, threads);
  bvh.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  bvh.sah_cost = sah_cost(bvh, opts);
  return bvh;
}

}  // namespace raysort
