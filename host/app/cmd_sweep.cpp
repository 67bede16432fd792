// raysort sweep DIR DIR...: result sets of one matrix run at different values of one encoder
// parameter, side by side (bench/sweep.h); the paper appendix's λ and TwoPoint-distance figures.
#include <fmt/format.h>

#include "app/commands.h"
#include "bench/sweep.h"
#include "util/atomic_file.h"

namespace raysort {

void register_sweep_command(CLI::App& app) {
  auto dirs = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("sweep", "tables of a parameter sweep: result sets of one matrix run at different "
                                          "--lambda, --twopoint-length, --direction-bits, --region-bits, "
                                          "--traffic-blend or --cost-bits values, one column per value");
  cmd->add_option("DIR", *dirs, "result set folders, one per value")->required();
  cmd->add_option("--out", *out, "write the markdown here (default: print it)");
  cmd->callback([dirs, out] {
    const std::string md = render_sweep(load_sweep(*dirs));
    if (out->empty()) {
      fmt::print("{}", md);
      return;
    }
    write_file_atomically(*out, md);
    fmt::print("sweep of {} sets: {}\n", dirs->size(), *out);
  });
}

}  // namespace raysort
