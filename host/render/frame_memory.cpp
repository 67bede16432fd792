#include "render/frame_memory.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "render/batches.h"
#include "render/preview.h"

namespace raysort {

namespace {

constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
// A sort of host vectors (check_sort_memory), in copies of a pair: on the host the keys and values,
// the host twin's copies of both and its scratch, and slack; on the device the input and the
// scratch (double) buffers.
constexpr std::uint64_t kSortHostPerPair = 4, kSortDevicePerPair = 2;

}  // namespace

FrameMemory estimate_frame_memory(std::uint64_t width, std::uint64_t height, std::uint64_t spp,
                                  std::uint32_t shadow_rays_per_bounce, std::uint32_t max_bounces) {
  FrameMemory m;
  m.paths = saturating_mul(saturating_mul(width, height), spp);
  for (const PossibleBatch& b : possible_batches(shadow_rays_per_bounce > 0, max_bounces)) {
    const std::uint64_t rays = b.kind == BatchKind::Shadow ? saturating_mul(m.paths, shadow_rays_per_bounce) : m.paths;
    m.rays = saturating_add(m.rays, rays);
    m.largest_batch = std::max(m.largest_batch, rays);
  }
  m.host_bytes = saturating_add(saturating_mul(m.rays, FrameMemory::kHostPerRay),
                                saturating_mul(m.paths, FrameMemory::kHostPerPath));
  m.device_bytes = saturating_mul(m.largest_batch, FrameMemory::kDevicePerRay);
  m.largest_buffer_bytes = saturating_mul(m.largest_batch, FrameMemory::kLargestBufferPerRay);
  return m;
}

FrameMemory estimate_frame_memory(const Scene& scene) {
  return estimate_frame_memory(scene.camera.width, scene.camera.height, scene.effects.samples_per_pixel,
                               next_event_estimation(scene) ? scene.effects.shadow_rays_per_bounce : 0,
                               scene.effects.max_bounces);
}

FrameMemory estimate_render_memory(const Scene& scene) {
  const std::uint32_t w = scene.camera.width, h = scene.camera.height;
  FrameMemory m = estimate_frame_memory(largest_render_pass(w, h, scene.effects.samples_per_pixel), 1, 1,
                                        next_event_estimation(scene) ? scene.effects.shadow_rays_per_bounce : 0,
                                        scene.effects.max_bounces);
  const std::uint64_t pixels = std::uint64_t{w} * h;
  m.host_bytes = saturating_add(m.host_bytes, saturating_mul(pixels, FrameMemory::kRenderHostPerPixel));
  return m;
}

namespace {

// The limits every estimate is checked against, in one place: the largest single buffer against
// the device's maximum allocation, device memory against a GPU's global memory, host memory (the
// CPU device's buffers included) against what the host has free. `size` says what was counted.
void check_limits(std::uint64_t host_bytes, std::uint64_t device_bytes, std::uint64_t largest_buffer_bytes,
                  const std::string& buffer_name, const DeviceInfo* device, const std::string& what,
                  const std::string& size, const std::string& fix) {
  auto refuse = [&](const std::string& need, const std::string& limit) {
    throw ResourceError(fmt::format("{} needs {} ({}), over {}; {}", what, need, size, limit, fix));
  };
  const bool cpu_device = device && device->type == "CPU";
  if (device) {
    if (largest_buffer_bytes > device->max_alloc_bytes)
      refuse(fmt::format("a {} of {}", buffer_name, format_bytes(largest_buffer_bytes)),
             fmt::format("the device's maximum allocation of {} ({})", format_bytes(device->max_alloc_bytes), device->name));
    // A CPU device's global memory is host memory, checked below against what the host has free.
    // Its reported size is no limit: PoCL derives it from hwloc's NUMA-node figure (3/4 of it on
    // small nodes), which in a container can be a fraction of the machine's memory (4.7 GiB on a
    // 24 GiB machine), and it does not refuse allocations past it (4 buffers of 1.9 GiB allocated
    // and filled there). Comparing with it refused the paper preset on a machine that runs it.
    if (!cpu_device && device_bytes > device->global_mem_bytes)
      refuse(fmt::format("about {} of device memory", format_bytes(device_bytes)),
             fmt::format("the device's global memory of {} ({})", format_bytes(device->global_mem_bytes), device->name));
  }
  // A CPU device's buffers are host memory too.
  const bool shared = cpu_device;
  const std::uint64_t host = shared ? saturating_add(host_bytes, device_bytes) : host_bytes;
  const std::uint64_t available = available_host_memory();
  if (host > available)
    refuse(fmt::format("about {} of host memory{}", format_bytes(host), shared ? " (the CPU device's buffers included)" : ""),
           fmt::format("the {} available", format_bytes(available)));
}

std::string count_text(std::uint64_t n) { return n == kMax ? std::string("more than 1.8e19") : fmt::format("{}", n); }

}  // namespace

void check_frame_memory(const FrameMemory& m, const DeviceInfo* device, const std::string& what,
                        const std::string& fix) {
  const std::string size = fmt::format("{} paths, up to {} rays in its batches, {} in the largest", count_text(m.paths),
                                       count_text(m.rays), count_text(m.largest_batch));
  if (m.largest_batch > std::numeric_limits<std::uint32_t>::max())
    throw ResourceError(fmt::format("{} needs {} rays in one batch ({}), over the 4294967295 that 32-bit ray indices "
                                    "address; {}", what, count_text(m.largest_batch), size, fix));
  check_limits(m.host_bytes, m.device_bytes, m.largest_buffer_bytes, "ray buffer", device, what, size, fix);
}

void check_sort_memory(std::uint64_t pairs, unsigned key_bytes, const DeviceInfo* device, const std::string& what,
                       const std::string& fix) {
  if (pairs > std::numeric_limits<std::uint32_t>::max())
    throw ResourceError(fmt::format("{}: {} pairs is more than the 4294967295 that the sort's 32-bit positions address; "
                                    "{}", what, pairs, fix));
  const std::uint64_t pair_bytes = key_bytes + 4u;  // a key and its 32-bit value
  check_limits(saturating_mul(pairs, kSortHostPerPair * pair_bytes), saturating_mul(pairs, kSortDevicePerPair * pair_bytes),
               saturating_mul(pairs, key_bytes), "key buffer", device, what,
               fmt::format("{} pairs of {}-byte keys and 4-byte values", pairs, key_bytes), fix);
}

}  // namespace raysort
