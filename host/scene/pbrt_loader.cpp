// pbrt-v4 scene files, the part a ray batch needs (docs/scene-format.md, "pbrt-v4"): triangle
// geometry (Shape "trianglemesh" and "plymesh"), Include/Import, the transform directives with
// AttributeBegin/End and named coordinate systems, ObjectBegin/End/ObjectInstance as instances,
// Camera "perspective" with the Film's resolution, diffuse reflectance as albedo, and lights:
// AreaLightSource (a sphere light over each emitting shape's box), LightSource "point" (a small
// sphere light) and "infinite" (the sky). Everything else is counted as ignored: nothing of pbrt's
// shading is read. pbrt-v4 has no Debian parser, so this is our own, over scene/pbrt_tokenizer.h.
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>

#include "scene/mesh_formats.h"
#include "scene/pbrt_tokenizer.h"
#include "util/error.h"

namespace fs = std::filesystem;

namespace raysort {

namespace {

using Matrix = std::array<double, 16>;  // row-major 4×4
constexpr Matrix kIdentity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
constexpr int kMaxIncludeDepth = 32;  // an Include cycle is refused, not followed until the stack ends

Matrix compose(const Matrix& a, const Matrix& b) {
  Matrix r{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) r[i * 4 + j] += a[i * 4 + k] * b[k * 4 + j];
  return r;
}

Matrix transpose(const Matrix& m) {
  Matrix r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r[i * 4 + j] = m[j * 4 + i];
  return r;
}

// Gauss–Jordan with partial pivoting; nullopt when singular.
std::optional<Matrix> inverse(Matrix a) {
  Matrix r = kIdentity;
  for (int c = 0; c < 4; ++c) {
    int p = c;
    for (int i = c + 1; i < 4; ++i)
      if (std::fabs(a[i * 4 + c]) > std::fabs(a[p * 4 + c])) p = i;
    if (!(std::fabs(a[p * 4 + c]) > 1e-300)) return std::nullopt;
    for (int k = 0; k < 4; ++k) std::swap(a[c * 4 + k], a[p * 4 + k]), std::swap(r[c * 4 + k], r[p * 4 + k]);
    const double d = a[c * 4 + c];
    for (int k = 0; k < 4; ++k) a[c * 4 + k] /= d, r[c * 4 + k] /= d;
    for (int i = 0; i < 4; ++i) {
      if (i == c) continue;
      const double f = a[i * 4 + c];
      for (int k = 0; k < 4; ++k) a[i * 4 + k] -= f * a[c * 4 + k], r[i * 4 + k] -= f * r[c * 4 + k];
    }
  }
  return r;
}

std::array<double, 3> apply(const Matrix& m, double x, double y, double z, double w) {
  return {m[0] * x + m[1] * y + m[2] * z + m[3] * w, m[4] * x + m[5] * y + m[6] * z + m[7] * w,
          m[8] * x + m[9] * y + m[10] * z + m[11] * w};
}

// pbrt's Rotate(theta, axis) (pbrt-v4 util/transform.h).
Matrix rotation(double deg, double x, double y, double z) {
  const double len = std::sqrt(x * x + y * y + z * z);
  x /= len, y /= len, z /= len;
  const double s = std::sin(deg * std::numbers::pi / 180), c = std::cos(deg * std::numbers::pi / 180);
  return {x * x + (1 - x * x) * c, x * y * (1 - c) - z * s, x * z * (1 - c) + y * s, 0,
          x * y * (1 - c) + z * s, y * y + (1 - y * y) * c, y * z * (1 - c) - x * s, 0,
          x * z * (1 - c) - y * s, y * z * (1 - c) + x * s, z * z + (1 - z * z) * c, 0,
          0, 0, 0, 1};
}

// A parameter "type name" value(s), e.g. "point3 P" [0 0 0 1 0 0 0 1 0].
struct PbrtParam {
  std::string type, name;
  std::vector<double> numbers;
  std::vector<std::string> strings;
};

// One directive with its positional arguments and its parameters.
struct Statement {
  std::string_view name;
  std::size_t line = 0;
  std::vector<std::string> strings;
  std::vector<double> numbers;
  std::vector<PbrtParam> params;

  const PbrtParam* find(std::string_view n) const {
    for (const auto& p : params)
      if (p.name == n) return &p;
    return nullptr;
  }
  double number(std::string_view n, double fallback) const {
    const PbrtParam* p = find(n);
    return p && !p->numbers.empty() ? p->numbers[0] : fallback;
  }
  std::string string(std::string_view n) const {
    const PbrtParam* p = find(n);
    return p && !p->strings.empty() ? p->strings[0] : "";
  }
};

double parse_number(PbrtTokenizer& tz, const PbrtToken& t) {
  const char* first = t.text.data();
  const char* last = first + t.text.size();
  if (first != last && *first == '+') ++first;
  double v = 0;
  auto [stop, ec] = std::from_chars(first, last, v);
  if (ec != std::errc() || stop != last || !std::isfinite(v))
    tz.fail(t.line, fmt::format("'{}' is not a finite number", t.text));
  return v;
}

void read_value(PbrtTokenizer& tz, const PbrtToken& t, PbrtParam& p) {
  if (t.kind == PbrtToken::Number) p.numbers.push_back(parse_number(tz, t));
  else if (t.kind == PbrtToken::String) p.strings.emplace_back(t.text);
  else if (t.kind == PbrtToken::Word && (t.text == "true" || t.text == "false")) p.numbers.push_back(t.text == "true");
  else tz.fail(t.line, fmt::format("parameter \"{} {}\" has a value '{}' that is no number, string or bool", p.type, p.name, t.text));
}

Statement read_statement(PbrtTokenizer& tz, const PbrtToken& word) {
  Statement s;
  s.name = word.text;
  s.line = word.line;
  while (true) {
    const PbrtToken t = tz.peek();
    if (t.kind == PbrtToken::End || t.kind == PbrtToken::Word) break;
    tz.next();
    if (t.kind == PbrtToken::Close) tz.fail(t.line, "a ']' without its '['");
    if (t.kind == PbrtToken::Open) {  // positional numbers in brackets (Transform [ ... ])
      for (PbrtToken v = tz.next(); v.kind != PbrtToken::Close; v = tz.next()) {
        if (v.kind != PbrtToken::Number) tz.fail(v.line, fmt::format("{} expects numbers in its brackets", s.name));
        s.numbers.push_back(parse_number(tz, v));
      }
    } else if (t.kind == PbrtToken::Number) {
      s.numbers.push_back(parse_number(tz, t));
    } else if (t.text.find(' ') == std::string_view::npos) {
      s.strings.emplace_back(t.text);
    } else {  // a parameter declaration "type name"
      PbrtParam p;
      const std::size_t space = t.text.find(' ');
      p.type = t.text.substr(0, space);
      const std::size_t name = t.text.find_first_not_of(' ', space);
      p.name = t.text.substr(name == std::string_view::npos ? t.text.size() : name);
      const PbrtToken v = tz.next();
      if (v.kind == PbrtToken::Open) {
        for (PbrtToken e = tz.next(); e.kind != PbrtToken::Close; e = tz.next()) {
          if (e.kind == PbrtToken::End) tz.fail(v.line, fmt::format("the '[' of parameter \"{}\" is never closed", t.text));
          read_value(tz, e, p);
        }
      } else if (v.kind == PbrtToken::End) {
        tz.fail(t.line, fmt::format("parameter \"{}\" has no value", t.text));
      } else {
        read_value(tz, v, p);
      }
      s.params.push_back(std::move(p));
    }
  }
  return s;
}

struct GraphicsState {
  Matrix ctm = kIdentity;
  std::int32_t material = 0;
  std::optional<Vec3> area_light;  // the emitted radiance of shapes made now
};

class PbrtLoader {
 public:
  explicit PbrtLoader(ForeignScene& out) : out_(out) {}

  void parse(const std::string& text, const std::string& origin, const std::string& dir, int depth) {
    if (depth > kMaxIncludeDepth)
      throw Error(fmt::format("pbrt-v4 file {}: Include/Import nested over {} deep (a file that includes itself?); fix "
                              "the includes", origin, kMaxIncludeDepth));
    PbrtTokenizer tz(text, origin);
    for (PbrtToken t = tz.next(); t.kind != PbrtToken::End; t = tz.next()) {
      if (t.kind != PbrtToken::Word)
        tz.fail(t.line, fmt::format("expected a directive (Shape, Camera, ...) but found '{}'", t.text));
      const Statement s = read_statement(tz, t);
      if (s.name == "Include" || s.name == "Import") {
        if (s.strings.size() != 1) tz.fail(s.line, fmt::format("{} needs one file name", s.name));
        const std::string path = resolve(dir, s.strings[0]);
        parse(read_input_file(path, kPbrtFile), path, dir, depth + 1);  // pbrt: paths stay relative to the first file
        continue;
      }
      directive(tz, s, dir);
    }
  }

  void finish(const std::string& origin);

 private:
  static std::string resolve(const std::string& dir, const std::string& name) {
    return fs::path(name).is_absolute() ? name : (fs::path(dir) / name).lexically_normal().string();
  }

  void need_numbers(PbrtTokenizer& tz, const Statement& s, std::size_t n) {
    if (s.numbers.size() != n) tz.fail(s.line, fmt::format("{} needs {} numbers, found {}", s.name, n, s.numbers.size()));
  }

  void directive(PbrtTokenizer& tz, const Statement& s, const std::string& dir);
  bool transform_directive(PbrtTokenizer& tz, const Statement& s);
  void shape(PbrtTokenizer& tz, const Statement& s, const std::string& dir);
  void add_triangles(PbrtTokenizer& tz, std::size_t line, const std::vector<Vec3>& object_points,
                     const std::vector<std::array<std::uint32_t, 3>>& tris);
  void material(PbrtTokenizer& tz, const Statement& s, const std::string& type, const std::string& name);
  void light(const Statement& s);
  void camera();
  std::string origin_;

  ForeignScene& out_;
  GraphicsState gs_;
  std::vector<GraphicsState> stack_;
  std::map<std::string, Matrix, std::less<>> coordinate_systems_;
  std::map<std::string, std::int32_t, std::less<>> named_materials_;
  Mesh world_;
  std::map<std::string, std::uint32_t, std::less<>> objects_;  // name → index in out_.scene.meshes
  std::optional<std::uint32_t> defining_;                      // the object between ObjectBegin and ObjectEnd
  std::vector<Instance> object_instances_;
  struct AreaShape {
    Aabb box;
    Vec3 radiance;
  };
  std::vector<AreaShape> area_shapes_;
  std::optional<Matrix> camera_from_world_;
  double fov_ = 90;
  std::uint32_t width_ = 1280, height_ = 720;  // pbrt-v4's default Film resolution
};

bool PbrtLoader::transform_directive(PbrtTokenizer& tz, const Statement& s) {
  const auto& n = s.numbers;
  if (s.name == "Identity") gs_.ctm = kIdentity;
  else if (s.name == "Translate") need_numbers(tz, s, 3), gs_.ctm = compose(gs_.ctm, {1, 0, 0, n[0], 0, 1, 0, n[1], 0, 0, 1, n[2], 0, 0, 0, 1});
  else if (s.name == "Scale") need_numbers(tz, s, 3), gs_.ctm = compose(gs_.ctm, {n[0], 0, 0, 0, 0, n[1], 0, 0, 0, 0, n[2], 0, 0, 0, 0, 1});
  else if (s.name == "Rotate") {
    need_numbers(tz, s, 4);
    if (!(n[1] * n[1] + n[2] * n[2] + n[3] * n[3] > 0)) tz.fail(s.line, "Rotate about a zero axis");
    gs_.ctm = compose(gs_.ctm, rotation(n[0], n[1], n[2], n[3]));
  } else if (s.name == "Transform" || s.name == "ConcatTransform") {
    need_numbers(tz, s, 16);
    Matrix m;  // pbrt writes the matrix column by column (its translation is numbers 13–15)
    std::copy(n.begin(), n.end(), m.begin());
    gs_.ctm = s.name == "Transform" ? transpose(m) : compose(gs_.ctm, transpose(m));
  } else if (s.name == "LookAt") {
    need_numbers(tz, s, 9);
    // pbrt-v4 LookAt: world-from-camera has columns right, up, dir, eye; the CTM takes its inverse.
    double d[3] = {n[3] - n[0], n[4] - n[1], n[5] - n[2]}, u[3] = {n[6], n[7], n[8]};
    auto normalize = [](double* v) {
      const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      for (int k = 0; k < 3; ++k) v[k] /= l;
      return l > 0;
    };
    if (!normalize(d) || !normalize(u)) tz.fail(s.line, "LookAt with the eye at the target, or a zero up vector");
    double r[3] = {u[1] * d[2] - u[2] * d[1], u[2] * d[0] - u[0] * d[2], u[0] * d[1] - u[1] * d[0]};
    if (!normalize(r)) tz.fail(s.line, "LookAt with the up vector along the view direction");
    const double up[3] = {d[1] * r[2] - d[2] * r[1], d[2] * r[0] - d[0] * r[2], d[0] * r[1] - d[1] * r[0]};
    const Matrix world_from_camera{r[0], up[0], d[0], n[0], r[1], up[1], d[1], n[1], r[2], up[2], d[2], n[2], 0, 0, 0, 1};
    gs_.ctm = compose(gs_.ctm, *inverse(world_from_camera));
  } else if (s.name == "CoordinateSystem") {
    if (s.strings.size() != 1) tz.fail(s.line, "CoordinateSystem needs one name");
    coordinate_systems_[s.strings[0]] = gs_.ctm;
  } else if (s.name == "CoordSysTransform") {
    if (s.strings.size() != 1) tz.fail(s.line, "CoordSysTransform needs one name");
    auto it = coordinate_systems_.find(s.strings[0]);
    if (it == coordinate_systems_.end()) tz.fail(s.line, fmt::format("no coordinate system named \"{}\"", s.strings[0]));
    gs_.ctm = it->second;
  } else {
    return false;
  }
  return true;
}

void PbrtLoader::directive(PbrtTokenizer& tz, const Statement& s, const std::string& dir) {
  auto first = [&](const char* what) {
    if (s.strings.empty()) tz.fail(s.line, fmt::format("{} needs a {} in quotes", s.name, what));
    return s.strings[0];
  };
  if (transform_directive(tz, s)) return;
  if (s.name == "WorldBegin") {
    gs_.ctm = kIdentity;
    coordinate_systems_["world"] = kIdentity;
  } else if (s.name == "AttributeBegin" || s.name == "TransformBegin") {
    stack_.push_back(gs_);
  } else if (s.name == "AttributeEnd" || s.name == "TransformEnd") {
    if (stack_.empty()) tz.fail(s.line, fmt::format("{} without its AttributeBegin", s.name));
    if (s.name == "TransformEnd") stack_.back().material = gs_.material, stack_.back().area_light = gs_.area_light;
    gs_ = stack_.back();
    stack_.pop_back();
  } else if (s.name == "Camera") {
    if (first("camera type") != "perspective") return out_.ignored.add(fmt::format("Camera \"{}\"", s.strings[0]));
    camera_from_world_ = gs_.ctm;
    const std::optional<Matrix> world_from_camera = inverse(gs_.ctm);
    if (!world_from_camera) tz.fail(s.line, "the camera transform is singular (a Scale by 0?)");
    coordinate_systems_["camera"] = *world_from_camera;
    fov_ = s.number("fov", 90);
  } else if (s.name == "Film") {
    width_ = std::uint32_t(std::clamp(s.number("xresolution", 1280), 1.0, 16384.0));
    height_ = std::uint32_t(std::clamp(s.number("yresolution", 720), 1.0, 16384.0));
  } else if (s.name == "Shape") {
    shape(tz, s, dir);
  } else if (s.name == "Material") {
    material(tz, s, first("material type"), "");
  } else if (s.name == "MakeNamedMaterial") {
    material(tz, s, s.string("type"), first("material name"));
  } else if (s.name == "NamedMaterial") {
    auto it = named_materials_.find(first("material name"));
    if (it == named_materials_.end()) tz.fail(s.line, fmt::format("no material named \"{}\" (MakeNamedMaterial first)", s.strings[0]));
    gs_.material = it->second;
  } else if (s.name == "AreaLightSource") {
    const PbrtParam* l = s.find("L");
    gs_.area_light = l && l->type == "rgb" && l->numbers.size() == 3
                         ? Vec3{float(l->numbers[0]), float(l->numbers[1]), float(l->numbers[2])}
                         : Vec3{1, 1, 1};
    if (!l || l->type != "rgb") out_.ignored.add("AreaLightSource radiance not given as rgb (white used)");
  } else if (s.name == "LightSource") {
    first("light type");
    light(s);
  } else if (s.name == "ObjectBegin") {
    if (defining_) tz.fail(s.line, "ObjectBegin inside another ObjectBegin");
    stack_.push_back(gs_);
    Mesh m;
    m.name = first("object name");
    m.source = "pbrt:" + tz.origin();
    defining_ = std::uint32_t(out_.scene.meshes.size());
    objects_[m.name] = *defining_;
    out_.scene.meshes.push_back(std::move(m));
  } else if (s.name == "ObjectEnd") {
    if (!defining_ || stack_.empty()) tz.fail(s.line, "ObjectEnd without its ObjectBegin");
    defining_.reset();
    gs_ = stack_.back();
    stack_.pop_back();
  } else if (s.name == "ObjectInstance") {
    auto it = objects_.find(first("object name"));
    if (it == objects_.end()) tz.fail(s.line, fmt::format("no object named \"{}\" (ObjectBegin first)", s.strings[0]));
    Affine a;
    for (int k = 0; k < 12; ++k) {
      a.m[std::size_t(k)] = float(gs_.ctm[std::size_t(k)]);
      if (!std::isfinite(a.m[std::size_t(k)])) tz.fail(s.line, "the instance's transform is beyond the float range");
    }
    object_instances_.push_back({it->second, a});
  } else if (s.name == "WorldEnd") {  // pbrt-v3's end marker: nothing to do
  } else {
    out_.ignored.add(std::string(s.name));  // render settings, media, textures, ...: by directive
  }
}

void PbrtLoader::add_triangles(PbrtTokenizer& tz, std::size_t line, const std::vector<Vec3>& object_points,
                               const std::vector<std::array<std::uint32_t, 3>>& tris) {
  Mesh& target = defining_ ? out_.scene.meshes[*defining_] : world_;
  const auto base = std::uint32_t(target.positions.size());
  Aabb box;
  for (const Vec3& p : object_points) {
    const auto w = apply(gs_.ctm, p[0], p[1], p[2], 1);
    target.positions.push_back({float(w[0]), float(w[1]), float(w[2])});
    for (float c : target.positions.back())
      if (!std::isfinite(c)) tz.fail(line, "a vertex of this shape, transformed, is beyond the float range");
    box.grow(target.positions.back());
  }
  for (const auto& t : tris) {
    target.triangles.push_back({base + t[0], base + t[1], base + t[2]});
    target.material.push_back(gs_.material);
  }
  if (gs_.area_light) {
    if (defining_) return out_.ignored.add("area light inside an object (not placed as a light)");
    area_shapes_.push_back({box, *gs_.area_light});
  }
}

void PbrtLoader::shape(PbrtTokenizer& tz, const Statement& s, const std::string& dir) {
  if (s.strings.size() != 1) tz.fail(s.line, "Shape needs one shape type in quotes");
  const std::string& type = s.strings[0];
  std::vector<Vec3> points;
  std::vector<std::array<std::uint32_t, 3>> tris;
  if (type == "trianglemesh") {
    const PbrtParam* p = s.find("P");
    if (!p || p->numbers.empty() || p->numbers.size() % 3) tz.fail(s.line, "trianglemesh needs \"point3 P\" with 3 numbers per vertex");
    for (std::size_t i = 0; i + 2 < p->numbers.size(); i += 3)
      points.push_back({float(p->numbers[i]), float(p->numbers[i + 1]), float(p->numbers[i + 2])});
    const PbrtParam* ix = s.find("indices");
    std::vector<double> idx = ix ? ix->numbers : std::vector<double>{};
    if (!ix && points.size() == 3) idx = {0, 1, 2};  // pbrt-v4: indices may be left out for one triangle
    if (idx.empty() || idx.size() % 3) tz.fail(s.line, "trianglemesh needs \"integer indices\" with 3 per triangle");
    for (std::size_t i = 0; i < idx.size(); i += 3) {
      std::array<std::uint32_t, 3> t;
      for (int k = 0; k < 3; ++k) {
        const double v = idx[i + std::size_t(k)];
        if (!(v >= 0 && v < double(points.size())) || v != std::floor(v))
          tz.fail(s.line, fmt::format("trianglemesh index {} is not a vertex (it has {})", v, points.size()));
        t[std::size_t(k)] = std::uint32_t(v);
      }
      tris.push_back(t);
    }
  } else if (type == "plymesh") {
    const std::string name = s.string("filename");
    if (name.empty()) tz.fail(s.line, "plymesh needs \"string filename\"");
    if (name.size() > 3 && name.compare(name.size() - 3, 3, ".gz") == 0)
      tz.fail(s.line, fmt::format("plymesh {} is gzip-compressed, which raysort does not read; gunzip it and name the .ply", name));
    const std::string path = resolve(dir, name);
    Mesh m = parse_ply(read_input_file(path, kPlyFile), path, out_.ignored);
    points = std::move(m.positions);
    tris = std::move(m.triangles);
    if (s.find("displacement")) out_.ignored.add("plymesh displacement");
  } else {
    return out_.ignored.add(fmt::format("Shape \"{}\"", type));
  }
  add_triangles(tz, s.line, points, tris);
}

void PbrtLoader::material(PbrtTokenizer& tz, const Statement& s, const std::string& type, const std::string& name) {
  if (type.empty()) tz.fail(s.line, "MakeNamedMaterial needs \"string type\"");
  Material m;
  m.name = name.empty() ? type : name;
  // Diffuse reflectance as albedo (pbrt-v4's default 0.5); other materials are that grey, and said so.
  m.albedo = {0.5f, 0.5f, 0.5f};
  const PbrtParam* r = s.find("reflectance");
  if (r && r->type == "rgb" && r->numbers.size() == 3)
    m.albedo = {float(r->numbers[0]), float(r->numbers[1]), float(r->numbers[2])};
  else if (r)
    out_.ignored.add(fmt::format("reflectance of type {} (grey used)", r->type));
  if (type != "diffuse" && type != "coateddiffuse" && type != "diffusetransmission" && type != "interface")
    out_.ignored.add(fmt::format("Material \"{}\" (grey diffuse used)", type));
  gs_.material = std::int32_t(out_.scene.materials.size());
  out_.scene.materials.push_back(m);
  if (!name.empty()) named_materials_[name] = gs_.material;
}

void PbrtLoader::light(const Statement& s) {
  const std::string& type = s.strings[0];
  const double scale = s.number("scale", 1);
  auto rgb = [&](std::string_view n) -> Vec3 {
    const PbrtParam* p = s.find(n);
    if (p && p->type == "rgb" && p->numbers.size() == 3)
      return {float(p->numbers[0] * scale), float(p->numbers[1] * scale), float(p->numbers[2] * scale)};
    if (p) out_.ignored.add(fmt::format("light {} of type {} (white used)", n, p->type));
    return {float(scale), float(scale), float(scale)};
  };
  if (type == "point") {
    const PbrtParam* from = s.find("from");
    const auto c = from && from->numbers.size() == 3 ? apply(gs_.ctm, from->numbers[0], from->numbers[1], from->numbers[2], 1)
                                                     : apply(gs_.ctm, 0, 0, 0, 1);
    SphereLight l;
    l.center = {float(c[0]), float(c[1]), float(c[2])};
    l.radius_relative = 0.005f;  // a point light: a small sphere (the renderer's lights are spheres)
    l.color = rgb("I");
    out_.scene.sphere_lights.push_back(l);
  } else if (type == "infinite") {
    out_.scene.sky.enabled = true;
    out_.scene.sky.zenith = out_.scene.sky.horizon = rgb("L");
    if (!s.string("filename").empty()) out_.ignored.add("infinite light image (a constant sky used)");
  } else {
    return out_.ignored.add(fmt::format("LightSource \"{}\"", type));
  }
  out_.has_lights = true;
}

void PbrtLoader::finish(const std::string& origin) {
  if (defining_ || !stack_.empty())
    throw Error(fmt::format("pbrt-v4 file {}: the file ends inside an AttributeBegin or ObjectBegin; close it", origin));
  Scene& sc = out_.scene;
  if (!world_.triangles.empty()) {
    world_.name = fs::path(origin).stem().string();
    world_.source = "pbrt:" + origin;
    sc.meshes.insert(sc.meshes.begin(), std::move(world_));
    for (auto& inst : object_instances_) ++inst.mesh;
    if (!object_instances_.empty()) sc.instances.push_back({0, Affine{}});
  }
  sc.instances.insert(sc.instances.end(), object_instances_.begin(), object_instances_.end());
  if (sc.triangle_count() == 0)
    throw Error(fmt::format("pbrt-v4 file {} has no triangles (Shape \"trianglemesh\" or \"plymesh\", placed); a "
                            "scene needs at least one", origin));
  const float extent = sc.bounds().largest_extent();
  for (const AreaShape& a : area_shapes_) {  // a sphere over the emitter's box, as wide as its diagonal
    SphereLight l;
    l.center = a.box.center();
    const Vec3 e = a.box.extent();
    l.radius_relative = std::max(0.001f, 0.5f * std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) / extent);
    l.color = a.radiance;
    sc.sphere_lights.push_back(l);
    out_.has_lights = true;
  }
  origin_ = origin;
  if (camera_from_world_) camera();
}

// pbrt's camera looks down its +z with +y up; its "fov" spans the image's shorter axis.
void PbrtLoader::camera() {
  const Matrix w = *inverse(*camera_from_world_);  // checked at the Camera directive
  Camera& c = out_.scene.camera;
  const auto eye = apply(w, 0, 0, 0, 1), dir = apply(w, 0, 0, 1, 0), up = apply(w, 0, 1, 0, 0);
  c.position = {float(eye[0]), float(eye[1]), float(eye[2])};
  c.look_at = {float(eye[0] + dir[0]), float(eye[1] + dir[1]), float(eye[2] + dir[2])};
  c.up = {float(up[0]), float(up[1]), float(up[2])};
  c.width = width_;
  c.height = height_;
  const double half = std::tan(std::clamp(fov_, 1e-3, 179.0) * std::numbers::pi / 360);
  c.fov_y_deg = float(width_ >= height_ ? fov_ : 2 * std::atan(half * height_ / width_) * 180 / std::numbers::pi);
  for (const Vec3& v : {c.position, c.look_at, c.up})
    for (float k : v)
      if (!std::isfinite(k))
        throw Error(fmt::format("pbrt-v4 file {}: the camera's position or direction is beyond the float range; fix "
                                "its transform", origin_));
  out_.has_camera = true;
}

}  // namespace

ForeignScene parse_pbrt(const std::string& text, const std::string& origin, const std::string& dir) {
  ForeignScene out;
  PbrtLoader loader(out);
  loader.parse(text, origin, dir, 0);
  loader.finish(origin);
  return out;
}

ForeignScene load_pbrt(const std::string& path) {
  const std::string dir = fs::path(path).parent_path().string();
  return parse_pbrt(read_input_file(path, kPbrtFile), path, dir.empty() ? "." : dir);
}

}  // namespace raysort
