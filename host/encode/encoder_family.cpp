// What every family shares: the default binding and launch of a family kernel, the learning
// defaults, and the key-length check that asks the family (see encoder_family.h).
#include "encode/encoder_family.h"

#include "encode/encode_scene.h"
#include "util/error.h"

namespace raysort {

void EncodeEvents::wait() const {
  // The queue is in order: the last kernel ends after the first.
  cl_call("waiting for the encode kernels", [&] { last.wait(); });
}

double EncodeEvents::ms() const { return event_span_ms(first, last); }

void EncodeLaunch::set_args(cl::Kernel& k, const std::vector<KernelArg>& leading) const {
  cl_uint arg = 0;
  for (const KernelArg& a : leading)
    std::visit(
        [&](const auto& v) {
          if constexpr (std::is_same_v<std::decay_t<decltype(v)>, RsEncodeFrame>)
            k.setArg(arg++, sizeof(RsEncodeFrame), &v);  // by value (cl/encode.cl: `const RsEncodeFrame frame`)
          else
            k.setArg(arg++, v);
        },
        a);
  k.setArg(arg++, rays);
  k.setArg(arg++, order);
  k.setArg(arg++, count);
  k.setArg(arg++, static_cast<cl_uint>(bits));
  k.setArg(arg++, keys);
  k.setArg(arg++, values);
}

cl::Event EncodeLaunch::launch(cl::Kernel& k, std::size_t items) const {
  cl::Event ev;
  rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(Runtime::padded(items, local)), cl::NDRange(local),
                                  nullptr, &ev);
  return ev;
}

std::string EncoderFamily::key_bits_problem(Encoder, unsigned, const EncoderParams&) const { return ""; }

std::vector<KernelArg> EncoderFamily::upload(Encoder, unsigned, const EncodeScene&, DeviceUploads&) const { return {}; }

EncodeEvents EncoderFamily::enqueue(const EncodeLaunch& l) const {
  cl::Kernel& k = l.kernel(std::string(encoder_info(l.encoder).kernel));
  l.set_args(k, l.inputs);
  const unsigned per_item = rays_per_work_item();
  const cl::Event ev = l.launch(k, (std::size_t(l.count) + per_item - 1) / per_item);
  return {ev, ev};
}

std::shared_ptr<const LearnedInput> EncoderFamily::study(Encoder, const EncodeScene&, const RayBatch&) const {
  return nullptr;
}

void EncoderFamily::use(Encoder, const LearnedInput*, EncodeScene&) const {}

std::string key_bits_problem(Encoder e, unsigned bits, const EncoderParams& params) {
  if (bits < 1 || bits > max_key_bits(e))
    return std::string(encoder_name(e)) + " keys have 1 to " + std::to_string(max_key_bits(e)) + " bits, not " +
           std::to_string(bits);
  return encoder_family(e).key_bits_problem(e, bits, params);
}

void check_key_bits(Encoder e, unsigned bits, const EncoderParams& params) {
  std::string why = key_bits_problem(e, bits, params);
  if (!why.empty()) throw Error(why);
}

void build_own_programs(Runtime& rt, const std::vector<Encoder>& encoders) {
  for (Encoder e : encoders) (void)encoder_family(e).own_program(e, rt);
}

bool has_host_twin(Encoder e) { return encoder_family(e).has_host_twin(); }

}  // namespace raysort
