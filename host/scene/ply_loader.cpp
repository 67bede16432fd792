// PLY meshes (ascii, binary_little_endian, binary_big_endian), read by a small reader of our own
// rather than a library: a PLY's semantics are a header and a table of numbers, and this way the
// vertices are exactly the file's floats in the file's order (no merging, no reordering), a bad file
// is refused naming its line or byte offset, and the fuzzer sees every line that runs.
// Read: element "vertex" (properties x, y, z) and element "face" (list vertex_indices or
// vertex_index); every other element and property is counted as ignored.
#include <fmt/format.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "scene/mesh_formats.h"
#include "scene/polygon.h"
#include "util/error.h"

namespace raysort {

namespace {

enum class PlyEncoding { Ascii, BinaryLittle, BinaryBig };

// The scalar types of the PLY header, with both the PLY 1.0 names and the sized ones.
struct PlyType {
  std::string_view names[2];
  std::size_t bytes;
  bool is_float, is_signed;
};
constexpr PlyType kPlyTypes[] = {
    {{"char", "int8"}, 1, false, true},     {{"uchar", "uint8"}, 1, false, false},
    {{"short", "int16"}, 2, false, true},   {{"ushort", "uint16"}, 2, false, false},
    {{"int", "int32"}, 4, false, true},     {{"uint", "uint32"}, 4, false, false},
    {{"float", "float32"}, 4, true, true},  {{"double", "float64"}, 8, true, true},
};

struct PlyProperty {
  std::string name;
  const PlyType* type = nullptr;
  const PlyType* count_type = nullptr;  // a list: the type of its length
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::Ascii;
  std::vector<PlyElement> elements;
  std::size_t body = 0;       // byte offset of the data
  std::size_t body_line = 0;  // its line (ascii)
};

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t p = 0;
  while (p < line.size()) {
    while (p < line.size() && (line[p] == ' ' || line[p] == '\t' || line[p] == '\r')) ++p;
    std::size_t s = p;
    while (p < line.size() && line[p] != ' ' && line[p] != '\t' && line[p] != '\r') ++p;
    if (p > s) out.push_back(line.substr(s, p - s));
  }
  return out;
}

const PlyType* find_type(std::string_view name) {
  for (const PlyType& t : kPlyTypes)
    if (t.names[0] == name || t.names[1] == name) return &t;
  return nullptr;
}

PlyHeader read_header(const std::string& bytes, const std::string& origin, IgnoredFeatures& ignored) {
  auto fail = [&](std::size_t line, const std::string& why) {
    throw Error(fmt::format("PLY file {}:{}: {}; fix the header (docs/scene-format.md, \"PLY\")", origin, line, why));
  };
  if (bytes.compare(0, 3, "ply") != 0 || bytes.size() < 4 || (bytes[3] != '\n' && bytes[3] != '\r'))
    fail(1, "the file does not start with the line \"ply\", so it is no PLY file");
  PlyHeader h;
  bool have_format = false;
  std::size_t pos = 0, line = 0;
  while (true) {
    std::size_t end = bytes.find('\n', pos);
    ++line;
    if (end == std::string::npos) fail(line, "the header has no \"end_header\" line");
    std::string_view text(bytes.data() + pos, end - pos);
    pos = end + 1;
    auto w = split_words(text);
    if (w.empty() || line == 1 || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") break;
    if (w[0] == "format") {
      if (w.size() != 3 || w[2] != "1.0") fail(line, "expected \"format ascii|binary_little_endian|binary_big_endian 1.0\"");
      if (w[1] == "ascii") h.encoding = PlyEncoding::Ascii;
      else if (w[1] == "binary_little_endian") h.encoding = PlyEncoding::BinaryLittle;
      else if (w[1] == "binary_big_endian") h.encoding = PlyEncoding::BinaryBig;
      else fail(line, fmt::format("unknown format '{}'", w[1]));
      have_format = true;
    } else if (w[0] == "element") {
      std::uint64_t n = 0;
      if (w.size() != 3 || std::from_chars(w[2].data(), w[2].data() + w[2].size(), n).ptr != w[2].data() + w[2].size())
        fail(line, "expected \"element NAME COUNT\" with a whole-number count");
      h.elements.push_back({std::string(w[1]), n, {}});
    } else if (w[0] == "property") {
      if (h.elements.empty()) fail(line, "a property before any element");
      PlyProperty p;
      if (w.size() == 5 && w[1] == "list") {
        p.count_type = find_type(w[2]);
        p.type = find_type(w[3]);
        if (!p.count_type || p.count_type->is_float) fail(line, fmt::format("list length type '{}' is not an integer type", w[2]));
        p.name = w[4];
      } else if (w.size() == 3) {
        p.type = find_type(w[1]);
        p.name = w[2];
      } else {
        fail(line, "expected \"property TYPE NAME\" or \"property list COUNT_TYPE TYPE NAME\"");
      }
      if (!p.type) fail(line, fmt::format("unknown property type in '{}'", text));
      h.elements.back().properties.push_back(std::move(p));
    } else {  // a free-text line some exporters write (Blender 2.4: "Created by ..."), as a comment
      ignored.add("header line that is no PLY keyword");
    }
  }
  if (!have_format) fail(line, "the header has no \"format\" line");
  h.body = pos;
  h.body_line = line + 1;
  return h;
}

// The values of the body, one at a time, as double; errors name the line (ascii) or byte offset.
class PlyBody {
 public:
  PlyBody(const std::string& bytes, const PlyHeader& h, const std::string& origin)
      : bytes_(bytes), encoding_(h.encoding), pos_(h.body), line_(h.body_line), origin_(origin) {}

  double next(const PlyType& type, std::string_view what) {
    if (encoding_ == PlyEncoding::Ascii) return next_ascii(type, what);
    if (bytes_.size() - pos_ < type.bytes)
      fail(fmt::format("the file ends inside {} (truncated?)", what));
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + pos_, type.bytes);
    const bool file_little = encoding_ == PlyEncoding::BinaryLittle;
    if (file_little != (std::endian::native == std::endian::little))
      for (std::size_t i = 0; i < type.bytes / 2; ++i) std::swap(raw[i], raw[type.bytes - 1 - i]);
    pos_ += type.bytes;
    return decode(raw, type);
  }
  // Bytes (binary) or characters (ascii) left: a count larger than this cannot be in the file.
  std::size_t left() const { return bytes_.size() - pos_; }
  [[noreturn]] void fail(const std::string& why) const {
    if (encoding_ == PlyEncoding::Ascii)
      throw Error(fmt::format("PLY file {}:{}: {}; fix the file", origin_, line_, why));
    throw Error(fmt::format("PLY file {}: byte {}: {}; fix the file", origin_, pos_, why));
  }

 private:
  static double decode(const unsigned char* raw, const PlyType& type) {
    switch (type.bytes * 4 + (type.is_float ? 2 : 0) + (type.is_signed ? 1 : 0)) {
      case 4 * 1 + 1: return std::int8_t(raw[0]);
      case 4 * 1: return raw[0];
      case 4 * 2 + 1: { std::int16_t v; std::memcpy(&v, raw, 2); return v; }
      case 4 * 2: { std::uint16_t v; std::memcpy(&v, raw, 2); return v; }
      case 4 * 4 + 1: { std::int32_t v; std::memcpy(&v, raw, 4); return v; }
      case 4 * 4: { std::uint32_t v; std::memcpy(&v, raw, 4); return v; }
      case 4 * 4 + 3: { float v; std::memcpy(&v, raw, 4); return v; }
      default: { double v; std::memcpy(&v, raw, 8); return v; }
    }
  }
  double next_ascii(const PlyType& type, std::string_view what) {
    while (pos_ < bytes_.size() && (bytes_[pos_] == ' ' || bytes_[pos_] == '\t' || bytes_[pos_] == '\r' ||
                                   bytes_[pos_] == '\n'))
      line_ += bytes_[pos_++] == '\n';
    std::size_t s = pos_;
    while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    if (s == pos_) fail(fmt::format("the file ends before {} (fewer values than the header declares)", what));
    const char* first = bytes_.data() + s;
    const char* last = bytes_.data() + pos_;
    if (*first == '+') ++first;
    double v = 0;
    auto [stop, ec] = std::from_chars(first, last, v);
    if (ec != std::errc() || stop != last)
      fail(fmt::format("'{}' is not a number ({})", std::string_view(bytes_.data() + s, pos_ - s), what));
    if (!type.is_float && v != std::floor(v))
      fail(fmt::format("'{}' is not a whole number, as the header's {} type says ({})",
                       std::string_view(bytes_.data() + s, pos_ - s), type.names[0], what));
    return v;
  }

  const std::string& bytes_;
  PlyEncoding encoding_;
  std::size_t pos_, line_;
  const std::string& origin_;
};

// The fewest bytes one record of `e` takes in the file (a list at its length alone; ascii: a digit and
// a separator per value): a count whose records cannot fit in the bytes left is refused before any
// memory is sized by it.
std::uint64_t min_record_bytes(const PlyElement& e, PlyEncoding encoding) {
  std::uint64_t n = 0;
  for (const auto& p : e.properties)
    n += encoding == PlyEncoding::Ascii ? 2 : (p.count_type ? p.count_type : p.type)->bytes;
  return n;
}

void check_count(PlyBody& body, const PlyElement& e, PlyEncoding encoding) {
  const std::uint64_t each = min_record_bytes(e, encoding);
  if (each > 0 && e.count > body.left() / each)
    body.fail(fmt::format("element {} declares {} records, more than the {} bytes left can hold", e.name, e.count, body.left()));
}

void read_vertices(PlyBody& body, const PlyElement& e, Mesh& mesh) {
  int axis_of[64];
  bool have[3] = {false, false, false};
  if (e.properties.size() > 64) body.fail("the vertex element has more than 64 properties");
  for (std::size_t i = 0; i < e.properties.size(); ++i) {
    const std::string& n = e.properties[i].name;
    axis_of[i] = n == "x" ? 0 : n == "y" ? 1 : n == "z" ? 2 : -1;
    if (axis_of[i] >= 0) {
      if (e.properties[i].count_type) body.fail(fmt::format("vertex property '{}' is a list, not a number", n));
      have[axis_of[i]] = true;
    }
  }
  if (!have[0] || !have[1] || !have[2]) body.fail("the vertex element lacks one of the properties x, y, z");
  mesh.positions.resize(e.count);
  for (std::uint64_t v = 0; v < e.count; ++v) {
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      const std::string what = fmt::format("vertex {} property {}", v, p.name);
      if (p.count_type) {  // a list we do not use: read past it
        double n = body.next(*p.count_type, what);
        if (n < 0 || n > double(body.left())) body.fail(fmt::format("list length {} is out of range ({})", n, what));
        for (std::uint64_t k = 0; k < std::uint64_t(n); ++k) body.next(*p.type, what);
        continue;
      }
      double value = body.next(*p.type, what);
      if (axis_of[i] < 0) continue;
      float f = static_cast<float>(value);
      if (!std::isfinite(f)) body.fail(fmt::format("{} is {} (not a finite float)", what, value));
      mesh.positions[v][axis_of[i]] = f;
    }
  }
}

void read_faces(PlyBody& body, const PlyElement& e, Mesh& mesh) {
  std::size_t list = e.properties.size();
  for (std::size_t i = 0; i < e.properties.size(); ++i)
    if ((e.properties[i].name == "vertex_indices" || e.properties[i].name == "vertex_index") &&
        e.properties[i].count_type && !e.properties[i].type->is_float)
      list = i;
  if (list == e.properties.size())
    body.fail("the face element has no integer list property vertex_indices (or vertex_index)");
  const std::size_t nverts = mesh.positions.size();
  std::vector<std::uint32_t> corners;
  for (std::uint64_t f = 0; f < e.count; ++f) {
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      const std::string what = fmt::format("face {} property {}", f, p.name);
      std::size_t n = 1;
      if (p.count_type) {
        double len = body.next(*p.count_type, what);
        if (len < 0 || len > double(body.left())) body.fail(fmt::format("list length {} is out of range ({})", len, what));
        n = static_cast<std::size_t>(len);
      }
      if (i != list) {
        for (std::size_t k = 0; k < n; ++k) body.next(*p.type, what);
        continue;
      }
      if (n < 3) body.fail(fmt::format("{} has {} vertices; a face needs at least 3", what, n));
      corners.resize(n);
      for (std::size_t k = 0; k < n; ++k) {
        double idx = body.next(*p.type, what);
        if (idx < 0 || idx >= double(nverts))
          body.fail(fmt::format("{} refers to vertex {} but the file has {} vertices (indices start at 0)", what, idx,
                                nverts));
        corners[k] = static_cast<std::uint32_t>(idx);
      }
      triangulate_polygon(mesh.positions, n, [&](std::size_t k) { return corners[k]; },
                          [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) { mesh.triangles.push_back({a, b, c}); });
    }
  }
}

}  // namespace

Mesh parse_ply(const std::string& bytes, const std::string& origin, IgnoredFeatures& ignored) {
  const PlyHeader header = read_header(bytes, origin, ignored);
  PlyBody body(bytes, header, origin);
  Mesh mesh;
  mesh.name = std::filesystem::path(origin).stem().string();
  mesh.source = "ply:" + origin;
  bool have_vertices = false;
  for (const PlyElement& e : header.elements) {
    check_count(body, e, header.encoding);
    if (e.name == "vertex") {
      if (have_vertices) body.fail("a second vertex element; a PLY mesh has one");
      read_vertices(body, e, mesh);
      have_vertices = true;
      for (const auto& p : e.properties)
        if (p.name != "x" && p.name != "y" && p.name != "z") ignored.add(fmt::format("vertex property \"{}\"", p.name));
    } else if (e.name == "face") {
      if (!have_vertices) body.fail("the face element comes before the vertex element");
      read_faces(body, e, mesh);
      for (const auto& p : e.properties)
        if (p.name != "vertex_indices" && p.name != "vertex_index")
          ignored.add(fmt::format("face property \"{}\"", p.name));
    } else {
      // Skipped value by value: its size is only known by reading it (lists). An element without
      // properties takes no bytes, whatever its count (found by fuzz/ply_fuzzer: a count of 2^63 spun).
      for (std::uint64_t k = 0; k < e.count && !e.properties.empty(); ++k)
        for (const auto& p : e.properties) {
          const std::string what = fmt::format("{} {} property {}", e.name, k, p.name);
          std::size_t n = 1;
          if (p.count_type) {
            double len = body.next(*p.count_type, what);
            if (len < 0 || len > double(body.left())) body.fail(fmt::format("list length {} is out of range ({})", len, what));
            n = static_cast<std::size_t>(len);
          }
          for (std::size_t i = 0; i < n; ++i) body.next(*p.type, what);
        }
      ignored.add(fmt::format("element \"{}\"", e.name), e.count);
    }
  }
  if (mesh.triangles.empty())
    throw Error(fmt::format("PLY file {} has no faces (a point cloud?); a scene mesh needs at least one triangle; give "
                            "a PLY with a face element",
                            origin));
  return mesh;
}

ForeignScene load_ply(const std::string& path) {
  ForeignScene f;
  f.scene.meshes.push_back(parse_ply(read_input_file(path, kPlyFile), path, f.ignored));
  return f;
}

}  // namespace raysort
