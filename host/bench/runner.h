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
  // run --sort-passes: the GPU shape's passes, "auto" (the device's: Onesweep on NVIDIA, else
  // reduce-then-scan), "reduce-then-scan" or "onesweep" (refused on the CPU shape). The orders are
  // the same either way; only the sort's time differs, and meta.json's "sort" says which ran.
  std::string sort_passes = "auto";
};

// run --sort-passes's values, the default first (RunOptions::sort_passes).
inline const std::vector<std::string> kSortPassesValues = {"auto", "reduce-then-scan", "onesweep"};

struct RunSummary {
  std::string out_dir;
  std::size_t cells_run = 0;      // measured by this run (retries included)
  std::size_t cells_retried = 0;  // of those, cells the set held as failed or timeout
  // of those, cells the set held as ok, measured again with the rest of their batch (its cells share
  // their rounds: a batch is measured whole)
  std::size_t cells_remeasured = 0;
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

// The shard plan of a matrix (bench/shard.h), loading its scenes for their sizes and effects.
std::vector<PlannedCell> plan_matrix_shards(const MatrixSpec& spec, const std::string& scene_root, unsigned count);

}  // namespace raysort
