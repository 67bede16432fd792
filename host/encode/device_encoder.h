#pragma once
// DeviceEncoder: the encode kernels of cl/encode.cl for one scene on one device. What each encoder
// uploads and how its kernel is launched is its family's (encode/encoder_family.h).
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "encode/encode_scene.h"
#include "encode/encoder_family.h"
#include "runtime/runtime.h"

namespace raysort {

// An encoder's inputs (cut boxes, tables) are uploaded per (encoder, bits) at their first use (or by
// prepare()), and again after the encoder's learned input changed in scene().
class DeviceEncoder {
 public:
  DeviceEncoder(Runtime& rt, const Bvh& bvh, const Aabb& scene_box, const EncoderParams& params = {});

  using Events = EncodeEvents;
  // keys[i], values[i] = i for the ray rays[order[i]], i < count < kMaxRays. keys holds uint32
  // (bits ≤ 32) or uint64 (bits > 32). Enqueues and returns the kernels' events without waiting.
  static constexpr std::uint32_t kMaxRays = 1u << 28;
  Events enqueue(Encoder e, unsigned bits, const cl::Buffer& rays, const cl::Buffer& order, std::uint32_t count,
                 const cl::Buffer& keys, const cl::Buffer& values);
  // Uploads what (e, bits) needs now, so a timed enqueue does no host work.
  void prepare(Encoder e, unsigned bits);
  // Runs every kernel once on a few rays (PoCL compiles kernels at their first launch). Returns ms.
  double warm_up();

  static std::size_t key_bytes(unsigned bits) { return bits > 32 ? 8 : 4; }
  // The first n keys of `bits` bits in a device buffer, widened to 64 bits.
  static std::vector<std::uint64_t> download_keys(Runtime& rt, const cl::Buffer& keys, unsigned bits, std::uint32_t n,
                                                  const std::string& what = "keys");

  struct Run {
    std::vector<std::uint64_t> keys;  // widened to 64 bits
    std::vector<std::uint32_t> values;
  };
  // Uploads rays (order null = identity), encodes them once and returns keys and values. Untimed:
  // timed encodes go through the measurement protocol (bench/protocol.h) with enqueue().
  Run run(Encoder e, unsigned bits, const std::vector<RsRay>& rays, const std::vector<std::uint32_t>* order = nullptr);

  const EncodeScene& scene() const { return scene_; }
  // Where an encoder's learned input is set (e.g. set_node_traffic(encoder.scene(), visits), or its
  // family's use()); the next prepare or enqueue of that encoder uploads its inputs again.
  EncodeScene& scene() { return scene_; }
  std::size_t local_size() const { return local_; }

 private:
  struct Uploaded {
    std::vector<KernelArg> args;
    std::uint64_t generation = 0;  // EncodeScene::generation of the encoder when uploaded
  };
  const std::vector<KernelArg>& uploaded(Encoder e, unsigned bits);
  using Kernels = std::map<std::string, cl::Kernel>;  // by kernel name without the suffix
  // e's kernels for keys of `bits` bits: cl/encode.cl's, or those of e's own program
  // (EncoderFamily::own_program: an encoder from a file), created on first use.
  Kernels& kernels_of(Encoder e, unsigned bits);

  Runtime& rt_;
  EncodeScene scene_;
  Kernels k32_, k64_;
  std::map<Encoder, std::pair<Kernels, Kernels>> own_kernels_;  // _k32, _k64 of an own program
  std::map<std::pair<Encoder, unsigned>, Uploaded> uploads_;
  std::map<std::string, cl::Buffer> scene_buffers_;  // uploaded once per scene (DeviceUploads::scene_buffer)
  std::size_t local_ = 64;
};

}  // namespace raysort
