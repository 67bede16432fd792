#pragma once
// Encoders from files (issue 41, item 5): a user's OpenCL C file defining rs_file_code (cl/encode_file.h)
// becomes the encoder "file:<stem>" of this process, beside the encoders of the list (cl/encoders.h),
// without rebuilding raysort. Command lines name it by path (--encoders file:PATH); result sets name it
// "file:<stem>" and record the file's path and SHA-256 (meta.json "encoder_files"). Its keys come from
// the encoder family "file" (file_family.cpp); it has no host twin. docs/encoders.md, "An encoder from a
// file".
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "encode/encoder.h"

namespace raysort {

// What an encoder name starts with on the command line (a path follows) and in a result set (a stem).
inline constexpr std::string_view kFileEncoderPrefix = "file:";

struct EncoderFile {
  Encoder id;
  std::string name;    // "file:morton_zyx"
  std::string path;    // as given on the command line
  std::string text;    // the file as read: what is compiled
  std::string sha256;  // of text, 64 lowercase hex digits
};

// Reads PATH (util/input_file.h: a regular file, at most 16 MiB) and registers it as the encoder
// "file:<stem>". Reading the same file again gives the same encoder. Throws Error, one line naming the
// file and the fix, for a file that is missing, unreadable or not a regular file, a stem that is not
// a plain name, a file that does not define rs_file_code, or a second file with the same stem.
Encoder load_encoder_file(const std::string& path);

// The file behind an encoder, or null for the encoders of the list.
const EncoderFile* encoder_file(Encoder e);
// The registered encoder named "file:<stem>", if any (names as result sets spell them).
std::optional<Encoder> find_encoder_file(std::string_view name);
// The table row of a registered file encoder (encoder.h), or null for any other encoder.
const EncoderInfo* encoder_file_info(Encoder e);
// Every registered file encoder, in the order they were loaded.
std::vector<Encoder> file_encoders();

// The program source of a file encoder: cl/encode_file.h with its includes inlined, then the file
// under `#line 1 "PATH"`, so a build log names the file's own lines.
std::string encoder_file_program(const EncoderFile& file);

}  // namespace raysort
