#pragma once
// Finding and loading scenes: by name (an embedded scenes/*.toml or a file in the scene
// directory), by path to a .toml file, or by path to a bare .obj (framed by a default camera
// and lit by a sky light), so a user can try any mesh at once.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scene/scene.h"

namespace raysort {

// The size of a frame and how it is sampled: samples per pixel, next-event-estimation (shadow) rays
// per bounce and path depth. As an override (SceneOptions::frame), 0 keeps the scene's own value;
// the paper's setting (§5: "two shadow rays per bounce and eight samples per pixel") is
// {1920, 1080, 8, 2}.
struct FrameSize {
  std::uint32_t width = 0, height = 0, spp = 0;
  std::uint32_t shadow_rays = 0;  // shadow rays per bounce toward the sphere lights (Effects::shadow_rays_per_bounce)
  std::uint32_t bounces = 0;      // diffuse bounces after the primary hit (Effects::max_bounces)
};

// "1920x1080" -> {1920, 1080, 0}. Throws Error naming the text and the expected form.
FrameSize parse_resolution(const std::string& text);

// Applies the non-zero fields of `frame` to the scene's camera and effects: the one place a
// command's --resolution, --spp, --shadow-rays and --bounces take effect (load_scene calls it).
void apply_frame_size(Scene& scene, const FrameSize& frame);

struct SceneOptions {
  // Root for OBJ paths in scene files. Empty: env RAYSORT_SCENE_ROOT, else the compiled-in
  // default (../shared/scenes beside the source tree).
  std::string scene_root;
  FrameSize frame;  // overrides of the scene's resolution / sampling (0: the scene's own)
  // Triangles a scene may make (its meshes, and again after instancing). 0: as many as the host
  // memory available holds at kHostBytesPerTriangle each. A scene over it is refused with a
  // ResourceError (exit 2) before the mesh or placement that passes it is made.
  std::uint64_t max_triangles = 0;
};

// Host memory one triangle takes from load to trace (mesh, flattened copy, BVH, the device's copy):
// peak RSS of `raysort trace` grows by ≈ 380 B per triangle on heightfields of 0.5–8.4 M triangles
// (PoCL); rounded up for the wide BVH and the matrix's caches.
inline constexpr std::uint64_t kHostBytesPerTriangle = 512;

// The range of coordinates and lengths that ray tracing in float keeps finite (issue 44). Scene files
// and bare OBJs outside it are refused where they are loaded, naming the file and the range:
// - Coordinates within ±kMaxSceneCoordinate (the scene's box, the camera): the difference of two
//   points (a ray's origin to a box or a vertex) is then at most 3.5e18 and its square (distances to
//   lights, box areas for the SAH, the encoders' extents squared) at most 1.2e37, 30× below the
//   float maximum 3.4e38. A box at ±3.4e38 has an infinite extent in float (the grid encoder failed).
// - A largest extent of at least kMinSceneExtent: its square (1e-36) is still a normal float, 85×
//   above FLT_MIN, so 1/extent (the encoders quantise in the box) and directions between points
//   stay finite; a mesh at 1e-38 underflowed to 0 there and traced no hits at all.
// - The camera's view direction (look_at − position) and up between kMinCameraVector and
//   kMaxSceneCoordinate long, and not parallel (sine above 1e-6): the camera basis is normalised in
//   float (render/rays.cpp), and |up| · sine ≥ 1e-18 keeps the squared length of forward × up a
//   normal float too (a direction of 1e-38 or an up of 1e-40 made every ray NaN or one direction).
inline constexpr double kMaxSceneCoordinate = 1e18;
inline constexpr double kMinSceneExtent = 1e-18;
inline constexpr double kMinCameraVector = 1e-12;

// The scene root in effect for these options (see SceneOptions::scene_root).
std::string resolve_scene_root(const SceneOptions& opts);

// Loads `name_or_path`. Throws Error with a message naming the file, line and key for a bad
// scene file, the path for a missing OBJ (and the scene root used), and the known scene names
// for an unknown name.
Scene load_scene(const std::string& name_or_path, const SceneOptions& opts = {});

// The text of the embedded scene file of that name (scenes/<name>.toml), if there is one. Paths
// (a '/', a .toml or .obj ending) and the catalogue scenes/sources.toml are no scene names.
std::optional<std::string_view> find_embedded_scene(const std::string& name);

// The lookup part of load_scene without loading: throws the same Error for an unknown name, a
// missing file or a directory (so a command can refuse it before any work starts).
void check_scene_reference(const std::string& name_or_path);

// Parses scene TOML text; `origin` names it in error messages ("scenes/cornell.toml").
Scene parse_scene_toml(const std::string& text, const std::string& origin, const SceneOptions& opts);

// Loads an OBJ file into one mesh (all groups merged), with per-triangle material ids pointing
// into `materials` (appended from the OBJ's MTL, Kd as albedo). Polygons are triangulated.
// Refuses, with one line naming the file and the reason: a directory, a UTF-16 or binary file
// (NUL bytes), a line over 1 MiB (checked while streaming, before the file is read whole), a
// malformed or non-finite vertex, a face index out of range, a face of fewer than 3 vertices, and
// a file without faces.
Mesh load_obj(const std::string& path, std::vector<Material>& materials);

// The same on OBJ text in memory; `origin` names it in messages, .mtl files are read from `mtl_dir`.
Mesh parse_obj(const std::string& text, const std::string& origin, const std::string& mtl_dir,
               std::vector<Material>& materials);

struct SceneListing {
  std::string name;
  std::string file;         // "embedded:scenes/x.toml" or the .toml path
  std::string description;
  bool needs_scene_root;    // it names OBJ files
  std::vector<std::string> obj_files;  // the OBJ paths it names, relative to the scene root
};
// Every scene `load_scene` knows by name: the embedded scenes/*.toml.
std::vector<SceneListing> list_scenes();

// The OBJ files a scene file names (its [[mesh]] obj values, as written: relative to the scene root
// unless absolute), for an embedded scene name or a .toml path; empty for a bare .obj path (which
// is its own file). Throws Error as check_scene_reference does, or for a .toml that is not TOML.
std::vector<std::string> scene_file_obj_files(const std::string& name_or_path);

// What a scene file says, its `extends` resolved, as TOML text in a fixed layout (so its SHA-256
// changes exactly when the scene does: meta.json "scene_files"); "" for a bare .obj path.
std::string scene_description(const std::string& name_or_path);

}  // namespace raysort
