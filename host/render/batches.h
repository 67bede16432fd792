#pragma once
// The batches a scene's effects imply (docs/design.md, "Data flow"), captured from one frame of the host
// twin of the wavefront path tracer (render/pathtrace.h): primary, then for each bounce depth k the
// shadow rays of its diffuse hits (when the scene has sphere lights and asks for shadow rays) and
// the next bounce (while k < max_bounces). Empty batches are left out. Hits come from the host
// reference traversal, so the batches never depend on the device.
#include <cstdint>
#include <string>
#include <vector>

#include "bvh/bvh.h"
#include "render/rays.h"

namespace raysort {

struct ReferencedBatch {
  RayBatch batch;
  std::vector<RsHit> reference_hits;  // host reference, in ray order
};

std::vector<ReferencedBatch> generate_batches(const Scene& scene, const Scene::Flat& tris, const Bvh& bvh,
                                              const RayGenOptions& opts);

// The order a batch is traced in when it is not sorted: the NoSort baseline that every speedup and
// SIMT-model ratio is measured against, and the order the encoders' stable sort starts from.
//   pixel     generation order: pixel-major, with terminated paths compacted out in order (what a
//             path tracer that compacts with a prefix sum produces; raysort's own wavefront)
//   shuffled  a fixed-seed random permutation of that order: what a path tracer that compacts with
//             atomics produces, where which thread claims which slot is up to the scheduler
// The baseline decides how much coherence there is left for an ordering to recover.
enum class BaselineOrder { Pixel, Shuffled };
const char* baseline_order_name(BaselineOrder b);
// "pixel", "shuffled", a comma-separated list of them, or "all". Throws Error naming the choices.
std::vector<BaselineOrder> parse_baseline_orders(const std::string& list);

// The batch in `order`: itself for pixel; for shuffled, rays, pixels, samples and reference hits
// moved together by one permutation, drawn by Fisher-Yates (i from n-1 down to 1, j uniform in
// [0, i] by Lemire's multiply-shift on a std::mt19937_64 whose sequence the C++ standard fixes),
// seeded from `seed` and the batch name: the same command gives the same order on every machine.
ReferencedBatch in_baseline_order(const ReferencedBatch& b, BaselineOrder order, std::uint32_t seed);
// The permutation itself: result[i] = the generation index of the ray traced i-th.
std::vector<std::uint32_t> baseline_permutation(std::size_t n, const std::string& batch_name, std::uint32_t seed);

// Next-event estimation: the scene has sphere lights and asks for shadow rays per bounce.
bool next_event_estimation(const Scene& scene);

// The batches a frame can produce, in the order the path tracer traces them: primary, then per
// bounce depth k its shadow rays (with next-event estimation) and bounce k+1 while k < max_bounces.
// The one statement of that rule: the path tracer follows it, `scenes --describe` and the shard
// planner read it. A batch may still turn out empty at run time (every path ended), and then
// generate_batches leaves it out.
struct PossibleBatch {
  std::string name;  // "primary", "shadow<k>", "bounce<k>"
  BatchKind kind;
  std::uint32_t bounce;
};
std::vector<PossibleBatch> possible_batches(bool next_event, std::uint32_t max_bounces);
std::vector<PossibleBatch> possible_batches(const Scene& scene);

}  // namespace raysort
