#pragma once
// What a frame's rays cost in memory, estimated before anything is allocated, and the refusal when
// it does not fit (issue 23): every command that allocates per ray (trace, run, render,
// encodebench, scenes --describe) checks its scenes here first, and sortcheck its pairs (issue 44),
// so a size a user can type ends in one line that names
// the estimate, the limits and the fix, not in std::bad_alloc or a machine driven into swap.
//
// The model is an upper bound from the batches the scene's effects imply (render/batches.h): every
// batch at its largest (one ray per path; shadow batches shadow_rays_per_bounce per path), host
// memory for all of them at once (generate_batches keeps every batch with its reference hits), and
// device memory for the largest one (rays, hits, keys, order, the sort's scratch, permuted rays).
// The per-ray constants are calibrated on PoCL (peak RSS of `raysort trace`) with a margin;
// tests/frame_memory_test.cpp checks that the estimate stays above what a run really takes.
#include <cstdint>
#include <string>

#include "runtime/runtime.h"
#include "scene/scene.h"
#include "util/host_memory.h"  // available_host_memory, ResourceError, format_bytes

namespace raysort {

struct FrameMemory {
  std::uint64_t paths = 0;          // width × height × spp
  std::uint64_t rays = 0;           // over every batch the frame can produce (upper bound)
  std::uint64_t largest_batch = 0;  // rays of the largest batch
  std::uint64_t host_bytes = 0, device_bytes = 0;
  std::uint64_t largest_buffer_bytes = 0;  // the largest single device allocation

  // Bytes per ray and per path of the model (see the header comment).
  static constexpr std::uint64_t kHostPerRay = 96;     // ray 32, pixel + sample 8, reference hits 2 × 16, slack
  static constexpr std::uint64_t kHostPerPath = 64;    // the path tracer's per-path state while generating
  static constexpr std::uint64_t kDevicePerRay = 160;  // rays 32, hits 16, keys 8, order 4, sort scratch, permuted rays 32
  static constexpr std::uint64_t kLargestBufferPerRay = 32;  // the ray buffer (RsRay)
  // A render's per-pixel state: radiance sums 24, cost 8, image 12, heatmap 12 and its sorted cost
  // 8, the PNG/EXR conversion, slack.
  static constexpr std::uint64_t kRenderHostPerPixel = 96;
};

// The estimate for a scene as loaded (its camera size, samples per pixel and effects).
FrameMemory estimate_frame_memory(const Scene& scene);
FrameMemory estimate_frame_memory(std::uint64_t width, std::uint64_t height, std::uint64_t spp,
                                  std::uint32_t shadow_rays_per_bounce, std::uint32_t max_bounces);

// A render (render/preview.h) traces one pass of at most kRenderPassPaths paths at a time and keeps
// per-pixel sums for the whole frame: its rays are sized by the largest pass, not by the frame's
// spp, and its host memory adds kRenderHostPerPixel per pixel.
FrameMemory estimate_render_memory(const Scene& scene);

// Throws ResourceError naming `what` ("scene cornell at 20000x20000, 1 spp"), the estimate, the
// limit it passes (device max allocation, device global memory, host memory; on a CPU device the
// device's memory is host memory: its buffers count against the host's free memory, not against
// the global memory size the driver reports) and the fix. `device` may be null (the host twin).
void check_frame_memory(const FrameMemory& m, const DeviceInfo* device, const std::string& what,
                        const std::string& fix = "lower --resolution or --spp (or the scene's bounces)");

// The same check for a radix sort of `pairs` key/value pairs held in host vectors (`raysort
// sortcheck`): the keys and values, the host twin's copies, the device's input and scratch buffers;
// over 2^32 - 1 pairs the sort's 32-bit positions cannot address them. Throws ResourceError naming
// `what` ("sortcheck of 4294967295 pairs with 64-bit keys") and the fix.
void check_sort_memory(std::uint64_t pairs, unsigned key_bytes, const DeviceInfo* device, const std::string& what,
                       const std::string& fix);

}  // namespace raysort
