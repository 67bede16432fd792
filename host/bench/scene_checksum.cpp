// The scene's SHA-256 of ray batch files (see scene_checksum.h).
#include "bench/scene_checksum.h"

#include <fmt/format.h>

#include <filesystem>

#include "scene/provenance.h"
#include "util/error.h"

namespace raysort {

std::string scene_sha256(const std::string& scene, const std::string& scene_root) {
  const nlohmann::json files = scene_file_checksums({scene}, scene_root);
  std::string lines;
  for (const auto& [key, entry] : files.items()) {
    if (!entry.contains("sha256"))
      throw Error(fmt::format("scene {}: its file {} is {}; see {}", scene, key, entry.value("status", "missing"),
                              kObtainScenesHint));
    const std::string role =
        key.starts_with(kSceneDescriptionPrefix) ? "scene" : std::filesystem::path(key).filename().string();
    lines += role + " " + entry.at("sha256").get<std::string>() + "\n";
  }
  return sha256_text(lines);
}

}  // namespace raysort
