#pragma once
// raysort merge: the result sets of the shards of one matrix run (`raysort run --shard i/N`,
// bench/shard.h) into one result set, as if one machine had run the whole matrix.
//
// The inputs must agree on the matrix configuration, the shard plan, the device and the raysort
// build (version and commit), and together hold every cell of the plan exactly once. Every
// problem found is reported, one line each, naming the input folder and the fix; nothing is
// written then. The output is built in a temporary folder beside OUT and renamed into place, so
// OUT is either absent or complete; an existing non-empty OUT is touched only with --force.
#include <string>
#include <vector>

namespace raysort {

struct MergeSummary {
  std::size_t cells = 0;         // cells in the merged set
  std::size_t absent = 0;        // planned cells whose batch does not exist (meta "absent_cells")
  std::size_t failed = 0;        // cells whose status is not "ok"
  unsigned shard_count = 0;      // N of the --shard i/N split
};

// `command` is recorded in the merged meta.json. OUT is checked first (check_output_path in
// bench/result_set.h): never an input or inside one; an existing result set is replaced only with
// `force`. Throws Error listing every problem.
MergeSummary merge_result_sets(const std::vector<std::string>& inputs, const std::string& out,
                               const std::string& command, bool force = false);

}  // namespace raysort
