// raysort merge A B ... -o OUT: the shards of one matrix run into one result set (bench/merge.h).
#include <fmt/format.h>

#include "app/commands.h"
#include "bench/merge.h"

namespace raysort {

void register_merge_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> inputs;
    std::string out;
    bool force = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("merge",
                                 "merge the result sets of the shards of one matrix run (raysort run --shard i/N) "
                                 "into one result set, with its tables and plots");
  cmd->add_option("inputs", a->inputs, "the shards' result folders")->required();
  cmd->add_option("-o,--out", a->out, "the merged result folder (must not exist, or be empty; never inside an input)")
      ->required();
  cmd->add_flag("--force", a->force, "replace an existing result set at --out");
  cmd->callback([a] {
    std::string line = "raysort merge";
    for (const auto& in : a->inputs) line += " " + in;
    line += " -o " + a->out;
    MergeSummary s = merge_result_sets(a->inputs, a->out, line, a->force);
    fmt::print("merged {} cells of {} shards into {}{}\n", s.cells, s.shard_count, a->out,
               s.absent ? fmt::format(" ({} planned cells absent: their batch has no rays)", s.absent) : "");
    fmt::print("tables: {}/tables.md\n", a->out);
    // Failed cells were reported (and made their shard exit non-zero) when they ran; the merged
    // set keeps them, as a full run would.
    if (s.failed > 0) fmt::print(stderr, "note: {} merged cells have status failed or timeout\n", s.failed);
  });
}

}  // namespace raysort
