// The columns of cells.csv and the metrics of compare, made by walking the field tables
// (bench/record_fields.h): each field gives its columns by its type, each column its CSV text, its
// value and, for compare, its estimate with the interval it has.
#include "bench/record_columns.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "bench/record_fields.h"
#include "embree/embree_reference.h"  // kEmbreePaths only (a table, no Embree call): every build has it

namespace raysort {

namespace {

// A figure without an interval (compare falls back to the point rule).
Estimate point(double v) { return {v, kNaN, kNaN, 0}; }

// rays / time: the interval of a rate is the rate at the ends of the time's interval.
Estimate rate_estimate(double value, std::uint64_t rays, const Timing& t) {
  Estimate e{value, kNaN, kNaN, t.n};
  const double r = static_cast<double>(rays) * 1e-3;
  if (const Estimate time = t.estimate(); time.has_interval() && time.lo > 0) e.lo = r / time.hi, e.hi = r / time.lo;
  return e;
}

// "prefix_stem_suffix", leaving out the empty parts (Embree's sorted-arm timing has no stem:
// embree_16_ms).
std::string column_name(const std::string& prefix, const std::string& stem, const std::string& suffix) {
  std::string name;
  for (const std::string* part : {&prefix, &stem, &suffix})
    if (!part->empty()) name += (name.empty() ? "" : "_") + *part;
  return name;
}

std::string quoted(std::string text) {  // without quotes or line breaks inside
  std::replace(text.begin(), text.end(), '"', '\'');
  std::replace(text.begin(), text.end(), '\n', ' ');
  return "\"" + text + "\"";
}

// The columns of the fields of one owner type O: the record itself, its GPU model figures, or
// one Embree path's figures, found in a cell by `locate` (null: that part is absent from the cell).
template <class O>
struct ColumnMaker {
  std::vector<CellColumn>& out;
  std::string prefix;
  std::function<const O*(const CellRecord&)> locate;

  // The field's owner in a cell where the field has a value, else null.
  std::function<const O*(const CellRecord&)> holder(const Field<O>& f) const {
    return [locate = locate, f = &f](const CellRecord& r) -> const O* {
      const O* o = locate(r);
      return o && !field_absent(*f, *o) ? o : nullptr;
    };
  }

  void text(const Field<O>& f, std::function<std::string(const O&)> get, std::vector<std::string> vocabulary = {}) {
    auto csv = [has = holder(f), get, q = f.quoted](const CellRecord& r) {
      const O* o = has(r);
      return !o ? std::string() : q ? quoted(get(*o)) : get(*o);
    };
    out.push_back({column_name(prefix, column_stem(f), ""), CellColumn::Text, csv, nullptr, nullptr, std::move(vocabulary)});
  }

  // A number (decimals >= 0) or a count (decimals < 0: written as an integer); `estimate` gives
  // compare the interval, when the figure has one.
  void number(const Field<O>& f, const std::string& suffix, std::function<double(const CellRecord&, const O&)> get,
              int decimals, std::function<Estimate(const CellRecord&, const O&)> estimate = nullptr) {
    auto value = [has = holder(f), get](const CellRecord& r) {
      const O* o = has(r);
      return o ? get(r, *o) : kNaN;
    };
    auto csv = [value, decimals](const CellRecord& r) {
      const double x = value(r);
      if (!std::isfinite(x)) return std::string();
      return decimals < 0 ? fmt::format("{}", static_cast<std::uint64_t>(x)) : fmt::format("{:.{}f}", x, decimals);
    };
    auto weighed = [has = holder(f), get, estimate](const CellRecord& r) {
      const O* o = has(r);
      return !o ? point(kNaN) : estimate ? estimate(r, *o) : point(get(r, *o));
    };
    out.push_back({column_name(prefix, column_stem(f), suffix), CellColumn::Number, csv, value, weighed, {}});
  }

  template <class T>
  void count(const Field<O>& f, const std::string& suffix, T O::*m) {
    number(f, suffix, [m](const CellRecord&, const O& o) { return static_cast<double>(o.*m); }, -1);
  }

  void estimate(const Field<O>& f, Estimate O::*m) {
    const int d = f.decimals;
    number(f, "", [m](const CellRecord&, const O& o) { return (o.*m).value; }, d,
           [m](const CellRecord&, const O& o) { return o.*m; });
    number(f, "lo", [m](const CellRecord&, const O& o) { return (o.*m).lo; }, d);
    number(f, "hi", [m](const CellRecord&, const O& o) { return (o.*m).hi; }, d);
    number(f, "n", [m](const CellRecord&, const O& o) { return static_cast<double>((o.*m).n); }, -1);
  }

  void timing(const Field<O>& f, Timing O::*m) {
    const int d = f.decimals;
    number(f, "ms", [m](const CellRecord&, const O& o) { return (o.*m).median_ms; }, d,
           [m](const CellRecord&, const O& o) { return (o.*m).estimate(); });
    number(f, "lo_ms", [m](const CellRecord&, const O& o) { return (o.*m).lo_ms; }, d);
    number(f, "hi_ms", [m](const CellRecord&, const O& o) { return (o.*m).hi_ms; }, d);
    number(f, "min_ms", [m](const CellRecord&, const O& o) { return (o.*m).min_ms; }, d);
    number(f, "max_ms", [m](const CellRecord&, const O& o) { return (o.*m).max_ms; }, d);
    number(f, "n", [m](const CellRecord&, const O& o) { return static_cast<double>((o.*m).n); }, -1);
  }

  // A rate: rays / a timing's median, with the interval of that timing.
  void rate(const Field<O>& f, std::function<double(const CellRecord&, const O&)> get) {
    const Timing O::*t = f.interval_of;
    number(f, "", get, f.decimals, [get, t](const CellRecord& r, const O& o) { return rate_estimate(get(r, o), r.rays, o.*t); });
  }

  void add(const Field<O>& f);
};

void add_group_columns(std::vector<CellColumn>& out, const std::string& key);

template <class O>
void ColumnMaker<O>::add(const Field<O>& f) {
  const std::vector<std::string> vocabulary = f.vocabulary ? f.vocabulary() : std::vector<std::string>{};
  std::visit(Overload{[&](std::string O::*m) { text(f, [m](const O& o) { return o.*m; }, vocabulary); },
                      [&](DerivedText<O> get) { text(f, get, vocabulary); },
                      [&](bool O::*m) { text(f, [m](const O& o) { return std::string(o.*m ? "true" : "false"); }, {"true", "false"}); },
                      [&](unsigned O::*m) { count(f, "", m); },
                      [&](std::uint64_t O::*m) { count(f, "", m); },
                      [&](double O::*m) {
                        auto get = [m](const CellRecord&, const O& o) { return o.*m; };
                        if (f.interval_of) rate(f, get);
                        else number(f, "", get, f.decimals);
                      },
                      [&](DerivedRate) {
                        rate(f, [t = f.interval_of](const CellRecord& r, const O& o) { return mrays_at(r.rays, o.*t); });
                      },
                      [&](Estimate O::*m) { estimate(f, m); },
                      [&](Timing O::*m) { timing(f, m); },
                      [&](Series O::*) {},  // the raw samples stay in the cell file
                      [&](Group) { add_group_columns(out, f.json); }},
             f.member);
}

template <class O>
std::vector<CellColumn> columns_of(const std::vector<Field<O>>& fields, const std::string& prefix,
                                   std::function<const O*(const CellRecord&)> locate) {
  std::vector<CellColumn> out;
  ColumnMaker<O> maker{out, prefix, std::move(locate)};
  for (const Field<O>& f : fields) maker.add(f);
  return out;
}

// The GPU model's columns stand where its row is; Embree's are per path, made for a set
// (cell_columns_for) or a rule (find_cell_column).
void add_group_columns(std::vector<CellColumn>& out, const std::string& key) {
  if (key != kGpuModelKey) return;
  for (CellColumn& c : columns_of<CellRecord::GpuModelFigures>(
           gpu_model_fields(), "", [](const CellRecord& r) { return r.gpu.profile.empty() ? nullptr : &r.gpu; }))
    out.push_back(std::move(c));
}

}  // namespace

const std::vector<CellColumn>& cell_columns() {
  static const std::vector<CellColumn> columns =
      columns_of<CellRecord>(cell_fields(), "", [](const CellRecord& r) { return &r; });
  return columns;
}

std::vector<CellColumn> embree_columns(const std::string& path) {
  return columns_of<CellRecord::EmbreeFigures>(embree_fields(), "embree_" + path,
                                               [path](const CellRecord& r) { return r.embree_path(path); });
}

std::vector<CellColumn> cell_columns_for(const std::vector<CellRecord>& cells) {
  std::vector<CellColumn> columns = cell_columns();
  std::vector<std::string> paths;
  for (const CellRecord& r : cells)
    for (const auto& e : r.embree)
      if (std::find(paths.begin(), paths.end(), e.path) == paths.end()) paths.push_back(e.path);
  for (const std::string& path : paths)
    for (CellColumn& c : embree_columns(path)) columns.push_back(std::move(c));
  return columns;
}

const CellColumn* find_cell_column(const std::string& name) {
  for (const auto& c : cell_columns())
    if (c.name == name) return &c;
  // Every path's columns, made once: a rule may name a path whichever set it is checked on.
  static const std::vector<CellColumn> embree = [] {
    std::vector<CellColumn> all;
    for (const EmbreePathInfo& info : kEmbreePaths)
      for (CellColumn& c : embree_columns(info.key)) all.push_back(std::move(c));
    return all;
  }();
  for (const auto& c : embree)
    if (c.name == name) return &c;
  return nullptr;
}

std::string csv_header() { return csv_header(cell_columns()); }

std::string csv_row(const CellRecord& r) { return csv_row(r, cell_columns()); }

std::string csv_header(const std::vector<CellColumn>& columns) {
  std::string s;
  for (const auto& c : columns) s += (s.empty() ? "" : ",") + c.name;
  return s;
}

std::string csv_row(const CellRecord& r, const std::vector<CellColumn>& columns) {
  std::string s;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i > 0) s += ',';
    s += columns[i].csv(r);
  }
  return s;
}

}  // namespace raysort
