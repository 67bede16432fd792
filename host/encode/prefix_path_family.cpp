// The prefix-path family, PPC (Xiang et al. §4.1): the first b box tests of a closest-hit traversal
// in fixed left-first order (cl/keys_ppc.h). It reads the BVH itself, uploaded once per scene.
#include "encode/encode_scene.h"
#include "encode/encoder_family.h"
#include "keys_ppc.h"

namespace raysort {

namespace {

class PrefixPathFamily final : public EncoderFamily {
 public:
  HostKey host_key(Encoder, unsigned bits, const EncodeScene& scene) const override {
    const Bvh& bvh = scene.bvh();
    return [&bvh, bits](const RsRay& ray) {
      return rs_key_from_code(rs_prefix_path_code(bvh.nodes.data(), bvh.triangles.data(), ray, bits), bits);
    };
  }
  std::vector<KernelArg> upload(Encoder, unsigned, const EncodeScene& scene, DeviceUploads& up) const override {
    return {up.scene_buffer("bvh nodes (ppc)", scene.bvh().nodes), up.scene_buffer("triangles (ppc)", scene.bvh().triangles)};
  }
};

}  // namespace

const EncoderFamily& encoder_family_prefix_path() {
  static const PrefixPathFamily family;
  return family;
}

}  // namespace raysort
