#include "bvh/cut.h"

#include <algorithm>
#include <queue>

#include "bvh/had.h"

namespace raysort {

namespace {

// Highest priority first; equal priority: higher `tie` first (when given), then the lower node
// index (deterministic).
struct ByHad {
  const std::vector<double>* had;
  const std::vector<double>* tie = nullptr;
  bool higher(std::uint32_t a, std::uint32_t b) const {
    if ((*had)[a] != (*had)[b]) return (*had)[a] > (*had)[b];
    if (tie && (*tie)[a] != (*tie)[b]) return (*tie)[a] > (*tie)[b];
    return a < b;
  }
  // std::priority_queue keeps the "largest" on top: a is "less" than b when b comes first.
  bool operator()(std::uint32_t a, std::uint32_t b) const { return higher(b, a); }
};

using HadQueue = std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, ByHad>;

std::vector<std::uint32_t> in_bit_order(std::vector<std::uint32_t> cut, HadQueue& rest, const ByHad& by) {
  while (!rest.empty()) {
    cut.push_back(rest.top());
    rest.pop();
  }
  std::sort(cut.begin(), cut.end(), [&](std::uint32_t a, std::uint32_t b) { return by.higher(a, b); });
  return cut;
}

}  // namespace

Aabb node_box(const RsBvhNode& n) {
  Aabb b;
  b.min = {n.bmin[0], n.bmin[1], n.bmin[2]};
  b.max = {n.bmax[0], n.bmax[1], n.bmax[2]};
  return b;
}

std::vector<std::uint32_t> hierarchy_cut(const Bvh& bvh, const std::vector<double>& had, std::uint32_t size,
                                         std::uint32_t root) {
  return priority_cut(bvh, had, size, root);
}

std::vector<std::uint32_t> priority_cut(const Bvh& bvh, const std::vector<double>& priority, std::uint32_t size,
                                        std::uint32_t root, const std::vector<double>* tie,
                                        const std::function<bool(std::uint32_t)>& keep) {
  std::vector<std::uint32_t> cut;
  if (size == 0 || bvh.nodes.empty()) return cut;
  ByHad by{&priority, tie};
  HadQueue queue(by);
  if (!keep || keep(root)) queue.push(root);
  std::uint32_t target = size;
  while (!queue.empty() && queue.size() < target) {
    const std::uint32_t n = queue.top();
    queue.pop();
    bool split = false;
    if (!bvh.is_leaf(n)) {
      for (std::uint32_t c = bvh.nodes[n].first; c < bvh.nodes[n].first + 2; ++c)
        if (!keep || keep(c)) {
          queue.push(c);
          split = true;
        }
    }
    if (!split) {
      cut.push_back(n);  // a leaf (or a node with no kept child) cannot be split: it is a cut node
      --target;
    }
  }
  return in_bit_order(std::move(cut), queue, by);
}

bool boxes_overlap(const Aabb& a, const Aabb& b) {
  for (int k = 0; k < 3; ++k)
    if (!(a.min[k] <= b.max[k] && b.min[k] <= a.max[k])) return false;
  return true;
}

std::vector<std::uint32_t> region_cut(const Bvh& bvh, const std::vector<double>& had, std::uint32_t size,
                                      const Aabb& region) {
  return priority_cut(bvh, had, size, 0, nullptr,
                      [&](std::uint32_t n) { return boxes_overlap(node_box(bvh.nodes[n]), region); });
}

std::vector<double> traffic_priority(const std::vector<double>& had, const std::vector<std::uint64_t>& visits,
                                     double blend) {
  if (blend == 0.0 || visits.size() != had.size() || visits.empty() || visits[0] == 0 || !(had[0] > 0.0)) return had;
  std::vector<double> p(had.size());
  const double h0 = had[0], v0 = static_cast<double>(visits[0]);
  for (std::size_t i = 0; i < had.size(); ++i)
    p[i] = (1.0 - blend) * (had[i] / h0) + blend * (static_cast<double>(visits[i]) / v0);
  return p;
}

TwoLevelCut two_level_cut(const Bvh& bvh, const std::vector<double>& had, std::uint32_t half) {
  return two_level_cut(bvh, had, half, half);
}

TwoLevelCut two_level_cut(const Bvh& bvh, const std::vector<double>& had, std::uint32_t top_count,
                          std::uint32_t low_count) {
  TwoLevelCut out;
  if (top_count == 0 || low_count == 0 || bvh.nodes.empty()) return out;
  const auto leaves = subtree_leaf_counts(bvh);
  ByHad by{&had};
  HadQueue queue(by);
  queue.push(0);
  std::vector<std::uint32_t> final_nodes;
  std::uint32_t target = top_count;
  while (!queue.empty() && queue.size() < target) {
    const std::uint32_t n = queue.top();
    queue.pop();
    bool expanded = false;
    if (!bvh.is_leaf(n)) {
      for (std::uint32_t c = bvh.nodes[n].first; c < bvh.nodes[n].first + 2; ++c) {
        if (leaves[c] >= low_count) {
          queue.push(c);
          expanded = true;
        }
      }
    }
    if (!expanded) {
      final_nodes.push_back(n);
      --target;
    }
  }
  out.top = in_bit_order(std::move(final_nodes), queue, by);
  for (std::uint32_t t : out.top) out.low.push_back(hierarchy_cut(bvh, had, low_count, t));
  return out;
}

std::array<std::uint32_t, 3> regular_grid_shape(const Aabb& box, std::uint32_t max_cells) {
  std::array<std::uint32_t, 3> n{1, 1, 1};
  if (max_cells == 0) return {0, 0, 0};
  const Vec3 e = box.empty() ? Vec3{0, 0, 0} : box.extent();
  for (std::uint32_t cells = 2; cells <= max_cells; cells *= 2) {
    int best = 0;
    for (int a = 1; a < 3; ++a)
      if (static_cast<double>(e[a]) / n[a] > static_cast<double>(e[best]) / n[best]) best = a;
    n[best] *= 2;
  }
  return n;
}

std::vector<Aabb> regular_grid_cells(const Aabb& box, std::uint32_t max_cells) {
  const auto n = regular_grid_shape(box, max_cells);
  std::vector<Aabb> cells;
  if (max_cells == 0) return cells;
  const Aabb b = box.empty() ? Aabb{{0, 0, 0}, {0, 0, 0}} : box;
  // Axes by number of cells, descending (ties: lower axis first): the first is most significant.
  std::array<int, 3> axes{0, 1, 2};
  std::stable_sort(axes.begin(), axes.end(), [&](int x, int y) { return n[x] > n[y]; });
  auto bound = [&](int a, std::uint32_t i) {
    if (i == 0) return b.min[a];
    if (i == n[a]) return b.max[a];
    return b.min[a] + (b.max[a] - b.min[a]) * (static_cast<float>(i) / static_cast<float>(n[a]));
  };
  for (std::uint32_t i0 = 0; i0 < n[axes[0]]; ++i0)
    for (std::uint32_t i1 = 0; i1 < n[axes[1]]; ++i1)
      for (std::uint32_t i2 = 0; i2 < n[axes[2]]; ++i2) {
        const std::uint32_t idx[3] = {i0, i1, i2};
        Aabb c;
        for (int k = 0; k < 3; ++k) {
          const int a = axes[k];
          c.min[a] = bound(a, idx[k]);
          c.max[a] = bound(a, idx[k] + 1);
        }
        cells.push_back(c);
      }
  return cells;
}

std::string validate_cut(const Bvh& bvh, const std::vector<std::uint32_t>& cut, std::uint32_t root) {
  std::vector<std::uint8_t> in_cut(bvh.nodes.size(), 0);
  for (std::uint32_t c : cut) {
    if (c >= bvh.nodes.size()) return "cut node " + std::to_string(c) + " is not a node";
    if (in_cut[c]) return "cut node " + std::to_string(c) + " appears twice";
    in_cut[c] = 1;
  }
  // Depth-first walk carrying how many cut nodes the path from root has met so far.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{root, 0u}};
  std::size_t reached = 0;
  while (!stack.empty()) {
    auto [k, met] = stack.back();
    stack.pop_back();
    met += in_cut[k];
    reached += in_cut[k];
    if (met > 1) return "node " + std::to_string(k) + " lies below two cut nodes";
    if (bvh.is_leaf(k)) {
      if (met != 1) return "the path to leaf " + std::to_string(k) + " crosses no cut node";
    } else {
      stack.push_back({bvh.nodes[k].first, met});
      stack.push_back({bvh.nodes[k].first + 1, met});
    }
  }
  if (reached != cut.size()) return "some cut nodes are not below node " + std::to_string(root);
  return "";
}

}  // namespace raysort
