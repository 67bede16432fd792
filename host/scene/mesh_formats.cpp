// The list of scene file formats (scene/mesh_formats.h) and what is common to them: the ignored
// features' report, and a file's scene flattened into one mesh for a scene TOML.
#include "scene/mesh_formats.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "scene/load.h"
#include "util/error.h"

namespace raysort {

void IgnoredFeatures::add(const std::string& what, std::size_t n) {
  if (n == 0) return;
  for (auto& [name, count] : counts_)
    if (name == what) {
      count += n;
      return;
    }
  counts_.emplace_back(what, n);
}

std::string IgnoredFeatures::summary() const {
  if (counts_.empty()) return "";
  std::vector<std::string> parts;
  for (const auto& [name, count] : counts_) parts.push_back(fmt::format("{} {}", count, name));
  return fmt::format("ignored: {}", fmt::join(parts, ", "));
}

ForeignScene load_obj_as_foreign(const std::string& path) {
  ForeignScene f;
  f.scene.meshes.push_back(load_obj(path, f.scene.materials));
  return f;
}

const std::vector<MeshFormat>& mesh_formats() {
  static const std::vector<MeshFormat> formats = {
      {"Wavefront OBJ", {".obj"}, kObjFile, &load_obj_as_foreign},
      {"PLY", {".ply"}, kPlyFile, &load_ply},
      {"glTF 2.0", {".gltf", ".glb"}, kGltfFile, &load_gltf},
      {"pbrt-v4", {".pbrt"}, kPbrtFile, &load_pbrt},
  };
  return formats;
}

const MeshFormat* find_mesh_format(const std::string& path) {
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  for (const MeshFormat& f : mesh_formats())
    for (std::string_view e : f.extensions)
      if (lower.size() > e.size() && lower.compare(lower.size() - e.size(), e.size(), e) == 0) return &f;
  return nullptr;
}

std::string mesh_format_endings() {
  std::vector<std::string_view> all;
  for (const MeshFormat& f : mesh_formats()) all.insert(all.end(), f.extensions.begin(), f.extensions.end());
  return fmt::format("{}", fmt::join(all, ", "));
}

ForeignScene load_foreign_file(const std::string& path) {
  const MeshFormat* format = find_mesh_format(path);
  if (!format)
    throw Error(fmt::format("{}: not a scene file raysort reads; give a file ending in {} or .toml", path,
                            mesh_format_endings()));
  ForeignScene f = format->load(path);
  if (!f.ignored.empty()) fmt::print(stderr, "raysort: note: {} file {}: {}\n", format->name, path, f.ignored.summary());
  return f;
}

Mesh load_mesh_file_as_mesh(const std::string& path, std::vector<Material>& materials) {
  ForeignScene f = load_foreign_file(path);
  const Scene& s = f.scene;
  Mesh out;
  out.name = s.meshes.size() == 1 ? s.meshes[0].name : "";
  out.source = s.meshes.size() == 1 ? s.meshes[0].source : "file:" + path;
  const auto material_base = static_cast<std::int32_t>(materials.size()) - 1;  // the file's materials[0] is the default
  materials.insert(materials.end(), s.materials.begin() + 1, s.materials.end());
  bool any_material = false;
  auto add = [&](const Mesh& m, const Affine* xf) {
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    for (const Vec3& p : m.positions) out.positions.push_back(xf ? xf->apply(p) : p);
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const auto& tri = m.triangles[t];
      out.triangles.push_back({base + tri[0], base + tri[1], base + tri[2]});
      const std::int32_t id = m.material.empty() ? 0 : m.material[t];
      any_material |= id != 0;
      out.material.push_back(id == 0 ? 0 : material_base + id);
    }
  };
  if (s.instances.empty() && s.meshes.size() == 1) {  // one mesh where it is: taken as is, ids moved
    out = std::move(f.scene.meshes[0]);
    for (auto& id : out.material) id = id == 0 ? 0 : material_base + id;
    return out;
  }
  if (s.instances.empty())
    for (const Mesh& m : s.meshes) add(m, nullptr);
  else
    for (const Instance& inst : s.instances) add(s.meshes[inst.mesh], &inst.transform);
  if (!any_material) out.material.clear();
  return out;
}

}  // namespace raysort
