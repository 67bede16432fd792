#pragma once
// Pictures of what the benchmark traces (`raysort render`):
//   render_frame     the converged image of the scene's light transport (the wavefront path tracer
//                    on a device, or its host twin), sample passes averaged per pixel, with the
//                    BVH nodes visited per pixel and sample;
//   cost_heatmap     that traversal cost as colours;
//   shade_primary    a simple preview shading of primary hits, albedo × (ambient + |cos|);
//   draw_boxes       box wireframes over an image, like the "cut node boundaries" figure of
//                    Xiang et al. (section 6): the boxes the cut keys put their bits on.
// Writing them to disk is util/image.h's.
#include <cstdint>
#include <vector>

#include "bvh/prepared_scene.h"
#include "render/pathtrace.h"
#include "render/rays.h"
#include "runtime/runtime.h"
#include "util/image.h"

namespace raysort {

struct RenderedFrame {
  Image image;                       // linear radiance
  std::vector<double> cost;          // BVH nodes visited per pixel and sample (closest-hit rays)
  std::vector<BatchCount> first_pass;  // the batches of sample 0's passes, summed over their rows
  std::size_t rays = 0;
  std::size_t passes = 0;
  double ms = 0.0;                   // wall clock of the passes
};

// One pass of a render: samples [sample_begin, + sample_count) of pixels [pixel_begin, + pixel_count).
struct RenderPass {
  std::uint32_t sample_begin = 0, sample_count = 0, pixel_begin = 0, pixel_count = 0;
};

// Paths a render traces at once: what bounds its rays' memory at any resolution and spp.
inline constexpr std::uint64_t kRenderPassPaths = std::uint64_t{2} << 20;

// The passes of a width × height × spp render of at most `paths_per_pass` paths each (one row of
// one sample at the least): several samples of the whole frame per pass while the frame has fewer
// pixels than that, else one sample of as many whole rows as fit. Sample-major, so every pixel
// adds up its samples in sample order whatever the split: the image is the same bit for bit.
std::vector<RenderPass> plan_render_passes(std::uint32_t width, std::uint32_t height, std::uint32_t spp,
                                           std::uint64_t paths_per_pass = kRenderPassPaths);

// Paths of the largest of those passes (what a render's ray memory is sized by).
std::uint64_t largest_render_pass(std::uint32_t width, std::uint32_t height, std::uint32_t spp,
                                  std::uint64_t paths_per_pass = kRenderPassPaths);

// The frame at the scene's resolution and spp, in the passes above. rt null: the host twin.
RenderedFrame render_frame(const PreparedScene& scene, const RayGenOptions& gen, Runtime* rt,
                           std::uint64_t paths_per_pass = kRenderPassPaths);

// The cost as an inferno-like ramp spanning its 1st to 99th percentile (returned in low, top), so
// a few extreme pixels do not flatten the picture.
Image cost_heatmap(const std::vector<double>& cost, std::uint32_t width, std::uint32_t height, double& low,
                   double& top);

// Primary hits shaded by albedo × (0.15 + 0.85·|cos θ|) against the view ray; misses are the sky
// colour when the scene has a sky, else dark grey (host reference traversal).
Image shade_primary(const PreparedScene& scene, const RsCamera& cam);

// Orange wireframes of the boxes: each edge clipped to the space in front of the camera, projected
// with the pinhole model (the inverse of rs_camera_ray) and drawn 2 pixels wide. No depth test:
// boxes behind walls show through, as in the paper's figure.
void draw_boxes(Image& img, const RsCamera& cam, const std::vector<Aabb>& boxes, float near);

}  // namespace raysort
