// The nosort family: NoSort's key is 0 for every ray, so the stable sort keeps the batch in its
// baseline order (docs/design.md, "Words").
#include "encode/encoder_family.h"

namespace raysort {

namespace {

class NoSortFamily final : public EncoderFamily {
 public:
  HostKey host_key(Encoder, unsigned, const EncodeScene&) const override {
    return [](const RsRay&) { return std::uint64_t{0}; };
  }
  // encode_nosort(count, keys, values): it reads no ray.
  EncodeEvents enqueue(const EncodeLaunch& l) const override {
    cl::Kernel& k = l.kernel(std::string(encoder_info(l.encoder).kernel));
    k.setArg(0, l.count);
    k.setArg(1, l.keys);
    k.setArg(2, l.values);
    const cl::Event ev = l.launch(k, l.count);
    return {ev, ev};
  }
};

}  // namespace

const EncoderFamily& encoder_family_nosort() {
  static const NoSortFamily family;
  return family;
}

}  // namespace raysort
