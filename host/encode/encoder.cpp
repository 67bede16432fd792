// The encoder table, made from the encoder list (cl/encoders.h), and the encoders' names.
#include "encode/encoder.h"

#include <algorithm>
#include <cctype>

#include "encode/encoder_family.h"
#include "encode/encoder_file.h"
#include "util/error.h"

namespace raysort {

const std::vector<EncoderInfo>& encoder_table() {
// A row's aliases come in parentheses (cl/encoders.h); RS_UNPAREN opens them into the initializer.
#define RS_UNPAREN(...) __VA_ARGS__
#define RS_FAMILY_ROW(ID, HOST, NAME, FAMILY, WEIGHT, ALIASES) \
  {Encoder::HOST, NAME, {RS_UNPAREN ALIASES}, &encoder_family_##FAMILY(), #FAMILY, "encode_" #FAMILY, WEIGHT},
#define RS_SPATIAL_ROW(ID, HOST, NAME, CODE, WEIGHT, ALIASES) \
  {Encoder::HOST, NAME, {RS_UNPAREN ALIASES}, &encoder_family_spatial(), "spatial", "encode_" #CODE, WEIGHT},
  static const std::vector<EncoderInfo> table = {RS_ENCODERS(RS_FAMILY_ROW, RS_SPATIAL_ROW)};
#undef RS_FAMILY_ROW
#undef RS_SPATIAL_ROW
#undef RS_UNPAREN
  return table;
}

const EncoderInfo& encoder_info(Encoder e) {
  const auto& table = encoder_table();
  const auto i = static_cast<std::size_t>(e);
  if (i < table.size() && table[i].id == e) return table[i];
  // Past the list: an encoder from a file (encoder_file.h).
  if (const EncoderInfo* file = encoder_file_info(e)) return *file;
  throw Error("encoder_info: an encoder outside the table");
}

const EncoderFamily& encoder_family(Encoder e) { return *encoder_info(e).family; }

std::string_view encoder_name(Encoder e) { return encoder_info(e).name; }

std::optional<Encoder> parse_encoder(std::string_view name) {
  // An encoder from a file, as result sets name it ("file:<stem>", once loaded): spelled exactly.
  if (name.starts_with(kFileEncoderPrefix)) return find_encoder_file(name);
  auto folded = [](std::string_view text) {
    std::string s;
    for (char c : text)
      if (c != '-' && c != '_' && c != ' ') s += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string wanted = folded(name);
  for (const EncoderInfo& info : encoder_table()) {
    if (folded(info.name) == wanted) return info.id;
    for (std::string_view alias : info.aliases)
      if (folded(alias) == wanted) return info.id;
  }
  return std::nullopt;
}

const std::vector<Encoder>& all_encoders() {
  static const std::vector<Encoder> all = [] {
    std::vector<Encoder> ids;
    for (const EncoderInfo& info : encoder_table()) ids.push_back(info.id);
    return ids;
  }();
  return all;
}

std::vector<Encoder> parse_encoders(const std::vector<std::string>& names) {
  if (names.size() == 1 && names[0] == "all") return all_encoders();
  std::vector<Encoder> out;
  for (const auto& name : names) {
    // file:PATH loads the file (encoder_file.h); the same path twice is one encoder.
    const auto e = name.starts_with(kFileEncoderPrefix)
                       ? std::optional<Encoder>(load_encoder_file(name.substr(kFileEncoderPrefix.size())))
                       : parse_encoder(name);
    if (!e) {
      std::string valid;
      for (const EncoderInfo& info : encoder_table()) valid += (valid.empty() ? "" : ", ") + std::string(info.name);
      throw Error("unknown encoder '" + name + "'; encoders are: " + valid +
                  ", or file:PATH (an OpenCL C file; docs/encoders.md, \"An encoder from a file\")");
    }
    if (std::find(out.begin(), out.end(), *e) == out.end()) out.push_back(*e);
  }
  return out;
}

unsigned max_key_bits(Encoder) { return RS_MAX_KEY_BITS; }

}  // namespace raysort
