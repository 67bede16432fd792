#pragma once
// Typed, checked access to one TOML table of a scene file. Every failure throws Error naming
// the file, the line and the full key ("scenes/x.toml:12: 'camera.fov_y' ...") and what to do.
#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scene/scene.h"

namespace raysort {

class TomlTable {
 public:
  // `path` names the table in messages ("camera", "mesh[2]"); `keys` are the allowed keys:
  // any other key is reported with its line.
  TomlTable(const std::string& origin, const toml::table& table, std::string path,
            std::initializer_list<std::string_view> keys);

  bool has(std::string_view key) const { return table_.get(key) != nullptr; }
  const toml::node* node(std::string_view key) const { return table_.get(key); }
  const toml::table& table() const { return table_; }
  const std::string& path() const { return path_; }
  const std::string& origin() const { return origin_; }
  std::uint32_t line() const;                       // the table's own line (its header)
  std::uint32_t line(std::string_view key) const;   // the line of a key's value
  // "file:line" of the table's header, or of a key's value. The file is the one the node was parsed
  // from: with `extends`, a table can come from the base scene's file, not from `origin`.
  std::string location() const;
  std::string location(std::string_view key) const;
  std::string full_key(std::string_view key) const;  // "camera.fov_y"

  double number(std::string_view key, double fallback) const;
  double number(std::string_view key) const;  // required
  std::uint64_t integer(std::string_view key, std::uint64_t fallback, std::uint64_t lo, std::uint64_t hi) const;
  bool boolean(std::string_view key, bool fallback) const;
  std::string string(std::string_view key, const std::string& fallback) const;
  std::string string(std::string_view key) const;  // required
  Vec3 vec3(std::string_view key, Vec3 fallback) const;
  Vec3 vec3(std::string_view key) const;  // required
  // A number or an array of `n` numbers.
  std::vector<double> numbers(std::string_view key, std::size_t n) const;
  // A sub-table, or nullptr when absent.
  const toml::table* subtable(std::string_view key) const;
  // The tables of an array of tables ([[key]]); empty when absent.
  std::vector<const toml::table*> table_array(std::string_view key) const;

  // Throws "<origin>:<line>: '<table.key>' <message>".
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;
  [[noreturn]] void fail_table(const std::string& message) const;  // at the table's line

 private:
  const toml::node& required(std::string_view key, std::string_view example) const;
  double as_number(std::string_view key, const toml::node& n) const;

  std::string origin_;
  const toml::table& table_;
  std::string path_;
};

// "file:line" of a node as parsed (toml++ keeps each node's file and line; a copied node loses them,
// so scene tables are moved, never copied, when `extends` merges them). `fallback_origin` names the
// file when the node has none.
std::string toml_location(const toml::node& n, const std::string& fallback_origin);

// Name of a TOML value's type for messages ("a string", "an array").
std::string toml_type_name(const toml::node& n);

// A TOML number (integer or float) as a double; n must be a number (is_number()).
double toml_number(const toml::node& n);

// Whether x fits the float that geometry, cameras and lights are stored in (|x| <= 3.4e38, not NaN):
// a larger value would become inf there (and 0 · inf = NaN in a transform), which no later check
// could tell from a user's intent.
bool fits_scene_float(double x);

// Parses TOML text; a syntax error throws Error "<origin>:<line>:<column>: ...".
toml::table parse_toml_text(const std::string& text, const std::string& origin);

}  // namespace raysort
