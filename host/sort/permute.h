#pragma once
// Applying a sorted order to the rays themselves: the "permute" access mode (cl/permute.cl;
// docs/measurement.md, "Access modes"). out[i] = rays[order[i]], on the device and on the host.
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "shared.h"

namespace raysort {

// How a sorted trace reads its rays (docs/measurement.md, "Access modes"): through the sorted
// order, ray[order[i]] (gather), or moved into sorted order by this stage first (permute).
enum class RayAccess { Gather, Permute };
const char* ray_access_name(RayAccess a);  // "gather", "permute"
// A command line's access list: "gather,permute" or "all". Throws Error naming an unknown mode.
std::vector<RayAccess> parse_ray_accesses(const std::string& list);

class RayPermuter {
 public:
  explicit RayPermuter(Runtime& rt);
  // out[i] = rays[order[i]] for i < count. Enqueues and returns the kernel's event without waiting.
  cl::Event enqueue(const cl::Buffer& rays, const cl::Buffer& order, std::uint32_t count, const cl::Buffer& out);
  // Runs the kernel once on a few rays (PoCL compiles kernels at their first launch).
  void warm_up();

 private:
  Runtime& rt_;
  cl::Kernel kernel_;
  std::size_t local_ = 64;
};

// The host twin.
std::vector<RsRay> permute_on_host(const std::vector<RsRay>& rays, const std::vector<std::uint32_t>& order);

}  // namespace raysort
