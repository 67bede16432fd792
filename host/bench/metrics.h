#pragma once
// Ordering-quality metrics of a sorted batch: ANC (the paper's Table 7) and the SIMT model of
// docs/design.md, "Metrics", which shows what a 32-wide GPU would gain even when the run is on a CPU.
#include <cstdint>
#include <span>
#include <vector>

#include "bench/gpu_model.h"
#include "bvh/bvh.h"
#include "trace/tracer.h"
#include "shared.h"

namespace raysort {

constexpr std::size_t kWarpSize = 32;

// Average number of distinct keys per group of 32 consecutive keys (the last group may be
// shorter). keys are in trace (sorted) order. 0 for an empty sequence.
double average_number_of_codes(std::span<const std::uint64_t> keys);

struct SimtModel {
  // Σ steps / Σ_warps (lanes · max steps): the fraction of issued lane-steps doing work when
  // each warp of 32 consecutive rays runs until its longest traversal ends.
  double lane_efficiency = 0.0;
  // Σ_warps |∪ nodes visited| / Σ_rays |nodes visited|: distinct BVH nodes a warp fetches per
  // node visit (lower = rays of a warp share more of their paths).
  double distinct_nodes_per_visit = 0.0;
  std::uint64_t total_steps = 0;
  std::uint64_t warps = 0;
};

// The model from per-ray traversal trails (node ids in visit order), rays in trace order.
SimtModel simt_model_from_trails(const std::vector<std::vector<std::uint32_t>>& trails);

// Traces rays[order[i]] with the host twin of the traversal the kernels run on `layout`
// (cl/traverse_wide.h on the 4-wide tree, the default; cl/traverse_wide8.h on the 8-wide one for
// wide8; cl/traverse_binary.h on the binary one), recording every ray's trail, warp by warp on host
// threads, and returns the model. A step is one node the loop fetches: on a wide tree a wide node
// (four or eight child boxes) or a leaf (its packets), on the binary tree a node (two child boxes)
// or a leaf. order null = identity.
// With a GPU profile, the same trails are also replayed through its caches (bench/gpu_model.h)
// and *gpu_counts receives the counts; the SIMT figures do not depend on it.
//
// `trails`, when given, holds every ray's trail for the models of other orders of the same rays,
// tree and variant: a ray's walk is its own wherever an order puts it (one ray per lane), only the
// warps change. A call in ray order (order null) fills it while it fits in its budget; a call given
// it filled reads the trails instead of walking the rays again. The figures are the same either way.
struct RayTrails {
  std::uint64_t budget_bytes = 0;
  std::vector<std::uint64_t> begin;  // ray i's steps: [begin[i], begin[i + 1]); rays + 1 entries once filled
  std::vector<std::uint32_t> steps;
  std::vector<std::uint32_t> last_reads;
  bool over_budget = false;
  bool filled() const { return !begin.empty(); }
  std::uint64_t bytes() const {
    return begin.size() * sizeof(std::uint64_t) + (steps.size() + last_reads.size()) * sizeof(std::uint32_t);
  }
};
SimtModel simt_model(const Bvh& bvh, const std::vector<RsRay>& rays, const std::uint32_t* order, bool any_hit,
                     TraceVariant variant = TraceVariant::Fast, TraceLayout layout = TraceLayout::Wide,
                     const GpuProfile* gpu = nullptr, GpuCounts* gpu_counts = nullptr, RayTrails* trails = nullptr);

}  // namespace raysort
