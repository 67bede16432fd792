// DeviceEncoder: the encode kernels of cl/encode.cl on one device (see device_encoder.h).
#include "encode/device_encoder.h"

#include <algorithm>
#include <chrono>
#include <numeric>

#include "encode/encoder_file.h"
#include "util/error.h"

namespace raysort {

DeviceEncoder::DeviceEncoder(Runtime& rt, const Bvh& bvh, const Aabb& scene_box, const EncoderParams& params)
    : rt_(rt), scene_(bvh, scene_box, params) {
  cl::Program program = rt.build({"cl/encode.cl"});
  cl_call("creating the encode kernels", [&] {
    for (auto [kernels, suffix] : {std::pair{&k32_, "_k32"}, std::pair{&k64_, "_k64"}})
      for (const EncoderInfo& info : encoder_table()) {
        std::vector<std::string> names = info.family->extra_kernels();
        names.emplace_back(info.kernel);
        for (const std::string& name : names)
          if (!kernels->count(name)) kernels->emplace(name, cl::Kernel(program, (name + suffix).c_str()));
      }
  });
  // 64 work-items suit PoCL (the group is a loop; 256 measured no faster) and GPUs (two warps).
  // Cut boxes are read from __constant memory (broadcast on GPUs; no copy or barrier on PoCL).
  local_ = std::min<std::size_t>(64, rt.info().max_work_group_size);
}

DeviceEncoder::Kernels& DeviceEncoder::kernels_of(Encoder e, unsigned bits) {
  const EncoderFamily& family = encoder_family(e);
  auto own = own_kernels_.find(e);
  if (own == own_kernels_.end()) {
    const std::optional<cl::Program> program = family.own_program(e, rt_);
    if (!program) return bits > 32 ? k64_ : k32_;
    std::pair<Kernels, Kernels> made;
    const std::string name(encoder_info(e).kernel);
    cl_call("creating the kernels of " + std::string(encoder_name(e)), [&] {
      made.first.emplace(name, cl::Kernel(*program, (name + "_k32").c_str()));
      made.second.emplace(name, cl::Kernel(*program, (name + "_k64").c_str()));
    });
    own = own_kernels_.emplace(e, std::move(made)).first;
  }
  return bits > 32 ? own->second.second : own->second.first;
}

const std::vector<KernelArg>& DeviceEncoder::uploaded(Encoder e, unsigned bits) {
  const std::uint64_t generation = scene_.generation(e);
  auto it = uploads_.find({e, bits});
  if (it != uploads_.end() && it->second.generation == generation) return it->second.args;
  DeviceUploads up(rt_, std::string(encoder_name(e)) + " " + std::to_string(bits) + "-bit ", scene_buffers_);
  Uploaded u{encoder_family(e).upload(e, bits, scene_, up), generation};
  return (uploads_[{e, bits}] = std::move(u)).args;
}

void DeviceEncoder::prepare(Encoder e, unsigned bits) {
  check_key_bits(e, bits, scene_.params());
  uploaded(e, bits);
}

DeviceEncoder::Events DeviceEncoder::enqueue(Encoder e, unsigned bits, const cl::Buffer& rays, const cl::Buffer& order,
                                             std::uint32_t count, const cl::Buffer& keys, const cl::Buffer& values) {
  check_key_bits(e, bits, scene_.params());
  // The spatial kernels read ray fields at signed 32-bit float offsets (cl/encode.cl, rs_load_ray).
  if (count >= kMaxRays)
    throw Error("a batch of " + std::to_string(count) + " rays is too large to encode (at most " +
                std::to_string(kMaxRays - 1) + "); trace it in smaller batches (a lower --resolution or --spp)");
  const std::vector<KernelArg>& inputs = uploaded(e, bits);
  Kernels& kernels = kernels_of(e, bits);
  const EncodeLaunch launch{e,     bits,   scene_, inputs, rays, order, count, keys, values, rt_, local_,
                            [&kernels](const std::string& name) -> cl::Kernel& { return kernels.at(name); }};
  Events ev;
  cl_call("encoding " + std::to_string(count) + " rays with " + std::string(encoder_name(e)) + " (" +
              std::to_string(bits) + " bits)",
          [&] {
            if (count > 0) {
              ev = encoder_family(e).enqueue(launch);
            } else {
              rt_.queue().enqueueMarkerWithWaitList(nullptr, &ev.last);
              ev.first = ev.last;
            }
          });
  return ev;
}

DeviceEncoder::Run DeviceEncoder::run(Encoder e, unsigned bits, const std::vector<RsRay>& rays,
                                      const std::vector<std::uint32_t>* order) {
  const auto n = static_cast<std::uint32_t>(order ? order->size() : rays.size());
  std::vector<std::uint32_t> identity;
  if (!order) {
    identity.resize(n);
    std::iota(identity.begin(), identity.end(), 0u);
    order = &identity;
  }
  prepare(e, bits);
  cl::Buffer ray_buf = rt_.upload("rays", rays);
  cl::Buffer order_buf = rt_.upload("ray order", *order);
  cl::Buffer key_buf = rt_.buffer("keys", std::max<std::size_t>(1, n) * key_bytes(bits));
  cl::Buffer value_buf = rt_.buffer("values", std::max<std::size_t>(1, n) * sizeof(std::uint32_t));
  const Events ev = enqueue(e, bits, ray_buf, order_buf, n, key_buf, value_buf);
  ev.wait();
  Run r;
  r.keys = download_keys(rt_, key_buf, bits, n);
  rt_.download("values", value_buf, r.values, n);
  return r;
}

std::vector<std::uint64_t> DeviceEncoder::download_keys(Runtime& rt, const cl::Buffer& keys, unsigned bits,
                                                        std::uint32_t n, const std::string& what) {
  if (bits > 32) {
    std::vector<std::uint64_t> k;
    rt.download(what, keys, k, n);
    return k;
  }
  std::vector<std::uint32_t> k;
  rt.download(what, keys, k, n);
  return {k.begin(), k.end()};
}

double DeviceEncoder::warm_up() {
  auto t0 = std::chrono::steady_clock::now();
  RsRay ray{};
  ray.d[2] = 1.0f;
  ray.tmax = RS_T_FAR;
  // One whole work-group and one ray more: the spatial kernels launch both shapes (enqueue), and
  // PoCL compiles a kernel per local size.
  std::vector<RsRay> rays(local_ + 1, ray);
  // Best effort: an encoder's cut data is per key length, and if it cannot be made here (HCC_DIR
  // whose direction bits do not fit, a device out of memory), the cell that needs it fails with
  // that message and the other cells still run.
  std::vector<Encoder> encoders = all_encoders();
  for (Encoder e : file_encoders()) encoders.push_back(e);  // loaded for this run (encode/encoder_file.h)
  for (unsigned bits : {32u, 64u})
    for (Encoder e : encoders) {
      try {
        run(e, bits, rays);
      } catch (const Error&) {
      }
    }
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace raysort
