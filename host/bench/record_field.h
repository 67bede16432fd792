#pragma once
// One row of the record's field table (bench/record_fields.h): where a field of a cell record lives,
// what it is, and how the cell file, cells.csv and `raysort compare` write, read and compare it.
// The rows are data; bench/record_json.cpp and bench/record_columns.cpp are the only code that walks
// them, so a field is added, renamed or retyped in its row and nowhere else.
#include <cstdint>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "bench/protocol.h"

namespace raysort {

struct CellRecord;

// A figure computed from other fields (the cell id; an MRays/s from its timing and the cell's rays):
// written into the file for its readers and into cells.csv, never read back (one truth).
template <class O>
using DerivedText = std::string (*)(const O&);
struct DerivedRate {};  // rays / the median of Field::interval_of, MRays/s
// A sub-table of the record (bench/record_fields.h: the GPU model's figures, Embree's paths), written
// where its row stands: in the JSON under the row's key, in cells.csv as its own columns.
struct Group {};

// When a field has no value. Whatever the reason, an absent field is written one way: JSON null
// under its key (the key is always written), an empty field in every cells.csv column it fills,
// and no value (NaN) for `compare` (null on both sides is no change; on one side is).
enum class Absent {
  Never,           // always holds a value; a number that is not finite is still null
  WhenNegative,    // in memory -1, as the runner sets it (leaks_per_million, cut_ms)
  WithoutSamples,  // when the timing Field::samples_of has no samples (an Embree path's sorted arm in a NoSort cell)
};

template <class O>
struct Field {
  // Where the value lives in its owner (the record, or one element of a group): its C++ type is the
  // field's type. Text, flag, count, number; an Estimate (value, lo, hi, n); a Timing (median,
  // lo, hi, min, max, n); the raw samples (JSON only: a series per stage, every figure is computed
  // from them); a derived figure; or a group.
  using Member = std::variant<std::string O::*, bool O::*, unsigned O::*, std::uint64_t O::*, double O::*,
                              Estimate O::*, Timing O::*, Series O::*, DerivedText<O>, DerivedRate, Group>;
  std::string json;  // its key in its JSON object
  // Its cells.csv column and compare metric (the stem of an Estimate's or a Timing's columns):
  // empty, the same as json; kNoStem, none (column_stem).
  std::string column = "";
  Member member;
  Absent absent = Absent::Never;
  Timing O::*samples_of = nullptr;  // Absent::WithoutSamples: the timing whose samples it needs
  // The first format version whose every record holds the key: an older record may lack it, and
  // reads as the field's default (the value a fresh record has). From this version on, a record
  // without the key is refused.
  int required_from = 1;
  int decimals = 4;                  // cells.csv digits after the point (numbers)
  Timing O::*interval_of = nullptr;  // a rate: its 95 % interval is rays over this timing's interval
  // Text from a closed set: a value outside it is refused. (A function, not a list: GCC 12 fails
  // on a defaulted std::vector member in a class template initialised by designators.)
  const std::vector<std::string>& (*vocabulary)() = nullptr;
  bool quoted = false;                       // cells.csv: quoted, as free text (the error)
};

// A Field::column for no stem at all: an Embree path's sorted-arm timing, whose columns are the
// path's own (embree_<path>_ms, embree_<path>_lo_ms, ...).
inline constexpr const char* kNoStem = "-";

// The stem of a field's cells.csv columns (Field::column).
template <class O>
std::string column_stem(const Field<O>& f) {
  return f.column.empty() ? f.json : f.column == kNoStem ? std::string() : f.column;
}

// Whether a field of `owner` has no value (Field::absent).
template <class O>
bool field_absent(const Field<O>& f, const O& owner) {
  switch (f.absent) {
    case Absent::Never: return false;
    case Absent::WhenNegative: return owner.*std::get<double O::*>(f.member) < 0;
    case Absent::WithoutSamples: return (owner.*f.samples_of).n == 0;
  }
  return false;
}

// MRays/s of `rays` at a timing's median (NaN without one): trace_mrays and Embree's rates.
inline double mrays_at(std::uint64_t rays, const Timing& t) {
  return t.n > 0 && t.median_ms > 0 ? static_cast<double>(rays) / (t.median_ms * 1e3)
                                    : std::numeric_limits<double>::quiet_NaN();
}

// The visitor of a Field::Member: one lambda per type (std::visit(Overload{...}, f.member)).
template <class... F>
struct Overload : F... {
  using F::operator()...;
};
template <class... F>
Overload(F...) -> Overload<F...>;

}  // namespace raysort
