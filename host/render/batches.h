#pragma once
// The batches a scene's effects imply (docs/design.md, "Data flow"), captured from one frame of the host
// twin of the wavefront path tracer (render/pathtrace.h): primary, then for each bounce depth k the
// shadow rays of its diffuse hits (when the scene has sphere lights and asks for shadow rays) and
// the next bounce (while k < max_bounces). Empty batches are left out. Hits come from the host
// reference traversal, so the batches never depend on the device.
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
