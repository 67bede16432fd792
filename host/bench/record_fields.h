#pragma once
// The fields of a cell record as data (issue 41): one table per part of the record, behind the cell
// file's JSON writer and reader (bench/record_json.cpp), the columns of cells.csv and the metrics of
// `raysort compare` (bench/record_columns.cpp). The order of a table is the order of its columns.
//
// Two groups are sub-tables, each written once: the GPU cost model's figures, one object under
// "gpu_model" (null when the model was off), and Embree's figures, a list under "embree" with one
// object per path (empty when the run named none), whose columns carry the path's key:
// embree_<path>_<column>.
//
// A change of a field's meaning (its unit, what it counts, how it is estimated) bumps
// kResultFormatVersion (bench/record.h); a new field gets required_from = the version after the
// current one, so records of the current version, which lack it, still read.
#include <limits>
#include <vector>

#include "bench/record.h"
#include "bench/record_field.h"

namespace raysort {

const std::vector<Field<CellRecord>>& cell_fields();
const std::vector<Field<CellRecord::GpuModelFigures>>& gpu_model_fields();
const std::vector<Field<CellRecord::EmbreeFigures>>& embree_fields();

// The groups' keys in the cell file, and the first format version whose every record holds them.
inline constexpr const char* kGpuModelKey = "gpu_model";
inline constexpr const char* kEmbreeKey = "embree";
inline constexpr const char* kEmbreePathKey = "path";  // names an Embree element; in its columns' names
inline constexpr int kGroupsRequiredFrom = 4;
// A figure that is not there (null in the cell file, an empty column in cells.csv).
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace raysort
