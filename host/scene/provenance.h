#pragma once
// Where the real scene files come from and whether a user's copy is the same file: the catalogue
// scenes/sources.toml (embedded; one entry per file under the scene root, with its SHA-256, source,
// licence and conversion), and the checks `raysort scenes` lists and `raysort run` records.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace raysort {

// The catalogue's path among the embedded files. It sits beside the scene files, but it is not a
// scene: the scene lookup skips it.
inline constexpr std::string_view kSceneCatalogue = "scenes/sources.toml";
// Where a user with a missing or different file is sent.
inline constexpr std::string_view kObtainScenesHint = "README.md, \"Real scenes: how to obtain them\"";

struct SceneFileSource {
  std::string origin;   // repository ("github.com/owner/name") or archive/package
  std::string path;     // the file(s) inside it
  std::string commit;   // git commit, or
  std::string version;  // package version (exactly one of the two is set)
};

struct CatalogueEntry {
  std::string path;         // relative to the scene root: "sibenik/sibenik_75k_geom.obj"
  std::string sha256;       // 64 lowercase hex digits
  std::uint64_t bytes = 0;
  // An OBJ file: triangles > 0 and the fields below are set. A material file: material_of names
  // the OBJ that loads it, whose source, licence and conversion it shares.
  std::uint64_t triangles = 0;
  SceneFileSource source;
  std::string licence, credit, conversion;
  std::string mtl;          // the material file this OBJ loads (its own entry), or ""
  std::string material_of;
};

// Parses catalogue text; `origin` names it in messages. Throws Error "<origin>:<line>: ..." for an
// unknown or missing key, a malformed checksum, or an mtl / material_of naming no entry.
std::vector<CatalogueEntry> parse_scene_catalogue(const std::string& text, const std::string& origin);

// The embedded catalogue, parsed once.
const std::vector<CatalogueEntry>& scene_catalogue();

// The entry for `relative_path`, or nullptr when the catalogue has none.
const CatalogueEntry* find_catalogued(std::string_view relative_path);

// The files that OBJ paths (as scene files name them) bring in: each OBJ, then its material file
// when the catalogue lists one; duplicates dropped, order kept.
std::vector<std::string> files_with_materials(const std::vector<std::string>& obj_files);

// SHA-256 of a file as 64 lowercase hex digits, read in chunks (scene files run to tens of MB).
// Throws Error naming the file when it cannot be read.
std::string sha256_file(const std::string& path);

// SHA-256 of bytes in memory, as 64 lowercase hex digits.
std::string sha256_text(std::string_view text);

// The key prefix of a scene file's own entry in "scene_files" ("scene:cornell": the SHA-256 of its
// resolved text, extends included; scene_description in scene/load.h).
inline constexpr std::string_view kSceneDescriptionPrefix = "scene:";

enum class FileStatus { Present, Missing, Different, Uncatalogued };
std::string_view status_name(FileStatus s);  // "present", "missing", "different", "uncatalogued"

struct FileCheck {
  std::string path;      // relative to the scene root
  FileStatus status = FileStatus::Missing;
  std::string expected;  // the catalogue's sha256 ("" when uncatalogued)
  std::string found;     // the file's sha256 ("" when missing)
};

// Checks the file `relative_path` under `scene_root` against the catalogue.
FileCheck check_scene_file(const std::string& relative_path, const std::string& scene_root);

// One line for a check: "present", "missing", "different: expected fc498ed67bff, found 0123456789ab".
std::string describe_check(const FileCheck& check);

// For result-set metadata (meta.json "scene_files"): each scene's own file as "scene:<name>" (the
// SHA-256 of its resolved text, with what it extends; embedded scenes too), and every file that the named scenes use (embedded
// scene names: the OBJ files their scene file names plus catalogued material files; a .toml path:
// the OBJ files it names; an .obj path: that file), as
//   {"<path>": {"sha256": "<hex>", "status": "present|different|uncatalogued"}}
// keyed by the path relative to the scene root (an .obj path and absolute paths as given). A file
// that cannot be found is recorded as {"status": "missing"} with no sha256. Throws Error only for a
// scene reference that load_scene would refuse too, or a file that exists but cannot be read.
nlohmann::json scene_file_checksums(const std::vector<std::string>& scene_names, const std::string& scene_root);

// One line per file whose recorded checksum differs between two result sets' meta.json objects
// (their "scene_files"), or that only one of them records; empty when they agree. A meta without
// "scene_files" (a result set made before it was recorded) gives one line saying so, unless both
// lack it. Never throws: malformed entries are reported as lines.
std::vector<std::string> scene_file_differences(const nlohmann::json& meta_a, const nlohmann::json& meta_b);

}  // namespace raysort
