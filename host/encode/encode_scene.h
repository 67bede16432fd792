#pragma once
// What the keys of one scene depend on: the scene box frame, HAD, HCC cuts, and each encoder's own
// inputs and learned input, which its family keeps here (EncoderState) and builds on first use.
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "bvh/bvh.h"
#include "encode/encoder.h"
#include "encode/encoder_params.h"

namespace raysort {

// One encoder's state in an EncodeScene, of its family's own type: its inputs per key length and
// what it learned. Made on the family's first ask.
struct EncoderState {
  virtual ~EncoderState() = default;
};

// Computed on the host once per scene; the inputs are cached per key length. Holds a reference to
// the BVH: keep it alive as long as this.
class EncodeScene {
 public:
  EncodeScene(const Bvh& bvh, const Aabb& scene_box, const EncoderParams& params = {});

  const Bvh& bvh() const { return *bvh_; }
  const EncoderParams& params() const { return params_; }
  const Aabb& box() const { return box_; }  // the scene box the keys quantise and hcc-region splits
  const RsEncodeFrame& frame() const { return frame_; }
  const std::vector<double>& had() const { return had_; }

  // HCC cut of `size` nodes (node indices, bit order), cached: HCC's, HCC_DIR's and hcc-region's
  // fallback, and render --overlay's.
  const std::vector<std::uint32_t>& hcc_cut(unsigned size) const;

  // Encoder e's state, made on first use. A family asks for its own type only (the table gives
  // each encoder one family). Building inputs into it is caching, so a const scene may.
  template <class State>
  State& state(Encoder e) const {
    std::unique_ptr<EncoderState>& slot = states_[e];
    if (!slot) slot = std::make_unique<State>();
    return static_cast<State&>(*slot);
  }
  // A new state for e, replacing its inputs (a family's learned input changed): DeviceEncoder
  // uploads e's inputs again when this count has moved since it last did.
  template <class State>
  State& renew_state(Encoder e) {
    State& fresh = state<State>(e) = State{};
    ++generations_[e];
    return fresh;
  }
  std::uint64_t generation(Encoder e) const;

 private:
  const Bvh* bvh_;
  EncoderParams params_;
  RsEncodeFrame frame_{};
  Aabb box_;
  std::vector<double> had_;
  mutable std::map<unsigned, std::vector<std::uint32_t>> hcc_cuts_;
  mutable std::map<Encoder, std::unique_ptr<EncoderState>> states_;
  std::map<Encoder, std::uint64_t> generations_;
};

// The inputs of `bits` from a family's cache, made by build() on the first ask.
template <class Inputs, class Build>
const Inputs& cached_inputs(std::map<unsigned, Inputs>& cache, unsigned bits, Build&& build) {
  auto it = cache.find(bits);
  if (it == cache.end()) it = cache.emplace(bits, build()).first;
  return it->second;
}

}  // namespace raysort
