#pragma once
// A scene loaded for measuring, as the runner measures its cells and encodebench one batch of it:
// triangles and BVH, the batches its effects imply (generated once: every encoder sees the same
// rays), its tracers and encode kernels, and what the encoders that learn are given
// (bench/learned_inputs.h), all from a matrix (bench/matrix.h).
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "bench/learned_inputs.h"
#include "bench/matrix.h"
#include "bench/shard.h"
#include "bvh/prepared_scene.h"
#include "embree/embree_reference.h"
#include "encode/encode.h"
#include "render/batches.h"
#include "trace/tracer.h"

namespace raysort {

// The frame of scene `name` at the matrix's resolution and spp must fit the device and the host (a
// refusal names the scene, the estimate and the limit; render/frame_memory.h).
void check_scene_memory(const MatrixSpec& spec, const std::string& name, const SceneFacts& facts,
                        const DeviceInfo& device);

class SceneBench {
 public:
  // `note` gets a line for each step that takes a while (the runner's progress on stderr).
  SceneBench(Runtime& rt, PreparedScene scene, const MatrixSpec& spec,
             const std::function<void(const std::string&)>& note = {});

  PreparedScene prepared;
  const Bvh& bvh = prepared.bvh;
  const MatrixSpec& spec;
  std::unique_ptr<DeviceEncoder> encoder;
  std::vector<ReferencedBatch> batches;  // in generation (pixel) order
  std::map<std::pair<std::string, std::string>, std::unique_ptr<Tracer>> tracers;  // by variant, class
  std::vector<EmbreePath> embree_paths;

  // The batch in a baseline order (render/batches.h), or null when the frame has no such batch.
  const ReferencedBatch* batch(const std::string& name, const std::string& baseline);
  // The host twin's hits of a variant and trace class. The batch's own is the fast one on the wide
  // tree (render/batches.h); any other is traced when a cell first needs it (on the binary tree, or
  // in packets, of two equally near triangles the other may win).
  const std::vector<RsHit>& reference(const ReferencedBatch& b, const std::string& variant, const std::string& layout);
  // Rays this variant misses that the other one hits in the same class, per million (-1 unless
  // both variants run).
  double leaks_per_million(const ReferencedBatch& b, const std::string& variant, const std::string& layout,
                           bool both_variants);
  // Readies encoder e for keys of `bits` bits on batch `name`: its learned input for that batch set
  // (LearnedInputs::use) and its inputs uploaded, outside any timed round. Returns the host ms of
  // both, the cells' cut_ms, or -1 for an encoder that learns nothing (its upload is not a per-batch
  // cost). A failing upload is left to the measurement, which fails the cells with its message.
  double prepare_encoder(Encoder e, unsigned bits, const std::string& name);
  // Embree's scene for the cells' stages (null without --embree-paths).
  const EmbreeScene* embree_scene() const;

 private:
  std::unique_ptr<LearnedInputs> learned_;
  std::map<std::string, ReferencedBatch> shuffled_;  // by batch name, made when first asked
  // The host twin's hits by batch, variant and class.
  std::map<std::tuple<const ReferencedBatch*, std::string, std::string>, std::vector<RsHit>> references_;
#ifdef RAYSORT_HAVE_EMBREE
  // Embree's scene of the same triangles (run --embree-paths): built once per scene, its paths
  // arms of every cell's rounds (bench/cell_measure.h).
  std::optional<EmbreeScene> embree_;
#endif
};

}  // namespace raysort
