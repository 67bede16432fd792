#include "scene/toml_reader.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <limits>

#include "util/error.h"

namespace raysort {

std::string toml_type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a floating-point number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::date: return "a date";
    case toml::node_type::time: return "a time";
    case toml::node_type::date_time: return "a date-time";
    default: return "nothing";
  }
}

toml::table parse_toml_text(const std::string& text, const std::string& origin) {
  try {
    return toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw Error(fmt::format("{}:{}:{}: TOML syntax error: {}; fix the file (docs/scene-format.md shows the format)",
                            origin, e.source().begin.line, e.source().begin.column, e.description()));
  }
}

TomlTable::TomlTable(const std::string& origin, const toml::table& table, std::string path,
                     std::initializer_list<std::string_view> keys)
    : origin_(origin), table_(table), path_(std::move(path)) {
  for (auto&& [k, v] : table_) {
    bool known = false;
    for (auto allowed : keys) known = known || k.str() == allowed;
    if (known) continue;
    throw Error(fmt::format("{}: unknown key '{}'{}; the keys allowed here are: {} (docs/scene-format.md)",
                            toml_location(v, origin_), full_key(k.str()),
                            path_.empty() ? "" : fmt::format(" in [{}]", path_), fmt::join(keys, ", ")));
  }
}

std::uint32_t TomlTable::line() const { return table_.source().begin.line ? table_.source().begin.line : 1; }

std::uint32_t TomlTable::line(std::string_view key) const {
  const toml::node* n = table_.get(key);
  return n && n->source().begin.line ? n->source().begin.line : line();
}

std::string toml_location(const toml::node& n, const std::string& fallback_origin) {
  const auto& src = n.source();
  const std::string& file = src.path && !src.path->empty() ? *src.path : fallback_origin;
  return fmt::format("{}:{}", file, src.begin.line ? src.begin.line : 1);
}

std::string TomlTable::location() const { return toml_location(table_, origin_); }

std::string TomlTable::location(std::string_view key) const {
  const toml::node* n = table_.get(key);
  return n && n->source().begin.line ? toml_location(*n, origin_) : location();
}

std::string TomlTable::full_key(std::string_view key) const {
  return path_.empty() ? std::string(key) : fmt::format("{}.{}", path_, key);
}

void TomlTable::fail(std::string_view key, const std::string& message) const {
  throw Error(fmt::format("{}: '{}' {}", location(key), full_key(key), message));
}

void TomlTable::fail_table(const std::string& message) const {
  throw Error(fmt::format("{}: [{}] {}", location(), path_, message));
}

const toml::node& TomlTable::required(std::string_view key, std::string_view example) const {
  const toml::node* n = table_.get(key);
  if (!n)
    throw Error(fmt::format("{}: [{}] is missing the required key '{}'; add it, e.g. {} = {}", location(), path_,
                            key, key, example));
  return *n;
}

double toml_number(const toml::node& n) {
  return n.is_integer() ? static_cast<double>(n.as_integer()->get()) : n.as_floating_point()->get();
}

bool fits_scene_float(double x) { return std::fabs(x) <= std::numeric_limits<float>::max(); }

double TomlTable::as_number(std::string_view key, const toml::node& n) const {
  if (!n.is_number()) fail(key, fmt::format("must be a number, not {}", toml_type_name(n)));
  const double v = toml_number(n);
  if (!std::isfinite(v)) fail(key, "must be a finite number, not nan or inf");
  if (!fits_scene_float(v))
    fail(key, fmt::format("= {:g} is beyond the float range scenes are stored in (|x| <= 3.4e38)", v));
  return v;
}

double TomlTable::number(std::string_view key, double fallback) const {
  const toml::node* n = table_.get(key);
  return n ? as_number(key, *n) : fallback;
}

double TomlTable::number(std::string_view key) const { return as_number(key, required(key, "1.0")); }

std::uint64_t TomlTable::integer(std::string_view key, std::uint64_t fallback, std::uint64_t lo,
                                 std::uint64_t hi) const {
  const toml::node* n = table_.get(key);
  if (!n) return fallback;
  auto i = n->as_integer();
  if (!i) fail(key, fmt::format("must be a whole number, not {}", toml_type_name(*n)));
  std::int64_t v = i->get();
  if (v < 0 || static_cast<std::uint64_t>(v) < lo || static_cast<std::uint64_t>(v) > hi)
    fail(key, fmt::format("= {} is out of range; use a whole number in [{}, {}]", v, lo, hi));
  return static_cast<std::uint64_t>(v);
}

bool TomlTable::boolean(std::string_view key, bool fallback) const {
  const toml::node* n = table_.get(key);
  if (!n) return fallback;
  auto b = n->as_boolean();
  if (!b) fail(key, fmt::format("must be true or false, not {}", toml_type_name(*n)));
  return b->get();
}

std::string TomlTable::string(std::string_view key, const std::string& fallback) const {
  const toml::node* n = table_.get(key);
  if (!n) return fallback;
  auto s = n->as_string();
  if (!s) fail(key, fmt::format("must be a string, not {}", toml_type_name(*n)));
  return s->get();
}

std::string TomlTable::string(std::string_view key) const {
  const toml::node& n = required(key, "\"...\"");
  auto s = n.as_string();
  if (!s) fail(key, fmt::format("must be a string, not {}", toml_type_name(n)));
  return s->get();
}

std::vector<double> TomlTable::numbers(std::string_view key, std::size_t count) const {
  const toml::node* n = table_.get(key);
  if (!n) return {};
  if (n->is_number()) return {as_number(key, *n)};
  auto arr = n->as_array();
  if (!arr || arr->size() != count)
    fail(key, fmt::format("must be a number or an array of {} numbers, not {}{}", count, toml_type_name(*n),
                          arr ? fmt::format(" of {} elements", arr->size()) : ""));
  std::vector<double> out;
  for (const auto& e : *arr) {
    if (!e.is_number()) fail(key, fmt::format("must hold numbers only, found {}", toml_type_name(e)));
    out.push_back(as_number(key, e));
  }
  return out;
}

Vec3 TomlTable::vec3(std::string_view key, Vec3 fallback) const {
  const toml::node* n = table_.get(key);
  if (!n) return fallback;
  auto arr = n->as_array();
  if (!arr || arr->size() != 3)
    fail(key, fmt::format("must be an array of 3 numbers like [0.0, 1.0, 0.0], not {}{}", toml_type_name(*n),
                          arr ? fmt::format(" of {} elements", arr->size()) : ""));
  Vec3 out{};
  for (std::size_t i = 0; i < 3; ++i) {
    if (!(*arr)[i].is_number()) fail(key, fmt::format("must hold numbers only, found {}", toml_type_name((*arr)[i])));
    out[i] = static_cast<float>(as_number(key, (*arr)[i]));
  }
  return out;
}

Vec3 TomlTable::vec3(std::string_view key) const {
  required(key, "[0.0, 0.0, 0.0]");
  return vec3(key, {});
}

const toml::table* TomlTable::subtable(std::string_view key) const {
  const toml::node* n = table_.get(key);
  if (!n) return nullptr;
  auto t = n->as_table();
  if (!t) fail(key, fmt::format("must be a table ([{}]), not {}", full_key(key), toml_type_name(*n)));
  return t;
}

std::vector<const toml::table*> TomlTable::table_array(std::string_view key) const {
  const toml::node* n = table_.get(key);
  if (!n) return {};
  auto arr = n->as_array();
  if (!arr || !arr->is_array_of_tables())
    fail(key, fmt::format("must be an array of tables: write each entry as [[{}]]", full_key(key)));
  std::vector<const toml::table*> out;
  for (const auto& e : *arr) out.push_back(e.as_table());
  return out;
}

}  // namespace raysort
