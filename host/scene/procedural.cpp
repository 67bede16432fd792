// Procedural mesh generators (docs/design.md, "Scenes"): rooms, terrain, dense objects and small
// props, each a pure function of its parameters and seed (noise.h has the RNG and noise).
#include "scene/procedural.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>

#include "scene/noise.h"
#include "util/error.h"

namespace raysort {

namespace {

// Reads and range-checks one generator's parameters, naming the generator and key on failure.
class Params {
 public:
  Params(const std::string& generator, const GeneratorParams& p) : generator_(generator), p_(p) {}
  double number(const char* key, double fallback, double lo, double hi) const {
    double v = p_.number(key, fallback);
    if (!std::isfinite(v) || v < lo || v > hi)
      throw Error(fmt::format("generator '{}': parameter '{}' = {} is out of range; use a value in [{}, {}]",
                              generator_, key, v, lo, hi));
    return v;
  }
  std::uint32_t count(const char* key, double fallback, double lo, double hi) const {
    double v = number(key, fallback, lo, hi);
    if (v != std::floor(v))
      throw Error(fmt::format("generator '{}': parameter '{}' = {} must be a whole number", generator_, key, v));
    return static_cast<std::uint32_t>(v);
  }
  bool flag(const char* key) const { return number(key, 0.0, 0.0, 1.0) != 0.0; }
  Vec3 vector(const char* key, Vec3 fallback) const { return p_.vector(key, fallback); }

 private:
  std::string generator_;
  const GeneratorParams& p_;
};

// Accumulates vertices and triangles.
struct Builder {
  Mesh mesh;
  std::uint32_t vertex(double x, double y, double z) {
    mesh.positions.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
    return static_cast<std::uint32_t>(mesh.positions.size() - 1);
  }
  void tri(std::uint32_t a, std::uint32_t b, std::uint32_t c) { mesh.triangles.push_back({a, b, c}); }
  // Quad a-b-c-d, counter-clockwise seen from the front.
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    tri(a, b, c);
    tri(a, c, d);
  }
  // Axis box from lo to hi; `inward` flips the winding (a room seen from inside); `skip_top`
  // leaves out the +y face.
  void box(const Vec3& lo, const Vec3& hi, bool inward = false, bool skip_top = false) {
    std::uint32_t v[8];
    for (int i = 0; i < 8; ++i) v[i] = vertex(i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
    auto face = [&](int a, int b, int c, int d) {
      if (inward)
        quad(v[a], v[d], v[c], v[b]);
      else
        quad(v[a], v[b], v[c], v[d]);
    };
    face(0, 4, 6, 2);  // -x
    face(1, 3, 7, 5);  // +x
    face(0, 1, 5, 4);  // -y
    if (!skip_top) face(2, 6, 7, 3);  // +y
    face(0, 2, 3, 1);  // -z
    face(4, 5, 7, 6);  // +z
  }
  // Closed ring strips: rows × cols vertices starting at `first`, each row a loop.
  void ring_strip(std::uint32_t first, std::uint32_t rows, std::uint32_t cols, bool close_rows) {
    std::uint32_t row_quads = close_rows ? rows : rows - 1;
    for (std::uint32_t r = 0; r < row_quads; ++r) {
      std::uint32_t r1 = (r + 1) % rows;
      for (std::uint32_t c = 0; c < cols; ++c) {
        std::uint32_t c1 = (c + 1) % cols;
        quad(first + r * cols + c, first + r * cols + c1, first + r1 * cols + c1, first + r1 * cols + c);
      }
    }
  }
};

// The parameters that set each generator's size, read in one place for its build and for its
// triangle count (generated_triangle_count below), so that the two cannot disagree.
std::uint32_t plane_segments_x(const Params& p) { return p.count("segments_x", 1, 1, 8192); }
std::uint32_t plane_segments_z(const Params& p) { return p.count("segments_z", 1, 1, 8192); }
std::uint32_t sphere_rings(const Params& p) { return p.count("subdivisions", 64, 3, 4096); }
std::uint32_t heightfield_resolution(const Params& p) { return p.count("resolution", 256, 1, 8192); }
std::uint32_t knot_segments(const Params& p) { return p.count("segments", 256, 3, 1 << 20); }
std::uint32_t knot_sides(const Params& p) { return p.count("sides", 32, 3, 4096); }
std::uint32_t gem_facets(const Params& p) { return p.count("facets", 8, 3, 4096); }
std::uint32_t rock_subdivisions(const Params& p) { return p.count("subdivisions", 2, 0, 7); }
std::uint32_t tree_sides(const Params& p) { return p.count("sides", 8, 3, 4096); }
std::uint32_t tree_layers(const Params& p) { return p.count("layers", 3, 1, 64); }

Mesh make_box(const Params& p, std::uint64_t) {
  Builder b;
  b.box(p.vector("min", {-0.5f, -0.5f, -0.5f}), p.vector("max", {0.5f, 0.5f, 0.5f}), p.flag("inverted"),
        p.flag("open_top"));
  return std::move(b.mesh);
}

Mesh make_plane(const Params& p, std::uint64_t) {
  double sx = p.number("size_x", 1.0, 1e-6, 1e9), sz = p.number("size_z", 1.0, 1e-6, 1e9);
  std::uint32_t nx = plane_segments_x(p), nz = plane_segments_z(p);
  Builder b;
  for (std::uint32_t j = 0; j <= nz; ++j)
    for (std::uint32_t i = 0; i <= nx; ++i) b.vertex(sx * (double(i) / nx - 0.5), 0.0, sz * (double(j) / nz - 0.5));
  for (std::uint32_t j = 0; j < nz; ++j)
    for (std::uint32_t i = 0; i < nx; ++i) {
      std::uint32_t a = j * (nx + 1) + i;
      b.quad(a, a + nx + 1, a + nx + 2, a + 1);  // normal +y
    }
  return std::move(b.mesh);
}

// A UV sphere with fbm displacement along the normal: rings × 2·rings quads (poles as fans).
// The noise is sampled at the unit direction, so the seam and the poles close without cracks.
Mesh make_displaced_sphere(const Params& p, std::uint64_t seed) {
  std::uint32_t rings = sphere_rings(p);
  double radius = p.number("radius", 1.0, 1e-6, 1e9);
  double amplitude = p.number("amplitude", 0.15, 0.0, 0.9);
  double frequency = p.number("frequency", 3.0, 0.0, 1e6);
  int octaves = static_cast<int>(p.count("octaves", 4, 1, 16));
  std::uint32_t segs = 2 * rings;
  Builder b;
  auto displaced = [&](double x, double y, double z) {
    double r = radius * (1.0 + amplitude * fbm(x * frequency, y * frequency, z * frequency, octaves, seed));
    return b.vertex(x * r, y * r, z * r);
  };
  b.mesh.positions.reserve(std::size_t(rings - 1) * segs + 2);
  b.mesh.triangles.reserve(std::size_t(rings - 1) * segs * 2);
  std::uint32_t top = displaced(0, 1, 0);
  for (std::uint32_t r = 1; r < rings; ++r) {
    double theta = std::numbers::pi * r / rings, st = std::sin(theta), ct = std::cos(theta);
    for (std::uint32_t s = 0; s < segs; ++s) {
      double phi = 2.0 * std::numbers::pi * s / segs;
      displaced(st * std::cos(phi), ct, st * std::sin(phi));
    }
  }
  std::uint32_t bottom = displaced(0, -1, 0);
  std::uint32_t first = top + 1;
  for (std::uint32_t s = 0; s < segs; ++s) {
    std::uint32_t s1 = (s + 1) % segs;
    b.tri(top, first + s1, first + s);
    b.tri(bottom, first + (rings - 2) * segs + s, first + (rings - 2) * segs + s1);
  }
  for (std::uint32_t r = 0; r + 1 < rings - 1; ++r)
    for (std::uint32_t s = 0; s < segs; ++s) {
      std::uint32_t s1 = (s + 1) % segs, a = first + r * segs;
      b.quad(a + s, a + s1, a + segs + s1, a + segs + s);
    }
  return std::move(b.mesh);
}

// fbm value-noise terrain on a regular (resolution+1)² grid, centred on the origin in x/z.
Mesh make_heightfield(const Params& p, std::uint64_t seed) {
  std::uint32_t res = heightfield_resolution(p);
  double size = p.number("size", 100.0, 1e-6, 1e9);
  double height = p.number("height", 10.0, 0.0, 1e9);
  double frequency = p.number("frequency", 4.0, 0.0, 1e6);
  int octaves = static_cast<int>(p.count("octaves", 6, 1, 16));
  Builder b;
  b.mesh.positions.reserve(std::size_t(res + 1) * (res + 1));
  b.mesh.triangles.reserve(std::size_t(res) * res * 2);
  for (std::uint32_t j = 0; j <= res; ++j)
    for (std::uint32_t i = 0; i <= res; ++i) {
      double u = double(i) / res, v = double(j) / res;
      double h = fbm(u * frequency, v * frequency, 0.5, octaves, seed);
      // Sharpen ridges a little so the terrain has valleys and peaks, not rolling bumps.
      b.vertex(size * (u - 0.5), height * h * std::fabs(h) * 2.0, size * (v - 0.5));
    }
  for (std::uint32_t j = 0; j < res; ++j)
    for (std::uint32_t i = 0; i < res; ++i) {
      std::uint32_t a = j * (res + 1) + i;
      b.quad(a, a + res + 1, a + res + 2, a + 1);
    }
  return std::move(b.mesh);
}

// A (p, q) torus knot tube, segments × sides quads, closed in both directions.
Mesh make_torus_knot(const Params& p, std::uint64_t) {
  double kp = p.count("p", 2, 1, 64), kq = p.count("q", 3, 1, 64);
  double radius = p.number("radius", 1.0, 1e-6, 1e9);
  double tube = p.number("tube", 0.25, 1e-6, 1e9);
  std::uint32_t segments = knot_segments(p), sides = knot_sides(p);
  auto curve = [&](double u) -> std::array<double, 3> {
    double cs = std::cos(kq / kp * u);
    return {radius * (2.0 + cs) * 0.5 * std::cos(u), radius * (2.0 + cs) * 0.5 * std::sin(u),
            radius * std::sin(kq / kp * u) * 0.5};
  };
  auto normalize = [](std::array<double, 3> v) {
    double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return std::array<double, 3>{v[0] / l, v[1] / l, v[2] / l};
  };
  auto cross = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::array<double, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  Builder b;
  b.mesh.positions.reserve(std::size_t(segments) * sides);
  for (std::uint32_t i = 0; i < segments; ++i) {
    double u = double(i) / segments * kp * 2.0 * std::numbers::pi;
    auto p1 = curve(u), p2 = curve(u + 0.01);
    std::array<double, 3> t{p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2]};
    std::array<double, 3> n{p2[0] + p1[0], p2[1] + p1[1], p2[2] + p1[2]};
    auto bn = normalize(cross(t, n));
    n = normalize(cross(bn, t));
    for (std::uint32_t j = 0; j < sides; ++j) {
      double v = double(j) / sides * 2.0 * std::numbers::pi;
      double cx = -tube * std::cos(v), cy = tube * std::sin(v);
      b.vertex(p1[0] + cx * n[0] + cy * bn[0], p1[1] + cx * n[1] + cy * bn[1], p1[2] + cx * n[2] + cy * bn[2]);
    }
  }
  b.ring_strip(0, segments, sides, true);
  return std::move(b.mesh);
}

// A faceted low-poly gem (brilliant-like): table, crown, girdle and pavilion; 4·facets triangles.
// The seed varies the proportions by up to ±10 %, so scattered gems are not all alike.
Mesh make_gem(const Params& p, std::uint64_t seed) {
  std::uint32_t n = gem_facets(p);
  double r = p.number("radius", 0.5, 1e-6, 1e9);
  SceneRng rng(seed);
  double crown = p.number("crown_height", 0.35, 0.0, 10.0) * r * rng.uniform(0.9, 1.1);
  double pavilion = p.number("pavilion_depth", 0.8, 0.0, 10.0) * r * rng.uniform(0.9, 1.1);
  double table = p.number("table", 0.55, 0.01, 1.0) * r * rng.uniform(0.9, 1.1);
  Builder b;
  std::uint32_t center = b.vertex(0, crown, 0), apex = b.vertex(0, -pavilion, 0);
  std::uint32_t tab = center + 2, gir = tab + n;
  for (std::uint32_t i = 0; i < n; ++i) {
    double a = 2.0 * std::numbers::pi * i / n;
    b.vertex(table * std::cos(a), crown, table * std::sin(a));
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    double a = 2.0 * std::numbers::pi * (i + 0.5) / n;
    b.vertex(r * std::cos(a), 0.0, r * std::sin(a));
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    std::uint32_t i1 = (i + 1) % n;
    b.tri(center, tab + i1, tab + i);   // table
    b.tri(tab + i, tab + i1, gir + i);  // crown: star facet
    b.tri(tab + i, gir + i, gir + (i + n - 1) % n);  // crown: kite facet
    b.tri(apex, gir + i, gir + i1);     // pavilion
  }
  return std::move(b.mesh);
}

// Icosphere: the 20 faces of an icosahedron split `subdivisions` times (20·4^s triangles).
Builder icosphere(std::uint32_t subdivisions) {
  Builder b;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const double v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  const std::uint32_t f[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                  {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                  {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  auto add_unit = [&](double x, double y, double z) {
    double l = std::sqrt(x * x + y * y + z * z);
    return b.vertex(x / l, y / l, z / l);
  };
  for (auto& p : v) add_unit(p[0], p[1], p[2]);
  for (auto& tri : f) b.tri(tri[0], tri[1], tri[2]);
  for (std::uint32_t s = 0; s < subdivisions; ++s) {
    std::unordered_map<std::uint64_t, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t c) {
      std::uint64_t key = (std::uint64_t(std::min(a, c)) << 32) | std::max(a, c);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      Vec3 pa = b.mesh.positions[a], pc = b.mesh.positions[c];
      std::uint32_t m = add_unit(double(pa[0]) + pc[0], double(pa[1]) + pc[1], double(pa[2]) + pc[2]);
      mid.emplace(key, m);
      return m;
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    next.reserve(b.mesh.triangles.size() * 4);
    for (auto tri : b.mesh.triangles) {
      std::uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]), ca = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    b.mesh.triangles = std::move(next);
  }
  return b;
}

// A lumpy rock for scattering: a noise-displaced icosphere, flattened below and standing on y = 0.
Mesh make_rock(const Params& p, std::uint64_t seed) {
  std::uint32_t subdivisions = rock_subdivisions(p);
  double radius = p.number("radius", 0.5, 1e-6, 1e9);
  double roughness = p.number("roughness", 0.35, 0.0, 0.9);
  double frequency = p.number("frequency", 1.5, 0.0, 1e6);
  Builder b = icosphere(subdivisions);
  SceneRng rng(seed);
  double squash = rng.uniform(0.5, 0.8);  // rocks are wider than tall
  for (auto& v : b.mesh.positions) {
    double x = v[0], y = v[1], z = v[2];
    double r = radius * (1.0 + roughness * fbm(x * frequency, y * frequency, z * frequency, 3, seed));
    double yy = std::max(y * r * squash, -0.2 * radius);
    v = {static_cast<float>(x * r), static_cast<float>(yy + 0.15 * radius), static_cast<float>(z * r)};
  }
  return std::move(b.mesh);
}

// A stylised tree standing on y = 0: an open trunk cylinder and `layers` stacked cones.
Mesh make_tree(const Params& p, std::uint64_t seed) {
  double height = p.number("height", 3.0, 1e-6, 1e9);
  std::uint32_t sides = tree_sides(p), layers = tree_layers(p);
  double trunk = p.number("trunk_radius", 0.08, 1e-6, 1e9);
  double crown = p.number("crown_radius", 0.9, 1e-6, 1e9);
  SceneRng rng(seed);
  Builder b;
  double trunk_top = 0.35 * height;
  std::uint32_t first = static_cast<std::uint32_t>(b.mesh.positions.size());
  for (int ring = 0; ring < 2; ++ring)
    for (std::uint32_t s = 0; s < sides; ++s) {
      double a = 2.0 * std::numbers::pi * s / sides;
      b.vertex(trunk * std::cos(a), ring ? trunk_top : 0.0, trunk * std::sin(a));
    }
  b.ring_strip(first, 2, sides, false);
  double layer_h = (height - trunk_top * 0.6) / layers;
  for (std::uint32_t l = 0; l < layers; ++l) {
    double base = trunk_top * 0.6 + l * layer_h * 0.8;
    double rad = crown * (1.0 - 0.25 * l) * rng.uniform(0.85, 1.15);
    double twist = rng.uniform(0.0, 2.0 * std::numbers::pi);
    std::uint32_t apex = b.vertex(0.0, std::min(height, base + layer_h * 1.4), 0.0);
    std::uint32_t centre = b.vertex(0.0, base, 0.0);
    std::uint32_t ring = static_cast<std::uint32_t>(b.mesh.positions.size());
    for (std::uint32_t s = 0; s < sides; ++s) {
      double a = twist + 2.0 * std::numbers::pi * s / sides;
      b.vertex(rad * std::cos(a), base, rad * std::sin(a));
    }
    for (std::uint32_t s = 0; s < sides; ++s) {
      std::uint32_t s1 = (s + 1) % sides;
      b.tri(apex, ring + s1, ring + s);
      b.tri(centre, ring + s, ring + s1);
    }
  }
  return std::move(b.mesh);
}

// A table standing on y = 0 with its top surface at y = height: a slab and four legs (60 triangles).
Mesh make_table(const Params& p, std::uint64_t) {
  double w = p.number("width", 2.0, 1e-6, 1e9), d = p.number("depth", 1.0, 1e-6, 1e9);
  double h = p.number("height", 0.75, 1e-6, 1e9), t = p.number("top_thickness", 0.05, 1e-6, 1e9);
  double leg = p.number("leg_size", 0.06, 1e-6, 1e9);
  auto f = [](double x) { return static_cast<float>(x); };
  Builder b;
  b.box({f(-w / 2), f(h - t), f(-d / 2)}, {f(w / 2), f(h), f(d / 2)});
  for (int i = 0; i < 4; ++i) {
    double x = (i & 1 ? 1 : -1) * (w / 2 - 2 * leg), z = (i & 2 ? 1 : -1) * (d / 2 - 2 * leg);
    b.box({f(x - leg / 2), 0.0f, f(z - leg / 2)}, {f(x + leg / 2), f(h - t), f(z + leg / 2)});
  }
  return std::move(b.mesh);
}

struct Generator {
  const char* name;
  Mesh (*build)(const Params&, std::uint64_t);
  std::uint64_t (*triangles)(const Params&);  // what build makes, at most; computed without building
  std::vector<const char*> numbers;
  std::vector<const char*> vectors;
};

// Triangle counts of the generators above (upper bounds where poles or open faces drop a few),
// so that a scene can refuse a size before it allocates (scene/load.h, SceneOptions::max_triangles).
std::uint64_t box_triangles(const Params&) { return 12; }
std::uint64_t displaced_sphere_triangles(const Params& p) {
  const std::uint64_t rings = sphere_rings(p);
  return 4 * rings * (rings - 1);
}
std::uint64_t gem_triangles(const Params& p) { return 4 * std::uint64_t{gem_facets(p)}; }
std::uint64_t heightfield_triangles(const Params& p) {
  const std::uint64_t res = heightfield_resolution(p);
  return 2 * res * res;
}
std::uint64_t plane_triangles(const Params& p) { return 2 * std::uint64_t{plane_segments_x(p)} * plane_segments_z(p); }
std::uint64_t rock_triangles(const Params& p) { return 20ull << (2 * rock_subdivisions(p)); }
std::uint64_t table_triangles(const Params&) { return 60; }
std::uint64_t torus_knot_triangles(const Params& p) { return 2 * std::uint64_t{knot_segments(p)} * knot_sides(p); }
std::uint64_t tree_triangles(const Params& p) { return 2 * std::uint64_t{tree_sides(p)} * (1 + tree_layers(p)); }

const std::vector<Generator>& generators() {
  static const std::vector<Generator> g = {
      {"box", make_box, box_triangles, {"inverted", "open_top"}, {"min", "max"}},
      {"displaced_sphere", make_displaced_sphere, displaced_sphere_triangles, {"subdivisions", "radius", "amplitude", "frequency", "octaves"}, {}},
      {"gem", make_gem, gem_triangles, {"facets", "radius", "crown_height", "pavilion_depth", "table"}, {}},
      {"heightfield", make_heightfield, heightfield_triangles, {"resolution", "size", "height", "frequency", "octaves"}, {}},
      {"plane", make_plane, plane_triangles, {"size_x", "size_z", "segments_x", "segments_z"}, {}},
      {"rock", make_rock, rock_triangles, {"subdivisions", "radius", "roughness", "frequency"}, {}},
      {"table", make_table, table_triangles, {"width", "depth", "height", "top_thickness", "leg_size"}, {}},
      {"torus_knot", make_torus_knot, torus_knot_triangles, {"p", "q", "radius", "tube", "segments", "sides"}, {}},
      {"tree", make_tree, tree_triangles, {"height", "sides", "layers", "trunk_radius", "crown_radius"}, {}},
  };
  return g;
}

}  // namespace

std::vector<std::string> generator_names() {
  std::vector<std::string> names;
  for (const auto& g : generators()) names.emplace_back(g.name);
  return names;
}

namespace {

// The generator of that name, after checking that `params` names only its parameters.
const Generator& find_generator(const std::string& name, const GeneratorParams& params) {
  for (const auto& g : generators()) {
    if (name != g.name) continue;
    auto listed = [](const std::vector<const char*>& keys) { return fmt::format("{}", fmt::join(keys, ", ")); };
    for (const auto& [key, value] : params.numbers) {
      (void)value;
      if (std::find(g.numbers.begin(), g.numbers.end(), key) == g.numbers.end())
        throw Error(fmt::format("generator '{}' has no number parameter '{}'; its number parameters are: {}", name,
                                key, g.numbers.empty() ? "(none)" : listed(g.numbers)));
    }
    for (const auto& [key, value] : params.vectors) {
      (void)value;
      if (std::find(g.vectors.begin(), g.vectors.end(), key) == g.vectors.end())
        throw Error(fmt::format("generator '{}' has no vector parameter '{}'; its vector parameters are: {}", name,
                                key, g.vectors.empty() ? "(none)" : listed(g.vectors)));
    }
    return g;
  }
  throw Error(fmt::format("unknown generator '{}'; the generators are: {}", name, fmt::join(generator_names(), ", ")));
}

}  // namespace

std::uint64_t generated_triangle_count(const std::string& name, const GeneratorParams& params) {
  return find_generator(name, params).triangles(Params(name, params));
}

Mesh generate_mesh(const std::string& name, const GeneratorParams& params, std::uint64_t seed) {
  Mesh mesh = find_generator(name, params).build(Params(name, params), seed);
  mesh.source = "procedural:" + name;
  return mesh;
}

}  // namespace raysort
