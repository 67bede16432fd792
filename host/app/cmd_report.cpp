// raysort report DIR: writes a result set's views again from its cell files (tables.md, cells.csv,
// cells.json, meta.json's fingerprints and noise summary, the plots), e.g. after an upgrade of
// raysort changed how they are drawn. Measures nothing; the cell files are not touched.
#include <fmt/format.h>

#include "app/commands.h"
#include "bench/matrix.h"
#include "bench/result_set.h"

namespace raysort {

void register_report_command(CLI::App& app) {
  auto dir = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("report", "write a result set's tables, CSV/JSON and plots again from its cell files");
  cmd->add_option("DIR", *dir, "result set folder")->required();
  cmd->callback([dir] {
    // One writer: not while a run or merge writes into it.
    ResultSet rs = ResultSet::load_for_writing(*dir, "raysort report " + *dir);
    // The tables read the matrix's entries by type; a damaged entry is named, not a JSON type error.
    if (rs.meta().contains("matrix")) check_matrix_json(rs.meta()["matrix"], *dir + "/meta.json");
    rs.write_views();
    rs.write_plots();
    const NoiseSummary noise = summarize_noise(rs.cells());
    fmt::print("{}: {} cells; tables: {}/tables.md\n", *dir, rs.cells().size(), *dir);
    if (noise.aa_intervals > 0)
      fmt::print("noise: A/A calibration {} of {} intervals contain 1.00 ({:.1f} %); speedup interval half-width "
                 "median {:.1f} %\n",
                 noise.aa_containing_one, noise.aa_intervals, 100.0 * noise.aa_coverage(),
                 100.0 * noise.median_half_width);
  });
}

}  // namespace raysort
