#pragma once
// The batches a scene's effects imply (DESIGN.md section 1), captured from one frame of the host
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

}  // namespace raysort
