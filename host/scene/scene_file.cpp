// Scene files (docs/scene-format.md): TOML → Scene, scene lookup by name or path, and bare OBJs.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>

#include "scene/ground.h"
#include "scene/load.h"
#include "scene/mesh_formats.h"
#include "scene/noise.h"
#include "scene/procedural.h"
#include "scene/provenance.h"
#include "scene/toml_reader.h"
#include "util/embedded.h"
#include "util/error.h"
#include "util/host_memory.h"
#include "util/input_file.h"
#include "util/output_name.h"

namespace fs = std::filesystem;

namespace raysort {

namespace {

constexpr std::uint32_t kDefaultWidth = 1920, kDefaultHeight = 1080;

std::string read_text_file(const std::string& path) { return read_input_file(path, kSceneFile); }

bool ends_with(const std::string& s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The obj values of a scene file's [[mesh]] tables, as written (a lenient read: the scene builder
// reports malformed tables when the scene is loaded).
std::vector<std::string> obj_values(const toml::table& root) {
  std::vector<std::string> out;
  if (auto meshes = root["mesh"].as_array())
    for (const auto& m : *meshes)
      if (auto t = m.as_table())
        for (const char* key : {"obj", "file"})
          if (auto obj = (*t)[key].value<std::string>()) out.push_back(*obj);
  return out;
}

// `extends = "sibenik"`: a scene file may start from another scene (an embedded name, or a .toml
// path relative to the extending file) and give only what differs; each top-level key it gives
// ([camera], [effects], the [[mesh]] list, description ...) replaces the base's whole. The
// geometry and lights of a scene are then written once, and a variant (a limited viewport)
// states its camera and nothing else. Chains are followed up to 8 deep.
std::vector<std::string> embedded_scene_names();

toml::table resolve_extends(toml::table root, const std::string& origin, int depth = 0) {
  const toml::node* ext = root.get("extends");
  if (!ext) return root;
  const auto name = ext->value<std::string>();
  if (!name || name->empty())
    throw Error(fmt::format("{}: 'extends' must be a scene name or a .toml path, e.g. extends = \"sibenik\"",
                            toml_location(*ext, origin)));
  if (depth >= 8)
    throw Error(fmt::format("{}: extends = \"{}\": chain of more than 8 scene files (a cycle?); extend a scene that "
                            "does not extend this one", toml_location(*ext, origin), *name));
  std::string text, base_origin;
  if (auto embedded = find_embedded_scene(*name)) {
    text = std::string(*embedded);
    base_origin = "embedded:scenes/" + *name + ".toml";
  } else if (ends_with(*name, ".toml")) {
    fs::path p(*name);
    if (p.is_relative() && origin.rfind("embedded:", 0) != 0) p = fs::path(origin).parent_path() / p;
    base_origin = p.string();
    std::error_code ec;
    if (!fs::exists(p, ec))  // anything else that is no regular file is refused by the read, by its type
      throw Error(fmt::format("{}: extends = \"{}\": scene file not found: {}", toml_location(*ext, origin), *name,
                              base_origin));
    try {
      text = read_text_file(base_origin);
    } catch (const Error& e) {
      throw Error(fmt::format("{}: extends = \"{}\": {}", toml_location(*ext, origin), *name, e.what()));
    }
  } else {
    throw Error(fmt::format("{}: extends = \"{}\": no scene of that name; name an embedded scene ({}) or a .toml path",
                            toml_location(*ext, origin), *name, fmt::join(embedded_scene_names(), ", ")));
  }
  toml::table merged = resolve_extends(parse_toml_text(text, base_origin), base_origin, depth + 1);
  // Moved, not copied: toml++ drops a node's file and line when it is copied, and every later
  // message about a key of the extending file would point at line 1.
  for (auto&& [key, value] : root)
    if (key.str() != "extends") merged.insert_or_assign(key, std::move(value));
  return merged;
}

// A scene file's text as one table, its `extends` resolved.
toml::table read_scene_table(const std::string& text, const std::string& origin) {
  return resolve_extends(parse_toml_text(text, origin), origin);
}

// The checks of a camera's basis, for a TOML [camera] and a mesh file's own camera alike: `fail(key,
// why)` reports a problem with position, look_at or up and does not return.
using CameraFail = std::function<void(const char* key, const std::string& why)>;
void check_camera(const Camera& c, const CameraFail& fail) {
  // The basis make_camera (render/rays.cpp) normalises in float must be normalisable: see load.h.
  for (const char* key : {"position", "look_at"})
    for (float x : key[0] == 'p' ? c.position : c.look_at)
      if (std::fabs(x) > kMaxSceneCoordinate)
        fail(key, fmt::format("has a coordinate {:g}, outside the ±{:g} that ray tracing in float keeps finite; "
                                "scale the scene down", x, kMaxSceneCoordinate));
  Vec3 d{c.look_at[0] - c.position[0], c.look_at[1] - c.position[1], c.look_at[2] - c.position[2]};
  const auto length = [](const Vec3& v) {
    return std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
  };
  const double len = length(d);
  if (len == 0.0) fail("look_at", "equals the camera position (in float); look at another point");
  if (len < kMinCameraVector)
    fail("look_at", fmt::format("is {:.3g} from the camera position, too close to normalise the view direction in "
                                  "float (at least {:g}); look at a point farther away",
                                  len, kMinCameraVector));
  const double ul = length(c.up);
  if (!(ul >= kMinCameraVector && ul <= kMaxSceneCoordinate))
    fail("up", fmt::format("is {:.3g} long; it must be between {:g} and {:g} long to normalise in float, e.g. up = "
                             "[0.0, 1.0, 0.0]",
                             ul, kMinCameraVector, kMaxSceneCoordinate));
  const double cross[3] = {double(d[1]) * c.up[2] - double(d[2]) * c.up[1],
                           double(d[2]) * c.up[0] - double(d[0]) * c.up[2],
                           double(d[0]) * c.up[1] - double(d[1]) * c.up[0]};
  const double cl = std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
  if (cl <= 1e-6 * len * ul) fail("up", "is parallel to the view direction (look_at − position); use another up vector");
}

Camera read_camera(const TomlTable& t) {
  Camera c;
  c.position = t.vec3("position");
  c.look_at = t.vec3("look_at");
  c.up = t.vec3("up", {0, 1, 0});
  c.fov_y_deg = static_cast<float>(t.number("fov_y", 45.0));
  if (!(c.fov_y_deg > 0.0f && c.fov_y_deg < 180.0f))
    t.fail("fov_y", fmt::format("= {} is not a field of view; use degrees in (0, 180)", c.fov_y_deg));
  c.width = kDefaultWidth;
  c.height = kDefaultHeight;
  if (t.has("resolution")) {
    auto r = t.numbers("resolution", 2);
    if (r.size() != 2 || r[0] < 1 || r[1] < 1 || r[0] > 65536 || r[1] > 65536 || r[0] != std::floor(r[0]) ||
        r[1] != std::floor(r[1]))
      t.fail("resolution", "must be [width, height] with whole numbers in [1, 65536], e.g. [1920, 1080]");
    c.width = static_cast<std::uint32_t>(r[0]);
    c.height = static_cast<std::uint32_t>(r[1]);
  }
  check_camera(c, [&](const char* key, const std::string& why) { t.fail(key, why); });
  return c;
}

Vec3 read_color(const TomlTable& t, std::string_view key, Vec3 fallback) {
  Vec3 c = t.vec3(key, fallback);
  for (float v : c)
    if (v < 0.0f) t.fail(key, "must not be negative");
  return c;
}

// Builds an affine transform from translate / rotate / scale keys: T · R · S.
Affine read_transform(const TomlTable& t) {
  Vec3 tr = t.vec3("translate", {0, 0, 0});
  Vec3 rot = t.vec3("rotate", {0, 0, 0});
  Vec3 s{1, 1, 1};
  if (t.has("scale")) {
    auto v = t.node("scale")->is_number() ? std::vector<double>(3, t.number("scale")) : t.numbers("scale", 3);
    for (int i = 0; i < 3; ++i) s[i] = static_cast<float>(v[i]);
    for (float x : s)
      if (!(x > 0.0f)) t.fail("scale", "must be positive (a mirror or a flat instance is not supported)");
  }
  return Affine::translation(tr).then_after(Affine::rotation_deg(rot)).then_after(Affine::scaling(s));
}

class SceneBuilder {
 public:
  SceneBuilder(const std::string& origin, const SceneOptions& opts) : origin_(origin), opts_(opts) {}

  Scene build(const toml::table& root) {
    TomlTable top(origin_, root, "",
                  {"name", "description", "camera", "material", "mesh", "instance", "scatter", "sphere_light", "sky",
                   "effects"});
    Scene s;
    s.file = origin_;
    // The name becomes the base of output files (render's <name>.png, trace's <name>.json): a name
    // that is no plain file name is refused here, with its line, rather than silently renamed.
    const std::string stem = safe_file_name(fs::path(origin_).stem().string());
    s.name = top.string("name", stem);
    if (const std::string problem = file_name_problem(s.name); !problem.empty())
      top.fail("name", fmt::format("{}; give a plain name such as \"{}\"", problem, safe_file_name(s.name, stem)));
    s.description = top.string("description", "");

    // Named materials first, so meshes can refer to them.
    auto materials = top.table_array("material");
    for (std::size_t i = 0; i < materials.size(); ++i) {
      TomlTable t(origin_, *materials[i], fmt::format("material[{}]", i), {"name", "albedo", "mirror"});
      Material m;
      m.name = t.string("name");
      if (m.name.empty()) t.fail("name", "must not be empty");
      if (material_names_.count(m.name))
        t.fail("name", fmt::format("'{}' is already the name of another material; material names must be unique", m.name));
      m.albedo = read_color(t, "albedo", m.albedo);
      for (float a : m.albedo)
        if (a > 1.0f) t.fail("albedo", "must not exceed 1 (a surface cannot reflect more light than it receives)");
      m.mirror = t.boolean("mirror", false);
      material_names_[m.name] = static_cast<std::int32_t>(s.materials.size());
      s.materials.push_back(m);
    }

    auto meshes = top.table_array("mesh");
    if (meshes.empty())
      throw Error(fmt::format("{}:1: the scene has no [[mesh]]; add at least one (docs/scene-format.md)", origin_));
    std::vector<bool> drawn;
    for (std::size_t i = 0; i < meshes.size(); ++i) drawn.push_back(read_mesh(s, *meshes[i], i));

    // Placements: drawn meshes once, then [[instance]], then [[scatter]].
    bool plain = std::all_of(drawn.begin(), drawn.end(), [](bool d) { return d; });
    for (std::size_t i = 0; i < drawn.size(); ++i)
      if (drawn[i]) s.instances.push_back({static_cast<std::uint32_t>(i), Affine{}});
    auto instances = top.table_array("instance");
    for (std::size_t i = 0; i < instances.size(); ++i) {
      TomlTable t(origin_, *instances[i], fmt::format("instance[{}]", i), {"mesh", "translate", "rotate", "scale"});
      s.instances.push_back({mesh_index(t, "mesh"), read_transform(t)});
    }
    check_triangles(placed_triangles(s), origin_ + ":1", "its placed meshes", "place fewer instances or lighter meshes");
    check_finite_placements(s, 0, "a drawn mesh or an [[instance]]");
    std::size_t placed_before_scatter = s.instances.size();
    auto scatters = top.table_array("scatter");
    for (std::size_t i = 0; i < scatters.size(); ++i) read_scatter(s, *scatters[i], i, placed_before_scatter);
    check_finite_placements(s, placed_before_scatter, "a [[scatter]]");
    if (s.instances.empty())
      throw Error(fmt::format("{}:1: the scene draws nothing: every mesh has draw = false and there is no [[instance]] "
                              "or [[scatter]]; place a mesh",
                              origin_));
    if (plain && instances.empty() && scatters.empty()) s.instances.clear();  // every mesh once, untransformed

    if (auto cam = top.subtable("camera"))
      s.camera = read_camera(TomlTable(origin_, *cam, "camera", {"position", "look_at", "up", "fov_y", "resolution"}));
    else
      throw Error(fmt::format("{}:1: the scene has no [camera]; add one with position and look_at", origin_));

    auto lights = top.table_array("sphere_light");
    for (std::size_t i = 0; i < lights.size(); ++i) {
      TomlTable t(origin_, *lights[i], fmt::format("sphere_light[{}]", i), {"center", "radius", "color", "power"});
      SphereLight l;
      l.center = t.vec3("center");
      l.radius_relative = static_cast<float>(t.number("radius"));
      if (!(l.radius_relative > 0.0f))
        t.fail("radius", fmt::format("= {} must be positive (a fraction of the scene's largest extent, e.g. 0.05)",
                                     l.radius_relative));
      l.color = read_color(t, "color", {1, 1, 1});
      l.power = static_cast<float>(t.number("power", 1.0));
      if (!(l.power > 0.0f)) t.fail("power", "must be positive");
      s.sphere_lights.push_back(l);
    }

    if (auto sky = top.subtable("sky")) {
      TomlTable t(origin_, *sky, "sky", {"color", "zenith", "horizon"});
      s.sky.enabled = true;
      if (t.has("color")) {
        if (t.has("zenith") || t.has("horizon"))
          t.fail("color", "conflicts with zenith/horizon; give either color or both zenith and horizon");
        s.sky.zenith = s.sky.horizon = read_color(t, "color", {1, 1, 1});
      } else if (t.has("zenith") || t.has("horizon")) {
        if (!t.has("zenith") || !t.has("horizon"))
          t.fail_table("needs both zenith and horizon for a gradient sky (or one color)");
        s.sky.zenith = read_color(t, "zenith", {1, 1, 1});
        s.sky.horizon = read_color(t, "horizon", {1, 1, 1});
      }
    }

    if (auto fx = top.subtable("effects")) {
      TomlTable t(origin_, *fx, "effects",
                  {"max_bounces", "shadow_rays_per_bounce", "russian_roulette_start", "russian_roulette_survival",
                   "samples_per_pixel"});
      auto& e = s.effects;
      e.max_bounces = static_cast<std::uint32_t>(t.integer("max_bounces", e.max_bounces, 0, 64));
      e.shadow_rays_per_bounce =
          static_cast<std::uint32_t>(t.integer("shadow_rays_per_bounce", e.shadow_rays_per_bounce, 0, 64));
      e.russian_roulette_start =
          static_cast<std::uint32_t>(t.integer("russian_roulette_start", e.russian_roulette_start, 0, 1024));
      e.russian_roulette_survival = static_cast<float>(t.number("russian_roulette_survival", e.russian_roulette_survival));
      if (!(e.russian_roulette_survival > 0.0f && e.russian_roulette_survival <= 1.0f))
        t.fail("russian_roulette_survival", "must be in (0, 1]");
      e.samples_per_pixel = static_cast<std::uint32_t>(t.integer("samples_per_pixel", e.samples_per_pixel, 1, 1 << 16));
    }

    return s;
  }

 private:
  // Reads one [[mesh]]; returns its `draw` flag.
  bool read_mesh(Scene& s, const toml::table& table, std::size_t index) {
    TomlTable t(origin_, table, fmt::format("mesh[{}]", index),
                {"name", "obj", "file", "generator", "seed", "params", "albedo", "material", "draw"});
    std::string name = t.string("name");
    if (name.empty()) t.fail("name", "must not be empty");
    if (mesh_names_.count(name))
      t.fail("name", fmt::format("'{}' is already the name of another mesh; mesh names must be unique", name));
    // `file` names a mesh file of any format (scene/mesh_formats.h); `obj`, the older key, does too.
    if (t.has("obj") && t.has("file")) t.fail("file", "and 'obj' both name a file; give one");
    const char* file_key = t.has("file") ? "file" : "obj";
    bool has_obj = t.has(file_key), has_gen = t.has("generator");
    if (has_obj == has_gen)
      t.fail_table(fmt::format("mesh '{}' needs exactly one of 'obj' (a file) or 'generator' (one of: {})", name,
                               fmt::join(generator_names(), ", ")));
    Mesh mesh;
    if (has_obj) {
      if (t.has("params")) t.fail("params", "applies to generated meshes only, not to an obj mesh");
      if (t.has("seed")) t.fail("seed", "applies to generated meshes only, not to an obj mesh");
      std::string rel = t.string(file_key);
      std::string root = resolve_scene_root(opts_);
      fs::path p = fs::path(rel).is_absolute() ? fs::path(rel) : fs::path(root) / rel;
      const MeshFormat* format = find_mesh_format(rel);
      const std::string what = std::string(format && format->name == "Wavefront OBJ" ? "an " : "a ") +
                               std::string(format ? format->input.what : "mesh file");
      std::error_code ec;
      if (fs::is_directory(p, ec))
        t.fail(file_key, fmt::format("names a directory, not {}: {}", what, p.lexically_normal().string()));
      if (!format)
        t.fail(file_key, fmt::format("names {}, which is no mesh file raysort reads; give a file ending in {}", rel,
                                     mesh_format_endings()));
      if (!fs::exists(p, ec))  // a FIFO or device is refused by the loader, naming its type
        t.fail(file_key, fmt::format("names {} that does not exist: {} (scene root: {}); pass --scene-root DIR "
                                     "or set RAYSORT_SCENE_ROOT to the folder that holds '{}'",
                                     what, p.lexically_normal().string(), root, rel));
      try {
        mesh = load_mesh_file_as_mesh(p.lexically_normal().string(), s.materials);
      } catch (const Error& e) {
        throw Error(fmt::format("{}: mesh '{}': {}", t.location(file_key), name, e.what()));
      }
    } else {
      std::string gen = t.string("generator");
      std::uint64_t seed = t.integer("seed", 0, 0, ~std::uint64_t{0} >> 1);
      GeneratorParams params;
      if (auto pt = t.subtable("params")) {
        for (auto&& [k, v] : *pt) {
          std::string key(k.str());
          const std::string at = toml_location(v, origin_);
          if (v.is_number()) {
            params.numbers[key] = toml_number(v);
          } else if (auto arr = v.as_array(); arr && arr->size() == 3 &&
                                              std::all_of(arr->begin(), arr->end(),
                                                          [](const toml::node& e) { return e.is_number(); })) {
            Vec3 vec{};
            for (std::size_t i = 0; i < 3; ++i) {
              const auto& e = (*arr)[i];
              const double x = toml_number(e);
              if (!fits_scene_float(x))
                throw Error(fmt::format("{}: '{}.params.{}' = {:g} is not a finite number within the float range "
                                        "scenes are stored in (|x| <= 3.4e38)",
                                        at, t.path(), key, x));
              vec[i] = static_cast<float>(x);
            }
            params.vectors[key] = vec;
          } else {
            throw Error(fmt::format("{}: '{}.params.{}' must be a number or an array of 3 numbers, not {}", at,
                                    t.path(), key, toml_type_name(v)));
          }
        }
      }
      std::uint64_t triangles = 0;
      try {
        triangles = generated_triangle_count(gen, params);
      } catch (const Error& e) {
        std::string_view key = gen_known(gen) ? "params" : "generator";
        t.fail(key, fmt::format("(mesh '{}'): {}", name, e.what()));
      }
      check_triangles(saturating_add(mesh_triangles(s), triangles), t.location("generator"),
                      fmt::format("mesh '{}' ({}, {} triangles)", name, gen, triangles),
                      "lower its params (resolution, segments, subdivisions, sides)");
      try {
        mesh = generate_mesh(gen, params, seed);
      } catch (const Error& e) {
        std::string_view key = gen_known(gen) ? "params" : "generator";
        t.fail(key, fmt::format("(mesh '{}'): {}", name, e.what()));
      }
    }
    mesh.name = name;
    if (t.has("albedo") && t.has("material"))
      t.fail("material", "conflicts with 'albedo'; give the albedo in the [[material]] or drop the material");
    if (t.has("albedo")) {
      Material m;
      m.name = name;
      m.albedo = read_color(t, "albedo", {0.7f, 0.7f, 0.7f});
      for (float a : m.albedo)
        if (a > 1.0f) t.fail("albedo", "must not exceed 1 (a surface cannot reflect more light than it receives)");
      s.materials.push_back(m);
      mesh.material.assign(mesh.triangles.size(), static_cast<std::int32_t>(s.materials.size() - 1));
    } else if (t.has("material")) {
      std::string mat = t.string("material");
      auto it = material_names_.find(mat);
      if (it == material_names_.end()) {
        std::vector<std::string> names;
        for (auto& [n, i] : material_names_) names.push_back(n);
        t.fail("material", names.empty()
                               ? fmt::format("names an unknown material '{}'; the scene declares no [[material]]", mat)
                               : fmt::format("names an unknown material '{}'; the scene's materials are: {}", mat,
                                             fmt::join(names, ", ")));
      }
      mesh.material.assign(mesh.triangles.size(), it->second);
    }
    mesh_names_[name] = static_cast<std::uint32_t>(s.meshes.size());
    s.meshes.push_back(std::move(mesh));
    return t.boolean("draw", true);
  }

  static bool gen_known(const std::string& gen) {
    auto names = generator_names();
    return std::find(names.begin(), names.end(), gen) != names.end();
  }

  std::uint32_t mesh_index(const TomlTable& t, std::string_view key) const {
    std::string name = t.string(key);
    auto it = mesh_names_.find(name);
    if (it == mesh_names_.end()) {
      std::vector<std::string> names;
      for (auto& [n, i] : mesh_names_) names.push_back(n);
      t.fail(key, fmt::format("names an unknown mesh '{}'; the scene's meshes are: {}", name, fmt::join(names, ", ")));
    }
    return it->second;
  }

  void read_scatter(Scene& s, const toml::table& table, std::size_t index, std::size_t placed) {
    TomlTable t(origin_, table, fmt::format("scatter[{}]", index),
                {"mesh", "count", "seed", "min", "max", "ground", "y_offset", "scale", "rotate", "random_rotation_y"});
    std::uint32_t mesh = mesh_index(t, "mesh");
    auto count = t.integer("count", 0, 0, 10'000'000);
    if (!t.has("count")) t.fail_table("is missing the required key 'count'; add it, e.g. count = 100");
    std::uint64_t seed = t.integer("seed", 0, 0, ~std::uint64_t{0} >> 1);
    Vec3 lo = t.vec3("min"), hi = t.vec3("max");
    for (int a = 0; a < 3; ++a)
      if (lo[a] > hi[a]) t.fail("max", "must not be below min on any axis");
    double scale_lo = 1.0, scale_hi = 1.0;
    if (t.has("scale")) {
      auto v = t.node("scale")->is_number() ? std::vector<double>(2, t.number("scale")) : t.numbers("scale", 2);
      scale_lo = v[0];
      scale_hi = v[1];
      if (!(scale_lo > 0.0) || scale_hi < scale_lo) t.fail("scale", "must be a positive number or [low, high] with 0 < low <= high");
    }
    Vec3 rotate = t.vec3("rotate", {0, 0, 0});
    bool spin = t.boolean("random_rotation_y", true);
    double y_offset = t.number("y_offset", 0.0);
    std::optional<GroundGrid> ground;
    std::string ground_name;
    if (t.has("ground")) {
      std::uint32_t g = mesh_index(t, "ground");
      ground_name = t.string("ground");
      std::vector<Affine> xfs;
      for (std::size_t i = 0; i < placed; ++i)
        if (s.instances[i].mesh == g) xfs.push_back(s.instances[i].transform);
      if (xfs.empty())
        t.fail("ground", fmt::format("names mesh '{}', which is not placed (draw = false and no [[instance]] of it)",
                                     ground_name));
      ground.emplace(s.meshes[g], xfs);
    }
    check_triangles(saturating_add(placed_triangles(s), saturating_mul(count, s.meshes[mesh].triangles.size())),
                    t.location("count"), fmt::format("scatter[{}] ({} × mesh '{}')", index, count, s.meshes[mesh].name),
                    "lower its count or scatter a mesh with fewer triangles");
    SceneRng rng(seed ^ 0x5CA77E5ull);
    Affine base = Affine::rotation_deg(rotate);
    for (std::uint64_t i = 0; i < count; ++i) {
      double x = rng.uniform(lo[0], hi[0]);
      double y = rng.uniform(lo[1], hi[1]);
      double z = rng.uniform(lo[2], hi[2]);
      double scale = rng.uniform(scale_lo, scale_hi);
      double angle = rng.uniform(0.0, 360.0);
      if (ground) {
        auto h = ground->height(x, z, lo[1], hi[1]);
        if (!h)
          t.fail("ground", fmt::format("has no surface of mesh '{}' at x = {:.3f}, z = {:.3f} between y = {} and {}; "
                                       "make min/max lie over the ground and span its heights",
                                       ground_name, x, z, lo[1], hi[1]));
        y = *h;
      }
      y += y_offset;
      auto f = [](double v) { return static_cast<float>(v); };
      Affine xf = Affine::translation({f(x), f(y), f(z)})
                      .then_after(Affine::rotation_deg({0.0f, spin ? f(angle) : 0.0f, 0.0f}))
                      .then_after(base)
                      .then_after(Affine::scaling({f(scale), f(scale), f(scale)}));
      s.instances.push_back({mesh, xf});
    }
  }

  // Triangles of the meshes made so far, and of the placements so far (instances flattened).
  static std::uint64_t mesh_triangles(const Scene& s) {
    std::uint64_t n = 0;
    for (const Mesh& m : s.meshes) n = saturating_add(n, m.triangles.size());
    return n;
  }
  static std::uint64_t placed_triangles(const Scene& s) {
    std::uint64_t n = 0;
    for (const Instance& i : s.instances) n = saturating_add(n, s.meshes[i.mesh].triangles.size());
    return n;
  }

  // Refuses placements whose world-space box leaves the float range (a huge scale or translation:
  // inf vertices, and NaN where a transform multiplies inf by 0), before anything uses them (the
  // scatter's ground grid, the BVH). The box's corners bound every vertex under an affine map.
  void check_finite_placements(const Scene& s, std::size_t first, const char* kind) const {
    std::vector<std::optional<Aabb>> bounds(s.meshes.size());  // each placed mesh's own box, once
    for (std::size_t i = first; i < s.instances.size(); ++i) {
      const Instance& inst = s.instances[i];
      auto& b = bounds[inst.mesh];
      if (!b) {
        b.emplace();
        for (const Vec3& p : s.meshes[inst.mesh].positions) b->grow(p);
      }
      if (b->empty()) continue;
      for (int corner = 0; corner < 8; ++corner) {
        const Vec3 p = inst.transform.apply({(corner & 1 ? b->max : b->min)[0], (corner & 2 ? b->max : b->min)[1],
                                             (corner & 4 ? b->max : b->min)[2]});
        if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
          throw Error(fmt::format("{}:1: a placement of mesh '{}' ({}) reaches coordinates beyond the float range "
                                  "scenes are stored in (a scale or translate too large for its mesh's size); make "
                                  "it smaller",
                                  origin_, s.meshes[inst.mesh].name, kind));
      }
    }
  }

  // Refuses (ResourceError, exit 2) a scene whose triangles would pass SceneOptions::max_triangles,
  // or else the host memory available at kHostBytesPerTriangle each, before they are made.
  void check_triangles(std::uint64_t triangles, const std::string& at, const std::string& what,
                       const std::string& fix) const {
    const std::uint64_t bytes = saturating_mul(triangles, kHostBytesPerTriangle);
    std::string limit;
    if (opts_.max_triangles != 0) {
      if (triangles <= opts_.max_triangles) return;
      limit = fmt::format("the limit of {} triangles set for this load", opts_.max_triangles);
    } else {
      if (!available_) available_ = available_host_memory();  // /proc/meminfo once per load, not per mesh
      const std::uint64_t available = *available_;
      if (bytes <= available) return;
      limit = fmt::format("the {} of host memory available", format_bytes(available));
    }
    throw ResourceError(fmt::format("{}: the scene would hold {} triangles with {}, about {} of host memory at {} B "
                                    "each from load to trace, over {}; {}",
                                    at, triangles, what, format_bytes(bytes), kHostBytesPerTriangle, limit,
                                    fix));
  }

  std::string origin_;
  const SceneOptions& opts_;
  mutable std::optional<std::uint64_t> available_;  // host memory, read at the first check
  std::map<std::string, std::uint32_t> mesh_names_;
  std::map<std::string, std::int32_t> material_names_;  // [[material]] name -> index in Scene::materials
};

std::vector<std::string> embedded_scene_names() {
  std::vector<std::string> names;
  for (const auto& f : embedded_files()) {
    std::string p(f.path);
    // scenes/sources.toml, the catalogue of scene files (scene/provenance.h), is no scene.
    if (p.rfind("scenes/", 0) == 0 && ends_with(p, ".toml") && p != kSceneCatalogue)
      names.push_back(fs::path(p).stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// Refuses a scene whose bounding box lies outside what ray tracing in float keeps finite (load.h:
// coordinates within ±1e18, a largest extent of at least 1e-18). The box is the placed meshes' own
// boxes carried through their transforms (corners), so no vertex of a large scatter is walked twice.
void check_scene_extent(const Scene& s, const std::string& origin) {
  std::vector<Aabb> own(s.meshes.size());
  for (std::size_t m = 0; m < s.meshes.size(); ++m)
    for (const auto& tri : s.meshes[m].triangles)
      for (auto idx : tri) own[m].grow(s.meshes[m].positions[idx]);
  Aabb box;
  if (s.instances.empty()) {
    for (const Aabb& b : own) box.grow(b);
  } else {
    for (const Instance& inst : s.instances) {
      const Aabb& b = own[inst.mesh];
      if (b.empty()) continue;
      for (int corner = 0; corner < 8; ++corner)
        box.grow(inst.transform.apply({(corner & 1 ? b.max : b.min)[0], (corner & 2 ? b.max : b.min)[1],
                                       (corner & 4 ? b.max : b.min)[2]}));
    }
  }
  if (box.empty()) return;  // no triangles: refused elsewhere
  double largest = 0.0, farthest = 0.0;
  for (int a = 0; a < 3; ++a) {
    largest = std::max(largest, double(box.max[a]) - double(box.min[a]));
    farthest = std::max({farthest, std::fabs(double(box.min[a])), std::fabs(double(box.max[a]))});
  }
  const std::string where = fmt::format("{}: the scene's bounding box [{:g}, {:g}, {:g}] – [{:g}, {:g}, {:g}]", origin,
                                        box.min[0], box.min[1], box.min[2], box.max[0], box.max[1], box.max[2]);
  if (farthest > kMaxSceneCoordinate)
    throw Error(fmt::format("{} reaches {:g}, outside the ±{:g} that ray tracing in float keeps finite; scale or move "
                            "the geometry (docs/scene-format.md, \"Float range\")",
                            where, farthest, kMaxSceneCoordinate));
  if (largest < kMinSceneExtent)
    throw Error(fmt::format("{} is {:g} across, below the {:g} that ray tracing in float resolves; scale the geometry "
                            "up (docs/scene-format.md, \"Float range\")",
                            where, largest, kMinSceneExtent));
}

// A bare mesh file (OBJ, PLY, glTF, pbrt-v4): its meshes, its camera or one looking at its bounding
// box from a 3/4 view, and its lights or a sky light.
Scene load_bare_file(const std::string& path) {
  ForeignScene f = load_foreign_file(path);
  Scene s = std::move(f.scene);
  s.name = safe_file_name(fs::path(path).stem().string());  // the base of output files: a plain name
  const std::string_view format = find_mesh_format(path)->name;
  s.description = fmt::format("bare {} {}", format == "Wavefront OBJ" ? "OBJ" : format, path);
  s.file = path;
  check_scene_extent(s, path);
  if (!f.has_lights) {
    s.sky.enabled = true;
    s.sky.zenith = {0.6f, 0.7f, 0.9f};
    s.sky.horizon = {0.9f, 0.9f, 0.9f};
  }
  s.effects.max_bounces = 1;
  if (f.has_camera) {
    if (!(s.camera.fov_y_deg > 0.0f && s.camera.fov_y_deg < 180.0f))
      throw Error(fmt::format("{}: the file's camera has a field of view of {} degrees; fix the camera in the file "
                              "(a vertical field of view in (0, 180))", path, s.camera.fov_y_deg));
    check_camera(s.camera, [&](const char* key, const std::string& why) {
      throw Error(fmt::format("{}: the file's camera (its {}) {}; fix the camera in the file", path, key, why));
    });
    return s;
  }
  Aabb b = s.bounds();
  Vec3 c = b.center(), e = b.extent();
  double radius = 0.5 * std::sqrt(double(e[0]) * e[0] + double(e[1]) * e[1] + double(e[2]) * e[2]);
  if (radius <= 0.0) radius = 1.0;
  s.camera.fov_y_deg = 45.0f;
  double dist = radius / std::sin(0.5 * 45.0 * 3.14159265358979323846 / 180.0) * 1.05;
  double dir[3] = {0.62, 0.45, 0.64};  // from front-right, above
  double dl = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  for (int a = 0; a < 3; ++a) s.camera.position[a] = static_cast<float>(c[a] + dir[a] / dl * dist);
  s.camera.look_at = c;
  s.camera.up = {0, 1, 0};
  s.camera.width = kDefaultWidth;
  s.camera.height = kDefaultHeight;
  return s;
}

}  // namespace

std::string resolve_scene_root(const SceneOptions& opts) {
  if (!opts.scene_root.empty()) return opts.scene_root;
  if (const char* env = std::getenv("RAYSORT_SCENE_ROOT"); env && *env) return env;
  return fs::path(RAYSORT_DEFAULT_SCENE_ROOT).lexically_normal().string();
}

FrameSize parse_resolution(const std::string& text) {
  unsigned a = 0, b = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%u%c%u%c", &a, &x, &b, &extra) != 3 || (x != 'x' && x != 'X') || a == 0 || b == 0)
    throw Error(fmt::format("resolution '{}': expected WIDTHxHEIGHT with both at least 1, e.g. 1920x1080", text));
  return {a, b, 0};
}

void apply_frame_size(Scene& scene, const FrameSize& frame) {
  if (frame.width) scene.camera.width = frame.width;
  if (frame.height) scene.camera.height = frame.height;
  if (frame.spp) scene.effects.samples_per_pixel = frame.spp;
  if (frame.shadow_rays) scene.effects.shadow_rays_per_bounce = frame.shadow_rays;
  if (frame.bounces) scene.effects.max_bounces = frame.bounces;
}

Scene parse_scene_toml(const std::string& text, const std::string& origin, const SceneOptions& opts) {
  toml::table root = read_scene_table(text, origin);
  Scene s = SceneBuilder(origin, opts).build(root);
  check_scene_extent(s, origin);
  apply_frame_size(s, opts.frame);
  return s;
}

std::optional<std::string_view> find_embedded_scene(const std::string& name) {
  if (name.find('/') != std::string::npos || ends_with(name, ".toml") || find_mesh_format(name)) return std::nullopt;
  const std::string path = "scenes/" + name + ".toml";
  if (path == kSceneCatalogue) return std::nullopt;
  return find_embedded(path);
}

void check_scene_reference(const std::string& name_or_path) {
  if (find_embedded_scene(name_or_path)) return;
  std::error_code ec;
  if (fs::is_directory(name_or_path, ec))
    throw Error(fmt::format("scene '{}' is a directory; give a scene name, or the path of a .toml or .obj file",
                            name_or_path));
  // A FIFO, a device or a socket exists but is no scene: it is named as such (a FIFO was "not found"
  // before, and would have blocked the read).
  const bool exists = fs::exists(name_or_path, ec);
  if (ends_with(name_or_path, ".toml")) {
    if (!exists) throw Error(fmt::format("scene file not found: {}", name_or_path));
    check_input_file(name_or_path, kSceneFile);
    return;
  }
  if (const MeshFormat* format = find_mesh_format(name_or_path)) {
    if (!exists) throw Error(fmt::format("{} not found: {}", format->input.what, name_or_path));
    check_input_file(name_or_path, format->input);
    return;
  }
  throw Error(fmt::format("unknown scene '{}'; the known scenes are: {} (or give a path to a .toml file or to a mesh file: {})",
                          name_or_path, fmt::join(embedded_scene_names(), ", "), mesh_format_endings()));
}

Scene load_scene(const std::string& name_or_path, const SceneOptions& opts) {
  check_scene_reference(name_or_path);
  if (auto text = find_embedded_scene(name_or_path))
    return parse_scene_toml(std::string(*text), "embedded:scenes/" + name_or_path + ".toml", opts);
  if (ends_with(name_or_path, ".toml")) return parse_scene_toml(read_text_file(name_or_path), name_or_path, opts);
  Scene s = load_bare_file(name_or_path);
  apply_frame_size(s, opts.frame);
  return s;
}

std::vector<SceneListing> list_scenes() {
  std::vector<SceneListing> out;
  for (const auto& name : embedded_scene_names()) {
    std::string path = "scenes/" + name + ".toml";
    SceneListing l;
    l.name = name;
    l.file = "embedded:" + path;
    l.needs_scene_root = false;
    auto text = find_embedded(path);
    toml::table root = read_scene_table(std::string(*text), l.file);
    if (auto d = root["description"].value<std::string>()) l.description = *d;
    l.obj_files = obj_values(root);
    l.needs_scene_root = !l.obj_files.empty();
    out.push_back(std::move(l));
  }
  return out;
}

std::vector<std::string> scene_file_obj_files(const std::string& name_or_path) {
  check_scene_reference(name_or_path);
  if (auto text = find_embedded_scene(name_or_path))
    return obj_values(read_scene_table(std::string(*text), "embedded:scenes/" + name_or_path + ".toml"));
  if (ends_with(name_or_path, ".toml")) return obj_values(read_scene_table(read_text_file(name_or_path), name_or_path));
  return {};
}

std::string scene_description(const std::string& name_or_path) {
  check_scene_reference(name_or_path);
  toml::table t;
  if (auto text = find_embedded_scene(name_or_path))
    t = read_scene_table(std::string(*text), "embedded:scenes/" + name_or_path + ".toml");
  else if (ends_with(name_or_path, ".toml"))
    t = read_scene_table(read_text_file(name_or_path), name_or_path);
  else
    return "";
  std::ostringstream out;
  out << toml::toml_formatter(t);
  return out.str();
}

}  // namespace raysort
