#include "render/batches.h"

#include "trace/tracer.h"

namespace raysort {

std::vector<ReferencedBatch> generate_batches(const Scene& scene, const Scene::Flat& tris, const Bvh& bvh,
                                              const RayGenOptions& opts) {
  std::vector<ReferencedBatch> out;
  RayBatch current = generate_primary(scene, opts);
  while (!current.rays.empty()) {
    auto hits = trace_reference(bvh, current.rays, nullptr, false);
    RayBatch shadow = generate_shadow(scene, tris, current, hits, opts);
    RayBatch next;
    const bool more = current.bounce < scene.effects.max_bounces;
    if (more) next = generate_bounce(scene, tris, current, hits, opts);
    out.push_back({std::move(current), std::move(hits)});
    if (!shadow.rays.empty()) {
      auto shadow_hits = trace_reference(bvh, shadow.rays, nullptr, true);
      out.push_back({std::move(shadow), std::move(shadow_hits)});
    }
    if (!more) break;
    current = std::move(next);
  }
  return out;
}

}  // namespace raysort
