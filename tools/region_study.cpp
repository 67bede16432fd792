// region_study: what each part of hcc-region buys (issue 21's region code on the open scenes).
//
//   build/region_study SCENE [WIDTHxHEIGHT] [BATCH]      (default 1920x1080 bounce1)
//
// Host twins only (encode_on_host, the SIMT model's traversal), so the figures are deterministic
// and need no OpenCL device. For one batch it prints the SIMT lane-efficiency and distinct-nodes
// ratios (vs NoSort, pixel order) and ANC of HCC, MLHCC and PPC at 32 bits, and of 32-bit region
// codes for r = 2 … 6 region bits that differ in two choices (docs/encoders.md, "hcc-region"):
//   - where the regions are: each split halving its cell (RegularGrid's cells: the first version)
//     or at the median origin of the previous frame's rays (seed 2; the study's frame is seed 1);
//   - which nodes a region's bits name: HAD among the nodes overlapping the region (the first
//     version) or HAD blended half and half with the traffic of the previous frame's rays that
//     started in the region.
// "median + traffic" is hcc-region as `raysort run` measures it (encode_on_host with
// region_statistics); "halved + HAD" is hcc-region without statistics.
#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <string>
#include <vector>

#include "bench/metrics.h"
#include "bench/runner.h"
#include "bvh/cut.h"
#include "bvh/prepared_scene.h"
#include "encode/encode.h"
#include "render/batches.h"
#include "scene/load.h"
#include "util/error.h"
#include "study.h"

using namespace raysort;

namespace {

int run_study(int argc, char** argv) {
  const study::Args args = study::parse_args("region_study", argc, argv, "1920x1080");
  const SceneOptions& options = args.options;
  const PreparedScene p = prepare_scene(args.scene, options);
  RayGenOptions gen;  // the matrix's seed (1)
  RayGenOptions previous_gen;
  previous_gen.seed = 2;
  std::vector<RsRay> previous;
  {
    const std::vector<ReferencedBatch> frame = generate_batches(p.scene, p.tris, p.bvh, previous_gen);
    previous = study::find_batch(frame, args).batch.rays;
  }
  const std::vector<ReferencedBatch> frame = generate_batches(p.scene, p.tris, p.bvh, gen);
  const ReferencedBatch& measured = study::find_batch(frame, args);
  const std::vector<RsRay>& rays = measured.batch.rays;
  const bool any_hit = measured.batch.any_hit();
  const Aabb box = p.scene.bounds();
  const EncodeScene es(p.bvh, box, {});
  const study::OrderReport report(p.bvh, rays, any_hit, 36);
  fmt::print("{} {} at {}x{}: {} rays, {} in the previous frame (lane and distinct-node ratios vs NoSort; ANC)\n",
             args.scene, args.batch, options.frame.width, options.frame.height, rays.size(), previous.size());
  for (Encoder e : {Encoder::HCC, Encoder::MLHCC, Encoder::PPC})
    report(fmt::format("{}/32", encoder_name(e)), encode_on_host(e, 32, es, rays));

  for (unsigned r = 2; r <= 6; ++r) {
    EncoderParams params;
    params.region_bits = r;
    const std::vector<RsRegionSplit> halved = median_region_splits(box, {}, r);
    const std::vector<RsRegionSplit> median = median_region_splits(box, previous, r);
    // The HAD cuts of a split tree's cells, in the layout hcc-region's code reads (the region's
    // overlap-restricted cuts: what region_inputs does without statistics).
    auto had_keys = [&](const std::vector<RsRegionSplit>& splits) {
      std::vector<std::vector<std::uint32_t>> cuts;
      for (const Aabb& cell : region_boxes(box, splits, r)) cuts.push_back(region_cut(p.bvh, es.had(), 32 - r, cell));
      const CutRows rows = cut_rows(p.bvh, cuts, 32 - r);
      const std::vector<RsRegionCells> cells = region_cells(splits, r);
      std::vector<std::uint64_t> keys(rays.size());
      for (std::size_t i = 0; i < rays.size(); ++i)
        keys[i] = rs_key_from_code(
            rs_region_cut_code(rays[i], cells.data(), r, rows.groups.data(), rows.counts.data(), 32 - r), 32);
      return keys;
    };
    auto traffic_keys = [&](const std::vector<RsRegionSplit>& splits) {
      EncodeScene with(p.bvh, box, params);
      set_region_statistics(with, region_statistics(p.bvh, splits, r, previous, any_hit));
      return encode_on_host(Encoder::HCC_REGION, 32, with, rays);
    };
    const EncodeScene without(p.bvh, box, params);
    const std::vector<std::uint64_t> first_version = encode_on_host(Encoder::HCC_REGION, 32, without, rays);
    if (had_keys(halved) != first_version) throw Error("region_study: the halved HAD keys differ from hcc-region's");
    report(fmt::format("r = {}: halved + HAD", r), first_version);
    report(fmt::format("r = {}: halved + traffic", r), traffic_keys(halved));
    report(fmt::format("r = {}: median + HAD", r), had_keys(median));
    report(fmt::format("r = {}: median + traffic (hcc-region)", r), traffic_keys(median));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return study::run("region_study", run_study, argc, argv); }
