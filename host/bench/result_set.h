#pragma once
// A result set on disk: DIR/meta.json, one DIR/cells/<id>.json per finished cell (each written
// atomically the moment the cell finishes, so a killed run loses no finished cell and a rerun
// skips them), and the views regenerated from those files after every cell: cells.json,
// cells.csv and tables.md.
#include <nlohmann/json.hpp>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bench/record.h"
#include "util/folder_lock.h"

namespace raysort {

class ResultSet {
 public:
  // Opens DIR for a run with this meta, creating it if needed. If DIR already holds a result set,
  // its "matrix" entry must equal meta["matrix"] (same configuration), and its "shard" entry
  // (bench/shard.h) name the same shard of the same plan, or an Error says so;
  // its finished cells are kept and reported by has().
  // A result set has one writer: the set is locked (util/folder_lock.h) while the object lives, and
  // a second writer fails at once naming the holder; the leftover temporary files of a killed
  // writer are removed. A folder that is not empty and not a result set (no meta.json), or a set
  // whose meta.json is missing, is refused before anything is written.
  static ResultSet open_for_run(const std::string& dir, const nlohmann::json& meta);
  // Reads a finished (or partial) result set, lock-free. Throws Error for a missing set, another
  // format, or a cell file that is not what its name says (validate_cell_file).
  static ResultSet load(const std::string& dir);
  // The same under the writer's lock, taken before anything is read (raysort report rewrites the
  // views): a set being written is refused, and so is one whose meta.json lists cells (its
  // fingerprints) whose files are gone, whose views would silently lose them.
  static ResultSet load_for_writing(const std::string& dir, const std::string& command);

  bool has(const std::string& cell_id) const { return cells_.count(cell_id) > 0; }
  const CellRecord* find(const std::string& cell_id) const;
  // Writes the cell's file atomically (the set's record of it); the views (write_views) are the
  // caller's to regenerate: `run` does so once a batch, as its cells arrive together.
  void write_cell(const CellRecord& cell);
  // One cell: its file, then the views.
  void add(const CellRecord& cell);
  // Many cells, with the views written once at the end (raysort merge).
  void add_all(const std::vector<CellRecord>& cells);
  // Sets one entry of meta.json and rewrites it (a shard's "absent_cells").
  void set_meta(const std::string& key, const nlohmann::json& value);
  std::vector<CellRecord> cells() const;  // sorted by id
  const nlohmann::json& meta() const { return meta_; }
  const std::string& dir() const { return dir_; }
  // cells.json, cells.csv, tables.md and meta.json from every cell: all of them each time, so a
  // writer calls it once per burst of cells, not per cell (at 960 cells, per cell made `make
  // bench` write 3 GB).
  void write_views() const;
  // PNG plots (bench/plots.h); slower than the text views, so written at the end of a run.
  void write_plots() const;

 private:
  std::string dir_;
  nlohmann::json meta_;
  std::map<std::string, CellRecord> cells_;
  std::shared_ptr<FolderLock> lock_;
};

// The file name of a cell in DIR/cells: the id's parts joined by "__", each character other than
// letters, digits, '-', '.' and a lone inner '_' written %XX, so two ids never share a name
// ("d/s.obj/..." is "d%2Fs.obj__...", "d__s.obj/..." is "d%5F%5Fs.obj__..."); an id whose name
// would pass 180 characters keeps its start and ends in '~' and the FNV-1a hash of the id.
std::string cell_file_name(const std::string& cell_id);
// The name raysort gave a cell file before (every "/" became "__", nothing else): still read, and
// replaced when that cell is written again.
std::string legacy_cell_file_name(const std::string& cell_id);

// The readers behind ResultSet::load and open_for_run, on text (the fuzz target calls them):
// a cell record as read from `file`, checked against its name, the status vocabulary, its figures
// and `matrix` (meta.json's entry); meta.json's text, checked to be an object whose entries have
// the types raysort reads. Each throws one Error naming the file and the fix.
CellRecord parse_cell_record(const std::string& text, const std::string& file, const nlohmann::json& matrix);
nlohmann::json parse_meta(const std::string& text, const std::string& path);

// Why a cell cannot belong to the matrix of a meta.json ("encoder 'x' is not one of its
// encoders"), or "" when it can. Checks the axes only (scenes, batches, encoders, bits, top-k,
// variants, access modes); `raysort run` also checks its plan.
std::string cell_outside_matrix(const CellRecord& cell, const nlohmann::json& matrix);

// A meta.json "matrix" with the order of its list axes (scenes, batches, encoders, key lengths,
// top-k, variants, access modes, baselines, Embree paths) made canonical: two matrices that plan the same cells
// compare equal however their lists were written. The trace classes keep their order.
nlohmann::json canonical_matrix(const nlohmann::json& matrix);

// "resolution \"48x27\" vs \"320x180\"; reps 1 vs 3": the entries of two JSON objects that differ,
// restricted to `keys` when it is not empty.
std::string json_differences(const nlohmann::json& a, const nlohmann::json& b,
                             const std::vector<std::string>& keys = {});

// Checks an output path before anything is written: not empty, not an input folder nor inside one
// (nor holding one), and not an existing file or non-empty folder unless `force`. `option` names
// it in the message ("-o", "--out"). Throws Error naming the path and the fix.
void check_output_path(const std::string& out, const std::vector<std::string>& inputs, bool force,
                       const std::string& option);

// The paper's tables from a set of cells, as markdown (see tables.cpp).
std::string render_tables(const std::vector<CellRecord>& cells, const nlohmann::json& meta);

// The noise floor of a set of cells (docs/measurement.md, "Noise floor"): how many A/A intervals
// contain 1 (about 95 % when the intervals are honest), how wide the speedup intervals are and
// what stopped the cells. Cells that shared their rounds (the gather and permute cells of one
// encoder) share one A/A interval and count once. tables.md and meta.json ("noise") show it.
struct NoiseSummary {
  std::size_t aa_intervals = 0, aa_containing_one = 0;
  std::size_t cells_with_interval = 0;  // ok encoder cells with a speedup interval
  double median_half_width = 0, p90_half_width = 0, max_half_width = 0;  // relative, of those
  unsigned median_rounds = 0, min_rounds = 0, max_rounds = 0;
  std::size_t stopped_by_noise = 0, stopped_by_time = 0, stopped_by_rounds = 0;
  std::size_t same_order_cells = 0, speedups_containing_one = 0;
  double aa_coverage() const {
    return aa_intervals ? static_cast<double>(aa_containing_one) / static_cast<double>(aa_intervals) : 0.0;
  }
  nlohmann::json to_json() const;
};
NoiseSummary summarize_noise(const std::vector<CellRecord>& cells);

}  // namespace raysort
