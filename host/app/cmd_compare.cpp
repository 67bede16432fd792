// raysort compare A B: two result sets side by side, with regression rules (--fail-if).
#include <fmt/format.h>

#include <filesystem>

#include "app/commands.h"
#include "bench/compare.h"
#include "util/atomic_file.h"
#include "util/error.h"

namespace raysort {

void register_compare_command(CLI::App& app) {
  struct Args {
    std::string a, b, out;
    std::vector<std::string> metrics{"trace_mrays", "speedup", "net_speedup", "overhead_pct", "anc"};
    std::vector<std::string> fail_if;
    bool allow_different_matrix = false, force = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("compare", "compare two result sets cell by cell");
  cmd->add_option("A", a->a, "first result set (baseline)")->required();
  cmd->add_option("B", a->b, "second result set")->required();
  cmd->add_option("--metrics", a->metrics, "metrics to tabulate")->delimiter(',');
  cmd->add_option("--fail-if", a->fail_if,
                  "regression rule, repeatable: 'speedup<-5%', 'overhead_pct>+10%', 'anc!=', 'anc!=0.01', 'missing'; "
                  "a relative rule on a timed figure fires only when the change passes the threshold between the "
                  "nearest ends of the two 95 % intervals");
  cmd->add_option("--out", a->out, "also write the report to this markdown file (never inside A or B)");
  cmd->add_flag("--force", a->force, "overwrite an existing --out file");
  cmd->add_flag("--allow-different-matrix", a->allow_different_matrix,
                "compare sets that ran different matrices (scenes, batches, encoders, bits, resolution, spp, seed, "
                "variants, access modes); the report says what differs");
  cmd->callback([a] {
    std::vector<FailRule> rules;
    for (auto& r : a->fail_if) rules.push_back(FailRule::parse(r));
    if (!a->out.empty()) {
      check_output_path(a->out, {a->a, a->b}, a->force, "--out");
      std::error_code ec;
      if (std::filesystem::is_directory(a->out, ec))
        throw Error(fmt::format("--out {}: a folder; name the markdown file to write, e.g. {}/compare.md", a->out, a->out));
    }
    auto ra = ResultSet::load(a->a), rb = ResultSet::load(a->b);
    CompareResult res = compare_result_sets(ra, rb, a->metrics, rules, a->allow_different_matrix);
    fmt::print("{}", res.report);
    if (!a->out.empty()) write_file_atomically(a->out, res.report);
    for (const auto& line : res.scene_files)
      fmt::print(stderr, "raysort compare: scene files: {}\n", line);
    for (const auto& line : res.encoder_files)
      fmt::print(stderr, "raysort compare: encoder files: {}\n", line);
    for (const auto& line : res.ray_files) fmt::print(stderr, "raysort compare: ray files: {}\n", line);
    if (!res.within_noise.empty())
      fmt::print(stderr, "raysort compare: {} change(s) past a --fail-if threshold on the points stayed within the "
                         "noise (not past it between the 95 % intervals' nearest ends), not counted as regressions\n",
                 res.within_noise.size());
    if (!res.violations.empty()) {
      fmt::print(stderr, "raysort compare: {} regression(s) past the --fail-if rules\n", res.violations.size());
      set_command_exit_code(1);
    }
  });
}

}  // namespace raysort
