#pragma once
// What every scene-format fuzz target checks on a loaded file (issue 45): every vertex finite, every
// index and material id in range, every instance's mesh there; or a raysort::Error of one line.
// Anything else (a crash, a sanitizer report, another exception, a multi-line message) aborts: a finding.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>

#include "scene/mesh_formats.h"
#include "util/error.h"

namespace raysort::fuzz {

[[noreturn]] inline void finding(const char* what) {
  std::fprintf(stderr, "%s\n", what);
  std::abort();
}

inline void check_mesh(const Mesh& mesh, std::size_t materials) {
  for (const auto& p : mesh.positions)
    for (float c : p)
      if (!std::isfinite(c)) finding("non-finite vertex loaded");
  for (const auto& t : mesh.triangles)
    for (auto i : t)
      if (i >= mesh.positions.size()) finding("index out of range loaded");
  if (!mesh.material.empty() && mesh.material.size() != mesh.triangles.size()) finding("material list not per triangle");
  for (auto id : mesh.material)
    if (id < 0 || static_cast<std::size_t>(id) >= materials) finding("material id out of range");
}

inline void check_scene(const Scene& s) {
  for (const auto& m : s.meshes) check_mesh(m, s.materials.size());
  for (const auto& inst : s.instances)
    if (inst.mesh >= s.meshes.size()) finding("instance of a mesh that is not there");
}

// Runs `load`; a raysort::Error must be one line.
inline void expect_loaded_or_one_line_error(const std::function<void()>& load) {
  try {
    load();
  } catch (const Error& e) {
    if (std::string(e.what()).find('\n') != std::string::npos) {
      std::fprintf(stderr, "multi-line error: %s\n", e.what());
      std::abort();
    }
  }
}

}  // namespace raysort::fuzz
