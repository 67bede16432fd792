#pragma once
// Sharding a matrix run over several machines (issue 10): `raysort run --shard i/N` runs a
// deterministic 1/N of the matrix's cells, balanced by an estimated cost rather than by count, so a
// Slurm job array of N tasks finishes at about the same time. `raysort merge` (bench/merge.h) puts
// the N result sets back together.
//
// The plan depends only on the matrix and on the scenes (triangle count, lights, bounce depth), and
// uses integer arithmetic only, so every shard and every machine computes the same plan.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bench/matrix.h"

namespace raysort {

// "--shard i/N": shard i of N, numbered from 1 (1/4 … 4/4, as Slurm's --array=1-N numbers its
// tasks). index == 0: not sharded.
struct ShardSpec {
  unsigned index = 0, count = 0;
  bool active() const { return count > 0; }
  // Throws Error naming the text and the expected form for "0/4", "5/4", "2", "a/b", "1/0".
  static ShardSpec parse(const std::string& text);
  std::string str() const;  // "2/4"
};

// What the plan needs to know of a scene: its size and the batches its effects can produce.
struct SceneFacts {
  std::uint64_t triangles = 0;
  std::uint64_t rays_per_batch = 0;           // width × height × spp
  std::uint32_t shadow_rays_per_bounce = 0;   // 0 or no sphere lights: no shadow batches
  std::uint32_t max_bounces = 0;
};
// The facts of a loaded scene at `frame`'s resolution and spp.
SceneFacts scene_facts_of(const Scene& scene, const FrameSize& frame);
// Loads the scene (at 1×1: only its size and effects are needed) and reads its facts.
SceneFacts load_scene_facts(const std::string& scene, const MatrixSpec& spec, const std::string& scene_root);

// One cell of the full matrix, with its estimated cost in arbitrary integer units.
struct PlannedCell {
  std::string id;  // CellRecord::id()
  std::string scene, batch, variant;
  std::uint64_t cost = 0;
  unsigned shard = 0;  // 1..N once planned
  std::string encoder, access;
  unsigned bits = 0, top_bits = 0;
  std::string baseline = "pixel";
  std::string layout = "wide";  // the trace class
};

// Every cell the matrix can produce, in the order `raysort run` visits them. A requested batch the
// scene's effects cannot produce (shadow rays in a scene without lights) has no cells; a batch
// that turns out empty at run time (every ray missed) is reported by the shard that owns it
// (meta.json "absent_cells").
//
// Estimated cost = rays × bit_width(triangles) × encoder weight: a trace costs about rays × tree
// depth, and every cell traces its batch (reps + warm-up, and once more for the host SIMT model);
// the weight adds encode + sort, measured on PoCL in results/bench-quick (encode + sort as a
// share of the trace: origin 15 %, hcc 28 %, mlhcc 42 %, hcc-dir 50 %, ppc 65 %).
std::vector<PlannedCell> matrix_cells(const MatrixSpec& spec,
                                      const std::function<SceneFacts(const std::string&)>& facts);

// The cells `raysort run` measures in one set of rounds (bench/cell_measure.h): every cell of one
// batch, variant, trace class and baseline order share their rounds and their NoSort and A/A arms
// (issue 42). A shard never splits them, and a resume measures them whole.
std::string round_group(const PlannedCell& c);
// The cells of one encode + sort within a round group: one encoder, key length and top-k with its
// access modes side by side.
std::string sort_group(const PlannedCell& c);

// Contiguous split by cost: `cells` in visiting order (as matrix_cells lists them) are cut into
// round groups, and group g, whose cost spans [P, P + c) of the total T, goes to shard
// ⌊(P + c/2) · N / T⌋ + 1 (its midpoint's Nth). Shards are consecutive runs of the visiting order,
// so a shard loads few scenes (N shards generate at most scenes + N − 1 scenes' batches in all)
// and each shard's cost is within one round group's cost of the mean T / N. Returns the cells in
// their input order, each with its shard; a shard may be empty when N exceeds the groups.
std::vector<PlannedCell> plan_shards(std::vector<PlannedCell> cells, unsigned count);

// Per shard (index 0 is shard 1): number of cells and total estimated cost.
struct ShardLoad {
  std::size_t cells = 0;
  std::uint64_t cost = 0;
};
std::vector<ShardLoad> shard_loads(const std::vector<PlannedCell>& planned, unsigned count);

// The plan as meta.json records it in every shard's result set:
//   {"index": i, "count": N, "cells": M, "plan_hash": "...", "plan": {cell id: shard, ...}}
// plan_hash fingerprints the matrix and the whole assignment: shards planned from different
// matrices or different scene files do not merge.
nlohmann::json shard_meta(const MatrixSpec& spec, const ShardSpec& shard, const std::vector<PlannedCell>& planned);

// A human-readable plan: one line per shard (cells, estimated cost, share of the mean), then one
// line per cell (shard, cost, id).
std::string format_plan(const std::vector<PlannedCell>& planned, unsigned count);

}  // namespace raysort
