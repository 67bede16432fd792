// The spatial-split BVH (SBVH; Stich, Friedrich and Dietrich 2009, "Spatial Splits in Bounding Volume
// Hierarchies"), the binary tree the 8-wide classes' collapse starts from (split_tree, bvh.h). Each
// node is split as build_sah.cpp splits it (binned SAH over the references' centroids), unless a
// plane through the node's box is cheaper: a triangle that straddles that plane is then referenced
// from both sides, each side's reference boxing only the triangle's part on that side, so boxes
// overlap less where large triangles meet small ones (the paper's section 4, with reference
// unsplitting, its section 4.3). Spatial splits are tried only where the object split's children
// overlap by more than a small fraction of the root's area (its alpha), and a subtree may add at
// most its share of a budget of references.
//
// Deterministic, whatever the thread count: a node's split depends only on its references (their
// boxes and order); both sides keep their references in the node's order; the budget is handed
// down by counts; bins of chunks merge exactly (min/max boxes, summed counts), as build_sah.cpp's;
// and the tree is laid out as the serial depth-first build numbers it (children in pairs when
// their parent is split, left subtree first), whichever thread built which subtree.
//
// Conservative: a reference's box holds its part of the triangle exactly. Where an edge crosses a
// plane, the crossing is computed in double (far below a float step off) and rounded outward to
// floats one step further out; the plane's own coordinate is exact. So every point of a triangle
// lies in the box of one of its references, and a ray that hits it enters a leaf that holds it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

#include "bvh/bvh.h"
#include "bvh/sah_bins.h"
#include "util/error.h"
#include "util/parallel.h"

namespace raysort {

// Named apart from build_sah.cpp's helpers (a unity build compiles both files as one).
namespace spatial_build {
namespace {

using sah::BinMap;
using sah::Box;
using sah::NodeBounds;
using sah::PrimRef;
using sah::SahBins;
using sah::Split;
using sah::set_box;

// As build_sah.cpp: past this depth, nodes split at the object median (and never spatially).
constexpr std::uint32_t kMaxSahDepth = 32;
// Planes per axis of a node's box: kSpatialBins - 1 (Stich et al. bin too; Embree uses 16).
constexpr std::uint32_t kSpatialBins = 16;
// Spatial splits are tried where the object split's children overlap by more than this fraction of
// the root's surface area (Stich et al.'s alpha, their value).
constexpr float kOverlapFraction = 1.0e-5f;
// Nodes of more references than this per thread are split by one thread each (the root by all);
// smaller ones are a job: their whole subtree on one thread.
constexpr std::uint32_t kMinParallelPerThread = 4096;

// The triangles the tree is built over: a reference's id is an index into them.
using Source = UninitVector<RsTriangle>;

bool is_empty(const Box& b) {
  for (int k = 0; k < 3; ++k)
    if (b.lo[k] > b.hi[k]) return true;
  return false;
}

Box intersect(const Box& a, const Box& b) {
  Box o;
  for (int k = 0; k < 3; ++k) {
    o.lo[k] = std::max(a.lo[k], b.lo[k]);
    o.hi[k] = std::min(a.hi[k], b.hi[k]);
  }
  return o;
}

Box box_of(const PrimRef& r) {
  Box b;
  b.grow(r.lo, r.hi);
  return b;
}

PrimRef ref_of(const Box& b, std::uint32_t id) {
  PrimRef r;
  for (int k = 0; k < 3; ++k) r.lo[k] = b.lo[k], r.hi[k] = b.hi[k];
  r.id = id;
  r.pad = 0;
  return r;
}

// A float below (above) x by at least one float step: x, a crossing computed in double, is off by
// far less than a step, so the float holds the exact crossing.
float below(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -INFINITY);
  return std::nextafter(f, -INFINITY);
}
float above(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, INFINITY);
  return std::nextafter(f, INFINITY);
}

struct Halves {
  Box left, right;  // either may be empty (is_empty)
};

// The part of triangle t inside `box`, cut by the plane x[axis] = pos: the boxes of its parts on
// both sides, each inside `box` and holding its part exactly (see the top of the file).
Halves split_reference(const RsTriangle& t, const Box& box, int axis, float pos) {
  const float* v[3] = {t.v0, t.v1, t.v2};
  Halves h;
  for (int i = 0; i < 3; ++i) {
    const float* a = v[i];
    const float* b = v[(i + 1) % 3];
    if (a[axis] <= pos) h.left.grow(a);
    if (a[axis] >= pos) h.right.grow(a);
    if ((a[axis] < pos && pos < b[axis]) || (b[axis] < pos && pos < a[axis])) {
      const double s = (static_cast<double>(pos) - a[axis]) / (static_cast<double>(b[axis]) - a[axis]);
      float lo[3], hi[3];
      for (int k = 0; k < 3; ++k) {
        if (k == axis) {
          lo[k] = hi[k] = pos;
          continue;
        }
        const double x = a[k] + s * (static_cast<double>(b[k]) - a[k]);
        lo[k] = below(x), hi[k] = above(x);
      }
      h.left.grow(lo, hi);
      h.right.grow(lo, hi);
    }
  }
  h.left = intersect(h.left, box);
  h.right = intersect(h.right, box);
  h.left.hi[axis] = std::min(h.left.hi[axis], pos);
  h.right.lo[axis] = std::max(h.right.lo[axis], pos);
  return h;
}

// A node's planes on one axis: pos[0] = its box's low side, pos[kSpatialBins] its high side.
struct Planes {
  float pos[kSpatialBins + 1];
  float lo = 0.0f, scale = 0.0f;  // scale 0: no extent, no planes
  Planes(const Box& node, int a) {
    const float ext = node.hi[a] - node.lo[a];
    lo = node.lo[a];
    if (!(ext > 0.0f)) return;
    scale = static_cast<float>(kSpatialBins) / ext;
    for (std::uint32_t b = 0; b < kSpatialBins; ++b) pos[b] = lo + ext * (static_cast<float>(b) / kSpatialBins);
    pos[kSpatialBins] = node.hi[a];
  }
  // The bins a reference spans, [first, last], by the partition's rule: a box that ends on plane b
  // lies left of it, one that starts on it right of it (a flat box on it: left).
  std::pair<std::uint32_t, std::uint32_t> span(float r_lo, float r_hi) const {
    auto guess = [&](float x) {
      return static_cast<std::int32_t>(std::clamp((x - lo) * scale, 0.0f, static_cast<float>(kSpatialBins - 1)));
    };
    std::int32_t last = guess(r_hi);
    while (last > 0 && r_hi <= pos[last]) --last;
    while (last < static_cast<std::int32_t>(kSpatialBins) - 1 && r_hi > pos[last + 1]) ++last;
    std::int32_t first = guess(r_lo);
    while (first > 0 && r_lo < pos[first]) --first;
    while (first < static_cast<std::int32_t>(kSpatialBins) - 1 && r_lo >= pos[first + 1]) ++first;
    return {static_cast<std::uint32_t>(std::min(first, last)), static_cast<std::uint32_t>(last)};
  }
};

// A node's spatial bins, all three axes: the boxes of the references' parts in each bin, and how
// many references start (enter) and end (exit) in each. Bins of chunks merge exactly.
struct SpatialBins {
  Box box[3][kSpatialBins];
  std::uint32_t enter[3][kSpatialBins] = {}, exit[3][kSpatialBins] = {};
  void add(const Source& src, const PrimRef* begin, const PrimRef* end, const Box& node) {
    for (int a = 0; a < 3; ++a) {
      const Planes planes(node, a);
      if (planes.scale == 0.0f) continue;
      for (const PrimRef* r = begin; r != end; ++r) {
        const auto [first, last] = planes.span(r->lo[a], r->hi[a]);
        ++enter[a][first];
        ++exit[a][last];
        Box part = box_of(*r);
        for (std::uint32_t b = first; b < last && !is_empty(part); ++b) {
          const Halves h = split_reference(src[r->id], part, a, planes.pos[b + 1]);
          if (!is_empty(h.left)) box[a][b].grow(h.left);
          part = h.right;
        }
        if (!is_empty(part)) box[a][last].grow(part);
      }
    }
  }
  void merge(const SpatialBins& o) {
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t b = 0; b < kSpatialBins; ++b) {
        box[a][b].grow(o.box[a][b]);
        enter[a][b] += o.enter[a][b];
        exit[a][b] += o.exit[a][b];
      }
  }
};

// The cheapest plane of a node's spatial bins: cost as Split::cost (left area · count + right area ·
// count), the sides' boxes and counts (every straddling reference on both), for the partition.
struct SpatialSplit {
  int axis = -1;  // -1: none
  float pos = 0.0f;
  float cost = 3.0e38f;
  Box left, right;
  std::uint32_t left_n = 0, right_n = 0;
};

SpatialSplit best_spatial_split(const SpatialBins& bins, const Box& node) {
  SpatialSplit best;
  for (int a = 0; a < 3; ++a) {
    const Planes planes(node, a);
    if (planes.scale == 0.0f) continue;
    Box right[kSpatialBins];  // right[b]: bins b.. together
    Box acc;
    for (std::uint32_t b = kSpatialBins - 1; b >= 1; --b) {
      acc.grow(bins.box[a][b]);
      right[b] = acc;
    }
    std::uint32_t right_n = 0;
    for (std::uint32_t b = 0; b < kSpatialBins; ++b) right_n += bins.exit[a][b];
    Box left;
    std::uint32_t left_n = 0;
    for (std::uint32_t b = 0; b + 1 < kSpatialBins; ++b) {  // the plane after bin b
      left.grow(bins.box[a][b]);
      left_n += bins.enter[a][b];
      right_n -= bins.exit[a][b];
      if (left_n == 0 || right_n == 0) continue;
      const float cost = left.area() * static_cast<float>(left_n) + right[b + 1].area() * static_cast<float>(right_n);
      if (cost < best.cost) best = {a, planes.pos[b + 1], cost, left, right[b + 1], left_n, right_n};
    }
  }
  return best;
}

// A node to build: its references (ids index the source), depth, and how many references its
// subtree may still add by splitting.
struct Work {
  std::vector<PrimRef> refs;
  std::uint32_t depth = 0;
  std::uint64_t budget = 0;
};

// The references of w on each side of a spatial split, straddlers split or, where cheaper, kept
// whole on one side (reference unsplitting). Empty sides when the split makes no progress or
// overruns the budget.
std::pair<std::vector<PrimRef>, std::vector<PrimRef>> spatial_partition(const Source& src, const Work& w,
                                                                        const SpatialSplit& s) {
  std::vector<PrimRef> left, right;
  const int a = s.axis;
  const float al = s.left.area(), ar = s.right.area();
  const float nl = static_cast<float>(s.left_n), nr = static_cast<float>(s.right_n);
  const float c_split = al * nl + ar * nr;
  for (const PrimRef& p : w.refs) {
    if (p.hi[a] <= s.pos) {
      left.push_back(p);
    } else if (p.lo[a] >= s.pos) {
      right.push_back(p);
    } else {
      const Box whole = box_of(p);
      Box l = s.left, r = s.right;
      l.grow(whole);
      r.grow(whole);
      const float c_left = l.area() * nl + ar * (nr - 1.0f);
      const float c_right = al * (nl - 1.0f) + r.area() * nr;
      if (c_left <= c_split && c_left <= c_right) {
        left.push_back(p);
      } else if (c_right <= c_split) {
        right.push_back(p);
      } else {
        const Halves h = split_reference(src[p.id], whole, a, s.pos);
        if (!is_empty(h.left)) left.push_back(ref_of(h.left, p.id));
        if (!is_empty(h.right)) right.push_back(ref_of(h.right, p.id));
      }
    }
  }
  if (left.empty() || right.empty() || left.size() + right.size() - w.refs.size() > w.budget) return {};
  return {std::move(left), std::move(right)};
}

// Node w's box, and its two children, or none for a leaf; on `threads` threads (the bins of
// chunks merged in chunk order). The leaf rule is build_sah.cpp's: split when the cheaper split
// costs less than a leaf or the leaf would hold more than max_leaf_size references; the object
// median when no split separates them.
std::optional<std::pair<Work, Work>> split_node(const Source& src, Work& w, const BvhBuildOptions& opts,
                                                float overlap_min, unsigned threads, Box& box) {
  const auto n = static_cast<std::uint32_t>(w.refs.size());
  const PrimRef* refs = w.refs.data();
  const std::size_t chunk = (n + threads - 1) / threads;
  std::vector<NodeBounds> parts(threads);
  for_each_chunk_on(threads, n, [&](std::size_t b, std::size_t e) { parts[b / chunk].add(refs + b, refs + e); });
  NodeBounds nb;
  for (const NodeBounds& p : parts) nb.merge(p);
  box = nb.bounds;
  if (n == 1) return std::nullopt;
  const std::uint32_t nbins = std::max<std::uint32_t>(2, opts.bins);
  const BinMap map(nb.centroids, nbins);
  Split split;
  SpatialSplit spatial;
  if (w.depth < kMaxSahDepth) {
    std::vector<SahBins> bins(threads, SahBins(nbins));
    for (SahBins& b : bins) b.clear();
    for_each_chunk_on(threads, n, [&](std::size_t b, std::size_t e) { bins[b / chunk].add(refs + b, refs + e, map); });
    for (unsigned k = 1; k < threads; ++k) bins[0].merge(bins[k]);
    split = bins[0].best(map);
    if (split.axis >= 0 && w.budget > 0) {
      Box l, r;  // the object split's sides: a spatial split is tried only where they overlap
      for (const PrimRef& p : w.refs) (map.bin(p, split.axis) <= split.bin ? l : r).grow(p.lo, p.hi);
      const Box overlap = intersect(l, r);
      if (!is_empty(overlap) && overlap.area() > overlap_min) {
        std::vector<SpatialBins> sb(threads);
        for_each_chunk_on(threads, n, [&](std::size_t b, std::size_t e) { sb[b / chunk].add(src, refs + b, refs + e, nb.bounds); });
        for (unsigned k = 1; k < threads; ++k) sb[0].merge(sb[k]);
        spatial = best_spatial_split(sb[0], nb.bounds);
      }
    }
  }
  const bool try_spatial = spatial.axis >= 0 && spatial.cost < split.cost;
  const float best_cost = try_spatial ? spatial.cost : split.cost;
  const float area = nb.bounds.area();
  const float split_cost = best_cost < 3.0e38f && area > 0.0f
                               ? opts.traversal_cost + opts.intersection_cost * best_cost / area
                               : 3.0e38f;
  if (!(split_cost < opts.intersection_cost * static_cast<float>(n)) && n <= opts.max_leaf_size) return std::nullopt;
  std::pair<std::vector<PrimRef>, std::vector<PrimRef>> sides;
  if (try_spatial) sides = spatial_partition(src, w, spatial);
  if (sides.first.empty() && split.axis >= 0) {
    for (const PrimRef& p : w.refs) (map.bin(p, split.axis) <= split.bin ? sides.first : sides.second).push_back(p);
    if (sides.first.empty() || sides.second.empty()) sides = {};
  }
  if (sides.first.empty()) {
    // The object median along the widest centroid axis, ties broken by reference id.
    const Box& cb = nb.centroids;
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (cb.hi[a] - cb.lo[a] > cb.hi[axis] - cb.lo[axis]) axis = a;
    std::vector<PrimRef> sorted = w.refs;
    std::stable_sort(sorted.begin(), sorted.end(), [&](const PrimRef& x, const PrimRef& y) {
      const float cx = x.centroid(axis), cy = y.centroid(axis);
      return cx < cy || (cx == cy && x.id < y.id);
    });
    sides.first.assign(sorted.begin(), sorted.begin() + n / 2);
    sides.second.assign(sorted.begin() + n / 2, sorted.end());
  }
  // What is left of the budget goes to both sides by their sizes.
  const std::uint64_t l = sides.first.size(), r = sides.second.size();
  const std::uint64_t rest = w.budget - (l + r - n);
  const std::uint64_t left_budget = rest * l / (l + r);
  std::vector<PrimRef>().swap(w.refs);
  return std::pair<Work, Work>{Work{std::move(sides.first), w.depth + 1, left_budget},
                               Work{std::move(sides.second), w.depth + 1, rest - left_budget}};
}

// A subtree built by one thread, numbered as the serial build numbers a tree (root 0, children in
// pairs, depth first, left first); its leaves index its own `order` (source indices, leaf order).
struct Subtree {
  std::vector<RsBvhNode> nodes;
  std::vector<std::uint32_t> order;
  std::uint32_t depth = 0, leaves = 0;
};

Subtree build_subtree(const Source& src, Work root, const BvhBuildOptions& opts, float overlap_min) {
  Subtree t;
  t.nodes.push_back({});
  std::vector<std::pair<std::uint32_t, Work>> stack;
  stack.emplace_back(0u, std::move(root));
  while (!stack.empty()) {
    auto [node, w] = std::move(stack.back());
    stack.pop_back();
    t.depth = std::max(t.depth, w.depth);
    Box box;
    auto children = split_node(src, w, opts, overlap_min, 1, box);
    set_box(t.nodes[node], box);
    if (!children) {
      t.nodes[node].first = static_cast<std::uint32_t>(t.order.size());
      t.nodes[node].count = static_cast<std::uint32_t>(w.refs.size());
      for (const PrimRef& p : w.refs) t.order.push_back(p.id);
      ++t.leaves;
      continue;
    }
    const auto left = static_cast<std::uint32_t>(t.nodes.size());
    t.nodes.push_back({});
    t.nodes.push_back({});
    t.nodes[node].first = left;
    t.nodes[node].count = 0;
    stack.emplace_back(left + 1, std::move(children->second));  // right first: the left subtree is laid out first
    stack.emplace_back(left, std::move(children->first));
  }
  return t;
}

// A node of the top of the tree (split by one thread each, the root by all): inner, a leaf, or a job's root.
struct TopNode {
  Work work;  // until it is split or handed to a job
  Box box;
  std::vector<std::uint32_t> leaf;  // a leaf's references (source indices)
  std::uint32_t depth = 0;
  std::int32_t left = -1;  // inner: the left child's index among the top nodes, the right one next to it
  std::int32_t job = -1;
};

Bvh build(const Bvh& plain, const BvhBuildOptions& opts, double budget) {
  const auto t0 = std::chrono::steady_clock::now();
  const Source& src = plain.triangles;
  const std::size_t count = src.size();
  if (count == 0) throw Error("cannot build a BVH over a scene with no triangles");
  const std::uint64_t max_refs = static_cast<std::uint64_t>(static_cast<double>(count) * (1.0 + budget));
  if (max_refs >= 0xFFFFFFF0u) throw Error("scene has too many triangles for 32-bit indices with spatial splits");
  const unsigned threads = opts.threads > 0 ? opts.threads : host_threads();
  Work root{std::vector<PrimRef>(count), 0, max_refs - count};
  for_each_chunk_on(threads, count, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      Box box;
      box.grow(src[i].v0);
      box.grow(src[i].v1);
      box.grow(src[i].v2);
      root.refs[i] = ref_of(box, static_cast<std::uint32_t>(i));
    }
  });
  Box root_box;
  root_box.grow(plain.nodes[0].bmin, plain.nodes[0].bmax);
  const float overlap_min = kOverlapFraction * root_box.area();
  const std::uint32_t job_size = threads > 1 ? kMinParallelPerThread * threads : 0xFFFFFFFFu;

  std::deque<TopNode> top;
  top.push_back({std::move(root), {}, {}, 0});
  std::deque<Subtree> jobs;
  std::mutex mutex;
  {
    JobStream stream(threads);
    std::function<void(std::size_t)> add_task;
    auto split_task = [&](std::size_t i) {
      Work w;
      {
        std::lock_guard<std::mutex> lock(mutex);
        w = std::move(top[i].work);
      }
      Box box;
      auto children = split_node(src, w, opts, overlap_min, i == 0 ? threads : 1, box);
      std::size_t left = 0;
      {
        std::lock_guard<std::mutex> lock(mutex);
        top[i].box = box;
        if (!children) {
          for (const PrimRef& p : w.refs) top[i].leaf.push_back(p.id);
          return;
        }
        left = top.size();
        top[i].left = static_cast<std::int32_t>(left);
        top.push_back({std::move(children->first), {}, {}, w.depth + 1});
        top.push_back({std::move(children->second), {}, {}, w.depth + 1});
      }
      add_task(left);
      add_task(left + 1);
    };
    add_task = [&](std::size_t i) {
      std::unique_lock<std::mutex> lock(mutex);
      TopNode& t = top[i];
      const auto n = static_cast<std::uint32_t>(t.work.refs.size());
      if (n > job_size) {
        lock.unlock();
        stream.add(n, [&split_task, i] { split_task(i); });
        return;
      }
      t.job = static_cast<std::int32_t>(jobs.size());
      Subtree& out = jobs.emplace_back();
      auto w = std::make_shared<Work>(std::move(t.work));
      lock.unlock();
      stream.add(n, [&src, &out, &opts, overlap_min, w] { out = build_subtree(src, std::move(*w), opts, overlap_min); });
    };
    add_task(0);
    stream.finish();
  }

  // Lay the tree out as the serial build numbers it (see the top of the file).
  std::size_t total_nodes = 0, total_refs = 0;
  for (const TopNode& t : top) {
    total_nodes += t.job >= 0 ? jobs[t.job].nodes.size() : 1;
    total_refs += t.job >= 0 ? jobs[t.job].order.size() : t.leaf.size();
  }
  Bvh bvh;
  bvh.nodes.resize(total_nodes);
  std::vector<std::uint32_t> order(total_refs);
  std::vector<std::uint32_t> job_slot(jobs.size()), job_node(jobs.size()), job_ref(jobs.size());
  std::uint32_t next = 1, next_ref = 0;
  std::function<void(std::size_t, std::uint32_t)> place = [&](std::size_t i, std::uint32_t slot) {
    const TopNode& t = top[i];
    bvh.depth = std::max(bvh.depth, t.depth);
    if (t.job >= 0) {
      const Subtree& s = jobs[t.job];
      job_slot[t.job] = slot, job_node[t.job] = next, job_ref[t.job] = next_ref;
      next += static_cast<std::uint32_t>(s.nodes.size()) - 1;
      next_ref += static_cast<std::uint32_t>(s.order.size());
      return;
    }
    set_box(bvh.nodes[slot], t.box);
    if (t.left < 0) {
      bvh.nodes[slot].first = next_ref;
      bvh.nodes[slot].count = static_cast<std::uint32_t>(t.leaf.size());
      std::copy(t.leaf.begin(), t.leaf.end(), order.begin() + next_ref);
      next_ref += static_cast<std::uint32_t>(t.leaf.size());
      ++bvh.leaf_count;
      return;
    }
    const std::uint32_t pair = next;
    next += 2;
    bvh.nodes[slot].first = pair;
    bvh.nodes[slot].count = 0;
    place(static_cast<std::size_t>(t.left), pair);
    place(static_cast<std::size_t>(t.left) + 1, pair + 1);
  };
  place(0, 0);
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    const Subtree& s = jobs[j];
    bvh.depth = std::max(bvh.depth, s.depth);
    bvh.leaf_count += s.leaves;
    for (std::size_t k = 0; k < s.nodes.size(); ++k) {
      RsBvhNode nd = s.nodes[k];
      nd.first = nd.count > 0 ? nd.first + job_ref[j] : nd.first - 1 + job_node[j];
      bvh.nodes[k == 0 ? job_slot[j] : job_node[j] + static_cast<std::uint32_t>(k) - 1] = nd;
    }
    std::copy(s.order.begin(), s.order.end(), order.begin() + job_ref[j]);
  }
  bvh.triangles.resize(total_refs);
  for (std::size_t k = 0; k < total_refs; ++k) bvh.triangles[k] = src[order[k]];
  bvh.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  bvh.sah_cost = sah_cost(bvh, opts);
  return bvh;
}

}  // namespace
}  // namespace spatial_build

Bvh build_spatial_bvh(const Bvh& plain, const BvhBuildOptions& opts, double budget) {
  return spatial_build::build(plain, opts, budget);
}

struct SplitTreeSlot::State {
  std::once_flag once;
  std::unique_ptr<SplitTree> tree;
};
SplitTreeSlot::SplitTreeSlot() : state_(std::make_unique<State>()) {}
SplitTreeSlot::~SplitTreeSlot() = default;
SplitTreeSlot::SplitTreeSlot(SplitTreeSlot&&) noexcept = default;
SplitTreeSlot& SplitTreeSlot::operator=(SplitTreeSlot&&) noexcept = default;
SplitTreeSlot& SplitTreeSlot::operator=(const SplitTreeSlot&) {
  state_ = std::make_unique<State>();
  return *this;
}

const SplitTree& split_tree(const Bvh& bvh) {
  SplitTreeSlot::State* state = bvh.split_tree_slot.state_.get();
  if (!state) throw Error("internal: split_tree of a moved-from BVH");
  std::call_once(state->once, [&] {
    const auto t0 = std::chrono::steady_clock::now();
    auto tree = std::make_unique<SplitTree>();
    tree->binary = build_spatial_bvh(bvh);
    tree->wide8 = collapse_to_wide8(tree->binary);
    tree->build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    state->tree = std::move(tree);
  });
  return *state->tree;
}

}  // namespace raysort
