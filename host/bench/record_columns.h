#pragma once
// The columns of cells.csv, made from the record's field tables (bench/record_fields.h): the one
// list behind the CSV header, its rows and the metrics `raysort compare` tabulates and checks
// rules on. Every field reaches a column (an Estimate four: the value, _lo, _hi, _n; a Timing six:
// _ms, _lo_ms, _hi_ms, _min_ms, _max_ms, _n), except the raw samples, which stay in the cell file.
// An absent field is an empty field in each of its columns.
#include <functional>
#include <string>
#include <vector>

#include "bench/record.h"

namespace raysort {

struct CellColumn {
  std::string name;
  enum Kind { Number, Text } kind = Number;
  std::function<std::string(const CellRecord&)> csv;  // the CSV field
  std::function<double(const CellRecord&)> value;     // Number columns: the figure (NaN: none)
  // Number columns: the figure as `compare` weighs it: with its 95 % interval where it has one (an
  // estimate, a timing's median, a rate of a timing), without one (lo and hi NaN) otherwise.
  std::function<Estimate(const CellRecord&)> estimate;
  // Text columns whose values form a closed set (status, stopped_by, the true/false flags): a rule
  // naming another value is refused. Empty: any value.
  std::vector<std::string> vocabulary;
};
const std::vector<CellColumn>& cell_columns();
// The columns of one Embree path's figures (CellRecord::embree), empty fields in a cell without
// that path: embree_<path>_ and each column of the Embree table (speedup, speedup_lo, ..., ms, ...,
// nosort_ms, ..., mrays, nosort_mrays, call, threads, ties, differ, agreement_with_ours). <path> is
// the --embree-paths key as written ("embree_16-coherent_speedup", "embree_1M_ms").
std::vector<CellColumn> embree_columns(const std::string& path);
// The columns of a set of cells: cell_columns(), then embree_columns() of every Embree path the
// cells hold, in the order the cells name them. Without Embree figures: cell_columns() exactly.
std::vector<CellColumn> cell_columns_for(const std::vector<CellRecord>& cells);
// A column by name: one of cell_columns(), or an Embree path's column of any path raysort knows
// (kEmbreePaths), whether or not a set holds it.
const CellColumn* find_cell_column(const std::string& name);

// CSV header and row, in the order of `columns` (default: cell_columns()).
std::string csv_header();
std::string csv_row(const CellRecord& r);
std::string csv_header(const std::vector<CellColumn>& columns);
std::string csv_row(const CellRecord& r, const std::vector<CellColumn>& columns);

}  // namespace raysort
