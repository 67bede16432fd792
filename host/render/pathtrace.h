#pragma once
// The wavefront path tracer (docs/design.md, "Data flow"; Laine et al. 2013, the pipeline of Xiang et al.
// section 6.1): generate -> trace -> shade -> compact -> trace shadows -> accumulate -> next bounce,
// one kernel per stage in cl/shade.cl, with a host twin running the same shade.h arithmetic.
// A frame runs only the stages the scene's effects imply (describe_frame lists them), and every
// traced batch can be handed to a sink: that is where the benchmark's ray batches come from.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bvh/bvh.h"
#include "runtime/runtime.h"
#include "render/rays.h"
#include "scene/scene.h"
#include "shade.h"
#include "trace/tracer.h"

namespace raysort {

// A scene's shading data in the device layout (cl/shade.h), built once per scene and resolution.
struct ShadeInputs {
  std::vector<RsShadeTriangle> triangles;  // scene order (hit ids)
  std::vector<RsMaterial> materials;
  std::vector<RsSphereLight> lights;       // never empty on upload: a zero entry stands in for none
  RsShadeParams params{};                  // spp / sample_begin are set per frame
  RsCamera camera{};
  std::uint32_t width = 0, height = 0, spp = 0;  // the frame: resolution and samples per pixel
};
ShadeInputs make_shade_inputs(const Scene& scene, const Scene::Flat& tris, const RayGenOptions& opts);

// "primary", "shadow<k>", "bounce<k>" (rays.h).
std::string batch_name(BatchKind kind, std::uint32_t bounce);

// A traced batch, as a sink sees it (valid only during the call).
struct TracedBatch {
  BatchKind kind;
  std::uint32_t bounce;
  const std::vector<RsRay>& rays;
  const std::vector<RsPathState>& states;  // path ids (and weights) of the rays
  const std::vector<RsHit>& hits;          // closest hits, or any hits for shadow rays
};
using BatchSink = std::function<void(const TracedBatch&)>;

struct FrameOptions {
  std::uint32_t sample_begin = 0, sample_count = 0;  // a pass over samples [begin, begin + count); 0: all
  std::uint32_t pixel_begin = 0, pixel_count = 0;    // ... and pixels [begin, begin + count), y * width + x; 0: all
  bool count_visits = false;                         // per-path BVH node visits (closest-hit batches)
  BatchSink sink;                                    // called once per non-empty batch, in trace order
};

struct BatchCount {
  std::string name;
  BatchKind kind;
  std::uint32_t bounce;
  std::size_t rays;
};

struct Frame {
  std::uint32_t spp = 0;                 // samples in this pass
  std::uint32_t pixel_begin = 0, pixels = 0;  // the pass's pixels
  std::vector<float> radiance;           // rgb per path; path = (pixel - pixel_begin) * spp + (sample - sample_begin)
  std::vector<std::uint32_t> visits;     // per path, when counted
  std::vector<BatchCount> batches;       // in trace order, non-empty ones only
};

// The host twin: same rays, same radiance, bit for bit, as DevicePathTracer.
Frame trace_frame_host(const ShadeInputs& in, const Bvh& bvh, const FrameOptions& opts,
                       TraceVariant variant = TraceVariant::Fast);

// The same frame on an OpenCL device: every stage a kernel, tracing through Tracer.
class DevicePathTracer {
 public:
  DevicePathTracer(Runtime& rt, const Bvh& bvh, const ShadeInputs& in, TraceVariant variant = TraceVariant::Fast);
  Frame trace_frame(const FrameOptions& opts);

 private:
  std::uint32_t compact(const cl::Buffer& valid, std::uint32_t n, const cl::Buffer& dest, const cl::Buffer& rays,
                        const cl::Buffer& states, const cl::Buffer& out_rays, const cl::Buffer& out_states);
  void launch(cl::Kernel& k, std::size_t n, const std::string& doing);

  Runtime& rt_;
  const ShadeInputs& in_;
  Tracer tracer_;
  cl::Buffer triangles_, materials_, lights_;
  cl::Kernel generate_, shade_, accumulate_, visits_, count_, scan_, dest_, copy_;
  std::size_t local_ = 64;
};

// What a scene's frame implies, for `raysort scenes --describe`: the stages in order, one line each.
std::vector<std::string> describe_stages(const Scene& scene);

}  // namespace raysort
