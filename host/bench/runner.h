#pragma once
// Runs a scenario matrix into a result set: plan (every cell, or a shard's) → scene (load, BVH, the
// batches its effects imply, generated once so every encoder sees the same rays) → batch → cell
// (bench/cell_measure.h: encode → radix sort → [permute] → trace, paired with NoSort traces in the
// rounds of bench/protocol.h, checked bit for bit, ANC and SIMT model) → record (each cell written
// the moment it finishes; a rerun skips finished cells).
#include <cstdint>
#include <map>
#include <utility>
#include <string>
#include <vector>

#include "bench/matrix.h"
#include "bench/shard.h"
#include "bvh/prepared_scene.h"
#include "render/batches.h"

namespace raysort {

struct RunOptions {
  std::string device;      // select_device spec
  std::string scene_root;  // for real scenes
  std::string out;         // result folder; empty: results/<device-slug>/<preset>-<matrix hash>
  std::string command;     // the command line, for meta.json
  ShardSpec shard;         // --shard i/N: run only this shard's cells (bench/shard.h)
  // Resuming: cells already recorded as failed or timeout are measured again unless no_retry.
  bool no_retry = false;
};

struct RunSummary {
  std::string out_dir;
  std::size_t cells_run = 0;      // measured by this run (retries included)
  std::size_t cells_retried = 0;  // of those, cells the set held as failed or timeout
  std::size_t cells_skipped = 0;  // already in the set and kept (ok, or not ok with no_retry)
  std::size_t cells_failed = 0;   // measured by this run and not ok
  // The final state: planned cells (of this shard) the set holds that are not ok, and planned
  // cells it lacks (an interrupted run; absent batches not counted). 0 and 0: the set is whole.
  std::size_t cells_not_ok = 0, cells_missing = 0;
  bool interrupted = false;
  int signal = 0;  // the signal that interrupted it (SIGINT 2, SIGTERM 15), 0 when none
};

RunSummary run_matrix(const MatrixSpec& spec, const RunOptions& opts);

// The default result folder for a matrix (or one shard of it) on a device.
std::string default_result_dir(const MatrixSpec& spec, const std::string& device_slug, const ShardSpec& shard = {});

// hcc-traffic's input for `batch` (docs/encoders.md): the node traffic (trace/tracer.h,
// node_traffic) of the batch traced just before it in `frame` (generation order: primary, shadow0,
// bounce1, shadow1, ...). Causal: only that earlier batch's rays are read. Empty for the frame's
// first batch and for a batch the frame lacks (hcc-traffic then has HCC's cut).
std::vector<std::uint64_t> traffic_before(const Bvh& bvh, const std::vector<ReferencedBatch>& frame,
                                          const std::string& batch);

// hcc-region's input from one batch of a previous frame (docs/encoders.md): the split tree at the
// batch's median origins (median_region_splits of `box`, r levels) and, per region, the node
// traffic (trace/tracer.h, node_traffic) of the batch's rays that start in it, kept sparse.
RegionStatistics region_statistics(const Bvh& bvh, const Aabb& box, const std::vector<RsRay>& rays, bool any_hit,
                                   unsigned r);
// The same over given splits (tools/region_study compares them with the halving ones).
RegionStatistics region_statistics(const Bvh& bvh, std::vector<RsRegionSplit> splits, unsigned r,
                                   const std::vector<RsRay>& rays, bool any_hit);

// What a previous frame tells the encoders that learn from one, for one batch: mlhcc-cost's
// per-bin mean steps (cost_statistics) and hcc-region's statistics (region_statistics), each with
// the host ms its trace and statistics took; each is empty unless asked for.
struct PreviousBatchStatistics {
  std::vector<std::uint64_t> cost_means;
  double cost_ms = 0.0;
  RegionStatistics regions;
  double regions_ms = 0.0;
};

// The input of mlhcc-cost (`costs`) and hcc-region (`regions`) for every batch of a scene: the frame
// drawn with seed + 1 (another frame of the same camera and lights, standing for the one a renderer
// traced before), each batch traced on the host (fast variant), and the statistics of that trace
// for `keys` (the encoder's scene: the box the bins quantise and the regions split, and its region
// bits). Only the batches named in `wanted` (empty: every batch) are traced. By batch name; a
// renderer would gather them in its own trace, so the frame's generation is not counted. The frame
// is dropped before this returns, so a run never holds two frames.
std::map<std::string, PreviousBatchStatistics> previous_frame_statistics(const PreparedScene& scene,
                                                                        const RayGenOptions& gen,
                                                                        const EncodeScene& keys, bool costs,
                                                                        bool regions,
                                                                        const std::vector<std::string>& wanted = {});

// The shard plan of a matrix (bench/shard.h), loading its scenes for their sizes and effects.
std::vector<PlannedCell> plan_matrix_shards(const MatrixSpec& spec, const std::string& scene_root, unsigned count);

}  // namespace raysort
