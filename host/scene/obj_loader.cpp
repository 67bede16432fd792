// OBJ loading through tinyobjloader, with the checks it leaves out: every vertex coordinate must
// be a finite number, every face index in range, and no face is dropped without an error.
// Polygons are triangulated here (not by tinyobjloader, which skips faces it cannot split), by the
// rule every format shares (scene/polygon.h), so an n-gon always gives n − 2 triangles.
#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include <charconv>
#include <cstdint>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

#include "scene/load.h"
#include "scene/polygon.h"
#include "util/error.h"
#include "util/input_file.h"

namespace raysort {

namespace {

// OBJ is line-oriented text with short lines; tinyobjloader reads each line whole into memory, so
// a corrupt or hostile file with a 1 GB line would cost 1 GB (and minutes). Lines longer than this
// are refused before parsing.
constexpr std::size_t kMaxObjLineBytes = std::size_t(1) << 20;

// Byte-level checks on the text of an OBJ, fed in chunks (a file is streamed through a bounded
// buffer before it is read whole): not UTF-16, no NUL byte (binary data), no overlong line.
class TextCheck {
 public:
  explicit TextCheck(const std::string& origin) : origin_(origin) {}
  void feed(const char* data, std::size_t n) {
    if (offset_ == 0 && n >= 2 &&
        ((data[0] == '\xFE' && data[1] == '\xFF') || (data[0] == '\xFF' && data[1] == '\xFE')))
      throw Error(fmt::format(
          "OBJ file {} is UTF-16 encoded; convert it to UTF-8 or ASCII (e.g. iconv -f UTF-16 -t UTF-8)", origin_));
    for (std::size_t i = 0; i < n; ++i) {
      char c = data[i];
      if (c == '\n') {
        ++line_;
        line_bytes_ = 0;
        continue;
      }
      if (c == '\0')
        throw Error(fmt::format("OBJ file {}:{}: byte {} is NUL: this is binary data, not a text OBJ file; check the "
                                "file (truncated download, wrong format?)",
                                origin_, line_, offset_ + i));
      if (++line_bytes_ > kMaxObjLineBytes)
        throw Error(fmt::format("OBJ file {}:{}: line longer than {} MiB; OBJ lines are short, so the file is corrupt "
                                "or not an OBJ file; fix the file",
                                origin_, line_, kMaxObjLineBytes >> 20));
    }
    offset_ += n;
  }

 private:
  const std::string& origin_;
  std::size_t offset_ = 0, line_ = 1, line_bytes_ = 0;
};

// Read through the shared input reader (util/input_file.h: a regular file, at most 4 GiB), with
// the byte checks run on each 64 KiB chunk as it arrives: a file with an overlong line is refused
// after its first MiB, before it is read whole.
std::string read_file(const std::string& path) {
  TextCheck check(path);
  return read_input_file(path, kObjFile, [&](const char* data, std::size_t n) { check.feed(data, n); });
}

// Reads the MTL files an OBJ names (mtllib) through the same input reader as every other file: a
// FIFO or /dev/zero named as an mtllib would otherwise block or read without end (tinyobjloader's
// own reader opens any path). A missing file is no error (many downloaded OBJs lack theirs; the
// faces get the default grey), but it is reported: see parse_obj.
class BoundedMtlReader : public tinyobj::MaterialReader {
 public:
  BoundedMtlReader(std::string dir, const std::string& obj) : dir_(std::move(dir)), obj_(obj) {}
  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* names, std::string* warn, std::string* err) override {
    const std::string path = (std::filesystem::path(dir_) / name).lexically_normal().string();
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
      missing_.push_back(path);
      return false;
    }
    std::string text;
    try {
      text = read_input_file(path, kMtlFile);
    } catch (const Error& e) {
      throw Error(fmt::format("OBJ file {}: mtllib {}: {}", obj_, name, e.what()));
    }
    std::istringstream in(text);
    tinyobj::LoadMtl(names, materials, &in, warn, err);
    return true;
  }
  const std::vector<std::string>& missing() const { return missing_; }

 private:
  std::string dir_;
  const std::string& obj_;  // the OBJ file, for messages
  std::vector<std::string> missing_;
};

// Checks the vertex index of every corner of an `f` line (p..e, after the "f"): an integer that
// parses completely, not 0, and (when negative) not counting back past the first vertex defined so
// far. tinyobjloader wraps an index like 99999999999999999999 to some int and reads "f a b c"
// as index 0, with a misleading message.
void check_face_line(const char* p, const char* e, const std::string& path, std::size_t line,
                     std::size_t vertices_so_far) {
  auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (p < e) {
    while (p < e && is_space(*p)) ++p;
    if (p == e) break;
    const char* tok = p;
    while (p < e && !is_space(*p)) ++p;
    std::string_view token(tok, static_cast<std::size_t>(p - tok));
    std::string_view index = token.substr(0, token.find('/'));
    long long v = 0;
    auto [stop, ec] = std::from_chars(index.data(), index.data() + index.size(), v);
    if (ec == std::errc::result_out_of_range || (ec == std::errc() && (v > INT32_MAX || v < -INT32_MAX)))
      throw Error(fmt::format("{}:{}: face index '{}' is out of range; fix the file", path, line, token));
    if (ec != std::errc() || stop != index.data() + index.size())
      throw Error(fmt::format("{}:{}: face corner '{}' is malformed (expected v, v/vt, v//vn or v/vt/vn with "
                              "integer indices); fix the file",
                              path, line, token));
    if (v == 0)
      throw Error(fmt::format("{}:{}: face index 0 is invalid (OBJ indices start at 1; negative ones count back "
                              "from the last vertex); fix the file",
                              path, line));
    if (v < 0 && static_cast<unsigned long long>(-v) > vertices_so_far)
      throw Error(fmt::format("{}:{}: face index {} counts back past the first vertex ({} vertices defined so far); "
                              "fix the file",
                              path, line, v, vertices_so_far));
  }
}

// Checks the first three coordinates of every `v` line: a number that parses completely and is
// finite. tinyobjloader reads "nan", "1e999" or "3.1+e2" without complaint as some value.
// Returns the number of `v` lines.
std::size_t check_vertex_lines(const std::string& text, const std::string& path) {
  std::size_t vertex = 0, line = 0, pos = 0;
  while (pos < text.size()) {
    ++line;
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const char* p = text.data() + pos;
    const char* e = text.data() + end;
    pos = end + 1;
    while (p < e && (*p == ' ' || *p == '\t')) ++p;
    if (e - p >= 2 && p[0] == 'f' && (p[1] == ' ' || p[1] == '\t')) {
      check_face_line(p + 2, e, path, line, vertex);
      continue;
    }
    if (e - p < 2 || p[0] != 'v' || (p[1] != ' ' && p[1] != '\t')) continue;
    p += 2;
    for (int axis = 0; axis < 3; ++axis) {
      while (p < e && (*p == ' ' || *p == '\t')) ++p;
      const char* tok = p;
      while (p < e && *p != ' ' && *p != '\t' && *p != '\r') ++p;
      std::string_view token(tok, static_cast<std::size_t>(p - tok));
      if (token.empty())
        throw Error(fmt::format("{}:{}: vertex {} has {} coordinate(s), an OBJ 'v' line needs 3; fix the file", path,
                                line, vertex + 1, axis));
      const char* first = token.data();
      if (*first == '+') ++first;
      float value = 0.0f;
      auto [stop, ec] = std::from_chars(first, token.data() + token.size(), value);
      if (ec == std::errc::result_out_of_range || (ec == std::errc() && !std::isfinite(value)))
        throw Error(fmt::format("{}:{}: vertex {} has a non-finite coordinate '{}' (NaN or Inf); fix the file", path,
                                line, vertex + 1, token));
      if (ec != std::errc() || stop != token.data() + token.size())
        throw Error(fmt::format("{}:{}: vertex {} has a malformed coordinate '{}'; fix the file", path, line,
                                vertex + 1, token));
    }
    ++vertex;
  }
  return vertex;
}

// The text tinyobjloader gets: `vw` (vertex weight) and `t` (subdivision tag) lines commented out.
// raysort uses neither, and tinyobjloader's readers of both are unsafe on hostile input (found by
// fuzz/obj_fuzzer): `vw` converts an infinite joint id to int (undefined), and `t` sizes its value
// arrays from counts written in the line, so a 62 KB file of tag lines took 2.5 GB. Every line keeps
// its place, so line numbers still hold.
bool is_ignored_statement(const std::string& text, std::size_t p) {
  auto blank = [&](std::size_t i) { return i < text.size() && (text[i] == ' ' || text[i] == '\t'); };
  return (text[p] == 'v' && p + 1 < text.size() && text[p + 1] == 'w' && blank(p + 2)) ||
         (text[p] == 't' && blank(p + 1));
}

std::string without_ignored_statements(const std::string& text) {
  std::string out;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t p = pos;
    while (p < text.size() && (text[p] == ' ' || text[p] == '\t')) ++p;
    if (p < text.size() && is_ignored_statement(text, p)) {
      if (out.empty()) out = text;
      out[p] = '#';
    }
    // tinyobjloader ends a line at \n, \r or \r\n (a second fuzz finding: lines split by \r alone).
    const std::size_t end = text.find_first_of("\r\n", pos);
    if (end == std::string::npos) break;
    pos = end + 1;
  }
  return out.empty() ? text : out;
}

}  // namespace

Mesh load_obj(const std::string& path, std::vector<Material>& materials) {
  std::string dir = std::filesystem::path(path).parent_path().string();
  return parse_obj(read_file(path), path, dir.empty() ? "." : dir, materials);
}

Mesh parse_obj(const std::string& text, const std::string& path, const std::string& mtl_dir,
               std::vector<Material>& materials) {
  if (text.empty()) throw Error(fmt::format("OBJ file {} is empty (0 bytes); give an OBJ file with faces", path));
  TextCheck(path).feed(text.data(), text.size());
  std::size_t vertex_lines = check_vertex_lines(text, path);

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> obj_materials;
  std::string warn, err;
  std::istringstream stream(without_ignored_statements(text));
  BoundedMtlReader mtl_reader(mtl_dir, path);
  bool ok = tinyobj::LoadObj(&attrib, &shapes, &obj_materials, &warn, &err, &stream, &mtl_reader,
                             /*triangulate=*/false);
  if (!ok || !err.empty()) {
    while (!err.empty() && (err.back() == '\n' || err.back() == '.')) err.pop_back();
    for (std::size_t at; (at = err.find('\n')) != std::string::npos;) err.replace(at, 1, "; ");  // one line
    throw Error(fmt::format("cannot read OBJ file {}: {}; fix the file", path, err.empty() ? "parse error" : err));
  }
  if (warn.find("Degenerated face") != std::string::npos)
    throw Error(fmt::format("OBJ file {} has a face with fewer than 3 vertices; remove or fix it", path));
  for (const std::string& mtl : mtl_reader.missing())
    fmt::print(stderr, "raysort: warning: OBJ file {} names the MTL file {} (mtllib), which does not exist; its "
               "materials get the default 0.7 grey albedo\n", path, mtl);

  std::size_t nverts = attrib.vertices.size() / 3;
  if (nverts != vertex_lines)
    throw Error(fmt::format("OBJ file {}: read {} vertices but the file has {} 'v' lines; fix the file", path, nverts,
                            vertex_lines));

  Mesh mesh;
  mesh.name = std::filesystem::path(path).stem().string();
  mesh.source = "obj:" + path;
  mesh.positions.resize(nverts);
  for (std::size_t i = 0; i < nverts; ++i) {
    mesh.positions[i] = {attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]};
    // tinyobjloader's own number reader can disagree with the check above: it reads "0.e0418548"
    // (zero, to std::from_chars) as NaN. Its values are the ones loaded, so they are checked too
    // (found by fuzz/obj_fuzzer).
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(mesh.positions[i][k]))
        throw Error(fmt::format("{}: vertex {} has a coordinate the OBJ reader (tinyobjloader) reads as non-finite "
                                "(NaN or Inf), e.g. a huge exponent; fix the file",
                                path, i + 1));
  }

  auto material_base = static_cast<std::int32_t>(materials.size());
  for (const auto& m : obj_materials) {
    Material mat;
    mat.name = m.name;
    mat.albedo = {m.diffuse[0], m.diffuse[1], m.diffuse[2]};
    materials.push_back(mat);
  }
  bool any_material = !obj_materials.empty();

  for (const auto& shape : shapes) {
    // tinyobjloader stores a face's vertex count in an unsigned char: a face of 256 or more
    // vertices wraps around, and its indices no longer line up with the counts.
    std::size_t counted = 0;
    for (auto n : shape.mesh.num_face_vertices) counted += n;
    if (counted != shape.mesh.indices.size())
      throw Error(fmt::format("OBJ file {}: object '{}' has a face with 256 or more vertices, which the OBJ reader "
                              "(tinyobjloader) cannot represent; split that polygon into smaller faces",
                              path, shape.name));
    std::size_t offset = 0;
    for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
      std::size_t n = shape.mesh.num_face_vertices[f];
      auto vertex_of = [&](std::size_t k) -> std::uint32_t {
        int v = shape.mesh.indices[offset + k].vertex_index;
        if (v < 0 || static_cast<std::size_t>(v) >= nverts)
          throw Error(fmt::format(
              "OBJ file {}: face {} of object '{}' refers to vertex {} but the file has {} vertices (indices start at "
              "1; negative ones count back from the last vertex); fix the face",
              path, f + 1, shape.name, v + 1, nverts));
        return static_cast<std::uint32_t>(v);
      };
      std::int32_t mat = 0;
      if (any_material && f < shape.mesh.material_ids.size() && shape.mesh.material_ids[f] >= 0)
        mat = material_base + shape.mesh.material_ids[f];
      auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        mesh.triangles.push_back({a, b, c});
        mesh.material.push_back(mat);
      };
      triangulate_polygon(mesh.positions, n, vertex_of, emit);
      offset += n;
    }
  }
  if (mesh.triangles.empty())
    throw Error(fmt::format("OBJ file {} has no triangles (no 'f' faces); a scene mesh needs at least one", path));
  // An OBJ without materials uses Scene::materials[0] throughout.
  if (!any_material) mesh.material.clear();
  return mesh;
}

}  // namespace raysort
