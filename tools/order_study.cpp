// order_study: how much ordering quality the encoders leave on the table (issue 21's study).
//
//   build/order_study SCENE [WIDTHxHEIGHT] [BATCH]      (default 960x540 bounce1)
//
// Host twins only (encode_on_host, the SIMT model's traversal), so the figures are deterministic
// and need no OpenCL device. For one batch it prints the SIMT lane-efficiency and distinct-nodes
// ratios (vs NoSort, pixel order) and ANC of:
//   - the paper's cut codes and the spatial codes at 32 and 64 bits (HCC, MLHCC, TwoPoint, PPC);
//   - oracles no encoder can compute, because they need the traversal itself: rays sorted by their
//     step count, and HCC's groups with each group's rays sorted by step count. They bound what
//     ordering rays of equal code could buy on lane efficiency;
//   - cheap stand-ins for a ray's traversal length inside HCC's groups (the popcount of a 64-node
//     cut, the distance to the scene-box exit, the mean step count of the origin's Morton cell: an
//     in-batch oracle), and HCC over a shortened segment (a fixed 0.25 of the scene's largest
//     extent; the true hit distance, an oracle);
//   - composite keys that spend more bits on the same information: MLHCC's 32-bit code with
//     TwoPoint's top 32 bits as a tie-break (a 64-bit key), and MLHCC with its 16 top-node bits
//     folded into the representative's index to free 11 bits for TwoPoint (a 32-bit key); HCC/24 or
//     MLHCC/24 with TwoPoint's top 8 bits (32-bit keys), and HCC/32 with TwoPoint/32 (64 bits);
//   - MLHCC/32 with another representative top node: the one the ray enters first, the one of
//     lowest HAD (the paper takes the highest), or the one the previous frame's rays entered most.
//   - MLHCC/32 with its bits split 8 | 24 or 24 | 8 between the top mask and the low cut; MLHCC
//     with PPC's first box tests as the tie-break (mlhcc/24 | ppc/8, mlhcc/32 | ppc/32);
//   - a causal estimate of traversal length (mlhcc-cost's table): the previous frame's mean step
//     count per (origin cell, direction cell), after HCC/32 or MLHCC/32 (64-bit keys) or in the last
//     8 bits of HCC/24 or MLHCC/24 (32-bit keys); the same table built from this frame (an oracle);
//     and mlhcc-cost/32 itself with 4, 8 and 12 cost bits.
// Rays keep their generation order within equal keys (a stable sort), as the radix sort does.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "bench/metrics.h"
#include "bvh/cut.h"
#include "bvh/prepared_scene.h"
#include "encode/encode.h"
#include "render/batches.h"
#include "scene/load.h"
#include "trace/tracer.h"
#include "traverse_wide.h"
#include "util/error.h"
#include "study.h"

using namespace raysort;

namespace {

// Steps of each ray's traversal on the wide tree the kernels walk (fast variant).
std::vector<std::uint32_t> step_counts(const Bvh& bvh, const std::vector<RsRay>& rays, bool any_hit) {
  WideBvh scratch;
  const WideBvh& wide = wide_of(bvh, scratch);
  std::vector<std::uint32_t> steps(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    rs_u32 len = 0;
    rs_traverse_wide_recorded(wide.nodes.data(), wide.packets.data(), rays[i], 0, any_hit ? 1 : 0, nullptr, nullptr, 0,
                              &len);
    steps[i] = len;
  }
  return steps;
}

int run_study(int argc, char** argv) {
  const study::Args args = study::parse_args("order_study", argc, argv, "960x540");
  const std::string& scene = args.scene;
  const std::string& batch = args.batch;
  const SceneOptions& options = args.options;
  const PreparedScene p = prepare_scene(scene, options);
  RayGenOptions gen;  // the matrix's seed (1)
  const std::vector<ReferencedBatch> frame = generate_batches(p.scene, p.tris, p.bvh, gen);
  const ReferencedBatch* it = &study::find_batch(frame, args);
  const std::vector<RsRay>& rays = it->batch.rays;
  const bool any_hit = it->batch.any_hit();
  const EncodeScene es(p.bvh, p.scene.bounds(), {});
  const study::OrderReport report(p.bvh, rays, any_hit, 38);
  fmt::print("{} {} at {}x{}: {} rays (lane and distinct-node ratios vs NoSort; ANC of the sorted keys)\n", scene,
             batch, options.frame.width, options.frame.height, rays.size());
  for (unsigned bits : {32u, 64u})
    for (Encoder e : {Encoder::HCC, Encoder::MLHCC, Encoder::TwoPoint, Encoder::PPC})
      report(fmt::format("{}/{}", encoder_name(e), bits), encode_on_host(e, bits, es, rays));

  const std::vector<std::uint32_t> steps = step_counts(p.bvh, rays, any_hit);
  const std::vector<std::uint64_t> hcc = encode_on_host(Encoder::HCC, 32, es, rays);
  const std::vector<std::uint64_t> mlhcc = encode_on_host(Encoder::MLHCC, 32, es, rays);
  const std::vector<std::uint64_t> twopoint = encode_on_host(Encoder::TwoPoint, 64, es, rays);
  std::vector<std::uint64_t> key(rays.size());
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = steps[i];
  report("oracle: step count", key);
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = hcc[i] << 32 | steps[i];
  report("oracle: hcc/32, then step count", key);

  const std::vector<std::uint64_t> hcc64 = encode_on_host(Encoder::HCC, 64, es, rays);
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = hcc[i] << 32 | static_cast<unsigned>(std::popcount(hcc64[i]));
  report("hcc/32, then popcount of hcc/64", key);
  const Aabb box = p.scene.bounds();
  float extent = 0.0f;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, box.max[a] - box.min[a]);
  for (std::size_t i = 0; i < key.size(); ++i) {
    const RsRay& r = rays[i];
    float exit = r.tmax;  // where the ray leaves the scene box (its origin is inside it)
    for (int a = 0; a < 3; ++a) {
      const float inv = 1.0f / r.d[a];
      exit = std::min(exit, std::max((box.min[a] - r.o[a]) * inv, (box.max[a] - r.o[a]) * inv));
    }
    const float length = std::sqrt(r.d[0] * r.d[0] + r.d[1] * r.d[1] + r.d[2] * r.d[2]);
    key[i] = hcc[i] << 32 | static_cast<std::uint32_t>(std::clamp(exit * length / extent, 0.0f, 1.0f) * 65535.0f);
  }
  report("hcc/32, then scene-box exit distance", key);
  {
    const std::vector<std::uint64_t> origin = encode_on_host(Encoder::Origin, 64, es, rays);
    std::unordered_map<std::uint64_t, std::pair<std::uint64_t, std::uint64_t>> cells;  // steps, rays
    auto cell = [&](std::size_t i) { return origin[i] >> (64 - 3 * 5); };             // 32^3 cells
    for (std::size_t i = 0; i < rays.size(); ++i) cells[cell(i)].first += steps[i], ++cells[cell(i)].second;
    for (std::size_t i = 0; i < key.size(); ++i) {
      const auto& [sum, count] = cells[cell(i)];
      key[i] = hcc[i] << 32 | (sum * 16 / count);
    }
    report("hcc/32, then origin cell's mean steps", key);
  }
  std::vector<RsRay> shortened = rays;
  for (RsRay& r : shortened)
    r.tmax = std::min(r.tmax, 0.25f * extent / std::sqrt(r.d[0] * r.d[0] + r.d[1] * r.d[1] + r.d[2] * r.d[2]));
  report("hcc/32 over 0.25 of the extent", encode_on_host(Encoder::HCC, 32, es, shortened));
  shortened = rays;
  for (std::size_t i = 0; i < rays.size(); ++i)
    if (it->reference_hits[i].tri != RS_NO_HIT) shortened[i].tmax = it->reference_hits[i].t;
  report("oracle: hcc/32 up to the hit", encode_on_host(Encoder::HCC, 32, es, shortened));

  for (std::size_t i = 0; i < key.size(); ++i) key[i] = mlhcc[i] << 32 | twopoint[i] >> 32;
  report("mlhcc/32 | twopoint/32 (64 bits)", key);
  for (std::size_t i = 0; i < key.size(); ++i) {
    // MLHCC/32 is | t (16 top-node bits) | l (16 low bits) |; the representative is the first top
    // node hit (the highest set bit of t), 16 when none.
    const auto t = static_cast<std::uint32_t>(mlhcc[i] >> 16), l = static_cast<std::uint32_t>(mlhcc[i] & 0xFFFFu);
    const std::uint64_t representative = t ? 16u - std::bit_width(t) : 16u;
    key[i] = representative << 27 | std::uint64_t{l} << 11 | twopoint[i] >> 53;
  }
  report("representative | l | twopoint/11", key);

  // 32-bit keys that give a quarter of the bits to TwoPoint's code: the cut's coarser groups, then
  // the endpoints' Morton cell as the tie-break (HCC's ANC at 32 bits is 1.1-2.1: most warps hold one
  // cut code, so the order inside a code decides their coherence).
  const std::vector<std::uint64_t> hcc24 = encode_on_host(Encoder::HCC, 24, es, rays);
  const std::vector<std::uint64_t> mlhcc24 = encode_on_host(Encoder::MLHCC, 24, es, rays);
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = hcc24[i] << 8 | twopoint[i] >> 56;
  report("hcc/24 | twopoint/8 (32 bits)", key);
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = mlhcc24[i] << 8 | twopoint[i] >> 56;
  report("mlhcc/24 | twopoint/8 (32 bits)", key);
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = hcc[i] << 32 | twopoint[i] >> 32;
  report("hcc/32 | twopoint/32 (64 bits)", key);

  // The same batch of the frame of seed 2 (the study's frame is seed 1): the previous frame the
  // causal rows below learn from, as `raysort run` draws it.
  RayGenOptions prev_gen;
  prev_gen.seed = 2;
  const std::vector<ReferencedBatch> prev_frame = generate_batches(p.scene, p.tris, p.bvh, prev_gen);
  const ReferencedBatch* prev = &study::find_batch(prev_frame, args);

  // MLHCC's representative (issue 21's optional item; the paper: a single representative "can
  // significantly impact" the quality). The paper's rule takes the overlapped top node of highest
  // HAD; the alternatives take the one the ray enters first (the kernels' slab test,
  // rs_intersect_box), the one of lowest HAD, or the one the previous frame's rays of this batch
  // entered most (node_traffic; ties: the higher HAD). The low bits are then that node's low-level
  // cut, as in rs_two_level_cut_code.
  {
    const std::vector<std::uint64_t> traffic = node_traffic(p.bvh, prev->batch.rays, any_hit);
    const TwoLevelInputs& tl = two_level_inputs(es, 32);
    const rs_u32 groups = rs_cut_group_count(tl.half);
    std::vector<std::uint64_t> entered_first(rays.size(), 0), lowest_had(rays.size(), 0), most_traffic(rays.size(), 0);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const auto top = static_cast<std::uint32_t>(mlhcc[i] >> tl.half);  // bit half − 1 − j: top node j
      if (top == 0) continue;  // no top node overlapped: key 0 under every rule
      const RsTraversalRay tr = rs_prepare_ray(rays[i]);
      RsCutRay c = rs_cut_ray(tr);
      auto key_with = [&](rs_u32 rep) {
        const rs_u64 low = rs_cut_bits_g(&c, tl.low_groups.data() + rep * groups, tl.low_count[rep], tl.half);
        return (std::uint64_t{top} << (64 - tl.half) | low) >> 32;
      };
      // The paper's rule through the same lines must give MLHCC's own key (checks the rebuild).
      if (key_with(tl.half - static_cast<rs_u32>(std::bit_width(top))) != mlhcc[i])
        throw Error(fmt::format("order_study: the rebuilt MLHCC key of ray {} differs from encode_on_host's", i));
      lowest_had[i] = key_with(tl.half - 1 - static_cast<rs_u32>(std::countr_zero(top)));
      rs_u32 first = 0;
      float nearest = INFINITY;
      for (rs_u32 j = 0; j < tl.cut.top.size(); ++j) {
        if (!(top >> (tl.half - 1 - j) & 1u)) continue;
        int hit = 0;
        const float entry = rs_intersect_box(tr, &p.bvh.nodes[tl.cut.top[j]], tr.tmax, &hit);
        if (entry < nearest) nearest = entry, first = j;
      }
      entered_first[i] = key_with(first);
      rs_u32 busiest = tl.half;
      for (rs_u32 j = 0; j < tl.cut.top.size(); ++j)
        if (top >> (tl.half - 1 - j) & 1u)
          if (busiest == tl.half || traffic[tl.cut.top[j]] > traffic[tl.cut.top[busiest]]) busiest = j;
      most_traffic[i] = key_with(busiest);
    }
    report("mlhcc/32, representative entered first", entered_first);
    report("mlhcc/32, representative of lowest HAD", lowest_had);
    report("mlhcc/32, busiest representative", most_traffic);
  }

  // MLHCC's 32 bits split unevenly between the top-level mask and the representative's low cut
  // (two_level_cut with top_count + low_count = 32; the paper splits them 16 | 16), through the
  // kernels' two-level code (rs_two_level_split_code, as mlhcc-cost's).
  for (const auto& [top_count, low_count] : {std::pair{8u, 24u}, std::pair{24u, 8u}}) {
    const TwoLevelTables t = two_level_tables(p.bvh, two_level_cut(p.bvh, es.had(), top_count, low_count), low_count);
    for (std::size_t i = 0; i < rays.size(); ++i)
      key[i] = rs_key_from_code(rs_two_level_split_code(rays[i], t.top_groups.data(), static_cast<rs_u32>(t.top.size()),
                                                        t.low_groups.data(), t.low_count.data(), top_count, low_count),
                                32);
    report(fmt::format("mlhcc/32 split {} | {}", top_count, low_count), key);
  }

  // PPC (the traversal's first box tests) after MLHCC's cut: the path prefix as the tie-break.
  {
    const std::vector<std::uint64_t> ppc32 = encode_on_host(Encoder::PPC, 32, es, rays);
    const std::vector<std::uint64_t> ppc8 = encode_on_host(Encoder::PPC, 8, es, rays);
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = mlhcc24[i] << 8 | ppc8[i];
    report("mlhcc/24 | ppc/8 (32 bits)", key);
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = mlhcc[i] << 32 | ppc32[i];
    report("mlhcc/32 | ppc/32 (64 bits)", key);
  }

  // A causal estimate of traversal length, mlhcc-cost's (docs/encoders.md): per (origin cell,
  // octahedral direction cell), the mean step count of the same batch in the frame of seed 2 (the
  // study's frame is seed 1), from cost_statistics as `raysort run` makes it. After HCC/32 or
  // MLHCC/32 (64-bit keys), or in the last 8 bits of HCC/24 or MLHCC/24 (quantised as mlhcc-cost
  // quantises); the same table built from this frame (an oracle); and mlhcc-cost itself.
  {
    std::vector<std::uint32_t> prev_steps;
    trace_reference(p.bvh, prev->batch.rays, nullptr, any_hit, &prev_steps);
    const std::vector<std::uint64_t> causal_means = cost_statistics(es.frame(), prev->batch.rays, prev_steps);
    const std::vector<std::uint64_t> oracle_means = cost_statistics(es.frame(), rays, steps);
    auto per_ray = [&](const std::vector<std::uint64_t>& means) {
      std::vector<std::uint64_t> e(rays.size());
      for (std::size_t i = 0; i < rays.size(); ++i) e[i] = means[rs_cost_bin(&es.frame(), rays[i])];
      return e;
    };
    const std::vector<std::uint64_t> causal = per_ray(causal_means), oracle = per_ray(oracle_means);
    const std::uint64_t largest = *std::max_element(causal_means.begin(), causal_means.end());
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = hcc[i] << 32 | oracle[i];
    report("oracle cost table: hcc/32 | est", key);
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = hcc[i] << 32 | causal[i];
    report("prev-frame cost table: hcc/32 | est", key);
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = mlhcc[i] << 32 | causal[i];
    report("prev-frame cost table: mlhcc/32 | est", key);
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = hcc24[i] << 8 | (causal[i] << 8) / (largest + 1);
    report("prev-frame cost table: hcc/24 | est/8", key);
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = mlhcc24[i] << 8 | (causal[i] << 8) / (largest + 1);
    report("prev-frame cost table: mlhcc/24 | est/8", key);
    for (unsigned cost_bits : {4u, 8u, 12u}) {
      EncoderParams params;
      params.cost_bits = cost_bits;
      EncodeScene with_costs(p.bvh, p.scene.bounds(), params);
      set_cost_estimates(with_costs, causal_means);
      const CostSplit split = cost_split(32, params);
      report(fmt::format("mlhcc-cost/32 ({} | {} | {})", split.top_bits, split.low_bits, split.cost_bits),
             encode_on_host(Encoder::MLHCC_COST, 32, with_costs, rays));
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return study::run("order_study", run_study, argc, argv); }
