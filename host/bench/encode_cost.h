#pragma once
// What one encoder's encode costs on one batch (raysort encodebench; the paper: PPC's encode costs
// about a trace): the encode of the runner's DeviceEncoder, paired in the rounds of the
// measurement protocol (bench/protocol.h) with a trace of the same batch, and optionally with a
// reference encoder's encode at the same key length, for a cost ratio with its interval (issue 21's
// "encode within 1.5× HCC").
#include <cstdint>
#include <optional>
#include <vector>

#include "bench/protocol.h"
#include "encode/encode.h"
#include "trace/tracer.h"

namespace raysort {

struct EncodeCost {
  Timing encode;                   // the encode kernels' time
  Estimate share;                  // encode / trace, paired per round
  std::optional<Estimate> versus;  // encode / the reference's encode, paired per round (absent: not paired)
  std::vector<std::uint64_t> keys; // the last round's keys (every round computes the same), widened
  unsigned rounds = 0;
  StopReason stop = StopReason::Rounds;
};

// The rays of one batch on the device, and the buffers its encodes and trace write.
class EncodeCostBench {
 public:
  EncodeCostBench(Runtime& rt, DeviceEncoder& encoder, Tracer& tracer, const RayBatch& batch);
  // e's encode at `bits` bits, prepared by the caller (its learned input, if any, set): paired with
  // the trace, and with versus's encode unless versus is e or takes no such key.
  EncodeCost measure(Encoder e, unsigned bits, std::optional<Encoder> versus, const ProtocolSettings& settings);

 private:
  Arm encode_arm(const char* stage, Encoder e, unsigned bits, const cl::Buffer& keys, const cl::Buffer& values);

  Runtime& rt_;
  DeviceEncoder& encoder_;
  Tracer& tracer_;
  const RayBatch& batch_;
  const std::uint32_t n_;
  // The reference's keys go to buffers of their own, so the keys returned are the encoder's.
  cl::Buffer rays_, order_, hits_, keys_, values_, versus_keys_, versus_values_;
};

}  // namespace raysort
