// The scene-file catalogue (scenes/sources.toml) and the checks against it (scene/provenance.h).
#include "scene/provenance.h"

#include <fmt/format.h>
#include <openssl/evp.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include "scene/load.h"
#include "scene/toml_reader.h"
#include "util/embedded.h"
#include "util/error.h"

namespace fs = std::filesystem;

namespace raysort {

namespace {

bool is_hex(std::string_view s, std::size_t digits) {
  return s.size() == digits &&
         std::all_of(s.begin(), s.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

std::string short_hash(const std::string& hex) { return hex.substr(0, 12); }

std::uint64_t required_count(const TomlTable& t, std::string_view key) {
  if (!t.has(key)) t.fail_table(fmt::format("is missing the required key '{}' (a whole number of at least 1)", key));
  return t.integer(key, 0, 1, ~std::uint64_t{0} >> 1);
}

SceneFileSource read_source(const TomlTable& entry) {
  const toml::table* st = entry.subtable("source");
  if (!st) entry.fail_table("is missing the required key 'source' = { origin = \"...\", path = \"...\", commit = \"...\" }");
  TomlTable t(entry.origin(), *st, entry.full_key("source"), {"origin", "path", "commit", "version"});
  SceneFileSource s;
  s.origin = t.string("origin");
  s.path = t.string("path");
  s.commit = t.string("commit", std::string());
  s.version = t.string("version", std::string());
  if (s.commit.empty() == s.version.empty())
    t.fail_table("needs exactly one of 'commit' (a git commit) or 'version' (a package version)");
  if (!s.commit.empty() && !is_hex(s.commit, 40)) t.fail("commit", "must be a full git commit: 40 lowercase hex digits");
  return s;
}

// One [\"<path>\"] table: an OBJ file or, with material_of, a material file.
CatalogueEntry read_entry(const std::string& origin, const std::string& path, const toml::table& table) {
  const bool material = table.contains("material_of");
  const std::string name = fmt::format("\"{}\"", path);
  TomlTable t = material ? TomlTable(origin, table, name, {"sha256", "bytes", "material_of"})
                         : TomlTable(origin, table, name,
                                     {"sha256", "bytes", "triangles", "source", "licence", "credit", "conversion", "mtl"});
  CatalogueEntry e;
  e.path = path;
  e.sha256 = t.string("sha256");
  if (!is_hex(e.sha256, 64)) t.fail("sha256", "must be 64 lowercase hex digits (the output of sha256sum)");
  e.bytes = required_count(t, "bytes");
  if (material) {
    e.material_of = t.string("material_of");
    return e;
  }
  e.triangles = required_count(t, "triangles");
  e.source = read_source(t);
  e.licence = t.string("licence");
  e.credit = t.string("credit", std::string());
  e.conversion = t.string("conversion");
  e.mtl = t.string("mtl", std::string());
  if (e.licence.empty()) t.fail("licence", "must not be empty: write \"unknown: ...\" when the source states none");
  return e;
}

// Every mtl names a material entry that names this OBJ back (material_of), and the reverse.
void check_links(const std::vector<CatalogueEntry>& entries, const std::string& origin) {
  std::map<std::string, const CatalogueEntry*> by_path;
  for (const auto& e : entries) by_path[e.path] = &e;
  for (const auto& e : entries) {
    const bool is_obj = e.material_of.empty();
    const std::string& other = is_obj ? e.mtl : e.material_of;
    if (other.empty()) continue;
    const std::string_view key = is_obj ? "mtl" : "material_of", back_key = is_obj ? "material_of" : "mtl";
    auto it = by_path.find(other);
    if (it == by_path.end())
      throw Error(fmt::format("{}: \"{}\" has {} = \"{}\", which has no entry; add [\"{}\"] with {} = \"{}\"", origin,
                              e.path, key, other, other, back_key, e.path));
    const std::string& back = is_obj ? it->second->material_of : it->second->mtl;
    if (back != e.path)
      throw Error(fmt::format("{}: \"{}\" has {} = \"{}\", but that entry does not name it back; set {} = \"{}\" there",
                              origin, e.path, key, other, back_key, e.path));
  }
}

}  // namespace

std::vector<CatalogueEntry> parse_scene_catalogue(const std::string& text, const std::string& origin) {
  const toml::table root = parse_toml_text(text, origin);
  std::vector<CatalogueEntry> out;
  for (auto&& [key, node] : root) {
    const std::string path(key.str());
    const std::uint32_t line = key.source().begin.line ? key.source().begin.line : node.source().begin.line;
    if (path.empty() || fs::path(path).is_absolute() || path.find("..") != std::string::npos ||
        path.find('\\') != std::string::npos)
      throw Error(fmt::format("{}:{}: \"{}\" must be a path relative to the scene root, like \"sibenik/sibenik.obj\"",
                              origin, line, path));
    const toml::table* table = node.as_table();
    if (!table)
      throw Error(fmt::format("{}:{}: \"{}\" must be a table ([\"{}\"] followed by sha256, bytes, ...), not {}",
                              origin, line, path, path, toml_type_name(node)));
    out.push_back(read_entry(origin, path, *table));
  }
  check_links(out, origin);
  return out;
}

const std::vector<CatalogueEntry>& scene_catalogue() {
  static const std::vector<CatalogueEntry> catalogue = [] {
    auto text = find_embedded(kSceneCatalogue);
    if (!text) throw Error(fmt::format("{} is not embedded in this build; rebuild raysort", kSceneCatalogue));
    return parse_scene_catalogue(std::string(*text), fmt::format("embedded:{}", kSceneCatalogue));
  }();
  return catalogue;
}

const CatalogueEntry* find_catalogued(std::string_view relative_path) {
  for (const auto& e : scene_catalogue())
    if (e.path == relative_path) return &e;
  return nullptr;
}

std::vector<std::string> files_with_materials(const std::vector<std::string>& obj_files) {
  std::vector<std::string> out;
  auto add = [&](const std::string& f) {
    if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
  };
  for (const auto& obj : obj_files) {
    add(obj);
    if (const CatalogueEntry* e = find_catalogued(obj); e && !e->mtl.empty()) add(e->mtl);
  }
  return out;
}

namespace {
struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
}  // namespace

namespace {

// A SHA-256 digest fed in pieces (OpenSSL's EVP interface), as 64 lowercase hex digits at the end.
class Sha256 {
 public:
  Sha256() {
    if (!ctx_ || EVP_DigestInit_ex(ctx_.get(), EVP_sha256(), nullptr) != 1)
      throw Error("OpenSSL could not start a SHA-256 digest; check the libcrypto installation (scripts/install-deps.sh)");
  }
  void update(const void* data, std::size_t n) {
    if (n > 0 && EVP_DigestUpdate(ctx_.get(), data, n) != 1) throw Error("OpenSSL SHA-256 update failed");
  }
  std::string hex() {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned int len = 0;
    if (EVP_DigestFinal_ex(ctx_.get(), digest, &len) != 1) throw Error("OpenSSL SHA-256 final step failed");
    std::string out;
    for (unsigned int i = 0; i < len; ++i) out += fmt::format("{:02x}", digest[i]);
    return out;
  }

 private:
  std::unique_ptr<EVP_MD_CTX, void (*)(EVP_MD_CTX*)> ctx_{EVP_MD_CTX_new(), &EVP_MD_CTX_free};
};

}  // namespace

std::string sha256_file(const std::string& path) {
  // A FIFO would block the read forever and a device never end it (issue 44): regular files only.
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    throw Error(fmt::format("cannot read {}: not a regular file (a directory, FIFO or device); give the scene file "
                            "itself",
                            path));
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw Error(fmt::format("cannot read {}: {}; check the path and its permissions", path, std::strerror(errno)));
  Sha256 digest;
  // 256 KiB at a time: the largest scene files are tens of MB and need not be held whole.
  std::vector<unsigned char> chunk(256 * 1024);
  while (true) {
    const std::size_t n = std::fread(chunk.data(), 1, chunk.size(), file.get());
    digest.update(chunk.data(), n);
    if (n < chunk.size()) break;
  }
  if (std::ferror(file.get()))
    throw Error(fmt::format("cannot read {}: {}; check that it is a readable file", path, std::strerror(errno)));
  return digest.hex();
}

std::string sha256_text(std::string_view text) {
  Sha256 digest;
  digest.update(text.data(), text.size());
  return digest.hex();
}

std::string_view status_name(FileStatus s) {
  switch (s) {
    case FileStatus::Present: return "present";
    case FileStatus::Missing: return "missing";
    case FileStatus::Different: return "different";
    case FileStatus::Uncatalogued: return "uncatalogued";
  }
  return "unknown";
}

namespace {

// The check of the file at `file` on disk, recorded under `key`.
FileCheck check_file_at(const std::string& key, const fs::path& file) {
  FileCheck c;
  c.path = key;
  const CatalogueEntry* entry = find_catalogued(key);
  if (entry) c.expected = entry->sha256;
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) {
    c.status = FileStatus::Missing;
    return c;
  }
  c.found = sha256_file(file.string());
  c.status = !entry ? FileStatus::Uncatalogued : c.found == c.expected ? FileStatus::Present : FileStatus::Different;
  return c;
}

fs::path under_root(const std::string& path, const std::string& scene_root) {
  return fs::path(path).is_absolute() ? fs::path(path) : fs::path(scene_root) / path;
}

}  // namespace

FileCheck check_scene_file(const std::string& relative_path, const std::string& scene_root) {
  return check_file_at(relative_path, under_root(relative_path, scene_root));
}

std::string describe_check(const FileCheck& c) {
  switch (c.status) {
    case FileStatus::Different:
      return fmt::format("different: expected {}, found {}", short_hash(c.expected), short_hash(c.found));
    case FileStatus::Uncatalogued:
      return fmt::format("uncatalogued: sha256 {}, not in {}", short_hash(c.found), kSceneCatalogue);
    default: return std::string(status_name(c.status));
  }
}

nlohmann::json scene_file_checksums(const std::vector<std::string>& scene_names, const std::string& scene_root) {
  nlohmann::json out = nlohmann::json::object();
  auto record = [&](const std::string& key, const fs::path& file) {
    if (out.contains(key)) return;
    const FileCheck c = check_file_at(key, file);
    nlohmann::json entry = {{"status", std::string(status_name(c.status))}};
    if (!c.found.empty()) entry["sha256"] = c.found;
    out[key] = std::move(entry);
  };
  for (const auto& name : scene_names) {
    std::vector<std::string> objs = scene_file_obj_files(name);  // checks the reference, as load_scene does
    // The scene file itself, with every file it extends: what it says (camera, lights, effects,
    // meshes) as one resolved table, so an edited TOML (or a base it extends) is noticed.
    if (const std::string description = scene_description(name); !description.empty())
      out[std::string(kSceneDescriptionPrefix) + name] = {{"status", "scene file"},
                                                          {"sha256", sha256_text(description)}};
    if (objs.empty() && !find_embedded_scene(name) && !name.ends_with(".toml")) {
      record(name, fs::path(name));  // a bare .obj path: the file as given
      continue;
    }
    for (const auto& f : files_with_materials(objs)) record(f, under_root(f, scene_root));
  }
  return out;
}

namespace {

const nlohmann::json* recorded_files(const nlohmann::json& meta) {
  if (!meta.is_object()) return nullptr;
  auto it = meta.find("scene_files");
  return it != meta.end() && it->is_object() ? &*it : nullptr;
}

// A recorded file's checksum, "missing" or "no checksum" (a malformed entry).
std::string recorded_hash(const nlohmann::json& entry) {
  if (entry.is_object()) {
    auto sha = entry.find("sha256");
    if (sha != entry.end() && sha->is_string()) return sha->get<std::string>();
    auto status = entry.find("status");
    if (status != entry.end() && status->is_string() && status->get<std::string>() == "missing") return "missing";
  }
  return "no checksum";
}

}  // namespace

std::vector<std::string> scene_file_differences(const nlohmann::json& meta_a, const nlohmann::json& meta_b) {
  const nlohmann::json* a = recorded_files(meta_a);
  const nlohmann::json* b = recorded_files(meta_b);
  if (!a && !b) return {};
  // One set recorded no files at all (procedural scenes only): nothing the other could differ in.
  if ((!a && b->empty()) || (!b && a->empty())) return {};
  if (!a || !b)
    return {fmt::format("result set {} records no scene file checksums (made before raysort recorded them), so "
                        "whether both ran on the same scene files cannot be told",
                        a ? "B" : "A")};
  std::set<std::string> paths;
  for (auto it = a->begin(); it != a->end(); ++it) paths.insert(it.key());
  for (auto it = b->begin(); it != b->end(); ++it) paths.insert(it.key());
  // A set made before scene files were recorded by their resolved text has no "scene:" entries;
  // then those of the other set cannot differ from anything.
  auto describes_scenes = [](const nlohmann::json& files) {
    for (auto it = files.begin(); it != files.end(); ++it)
      if (it.key().rfind(kSceneDescriptionPrefix, 0) == 0) return true;
    return false;
  };
  if (!describes_scenes(*a) || !describes_scenes(*b))
    std::erase_if(paths, [](const std::string& p) { return p.rfind(kSceneDescriptionPrefix, 0) == 0; });
  std::vector<std::string> lines;
  for (const auto& p : paths) {
    auto ia = a->find(p), ib = b->find(p);
    if (ia == a->end() || ib == b->end()) {
      const std::string h = recorded_hash(ia == a->end() ? *ib : *ia);
      lines.push_back(fmt::format("{}: recorded in {} only ({})", p, ia == a->end() ? "B" : "A",
                                  is_hex(h, 64) ? "sha256 " + short_hash(h) : h));
      continue;
    }
    const std::string ha = recorded_hash(*ia), hb = recorded_hash(*ib);
    if (ha == hb && ha != "no checksum") continue;
    auto show = [](const std::string& h) { return is_hex(h, 64) ? short_hash(h) : h; };
    lines.push_back(fmt::format("{}: sha256 {} in A, {} in B; results on these files are not comparable", p, show(ha),
                                show(hb)));
  }
  return lines;
}

}  // namespace raysort
