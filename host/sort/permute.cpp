#include "sort/permute.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

#include "util/error.h"
#include "util/text.h"

namespace raysort {

const char* ray_access_name(RayAccess a) { return a == RayAccess::Permute ? "permute" : "gather"; }

std::vector<RayAccess> parse_ray_accesses(const std::string& list) {
  static const ListAxis<RayAccess> axis{
      "--access", "access modes", "access mode", {{"gather", RayAccess::Gather}, {"permute", RayAccess::Permute}}};
  return parse_list_axis(axis, list);
}

RayPermuter::RayPermuter(Runtime& rt) : rt_(rt) {
  cl::Program program = rt.build({"cl/permute.cl"});
  cl_call("creating the permute kernel", [&] { kernel_ = cl::Kernel(program, "permute_rays"); });
  local_ = std::min<std::size_t>(64, rt.info().max_work_group_size);
}

cl::Event RayPermuter::enqueue(const cl::Buffer& rays, const cl::Buffer& order, std::uint32_t count,
                               const cl::Buffer& out) {
  cl::Event ev;
  cl_call(fmt::format("permuting {} rays into trace order", count), [&] {
    kernel_.setArg(0, rays);
    kernel_.setArg(1, order);
    kernel_.setArg(2, count);
    kernel_.setArg(3, out);
    if (count > 0)
      rt_.queue().enqueueNDRangeKernel(kernel_, cl::NullRange, cl::NDRange(Runtime::padded(count, local_)),
                                       cl::NDRange(local_), nullptr, &ev);
    else
      rt_.queue().enqueueMarkerWithWaitList(nullptr, &ev);
  });
  return ev;
}

void RayPermuter::warm_up() {
  std::vector<RsRay> rays(local_ + 1);
  std::vector<std::uint32_t> order(rays.size());
  std::iota(order.begin(), order.end(), 0u);
  cl::Buffer in = rt_.upload("permute warm-up rays", rays);
  cl::Buffer ord = rt_.upload("permute warm-up order", order);
  cl::Buffer out = rt_.buffer("permute warm-up output", rays.size() * sizeof(RsRay));
  cl::Event ev = enqueue(in, ord, static_cast<std::uint32_t>(rays.size()), out);
  cl_call("waiting for the permute warm-up", [&] { ev.wait(); });
}

std::vector<RsRay> permute_on_host(const std::vector<RsRay>& rays, const std::vector<std::uint32_t>& order) {
  std::vector<RsRay> out(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (order[i] >= rays.size())
      throw Error(fmt::format("permute_on_host: order[{}] = {} is not a ray index (there are {} rays)", i, order[i],
                              rays.size()));
    out[i] = rays[order[i]];
  }
  return out;
}

}  // namespace raysort
