// EncodeScene: the per-scene inputs every encoder shares (see encode_scene.h).
#include "encode/encode_scene.h"

#include "bvh/cut.h"
#include "bvh/had.h"

namespace raysort {

EncodeScene::EncodeScene(const Bvh& bvh, const Aabb& scene_box, const EncoderParams& params)
    : bvh_(&bvh), params_(params), box_(scene_box.empty() ? Aabb{{0, 0, 0}, {0, 0, 0}} : scene_box) {
  for (int a = 0; a < 3; ++a) {
    frame_.box_min[a] = box_.min[a];
    frame_.box_max[a] = box_.max[a];
    const float extent = box_.max[a] - box_.min[a];
    frame_.inv_extent[a] = extent > 0.0f ? 1.0f / extent : 0.0f;  // flat axis: every t is 0
  }
  frame_.twopoint_length = params.twopoint_length_fraction * box_.largest_extent();
  had_ = hierarchically_accumulated_density(bvh, params.had_lambda);
}

const std::vector<std::uint32_t>& EncodeScene::hcc_cut(unsigned size) const {
  auto it = hcc_cuts_.find(size);
  if (it == hcc_cuts_.end()) it = hcc_cuts_.emplace(size, hierarchy_cut(*bvh_, had_, size)).first;
  return it->second;
}

std::uint64_t EncodeScene::generation(Encoder e) const {
  const auto it = generations_.find(e);
  return it == generations_.end() ? 0 : it->second;
}

}  // namespace raysort
