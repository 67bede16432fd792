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

struct RayGenOptions {
  std::uint32_t width = 0, height = 0, spp = 0;  // 0: the scene's own
  std::uint32_t seed = 1;
};

// The camera struct the kernels and the shared ray generator use.
RsCamera make_camera(const Camera& cam, std::uint32_t width, std::uint32_t height);

// Primary rays: width × height × spp, pixel-major (all samples of a pixel together).
RayBatch generate_primary(const Scene& scene, const RayGenOptions& opts);

// From the closest hits of `batch` (a primary or bounce batch; hits[i] belongs to batch.rays[i]):
// next-event shadow rays toward the scene's sphere lights (light chosen by power; rays toward
// lights below the surface are not generated), shadow_rays_per_bounce per hit. Empty when the
// scene has no sphere lights or declares no shadow rays.
RayBatch generate_shadow(const Scene& scene, const Scene::Flat& tris, const RayBatch& batch,
                         const std::vector<RsHit>& hits, const RayGenOptions& opts);

// Diffuse bounce rays from the hits of `batch` (cosine-weighted about the geometric normal),
// after Russian roulette from the scene's declared start depth. Misses and terminated paths are
// compacted out, so batch sizes shrink with depth.
RayBatch generate_bounce(const Scene& scene, const Scene::Flat& tris, const RayBatch& batch,
                         const std::vector<RsHit>& hits, const RayGenOptions& opts);

}  // namespace raysort
