// Hard cases for the two trace variants (docs/trace.md): rays aimed at the shared edges and
// vertices of finely tessellated meshes, axis-parallel and grazing rays, rays in a triangle's
// plane, origins on slab planes, translated and scaled scenes, degenerate triangles; and the robust
// kernels against the host reference, bit for bit, on every batch of two pipelines.
//
// Leak: a ray from outside a surface, aimed at a point p of it (a shared vertex or a point on a
// shared edge) with d = p - o so that t = 1 at p, that reports no hit or a hit beyond p
// (t > 1 + 1e-3): it slipped through the crack between triangles. An occluded ray (t < 1) is fine.
// The robust variant must have no leak; the fast variant's count is printed, not asserted.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>

#include "bvh/bvh.h"
#include "render/batches.h"
#include "scene/load.h"
#include "test_util.h"
#include "trace/exact_oracle.h"
#include "trace/tracer.h"
#include "intersect.h"  // cl/intersect.h: the triangle tests themselves
#include "sampling.h"
#include "traverse_wide.h"

namespace raysort {

namespace {

constexpr TraceVariant kVariants[] = {TraceVariant::Fast, TraceVariant::Robust};

struct IndexedMesh {
  std::vector<Vec3> pos;
  std::vector<std::array<std::uint32_t, 3>> tri;
};

Scene::Flat flat_of(const IndexedMesh& m) {
  Scene::Flat f;
  for (auto& t : m.tri) {
    f.v0.push_back(m.pos[t[0]]);
    f.v1.push_back(m.pos[t[1]]);
    f.v2.push_back(m.pos[t[2]]);
    f.material.push_back(0);
  }
  return f;
}

// UV sphere, unit radius: `rings` latitude bands, `segments` longitudes, one vertex per pole (fans
// of `segments` triangles meet there), every vertex shared: closed.
IndexedMesh uv_sphere(std::uint32_t rings, std::uint32_t segments) {
  IndexedMesh m;
  m.pos.push_back({0, 1, 0});
  for (std::uint32_t r = 1; r < rings; ++r) {
    double th = M_PI * r / rings;
    for (std::uint32_t s = 0; s < segments; ++s) {
      double ph = 2 * M_PI * s / segments;
      m.pos.push_back({float(std::sin(th) * std::cos(ph)), float(std::cos(th)), float(std::sin(th) * std::sin(ph))});
    }
  }
  m.pos.push_back({0, -1, 0});
  const std::uint32_t south = static_cast<std::uint32_t>(m.pos.size() - 1);
  auto ring = [&](std::uint32_t r, std::uint32_t s) { return 1 + (r - 1) * segments + s % segments; };
  for (std::uint32_t s = 0; s < segments; ++s) {
    m.tri.push_back({0, ring(1, s + 1), ring(1, s)});
    m.tri.push_back({south, ring(rings - 1, s), ring(rings - 1, s + 1)});
    for (std::uint32_t r = 1; r + 1 < rings; ++r) {
      m.tri.push_back({ring(r, s), ring(r, s + 1), ring(r + 1, s + 1)});
      m.tri.push_back({ring(r, s), ring(r + 1, s + 1), ring(r + 1, s)});
    }
  }
  return m;
}

// Unit cube [0,1]³, each face an n×n grid of cells split along a diagonal; vertices shared: closed.
IndexedMesh lattice_cube(std::uint32_t n) {
  IndexedMesh m;
  std::map<std::array<std::uint32_t, 3>, std::uint32_t> index;
  auto vertex = [&](std::array<std::uint32_t, 3> q) {
    auto it = index.find(q);
    if (it != index.end()) return it->second;
    auto id = static_cast<std::uint32_t>(m.pos.size());
    m.pos.push_back({float(q[0]) / float(n), float(q[1]) / float(n), float(q[2]) / float(n)});
    index.emplace(q, id);
    return id;
  };
  for (std::uint32_t axis = 0; axis < 3; ++axis) {
    for (std::uint32_t side = 0; side < 2; ++side) {
      for (std::uint32_t i = 0; i < n; ++i) {
        for (std::uint32_t j = 0; j < n; ++j) {
          auto at = [&](std::uint32_t a, std::uint32_t b) {
            std::array<std::uint32_t, 3> q{};
            q[axis] = side * n;
            q[(axis + 1) % 3] = a;
            q[(axis + 2) % 3] = b;
            return vertex(q);
          };
          std::uint32_t v00 = at(i, j), v10 = at(i + 1, j), v11 = at(i + 1, j + 1), v01 = at(i, j + 1);
          m.tri.push_back({v00, v10, v11});
          m.tri.push_back({v00, v11, v01});
        }
      }
    }
  }
  return m;
}

RsRay make_ray(Vec3 o, Vec3 d, float tmax = RS_T_FAR) { return testing::ray(o[0], o[1], o[2], d[0], d[1], d[2], tmax); }

RsVec3 v3(const Vec3& a) { return rs_vec3(a[0], a[1], a[2]); }

RsVec3 face_normal(const IndexedMesh& m, std::size_t t) {
  const auto& f = m.tri[t];
  return rs_normalize(rs_cross(rs_sub(v3(m.pos[f[1]]), v3(m.pos[f[0]])), rs_sub(v3(m.pos[f[2]]), v3(m.pos[f[0]]))));
}

// Rays aimed at the interior shared features of a mesh: every edge shared by exactly two triangles
// (at its midpoint and at a quarter point), and every vertex whose incident edges are all such
// edges. Only features where the surface is locally a mild crease (every incident face normal
// within 60° of the averaged normal) qualify, so that the ray, which comes along the averaged
// normal (jittered), crosses the surface there rather than touching it. Origins sit `dist` away.
std::vector<RsRay> rays_at_shared_features(const IndexedMesh& m, float dist, std::size_t max_rays, std::uint32_t seed) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edges;
  std::vector<std::vector<std::uint32_t>> vertex_tris(m.pos.size());
  for (std::uint32_t t = 0; t < m.tri.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      std::uint32_t a = m.tri[t][k], b = m.tri[t][(k + 1) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back(t);
      vertex_tris[a].push_back(t);
    }
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.25f, 0.25f);
  std::vector<RsRay> rays;
  auto aim = [&](Vec3 p, const std::vector<std::uint32_t>& tris) {
    RsVec3 n = rs_vec3(0, 0, 0);
    for (auto t : tris) n = rs_add(n, face_normal(m, t));
    n = rs_normalize(n);
    for (auto t : tris)
      if (rs_dot(n, face_normal(m, t)) < 0.5f) return;
    RsVec3 dir = rs_normalize(rs_add(n, rs_vec3(jitter(rng), jitter(rng), jitter(rng))));
    Vec3 o = {p[0] + dist * dir.x, p[1] + dist * dir.y, p[2] + dist * dir.z};
    rays.push_back(make_ray(o, {p[0] - o[0], p[1] - o[1], p[2] - o[2]}));
  };
  for (auto& [e, tris] : edges) {
    if (tris.size() != 2) continue;
    const Vec3 &a = m.pos[e.first], &b = m.pos[e.second];
    for (float s : {0.5f, 0.25f})
      aim({a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])}, tris);
  }
  for (std::uint32_t v = 0; v < m.pos.size(); ++v) {
    if (vertex_tris[v].empty()) continue;
    bool interior = true;
    for (auto t : vertex_tris[v])
      for (int k = 0; k < 3; ++k) {
        std::uint32_t a = m.tri[t][k], b = m.tri[t][(k + 1) % 3];
        if ((a == v || b == v) && edges[{std::min(a, b), std::max(a, b)}].size() != 2) interior = false;
      }
    if (interior) aim(m.pos[v], vertex_tris[v]);
  }
  if (rays.size() > max_rays) {
    std::shuffle(rays.begin(), rays.end(), rng);
    rays.resize(max_rays);
  }
  return rays;
}

bool finite_hit(const RsHit& h) { return std::isfinite(h.t) && std::isfinite(h.u) && std::isfinite(h.v); }

// The exact oracle's verdicts (trace/exact_oracle.h) on a set of answers.
VerdictCounts judged(const Scene::Flat& tris, const Bvh& bvh, const std::vector<RsRay>& rays,
                     const std::vector<RsHit>& hits, bool any_hit) {
  const ExactOracle oracle(tris, bvh);
  VerdictCounts c;
  for (std::size_t i = 0; i < rays.size(); ++i) c.add(ExactOracle::judge(oracle.truth(rays[i], any_hit), hits[i]));
  return c;
}

std::size_t count_leaks(const std::vector<RsHit>& hits) {
  std::size_t leaks = 0;
  for (auto& h : hits) leaks += h.tri == RS_NO_HIT || h.t > 1.001f;
  return leaks;
}

// Traces aimed rays with both variants on the host and the device; robust must not leak, and its
// device hits must equal the host's bit for bit. Prints the fast variant's leaks.
void expect_watertight(const char* what, const IndexedMesh& m, const std::vector<RsRay>& rays) {
  const Scene::Flat tris = flat_of(m);
  Bvh bvh = build_bvh(tris);
  for (TraceVariant v : kVariants) {
    auto host = trace_reference(bvh, rays, nullptr, false, nullptr, v);
    Tracer tracer(testing::runtime(), bvh, v);
    auto dev = tracer.run(rays, nullptr, false);
    std::size_t host_leaks = count_leaks(host), dev_leaks = count_leaks(dev.hits);
    std::size_t nan = 0;
    for (auto& h : host) nan += !finite_hit(h);
    std::printf("[ leaks    ] %-8s %-6s %zu rays: host %zu, device %zu (%.1f per million)\n", what, trace_variant_name(v),
                rays.size(), host_leaks, dev_leaks, 1e6 * double(host_leaks) / double(rays.size()));
    EXPECT_EQ(nan, 0u) << what << " " << trace_variant_name(v);
    const VerdictCounts exact = judged(tris, bvh, rays, dev.hits, false);
    std::printf("[ exactly  ] %-8s %-6s right %zu, tie %zu, wrong %zu\n", what, trace_variant_name(v), exact.right,
                exact.tie, exact.wrong);
    if (v == TraceVariant::Robust) {
      EXPECT_EQ(host_leaks, 0u) << what;
      EXPECT_EQ(dev_leaks, 0u) << what;
      EXPECT_EQ(count_hit_mismatches(dev.hits, host), 0u) << what;
      EXPECT_EQ(exact.wrong, 0u) << what;
      // The packet class, 16 aimed rays per packet, the 8-wide tree (eight boxes and eight
      // triangles per test), coherent packets of 16 and streams of 64 rays of one octant over it:
      // watertight too, and equal to their host twins.
      for (TraceLayout layout : {TraceLayout::Packet16, TraceLayout::Wide8, TraceLayout::Coherent16, TraceLayout::Stream,
                                 TraceLayout::Cwbvh}) {
        const char* name = trace_layout_name(layout);
        const auto class_host = trace_reference(bvh, rays, nullptr, false, nullptr, v, layout);
        const auto class_dev = Tracer(testing::runtime(), bvh, v, layout).run(rays, nullptr, false).hits;
        EXPECT_EQ(count_hit_mismatches(class_dev, class_host), 0u) << what << " " << name;
        EXPECT_EQ(count_leaks(class_dev), 0u) << what << " " << name;
        EXPECT_EQ(judged(tris, bvh, rays, class_dev, false).wrong, 0u) << what << " " << name;
      }
    }
  }
}

}  // namespace

TEST(Robust, VariantNames) {
  EXPECT_EQ(parse_trace_variant("fast"), TraceVariant::Fast);
  EXPECT_EQ(parse_trace_variant("robust"), TraceVariant::Robust);
  EXPECT_STREQ(trace_variant_name(TraceVariant::Robust), "robust");
  EXPECT_THROW(parse_trace_variant("exact"), Error);
}

TEST(Robust, SphereSharedEdgesAndVerticesNeverLeak) {
  IndexedMesh sphere = uv_sphere(96, 128);
  auto rays = rays_at_shared_features(sphere, 2.0f, 60000, 7);
  ASSERT_GT(rays.size(), 30000u);
  expect_watertight("sphere", sphere, rays);
}

// The bunny is not closed (holes in its base), so only interior features count: edges shared by
// two triangles and vertices surrounded by such edges, where the surface is locally a two-sided
// sheet that any crossing ray must hit.
TEST(Robust, BunnySharedEdgesAndVerticesNeverLeak) {
  RAYSORT_REQUIRE_REAL_SCENES();
  Scene scene = load_scene(testing::real_scene_root() + "/bunny/stanford-bunny.obj");
  IndexedMesh bunny;
  for (auto& mesh : scene.meshes) {
    auto base = static_cast<std::uint32_t>(bunny.pos.size());
    bunny.pos.insert(bunny.pos.end(), mesh.positions.begin(), mesh.positions.end());
    for (auto t : mesh.triangles) bunny.tri.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  auto rays = rays_at_shared_features(bunny, 0.05f * scene.bounds().largest_extent(), 80000, 11);
  ASSERT_GT(rays.size(), 20000u);
  expect_watertight("bunny", bunny, rays);
}

// Axis-parallel rays (direction components +0 and -0) aimed at every lattice point and cell-diagonal
// midpoint of a tessellated cube's faces, including its edges and corners, where the ray grazes
// along side faces and starts on their slab planes.
TEST(Robust, AxisParallelRaysThroughLatticeVerticesAndEdges) {
  const std::uint32_t n = 4;
  IndexedMesh cube = lattice_cube(n);
  std::vector<RsRay> rays;
  for (std::uint32_t axis = 0; axis < 3; ++axis)
    for (float sign : {1.0f, -1.0f})
      for (std::uint32_t i = 0; i <= 2 * n; ++i)
        for (std::uint32_t j = 0; j <= 2 * n; ++j)
          for (int zeros = 0; zeros < 4; ++zeros) {
            Vec3 o{}, d{};
            o[axis] = sign > 0 ? -1.0f : 2.0f;  // 1 unit before the face it aims at
            o[(axis + 1) % 3] = float(i) / float(2 * n);
            o[(axis + 2) % 3] = float(j) / float(2 * n);
            d[axis] = sign;
            d[(axis + 1) % 3] = (zeros & 1) ? -0.0f : 0.0f;
            d[(axis + 2) % 3] = (zeros & 2) ? -0.0f : 0.0f;
            rays.push_back(make_ray(o, d));
          }
  const Scene::Flat tris = flat_of(cube);
  Bvh bvh = build_bvh(tris);
  for (TraceVariant v : kVariants) {
    auto host = trace_reference(bvh, rays, nullptr, false, nullptr, v);
    auto dev = Tracer(testing::runtime(), bvh, v).run(rays, nullptr, false).hits;
    if (v == TraceVariant::Robust) {
      EXPECT_EQ(judged(tris, bvh, rays, dev, false).wrong, 0u);
    }
    std::size_t wrong = 0;
    for (auto& h : host) wrong += h.tri == RS_NO_HIT || !(std::fabs(h.t - 1.0f) <= 1e-6f);
    std::printf("[ lattice  ] %-6s %zu axis rays, %zu not hitting at t = 1\n", trace_variant_name(v), rays.size(), wrong);
    if (v == TraceVariant::Robust) {
      EXPECT_EQ(wrong, 0u);
      EXPECT_EQ(count_hit_mismatches(dev, host), 0u);
    }
  }
}

TEST(Robust, GrazingInPlaneAndSlabPlaneRays) {
  IndexedMesh cube = lattice_cube(2);
  const Scene::Flat tris = flat_of(cube);
  Bvh bvh = build_bvh(tris);
  struct Case {
    const char* what;
    RsRay ray;
    float t;  // expected distance, < 0: miss
  };
  const Case cases[] = {
      {"along face y=1 onto the top edge", make_ray({0.25f, 1, 2}, {0.25f, -0.0f, -1}), 1.0f},
      {"along face x=0, -0 component", make_ray({-0.0f, 0.25f, 2}, {-0.0f, 0.5f, -1}), 1.0f},
      {"in the top face's plane onto the x=0 face's edge", make_ray({-1, 0.3f, 1}, {1, 0, 0}), 1.0f},
      {"from the top face, inward", make_ray({0.5f, 0.5f, 1}, {0, -0.0f, -1}), 1.0f},
      {"from the top face, outward", make_ray({0.5f, 0.5f, 1}, {0, 0, 1}), -1.0f},
      {"from a corner, along an edge", make_ray({1, 1, 1}, {-0.0f, -0.0f, -1}), 1.0f},
      {"along the outside of an edge", make_ray({1, 1, 3}, {0, 0, -1}), 2.0f},
      {"parallel just outside a face", make_ray({1.0000001f, 0.5f, 3}, {0, 0, -1}), -1.0f},
      {"zero direction", make_ray({0.5f, 0.5f, 3}, {0, -0.0f, 0}), -1.0f},
  };
  std::vector<RsRay> rays;
  for (auto& c : cases) rays.push_back(c.ray);
  auto host = trace_reference(bvh, rays, nullptr, false, nullptr, TraceVariant::Robust);
  auto dev = Tracer(testing::runtime(), bvh, TraceVariant::Robust).run(rays, nullptr, false).hits;
  auto any = trace_reference(bvh, rays, nullptr, true, nullptr, TraceVariant::Robust);
  EXPECT_EQ(count_hit_mismatches(dev, host), 0u);
  EXPECT_EQ(judged(tris, bvh, rays, dev, false).wrong, 0u);
  EXPECT_EQ(judged(tris, bvh, rays, any, true).wrong, 0u);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Case& c = cases[i];
    EXPECT_TRUE(finite_hit(host[i])) << c.what;
    EXPECT_EQ(any[i].tri == RS_NO_HIT, host[i].tri == RS_NO_HIT) << c.what;
    if (c.t < 0) {
      EXPECT_EQ(host[i].tri, RS_NO_HIT) << c.what << " t=" << host[i].t;
    } else {
      EXPECT_NE(host[i].tri, RS_NO_HIT) << c.what;
      EXPECT_NEAR(host[i].t, c.t, 1e-6f) << c.what;
    }
  }
  auto fast = trace_reference(bvh, rays, nullptr, false, nullptr, TraceVariant::Fast);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    EXPECT_TRUE(finite_hit(fast[i])) << cases[i].what;
    bool ok = cases[i].t < 0 ? fast[i].tri == RS_NO_HIT : fast[i].tri != RS_NO_HIT && std::fabs(fast[i].t - cases[i].t) <= 1e-6f;
    if (!ok) std::printf("[ grazing  ] fast differs: %s\n", cases[i].what);
  }
}

// A long sliver seen edge-on (breakfast_room's 4.9 m × 7 mm strips, found by `raysort trace
// --adjudicate`): the watertight t's worst-case error bound (0.026 here, 13.6 at t = 10.45) far
// exceeds the true t, and rejecting such hits made the robust variant skip the strip for the
// surface behind it. Such a t is decided again in double; the hit is kept. Rays leaving points near
// the strip are judged by the exact oracle (no wrong answer; the test of rays leaving the very
// triangle they start on is TranslatedAndScaledSceneKeepsHits).
TEST(Robust, SliverSeenEdgeOnIsHitNotSkipped) {
  IndexedMesh m;
  m.pos = {{-3.09547f, 0.495951f, -0.734771f}, {1.81088f, 0.48888f, -0.7377f}, {1.81088f, 0.495951f, -0.734771f},
           // the surface behind it, 2.5 cm farther along the ray
           {-3.09547f, 0.485951f, -0.842195f}, {1.81088f, 0.485951f, -0.842195f}, {1.81088f, 0.485951f, -0.744771f}};
  m.tri = {{0, 1, 2}, {3, 4, 5}};
  const Scene::Flat tris = flat_of(m);
  Bvh bvh = build_bvh(tris);
  const RsRay ray = make_ray({0x1.cf93c6p+0f, 0x1.f8fdd2p-2f, -0x1.789afep-1f}, {-0x1.a81868p-1f, -0x1.1edd9p-2f, -0x1.f0d8cap-2f});
  // Points near the sliver, left along rays toward the other side.
  std::vector<RsRay> rays{ray};
  for (float f : {0.1f, 0.3f, 0.5f, 0.7f, 0.9f}) {
    const Vec3 p{-3.09547f + f * 4.90635f, 0.495951f - 0.5f * f * 0.007071f, -0.734771f - 0.5f * f * 0.002929f};
    rays.push_back(make_ray(p, {0.01f, -0.3f, -0.95f}));
  }
  for (TraceLayout layout : {TraceLayout::Wide, TraceLayout::Wide8, TraceLayout::Binary, TraceLayout::Cwbvh}) {
    auto host = trace_reference(bvh, rays, nullptr, false, nullptr, TraceVariant::Robust, layout);
    auto dev = Tracer(testing::runtime(), bvh, TraceVariant::Robust, layout).run(rays, nullptr, false).hits;
    EXPECT_EQ(count_hit_mismatches(dev, host), 0u) << trace_layout_name(layout);
    EXPECT_EQ(host[0].tri, 0u) << trace_layout_name(layout) << ": skipped the sliver, hit " << host[0].tri << " at t "
                               << host[0].t;
    EXPECT_NEAR(host[0].t, 0.00100600074f, 1e-7f) << trace_layout_name(layout);
    EXPECT_EQ(judged(tris, bvh, rays, dev, false).wrong, 0u) << trace_layout_name(layout);
  }
}

// A ray in a lone triangle's plane: det = 0, never a hit, never NaN.
TEST(Robust, RayInTrianglePlaneMisses) {
  IndexedMesh m;
  m.pos = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.tri = {{0, 1, 2}};
  Bvh bvh = build_bvh(flat_of(m));
  std::vector<RsRay> rays = {make_ray({-1, 0.25f, 0}, {1, 0, 0}), make_ray({-1, -1, 0}, {1, 1, 0}),
                             make_ray({0.2f, 0.2f, 0}, {0, 1, -0.0f}), make_ray({-1, 0, 0}, {1, 0, 0})};
  for (TraceVariant v : kVariants) {
    auto host = trace_reference(bvh, rays, nullptr, false, nullptr, v);
    auto dev = Tracer(testing::runtime(), bvh, v).run(rays, nullptr, false).hits;
    EXPECT_EQ(count_hit_mismatches(dev, host), 0u) << trace_variant_name(v);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      EXPECT_TRUE(finite_hit(host[i])) << trace_variant_name(v) << " " << i;
      EXPECT_EQ(host[i].tri, RS_NO_HIT) << trace_variant_name(v) << " " << i;
    }
  }
}

// Degenerate triangles (a point, repeated vertices, exactly collinear vertices) are never hit by
// rays aimed right at them, and no hit record holds NaN. One proper triangle far away keeps the
// tree non-trivial.
TEST(Robust, DegenerateTrianglesNeverHit) {
  IndexedMesh m;
  m.pos = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {0.5f, 0.25f, 0}, {1, 0.5f, 0}, {3, 0, 1}, {3, 0, 1}, {3, 2, 1},
           {50, 50, 50}, {51, 50, 50}, {50, 51, 50}};
  m.tri = {{0, 1, 2}, {0, 3, 4}, {5, 6, 7}, {5, 5, 5}, {1, 1, 2}, {8, 9, 10}};
  const std::uint32_t proper = 5;
  Bvh bvh = build_bvh(flat_of(m));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), s(0.0f, 1.0f);
  std::vector<RsRay> rays;
  for (std::uint32_t t = 0; t < proper; ++t) {
    const Vec3 &a = m.pos[m.tri[t][0]], &b = m.pos[m.tri[t][2]];
    for (int k = 0; k < 400; ++k) {
      float f = k < 3 ? 0.5f * float(k) : s(rng);
      Vec3 p{a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
      Vec3 o{p[0] + 3 * u(rng), p[1] + 3 * u(rng), p[2] + 3 * u(rng)};
      if (k % 4 == 0) o = {p[0], p[1], p[2] + 2};  // axis-parallel
      rays.push_back(make_ray(o, {p[0] - o[0], p[1] - o[1], p[2] - o[2]}));
    }
  }
  for (TraceVariant v : kVariants) {
    for (bool any_hit : {false, true}) {
      auto host = trace_reference(bvh, rays, nullptr, any_hit, nullptr, v);
      auto dev = Tracer(testing::runtime(), bvh, v).run(rays, nullptr, any_hit).hits;
      EXPECT_EQ(count_hit_mismatches(dev, host), 0u) << trace_variant_name(v);
      std::size_t degenerate_hits = 0, nan = 0;
      for (auto& h : host) {
        degenerate_hits += h.tri != RS_NO_HIT && h.tri != proper;
        nan += !finite_hit(h);
      }
      EXPECT_EQ(nan, 0u) << trace_variant_name(v);
      if (v == TraceVariant::Robust) {
        EXPECT_EQ(degenerate_hits, 0u) << "any_hit " << any_hit;
      }
      if (v == TraceVariant::Fast && !any_hit)
        std::printf("[ degenerate] fast: %zu of %zu rays hit a degenerate triangle\n", degenerate_hits, rays.size());
    }
  }
}

// The cornell box translated by 1e5, and scaled by 1e-4 and 1e4: the robust variant hits the same
// triangles as in the original scene for rays well away from edges (barycentrics at least 0.05 from
// every edge in both scenes, and no other surface within 0.05 behind the hit), and bounce rays leaving a hit (origin offset as in host/render/rays.cpp)
// never hit their own plane again (self-intersection at t ≈ 0).
TEST(Robust, TranslatedAndScaledSceneKeepsHits) {
  Scene scene = load_scene("cornell", {"", {64, 48, 0}});
  Scene::Flat base = scene.flatten();
  Bvh base_bvh = build_bvh(base);
  RayGenOptions gen;
  auto batches = generate_batches(scene, base, base_bvh, gen);
  ASSERT_FALSE(batches.empty());
  const std::vector<RsRay>& primary = batches[0].batch.rays;
  auto base_hits = trace_reference(base_bvh, primary, nullptr, false, nullptr, TraceVariant::Robust);
  auto margin = [](const RsHit& h) { return std::min(std::min(h.u, h.v), 1.0f - h.u - h.v); };
  // The next surface behind each hit: a ray whose hit has another surface within 0.05 behind it
  // (the coloured walls stand 1 mm inside the grey box; the blocks' bases lie on the floor) is not
  // "well away": moving the scene by 1e5 rounds such near-coplanar pairs together (float spacing
  // 1/128 there), and which of two coincident triangles wins is then arbitrary.
  std::vector<RsRay> behind = primary;
  for (std::size_t i = 0; i < behind.size(); ++i) behind[i].tmin = base_hits[i].t;
  auto behind_hits = trace_reference(base_bvh, behind, nullptr, false, nullptr, TraceVariant::Robust);

  struct Transform {
    const char* what;
    float scale, shift;
  };
  for (Transform tf : {Transform{"translated 1e5", 1.0f, 1e5f}, Transform{"scaled 1e-4", 1e-4f, 0.0f},
                       Transform{"scaled 1e4", 1e4f, 0.0f}}) {
    Scene::Flat flat = base;
    for (auto* vs : {&flat.v0, &flat.v1, &flat.v2})
      for (auto& p : *vs)
        for (float& c : p) c = c * tf.scale + tf.shift;
    Bvh bvh = build_bvh(flat);
    std::vector<RsRay> rays = primary;
    for (auto& r : rays)
      for (float& c : r.o) c = c * tf.scale + tf.shift;
    auto hits = trace_reference(bvh, rays, nullptr, false, nullptr, TraceVariant::Robust);
    std::size_t compared = 0, changed = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (base_hits[i].tri == RS_NO_HIT || hits[i].tri == RS_NO_HIT) continue;
      if (margin(base_hits[i]) < 0.05f || margin(hits[i]) < 0.05f) continue;
      if (behind_hits[i].tri != RS_NO_HIT && behind_hits[i].t - base_hits[i].t < 0.05f) continue;
      ++compared;
      if (hits[i].tri != base_hits[i].tri) {
        ++changed;
        std::printf("changed ray %zu: %u (t %g, margin %g) -> %u (t %g, margin %g); behind %u t %g\n", i, base_hits[i].tri,
                    base_hits[i].t, margin(base_hits[i]), hits[i].tri, hits[i].t, margin(hits[i]), behind_hits[i].tri,
                    behind_hits[i].t);
      }
    }
    EXPECT_GT(compared, rays.size() / 3) << tf.what;
    EXPECT_EQ(changed, 0u) << tf.what;

    // Bounce 1: leave every hit along a cosine direction from its facing normal.
    std::vector<RsRay> bounce;
    std::vector<std::uint32_t> from;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (hits[i].tri == RS_NO_HIT) continue;
      const auto t = hits[i].tri;
      RsVec3 v0 = v3(flat.v0[t]), v1 = v3(flat.v1[t]), v2 = v3(flat.v2[t]);
      RsVec3 n = rs_facing_normal(v0, v1, v2, rs_vec3(rays[i].d[0], rays[i].d[1], rays[i].d[2]));
      RsVec3 o = rs_offset_ray_origin(rs_hit_point(v0, v1, v2, hits[i].u, hits[i].v), n);
      RsVec3 d = rs_cosine_direction(n, rs_uniform(rs_hash4(5, std::uint32_t(i), 0, 0)),
                                     rs_uniform(rs_hash4(5, std::uint32_t(i), 0, 1)));
      bounce.push_back(make_ray({o.x, o.y, o.z}, {d.x, d.y, d.z}));
      from.push_back(t);
    }
    for (TraceVariant v : kVariants) {
      auto bh = trace_reference(bvh, bounce, nullptr, false, nullptr, v);
      std::size_t self = 0;
      for (std::size_t i = 0; i < bounce.size(); ++i) {
        if (bh[i].tri == RS_NO_HIT) continue;
        // Same plane as the triangle it leaves: normals parallel and the hit triangle's vertices
        // on the source plane (within 1e-4 of the scene size).
        const auto s = from[i], h = bh[i].tri;
        RsVec3 ns = rs_normalize(rs_cross(rs_sub(v3(flat.v1[s]), v3(flat.v0[s])), rs_sub(v3(flat.v2[s]), v3(flat.v0[s]))));
        RsVec3 nh = rs_normalize(rs_cross(rs_sub(v3(flat.v1[h]), v3(flat.v0[h])), rs_sub(v3(flat.v2[h]), v3(flat.v0[h]))));
        float off = 0.0f;
        for (auto* vs : {&flat.v0, &flat.v1, &flat.v2})
          off = std::max(off, std::fabs(rs_dot(ns, rs_sub(v3((*vs)[h]), v3(flat.v0[s])))));
        self += std::fabs(rs_dot(ns, nh)) > 0.9999f && off < 1e-4f * 4.5f * tf.scale;
      }
      std::printf("[ scaled   ] %-14s %-6s %zu compared primary hits, %zu bounce rays, %zu self-intersections\n",
                  tf.what, trace_variant_name(v), compared, bounce.size(), self);
      if (v == TraceVariant::Robust) {
        EXPECT_EQ(self, 0u) << tf.what;
      }
    }
    // The same without a BVH: each bounce ray against the very triangle it leaves. No box can
    // cull it here, so this is the watertight test's t error bound at work (at scale 1e4 the
    // unbounded test re-hits its source for about 1 % of these rays).
    std::size_t own = 0;
    for (std::size_t i = 0; i < bounce.size(); ++i) {
      const auto s = from[i];
      RsTriangle tri{};
      for (int a = 0; a < 3; ++a) tri.v0[a] = flat.v0[s][a], tri.v1[a] = flat.v1[s][a], tri.v2[a] = flat.v2[s][a];
      const RsRobustRay rr = rs_prepare_robust_ray(bounce[i]);
      float t, u, v;
      own += rs_intersect_triangle_robust(&rr, bounce[i].d, &tri, bounce[i].tmax, &t, &u, &v);
    }
    EXPECT_EQ(own, 0u) << tf.what << ": bounce rays that hit the triangle they leave";
    {
    }
  }
}

namespace {

void expect_robust_device_equals_reference(const Scene& scene, const RayGenOptions& gen, std::size_t min_batches) {
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  Tracer tracer(testing::runtime(), bvh, TraceVariant::Robust);
  auto batches = generate_batches(scene, tris, bvh, gen);
  ASSERT_GE(batches.size(), min_batches) << scene.name;
  for (const auto& rb : batches) {
    const bool any = rb.batch.any_hit();
    auto ref = trace_reference(bvh, rb.batch.rays, nullptr, any, nullptr, TraceVariant::Robust);
    auto run = tracer.run(rb.batch.rays, nullptr, any);
    EXPECT_EQ(count_hit_mismatches(run.hits, ref), 0u) << scene.name << " " << rb.batch.name;
    std::vector<std::uint32_t> reversed(rb.batch.size());
    for (std::size_t i = 0; i < reversed.size(); ++i) reversed[i] = static_cast<std::uint32_t>(reversed.size() - 1 - i);
    auto rev = tracer.run(rb.batch.rays, &reversed, any);
    auto ref_rev = trace_reference(bvh, rb.batch.rays, reversed.data(), any, nullptr, TraceVariant::Robust);
    EXPECT_EQ(count_hit_mismatches(rev.hits, ref_rev), 0u) << "indirect order, " << scene.name << " " << rb.batch.name;
    // Robust and fast agree on almost every ray of an ordinary scene.
    std::size_t differ = 0;
    for (std::size_t i = 0; i < ref.size(); ++i) differ += ref[i].tri != rb.reference_hits[i].tri;
    EXPECT_LE(differ, ref.size() / 100 + 1) << scene.name << " " << rb.batch.name;
  }
}

}  // namespace

TEST(Robust, CornellEveryBatchMatchesReference) {
  expect_robust_device_equals_reference(load_scene("cornell", {"", {96, 72, 2}}), {}, 4);
}

TEST(Robust, DetailRoomEveryBatchMatchesReference) {
  expect_robust_device_equals_reference(load_scene("detail-room", {"", {64, 36, 0}}), {}, 3);
}

}  // namespace raysort
