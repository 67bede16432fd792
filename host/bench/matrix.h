#pragma once
// The scenario matrix: axes (scenes × batches × encoders × key bits × trace variants × trace
// classes × access modes × baseline orders, plus top-k sorting), the run settings, and named presets. The axes are
// typed: the command line is parsed once, at its boundary, by each axis's own parser
// (parse_encoders in encode/, parse_trace_variants and parse_trace_layouts in trace/, parse_ray_accesses in
// sort/permute.h, parse_baseline_orders in render/batches.h, parse_resolution in scene/), and
// everything after it reads values, not text. Every axis is narrowed on the
// command line with one syntax: a comma-separated list, or "all".
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "bench/protocol.h"
#include "encode/encode.h"
#include "render/batches.h"
#include "scene/load.h"
#include "sort/permute.h"
#include "trace/tracer.h"

namespace raysort {

struct MatrixSpec {
  std::string preset;                 // "", "quick", "paper"
  std::vector<std::string> scenes;    // names, .toml or .obj paths
  std::vector<std::string> batches;   // "primary", "shadow<k>", "bounce<k>"; empty: every batch
  // --rays FILE: the one batch of every cell comes from this ray file (bench/batch_file.h), named
  // "file:<stem>" in batches; empty: the batches are generated. One scene only.
  std::string ray_file;
  std::vector<Encoder> encoders;      // NoSort always runs (every batch has its NoSort cell)
  std::vector<unsigned> bits{32};
  // Scenes that also run key_length_bits (the paper's key-length tables: 16/32/64 on sibenik).
  std::vector<std::string> key_length_scenes;
  std::vector<unsigned> key_length_bits;
  std::vector<unsigned> top_bits;     // extra top-k sorted cells at the largest key length (0: none)
  // run --warp-sort: every cell's sort stops at groups of this many pairs (RadixSortConfig::
  // warp_group, docs/sort.md); 0: the full sort. Recorded in meta.json's matrix only when on.
  unsigned sort_warp_group = 0;
  FrameSize frame{1920, 1080, 1};     // resolution, spp and (non-zero) shadow-ray / depth overrides of every scene
  unsigned seed = 1;
  std::vector<TraceVariant> variants{TraceVariant::Robust};  // the first is the tables' main one
  std::vector<RayAccess> accesses{RayAccess::Gather};        // the first is the tables' main one
  std::vector<BaselineOrder> baselines{BaselineOrder::Pixel};  // NoSort's order; the first is the tables' main one
  // The trace classes (docs/trace.md, "Trace classes"): which tree the kernels and the SIMT model
  // walk and how many rays walk it together; an axis like the variants (in the cell id when not
  // wide). The first is the tables' main one. Packet and Hybrid are resolved to the device's width
  // before the plan is made (run_matrix), so cells and meta.json name the width that ran.
  std::vector<TraceLayout> layouts{TraceLayout::Wide};
  // The GPU cost model's profile (bench/gpu_model.h: a name in gpu/profiles/ or a .toml path);
  // empty: the model is off.
  std::string gpu_model;
  // Embree's paths (run --embree-paths: kEmbreePaths keys, embree/embree_reference.h), each two more
  // arms of every cell's rounds: Embree tracing the batch in NoSort order and in the cell's sorted
  // order (docs/measurement.md, "Embree on sorted orders"). Empty: none (no arm, no entry in
  // meta.json's matrix, so sets written without it resume).
  std::vector<std::string> embree_paths;
  // The instruction set Embree's arms run (run --embree-isa: kEmbreeIsas, embree/embree_reference.h).
  // "native": the widest this CPU has (no entry in meta.json's matrix, so sets written before it resume).
  std::string embree_isa = "native";
  EncoderParams params;

  // The measurement protocol of every cell (bench/protocol.h): warm-up rounds, the fewest timed
  // rounds (--reps), and the stopping rule: stop once the speedup interval's relative half-width
  // is at most max_noise (--max-noise, in percent on the command line) or after max_time_s of
  // sampling (--max-time).
  //
  // No warm-up round by default: a batch's setup already ran every kernel of its rounds once,
  // untimed (the NoSort trace checked against the host, each encoder's keys in generation order, a
  // sort and a permute: BatchBench), and a kernel's time is its event's, which holds no compile.
  // A warm-up round re-ran every arm of every cell group, one round in eight of paper-1spp's bounce
  // rays (issue 42); each arm still checks its hits on its first run, after its clock stopped
  // (docs/measurement.md, "The protocol").
  unsigned warmup = 0;
  unsigned reps = 7;
  double max_noise = 0.02;
  double max_time_s = 5.0;
  double cell_timeout_s = 0;          // hard limit per cell (--timeout); 0: none
  // The protocol settings of one cell; the arm order is seeded from the run's seed and the cell id.
  ProtocolSettings protocol(const std::string& cell_id) const;

  nlohmann::json to_json() const;     // "matrix" in meta.json: what must match to resume
  // The encoder knobs' entries of to_json, by their rows (encode/encoder_params.h).
  void add_params_json(nlohmann::json& j) const;
  // The key lengths a scene runs.
  std::vector<unsigned> bits_for(const std::string& scene) const;
};

// "quick" (what `make bench` runs: procedural scenes, reduced resolution, a few minutes on 2 cores),
// "paper" (Tables 2, 3, 5-7 at the paper's sampling: 1920×1080, 8 spp, 2 shadow rays per bounce),
// "paper-1spp" (the same at 1 spp, 1 shadow ray), "paper-viewport" (Table 4), "paper-hcc-dir"
// (appendix Table 8) or "paper-bounces" (appendix, bounces 1-5 in Breakfast); docs/paper.md maps
// every table of the paper to its preset or command. Throws Error listing the presets for another name.
MatrixSpec matrix_preset(const std::string& name);
std::vector<std::string> preset_names();

// Checks that the entries of a meta.json "matrix" (as to_json spells them) have the JSON types the
// readers of a result set take them as (a string, a count, a number, a list of strings or of
// counts); throws Error naming `file`, the key and the fix otherwise. Unknown keys are left alone (a
// set written by another version). The readers (tables, plots, sweep) then call get<T>() safely.
void check_matrix_json(const nlohmann::json& matrix, const std::string& file);

// Checks the encoders' settings: every knob in its range (params_problem's message, the option's own
// refusal) and every key length valid for every encoder but NoSort ("encoder hcc-region with 8-bit
// keys: ..."). validate_matrix and encodebench both refuse with it. Throws Error.
void validate_encoders(const std::vector<Encoder>& encoders, const std::vector<unsigned>& bits,
                       const EncoderParams& params);

// Checks what parsing cannot: key bits valid per encoder (validate_encoders), batch names well formed, resolution and
// spp non-zero, axes non-empty, protocol settings in range. Throws Error naming the offending value.
void validate_matrix(const MatrixSpec& spec);

}  // namespace raysort
