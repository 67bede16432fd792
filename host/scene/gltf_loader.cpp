// glTF 2.0 scenes (.gltf with its buffers, .glb) through tinygltf: the default scene's node
// hierarchy (each node's matrix or translation/rotation/scale, composed from the root down),
// triangle primitives (modes TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN) as meshes placed by instances,
// each material's baseColorFactor as albedo, and the first perspective camera met. Accessors are
// bounds-checked here: tinygltf parses the JSON and buffers but leaves byte ranges to its user.
#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

#include "scene/mesh_formats.h"
#include "scene/tinygltf.h"
#include "util/error.h"

namespace raysort {

namespace {

using Matrix4 = std::array<double, 16>;  // column-major, as glTF writes it

Matrix4 identity4() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }

Matrix4 multiply(const Matrix4& a, const Matrix4& b) {
  Matrix4 r{};
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row)
      for (int k = 0; k < 4; ++k) r[c * 4 + row] += a[k * 4 + row] * b[c * 4 + k];
  return r;
}

// A node's local transform: its matrix, else T · R · S (glTF 2.0 §3.5.3).
Matrix4 local_transform(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    Matrix4 m;
    for (int i = 0; i < 16; ++i) m[i] = n.matrix[i];
    return m;
  }
  Matrix4 t = identity4(), r = identity4(), s = identity4();
  if (n.translation.size() == 3) t[12] = n.translation[0], t[13] = n.translation[1], t[14] = n.translation[2];
  if (n.scale.size() == 3) s[0] = n.scale[0], s[5] = n.scale[1], s[10] = n.scale[2];
  if (n.rotation.size() == 4) {
    const double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
    r = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),     0,
         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),     0,
         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y), 0,
         0,                       0,                       0,                       1};
  }
  return multiply(t, multiply(r, s));
}

Affine to_affine(const Matrix4& m) {
  Affine a;
  for (int row = 0; row < 3; ++row)
    for (int c = 0; c < 4; ++c) a.m[row * 4 + c] = static_cast<float>(m[c * 4 + row]);
  return a;
}

bool is_identity(const Matrix4& m) { return m == identity4(); }

Vec3 apply_point(const Matrix4& m, double x, double y, double z, double w) {
  return {static_cast<float>(m[0] * x + m[4] * y + m[8] * z + m[12] * w),
          static_cast<float>(m[1] * x + m[5] * y + m[9] * z + m[13] * w),
          static_cast<float>(m[2] * x + m[6] * y + m[10] * z + m[14] * w)};
}

class GltfReader {
 public:
  GltfReader(const tinygltf::Model& model, const std::string& origin, ForeignScene& out)
      : model_(model), origin_(origin), out_(out) {}

  void read() {
    for (const auto& m : model_.materials) {
      Material mat;
      mat.name = m.name.empty() ? "gltf-material" : m.name;
      const auto& c = m.pbrMetallicRoughness.baseColorFactor;
      if (c.size() >= 3) mat.albedo = {float(c[0]), float(c[1]), float(c[2])};
      if (m.pbrMetallicRoughness.baseColorTexture.index >= 0) out_.ignored.add("baseColorTexture");
      out_.scene.materials.push_back(mat);
    }
    count_ignored();
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      // tinygltf leaves "scene" unchecked (found by fuzz/gltf_fuzzer: one past the scenes read freed memory)
      const int chosen = model_.defaultScene >= 0 ? model_.defaultScene : 0;
      if (std::size_t(chosen) >= model_.scenes.size())
        fail(fmt::format("names scene {} as its scene, but has {} scenes", chosen, model_.scenes.size()));
      roots = model_.scenes[std::size_t(chosen)].nodes;
    } else {  // no scene: every node that is no other's child (glTF 2.0 §3.5.1 leaves this to the loader)
      std::vector<bool> child(model_.nodes.size(), false);
      for (const auto& n : model_.nodes)
        for (int c : n.children) {
          if (c < 0 || std::size_t(c) >= child.size()) fail(fmt::format("names node {} as a child, which does not exist", c));
          child[std::size_t(c)] = true;
        }
      for (std::size_t i = 0; i < model_.nodes.size(); ++i)
        if (!child[i]) roots.push_back(int(i));
    }
    std::vector<bool> on_path(model_.nodes.size(), false);
    for (int r : roots) visit(r, identity4(), on_path);
    drop_identity_instances();
    if (out_.scene.meshes.empty())
      fail("has no triangle primitive in its scene's nodes; a scene needs at least one triangle");
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw Error(fmt::format("glTF file {} {}; fix the file (docs/scene-format.md, \"glTF 2.0\")", origin_, why));
  }

  void count_ignored() {
    if (!model_.animations.empty()) out_.ignored.add("animation", model_.animations.size());
    if (!model_.skins.empty()) out_.ignored.add("skin", model_.skins.size());
    if (!model_.textures.empty()) out_.ignored.add("texture", model_.textures.size());
    if (!model_.lights.empty()) out_.ignored.add("KHR_lights_punctual light", model_.lights.size());
    for (const auto& e : model_.extensionsUsed)
      if (e != "KHR_lights_punctual") out_.ignored.add(fmt::format("extension \"{}\"", e));
  }

  void visit(int index, const Matrix4& parent, std::vector<bool>& on_path) {
    if (index < 0 || std::size_t(index) >= model_.nodes.size()) fail(fmt::format("names node {}, which does not exist", index));
    if (on_path[std::size_t(index)]) fail(fmt::format("has a cycle in its node hierarchy through node {}", index));
    on_path[std::size_t(index)] = true;
    const tinygltf::Node& node = model_.nodes[std::size_t(index)];
    const Matrix4 world = multiply(parent, local_transform(node));
    for (double v : world)
      if (!std::isfinite(v) || std::fabs(v) > 1e30)
        fail(fmt::format("has a transform beyond the float range at node {}", index));
    if (node.mesh >= 0) place_mesh(node.mesh, world);
    if (node.camera >= 0) read_camera(node.camera, world);
    if (!node.weights.empty()) out_.ignored.add("morph weights");
    for (int c : node.children) visit(c, world, on_path);
    on_path[std::size_t(index)] = false;
  }

  void place_mesh(int gltf_mesh, const Matrix4& world) {
    if (std::size_t(gltf_mesh) >= model_.meshes.size()) fail(fmt::format("names mesh {}, which does not exist", gltf_mesh));
    auto [it, is_new] = mesh_of_.try_emplace(gltf_mesh, -1);
    if (is_new) {
      Mesh m = convert_mesh(model_.meshes[std::size_t(gltf_mesh)], gltf_mesh);
      if (m.triangles.empty()) return;
      it->second = int(out_.scene.meshes.size());
      out_.scene.meshes.push_back(std::move(m));
    }
    if (it->second < 0) return;  // a mesh of points or lines only
    out_.scene.instances.push_back({std::uint32_t(it->second), to_affine(world)});
    identity_.push_back(is_identity(world));
  }

  // Instances only when something is moved or repeated: a file of meshes placed once where they
  // are flattens to the very same floats as an OBJ of them (no multiply by 1 and add of 0).
  void drop_identity_instances() {
    if (out_.scene.instances.size() != out_.scene.meshes.size()) return;
    for (std::size_t i = 0; i < identity_.size(); ++i)
      if (!identity_[i] || out_.scene.instances[i].mesh != i) return;
    out_.scene.instances.clear();
  }

  const unsigned char* accessor_data(int index, int type, std::size_t& count, std::size_t& stride,
                                     int& component) const {
    if (index < 0 || std::size_t(index) >= model_.accessors.size()) fail(fmt::format("names accessor {}, which does not exist", index));
    const auto& a = model_.accessors[std::size_t(index)];
    if (a.type != type) fail(fmt::format("accessor {} has type {}, expected {}", index, a.type, type));
    if (a.sparse.isSparse) fail(fmt::format("accessor {} is sparse, which raysort does not read; write it dense", index));
    if (a.bufferView < 0 || std::size_t(a.bufferView) >= model_.bufferViews.size())
      fail(fmt::format("accessor {} has no buffer view", index));
    const auto& v = model_.bufferViews[std::size_t(a.bufferView)];
    if (v.buffer < 0 || std::size_t(v.buffer) >= model_.buffers.size()) fail(fmt::format("buffer view {} has no buffer", a.bufferView));
    const auto& buffer = model_.buffers[std::size_t(v.buffer)].data;
    component = a.componentType;
    const int size = tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType)) * tinygltf::GetNumComponentsInType(std::uint32_t(a.type));
    if (size <= 0) fail(fmt::format("accessor {} has an unknown component type {}", index, a.componentType));
    count = a.count;
    stride = v.byteStride ? v.byteStride : std::size_t(size);
    const std::size_t need = count == 0 ? 0 : a.byteOffset + stride * (count - 1) + std::size_t(size);
    if (count > buffer.size() || stride > buffer.size() || a.byteOffset > buffer.size() || v.byteOffset > buffer.size() ||
        need > v.byteLength || v.byteLength > buffer.size() - v.byteOffset)
      fail(fmt::format("accessor {} reads past its buffer view or buffer (byte offset {} in view {})", index,
                       a.byteOffset, a.bufferView));
    return buffer.data() + v.byteOffset + a.byteOffset;
  }

  std::uint32_t read_index(const unsigned char* p, int component) const {
    switch (component) {
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return p[0];
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { std::uint16_t v; std::memcpy(&v, p, 2); return v; }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
      default: fail(fmt::format("has an index accessor of component type {} (expected an unsigned byte, short or int)", component));
    }
  }

  void add_primitive(const tinygltf::Primitive& prim, Mesh& mesh, const std::string& where) {
    auto pos = prim.attributes.find("POSITION");
    if (pos == prim.attributes.end()) fail(fmt::format("{} has no POSITION attribute", where));
    std::size_t count = 0, stride = 0;
    int component = 0;
    const unsigned char* p = accessor_data(pos->second, TINYGLTF_TYPE_VEC3, count, stride, component);
    if (component != TINYGLTF_COMPONENT_TYPE_FLOAT)
      fail(fmt::format("{} has POSITION of component type {}; raysort reads float positions (quantised ones need "
                       "KHR_mesh_quantization, which it does not read)", where, component));
    const std::uint32_t base = std::uint32_t(mesh.positions.size());
    for (std::size_t i = 0; i < count; ++i) {
      Vec3 v;
      std::memcpy(v.data(), p + i * stride, 12);
      for (float c : v)
        if (!std::isfinite(c)) fail(fmt::format("{} has a non-finite POSITION at vertex {}", where, i));
      mesh.positions.push_back(v);
    }
    std::vector<std::uint32_t> idx;
    if (prim.indices >= 0) {
      std::size_t n = 0, istride = 0;
      int icomp = 0;
      const unsigned char* ip = accessor_data(prim.indices, TINYGLTF_TYPE_SCALAR, n, istride, icomp);
      for (std::size_t i = 0; i < n; ++i) {
        std::uint32_t v = read_index(ip + i * istride, icomp);
        if (v >= count) fail(fmt::format("{} has index {} but {} vertices", where, v, count));
        idx.push_back(v);
      }
    } else {
      for (std::size_t i = 0; i < count; ++i) idx.push_back(std::uint32_t(i));
    }
    const std::int32_t mat = prim.material >= 0 ? 1 + prim.material : 0;  // materials[0] is the default grey
    if (prim.material >= int(model_.materials.size())) fail(fmt::format("{} names material {}, which does not exist", where, prim.material));
    auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      mesh.triangles.push_back({base + a, base + b, base + c});
      mesh.material.push_back(mat);
    };
    if (prim.mode == TINYGLTF_MODE_TRIANGLES || prim.mode == -1) {
      for (std::size_t i = 0; i + 2 < idx.size(); i += 3) emit(idx[i], idx[i + 1], idx[i + 2]);
    } else if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {  // glTF 2.0 §3.7.2.1: odd triangles flipped
      for (std::size_t i = 0; i + 2 < idx.size(); ++i)
        i % 2 ? emit(idx[i + 1], idx[i], idx[i + 2]) : emit(idx[i], idx[i + 1], idx[i + 2]);
    } else {
      for (std::size_t i = 1; i + 1 < idx.size(); ++i) emit(idx[0], idx[i], idx[i + 1]);
    }
  }

  Mesh convert_mesh(const tinygltf::Mesh& gm, int index) {
    Mesh mesh;
    mesh.name = gm.name.empty() ? fmt::format("mesh{}", index) : gm.name;
    mesh.source = "gltf:" + origin_;
    for (std::size_t p = 0; p < gm.primitives.size(); ++p) {
      const auto& prim = gm.primitives[p];
      const int mode = prim.mode;
      if (mode != -1 && mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        out_.ignored.add(fmt::format("primitive of mode {} (points or lines)", mode));
        continue;
      }
      if (!prim.targets.empty()) out_.ignored.add("morph target", prim.targets.size());
      add_primitive(prim, mesh, fmt::format("mesh {} primitive {}", index, p));
    }
    return mesh;
  }

  void read_camera(int index, const Matrix4& world) {
    if (std::size_t(index) >= model_.cameras.size()) fail(fmt::format("names camera {}, which does not exist", index));
    const auto& c = model_.cameras[std::size_t(index)];
    if (c.type != "perspective") return out_.ignored.add(fmt::format("{} camera", c.type));
    if (out_.has_camera) return out_.ignored.add("camera after the first");
    Camera& cam = out_.scene.camera;
    // glTF 2.0 §3.10.1: a camera looks down its local −Z with +Y up.
    cam.position = apply_point(world, 0, 0, 0, 1);
    const Vec3 forward = apply_point(world, 0, 0, -1, 0);
    cam.look_at = {cam.position[0] + forward[0], cam.position[1] + forward[1], cam.position[2] + forward[2]};
    cam.up = apply_point(world, 0, 1, 0, 0);
    cam.fov_y_deg = static_cast<float>(c.perspective.yfov * 180.0 / 3.14159265358979323846);
    cam.width = 1920;
    cam.height = 1080;
    if (c.perspective.aspectRatio > 0 && std::isfinite(c.perspective.aspectRatio))
      cam.height = std::uint32_t(std::clamp(std::lround(1920.0 / c.perspective.aspectRatio), 1L, 16384L));
    out_.has_camera = true;
  }

  const tinygltf::Model& model_;
  const std::string& origin_;
  ForeignScene& out_;
  std::map<int, int> mesh_of_;  // glTF mesh → scene mesh (−1: no triangles)
  std::vector<bool> identity_;  // per instance: its transform is the identity
};

// tinygltf reads external buffers through these: the shared bounded reader, so a FIFO or
// /dev/zero named as a buffer is refused in one line rather than blocking or reading forever.
bool read_buffer_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
  try {
    const std::string data = read_input_file(path, kGltfBuffer);
    out->assign(data.begin(), data.end());
    return true;
  } catch (const Error& e) {
    *err += e.what();
    return false;
  }
}
bool buffer_file_exists(const std::string& path, void*) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}
std::string same_path(const std::string& path, void*) { return path; }
bool ignore_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

// The GLB container (glTF 2.0 §4.4), checked here so that a broken one is refused at its byte
// offset (tinygltf says only "Invalid glTF binary"): a 12-byte header (magic, version 2, length),
// then chunks of 8-byte header (length, type) and 4-byte aligned data, JSON first.
void check_glb_layout(const std::string& bytes, const std::string& origin) {
  auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + at, 4);  // GLB is little-endian, as every host raysort builds on
    return v;
  };
  auto fail = [&](std::size_t at, const std::string& why) {
    throw Error(fmt::format("glTF file {}: byte {}: {}; fix the file (a GLB is a 12-byte header, then chunks)", origin,
                            at, why));
  };
  if (bytes.size() < 20) fail(bytes.size(), "the file ends inside the GLB header (20 bytes needed)");
  if (u32(4) != 2) fail(4, fmt::format("GLB version {}; raysort reads glTF 2.0 (version 2)", u32(4)));
  if (u32(8) != bytes.size()) fail(8, fmt::format("the header gives the length {}, but the file has {} bytes", u32(8), bytes.size()));
  std::size_t at = 12;
  for (int chunk = 0; at < bytes.size(); ++chunk) {
    if (bytes.size() - at < 8) fail(at, "the file ends inside a chunk header");
    const std::uint32_t length = u32(at), type = u32(at + 4);
    if (chunk == 0 && type != 0x4E4F534Au) fail(at + 4, "the first chunk is not the JSON chunk");
    if (length % 4) fail(at, fmt::format("chunk {} has length {}, not a multiple of 4", chunk, length));
    if (length > bytes.size() - at - 8) fail(at, fmt::format("chunk {} of {} bytes runs past the end of the file", chunk, length));
    at += 8 + std::size_t(length);
  }
}

std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '.' || s.back() == ' ')) s.pop_back();
  for (std::size_t at; (at = s.find('\n')) != std::string::npos;) s.replace(at, 1, "; ");
  return s;
}

}  // namespace

ForeignScene parse_gltf(const std::string& bytes, const std::string& origin, const std::string& dir) {
  if (bytes.size() > 0xFFFFFFFFu) throw Error(fmt::format("glTF file {} is over 4 GiB, which glTF cannot address", origin));
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&buffer_file_exists, &same_path, &read_buffer_file, nullptr, nullptr});
  loader.SetImageLoader(&ignore_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = bytes.compare(0, 4, "glTF") == 0;
  if (binary) check_glb_layout(bytes, origin);
  const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                                       unsigned(bytes.size()), dir)
                         : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(bytes.size()), dir);
  if (!ok || !err.empty())
    throw Error(fmt::format("cannot read glTF file {}: {}; fix the file (or give a glTF 2.0 .gltf/.glb)", origin,
                            err.empty() ? "parse error" : one_line(err)));
  ForeignScene out;
  if (!model.images.empty()) out.ignored.add("image", model.images.size());
  GltfReader(model, origin, out).read();
  return out;
}

ForeignScene load_gltf(const std::string& path) {
  const std::string dir = std::filesystem::path(path).parent_path().string();
  return parse_gltf(read_input_file(path, kGltfFile), path, dir.empty() ? "." : dir);
}

}  // namespace raysort
