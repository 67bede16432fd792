#pragma once
// Reading what a result set records of its encoders from files (encode/encoder_file.h): meta.json
// "encoder_files", {"file:<stem>": {"path", "sha256", "host_twin": false, "keys_checked"}}, which the
// runner writes only when the matrix runs one (a set without them keeps the meta it had). A resume
// with a file whose SHA-256 changed is refused as one with a changed scene file is, and compare,
// merge and the tables say which files the encoders came from. JSON only (the result-set fuzzer
// links it).
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace raysort {

// One line per encoder whose file's SHA-256 differs between two meta.json objects, or that only one
// of them records ("file:x: sha256 0123456789ab in A, ba9876543210 in B"); empty when they agree.
// Never throws: a malformed entry reads as no checksum.
std::vector<std::string> encoder_file_differences(const nlohmann::json& meta_a, const nlohmann::json& meta_b);
// The same for the ray file of run --rays (meta.json "ray_files", bench/batch_file.h): a resume with
// a changed file is refused.
std::vector<std::string> ray_file_differences(const nlohmann::json& meta_a, const nlohmann::json& meta_b);

// Each recorded file, in name order (the tables); "" for a field that is missing or not text.
struct RecordedEncoderFile {
  std::string name, path, sha256;
};
std::vector<RecordedEncoderFile> recorded_encoder_files(const nlohmann::json& meta);

}  // namespace raysort
