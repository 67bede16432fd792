// Scene files of other formats (issue 45; scene/mesh_formats.h): PLY, glTF 2.0 and pbrt-v4 files,
// written here by the test into its temp folder, load with the triangles, bounds, camera and lights
// the file says, and trace on the device with 0 mismatches against the host twin; the same mesh as
// OBJ, PLY (ascii, both binary byte orders) and glTF (.gltf, .glb) gives the same BVH and hits;
// malformed files are refused in one line naming the file, the position and the fix.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "bvh/bvh.h"
#include "render/batches.h"
#include "scene/load.h"
#include "scene/mesh_formats.h"
#include "test_util.h"
#include "trace/tracer.h"
#include "util/error.h"

namespace fs = std::filesystem;
using namespace raysort;

namespace {

void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

template <class T>
void put(std::string& out, T v, bool big_endian = false) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
  out.append(b, sizeof(T));
}

// A height field over a 24×24 grid (1152 triangles) with dyadic coordinates, which every format
// (OBJ text included) carries exactly.
Mesh test_mesh() {
  Mesh m;
  const int n = 24;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.push_back({i / 8.0f, float((i * 7 + j * 3) % 11) / 16.0f, j / 8.0f});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = std::uint32_t(j * (n + 1) + i), b = a + 1, c = a + n + 1, d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  return m;
}

std::string obj_text(const Mesh& m) {
  std::string s;
  for (const auto& p : m.positions) s += fmt::format("v {} {} {}\n", p[0], p[1], p[2]);
  for (const auto& t : m.triangles) s += fmt::format("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  return s;
}

enum class PlyKind { Ascii, Little, Big };

std::string ply_bytes(const Mesh& m, PlyKind kind) {
  const char* format = kind == PlyKind::Ascii ? "ascii" : kind == PlyKind::Little ? "binary_little_endian" : "binary_big_endian";
  std::string s = fmt::format("ply\nformat {} 1.0\ncomment made by scene_formats_test\nelement vertex {}\nproperty float x\n"
                              "property float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\n"
                              "end_header\n",
                              format, m.positions.size(), m.triangles.size());
  const bool big = kind == PlyKind::Big;
  for (const auto& p : m.positions) {
    if (kind == PlyKind::Ascii) s += fmt::format("{} {} {}\n", p[0], p[1], p[2]);
    else for (float c : p) put(s, c, big);
  }
  for (const auto& t : m.triangles) {
    if (kind == PlyKind::Ascii) s += fmt::format("3 {} {} {}\n", t[0], t[1], t[2]);
    else {
      put(s, std::uint8_t(3));
      for (auto i : t) put(s, std::int32_t(i), big);
    }
  }
  return s;
}

// A glTF of `json` with its binary buffer, whose "uri" is written "@URI@": a .gltf beside a .bin
// file, or one .glb (the buffer in its BIN chunk, no uri).
void write_gltf(const std::string& path, std::string json, const std::string& bin, bool glb) {
  if (!glb) {
    json.replace(json.find("@URI@"), 5, fs::path(path).stem().string() + ".bin");
    write_file(path, json);
    write_file(fs::path(path).replace_extension(".bin").string(), bin);
    return;
  }
  const std::string no_uri = "\"uri\": \"@URI@\", ";
  json.erase(json.find(no_uri), no_uri.size());
  while (json.size() % 4) json += ' ';
  std::string data = bin;
  while (data.size() % 4) data += '\0';
  std::string out = "glTF";
  put(out, std::uint32_t(2));
  put(out, std::uint32_t(12 + 8 + json.size() + 8 + data.size()));
  put(out, std::uint32_t(json.size()));
  put(out, std::uint32_t(0x4E4F534A));
  out += json;
  put(out, std::uint32_t(data.size()));
  put(out, std::uint32_t(0x004E4942));
  out += data;
  write_file(path, out);
}

// The mesh as one glTF node: positions (float VEC3) then indices (unsigned int).
void write_gltf_mesh(const std::string& path, const Mesh& m, bool glb) {
  std::string bin;
  Aabb box;
  for (const auto& p : m.positions) {
    box.grow(p);
    for (float c : p) put(bin, c);
  }
  const std::size_t positions = bin.size();
  for (const auto& t : m.triangles)
    for (auto i : t) put(bin, std::uint32_t(i));
  const std::string json = fmt::format(
      R"({{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
"meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
"buffers": [{{"uri": "@URI@", "byteLength": {}}}],
"bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": {}}}, {{"buffer": 0, "byteOffset": {}, "byteLength": {}}}],
"accessors": [{{"bufferView": 0, "componentType": 5126, "count": {}, "type": "VEC3", "min": [{}, {}, {}], "max": [{}, {}, {}]}},
              {{"bufferView": 1, "componentType": 5125, "count": {}, "type": "SCALAR"}}]}})",
      bin.size(), positions, positions, bin.size() - positions, m.positions.size(), box.min[0], box.min[1], box.min[2],
      box.max[0], box.max[1], box.max[2], 3 * m.triangles.size());
  write_gltf(path, json, bin, glb);
}

std::string temp_dir(const std::string& name) {
  const std::string d = raysort::testing::temp_path(name);
  fs::create_directories(d);
  return d;
}

void expect_near(const Vec3& a, const Vec3& b, const std::string& what) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-5) << what << " [" << k << "]";
}

// Device trace of every batch of the scene's frame against the host twin (as trace_test does).
void expect_traces_like_host(const Scene& scene) {
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  Tracer tracer(raysort::testing::runtime(), bvh);
  auto batches = generate_batches(scene, tris, bvh, {});
  ASSERT_FALSE(batches.empty());
  std::size_t hits = 0;
  for (const auto& rb : batches) {
    auto run = tracer.run(rb.batch.rays, nullptr, rb.batch.any_hit());
    EXPECT_EQ(count_hit_mismatches(run.hits, rb.reference_hits), 0u) << scene.name << " " << rb.batch.name;
    if (rb.batch.name == "primary")
      for (const auto& h : rb.reference_hits) hits += h.tri != RS_NO_HIT;
  }
  EXPECT_GT(hits, 0u) << scene.name << ": the primary rays hit nothing, which would test little";
}

Scene load_small(const std::string& path) {
  SceneOptions opts;
  opts.frame = {96, 64, 0};
  return load_scene(path, opts);
}

}  // namespace

TEST(SceneFormats, IgnoredFeaturesAreCountedOnceInFirstSeenOrder) {
  IgnoredFeatures f;
  EXPECT_EQ(f.summary(), "");
  f.add("Shape \"curve\"");
  f.add("Texture");
  f.add("Shape \"curve\"", 2);
  EXPECT_EQ(f.summary(), "ignored: 3 Shape \"curve\", 1 Texture");
}

TEST(SceneFormats, SameMeshInEveryFormatGivesIdenticalBvhAndHits) {
  const std::string dir = temp_dir("same-mesh");
  const Mesh mesh = test_mesh();
  const std::vector<std::string> files = {dir + "/m.obj", dir + "/ascii.ply", dir + "/le.ply", dir + "/be.ply",
                                          dir + "/m.gltf", dir + "/m.glb"};
  write_file(files[0], obj_text(mesh));
  write_file(files[1], ply_bytes(mesh, PlyKind::Ascii));
  write_file(files[2], ply_bytes(mesh, PlyKind::Little));
  write_file(files[3], ply_bytes(mesh, PlyKind::Big));
  write_gltf_mesh(files[4], mesh, false);
  write_gltf_mesh(files[5], mesh, true);
  const Scene reference = load_small(files[0]);
  const Scene::Flat ref_tris = reference.flatten();
  ASSERT_EQ(ref_tris.size(), mesh.triangles.size());
  const Bvh ref_bvh = build_bvh(ref_tris);
  const auto ref_batches = generate_batches(reference, ref_tris, ref_bvh, {});
  for (std::size_t f = 1; f < files.size(); ++f) {
    const Scene s = load_small(files[f]);
    const Scene::Flat tris = s.flatten();
    ASSERT_EQ(tris.size(), ref_tris.size()) << files[f];
    EXPECT_EQ(std::memcmp(tris.v0.data(), ref_tris.v0.data(), tris.size() * sizeof(Vec3)), 0) << files[f];
    EXPECT_EQ(std::memcmp(tris.v1.data(), ref_tris.v1.data(), tris.size() * sizeof(Vec3)), 0) << files[f];
    EXPECT_EQ(std::memcmp(tris.v2.data(), ref_tris.v2.data(), tris.size() * sizeof(Vec3)), 0) << files[f];
    const Bvh bvh = build_bvh(tris);
    ASSERT_EQ(bvh.nodes.size(), ref_bvh.nodes.size()) << files[f];
    EXPECT_EQ(std::memcmp(bvh.nodes.data(), ref_bvh.nodes.data(), bvh.nodes.size() * sizeof(RsBvhNode)), 0) << files[f];
    EXPECT_EQ(std::memcmp(bvh.triangles.data(), ref_bvh.triangles.data(), bvh.triangles.size() * sizeof(RsTriangle)), 0)
        << files[f];
    const auto batches = generate_batches(s, tris, bvh, {});
    ASSERT_EQ(batches.size(), ref_batches.size()) << files[f];
    for (std::size_t b = 0; b < batches.size(); ++b) {
      ASSERT_EQ(batches[b].reference_hits.size(), ref_batches[b].reference_hits.size()) << files[f];
      EXPECT_EQ(count_hit_mismatches(batches[b].reference_hits, ref_batches[b].reference_hits), 0u)
          << files[f] << " " << batches[b].batch.name;
    }
  }
  expect_traces_like_host(load_small(files[5]));
}

TEST(SceneFormats, GltfLoadsItsHierarchyMaterialsAndCamera) {
  const std::string dir = temp_dir("gltf-scene");
  std::string bin;
  for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 1.f, 0.f}) put(bin, c);  // quad, 48 B
  for (std::uint16_t i : {0, 1, 2, 0, 2, 3}) put(bin, i);                                   // 12 B
  for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(bin, c);                // triangle, 36 B
  const double r = std::sqrt(0.5);
  const std::string json = fmt::format(R"({{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 3, 4]}}],
"extensionsUsed": ["KHR_materials_emissive_strength"],
"nodes": [{{"translation": [10, 0, 0], "children": [1, 2]}}, {{"mesh": 0, "scale": [2, 2, 2]}},
          {{"mesh": 0, "rotation": [0, -{}, 0, {}]}}, {{"camera": 0, "translation": [11, 1, 5]}},
          {{"mesh": 1, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -3, 1]}}],
"cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "aspectRatio": 2.0, "znear": 0.1}}}}],
"materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [1, 0, 0, 1]}}}}, {{"pbrMetallicRoughness": {{"baseColorFactor": [0, 0, 1, 1]}}}}],
"meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}},
           {{"primitives": [{{"attributes": {{"POSITION": 2}}, "material": 1}}, {{"attributes": {{"POSITION": 2}}, "mode": 0}}]}}],
"buffers": [{{"uri": "@URI@", "byteLength": 96}}],
"bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 12}},
                {{"buffer": 0, "byteOffset": 60, "byteLength": 36}}],
"accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
              {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}},
              {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}]}})",
                                       r, r);
  for (bool glb : {false, true}) {
    const std::string path = dir + (glb ? "/scene.glb" : "/scene.gltf");
    write_gltf(path, json, bin, glb);
    const ForeignScene f = load_gltf(path);
    EXPECT_EQ(f.ignored.summary(), "ignored: 1 extension \"KHR_materials_emissive_strength\", 1 primitive of mode 0 (points or lines)");
    const Scene s = load_small(path);
    EXPECT_EQ(s.triangle_count(), 5u) << path;  // the quad twice (2 + 2), the triangle once
    EXPECT_EQ(s.instances.size(), 3u);
    const Aabb b = s.bounds();
    expect_near(b.min, {0, 0, -3}, path + " min");
    expect_near(b.max, {12, 2, 1}, path + " max");  // node 2's quad turned −90° about y reaches z = 1
    ASSERT_EQ(s.materials.size(), 3u);
    EXPECT_EQ(s.materials[1].albedo, (Vec3{1, 0, 0}));
    EXPECT_EQ(s.materials[2].albedo, (Vec3{0, 0, 1}));
    ASSERT_TRUE(f.has_camera);
    expect_near(f.scene.camera.position, {11, 1, 5}, "camera position");
    expect_near(f.scene.camera.look_at, {11, 1, 4}, "camera look_at");
    expect_near(f.scene.camera.up, {0, 1, 0}, "camera up");
    EXPECT_NEAR(f.scene.camera.fov_y_deg, 0.8 * 180 / 3.14159265358979, 1e-4);
    EXPECT_EQ(f.scene.camera.height, 960u);  // 1920 / aspectRatio 2
    EXPECT_TRUE(s.sky.enabled);             // no lights in the file: a sky
    expect_traces_like_host(s);
  }
}

TEST(SceneFormats, PlyLoadsPolygonsAndListsWhatItIgnores) {
  const std::string path = temp_dir("ply-scene") + "/box.ply";
  write_file(path, R"(ply
format ascii 1.0
element vertex 8
property float x
property float y
property float z
property uchar red
element face 6
property list uchar int vertex_indices
element edge 2
property int vertex1
property int vertex2
end_header
-1 -1 -1 255
1 -1 -1 0
1 1 -1 0
-1 1 -1 0
-1 -1 1 0
1 -1 1 0
1 1 1 0
-1 1 1 0
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 2 3 7 6
4 0 4 7 3
4 1 2 6 5
0 1
1 2
)");
  const ForeignScene f = load_ply(path);
  EXPECT_EQ(f.ignored.summary(), "ignored: 1 vertex property \"red\", 2 element \"edge\"");
  EXPECT_FALSE(f.has_camera);
  const Scene s = load_small(path);
  EXPECT_EQ(s.triangle_count(), 12u);  // six quads
  expect_near(s.bounds().min, {-1, -1, -1}, "min");
  expect_near(s.bounds().max, {1, 1, 1}, "max");
  // No camera in a PLY: one framing the box, looking at its centre.
  expect_near(s.camera.look_at, {0, 0, 0}, "framing camera");
  // Seen from outside, the closed box is hit by every primary ray that meets it.
  expect_traces_like_host(s);
}

TEST(SceneFormats, PbrtLoadsGeometryCameraLightsAndIncludes) {
  const std::string dir = temp_dir("pbrt-scene");
  Mesh floor;
  floor.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
  std::string ply = "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
  for (const auto& p : floor.positions)
    for (float c : p) put(ply, c, true);
  put(ply, std::uint8_t(4));
  for (std::uint32_t i : {0u, 1u, 2u, 3u}) put(ply, i, true);
  write_file(dir + "/floor.ply", ply);
  write_file(dir + "/floor.pbrt", "AttributeBegin\n  Scale 4 1 4\n  Shape \"plymesh\" \"string filename\" \"floor.ply\"\nAttributeEnd\n");
  write_file(dir + "/main.pbrt", R"(# a test scene
Film "rgb" "integer xresolution" [320] "integer yresolution" [240] "string filename" "x.exr"
LookAt 0 1 6  0 1 0  0 1 0
Camera "perspective" "float fov" [40]
Sampler "halton"
WorldBegin
LightSource "infinite" "rgb L" [0.2 0.3 0.4]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 4 4]
  Translate 0 3 0
  Shape "trianglemesh" "point3 P" [-0.5 0 -0.5  0.5 0 -0.5  0.5 0 0.5  -0.5 0 0.5] "integer indices" [0 1 2 0 2 3]
AttributeEnd
LightSource "point" "point3 from" [1 2 3] "rgb I" [5 5 5]
Material "diffuse" "rgb reflectance" [0.2 0.4 0.6]
Include "floor.pbrt"
Texture "checks" "spectrum" "checkerboard"
Shape "sphere" "float radius" 1
ObjectBegin "tri"
  Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0]
ObjectEnd
AttributeBegin
  Translate 2 0 0
  ObjectInstance "tri"
AttributeEnd
AttributeBegin
  Translate -2 0 0
  Scale 2 2 2
  ObjectInstance "tri"
AttributeEnd
)");
  const ForeignScene f = load_pbrt(dir + "/main.pbrt");
  EXPECT_EQ(f.ignored.summary(), "ignored: 1 Sampler, 1 Texture, 1 Shape \"sphere\"");
  const Scene s = load_small(dir + "/main.pbrt");
  EXPECT_EQ(s.triangle_count(), 6u);  // the light's quad, the floor's quad, the triangle twice
  expect_near(s.bounds().min, {-4, 0, -4}, "min");
  expect_near(s.bounds().max, {4, 3, 4}, "max");
  ASSERT_TRUE(f.has_camera);
  expect_near(f.scene.camera.position, {0, 1, 6}, "camera position");
  expect_near(f.scene.camera.look_at, {0, 1, 5}, "camera look_at");
  expect_near(f.scene.camera.up, {0, 1, 0}, "camera up");
  EXPECT_FLOAT_EQ(f.scene.camera.fov_y_deg, 40.0f);  // the shorter axis is the vertical one
  EXPECT_EQ(f.scene.camera.width, 320u);
  EXPECT_EQ(f.scene.camera.height, 240u);
  EXPECT_TRUE(s.sky.enabled);
  expect_near(s.sky.zenith, {0.2f, 0.3f, 0.4f}, "sky");
  ASSERT_EQ(s.sphere_lights.size(), 2u);  // the point light, then the area light (made at the end)
  expect_near(s.sphere_lights[0].center, {1, 2, 3}, "point light");
  expect_near(s.sphere_lights[1].center, {0, 3, 0}, "area light");
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[1].albedo, (Vec3{0.2f, 0.4f, 0.6f}));
  expect_traces_like_host(s);
}

TEST(SceneFormats, SceneTomlNamesAMeshFile) {
  const std::string dir = temp_dir("toml-mesh");
  const Mesh mesh = test_mesh();
  write_gltf_mesh(dir + "/m.glb", mesh, true);
  write_file(dir + "/m.ply", ply_bytes(mesh, PlyKind::Little));
  write_file(dir + "/s.toml", fmt::format(R"(name = "t"
[camera]
position = [1.5, 3.0, 6.0]
look_at = [1.5, 0.0, 1.5]
[[mesh]]
name = "a"
file = "{0}/m.glb"
[[mesh]]
name = "b"
obj = "{0}/m.ply"
)", dir));
  const Scene s = load_scene(dir + "/s.toml");
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(s.triangle_count(), 2 * mesh.triangles.size());
  EXPECT_EQ(s.meshes[0].positions, mesh.positions);
  EXPECT_EQ(s.meshes[1].positions, mesh.positions);
}

TEST(SceneFormats, MalformedFilesAreRefusedInOneLineWithFilePositionAndFix) {
  const std::string dir = temp_dir("malformed");
  std::string truncated = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nend_header\n";
  const std::size_t body = truncated.size();
  truncated += std::string(20, '\0');  // 3 vertices need 36 bytes
  std::string glb = "glTF";
  put(glb, std::uint32_t(2));
  put(glb, std::uint32_t(999));  // not the file's length
  put(glb, std::uint32_t(4));
  put(glb, std::uint32_t(0x4E4F534A));
  glb += "{}  ";
  struct Case {
    std::string name, bytes, position, detail;
  };
  const std::vector<Case> cases = {
      {"index.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
       "index.ply:13:", "refers to vertex 7"},
      {"header.ply", "ply\nformat ascii 2.0\nend_header\n", "header.ply:2:", "format"},
      {"truncated.ply", truncated, fmt::format("byte {}:", body), "declares 3 records, more than the 20 bytes left"},
      {"json.gltf", "{\"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [}", "line 2", "cannot read glTF file"},
      {"length.glb", glb, "byte 8:", "the header gives the length 999"},
      // A camera node scaled to 0: no view direction (the file's camera gets the TOML camera's checks).
      {"camera.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"scenes\": [{\"nodes\": [0, 1]}], \"nodes\": [{\"mesh\": 0}, {\"camera\": 0, \"scale\": [0, 0, 0]}], \"cameras\": [{\"type\": \"perspective\", \"perspective\": {\"yfov\": 0.8, \"znear\": 0.1}}], \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}], \"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}], \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}], \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}]}",
       "the file's camera (its look_at)", "equals the camera position"},
      {"index.pbrt", "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 5]\n",
       "index.pbrt:2:", "index 5"},
      {"string.pbrt", "WorldBegin\n\nShape \"trianglemesh\" \"point3 P [0 0 0 1 0 0 0 1 0]\n", "string.pbrt:3:", "not closed"},
      {"attribute.pbrt", "WorldBegin\nAttributeEnd\n", "attribute.pbrt:2:", "without its AttributeBegin"},
  };
  for (const Case& c : cases) {
    const std::string path = dir + "/" + c.name;
    write_file(path, c.bytes);
    try {
      load_scene(path);
      ADD_FAILURE() << c.name << " loaded";
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      EXPECT_NE(m.find(path), std::string::npos) << m;
      EXPECT_NE(m.find(c.position), std::string::npos) << c.name << ": " << m;
      EXPECT_NE(m.find(c.detail), std::string::npos) << c.name << ": " << m;
      EXPECT_NE(m.find("fix"), std::string::npos) << c.name << ": " << m;
    }
  }
  // Through the command line: one line on stderr, exit 1.
  const auto r = raysort::testing::run_cli({"scenes", "--describe", dir + "/index.ply"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("index.ply:13: face 0 property vertex_indices refers to vertex 7"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}
