// A cell record as its file holds it: to_json and from_json walk the field tables
// (bench/record_fields.h). Every key is written; an absent field is null. Reading accepts every
// format version from kOldestReadableFormatVersion: a key a version's records may lack reads as the
// field's default (Field::required_from), and the few older spellings are read as they always were
// (the end of this file).
#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "bench/record_fields.h"

namespace raysort {

namespace {

using nlohmann::json;

// Errors are plain runtime errors: the reader of the file (result_set.cpp) names the file and the fix.
[[noreturn]] void refuse(const std::string& what) { throw std::runtime_error(what); }

// A count (key bits, rays, rounds): a non-negative integer in JSON, never a float cast into one
// (fuzz/result_set_fuzzer: 7.8e50 was undefined).
template <class T>
T count_from(const json& v, const std::string& key) {
  if (!v.is_number_unsigned() || v.get<std::uint64_t>() > std::numeric_limits<T>::max())
    refuse(fmt::format("\"{}\" is {}, not a count", key, v.dump()));
  return v.get<T>();
}
// A number without a value (NaN, or infinite) is null.
json number(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }
double number_from(const json& j) { return j.is_null() ? kNaN : j.get<double>(); }

json estimate_json(const Estimate& e) {
  return {{"value", number(e.value)}, {"lo", number(e.lo)}, {"hi", number(e.hi)}, {"n", e.n}};
}
Estimate estimate_from(const json& j, const std::string& key) {
  if (j.is_number()) return {j.get<double>(), kNaN, kNaN, 0};  // format version 1 stored a point figure
  return {number_from(j.at("value")), number_from(j.at("lo")), number_from(j.at("hi")),
          count_from<std::size_t>(j.at("n"), key + ".n")};
}

json timing_json(const Timing& t) {
  return {{"median", number(t.median_ms)}, {"lo", number(t.lo_ms)}, {"hi", number(t.hi_ms)},
          {"min", number(t.min_ms)},       {"max", number(t.max_ms)}, {"n", t.n}};
}
Timing timing_from(const json& o, const std::string& key) {
  Timing t;
  t.median_ms = o.at("median").get<double>();
  t.min_ms = o.at("min").get<double>();
  t.max_ms = o.at("max").get<double>();
  // Version 1 wrote neither an interval nor the sample count.
  t.lo_ms = o.contains("lo") ? number_from(o.at("lo")) : kNaN;
  t.hi_ms = o.contains("hi") ? number_from(o.at("hi")) : kNaN;
  if (o.contains("n")) t.n = count_from<std::size_t>(o.at("n"), key + ".n");
  return t;
}

json group_json(const std::string& key, const CellRecord& cell);
void group_from(const std::string& key, const json& v, CellRecord& cell, std::uint64_t version);

template <class O>
json field_json(const Field<O>& f, const CellRecord& cell, const O& o) {
  if (field_absent(f, o)) return nullptr;
  return std::visit(Overload{[&](std::string O::*m) { return json(o.*m); },
                             [&](bool O::*m) { return json(o.*m); },
                             [&](unsigned O::*m) { return json(o.*m); },
                             [&](std::uint64_t O::*m) { return json(o.*m); },
                             [&](double O::*m) { return number(o.*m); },
                             [&](Estimate O::*m) { return estimate_json(o.*m); },
                             [&](Timing O::*m) { return timing_json(o.*m); },
                             [&](Series O::*m) { return json(o.*m); },
                             [&](DerivedText<O> text) { return json(text(o)); },
                             [&](DerivedRate) { return number(mrays_at(cell.rays, o.*f.interval_of)); },
                             [&](Group) { return group_json(f.json, cell); }},
                    f.member);
}

template <class O>
json fields_json(const std::vector<Field<O>>& fields, const CellRecord& cell, const O& o) {
  json j = json::object();
  for (const Field<O>& f : fields) j[f.json] = field_json(f, cell, o);
  return j;
}

// One field from its object `j` (`where` names the object in messages: "", "gpu_model: ").
template <class O>
void field_from(const json& j, const Field<O>& f, O& o, CellRecord& cell, std::uint64_t version,
                const std::string& where) {
  if (std::holds_alternative<DerivedText<O>>(f.member) || std::holds_alternative<DerivedRate>(f.member)) return;
  if (!j.contains(f.json)) {
    if (version >= static_cast<std::uint64_t>(f.required_from))
      refuse(fmt::format("{}\"{}\" is missing (every record of format version {} holds it)", where, f.json, version));
    return;  // an older record: the field's default
  }
  const json& v = j.at(f.json);
  const bool number = std::holds_alternative<double O::*>(f.member), group = std::holds_alternative<Group>(f.member);
  if (v.is_null() && !number && !group) {
    if (f.absent == Absent::Never) refuse(fmt::format("{}\"{}\" is null, but it always has a value", where, f.json));
    static const O defaults{};
    std::visit([&](auto m) {
      if constexpr (std::is_member_object_pointer_v<decltype(m)>) o.*m = defaults.*m;
    }, f.member);
    return;
  }
  std::visit(Overload{[&](std::string O::*m) { v.get_to(o.*m); },
                      [&](bool O::*m) { v.get_to(o.*m); },
                      [&](unsigned O::*m) { o.*m = count_from<unsigned>(v, where + f.json); },
                      [&](std::uint64_t O::*m) { o.*m = count_from<std::uint64_t>(v, where + f.json); },
                      [&](double O::*m) { o.*m = v.is_null() && f.absent == Absent::WhenNegative ? -1.0 : number_from(v); },
                      [&](Estimate O::*m) { o.*m = estimate_from(v, where + f.json); },
                      [&](Timing O::*m) { o.*m = timing_from(v, where + f.json); },
                      [&](Series O::*m) { v.get_to(o.*m); },
                      [&](DerivedText<O>) {}, [&](DerivedRate) {},
                      [&](Group) { group_from(f.json, v, cell, version); }},
             f.member);
}

template <class O>
void fields_from(const json& j, const std::vector<Field<O>>& fields, O& o, CellRecord& cell, std::uint64_t version,
                 const std::string& where) {
  if (!j.is_object()) refuse(fmt::format("{}not an object but {}", where, j.dump()));
  for (const Field<O>& f : fields) field_from(j, f, o, cell, version, where);
}

// The groups: the GPU model's figures, one object or null (the model was off); Embree's paths, a
// list of objects, each named by its path.
json group_json(const std::string& key, const CellRecord& cell) {
  if (key == kGpuModelKey) return cell.gpu.profile.empty() ? json(nullptr) : fields_json(gpu_model_fields(), cell, cell.gpu);
  json paths = json::array();
  for (const CellRecord::EmbreeFigures& e : cell.embree) {
    json p = fields_json(embree_fields(), cell, e);
    p[kEmbreePathKey] = e.path;
    paths.push_back(std::move(p));
  }
  return paths;
}

void group_from(const std::string& key, const json& v, CellRecord& cell, std::uint64_t version) {
  if (key == kGpuModelKey) {
    if (!v.is_null()) fields_from(v, gpu_model_fields(), cell.gpu, cell, version, "gpu_model: ");
    return;
  }
  if (!v.is_array()) refuse("\"embree\" is not a list of Embree paths");
  for (const json& p : v) {
    CellRecord::EmbreeFigures e;
    if (!p.is_object() || !p.contains(kEmbreePathKey)) refuse("an element of \"embree\" names no \"path\"");
    p.at(kEmbreePathKey).get_to(e.path);
    fields_from(p, embree_fields(), e, cell, version, fmt::format("Embree path {}: ", e.path));
    cell.embree.push_back(std::move(e));
  }
}

std::uint64_t format_version_of(const json& j) {
  // Read as a count, never as a float cast to int (fuzz/result_set_fuzzer: 7.8e50 was undefined).
  const std::uint64_t version = j.contains("format_version") ? count_from<std::uint64_t>(j.at("format_version"), "format_version") : 0;
  if (version < kOldestReadableFormatVersion || version > kResultFormatVersion)
    refuse(fmt::format("cell record has format version {}, this raysort reads versions {} to {}", version,
                       kOldestReadableFormatVersion, kResultFormatVersion));
  return version;
}

}  // namespace

void to_json(nlohmann::json& j, const CellRecord& r) {
  j = fields_json(cell_fields(), r, r);
  j["format_version"] = kResultFormatVersion;
}

void from_json(const nlohmann::json& j, CellRecord& r) {
  const std::uint64_t version = format_version_of(j);
  fields_from(j, cell_fields(), r, r, version, "");
  // Older spellings read as they always were: sets before NoSort's ANC was null stored it as 0 (in
  // any version: NoSort has no keys, so 0 is never its figure); version 3 and before wrote -1 for no
  // leaks_per_million (-1 is what the record holds in memory) and left out the keys of absent
  // fields (Field::required_from).
  if (r.encoder == kBaselineEncoder && r.anc == 0.0) r.anc = kNaN;
}

}  // namespace raysort
