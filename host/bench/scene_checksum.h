#pragma once
// The one SHA-256 that names a scene's content, for ray batch files (render/ray_file.h): a batch
// exported from a scene may only be traced in the same scene. It is built from the checksums the
// project already records per result set (meta.json "scene_files", scene/provenance.h): the scene
// file's resolved description (camera, lights, effects, meshes, with what it extends) and every
// geometry or material file it loads, so it changes exactly when one of them does, and does not
// depend on how the scene was named (sibenik, scenes/sibenik.toml) or where the scene root is.
#include <string>

namespace raysort {

// SHA-256 (64 lowercase hex digits) over "<role> <sha256>\n" lines, one per recorded file in the
// order of meta.json's "scene_files" keys, role "scene" for the description and the file's own
// name otherwise. Throws Error naming the scene for a file that is missing (the scene could not
// load either).
std::string scene_sha256(const std::string& scene, const std::string& scene_root);

}  // namespace raysort
