// Encoders from files: the process's registry of them (see encoder_file.h).
#include "encode/encoder_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <deque>
#include <filesystem>

#include "encode/encoder_family.h"
#include "runtime/runtime.h"
#include "scene/provenance.h"
#include "util/error.h"
#include "util/input_file.h"

namespace raysort {

namespace {

namespace fs = std::filesystem;

// A file's encoder and its table row (whose names view the file's strings: a deque keeps both in
// place as more are loaded).
struct Registered {
  EncoderFile file;
  EncoderInfo info;
};

std::deque<Registered>& registry() {
  static std::deque<Registered> files;
  return files;
}

// Its stem names the encoder in cell ids, file names and tables: a plain name, as short as a scene's.
void check_stem(const std::string& path, const std::string& stem) {
  const bool plain = !stem.empty() && stem.size() <= 64 && std::isalnum(static_cast<unsigned char>(stem[0])) &&
                     std::all_of(stem.begin(), stem.end(), [](char c) {
                       return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
                     });
  if (!plain)
    throw Error(fmt::format("encoder file {}: its name '{}' names the encoder (file:{}), so it must start with a letter "
                            "or digit and hold only letters, digits, '-', '_' and '.' (at most 64); rename the file, "
                            "e.g. to my_encoder.cl",
                            path, stem, stem));
}

std::string read_encoder_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(fmt::format("encoder file {} does not exist; {}", path, kEncoderFile.fix));
  std::string text;
  try {
    text = read_input_file(path, kEncoderFile);
  } catch (const Error& e) {  // "cannot open encoder file X: Permission denied" says no fix yet
    const std::string what = e.what();
    throw Error(what.find(kEncoderFile.fix) == std::string::npos ? what + "; " + std::string(kEncoderFile.fix) : what);
  }
  if (text.find("rs_file_code") == std::string::npos)
    throw Error(fmt::format("encoder file {} does not define rs_file_code; define rs_u64 rs_file_code(const "
                            "RsEncodeFrame* frame, RsRay ray, uint bits, const RsFileScene* scene) in it "
                            "(docs/encoders.md, \"An encoder from a file\")",
                            path));
  return text;
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
}

}  // namespace

Encoder load_encoder_file(const std::string& path) {
  if (path.empty())
    throw Error(fmt::format("--encoders file: names no file; give the path of an OpenCL C file after it, e.g. "
                            "file:docs/examples/morton_zyx.cl"));
  const std::string stem = fs::path(path).stem().string();
  check_stem(path, stem);
  const std::string name = std::string(kFileEncoderPrefix) + stem;
  if (const std::optional<Encoder> known = find_encoder_file(name)) {
    const EncoderFile& had = *encoder_file(*known);
    if (same_file(had.path, path)) return *known;
    throw Error(fmt::format("encoder files {} and {} would both be the encoder {}; rename one (a result set names an "
                            "encoder from a file by its file name)",
                            had.path, path, name));
  }
  std::string text = read_encoder_file(path);
  const auto id = static_cast<Encoder>(RS_ENC_COUNT + static_cast<int>(registry().size()));
  Registered& r = registry().emplace_back();
  r.file = {id, name, path, std::move(text), ""};
  r.file.sha256 = sha256_text(r.file.text);
  // The cost weight of an unknown key (the shard planner's estimate): HCC's.
  r.info = {id, r.file.name, {}, &encoder_family_file(), "file", "encode_file", 128};
  return id;
}

const EncoderFile* encoder_file(Encoder e) {
  const int i = static_cast<int>(e) - RS_ENC_COUNT;
  return i >= 0 && i < static_cast<int>(registry().size()) ? &registry()[static_cast<std::size_t>(i)].file : nullptr;
}

const EncoderInfo* encoder_file_info(Encoder e) {
  const EncoderFile* f = encoder_file(e);
  return f ? &registry()[static_cast<std::size_t>(static_cast<int>(e) - RS_ENC_COUNT)].info : nullptr;
}

std::optional<Encoder> find_encoder_file(std::string_view name) {
  for (const Registered& r : registry())
    if (r.file.name == name) return r.file.id;
  return std::nullopt;
}

std::vector<Encoder> file_encoders() {
  std::vector<Encoder> ids;
  for (const Registered& r : registry()) ids.push_back(r.file.id);
  return ids;
}

std::string encoder_file_program(const EncoderFile& file) {
  // The path as a string literal of the #line directive: quotes and backslashes escaped, and no
  // control character (a newline would end the directive).
  std::string literal;
  for (char c : file.path) {
    if (c == '"' || c == '\\') literal += '\\';
    literal += std::iscntrl(static_cast<unsigned char>(c)) ? '?' : c;
  }
  return kernel_source("cl/encode_file.h") + fmt::format("#line 1 \"{}\"\n", literal) + file.text + "\n";
}

}  // namespace raysort
