// The record's fields as data (issue 41, item 3): every field of the tables (bench/record_fields.h)
// is written to the cell file and read back equal, reaches cells.csv, and is a `compare` metric
// whose rule fires when that one field differs; older records read as they always did; the table
// does not change without a decision about the format version.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bench/compare.h"
#include "bench/record_columns.h"
#include "bench/record_fields.h"
#include "bench/result_set.h"
#include "test_util.h"
#include "util/atomic_file.h"
#include "util/fnv.h"

namespace fs = std::filesystem;
using namespace raysort;
using raysort::testing::temp_path;

namespace {

using G = CellRecord::GpuModelFigures;
using E = CellRecord::EmbreeFigures;
constexpr const char* kPath = "16-coherent";  // the Embree path of the test's record

// A value for each field, from `base` (1000 apart between fields, so no two fields share a value):
// `second` gives another one, for the record B that differs from A in that field alone. Text from a
// closed set takes a word of it other than the current one.
template <class O>
void set_value(const Field<O>& f, O& o, double base, bool second) {
  const double d = second ? 1.0 : 0.0;
  std::visit(Overload{[&](std::string O::*m) {
                        if (!f.vocabulary) return void(o.*m = fmt::format("{}{}", second ? "other" : "text", base));
                        const auto& words = f.vocabulary();
                        for (std::size_t i = 0; i < words.size(); ++i) {
                          const std::string& w = second ? words[words.size() - 1 - i] : words[i];
                          if (w != o.*m) return void(o.*m = w);
                        }
                      },
                      [&](bool O::*m) { o.*m = !(o.*m); },
                      [&](unsigned O::*m) { o.*m = static_cast<unsigned>(base + 1 + d); },
                      [&](std::uint64_t O::*m) { o.*m = static_cast<std::uint64_t>(base + 1 + d); },
                      [&](double O::*m) { o.*m = base + 0.5 + d / 4; },
                      [&](Estimate O::*m) {
                        o.*m = {base + 1.5 + d, base + 1.25 + d, base + 1.75 + d, static_cast<std::size_t>(base + 7 + d)};
                      },
                      [&](Timing O::*m) {
                        Timing& t = o.*m;
                        t.median_ms = base + 2 + d, t.lo_ms = base + 1.5 + d, t.hi_ms = base + 3 + d;
                        t.min_ms = base + 1 + d, t.max_ms = base + 4 + d, t.n = static_cast<std::size_t>(base + 9 + d);
                      },
                      [&](Series O::*m) { o.*m = {{"trace", {base + d}}}; },
                      // Derived figures follow their sources; a rate its timing's median.
                      [&](DerivedText<O>) {}, [&](Group) {},
                      [&](DerivedRate) { (o.*f.interval_of).median_ms = base + 2.5 + d; }},
             f.member);
}

template <class O>
bool same_value(const Field<O>& f, const O& a, const O& b) {
  auto same = [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  return std::visit(Overload{[&](Estimate O::*m) {
                               const Estimate &x = a.*m, &y = b.*m;
                               return same(x.value, y.value) && same(x.lo, y.lo) && same(x.hi, y.hi) && x.n == y.n;
                             },
                             [&](Timing O::*m) {
                               const Timing &x = a.*m, &y = b.*m;
                               return same(x.median_ms, y.median_ms) && same(x.lo_ms, y.lo_ms) &&
                                      same(x.hi_ms, y.hi_ms) && x.min_ms == y.min_ms && x.max_ms == y.max_ms && x.n == y.n;
                             },
                             [&](double O::*m) { return same(a.*m, b.*m); },
                             [&](DerivedText<O> text) { return text(a) == text(b); },
                             [&](DerivedRate) { return true; }, [&](Group) { return true; },
                             [&](auto m) { return a.*m == b.*m; }},
                    f.member);
}

// One field of the record, wherever it lives: the record, its GPU model figures, its Embree path.
struct AnyField {
  std::string where, json;  // for messages
  std::vector<std::string> columns;
  std::function<void(CellRecord&, double base, bool second)> set;
  std::function<bool(const CellRecord&, const CellRecord&)> same;
  bool derived = false;
};

// The cells.csv columns of a field, by the contract of bench/record_columns.h.
template <class O>
std::vector<std::string> columns_of(const Field<O>& f, const std::string& prefix) {
  auto name = [&](const std::string& suffix) {
    std::string n = prefix;
    for (const std::string& part : {column_stem(f), suffix})
      if (!part.empty()) n += (n.empty() ? "" : "_") + part;
    return n;
  };
  if (std::holds_alternative<Estimate O::*>(f.member)) return {name(""), name("lo"), name("hi"), name("n")};
  if (std::holds_alternative<Timing O::*>(f.member))
    return {name("ms"), name("lo_ms"), name("hi_ms"), name("min_ms"), name("max_ms"), name("n")};
  if (std::holds_alternative<Series O::*>(f.member) || std::holds_alternative<Group>(f.member)) return {};
  return {name("")};
}

template <class O>
void add_fields(std::vector<AnyField>& out, const std::vector<Field<O>>& table, const std::string& where,
                const std::string& prefix, std::function<O&(CellRecord&)> owner) {
  for (const Field<O>& f : table) {
    const bool derived = std::holds_alternative<DerivedText<O>>(f.member) || std::holds_alternative<DerivedRate>(f.member);
    out.push_back({where, f.json, columns_of(f, prefix),
                   [&f, owner](CellRecord& r, double base, bool second) { set_value(f, owner(r), base, second); },
                   [&f, owner](const CellRecord& a, const CellRecord& b) {
                     return same_value(f, owner(const_cast<CellRecord&>(a)), owner(const_cast<CellRecord&>(b)));
                   },
                   derived});
  }
}

std::vector<AnyField> every_field() {
  std::vector<AnyField> all;
  add_fields<CellRecord>(all, cell_fields(), "", "", [](CellRecord& r) -> CellRecord& { return r; });
  add_fields<G>(all, gpu_model_fields(), "gpu_model.", "", [](CellRecord& r) -> G& { return r.gpu; });
  add_fields<E>(all, embree_fields(), "embree.", std::string("embree_") + kPath,
                [](CellRecord& r) -> E& { return r.embree.at(0); });
  return all;
}

// A record with every field set to its own non-default value (a failed cell: the checks of an ok
// cell's figures against its samples do not apply to made-up figures).
CellRecord record_with_every_field(const std::vector<AnyField>& fields) {
  CellRecord r;
  r.embree.emplace_back();
  r.embree[0].path = kPath;
  for (std::size_t i = 0; i < fields.size(); ++i) fields[i].set(r, 1000.0 * static_cast<double>(i + 1), false);
  return r;
}

// A result set holding one cell, as compare reads it.
std::string set_of(const CellRecord& r, const std::string& name) {
  const fs::path dir = temp_path(name);
  fs::create_directories(dir / "cells");
  std::ofstream(dir / "meta.json") << nlohmann::json{{"format_version", kResultFormatVersion}}.dump();
  std::ofstream(dir / "cells" / cell_file_name(r.id())) << nlohmann::json(r).dump(1);
  return dir.string();
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::vector<std::string> split(const std::string& text, char at) {
  std::vector<std::string> parts{""};
  for (char c : text) {
    if (c == at) parts.emplace_back();
    else parts.back().push_back(c);
  }
  return parts;
}

}  // namespace

// Every field: written with a distinct non-default value and read back equal.
TEST(RecordFields, EveryFieldReadsBackEqual) {
  const std::vector<AnyField> fields = every_field();
  const CellRecord r = record_with_every_field(fields);
  ASSERT_EQ(r.status, "failed");
  ASSERT_FALSE(r.gpu.profile.empty());
  EXPECT_EQ(cell_record_problem(r), "");
  const nlohmann::json j = nlohmann::json::parse(nlohmann::json(r).dump());  // as a file holds it
  const CellRecord back = j.get<CellRecord>();
  for (const AnyField& f : fields) EXPECT_TRUE(f.same(r, back)) << f.where << f.json << " did not read back equal";
  EXPECT_EQ(nlohmann::json(back), j);
  // Every key is written, an absent one as null: a record without the GPU model and Embree paths.
  const nlohmann::json none = CellRecord{};
  for (const Field<CellRecord>& f : cell_fields()) EXPECT_TRUE(none.contains(f.json)) << f.json;
  EXPECT_TRUE(none["leaks_per_million"].is_null());
  EXPECT_TRUE(none["cut_ms"].is_null());
  EXPECT_TRUE(none["gpu_model"].is_null());
  EXPECT_EQ(none["embree"], nlohmann::json::array());
}

// Every field reaches cells.csv: each of its columns is in the header, and the row holds its value.
TEST(RecordFields, EveryFieldReachesCellsCsv) {
  const std::vector<AnyField> fields = every_field();
  const CellRecord r = record_with_every_field(fields);
  const std::vector<CellColumn> columns = cell_columns_for({r});
  std::map<std::string, std::string> row;
  for (const CellColumn& c : columns) row[c.name] = c.csv(r);
  std::size_t expected = 0;
  for (const AnyField& f : fields) {
    if (f.json == "samples") {
      EXPECT_TRUE(f.columns.empty()) << "the raw samples stay in the cell file";
    }
    for (const std::string& c : f.columns) {
      ++expected;
      ASSERT_TRUE(row.count(c)) << f.where << f.json << ": no column " << c << " in " << csv_header(columns);
      EXPECT_FALSE(row[c].empty()) << f.where << f.json << ": column " << c << " is empty";
    }
  }
  EXPECT_EQ(columns.size(), expected) << "a column no field of the table names: " << csv_header(columns);
  EXPECT_EQ(csv_header(columns).find("samples"), std::string::npos);
  // The values as written, one per kind.
  EXPECT_EQ(row["id"], r.id());
  EXPECT_EQ(row["leaks_per_million"], fmt::format("{:.3f}", r.leaks_per_million));
  EXPECT_EQ(row["gpu_warps"], fmt::format("{}", r.gpu.warps));
  EXPECT_EQ(row["speedup_n"], fmt::format("{}", r.speedup.n));
  EXPECT_EQ(row["encode_max_ms"], fmt::format("{:.4f}", r.encode.max_ms));
  EXPECT_EQ(row[std::string("embree_") + kPath + "_differ"], fmt::format("{}", r.embree[0].differ));
  EXPECT_EQ(row["error"], "\"" + r.error + "\"");
  EXPECT_EQ(row["status"], "failed");
}

// Every field is a compare metric: two sets whose one cell differs in that field alone make the
// rule `COLUMN!=` fire on each of its columns. A field of the cell's id (scene, bits, variant...)
// makes another cell: there `missing` fires.
TEST(RecordFields, EveryFieldIsACompareMetricWhoseRuleFires) {
  const std::vector<AnyField> fields = every_field();
  const CellRecord a = record_with_every_field(fields);
  const ResultSet set_a = ResultSet::load(set_of(a, "metric-a"));
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const AnyField& f = fields[i];
    if (f.columns.empty() || f.json == "id") continue;  // the samples; the id follows its parts
    CellRecord b = a;
    f.set(b, 1000.0 * static_cast<double>(i + 1), true);
    ASSERT_FALSE(f.same(a, b) && !f.derived) << f.where << f.json << ": the second value equals the first";
    std::vector<FailRule> rules;
    for (const std::string& c : f.columns) rules.push_back(FailRule::parse(c + "!="));
    if (b.id() != a.id()) rules = {FailRule::parse("missing")};
    const std::string dir_b = set_of(b, "metric-b-" + std::to_string(i));
    const CompareResult out = compare_result_sets(set_a, ResultSet::load(dir_b), {}, rules);
    for (const FailRule& rule : rules) {
      bool fired = false;
      for (const std::string& v : out.violations) fired = fired || contains(v, "(rule " + rule.text) || rule.text == "missing";
      EXPECT_TRUE(fired && !out.violations.empty()) << f.where << f.json << ": rule " << rule.text << " did not fire";
    }
    fs::remove_all(dir_b);
  }
}

// Records of format version 3 and before read as they always did: the keys they left out read as
// absent, -1 as no leaks_per_million, NoSort's ANC 0 as null; from version 4 every key is required.
TEST(RecordFields, OlderRecordsReadAsBeforeAndNewOnesNeedEveryKey) {
  // Read as from a file (a parsed file's counts are unsigned JSON numbers).
  auto read = [](const nlohmann::json& j) { return nlohmann::json::parse(j.dump()).get<CellRecord>(); };
  CellRecord r;
  r.scene = "cornell", r.batch = "primary", r.encoder = kBaselineEncoder;
  nlohmann::json v3 = r;
  v3["format_version"] = 3;
  v3["leaks_per_million"] = -1.0;
  v3["anc"] = 0.0;
  for (const char* key : {"cut_ms", "gpu_model", "embree"}) v3.erase(key);
  const CellRecord old = read(v3);
  EXPECT_EQ(old.leaks_per_million, -1.0);
  EXPECT_EQ(old.cut_ms, -1.0);
  EXPECT_TRUE(old.gpu.profile.empty());
  EXPECT_TRUE(old.embree.empty());
  EXPECT_TRUE(std::isnan(old.anc)) << "NoSort has no keys";
  EXPECT_EQ(csv_row(old), csv_row(r));
  // A GPU model object of early version 3, before steps_l2, steps_dram and ww_steps.
  v3["gpu_model"] = {{"profile", "rtx3060"}, {"time_us", 1.5}, {"speedup", 1.1}, {"warp_steps", 3}, {"idle_lanes", 4},
                     {"l1_hits", 5}, {"l1_misses", 6}, {"l2_hits", 7}, {"l2_misses", 8}, {"dram_bytes", 9},
                     {"warps", 10}, {"replayed_warps", 10}};
  EXPECT_EQ(read(v3).gpu.warps, 10u);
  EXPECT_EQ(read(v3).gpu.steps_l2, 0u);
  // Version 4: every key, null when absent.
  nlohmann::json v4 = r;
  EXPECT_NO_THROW(read(v4));
  v4.erase("cut_ms");
  try {
    (void)read(v4);
    ADD_FAILURE() << "a version 4 record without cut_ms was read";
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "\"cut_ms\" is missing")) << e.what();
  }
  nlohmann::json null_scene = r;
  null_scene["scene"] = nullptr;
  EXPECT_THROW((void)read(null_scene), std::exception);
}

// The table is the record's format: a change to a field's key, column, type, absence or required
// version changes this fingerprint. When it does, decide: a field whose meaning changed bumps
// kResultFormatVersion (bench/record.h, with a line saying what changed); a new field takes
// required_from = kResultFormatVersion + 1. Then set the fingerprint printed here. (A new word in a
// vocabulary, such as the trace classes 'stream' and 'coherent8' in layout, changes no field's
// meaning: same version.)
TEST(RecordFields, TheTableChangesOnlyWithADecisionOnTheFormatVersion) {
  std::string shape = fmt::format("version {}\n", kResultFormatVersion);
  auto describe = [&shape](const auto& table, const char* group) {
    for (const auto& f : table) {
      std::string words;
      if (f.vocabulary)
        for (const std::string& w : f.vocabulary()) words += w + "|";
      shape += fmt::format("{} {} '{}' type {} absent {} from {} digits {} rate {} quoted {} words {}\n", group, f.json,
                           column_stem(f), f.member.index(), static_cast<int>(f.absent), f.required_from, f.decimals,
                           f.interval_of != nullptr, f.quoted, words);
      EXPECT_LE(f.required_from, kResultFormatVersion + 1) << f.json << ": required before it was written";
    }
  };
  describe(cell_fields(), "cell");
  describe(gpu_model_fields(), "gpu_model");
  describe(embree_fields(), "embree");
  EXPECT_EQ(fmt::format("{:016x}", fnv1a(shape)), "a68f07d9b6a2693e") << shape;
}

// FNV-1a 64, written once (util/fnv.h): the published test vectors, and pieces hash as their
// concatenation.
TEST(Fnv1a, PublishedValuesAndPieces) {
  EXPECT_EQ(fnv1a(""), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a("foobar"), 0x85944171f73967e8ull);
  EXPECT_EQ(fnv1a("bar", fnv1a("foo")), fnv1a("foobar"));
  EXPECT_EQ(fnv1a_hex("foobar", 6), "85944171f73967e8");
}

// Issue 41's defect: `raysort report` on a copy of a golden set wrote a cells.csv without
// leaks_per_million and the GPU model's warps, though every cell file holds them, so compare could
// not rule on them. Now both are columns with the files' values, and rules on them fire.
TEST(ReportOnAGoldenCopy, KeepsLeaksPerMillionAndTheGpuModelsWarps) {
  const fs::path golden = fs::path(RAYSORT_SOURCE_DIR) / "tests/golden/quick-tiny";
  const std::string a = temp_path("golden-a"), b = temp_path("golden-b");
  fs::copy(golden, a, fs::copy_options::recursive);
  fs::copy(golden, b, fs::copy_options::recursive);
  auto edit = [](const fs::path& file, const std::function<void(nlohmann::json&)>& change) {
    std::ifstream in(file);
    nlohmann::json j = nlohmann::json::parse(in);
    in.close();
    change(j);
    std::ofstream(file) << j.dump(1);
  };
  // In B, as a version 3 writer writes them: a NoSort cell that measured leaks (a run with both
  // variants), and a cell whose replay counted one warp more.
  const fs::path cells = fs::path(b) / "cells";
  edit(cells / "cornell__primary__nosort__0.json", [](nlohmann::json& j) { j["leaks_per_million"] = 12.5; });
  std::uint64_t warps = 0;
  edit(cells / "cornell__primary__hcc__32.json", [&warps](nlohmann::json& j) {
    warps = j["gpu_model"]["warps"].get<std::uint64_t>() + 1;
    j["gpu_model"]["warps"] = warps;
  });
  for (const std::string& dir : {a, b}) {
    const raysort::testing::CliResult r = raysort::testing::run_cli({"report", dir});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  // The cells.csv of B: its header, and a cell's row (split at commas: the columns read here come
  // before the one quoted free-text column, error).
  const std::string csv = read_file(b + "/cells.csv");
  const std::vector<std::string> header = split(csv.substr(0, csv.find('\n')), ',');
  auto field = [&](const std::string& id, const std::string& column) -> std::string {
    const auto at = std::find(header.begin(), header.end(), column);
    if (at == header.end()) return "(no column " + column + ")";
    const std::size_t line = csv.find("\n" + id + ",") + 1;
    const std::vector<std::string> row = split(csv.substr(line, csv.find('\n', line) - line), ',');
    return row.at(static_cast<std::size_t>(at - header.begin()));
  };
  EXPECT_EQ(field("cornell/primary/nosort/0", "leaks_per_million"), "12.500");
  EXPECT_EQ(field("cornell/primary/hcc/32", "gpu_warps"), std::to_string(warps));
  EXPECT_EQ(field("cornell/primary/hcc/32", "leaks_per_million"), "") << "-1 in the file: not measured";
  const raysort::testing::CliResult r =
      raysort::testing::run_cli({"compare", a, b, "--fail-if", "leaks_per_million!=", "--fail-if", "gpu_warps!="});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(contains(r.out, "cornell/primary/nosort/0: leaks_per_million – -> 12.5 (rule leaks_per_million!=)")) << r.out;
  EXPECT_TRUE(contains(r.out, fmt::format("cornell/primary/hcc/32: gpu_warps {} -> {} (rule gpu_warps!=)", warps - 1, warps)))
      << r.out;
  fs::remove_all(a);
  fs::remove_all(b);
}
