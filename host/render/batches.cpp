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

}  // namespace raysort
