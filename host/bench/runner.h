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

// mlhcc-cost's input for every batch of a scene (docs/encoders.md): the frame drawn with seed + 1
// (another frame of the same camera and lights, standing for the one a renderer traced before),
// each batch traced on the host (trace_reference, fast variant, wide tree) for its rays' step
// counts, and cost_statistics of them in `keys` (the encoder's frame: the scene box the bins
// quantise). Only the batches named in `wanted` (empty: every batch) are traced. By batch name: the per-bin means and the ms of the trace
// and statistics (a renderer would gather them in its own trace; the frame's generation is not
// counted). The frame is dropped before this returns, so a run never holds two frames.
std::map<std::string, std::pair<std::vector<std::uint64_t>, double>> previous_frame_costs(
    const PreparedScene& scene, const RayGenOptions& gen, const RsEncodeFrame& keys,
    const std::vector<std::string>& wanted = {});

// The shard plan of a matrix (bench/shard.h), loading its scenes for their sizes and effects.
std::vector<PlannedCell> plan_matrix_shards(const MatrixSpec& spec, const std::string& scene_root, unsigned count);

}  // namespace raysort
