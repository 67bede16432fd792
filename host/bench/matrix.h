#pragma once
// The scenario matrix: axes (scenes × batches × encoders × key bits, plus top-k sorting), the
// run settings, and named presets. Every axis is narrowed on the command line with one syntax:
// a comma-separated list, or "all".
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "bench/protocol.h"
#include "encode/encode.h"

namespace raysort {

struct MatrixSpec {
  std::string preset;                 // "", "quick", "paper"
  std::vector<std::string> scenes;
  std::vector<std::string> batches;   // "primary", "shadow<k>", "bounce<k>"; empty: every batch
  std::vector<std::string> encoders;  // encoder names (NoSort always runs: it is the baseline)
  std::vector<unsigned> bits{32};
  // Scenes that also run key_length_bits (the paper's key-length tables: 16/32/64 on sibenik).
  std::vector<std::string> key_length_scenes;
  std::vector<unsigned> key_length_bits;
  std::vector<unsigned> top_bits;     // extra top-k sorted cells at the largest key length (0: none)
  std::string resolution = "1920x1080";
  unsigned spp = 1;
  unsigned seed = 1;
  std::string variant = "robust";     // trace variants, comma-separated: robust (watertight), fast
  std::vector<std::string> variant_list() const;  // "robust,fast" -> {"robust", "fast"}
  // Ray access modes, comma-separated (docs/measurement.md): gather (the trace reads rays through
  // the sorted order) and permute (a kernel moves the rays into sorted order first, timed as its
  // own stage). NoSort runs once per batch and variant: its order is the identity either way.
  std::string access = "gather";
  std::vector<std::string> access_list() const;
  EncoderParams params;

  // The measurement protocol of every cell (bench/protocol.h): warm-up rounds, the fewest timed
  // rounds (--reps), and the stopping rule: stop once the speedup interval's relative half-width
  // is at most max_noise (--max-noise, in percent on the command line) or after max_time_s of
  // sampling (--max-time).
  unsigned warmup = 1;
  unsigned reps = 7;
  double max_noise = 0.02;
  double max_time_s = 5.0;
  double cell_timeout_s = 0;          // hard limit per cell (--timeout); 0: none
  // The protocol settings of one cell; the arm order is seeded from the run's seed and the cell id.
  ProtocolSettings protocol(const std::string& cell_id) const;

  nlohmann::json to_json() const;     // "matrix" in meta.json: what must match to resume
  // The key lengths a scene runs.
  std::vector<unsigned> bits_for(const std::string& scene) const;
};

// "quick" (what `make bench` runs: procedural scenes, reduced resolution, a few minutes on 2 cores)
// or "paper" (the paper's setup). Throws Error listing the presets for another name.
MatrixSpec matrix_preset(const std::string& name);
std::vector<std::string> preset_names();

// Checks the matrix before any work starts: encoder names, key bits valid per encoder, batch
// names well formed, resolution non-zero, trace variants and access modes known, protocol
// settings in range. Throws Error naming the offending value and the valid ones.
void validate_matrix(const MatrixSpec& spec);

// "1920x1080" -> width, height (throws Error).
void parse_resolution(const std::string& s, std::uint32_t& w, std::uint32_t& h);

}  // namespace raysort
