// DeviceEncoder: the encode kernels of cl/encode.cl on one device (see encode.h).
#include <algorithm>
#include <chrono>
#include <numeric>

#include "encode/encode.h"

namespace raysort {

namespace {

constexpr cl_uint kSpatialFirstArg = 3;  // encode_<spatial>_k*(frame, rays, order, first, ...)

EncoderFamily family(Encoder e) { return encoder_info(e).family; }

// A kernel without a count guard (the spatial encoders, cl/encode.cl) over [0, count): whole
// work-groups over [0, full), then the rest, one work-item per group, with argument first_arg set
// to full. Events: the first launch and the last.
DeviceEncoder::Events enqueue_whole_groups(cl::CommandQueue& queue, cl::Kernel& k, std::size_t count,
                                           std::size_t local, cl_uint first_arg) {
  const std::size_t full = count / local * local, rest = count - full;
  DeviceEncoder::Events ev;
  if (full > 0) queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(full), cl::NDRange(local), nullptr, &ev.first);
  if (rest > 0) {
    k.setArg(first_arg, static_cast<cl_uint>(full));
    queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(rest), cl::NDRange(1), nullptr, &ev.last);
  }
  if (!ev.first()) ev.first = ev.last;
  if (!ev.last()) ev.last = ev.first;
  return ev;
}

}  // namespace

DeviceEncoder::DeviceEncoder(Runtime& rt, const Bvh& bvh, const Aabb& scene_box, const EncoderParams& params)
    : rt_(rt), scene_(bvh, scene_box, params) {
  nodes_ = rt.upload("bvh nodes (ppc)", bvh.nodes);
  triangles_ = rt.upload("triangles (ppc)", bvh.triangles);
  cl::Program program = rt.build({"cl/encode.cl"});
  cl_call("creating the encode kernels", [&] {
    for (auto [k, suffix] : {std::pair{&k32_, "k32"}, std::pair{&k64_, "k64"}}) {
      for (const EncoderInfo& info : encoder_table())
        k->by_encoder[info.id] = cl::Kernel(program, (std::string(info.kernel) + "_" + suffix).c_str());
      // HCC_DIR's two passes when it has more than one direction bit (enqueue).
      k->box_set_or = cl::Kernel(program, (std::string("encode_box_set_or_") + suffix).c_str());
      k->direction = cl::Kernel(program, (std::string("encode_direction_") + suffix).c_str());
    }
  });
  // 64 work-items suit PoCL (the group is a loop; 256 measured no faster) and GPUs (two warps).
  // Cut boxes are read from __constant memory (broadcast on GPUs; no copy or barrier on PoCL).
  local_ = std::min<std::size_t>(64, rt.info().max_work_group_size);
}

const DeviceEncoder::Uploaded& DeviceEncoder::uploaded(Encoder e, unsigned bits) {
  const auto key = std::make_pair(static_cast<int>(e), bits);
  auto it = uploads_.find(key);
  if (it != uploads_.end()) return it->second;
  Uploaded u;
  const std::string what = std::string(encoder_name(e)) + " " + std::to_string(bits) + "-bit ";
  if (family(e) == EncoderFamily::BoxSet) {
    const auto& set = scene_.cut_set(e, bits);
    u.a = rt_.upload(what + "cut boxes", set.groups);
    u.n = set.box_count;
  } else if (family(e) == EncoderFamily::RegionCut) {
    const auto& g = scene_.regions(bits);
    u.a = rt_.upload(what + "region cut boxes", g.groups);
    u.b = rt_.upload(what + "region cut sizes", g.counts);
    u.c = rt_.upload(what + "region cells", g.cells);
    u.n = static_cast<std::uint32_t>(g.counts.size());
  } else if (family(e) == EncoderFamily::TwoLevel) {
    const auto& t = scene_.two_level(bits);
    u.a = rt_.upload(what + "top-level cut boxes", t.top_groups);
    u.b = rt_.upload(what + "low-level cut boxes", t.low_groups);
    u.c = rt_.upload(what + "low-level cut sizes", t.low_count);
    u.n = static_cast<std::uint32_t>(t.top.size());
  } else if (family(e) == EncoderFamily::CostCut) {
    const auto& t = scene_.cost_cut(bits);
    u.a = rt_.upload(what + "top-level cut boxes", t.top_groups);
    u.b = rt_.upload(what + "low-level cut boxes", t.low_groups);
    u.c = rt_.upload(what + "low-level cut sizes", t.low_count);
    u.d = rt_.upload(what + "cost estimates", t.cost);
    u.n = static_cast<std::uint32_t>(t.top.size());
  }
  return uploads_.emplace(key, std::move(u)).first->second;
}

void DeviceEncoder::prepare(Encoder e, unsigned bits) {
  check_key_bits(e, bits, scene_.params());
  uploaded(e, bits);
}

void DeviceEncoder::drop_uploads(Encoder e) {
  std::erase_if(uploads_, [e](const auto& kv) { return kv.first.first == static_cast<int>(e); });
}

void DeviceEncoder::set_node_traffic(std::vector<std::uint64_t> visits) {
  scene_.set_node_traffic(std::move(visits));
  drop_uploads(Encoder::HCC_TRAFFIC);
}

void DeviceEncoder::set_region_statistics(RegionStatistics stats) {
  scene_.set_region_statistics(std::move(stats));
  drop_uploads(Encoder::HCC_REGION);
}

void DeviceEncoder::set_cost_estimates(std::vector<std::uint64_t> mean_steps) {
  scene_.set_cost_estimates(std::move(mean_steps));
  drop_uploads(Encoder::MLHCC_COST);
}

void DeviceEncoder::Events::wait() const {
  // The queue is in order: the last kernel ends after the first.
  cl_call("waiting for the encode kernels", [&] { last.wait(); });
}

double DeviceEncoder::Events::ms() const {
  const auto start = first.getProfilingInfo<CL_PROFILING_COMMAND_START>();
  const auto end = last.getProfilingInfo<CL_PROFILING_COMMAND_END>();
  return static_cast<double>(end - start) * 1e-6;
}

DeviceEncoder::Events DeviceEncoder::enqueue(Encoder e, unsigned bits, const cl::Buffer& rays, const cl::Buffer& order,
                                             std::uint32_t count, const cl::Buffer& keys, const cl::Buffer& values) {
  check_key_bits(e, bits, scene_.params());
  // The spatial kernels read ray fields at signed 32-bit float offsets (cl/encode.cl, rs_load_ray).
  if (count >= kMaxRays)
    throw Error("a batch of " + std::to_string(count) + " rays is too large to encode (at most " +
                std::to_string(kMaxRays - 1) + "); trace it in smaller batches (a lower --resolution or --spp)");
  Kernels& ks = bits > 32 ? k64_ : k32_;
  const Uploaded& u = uploaded(e, bits);
  cl::Kernel* k = nullptr;
  cl::Event ev;
  cl::Event first;  // the first of two kernels: HCC_DIR's direction pass, or a spatial kernel's whole groups
  // HCC_DIR with more than one direction bit: the direction pass first (atan2, acos), then the box
  // bits ORed in. One direction bit comes from the signs of dx and dy (keys.h, rs_direction_top_bit)
  // in the box-set kernel itself.
  const bool two_pass = e == Encoder::HCC_DIR && count > 0 && scene_.params().direction_bits > 1;
  if (two_pass) {
    const cl_uint dir = scene_.params().direction_bits;
    cl_call("encoding the direction bits of " + std::to_string(count) + " rays (HCC_DIR, " + std::to_string(bits) +
                " bits)",
            [&] {
              cl::Kernel& kd = ks.direction;
              int arg = 0;
              kd.setArg(arg++, rays);
              kd.setArg(arg++, order);
              kd.setArg(arg++, count);
              kd.setArg(arg++, static_cast<cl_uint>(bits - dir));
              kd.setArg(arg++, dir);
              kd.setArg(arg++, static_cast<cl_uint>(bits));
              kd.setArg(arg++, keys);
              kd.setArg(arg++, values);
              rt_.queue().enqueueNDRangeKernel(kd, cl::NullRange, cl::NDRange(Runtime::padded(count, local_)),
                                               cl::NDRange(local_), nullptr, &first);
            });
  }
  cl_call("encoding " + std::to_string(count) + " rays with " + std::string(encoder_name(e)) + " (" +
              std::to_string(bits) + " bits)",
          [&] {
            int arg = 0;
            k = two_pass ? &ks.box_set_or : &ks.by_encoder.at(e);
            switch (family(e)) {
              case EncoderFamily::None: break;
              case EncoderFamily::Spatial:
                k->setArg(arg++, sizeof(RsEncodeFrame), &scene_.frame());
                k->setArg(arg++, rays);
                k->setArg(arg++, order);
                k->setArg(arg++, 0u);  // first: set per launch below
                break;
              case EncoderFamily::BoxSet: {
                // HCC_DIR: the direction bits are in keys already; OR in the box field.
                const cl_uint dir = e == Encoder::HCC_DIR ? scene_.params().direction_bits : 0u;
                k->setArg(arg++, u.a);
                k->setArg(arg++, u.n);
                k->setArg(arg++, static_cast<cl_uint>(bits - dir));
                k->setArg(arg++, two_pass ? 0u : dir);
                k->setArg(arg++, rays);
                k->setArg(arg++, order);
                k->setArg(arg++, count);
                break;
              }
              case EncoderFamily::RegionCut: {
                const auto& g = scene_.regions(bits);
                k->setArg(arg++, u.c);
                k->setArg(arg++, static_cast<cl_uint>(g.region_bits));
                k->setArg(arg++, u.a);
                k->setArg(arg++, u.b);
                k->setArg(arg++, static_cast<cl_uint>(g.row_size));
                k->setArg(arg++, rays);
                k->setArg(arg++, order);
                k->setArg(arg++, count);
                break;
              }
              case EncoderFamily::TwoLevel:
                k->setArg(arg++, u.a);
                k->setArg(arg++, u.n);
                k->setArg(arg++, u.b);
                k->setArg(arg++, u.c);
                k->setArg(arg++, static_cast<cl_uint>(bits / 2));
                k->setArg(arg++, rays);
                k->setArg(arg++, order);
                k->setArg(arg++, count);
                break;
              case EncoderFamily::CostCut: {
                const CostSplit split = scene_.cost_cut(bits).split;
                k->setArg(arg++, sizeof(RsEncodeFrame), &scene_.frame());
                k->setArg(arg++, u.a);
                k->setArg(arg++, u.n);
                k->setArg(arg++, u.b);
                k->setArg(arg++, u.c);
                k->setArg(arg++, static_cast<cl_uint>(split.top_bits));
                k->setArg(arg++, static_cast<cl_uint>(split.low_bits));
                k->setArg(arg++, u.d);
                k->setArg(arg++, rays);
                k->setArg(arg++, order);
                k->setArg(arg++, count);
                break;
              }
              case EncoderFamily::PrefixPath:
                k->setArg(arg++, nodes_);
                k->setArg(arg++, triangles_);
                k->setArg(arg++, rays);
                k->setArg(arg++, order);
                k->setArg(arg++, count);
                break;
            }
            if (family(e) == EncoderFamily::None)
              k->setArg(arg++, count);
            else
              k->setArg(arg++, static_cast<cl_uint>(bits));
            k->setArg(arg++, keys);
            k->setArg(arg++, values);
            // MLHCC's work-items take RS_TWO_LEVEL_RAYS rays each (cl/keys_cut.h, rs_two_level_cut_code2).
            const std::size_t items = family(e) == EncoderFamily::TwoLevel
                                          ? (std::size_t(count) + RS_TWO_LEVEL_RAYS - 1) / RS_TWO_LEVEL_RAYS
                                          : count;
            if (count > 0 && family(e) == EncoderFamily::Spatial) {
              const Events launched = enqueue_whole_groups(rt_.queue(), *k, count, local_, kSpatialFirstArg);
              first = launched.first;
              ev = launched.last;
            } else if (count > 0)
              rt_.queue().enqueueNDRangeKernel(*k, cl::NullRange, cl::NDRange(Runtime::padded(items, local_)),
                                               cl::NDRange(local_), nullptr, &ev);
            else
              rt_.queue().enqueueMarkerWithWaitList(nullptr, &ev);
          });
  return Events{first() ? first : ev, ev};
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
  if (bits > 32) {
    rt_.download("keys", key_buf, r.keys, n);
  } else {
    std::vector<std::uint32_t> k32;
    rt_.download("keys", key_buf, k32, n);
    r.keys.assign(k32.begin(), k32.end());
  }
  rt_.download("values", value_buf, r.values, n);
  return r;
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
  for (unsigned bits : {32u, 64u})
    for (Encoder e : all_encoders()) {
      try {
        run(e, bits, rays);
      } catch (const Error&) {
      }
    }
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace raysort
