#pragma once
// What the encoders that learn are given (docs/encoders.md, "Beyond the paper"), for every batch of
// a scene, built once per scene in this one place: the runner and encodebench both ask it. An
// encoder's family says where it learns from (encode/encoder_family.h, LearnsFrom) and what it
// makes of those rays (study); nothing here knows an encoder by name.
//
// Causality: an encoder learns from rays traced before the batch it encodes, never from that batch:
//   EarlierBatch   the batch traced just before it in the same frame (generation order: primary,
//                  shadow0, bounce1, shadow1, ...); the frame's first batch has none (hcc-traffic).
//   PreviousFrame  the same batch of the frame drawn with seed + 1: another frame of the same camera
//                  and lights, standing for the one a renderer traced before (hcc-region,
//                  mlhcc-cost). A renderer would gather it in its own trace, so the frame's
//                  generation is not counted; its study is.
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bvh/prepared_scene.h"
#include "encode/encode.h"
#include "render/batches.h"

namespace raysort {

// The batch traced just before `name` in `frame`, or null for the frame's first batch and for a
// batch the frame lacks.
const ReferencedBatch* batch_before(const std::vector<ReferencedBatch>& frame, const std::string& name);

class LearnedInputs {
 public:
  // For each of `encoders` that learns from a previous frame: the frame of seed + 1, generated here
  // and dropped before this returns (so a run never holds two frames, and the measured frame is
  // generated after it), and each of its batches named in `wanted` (empty: every batch) studied by
  // the encoder's family, with `keys` (the encoder's scene: its box, frame and knobs).
  LearnedInputs(const PreparedScene& scene, const RayGenOptions& gen, const EncodeScene& keys,
                const std::vector<Encoder>& encoders, const std::vector<std::string>& wanted = {});

  struct Learned {
    std::shared_ptr<const LearnedInput> input;  // null: nothing to learn from
    double ms = 0.0;                            // the host time of its study
  };
  // What e learned for batch `name` of `frame` (the measured frame, in generation order): from the
  // previous frame, or from the batch before it in `frame`, studied at the first ask and kept (every
  // key length, trace variant and baseline order of the batch reuses it). Null when e learns nothing.
  const Learned* learned(Encoder e, const std::string& name, const std::vector<ReferencedBatch>& frame,
                         const EncodeScene& keys);
  // Makes that e's input in `keys` (its family's use) and returns the host ms of its study; -1 when
  // e learns nothing.
  double use(Encoder e, const std::string& name, const std::vector<ReferencedBatch>& frame, EncodeScene& keys);

 private:
  Learned study(Encoder e, const EncodeScene& keys, const ReferencedBatch* before) const;

  std::map<std::pair<Encoder, std::string>, Learned> learned_;
};

}  // namespace raysort
