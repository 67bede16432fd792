// meta.json "encoder_files" and "ray_files" (see encoder_files.h).
#include "bench/encoder_files.h"

#include <fmt/format.h>

#include <set>

namespace raysort {

namespace {

// The recorded files under `key` ("encoder_files", "ray_files"), or null when the meta has none (or
// not as an object).
const nlohmann::json* recorded(const nlohmann::json& meta, const char* key = "encoder_files") {
  if (!meta.is_object()) return nullptr;
  const auto it = meta.find(key);
  return it != meta.end() && it->is_object() ? &*it : nullptr;
}

std::string text_of(const nlohmann::json& entry, const char* key) {
  if (!entry.is_object()) return "";
  const auto it = entry.find(key);
  return it != entry.end() && it->is_string() ? it->get<std::string>() : "";
}

std::string short_sha(const std::string& sha) { return sha.empty() ? "no checksum" : sha.substr(0, 12); }

// One line per named file whose SHA-256 differs between the two metas' `key` objects.
std::vector<std::string> file_differences(const nlohmann::json& meta_a, const nlohmann::json& meta_b, const char* key) {
  const nlohmann::json* a = recorded(meta_a, key);
  const nlohmann::json* b = recorded(meta_b, key);
  if (!a && !b) return {};
  std::set<std::string> names;
  for (const nlohmann::json* files : {a, b})
    if (files)
      for (auto it = files->begin(); it != files->end(); ++it) names.insert(it.key());
  std::vector<std::string> lines;
  for (const std::string& name : names) {
    const bool in_a = a && a->contains(name), in_b = b && b->contains(name);
    if (!in_a || !in_b) {
      lines.push_back(fmt::format("{}: recorded in {} only (sha256 {})", name, in_a ? "A" : "B",
                                  short_sha(text_of((in_a ? *a : *b)[name], "sha256"))));
      continue;
    }
    const std::string sa = text_of((*a)[name], "sha256"), sb = text_of((*b)[name], "sha256");
    if (sa == sb && !sa.empty()) continue;
    lines.push_back(fmt::format("{}: sha256 {} in A, {} in B", name, short_sha(sa), short_sha(sb)));
  }
  return lines;
}

}  // namespace

std::vector<std::string> encoder_file_differences(const nlohmann::json& meta_a, const nlohmann::json& meta_b) {
  return file_differences(meta_a, meta_b, "encoder_files");
}

std::vector<std::string> ray_file_differences(const nlohmann::json& meta_a, const nlohmann::json& meta_b) {
  return file_differences(meta_a, meta_b, "ray_files");
}

std::vector<RecordedEncoderFile> recorded_encoder_files(const nlohmann::json& meta) {
  std::vector<RecordedEncoderFile> out;
  if (const nlohmann::json* files = recorded(meta))
    for (auto it = files->begin(); it != files->end(); ++it)
      out.push_back({it.key(), text_of(it.value(), "path"), text_of(it.value(), "sha256")});
  return out;
}

}  // namespace raysort
