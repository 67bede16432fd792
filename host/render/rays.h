#pragma once
// Ray batches: what the benchmark encodes, sorts and traces. A batch is generated once per
// scene from a counter-based RNG keyed by (pixel, sample, bounce), so every encoder, run and
// device sees the same rays.
//
// Names follow the paper: "primary"; "shadow<k>" = next-event rays from the hits of bounce k
// (shadow0 = the paper's "primary shadow rays"); "bounce<k>" = the k-th diffuse bounce
// (bounce1 = the paper's "secondary rays").
#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "shared.h"

namespace raysort {

enum class BatchKind { Primary, Shadow, Bounce };

struct RayBatch {
  std::string name;
  BatchKind kind = BatchKind::Primary;
  std::uint32_t bounce = 0;          // primary: 0; bounce k: k; shadow k: from the hits of bounce k
  std::vector<RsRay> rays;
  std::vector<std::uint32_t> pixel;  // y * width + x of the path each ray belongs to
  std::vector<std::uint32_t> sample; // sample index within the pixel
  bool any_hit() const { return kind == BatchKind::Shadow; }
  std::size_t size() const { return rays.size(); }
};

// How a frame's rays are drawn. Its size and samples per pixel are the scene's (scene.camera,
// scene.effects), set where the scene is loaded (scene/load.h, SceneOptions::frame).
struct RayGenOptions {
  std::uint32_t seed = 1;
};

// The camera struct the kernels and the shared ray generator use.
RsCamera make_camera(const Camera& cam, std::uint32_t width, std::uint32_t height);

// The rays themselves come from the wavefront path tracer (render/pathtrace.h, cl/shade.h):
// primary rays width x height x spp, pixel-major (all samples of a pixel together); shadow<k> =
// next-event rays toward the sphere lights (light chosen by power) from the diffuse hits of bounce k;
// bounce<k> = the surviving paths after Russian roulette, misses and terminated paths compacted out.
// render/batches.h captures them for the benchmark.

}  // namespace raysort
