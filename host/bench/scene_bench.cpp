// SceneBench: a scene ready for its cells (see scene_bench.h).
#include "bench/scene_bench.h"

#include <fmt/format.h>

#include <chrono>

#include "bench/batch_file.h"
#include "render/frame_memory.h"

namespace raysort {

void check_scene_memory(const MatrixSpec& spec, const std::string& name, const SceneFacts& f, const DeviceInfo& device) {
  check_frame_memory(
      estimate_frame_memory(spec.frame.width, spec.frame.height, spec.frame.spp, f.shadow_rays_per_bounce, f.max_bounces),
      &device,
      fmt::format("scene {} at {}x{}, {} spp, {} shadow ray(s) per bounce, {} bounce(s)", name, spec.frame.width,
                  spec.frame.height, spec.frame.spp, f.shadow_rays_per_bounce, f.max_bounces));
}

namespace {

// "hcc-region's and mlhcc-cost's": the encoders of the matrix that learn from a previous frame.
std::string previous_frame_learners(const std::vector<Encoder>& encoders) {
  std::string names;
  for (Encoder e : encoders)
    if (encoder_family(e).learns_from(e) == LearnsFrom::PreviousFrame)
      names += fmt::format("{}{}'s", names.empty() ? "" : " and ", encoder_name(e));
  return names;
}

}  // namespace

SceneBench::SceneBench(Runtime& rt, PreparedScene scene, const MatrixSpec& matrix,
                       const std::function<void(const std::string&)>& note)
    : prepared(std::move(scene)), spec(matrix) {
  const std::string& name = prepared.scene.name;
  auto say = [&](const std::string& line) {
    if (note) note(line);
  };
  say(fmt::format("{}: {} triangles, BVH {:.0f} ms (SAH cost {:.4f}); generating batches", name, prepared.tris.size(),
                  bvh.build_ms, bvh.sah_cost));
  encoder = std::make_unique<DeviceEncoder>(rt, bvh, prepared.scene.bounds(), spec.params);
  RayGenOptions gen;
  gen.seed = spec.seed;
  // The previous frame first, so that the measured one is generated after it is dropped.
  if (const std::string learners = previous_frame_learners(spec.encoders); !learners.empty())
    say(fmt::format("{}: first a previous frame (seed {}) for {} statistics", name, gen.seed + 1, learners));
  learned_ = std::make_unique<LearnedInputs>(prepared, gen, encoder->scene(), spec.encoders, spec.batches);
  if (spec.ray_file.empty()) {
    batches = generate_batches(prepared.scene, prepared.tris, bvh, gen);
  } else {  // checked against the scene before any work (check_ray_file_of_matrix)
    say(fmt::format("{}: the batch of {}, its host reference traced", name, spec.ray_file));
    batches.push_back(batch_from_ray_file(read_ray_file(spec.ray_file), spec.ray_file, bvh));
  }
#ifdef RAYSORT_HAVE_EMBREE
  if (!spec.embree_paths.empty()) {
    embree_.emplace(prepared.tris, 0, spec.embree_isa);
    for (const std::string& key : spec.embree_paths) embree_paths.push_back(parse_embree_paths(key).front());
    say(fmt::format("{}: Embree {}{} BVH built in {:.0f} ms ({} threads)", name, EmbreeScene::version(),
                    spec.embree_isa == "native" ? "" : " (held to " + spec.embree_isa + ")", embree_->build_ms(),
                    embree_->threads()));
  }
#endif
  for (TraceVariant v : spec.variants)
    for (TraceLayout l : spec.layouts)
      tracers[{trace_variant_name(v), trace_layout_name(l)}] = std::make_unique<Tracer>(rt, bvh, v, l);
  encoder->warm_up();
}

const EmbreeScene* SceneBench::embree_scene() const {
#ifdef RAYSORT_HAVE_EMBREE
  return embree_ ? &*embree_ : nullptr;
#else
  return nullptr;
#endif
}

const ReferencedBatch* SceneBench::batch(const std::string& name, const std::string& baseline) {
  for (const auto& b : batches) {
    if (b.batch.name != name) continue;
    if (baseline == baseline_order_name(BaselineOrder::Pixel)) return &b;
    auto it = shuffled_.find(name);
    if (it == shuffled_.end()) it = shuffled_.emplace(name, in_baseline_order(b, BaselineOrder::Shuffled, spec.seed)).first;
    return &it->second;
  }
  return nullptr;
}

const std::vector<RsHit>& SceneBench::reference(const ReferencedBatch& b, const std::string& variant,
                                                const std::string& layout) {
  if (variant == "fast" && layout == trace_layout_name(TraceLayout::Wide)) return b.reference_hits;
  auto it = references_.find({&b, variant, layout});
  if (it == references_.end())
    it = references_
             .emplace(std::tuple{&b, variant, layout},
                      trace_reference(bvh, b.batch.rays, nullptr, b.batch.any_hit(), nullptr,
                                      parse_trace_variant(variant), parse_trace_layout(layout)))
             .first;
  return it->second;
}

double SceneBench::leaks_per_million(const ReferencedBatch& b, const std::string& variant, const std::string& layout,
                                     bool both_variants) {
  if (!both_variants || b.batch.size() == 0) return -1.0;
  const auto& mine = reference(b, variant, layout);
  const auto& other = reference(b, variant == "fast" ? "robust" : "fast", layout);
  std::size_t leaks = 0;
  for (std::size_t i = 0; i < mine.size(); ++i) leaks += mine[i].tri == RS_NO_HIT && other[i].tri != RS_NO_HIT;
  return static_cast<double>(leaks) * 1e6 / static_cast<double>(b.batch.size());
}

double SceneBench::prepare_encoder(Encoder e, unsigned bits, const std::string& name) {
  const double input_ms = learned_->use(e, name, batches, encoder->scene());
  if (input_ms < 0) return -1.0;
  const auto start = std::chrono::steady_clock::now();
  try {
    encoder->prepare(e, bits);
  } catch (const Error&) {
    // the measurement's own prepare fails the cells with this error
  }
  return input_ms + std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace raysort
