#include "render/batches.h"

#include "render/pathtrace.h"

namespace raysort {

std::vector<ReferencedBatch> generate_batches(const Scene& scene, const Scene::Flat& tris, const Bvh& bvh,
                                              const RayGenOptions& opts) {
  const ShadeInputs in = make_shade_inputs(scene, tris, opts);
  std::vector<ReferencedBatch> out;
  FrameOptions frame;
  frame.sink = [&](const TracedBatch& b) {
    ReferencedBatch rb;
    rb.batch.name = batch_name(b.kind, b.bounce);
    rb.batch.kind = b.kind;
    rb.batch.bounce = b.bounce;
    rb.batch.rays = b.rays;
    rb.batch.pixel.reserve(b.states.size());
    rb.batch.sample.reserve(b.states.size());
    for (const RsPathState& s : b.states) {
      rb.batch.pixel.push_back(s.path / in.spp);
      rb.batch.sample.push_back(s.path % in.spp);
    }
    rb.reference_hits = b.hits;
    out.push_back(std::move(rb));
  };
  trace_frame_host(in, bvh, frame);
  return out;
}

bool next_event_estimation(const Scene& scene) {
  return !scene.sphere_lights.empty() && scene.effects.shadow_rays_per_bounce > 0;
}

std::vector<PossibleBatch> possible_batches(bool next_event, std::uint32_t max_bounces) {
  std::vector<PossibleBatch> out{{batch_name(BatchKind::Primary, 0), BatchKind::Primary, 0}};
  for (std::uint32_t k = 0;; ++k) {
    if (next_event) out.push_back({batch_name(BatchKind::Shadow, k), BatchKind::Shadow, k});
    if (k >= max_bounces) break;
    out.push_back({batch_name(BatchKind::Bounce, k + 1), BatchKind::Bounce, k + 1});
  }
  return out;
}

std::vector<PossibleBatch> possible_batches(const Scene& scene) {
  return possible_batches(next_event_estimation(scene), scene.effects.max_bounces);
}

}  // namespace raysort
