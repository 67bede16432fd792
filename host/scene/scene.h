#pragma once
// A scene: meshes, instances, camera, lights and the light-transport effects it declares.
// Scenes come from TOML files (scene_file.h), bare OBJ files, or the embedded procedural
// scenes; all end up in this one struct.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace raysort {

using Vec3 = std::array<float, 3>;

// Axis-aligned box; empty() until a point is added.
struct Aabb {
  Vec3 min{3.0e38f, 3.0e38f, 3.0e38f};
  Vec3 max{-3.0e38f, -3.0e38f, -3.0e38f};
  void grow(const Vec3& p) {
    for (int a = 0; a < 3; ++a) {
      min[a] = p[a] < min[a] ? p[a] : min[a];
      max[a] = p[a] > max[a] ? p[a] : max[a];
    }
  }
  void grow(const Aabb& b) {
    if (b.empty()) return;
    grow(b.min);
    grow(b.max);
  }
  bool empty() const { return min[0] > max[0]; }
  Vec3 extent() const { return {max[0] - min[0], max[1] - min[1], max[2] - min[2]}; }
  float largest_extent() const {
    auto e = extent();
    return e[0] > e[1] ? (e[0] > e[2] ? e[0] : e[2]) : (e[1] > e[2] ? e[1] : e[2]);
  }
  Vec3 center() const { return {(min[0] + max[0]) * 0.5f, (min[1] + max[1]) * 0.5f, (min[2] + max[2]) * 0.5f}; }
  float surface_area() const {
    if (empty()) return 0.0f;
    auto e = extent();
    return 2.0f * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]);
  }
};

// An indexed triangle mesh in its own object space.
struct Mesh {
  std::string name;
  std::vector<Vec3> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::int32_t> material;  // per triangle, index into Scene::materials; empty = all 0
  std::string source;                  // "obj:<path>" or "procedural:<generator>" for messages
};

// A 3x4 affine transform, row-major: p' = M * (p, 1).
struct Affine {
  std::array<float, 12> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  Vec3 apply(const Vec3& p) const {
    return {m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3], m[4] * p[0] + m[5] * p[1] + m[6] * p[2] + m[7],
            m[8] * p[0] + m[9] * p[1] + m[10] * p[2] + m[11]};
  }
  // this * other (apply other first).
  Affine then_after(const Affine& other) const;
  static Affine translation(const Vec3& t);
  static Affine scaling(const Vec3& s);
  static Affine rotation_deg(const Vec3& axis_angles_xyz);  // rotate about x, then y, then z
};

struct Instance {
  std::uint32_t mesh = 0;  // index into Scene::meshes
  Affine transform;
};

struct Camera {
  Vec3 position{0, 0, 5};
  Vec3 look_at{0, 0, 0};
  Vec3 up{0, 1, 0};
  float fov_y_deg = 45.0f;
  std::uint32_t width = 640;
  std::uint32_t height = 360;
};

struct Material {
  std::string name = "default";
  Vec3 albedo{0.7f, 0.7f, 0.7f};
  bool mirror = false;
};

// A spherical light. The radius is given relative to the scene's largest extent, as the paper's
// Table 1 does; radius() resolves it once the scene's bounds are known.
struct SphereLight {
  Vec3 center{0, 0, 0};
  float radius_relative = 0.05f;
  Vec3 color{1, 1, 1};
  float power = 1.0f;
  float radius(float largest_extent) const { return radius_relative * largest_extent; }
};

struct SkyLight {
  bool enabled = false;
  Vec3 zenith{1, 1, 1};
  Vec3 horizon{1, 1, 1};  // == zenith: constant sky
};

// The light transport a scene asks for; the pipeline runs only the stages these imply.
struct Effects {
  std::uint32_t max_bounces = 1;            // diffuse bounces after the primary hit
  std::uint32_t shadow_rays_per_bounce = 1; // next-event estimation rays per hit (0: none)
  std::uint32_t russian_roulette_start = 3; // depth from which paths may be terminated
  float russian_roulette_survival = 0.8f;
  std::uint32_t samples_per_pixel = 1;
};

struct Scene {
  std::string name;
  std::string description;
  std::string file;  // where it came from: a .toml path, an .obj path or "embedded:scenes/x.toml"
  std::vector<Mesh> meshes;
  std::vector<Instance> instances;  // empty: every mesh once with the identity transform
  std::vector<Material> materials{Material{}};
  Camera camera;
  std::vector<SphereLight> sphere_lights;
  SkyLight sky;
  Effects effects;

  // World-space triangles of every instance, in instance order (instances flattened).
  struct Flat {
    std::vector<Vec3> v0, v1, v2;
    std::vector<std::int32_t> material;
    std::size_t size() const { return v0.size(); }
  };
  Flat flatten() const;
  Aabb bounds() const;  // world-space bounds of all instances
  std::size_t triangle_count() const;  // after instancing
};

}  // namespace raysort
