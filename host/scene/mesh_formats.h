#pragma once
// Scene files in the formats other renderers publish (issue 45): Wavefront OBJ, PLY, glTF 2.0 and
// pbrt-v4. The list of formats lives once (mesh_formats()): `--scene FILE` and a scene TOML's
// [[mesh]] file = "..." both look the file's extension up there. What a ray batch needs is read
// (triangles, transforms, diffuse colour, the camera, lights); what a file has beyond that is
// counted and reported once per file ("ignored: 3 Shape "curve", 1 Texture"), never dropped
// silently. docs/scene-format.md, "Other formats", lists what each format reads and ignores.
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "scene/scene.h"
#include "util/input_file.h"

namespace raysort {

// What a loader saw but does not use, counted by kind in the order first seen.
class IgnoredFeatures {
 public:
  void add(const std::string& what, std::size_t n = 1);
  bool empty() const { return counts_.empty(); }
  // "ignored: 3 Shape "curve", 1 Texture"; "" when nothing was ignored.
  std::string summary() const;

 private:
  std::vector<std::pair<std::string, std::size_t>> counts_;
};

// A file of another format read whole: meshes (each in its own object space), the instances that
// place them, materials, and the camera and lights when the file gives them.
struct ForeignScene {
  Scene scene;
  bool has_camera = false;  // scene.camera is the file's
  bool has_lights = false;  // scene.sphere_lights / scene.sky are the file's
  IgnoredFeatures ignored;
};

// PLY (ascii, binary_little_endian, binary_big_endian): element "vertex" (x, y, z) and element
// "face" (a list vertex_indices or vertex_index). Polygons are triangulated as OBJ faces are
// (scene/polygon.h). Errors name the file with the line (ascii) or byte offset (binary).
Mesh parse_ply(const std::string& bytes, const std::string& origin, IgnoredFeatures& ignored);
ForeignScene load_ply(const std::string& path);

// glTF 2.0 (.gltf with its buffers, .glb) through tinygltf: the default scene's node hierarchy.
// `dir` is where external buffers are read from (the file's folder).
ForeignScene parse_gltf(const std::string& bytes, const std::string& origin, const std::string& dir);
ForeignScene load_gltf(const std::string& path);

// pbrt-v4 scene files: the subset docs/scene-format.md lists (scene/pbrt_tokenizer.h reads the text).
ForeignScene parse_pbrt(const std::string& text, const std::string& origin, const std::string& dir);
ForeignScene load_pbrt(const std::string& path);

// An OBJ (scene/load.h: load_obj) as the other formats are loaded.
ForeignScene load_obj_as_foreign(const std::string& path);

// One format: the file endings it is known by (lower case), what its files are called in
// messages and how large they may be, and its loader.
struct MeshFormat {
  std::string_view name;  // "glTF 2.0"
  std::vector<std::string_view> extensions;  // {".gltf", ".glb"}
  InputKind input;
  ForeignScene (*load)(const std::string& path);
};

// Every format a scene may be loaded from, besides scene TOML.
const std::vector<MeshFormat>& mesh_formats();
// The format of `path` by its ending (case-insensitive), or nullptr.
const MeshFormat* find_mesh_format(const std::string& path);
// ".obj, .ply, .gltf, .glb, .pbrt", for messages.
std::string mesh_format_endings();

// `path` loaded as one mesh of a scene TOML: every instance flattened into world space, its
// materials appended to `materials`. Prints the ignored features once on stderr.
Mesh load_mesh_file_as_mesh(const std::string& path, std::vector<Material>& materials);

// Loads `path` in its format (find_mesh_format) and prints what it ignored, once, on stderr.
ForeignScene load_foreign_file(const std::string& path);

}  // namespace raysort
