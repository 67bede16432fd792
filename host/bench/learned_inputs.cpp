// LearnedInputs: the one place that gives the encoders that learn their rays (see learned_inputs.h).
#include "bench/learned_inputs.h"

#include <algorithm>
#include <chrono>

namespace raysort {

const ReferencedBatch* batch_before(const std::vector<ReferencedBatch>& frame, const std::string& name) {
  for (std::size_t i = 0; i < frame.size(); ++i)
    if (frame[i].batch.name == name) return i == 0 ? nullptr : &frame[i - 1];
  return nullptr;
}

LearnedInputs::LearnedInputs(const PreparedScene& scene, const RayGenOptions& gen, const EncodeScene& keys,
                             const std::vector<Encoder>& encoders, const std::vector<std::string>& wanted) {
  std::vector<Encoder> learners;
  for (Encoder e : encoders)
    if (encoder_family(e).learns_from(e) == LearnsFrom::PreviousFrame) learners.push_back(e);
  if (learners.empty()) return;
  RayGenOptions previous = gen;
  previous.seed = gen.seed + 1;
  const std::vector<ReferencedBatch> frame = generate_batches(scene.scene, scene.tris, scene.bvh, previous);
  for (const ReferencedBatch& b : frame) {
    if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), b.batch.name) == wanted.end()) continue;
    for (Encoder e : learners) learned_[{e, b.batch.name}] = study(e, keys, &b);
  }
}

LearnedInputs::Learned LearnedInputs::study(Encoder e, const EncodeScene& keys, const ReferencedBatch* before) const {
  if (!before) return {};
  const auto start = std::chrono::steady_clock::now();
  Learned l;
  l.input = encoder_family(e).study(e, keys, before->batch);
  l.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return l;
}

const LearnedInputs::Learned* LearnedInputs::learned(Encoder e, const std::string& name,
                                                     const std::vector<ReferencedBatch>& frame,
                                                     const EncodeScene& keys) {
  const LearnsFrom from = encoder_family(e).learns_from(e);
  if (from == LearnsFrom::Nothing) return nullptr;
  auto it = learned_.find({e, name});
  if (it == learned_.end())  // the previous frame lacked the batch, or an earlier batch not studied yet
    it = learned_.emplace(std::pair{e, name}, from == LearnsFrom::EarlierBatch ? study(e, keys, batch_before(frame, name))
                                                                               : Learned{})
             .first;
  return &it->second;
}

double LearnedInputs::use(Encoder e, const std::string& name, const std::vector<ReferencedBatch>& frame,
                          EncodeScene& keys) {
  const Learned* l = learned(e, name, frame, keys);
  if (!l) return -1.0;
  encoder_family(e).use(e, l->input.get(), keys);
  return l->ms;
}

}  // namespace raysort
