// The host twin: every encoder's keys on the host, through its family's host key, which runs the
// key code the kernels run (cl/keys*.h).
#include "encode/encode.h"

#include "util/parallel.h"

namespace raysort {

std::uint64_t encode_ray(Encoder e, unsigned bits, const EncodeScene& scene, const RsRay& ray) {
  return encoder_family(e).host_key(e, bits, scene)(ray);
}

std::vector<std::uint64_t> encode_on_host(Encoder e, unsigned bits, const EncodeScene& scene,
                                          const std::vector<RsRay>& rays) {
  check_key_bits(e, bits, scene.params());
  // The family builds its inputs before the threads read them.
  const HostKey key = encoder_family(e).host_key(e, bits, scene);
  std::vector<std::uint64_t> keys(rays.size());
  auto work = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) keys[i] = key(rays[i]);
  };
  for_each_block(rays.size(), rays.size() < 8192, work);
  return keys;
}

std::vector<std::uint64_t> encode_on_host(Encoder e, unsigned bits, const Bvh& bvh, const Aabb& scene_box,
                                          const EncoderParams& params, const std::vector<RsRay>& rays) {
  EncodeScene scene(bvh, scene_box, params);
  return encode_on_host(e, bits, scene, rays);
}

}  // namespace raysort
