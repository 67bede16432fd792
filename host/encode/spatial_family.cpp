// The spatial family (Meister et al. 2020; Xiang et al. §3.2): Origin, Reis, Costa, Aila and
// TwoPoint, codes of a ray's origin, direction or estimated termination point in the scene box.
// Each has a kernel of its own, made from its row of the encoder list (cl/encode.cl,
// RS_DEFINE_SPATIAL_KERNEL), and reads only the scene frame, so a new one is its key function in
// cl/keys_spatial.h and its row in cl/encoders.h.
#include "encode/encode_scene.h"
#include "encode/encoder_family.h"
#include "keys_spatial.h"

namespace raysort {

namespace {

constexpr cl_uint kFirstArg = 3;  // encode_<spatial>_k*(frame, rays, order, first, bits, keys, values)

class SpatialFamily final : public EncoderFamily {
 public:
  HostKey host_key(Encoder e, unsigned bits, const EncodeScene& scene) const override {
    const RsEncodeFrame* frame = &scene.frame();
    return [e, bits, frame](const RsRay& ray) {
      return rs_key_from_code(rs_spatial_code(static_cast<int>(e), frame, ray), bits);
    };
  }

  // The spatial kernels have no count guard (cl/encode.cl): whole work-groups over [0, full), then
  // the rest, one work-item per group, with argument `first` set to full.
  EncodeEvents enqueue(const EncodeLaunch& l) const override {
    cl::Kernel& k = l.kernel(std::string(encoder_info(l.encoder).kernel));
    cl_uint arg = 0;
    k.setArg(arg++, sizeof(RsEncodeFrame), &l.scene.frame());
    k.setArg(arg++, l.rays);
    k.setArg(arg++, l.order);
    k.setArg(arg++, 0u);  // first
    k.setArg(arg++, static_cast<cl_uint>(l.bits));
    k.setArg(arg++, l.keys);
    k.setArg(arg++, l.values);
    const std::size_t full = l.count / l.local * l.local, rest = l.count - full;
    EncodeEvents ev;
    if (full > 0)
      l.rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(full), cl::NDRange(l.local), nullptr, &ev.first);
    if (rest > 0) {
      k.setArg(kFirstArg, static_cast<cl_uint>(full));
      l.rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(rest), cl::NDRange(1), nullptr, &ev.last);
    }
    if (!ev.first()) ev.first = ev.last;
    if (!ev.last()) ev.last = ev.first;
    return ev;
  }
};

}  // namespace

const EncoderFamily& encoder_family_spatial() {
  static const SpatialFamily family;
  return family;
}

}  // namespace raysort
