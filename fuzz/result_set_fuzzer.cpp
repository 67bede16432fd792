// libFuzzer target for the result-set reader (issue 23/24): what resume, compare and merge read
// from disk, on arbitrary text. The first byte picks the reader: a cell record (checked against
// its file name, the vocabulary and a real matrix), meta.json (then compared with a real set's
// meta, as compare does, and used to place a real cell), or a --fail-if rule. Each must return or
// throw raysort::Error; anything else (a crash, a sanitizer report, another exception) is a finding.
// Built by `make fuzz` (CMake option RAYSORT_FUZZ, clang).
#include <cstdint>
#include <string>

#include "bench/compare.h"
#include "bench/result_set.h"
#include "util/error.h"

namespace {

// The matrix of a real set (tests/golden/quick-tiny's, abridged) and one of its cells.
const nlohmann::json& matrix() {
  static const nlohmann::json m = nlohmann::json::parse(R"({
    "preset": "quick", "scenes": ["cornell", "detail-room"], "batches": ["primary", "shadow0", "bounce1"],
    "encoders": ["nosort", "hcc", "origin"], "bits": [32], "key_length_scenes": ["detail-room"],
    "key_length_bits": [16, 64], "top_bits": [], "resolution": "48x27", "spp": 1, "reps": 1, "warmup": 0,
    "max_noise": 0.02, "max_time_s": 0.0, "seed": 1, "variant": "robust", "access": "gather,permute",
    "twopoint_length_fraction": 0.25, "had_lambda": 0.125, "direction_bits": 4})");
  return m;
}

raysort::CellRecord a_cell() {
  raysort::CellRecord c;
  c.scene = std::string("cornell"), c.batch = std::string("primary"), c.encoder = std::string("hcc");
  c.bits = 32, c.rays = 1296;
  return c;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    switch (data[0] % 3) {
      case 0: {
        const raysort::CellRecord c = raysort::parse_cell_record(text, "cells/cornell__primary__hcc__32.json", matrix());
        (void)raysort::csv_row(c);
        break;
      }
      case 1: {
        const nlohmann::json meta = raysort::parse_meta(text, "meta.json");
        (void)raysort::cell_outside_matrix(a_cell(), meta.value("matrix", nlohmann::json()));
        (void)raysort::json_differences(meta.value("matrix", nlohmann::json()), matrix());
        break;
      }
      default:
        (void)raysort::FailRule::parse(text);
    }
  } catch (const raysort::Error&) {
  }
  return 0;
}
