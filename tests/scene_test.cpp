// Scene loading: the TOML parser's error messages, OBJ checks, procedural determinism and sizes,
// bare OBJ paths, and the real scenes when the scene root is there.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "scene/load.h"
#include "scene/procedural.h"
#include "scene/provenance.h"
#include "util/error.h"
#include "util/host_memory.h"
#include "test_util.h"

namespace fs = std::filesystem;
using namespace raysort;

namespace {

// A valid scene; tests append or replace lines to break it.
const std::string kValid = R"(name = "t"
[camera]
position = [0.0, 1.0, 3.0]
look_at = [0.0, 1.0, 0.0]
fov_y = 40.0

[[mesh]]
name = "floor"
generator = "plane"
[mesh.params]
size_x = 4.0
size_z = 4.0

[[sphere_light]]
center = [0.0, 2.0, 0.0]
radius = 0.05
)";

// The message of the Error that parsing `text` throws ("" when it does not throw).
std::string parse_error(const std::string& text) {
  try {
    parse_scene_toml(text, "bad.toml", {});
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return s.replace(pos, from.size(), to);
}

fs::path temp_dir(const std::string& name) {
  fs::path dir = raysort::testing::temp_path(name);  // removed when every test passed
  fs::create_directories(dir);
  return dir;
}

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

bool same_triangles(const Scene& a, const Scene& b) {
  auto fa = a.flatten(), fb = b.flatten();
  return fa.v0 == fb.v0 && fa.v1 == fb.v1 && fa.v2 == fb.v2 && fa.material == fb.material;
}

}  // namespace

TEST(SceneToml, ValidSceneParses) {
  Scene s = parse_scene_toml(kValid, "ok.toml", {});
  EXPECT_EQ(s.name, "t");
  EXPECT_EQ(s.triangle_count(), 2u);
  EXPECT_EQ(s.camera.width, 1920u);
  EXPECT_EQ(s.camera.height, 1080u);
  ASSERT_EQ(s.sphere_lights.size(), 1u);
  EXPECT_FLOAT_EQ(s.sphere_lights[0].radius(s.bounds().largest_extent()), 0.2f);
}

TEST(SceneToml, OptionsOverrideResolutionAndSpp) {
  SceneOptions o;
  o.frame = {64, 32, 4};
  Scene s = parse_scene_toml(kValid, "ok.toml", o);
  EXPECT_EQ(s.camera.width, 64u);
  EXPECT_EQ(s.camera.height, 32u);
  EXPECT_EQ(s.effects.samples_per_pixel, 4u);
}

TEST(SceneToml, UnknownKeyNamesLineAndKey) {
  std::string msg = parse_error(replace(kValid, "fov_y = 40.0", "fov_y = 40.0\nfovy = 3.0"));
  EXPECT_NE(msg.find("bad.toml:6:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("camera.fovy"), std::string::npos) << msg;
}

TEST(SceneToml, WrongTypeNamesLineAndKey) {
  std::string msg = parse_error(replace(kValid, "fov_y = 40.0", "fov_y = \"wide\""));
  EXPECT_NE(msg.find("bad.toml:5:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("camera.fov_y"), std::string::npos) << msg;
  EXPECT_NE(msg.find("a string"), std::string::npos) << msg;
}

TEST(SceneToml, MissingRequiredKeyNamesTableLineAndKey) {
  std::string msg = parse_error(replace(kValid, "look_at = [0.0, 1.0, 0.0]\n", ""));
  EXPECT_NE(msg.find("bad.toml:2:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("look_at"), std::string::npos) << msg;
}

TEST(SceneToml, BadMeshReferenceNamesLineAndMesh) {
  std::string msg = parse_error(kValid + "\n[[instance]]\nmesh = \"flor\"\n");
  EXPECT_NE(msg.find("bad.toml:19:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("instance[0].mesh"), std::string::npos) << msg;
  EXPECT_NE(msg.find("flor"), std::string::npos) << msg;
  EXPECT_NE(msg.find("floor"), std::string::npos) << msg;  // lists the meshes there are
}

TEST(SceneToml, NegativeRadiusNamesLineAndKey) {
  std::string msg = parse_error(replace(kValid, "radius = 0.05", "radius = -0.05"));
  EXPECT_NE(msg.find("bad.toml:16:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("sphere_light[0].radius"), std::string::npos) << msg;
}

TEST(SceneToml, OtherValidation) {
  EXPECT_NE(parse_error(replace(kValid, "fov_y = 40.0", "fov_y = 180.0")).find("camera.fov_y"), std::string::npos);
  EXPECT_NE(parse_error(replace(kValid, "fov_y = 40.0", "resolution = [0, 100]")).find("camera.resolution"),
            std::string::npos);
  EXPECT_NE(parse_error(replace(kValid, "radius = 0.05", "radius = 0.0")).find("radius"), std::string::npos);
  EXPECT_NE(parse_error(replace(kValid, "generator = \"plane\"", "generator = \"plain\"")).find("displaced_sphere"),
            std::string::npos);  // lists the generators
  EXPECT_NE(parse_error(replace(kValid, "size_x = 4.0", "sise_x = 4.0")).find("sise_x"), std::string::npos);
  EXPECT_NE(parse_error(kValid + "[effects]\nmax_bounces = -1\n").find("effects.max_bounces"), std::string::npos);
  std::string syntax = parse_error(replace(kValid, "fov_y = 40.0", "fov_y = = 40"));
  EXPECT_NE(syntax.find("bad.toml:5:"), std::string::npos) << syntax;
}

TEST(SceneToml, ScatterIsDeterministicAndStandsOnGround) {
  std::string text = kValid + R"(
[[mesh]]
name = "rock"
generator = "rock"
draw = false

[[scatter]]
mesh = "rock"
count = 50
seed = 9
min = [-1.5, -10.0, -1.5]
max = [1.5, 10.0, 1.5]
ground = "floor"
scale = [0.5, 1.0]
)";
  Scene a = parse_scene_toml(text, "s.toml", {}), b = parse_scene_toml(text, "s.toml", {});
  ASSERT_EQ(a.instances.size(), 51u);  // the floor + 50 rocks
  EXPECT_TRUE(same_triangles(a, b));
  for (std::size_t i = 1; i < a.instances.size(); ++i) EXPECT_FLOAT_EQ(a.instances[i].transform.m[7], 0.0f);
  std::string off = parse_error(replace(text, "max = [1.5, 10.0, 1.5]", "max = [9.0, 10.0, 9.0]"));
  EXPECT_NE(off.find("scatter[0].ground"), std::string::npos) << off;
}

TEST(SceneObj, MissingObjNamesPathAndRoot) {
  SceneOptions o;
  o.scene_root = "/nonexistent/scene-root";
  std::string text = replace(kValid, "generator = \"plane\"\n[mesh.params]\nsize_x = 4.0\nsize_z = 4.0\n",
                             "obj = \"nowhere/missing.obj\"\n");
  try {
    parse_scene_toml(text, "bad.toml", o);
    FAIL() << "no error";
  } catch (const Error& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("/nonexistent/scene-root/nowhere/missing.obj"), std::string::npos) << msg;
    EXPECT_NE(msg.find("--scene-root"), std::string::npos) << msg;
    EXPECT_NE(msg.find("RAYSORT_SCENE_ROOT"), std::string::npos) << msg;
    EXPECT_NE(msg.find("bad.toml:9:"), std::string::npos) << msg;
  }
}

TEST(SceneObj, NanVertexRejectedWithIndex) {
  fs::path dir = temp_dir("nan");
  write_file(dir / "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
  std::vector<Material> mats;
  try {
    load_obj((dir / "nan.obj").string(), mats);
    FAIL() << "no error";
  } catch (const Error& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("nan.obj:3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("vertex 3"), std::string::npos) << msg;
  }
  write_file(dir / "inf.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_THROW(load_obj((dir / "inf.obj").string(), mats), Error);
}

TEST(SceneObj, BadIndexAndEmptyFileRejected) {
  fs::path dir = temp_dir("bad");
  write_file(dir / "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
  write_file(dir / "empty.obj", "v 0 0 0\n");
  std::vector<Material> mats;
  try {
    load_obj((dir / "range.obj").string(), mats);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 9"), std::string::npos) << e.what();
  }
  try {
    load_obj((dir / "empty.obj").string(), mats);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("empty.obj"), std::string::npos) << e.what();
  }
}

TEST(SceneObj, PolygonsTriangulatedAndMaterialsRead) {
  fs::path dir = temp_dir("poly");
  write_file(dir / "m.mtl", "newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0.1 0.1 0.8\n");
  write_file(dir / "poly.obj",
             "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nusemtl blue\nf 1 2 3 4\nusemtl red\n"
             "f 1 2 3 4 5\nf -3 -2 -1\n");
  std::vector<Material> mats{Material{}};
  Mesh m = load_obj((dir / "poly.obj").string(), mats);
  EXPECT_EQ(m.triangles.size(), 2u + 3u + 1u);  // an n-gon gives n - 2 triangles
  ASSERT_EQ(mats.size(), 3u);
  ASSERT_EQ(m.material.size(), m.triangles.size());
  EXPECT_EQ(mats[m.material[0]].name, "blue");
  EXPECT_EQ(mats[m.material[5]].name, "red");
  EXPECT_FLOAT_EQ(mats[m.material[5]].albedo[0], 0.8f);
}

TEST(SceneObj, BareObjPathGetsCameraAndSky) {
  fs::path dir = temp_dir("bare");
  write_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n");
  Scene s = load_scene((dir / "tri.obj").string());
  EXPECT_EQ(s.name, "tri");
  EXPECT_EQ(s.triangle_count(), 2u);
  EXPECT_TRUE(s.sky.enabled);
  EXPECT_TRUE(s.sphere_lights.empty());
  EXPECT_EQ(s.effects.max_bounces, 1u);
  // The camera is outside the box, looking at its centre.
  Aabb b = s.bounds();
  bool outside = false;
  for (int a = 0; a < 3; ++a) outside = outside || s.camera.position[a] > b.max[a];
  EXPECT_TRUE(outside);
}

TEST(SceneLookup, UnknownNameListsScenes) {
  try {
    load_scene("no-such-scene");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cornell"), std::string::npos) << e.what();
  }
}

TEST(SceneProcedural, GeneratorsAreDeterministic) {
  for (const auto& name : generator_names()) {
    Mesh a = generate_mesh(name, {}, 17), b = generate_mesh(name, {}, 17);
    EXPECT_GT(a.triangles.size(), 0u) << name;
    EXPECT_EQ(a.positions, b.positions) << name;
    EXPECT_EQ(a.triangles, b.triangles) << name;
    for (const auto& t : a.triangles)
      for (auto i : t) ASSERT_LT(i, a.positions.size()) << name;
  }
}

// Scenes are stored as float: a number past its range would turn into inf (and NaN where a
// transform multiplies it by 0). Found by fuzz/scene_fuzzer: a box generator's `max` of 7.8e74
// made inf vertices, NaN after the identity transform, and an undefined float-to-int cast in the
// scatter's ground grid (input kept as fuzz/corpus/scene/regression-inf-box-max.toml).
TEST(SceneToml, NumbersBeyondTheFloatRangeAreRefused) {
  std::string msg = parse_error(replace(kValid, "position = [0.0, 1.0, 3.0]", "position = [0.0, 1e39, 3.0]"));
  EXPECT_NE(msg.find("bad.toml:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("beyond the float range"), std::string::npos) << msg;
  msg = parse_error(replace(kValid, "generator = \"plane\"", "generator = \"box\""));  // plane params on a box
  EXPECT_NE(msg.find("has no number parameter 'size_x'"), std::string::npos) << msg;
  msg = parse_error(replace(replace(kValid, "generator = \"plane\"", "generator = \"box\""),
                            "size_x = 4.0\nsize_z = 4.0", "max = [5.0, 7.8e74, 6.0]"));
  EXPECT_NE(msg.find("'mesh[0].params.max' = 7.8e+74 is not a finite number within the float range"),
            std::string::npos)
      << msg;
  // Each number in range, their product not: a plane of 4 scaled by 3e38.
  msg = parse_error(kValid + "\n[[instance]]\nmesh = \"floor\"\nscale = [3e38, 1.0, 1.0]\n");
  EXPECT_NE(msg.find("a placement of mesh 'floor' (a drawn mesh or an [[instance]]) reaches coordinates beyond"),
            std::string::npos)
      << msg;
  msg = parse_error(kValid + "\n[[scatter]]\nmesh = \"floor\"\ncount = 2\nmin = [0.0, 0.0, 0.0]\n"
                             "max = [1.0, 0.0, 1.0]\nscale = 3e38\n");
  EXPECT_NE(msg.find("(a [[scatter]]) reaches coordinates beyond"), std::string::npos) << msg;
  // The fuzzer's input itself: an Error, not a sanitizer report.
  std::ifstream in(std::string(RAYSORT_SOURCE_DIR) + "/fuzz/corpus/scene/regression-inf-box-max.toml");
  ASSERT_TRUE(in) << "fuzz/corpus/scene/regression-inf-box-max.toml is missing";
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  SceneOptions o;
  o.scene_root = "/nonexistent";
  EXPECT_THROW(parse_scene_toml(text, "regression.toml", o), Error);
}

// generated_triangle_count is what a scene refuses sizes by before it builds them: an upper bound of
// what generate_mesh makes, and close to it (poles and open faces drop a few).
TEST(SceneProcedural, TriangleCountsBoundWhatTheGeneratorsMake) {
  for (const auto& name : generator_names()) {
    const std::size_t made = generate_mesh(name, {}, 17).triangles.size();
    const std::uint64_t counted = generated_triangle_count(name, {});
    EXPECT_GE(counted, made) << name;
    EXPECT_LE(counted, made + made / 50 + 2) << name;
  }
  GeneratorParams big;
  big.numbers["resolution"] = 8192;
  EXPECT_EQ(generated_triangle_count("heightfield", big), 2ull * 8192 * 8192);
  GeneratorParams bad;
  bad.numbers["resolution"] = 1e9;
  EXPECT_THROW(generated_triangle_count("heightfield", bad), Error);  // the same range check as the build
  EXPECT_THROW(generated_triangle_count("no-such-generator", {}), Error);
}

// A size a user can type in a scene file (a mesh's resolution, a scatter's count) that would not
// fit is refused before it is made: ResourceError naming the file, line, triangles and the fix, at
// once and without the memory (issue 23, "no internal error for any size a user can type").
TEST(SceneToml, OversizedMeshesAndScattersAreRefusedBeforeTheyAreMade) {
  auto refusal = [](const std::string& text, const SceneOptions& o) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      parse_scene_toml(text, "big.toml", o);
    } catch (const ResourceError& e) {
      EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
      return std::string(e.what());
    }
    ADD_FAILURE() << "not refused";
    return std::string();
  };
  // 2 × 8192² triangles ≈ 64 GiB: over any host this test runs on.
  const std::string terrain = replace(replace(kValid, "generator = \"plane\"", "generator = \"heightfield\""),
                                      "size_x = 4.0\nsize_z = 4.0", "resolution = 8192");
  std::string msg = refusal(terrain, {});
  for (const char* part : {"big.toml:9:", "134217728 triangles", "mesh 'floor' (heightfield", "of host memory available",
                           "lower its params"})
    EXPECT_NE(msg.find(part), std::string::npos) << "no '" << part << "' in " << msg;
  // Ten million icosphere rocks of 327,680 triangles each.
  const std::string scatter = kValid + R"(
[[mesh]]
name = "rock"
generator = "rock"
draw = false
[mesh.params]
subdivisions = 7

[[scatter]]
mesh = "rock"
count = 10000000
min = [-1.0, 0.0, -1.0]
max = [1.0, 0.0, 1.0]
)";
  msg = refusal(scatter, {});
  for (const char* part : {"big.toml:27:", "scatter[0] (10000000 × mesh 'rock')", "lower its count"})
    EXPECT_NE(msg.find(part), std::string::npos) << "no '" << part << "' in " << msg;
  // SceneOptions::max_triangles caps a load below the memory (the scene fuzzer's cap): the plane's
  // 2 triangles pass a cap of 2, a 2 × 2 grid (8) does not, and the refusal names the cap.
  SceneOptions capped;
  capped.max_triangles = 2;
  EXPECT_EQ(parse_scene_toml(kValid, "ok.toml", capped).triangle_count(), 2u);
  msg = refusal(replace(kValid, "size_z = 4.0", "size_z = 4.0\nsegments_x = 2\nsegments_z = 2"), capped);
  EXPECT_NE(msg.find("over the limit of 2 triangles set for this load"), std::string::npos) << msg;
}

// The paper-size stand-ins (scenes/paper-size/, issue 45 item 3): their terrains hold the paper's
// sizes (the landscape scene's 21.84 M triangles and San Miguel's 5.6 M with landscape's 168 K of
// rocks and trees), read without building them: a load capped at 1,000 triangles is refused at the
// terrain, naming its count, in under a second.
TEST(SceneToml, PaperSizeStandInsHoldThePapersTriangleCounts) {
  SceneOptions capped;
  capped.max_triangles = 1000;
  for (const auto& [file, terrain] : {std::pair<const char*, const char*>{"landscape-21m.toml", "21674528 triangles"},
                                      std::pair<const char*, const char*>{"landscape-5m.toml", "5431808 triangles"}}) {
    const std::string path = std::string(RAYSORT_SOURCE_DIR) + "/scenes/paper-size/" + file;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      load_scene(path, capped);
      ADD_FAILURE() << file << ": not refused";
    } catch (const ResourceError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(std::string("would hold ") + terrain + " with mesh 'terrain' (heightfield"), std::string::npos)
          << msg;
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0) << file;
  }
}

// The embedded procedural scenes: deterministic, at least their triangle budgets, fast to load.
TEST(SceneProcedural, EmbeddedScenesMeetTheirBudgets) {
  struct Want {
    const char* name;
    std::size_t min_triangles, max_triangles;
  };
  for (Want w : {Want{"cornell", 10, 999}, Want{"detail-room", 300'000, 2'000'000},
                 Want{"landscape", 500'000, 3'000'000}, Want{"multi-instance", 300'000, 2'000'000}}) {
    auto t0 = std::chrono::steady_clock::now();
    Scene a = load_scene(w.name);
    double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    Scene b = load_scene(w.name);
    EXPECT_GE(a.triangle_count(), w.min_triangles) << w.name;
    EXPECT_LE(a.triangle_count(), w.max_triangles) << w.name;
    EXPECT_TRUE(same_triangles(a, b)) << w.name;
    EXPECT_EQ(a.camera.width, 1920u) << w.name;
    EXPECT_EQ(a.effects.max_bounces, 1u) << w.name;
    EXPECT_FALSE(a.sphere_lights.empty()) << w.name;
    // The budget is 2 s on a 2-core machine in a Release build; leave room for slow CI runners.
    EXPECT_LT(s, 6.0) << w.name;
  }
}

TEST(SceneLookup, EveryListedSceneParses) {
  // Every embedded scene file is well-formed (real ones need the scene root only for their OBJs).
  auto listings = list_scenes();
  EXPECT_GE(listings.size(), 13u);
  for (const auto& l : listings) {
    if (l.needs_scene_root) continue;
    EXPECT_NO_THROW(load_scene(l.name)) << l.name;
  }
}

// A scene file may extend another: it takes the base's tables and replaces those it gives whole.
TEST(SceneToml, ExtendsTakesTheBaseAndReplacesWholeTables) {
  const Scene base = load_scene("cornell");
  const Scene narrow = parse_scene_toml("extends = \"cornell\"\n[camera]\nposition = [0.0, 1.0, 3.0]\n"
                                        "look_at = [0.0, 1.0, 0.0]\nfov_y = 10.0\n",
                                        "narrow.toml", {});
  EXPECT_EQ(narrow.triangle_count(), base.triangle_count());
  EXPECT_EQ(narrow.sphere_lights.size(), base.sphere_lights.size());
  EXPECT_EQ(narrow.effects.max_bounces, base.effects.max_bounces);
  EXPECT_FLOAT_EQ(narrow.camera.fov_y_deg, 10.0f);
  EXPECT_NE(narrow.camera.fov_y_deg, base.camera.fov_y_deg);
  EXPECT_EQ(narrow.camera.width, 1920u);  // [camera] is replaced whole: its resolution falls back to the default

  // A file extending a file: relative to the extending file's folder; a cycle and an unknown base are refused.
  const fs::path dir = fs::temp_directory_path() / "raysort_extends_test";
  fs::create_directories(dir);
  std::ofstream(dir / "a.toml") << "extends = \"b.toml\"\n";
  std::ofstream(dir / "b.toml") << "extends = \"a.toml\"\n";
  std::ofstream(dir / "c.toml") << "extends = \"cornell\"\ndescription = \"c\"\n";
  std::ofstream(dir / "d.toml") << "extends = \"c.toml\"\n";
  EXPECT_EQ(load_scene((dir / "d.toml").string()).description, "c");
  std::string msg;
  try { load_scene((dir / "a.toml").string()); } catch (const Error& e) { msg = e.what(); }
  EXPECT_NE(msg.find("chain of more than 8"), std::string::npos) << msg;
  msg.clear();
  try { parse_scene_toml("extends = \"no_such_scene\"\n", "x.toml", {}); } catch (const Error& e) { msg = e.what(); }
  EXPECT_NE(msg.find("x.toml:1: extends = \"no_such_scene\": no scene of that name"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cornell"), std::string::npos) << msg;
  msg.clear();
  try { parse_scene_toml("extends = 3\n", "y.toml", {}); } catch (const Error& e) { msg = e.what(); }
  EXPECT_NE(msg.find("y.toml:1: 'extends' must be a scene name"), std::string::npos) << msg;
  fs::remove_all(dir);
}

// The sampling overrides (--spp, --shadow-rays, --bounces) replace the scene's effects; 0 keeps them.
TEST(SceneToml, SamplingOverridesReplaceTheEffects) {
  SceneOptions o;
  o.frame = {0, 0, 8, 2, 4};
  Scene s = parse_scene_toml(kValid, "ok.toml", o);
  EXPECT_EQ(s.effects.samples_per_pixel, 8u);
  EXPECT_EQ(s.effects.shadow_rays_per_bounce, 2u);
  EXPECT_EQ(s.effects.max_bounces, 4u);
  EXPECT_EQ(s.camera.width, 1920u);
  Scene kept = parse_scene_toml(kValid, "ok.toml", {});
  EXPECT_EQ(kept.effects.shadow_rays_per_bounce, 1u);
  EXPECT_EQ(kept.effects.max_bounces, 1u);
}

// The limited-viewport scenes (paper Table 4) are their base scenes with only the camera changed.
TEST(SceneReal, LimitedViewportsExtendTheirScenes) {
  RAYSORT_REQUIRE_REAL_SCENES();
  for (const std::string base : {"sibenik", "breakfast_room", "grey_white_room", "japanese_classroom", "wooden_staircase"}) {
    const Scene full = load_scene(base), limited = load_scene(base + "_limited");
    EXPECT_EQ(limited.triangle_count(), full.triangle_count()) << base;
    EXPECT_EQ(limited.sphere_lights.size(), full.sphere_lights.size()) << base;
    EXPECT_EQ(limited.materials.size(), full.materials.size()) << base;
    EXPECT_LT(limited.camera.fov_y_deg, full.camera.fov_y_deg / 2) << base;
    EXPECT_EQ(scene_file_obj_files(base + "_limited"), scene_file_obj_files(base)) << base;
  }
}

// Real scenes from the scene root: skipped when it is absent, except on CI where they must be there.
TEST(SceneReal, SibenikAndBreakfastRoomLoad) {
  SceneOptions o;
  std::string root = resolve_scene_root(o);
  if (!fs::exists(fs::path(root) / "sibenik")) {
    const char* ci = std::getenv("CI");
    if (ci && std::string(ci) == "true") FAIL() << "scene root " << root << " is missing on CI (set RAYSORT_SCENE_ROOT)";
    GTEST_SKIP() << "scene root " << root << " not found; set RAYSORT_SCENE_ROOT to run the real-scene test";
  }
  Scene sib = load_scene("sibenik", o);
  EXPECT_EQ(sib.triangle_count(), 75'284u);
  EXPECT_EQ(sib.sphere_lights.size(), 13u);
  Scene bfr = load_scene("breakfast_room", o);
  EXPECT_EQ(bfr.triangle_count(), 269'538u);
  EXPECT_EQ(bfr.sphere_lights.size(), 3u);
  EXPECT_GT(bfr.materials.size(), 10u);
  // Cameras inside the interiors.
  for (const Scene* s : {&sib, &bfr}) {
    Aabb b = s->bounds();
    for (int a = 0; a < 3; ++a) {
      EXPECT_GT(s->camera.position[a], b.min[a]) << s->name;
      EXPECT_LT(s->camera.position[a], b.max[a]) << s->name;
    }
  }
}

// Issue 8: more bad scene files, each refused with the file, the line and the key.
TEST(SceneToml, BadInputNamesFileLineAndKey) {
  // A wrong type for a path, a table where a value belongs, a duplicate key (TOML syntax).
  std::string obj_int = parse_error(replace(kValid, "generator = \"plane\"\n[mesh.params]\nsize_x = 4.0\nsize_z = 4.0\n",
                                            "obj = 3\n"));
  EXPECT_NE(obj_int.find("bad.toml:9:"), std::string::npos) << obj_int;
  EXPECT_NE(obj_int.find("mesh[0].obj"), std::string::npos) << obj_int;
  std::string dup = parse_error(replace(kValid, "fov_y = 40.0", "fov_y = 40.0\nfov_y = 41.0"));
  EXPECT_NE(dup.find("bad.toml:6:"), std::string::npos) << dup;
  std::string table = parse_error(replace(kValid, "fov_y = 40.0", "fov_y = { a = 1 }"));
  EXPECT_NE(table.find("bad.toml:5:"), std::string::npos) << table;
  EXPECT_NE(table.find("camera.fov_y"), std::string::npos) << table;
  // Empty and binary files: refused in one line, naming the file.
  for (const std::string& text : {std::string(""), std::string("\x01\x02\xff\xfe\0garbage", 12)}) {
    std::string msg = parse_error(text);
    EXPECT_NE(msg.find("bad.toml"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(SceneToml, BadObjPathsNameTheSceneLineAndTheObj) {
  fs::path dir = temp_dir("objpaths");
  SceneOptions o;
  o.scene_root = dir.string();
  fs::create_directories(dir / "folder.obj");
  write_file(dir / "broken.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
  auto with_obj = [&](const std::string& rel) {
    return replace(kValid, "generator = \"plane\"\n[mesh.params]\nsize_x = 4.0\nsize_z = 4.0\n",
                   "obj = \"" + rel + "\"\n");
  };
  auto error_of = [&](const std::string& text) -> std::string {
    try {
      parse_scene_toml(text, "bad.toml", o);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  std::string folder = error_of(with_obj("folder.obj"));
  EXPECT_NE(folder.find("bad.toml:9:"), std::string::npos) << folder;
  EXPECT_NE(folder.find("names a directory"), std::string::npos) << folder;
  std::string broken = error_of(with_obj("broken.obj"));
  EXPECT_NE(broken.find("bad.toml:9: mesh 'floor'"), std::string::npos) << broken;
  EXPECT_NE(broken.find("broken.obj:3: vertex 3 has a non-finite coordinate"), std::string::npos) << broken;
  // A scene path that is a directory, or missing, through load_scene.
  EXPECT_THROW(load_scene(dir.string() + "/folder.obj"), Error);
  try {
    load_scene((dir / "missing.toml").string());
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene file not found"), std::string::npos) << e.what();
  }
}

// Issue 6: materials and effects. A [[material]] (albedo, mirror) named by a mesh; invalid effect
// declarations refused with the file, the line and the key.
TEST(SceneEffects, MaterialsAreNamedByMeshes) {
  Scene s = parse_scene_toml(replace(kValid, "[[mesh]]\nname = \"floor\"\n",
                                     "[[material]]\nname = \"chrome\"\nalbedo = [0.9, 0.9, 0.9]\nmirror = true\n\n"
                                     "[[mesh]]\nname = \"floor\"\nmaterial = \"chrome\"\n"),
                             "ok.toml", {});
  ASSERT_EQ(s.materials.size(), 2u);  // the default material stays at index 0
  EXPECT_TRUE(s.materials[1].mirror);
  EXPECT_EQ(s.materials[1].albedo, (Vec3{0.9f, 0.9f, 0.9f}));
  auto flat = s.flatten();
  for (auto m : flat.material) EXPECT_EQ(m, 1);
}

TEST(SceneEffects, InvalidDeclarationsNameFileLineAndKey) {
  struct Case {
    std::string text, where, key;
  };
  const std::string mesh = "[[mesh]]\nname = \"floor\"\n";
  const std::vector<Case> cases = {
      // an unknown material, listing the ones there are
      {replace(kValid, mesh, "[[material]]\nname = \"white\"\n" + mesh + "material = \"whte\"\n"), "bad.toml:11:",
       "mesh[0].material"},
      {replace(kValid, mesh, mesh + "material = \"white\"\n"), "bad.toml:9:", "mesh[0].material"},
      {replace(kValid, mesh, "[[material]]\nname = \"w\"\nalbedo = [1.5, 0.5, 0.5]\n" + mesh), "bad.toml:9:",
       "material[0].albedo"},
      {replace(kValid, mesh, "[[material]]\nname = \"w\"\nmirror = 1\n" + mesh), "bad.toml:9:", "material[0].mirror"},
      {replace(kValid, mesh, "[[material]]\nname = \"w\"\n[[material]]\nname = \"w\"\n" + mesh), "bad.toml:10:",
       "material[1].name"},
      {replace(kValid, mesh, "[[material]]\nname = \"w\"\n" + mesh + "material = \"w\"\nalbedo = [0.5, 0.5, 0.5]\n"),
       "bad.toml:11:", "mesh[0].material"},
      // lights
      {replace(kValid, "radius = 0.05", "radius = -0.05"), "bad.toml:16:", "sphere_light[0].radius"},
      {kValid + "power = -3.0\n", "bad.toml:17:", "sphere_light[0].power"},
      {kValid + "color = [1.0, -1.0, 1.0]\n", "bad.toml:17:", "sphere_light[0].color"},
      {kValid + "[sky]\nzenith = [1.0, 1.0, 1.0]\n", "bad.toml:17:", "sky"},
      // effects: depth < 0, too many shadow rays, zero samples, roulette out of (0, 1]
      {kValid + "[effects]\nmax_bounces = -1\n", "bad.toml:18:", "effects.max_bounces"},
      {kValid + "[effects]\nrussian_roulette_start = -2\n", "bad.toml:18:", "effects.russian_roulette_start"},
      {kValid + "[effects]\nshadow_rays_per_bounce = 65\n", "bad.toml:18:", "effects.shadow_rays_per_bounce"},
      {kValid + "[effects]\nsamples_per_pixel = 0\n", "bad.toml:18:", "effects.samples_per_pixel"},
      {kValid + "[effects]\nrussian_roulette_survival = 0.0\n", "bad.toml:18:", "effects.russian_roulette_survival"},
      {kValid + "[effects]\nmax_bounce = 2\n", "bad.toml:18:", "effects.max_bounce"},
  };
  for (const auto& c : cases) {
    std::string msg = parse_error(c.text);
    EXPECT_NE(msg.find(c.where), std::string::npos) << c.key << ": " << msg;
    EXPECT_NE(msg.find(c.key), std::string::npos) << c.key << ": " << msg;
  }
  EXPECT_NE(parse_error(cases[0].text).find("white"), std::string::npos);  // the known materials
}

// --- Scene provenance (scenes/sources.toml, scene/provenance.h) ----------------------------------------

namespace {

// write_file, creating the folders on the way.
void write_file_in(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  write_file(p, text);
}

// The message of the Error that parsing catalogue text throws ("" when it does not throw).
std::string catalogue_error(const std::string& text) {
  try {
    parse_scene_catalogue(text, "cat.toml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

const std::string kSha = std::string(64, 'a');
const std::string kEntry = "[\"d/x.obj\"]\nsha256 = \"" + kSha + "\"\nbytes = 10\ntriangles = 2\n" +
                           "source = { origin = \"github.com/o/r\", path = \"x.obj\", commit = \"" + std::string(40, 'b') +
                           "\" }\nlicence = \"CC0 1.0\"\nconversion = \"none\"\n";

}  // namespace

TEST(SceneProvenance, CatalogueCoversEveryObjOfEveryEmbeddedScene) {
  // Adding a scene without the provenance of its files fails here.
  std::size_t objs = 0;
  for (const auto& l : list_scenes())
    for (const auto& obj : l.obj_files) {
      ++objs;
      const CatalogueEntry* e = find_catalogued(obj);
      ASSERT_NE(e, nullptr) << l.name << " uses " << obj << ", which has no entry in scenes/sources.toml";
      EXPECT_TRUE(e->material_of.empty()) << obj << " is catalogued as a material file";
      EXPECT_GT(e->triangles, 0u) << obj;
      EXPECT_FALSE(e->source.origin.empty()) << obj;
      EXPECT_FALSE(e->conversion.empty()) << obj;
      // A Creative Commons BY licence requires the credit to be recorded.
      if (e->licence.find("CC-BY") != std::string::npos) {
        EXPECT_FALSE(e->credit.empty()) << obj;
      }
    }
  EXPECT_GE(objs, 12u);
  // Material files are checked with their OBJ.
  EXPECT_EQ(files_with_materials({"cornell_box/CornellBox-Original.obj", "gems/diamond.obj"}),
            (std::vector<std::string>{"cornell_box/CornellBox-Original.obj", "cornell_box/CornellBox-Original.mtl",
                                      "gems/diamond.obj"}));
}

TEST(SceneProvenance, CatalogueIsNoScene) {
  for (const auto& l : list_scenes()) EXPECT_NE(l.name, "sources");
  try {
    check_scene_reference("sources");
    FAIL() << "'sources' was taken for a scene";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown scene 'sources'"), std::string::npos) << e.what();
  }
}

TEST(SceneProvenance, BadCatalogueNamesFileLineAndFix) {
  EXPECT_EQ(catalogue_error(kEntry), "");
  auto has = [](const std::string& msg, const std::string& part) {
    EXPECT_NE(msg.find(part), std::string::npos) << "no '" << part << "' in: " << msg;
  };
  std::string short_sha = replace(kEntry, kSha, "abc");
  has(catalogue_error(short_sha), "cat.toml:2: '\"d/x.obj\".sha256' must be 64 lowercase hex digits");
  has(catalogue_error(kEntry + "colour = \"red\"\n"), "unknown key '\"d/x.obj\".colour'");
  has(catalogue_error(replace(kEntry, "licence = \"CC0 1.0\"\n", "")), "missing the required key 'licence'");
  has(catalogue_error(replace(kEntry, "commit = \"" + std::string(40, 'b') + "\"", "version = \"1\", commit = \"" +
                                                                                    std::string(40, 'b') + "\"")),
      "exactly one of 'commit'");
  has(catalogue_error(replace(kEntry, "d/x.obj", "../x.obj")), "must be a path relative to the scene root");
  has(catalogue_error(kEntry + "mtl = \"d/x.mtl\"\n"), "\"d/x.obj\" has mtl = \"d/x.mtl\", which has no entry; add");
  has(catalogue_error(kEntry + "mtl = \"d/x.mtl\"\n[\"d/x.mtl\"]\nsha256 = \"" + kSha +
                      "\"\nbytes = 3\nmaterial_of = \"d/y.obj\"\n" + replace(kEntry, "d/x.obj", "d/y.obj")),
      "\"d/x.mtl\" has material_of = \"d/y.obj\", but that entry does not name it back; set mtl = \"d/x.mtl\" there");
  EXPECT_EQ(catalogue_error(kEntry + "mtl = \"d/x.mtl\"\n[\"d/x.mtl\"]\nsha256 = \"" + kSha +
                            "\"\nbytes = 3\nmaterial_of = \"d/x.obj\"\n"),
            "");
}

TEST(SceneProvenance, Sha256OfFiles) {
  const fs::path dir = raysort::testing::temp_path("sha256");
  write_file_in(dir / "abc", "abc");
  write_file_in(dir / "empty", "");
  write_file_in(dir / "million", std::string(1'000'000, 'a'));  // several read chunks
  EXPECT_EQ(sha256_file((dir / "abc").string()), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_file((dir / "empty").string()), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_file((dir / "million").string()), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  try {
    sha256_file((dir / "absent").string());
    FAIL() << "no Error for a missing file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "absent").string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(sha256_file(dir.string()), Error);  // a directory
}

TEST(SceneProvenance, ChecksumsUnderASceneRootRecordStatus) {
  const fs::path root = raysort::testing::temp_path("prov-root");
  write_file_in(root / "gems/diamond.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");  // not the catalogued bytes
  const std::string found = sha256_file((root / "gems/diamond.obj").string());
  FileCheck c = check_scene_file("gems/diamond.obj", root.string());
  EXPECT_EQ(c.status, FileStatus::Different);
  EXPECT_EQ(describe_check(c), "different: expected bc3379788dcc, found " + found.substr(0, 12));
  EXPECT_EQ(describe_check(check_scene_file("gems/emerald.obj", root.string())), "missing");

  // An embedded scene (its OBJs and catalogued .mtl), a procedural one (no files), a .toml path, a bare .obj.
  write_file_in(root / "mine.toml", replace(kValid, "generator = \"plane\"\n[mesh.params]\nsize_x = 4.0\nsize_z = 4.0\n",
                                         "obj = \"gems/diamond.obj\"\n"));
  const std::string bare = (root / "gems/diamond.obj").string();
  nlohmann::json j = scene_file_checksums({"multi-instance-real", "cornell", (root / "mine.toml").string(), bare},
                                          root.string());
  // Six files, and each TOML scene's own resolved text (issue 44: an edited scene file is noticed).
  ASSERT_EQ(j.size(), 9u) << j.dump(1);
  for (const std::string& s : {std::string("multi-instance-real"), std::string("cornell"), (root / "mine.toml").string()}) {
    EXPECT_EQ(j["scene:" + s].value("status", ""), "scene file") << s;
    EXPECT_EQ(j["scene:" + s].value("sha256", "").size(), 64u) << s;
  }
  EXPECT_FALSE(j.contains("scene:" + bare)) << "a bare OBJ is its own file";
  EXPECT_EQ(j["gems/diamond.obj"], (nlohmann::json{{"sha256", found}, {"status", "different"}}));
  for (const char* f : {"cornell_box/CornellBox-Original.obj", "cornell_box/CornellBox-Original.mtl",
                        "dragon/dragon_100k.obj", "gems/emerald.obj"})
    EXPECT_EQ(j[f], (nlohmann::json{{"status", "missing"}})) << f;
  EXPECT_EQ(j[bare], (nlohmann::json{{"sha256", found}, {"status", "uncatalogued"}}));
  EXPECT_THROW(scene_file_checksums({"nope"}, root.string()), Error);
}

TEST(SceneProvenance, RealFilesMatchTheCatalogue) {
  RAYSORT_REQUIRE_REAL_SCENES();
  const std::string root = raysort::testing::real_scene_root();
  for (const auto& e : scene_catalogue()) {
    FileCheck c = check_scene_file(e.path, root);
    EXPECT_EQ(c.status, FileStatus::Present) << e.path << ": " << describe_check(c);
    EXPECT_EQ(fs::file_size(fs::path(root) / e.path), e.bytes) << e.path;
  }
  nlohmann::json j = scene_file_checksums({"sibenik", "breakfast_room"}, root);
  EXPECT_EQ(j["sibenik/sibenik_75k_geom.obj"]["status"], "present");
  EXPECT_EQ(j["breakfast_room/breakfast_room.mtl"]["sha256"], find_catalogued("breakfast_room/breakfast_room.mtl")->sha256);
}

TEST(SceneProvenance, FileDifferencesBetweenResultSets) {
  const std::string h1 = std::string(64, '1'), h2 = std::string(64, '2');
  nlohmann::json a = {{"scene_files", {{"s/a.obj", {{"sha256", h1}, {"status", "present"}}},
                                       {"s/b.obj", {{"sha256", h1}, {"status", "present"}}},
                                       {"s/c.obj", {{"status", "missing"}}}}}};
  EXPECT_TRUE(scene_file_differences(a, a).empty());
  nlohmann::json b = a;
  b["scene_files"]["s/a.obj"] = {{"sha256", h2}, {"status", "different"}};
  b["scene_files"].erase("s/b.obj");
  b["scene_files"]["s/d.obj"] = {{"sha256", h2}, {"status", "uncatalogued"}};
  b["scene_files"]["s/c.obj"] = {{"sha256", h1}, {"status", "present"}};
  EXPECT_EQ(scene_file_differences(a, b),
            (std::vector<std::string>{
                "s/a.obj: sha256 111111111111 in A, 222222222222 in B; results on these files are not comparable",
                "s/b.obj: recorded in A only (sha256 111111111111)",
                "s/c.obj: sha256 missing in A, 111111111111 in B; results on these files are not comparable",
                "s/d.obj: recorded in B only (sha256 222222222222)"}));
  // Result sets from before scene_files was recorded, and malformed entries: lines, no throw.
  EXPECT_TRUE(scene_file_differences(nlohmann::json::object(), nlohmann::json::object()).empty());
  auto older = scene_file_differences(a, nlohmann::json::object());
  ASSERT_EQ(older.size(), 1u);
  EXPECT_NE(older[0].find("result set B records no scene file checksums"), std::string::npos) << older[0];
  // A set of procedural scenes only records no files: an older set cannot differ from it.
  EXPECT_TRUE(scene_file_differences(nlohmann::json{{"scene_files", nlohmann::json::object()}}, nlohmann::json::object())
                  .empty());
  nlohmann::json bad = {{"scene_files", {{"s/a.obj", 3}, {"s/b.obj", {{"sha256", 7}}}}}};
  std::vector<std::string> lines;
  EXPECT_NO_THROW(lines = scene_file_differences(a, bad));
  EXPECT_EQ(lines.size(), 3u);
  EXPECT_NO_THROW(scene_file_differences(nlohmann::json::array(), "text"));
}

// Issue 44, item 7: a scene's name is the base of output files (render's <name>.png, trace's
// <name>.json), so a name that is a path, hidden, empty or overlong is refused with its line.
TEST(SceneToml, SceneNameMustBeAPlainFileName) {
  EXPECT_EQ(parse_error(replace(kValid, "name = \"t\"", "name = \"\"")),
            "bad.toml:1: 'name' is empty; give a plain name such as \"bad\"");
  EXPECT_EQ(parse_error(replace(kValid, "name = \"t\"", "name = \"../../evil/x\"")),
            "bad.toml:1: 'name' holds a '/': it names output files, so it must be a name, not a path; give a plain "
            "name such as \"_._.._evil_x\"");
  EXPECT_NE(parse_error(replace(kValid, "name = \"t\"", "name = \"/tmp/x\"")).find("bad.toml:1: 'name' holds a '/'"),
            std::string::npos);
  EXPECT_NE(parse_error(replace(kValid, "name = \"t\"", "name = \"..\"")).find("bad.toml:1: 'name' starts with '.'"),
            std::string::npos);
  EXPECT_NE(parse_error(replace(kValid, "name = \"t\"", "name = \"a\\\\b\"")).find("holds a '\\'"),
            std::string::npos);
  EXPECT_NE(parse_error(replace(kValid, "name = \"t\"", "name = \"" + std::string(101, 'n') + "\""))
                .find("is 101 bytes long"),
            std::string::npos);
  EXPECT_EQ(parse_error(replace(kValid, "name = \"t\"", "name = \"cornell box (v2)\"")), "");
}

// Issue 44, item 9: a camera whose view direction or up cannot be normalised in float is refused
// where the scene is parsed, naming the key and why (it rendered NaN rays or one direction).
TEST(SceneToml, CameraVectorsTooSmallForFloatAreRefused) {
  const std::string tiny_view = parse_error(replace(kValid, "look_at = [0.0, 1.0, 0.0]", "look_at = [1e-38, 1.0, 3.0]"));
  EXPECT_NE(tiny_view.find("bad.toml:4: 'camera.look_at' is 1e-38 from the camera position, too close to normalise"),
            std::string::npos)
      << tiny_view;
  const std::string tiny_up = parse_error(replace(kValid, "fov_y = 40.0", "up = [0.0, 1e-40, 0.0]\nfov_y = 40.0"));
  EXPECT_NE(tiny_up.find("bad.toml:5: 'camera.up' is 1e-40 long; it must be between 1e-12 and 1e+18 long"),
            std::string::npos)
      << tiny_up;
  const std::string parallel = parse_error(replace(kValid, "fov_y = 40.0", "up = [0.0, 0.0, 2.0]\nfov_y = 40.0"));
  EXPECT_NE(parallel.find("bad.toml:5: 'camera.up' is parallel to the view direction"), std::string::npos) << parallel;
  const std::string far = parse_error(replace(kValid, "position = [0.0, 1.0, 3.0]", "position = [0.0, 1.0, 3e30]"));
  EXPECT_NE(far.find("bad.toml:3: 'camera.position' has a coordinate 3e+30, outside the ±1e+18"), std::string::npos)
      << far;
  EXPECT_EQ(parse_error(replace(kValid, "fov_y = 40.0", "up = [0.0, 1e-3, 0.0]\nfov_y = 40.0")), "");
}

// Issue 44, item 9: a scene whose box is too large or too small for float ray tracing is refused
// with the file, the box and the supported range, both from a scene file and as a bare OBJ.
TEST(SceneToml, SceneExtentOutsideTheFloatRangeIsRefused) {
  const std::string box = "[[mesh]]\nname = \"floor\"\ngenerator = \"plane\"\n[mesh.params]\nsize_x = 4.0\nsize_z = 4.0\n";
  const std::string huge = parse_error(replace(
      kValid, box, "[[mesh]]\nname = \"b\"\ngenerator = \"box\"\n[mesh.params]\nmin = [-3.4e38, -3.4e38, -3.4e38]\n"
                   "max = [3.4e38, 3.4e38, 3.4e38]\n"));
  EXPECT_NE(huge.find("bad.toml: the scene's bounding box [-3.4e+38, -3.4e+38, -3.4e+38] – [3.4e+38, 3.4e+38, 3.4e+38] "
                      "reaches 3.4e+38, outside the ±1e+18"),
            std::string::npos)
      << huge;
  const std::string tiny = parse_error(replace(
      kValid, box, "[[mesh]]\nname = \"b\"\ngenerator = \"box\"\n[mesh.params]\nmin = [0.0, 0.0, 0.0]\n"
                   "max = [1e-38, 1e-38, 1e-38]\n"));
  EXPECT_NE(tiny.find("across, below the 1e-18 that ray tracing in float resolves"), std::string::npos) << tiny;
  // A flat scene (a plane: no extent in y) is fine; only the largest extent counts.
  EXPECT_EQ(parse_error(kValid), "");

  const fs::path dir = temp_dir("scene_extent");
  for (const char* scale : {"1e38", "1e-38", "1e19"}) {
    const fs::path obj = dir / (std::string("at_") + scale + ".obj");
    write_file(obj, fmt::format("v 0 0 0\nv {0} 0 0\nv 0 {0} 0\nf 1 2 3\n", scale));
    std::string msg;
    try {
      load_scene(obj.string());
    } catch (const Error& e) {
      msg = e.what();
    }
    EXPECT_NE(msg.find(obj.string() + ": the scene's bounding box"), std::string::npos) << scale << ": " << msg;
  }
  write_file(dir / "ok.obj", "v 0 0 0\nv 1e15 0 0\nv 0 1e-15 0\nf 1 2 3\n");
  EXPECT_NO_THROW(load_scene((dir / "ok.obj").string()));
}

// Issue 44, item 17: with `extends`, an error names the file and line the bad key was written in:
// the extending file's own keys (they pointed at line 1), and the base file's (they named the
// extending file).
TEST(SceneToml, ExtendsErrorsNameTheirFileAndLine) {
  std::string msg = parse_error("extends = \"cornell\"\ndescription = \"d\"\n\n[camera]\nposition = [0.0, 1.0, 3.0]\n"
                                "look_at = [0.0, 1.0, 0.0]\nfovy = 10.0\n");
  EXPECT_EQ(msg.rfind("bad.toml:7: unknown key 'camera.fovy' in [camera]", 0), 0u) << msg;
  msg = parse_error("extends = \"cornell\"\n\n[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\n"
                    "fov_y = \"wide\"\n");
  EXPECT_EQ(msg, "bad.toml:6: 'camera.fov_y' must be a number, not a string");
  const fs::path dir = temp_dir("extends_lines");
  write_file(dir / "base.toml", replace(kValid, "fov_y = 40.0", "fov_y = 400.0"));
  write_file(dir / "top.toml", "extends = \"base.toml\"\ndescription = \"top\"\n");
  msg.clear();
  try {
    load_scene((dir / "top.toml").string());
  } catch (const Error& e) {
    msg = e.what();
  }
  EXPECT_EQ(msg.rfind((dir / "base.toml").string() + ":5: 'camera.fov_y' = 400", 0), 0u) << msg;
  msg = parse_error("\n\nextends = 3\n");
  EXPECT_EQ(msg.rfind("bad.toml:3: 'extends' must be a scene name", 0), 0u) << msg;
}

// Issue 44, item 15: a scene path that is a FIFO is named as such (it was "file not found"; read, it
// would block), and a scene file larger than the bound is refused before it is read.
TEST(SceneLookup, ScenePathsMustBeRegularFilesWithinTheBound) {
  const fs::path dir = temp_dir("scene_fifo");
  const fs::path fifo = dir / "pipe.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string msg;
  try {
    load_scene(fifo.string());
  } catch (const Error& e) {
    msg = e.what();
  }
  EXPECT_EQ(msg, "scene file " + fifo.string() +
                     " is a FIFO (named pipe), not a regular file; give the path of a .toml scene file");
  const fs::path obj_fifo = dir / "pipe.obj";
  ASSERT_EQ(::mkfifo(obj_fifo.c_str(), 0600), 0);
  msg.clear();
  try {
    check_scene_reference(obj_fifo.string());
  } catch (const Error& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("OBJ file " + obj_fifo.string() + " is a FIFO (named pipe), not a regular file"),
            std::string::npos)
      << msg;
  // A FIFO as a mesh's obj or an extends base: refused by type, not read.
  write_file(dir / "mesh.toml", replace(kValid, "generator = \"plane\"\n[mesh.params]\nsize_x = 4.0\nsize_z = 4.0\n",
                                        "obj = \"" + obj_fifo.string() + "\"\n"));
  msg.clear();
  try {
    load_scene((dir / "mesh.toml").string());
  } catch (const Error& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("mesh.toml:9: mesh 'floor': OBJ file " + obj_fifo.string() + " is a FIFO"), std::string::npos)
      << msg;
  write_file(dir / "ext.toml", "extends = \"pipe.toml\"\n");
  msg.clear();
  try {
    load_scene((dir / "ext.toml").string());
  } catch (const Error& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("ext.toml:1: extends = \"pipe.toml\": scene file " + fifo.string() + " is a FIFO"),
            std::string::npos)
      << msg;
  // 17 MiB of holes: over the 16 MiB a scene file may have; refused by its size, not parsed.
  const fs::path big = dir / "big.toml";
  write_file(big, "");
  ASSERT_EQ(::truncate(big.c_str(), 17 << 20), 0);
  msg.clear();
  try {
    load_scene(big.string());
  } catch (const Error& e) {
    msg = e.what();
  }
  EXPECT_EQ(msg, "scene file " + big.string() +
                     " is 17.0 MiB, over the 16.0 MiB bound for scene files; it is corrupt or the wrong file");
}
