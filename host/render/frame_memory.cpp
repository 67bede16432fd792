#include "render/frame_memory.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <limits>

#include "render/batches.h"

namespace raysort {

namespace {

constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();

// a × b, saturating (a resolution a user can type must not wrap into a small estimate).
std::uint64_t mul(std::uint64_t a, std::uint64_t b) { return b != 0 && a > kMax / b ? kMax : a * b; }
std::uint64_t add(std::uint64_t a, std::uint64_t b) { return a > kMax - b ? kMax : a + b; }

// The first number in a file ("max" or a missing file: none).
std::uint64_t read_number(const char* path) {
  std::ifstream in(path);
  std::uint64_t v = 0;
  return in >> v ? v : kMax;
}

}  // namespace

FrameMemory estimate_frame_memory(std::uint64_t width, std::uint64_t height, std::uint64_t spp,
                                  std::uint32_t shadow_rays_per_bounce, std::uint32_t max_bounces) {
  FrameMemory m;
  m.paths = mul(mul(width, height), spp);
  for (const PossibleBatch& b : possible_batches(shadow_rays_per_bounce > 0, max_bounces)) {
    const std::uint64_t rays = b.kind == BatchKind::Shadow ? mul(m.paths, shadow_rays_per_bounce) : m.paths;
    m.rays = add(m.rays, rays);
    m.largest_batch = std::max(m.largest_batch, rays);
  }
  m.host_bytes = add(mul(m.rays, FrameMemory::kHostPerRay), mul(m.paths, FrameMemory::kHostPerPath));
  m.device_bytes = mul(m.largest_batch, FrameMemory::kDevicePerRay);
  m.largest_buffer_bytes = mul(m.largest_batch, FrameMemory::kLargestBufferPerRay);
  return m;
}

FrameMemory estimate_frame_memory(const Scene& scene) {
  return estimate_frame_memory(scene.camera.width, scene.camera.height, scene.effects.samples_per_pixel,
                               next_event_estimation(scene) ? scene.effects.shadow_rays_per_bounce : 0,
                               scene.effects.max_bounces);
}

std::uint64_t available_host_memory() {
  if (const char* forced = std::getenv("RAYSORT_TEST_HOST_MEMORY_BYTES")) return std::strtoull(forced, nullptr, 10);
  std::uint64_t available = kMax;
  std::ifstream in("/proc/meminfo");
  std::string key;
  std::uint64_t kib = 0;
  std::string unit;
  while (in >> key >> kib >> unit)
    if (key == "MemAvailable:") available = kib * 1024;
  // A cgroup v2 limit (a Slurm job, a container): what is left below it.
  const std::uint64_t limit = read_number("/sys/fs/cgroup/memory.max");
  const std::uint64_t used = read_number("/sys/fs/cgroup/memory.current");
  if (limit != kMax && used != kMax) available = std::min(available, limit > used ? limit - used : 0);
  return available;
}

std::string format_bytes(std::uint64_t bytes) {
  if (bytes == kMax) return "more than 16 EiB";
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024.0 && u < 6) v /= 1024.0, ++u;
  return u == 0 ? fmt::format("{} B", bytes) : fmt::format("{:.1f} {}", v, units[u]);
}

void check_frame_memory(const FrameMemory& m, const DeviceInfo* device, const std::string& what) {
  auto count = [](std::uint64_t n) { return n == kMax ? std::string("more than 1.8e19") : fmt::format("{}", n); };
  const std::string size = fmt::format("{} paths, up to {} rays in its batches, {} in the largest", count(m.paths),
                                       count(m.rays), count(m.largest_batch));
  const std::string fix = "lower --resolution or --spp (or the scene's bounces)";
  auto refuse = [&](const std::string& need, const std::string& limit) {
    throw ResourceError(fmt::format("{} needs {} ({}), over {}; {}", what, need, size, limit, fix));
  };
  if (m.largest_batch > std::numeric_limits<std::uint32_t>::max())
    refuse(fmt::format("{} rays in one batch", count(m.largest_batch)), "the 4294967295 that 32-bit ray indices address");
  if (device) {
    if (m.largest_buffer_bytes > device->max_alloc_bytes)
      refuse(fmt::format("a ray buffer of {}", format_bytes(m.largest_buffer_bytes)),
             fmt::format("the device's maximum allocation of {} ({})", format_bytes(device->max_alloc_bytes), device->name));
    if (m.device_bytes > device->global_mem_bytes)
      refuse(fmt::format("about {} of device memory", format_bytes(m.device_bytes)),
             fmt::format("the device's global memory of {} ({})", format_bytes(device->global_mem_bytes), device->name));
  }
  // A CPU device's buffers are host memory too.
  const bool shared = device && device->type == "CPU";
  const std::uint64_t host = shared ? add(m.host_bytes, m.device_bytes) : m.host_bytes;
  const std::uint64_t available = available_host_memory();
  if (host > available)
    refuse(fmt::format("about {} of host memory{}", format_bytes(host), shared ? " (the CPU device's buffers included)" : ""),
           fmt::format("the {} available", format_bytes(available)));
}

}  // namespace raysort
