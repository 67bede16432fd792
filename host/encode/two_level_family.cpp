// The two-level family: MLHCC (see two_level_family.h).
#include "encode/two_level_family.h"

#include <map>

#include "encode/encoder_family.h"

namespace raysort {

namespace {

struct TwoLevelState : EncoderState {
  std::map<unsigned, TwoLevelInputs> by_bits;
};

class TwoLevelFamily final : public EncoderFamily {
 public:
  std::string key_bits_problem(Encoder, unsigned bits, const EncoderParams&) const override {
    if (bits % 2 != 0)
      return "mlhcc keys need an even number of bits (half top-level, half low-level cut nodes), not " +
             std::to_string(bits);
    return "";
  }

  HostKey host_key(Encoder, unsigned bits, const EncodeScene& scene) const override {
    const TwoLevelInputs& t = two_level_inputs(scene, bits);
    return [&t, bits](const RsRay& ray) {
      return rs_key_from_code(rs_two_level_cut_code(ray, t.top_groups.data(), static_cast<rs_u32>(t.top.size()),
                                                    t.low_groups.data(), t.low_count.data(), t.half),
                              bits);
    };
  }

  std::vector<KernelArg> upload(Encoder, unsigned bits, const EncodeScene& scene, DeviceUploads& up) const override {
    const TwoLevelInputs& t = two_level_inputs(scene, bits);
    return {up.buffer("top-level cut boxes", t.top_groups), static_cast<cl_uint>(t.top.size()),
            up.buffer("low-level cut boxes", t.low_groups), up.buffer("low-level cut sizes", t.low_count),
            static_cast<cl_uint>(bits / 2)};
  }

  // MLHCC's work-items take RS_TWO_LEVEL_RAYS rays each (cl/keys_cut.h, rs_two_level_cut_code2).
  unsigned rays_per_work_item() const override { return RS_TWO_LEVEL_RAYS; }
};

}  // namespace

const EncoderFamily& encoder_family_two_level() {
  static const TwoLevelFamily family;
  return family;
}

const TwoLevelInputs& two_level_inputs(const EncodeScene& scene, unsigned bits) {
  return cached_inputs(scene.state<TwoLevelState>(Encoder::MLHCC).by_bits, bits, [&] {
    check_key_bits(Encoder::MLHCC, bits, scene.params());
    TwoLevelInputs t;
    t.half = bits / 2;
    t.cut = two_level_cut(scene.bvh(), scene.had(), t.half);
    static_cast<TwoLevelTables&>(t) = two_level_tables(scene.bvh(), t.cut, t.half);
    return t;
  });
}

}  // namespace raysort
