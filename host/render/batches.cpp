#include "render/batches.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "render/pathtrace.h"
#include "util/error.h"
#include "util/fnv.h"
#include "util/text.h"

namespace raysort {

const char* baseline_order_name(BaselineOrder b) { return b == BaselineOrder::Shuffled ? "shuffled" : "pixel"; }

std::vector<BaselineOrder> parse_baseline_orders(const std::string& list) {
  static const ListAxis<BaselineOrder> axis{"--baseline",
                                            "baseline orders",
                                            "baseline order",
                                            {{"pixel", BaselineOrder::Pixel}, {"shuffled", BaselineOrder::Shuffled}}};
  return parse_list_axis(axis, list);
}

std::vector<std::uint32_t> baseline_permutation(std::size_t n, const std::string& batch_name, std::uint32_t seed) {
  std::vector<std::uint32_t> p(n);
  std::iota(p.begin(), p.end(), 0u);
  // FNV-1a of the batch name, so each batch of a frame gets its own permutation.
  const std::uint64_t h = fnv1a(batch_name);
  std::mt19937_64 rng(h ^ (std::uint64_t{seed} * 0x9e3779b97f4a7c15ull));
  for (std::size_t i = n; i > 1; --i) {
    // j uniform in [0, i - 1] (std::uniform_int_distribution differs between standard libraries).
    const auto j = static_cast<std::size_t>((static_cast<unsigned __int128>(rng()) * i) >> 64);
    std::swap(p[i - 1], p[j]);
  }
  return p;
}

ReferencedBatch in_baseline_order(const ReferencedBatch& b, BaselineOrder order, std::uint32_t seed) {
  if (order == BaselineOrder::Pixel) return b;
  const std::vector<std::uint32_t> p = baseline_permutation(b.batch.size(), b.batch.name, seed);
  ReferencedBatch out;
  out.batch.name = b.batch.name, out.batch.kind = b.batch.kind, out.batch.bounce = b.batch.bounce;
  auto move_all = [&](const auto& from, auto& to) {
    if (from.empty()) return;
    to.resize(from.size());
    for (std::size_t i = 0; i < p.size(); ++i) to[i] = from[p[i]];
  };
  move_all(b.batch.rays, out.batch.rays);
  move_all(b.batch.pixel, out.batch.pixel);
  move_all(b.batch.sample, out.batch.sample);
  move_all(b.reference_hits, out.reference_hits);
  return out;
}

std::vector<ReferencedBatch> generate_batches(const Scene& scene, const Scene::Flat& tris, const Bvh& bvh,
                                              const RayGenOptions& opts) {
  const ShadeInputs in = make_shade_inputs(scene, tris, opts);
  std::vector<ReferencedBatch> out;
  FrameOptions frame;
  frame.sink = [&](const TracedBatch& b) {
    ReferencedBatch rb;
    rb.batch.name = batch_name(b.kind, b.bounce);
    rb.batch.kind = b.kind;
    rb.batch.bounce = b.bounce;
    rb.batch.rays = b.rays;
    rb.batch.pixel.reserve(b.states.size());
    rb.batch.sample.reserve(b.states.size());
    for (const RsPathState& s : b.states) {
      rb.batch.pixel.push_back(s.path / in.spp);
      rb.batch.sample.push_back(s.path % in.spp);
    }
    rb.reference_hits = b.hits;
    out.push_back(std::move(rb));
  };
  trace_frame_host(in, bvh, frame);
  return out;
}

bool next_event_estimation(const Scene& scene) {
  return !scene.sphere_lights.empty() && scene.effects.shadow_rays_per_bounce > 0;
}

std::vector<PossibleBatch> possible_batches(bool next_event, std::uint32_t max_bounces) {
  std::vector<PossibleBatch> out{{batch_name(BatchKind::Primary, 0), BatchKind::Primary, 0}};
  for (std::uint32_t k = 0;; ++k) {
    if (next_event) out.push_back({batch_name(BatchKind::Shadow, k), BatchKind::Shadow, k});
    if (k >= max_bounces) break;
    out.push_back({batch_name(BatchKind::Bounce, k + 1), BatchKind::Bounce, k + 1});
  }
  return out;
}

std::vector<PossibleBatch> possible_batches(const Scene& scene) {
  return possible_batches(next_event_estimation(scene), scene.effects.max_bounces);
}

}  // namespace raysort
