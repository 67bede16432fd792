#include "scene/scene.h"

#include <cmath>

namespace raysort {

Affine Affine::then_after(const Affine& o) const {
  // Compose two affine maps: (this ∘ o)(p) = this(o(p)).
  Affine r;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 4; ++col) {
      float s = 0.0f;
      for (int k = 0; k < 3; ++k) s += m[row * 4 + k] * o.m[k * 4 + col];
      if (col == 3) s += m[row * 4 + 3];
      r.m[row * 4 + col] = s;
    }
  }
  return r;
}

Affine Affine::translation(const Vec3& t) {
  Affine a;
  a.m[3] = t[0];
  a.m[7] = t[1];
  a.m[11] = t[2];
  return a;
}

Affine Affine::scaling(const Vec3& s) {
  Affine a;
  a.m[0] = s[0];
  a.m[5] = s[1];
  a.m[10] = s[2];
  return a;
}

Affine Affine::rotation_deg(const Vec3& angles) {
  // Host-side setup only (scene transforms), so libm's sin/cos are fine here: every device
  // receives the same flattened float triangles.
  auto rot = [](int axis, float deg) {
    double r = deg * 3.14159265358979323846 / 180.0;
    float c = static_cast<float>(std::cos(r)), s = static_cast<float>(std::sin(r));
    Affine a;
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    a.m[i * 4 + i] = c;
    a.m[i * 4 + j] = -s;
    a.m[j * 4 + i] = s;
    a.m[j * 4 + j] = c;
    return a;
  };
  return rot(2, angles[2]).then_after(rot(1, angles[1])).then_after(rot(0, angles[0]));
}

Scene::Flat Scene::flatten() const {
  Flat f;
  std::size_t n = triangle_count();
  f.v0.reserve(n);
  f.v1.reserve(n);
  f.v2.reserve(n);
  f.material.reserve(n);
  auto add_mesh = [&](const Mesh& mesh, const Affine* xf) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]], c = mesh.positions[tri[2]];
      if (xf) {
        a = xf->apply(a);
        b = xf->apply(b);
        c = xf->apply(c);
      }
      f.v0.push_back(a);
      f.v1.push_back(b);
      f.v2.push_back(c);
      f.material.push_back(mesh.material.empty() ? 0 : mesh.material[t]);
    }
  };
  if (instances.empty()) {
    for (const auto& m : meshes) add_mesh(m, nullptr);
  } else {
    for (const auto& inst : instances) add_mesh(meshes[inst.mesh], &inst.transform);
  }
  return f;
}

Aabb Scene::bounds() const {
  Aabb b;
  auto add_mesh = [&](const Mesh& mesh, const Affine* xf) {
    // Referenced vertices only: an OBJ's unused vertices must not stretch the scene box
    // (the encoders quantize in it).
    for (const auto& tri : mesh.triangles)
      for (auto idx : tri) b.grow(xf ? xf->apply(mesh.positions[idx]) : mesh.positions[idx]);
  };
  if (instances.empty()) {
    for (const auto& m : meshes) add_mesh(m, nullptr);
  } else {
    for (const auto& inst : instances) add_mesh(meshes[inst.mesh], &inst.transform);
  }
  return b;
}

std::size_t Scene::triangle_count() const {
  std::size_t n = 0;
  if (instances.empty()) {
    for (const auto& m : meshes) n += m.triangles.size();
  } else {
    for (const auto& inst : instances) n += meshes[inst.mesh].triangles.size();
  }
  return n;
}

}  // namespace raysort
