// The ray batch file (see ray_file.h; docs/rays-format.md).
#include "render/ray_file.h"

#include <fmt/format.h>

#include <bit>
#include <cstring>
#include <filesystem>

#include "util/atomic_file.h"
#include "util/error.h"

namespace raysort {

namespace {

// Little-endian on every host: bytes are put and taken one by one, never by copying a struct.
void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
void put_u64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
void put_f32(std::string& out, float v) { put_u32(out, std::bit_cast<std::uint32_t>(v)); }

std::uint64_t get_le(const std::string& in, std::size_t at, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= std::uint64_t{static_cast<unsigned char>(in[at + i])} << (8 * i);
  return v;
}
std::uint32_t get_u32(const std::string& in, std::size_t at) { return static_cast<std::uint32_t>(get_le(in, at, 4)); }
float get_f32(const std::string& in, std::size_t at) { return std::bit_cast<float>(get_u32(in, at)); }

// How the messages send a user to a good file.
constexpr const char* kExportAgain = "export the batch again with `raysort rays --export` (docs/rays-format.md)";

}  // namespace

std::string ray_file_bytes(const RayFile& f) {
  std::string out(kRayFileMagic, sizeof kRayFileMagic);
  put_u32(out, kRayFileVersion);
  put_u32(out, (f.has_hits ? kRayFileHasHits : 0u) | (f.any_hit ? kRayFileAnyHit : 0u));
  put_u64(out, f.rays.size());
  out.append(reinterpret_cast<const char*>(f.scene_sha256.data()), f.scene_sha256.size());
  put_u32(out, static_cast<std::uint32_t>(f.batch_name.size()));
  put_u32(out, static_cast<std::uint32_t>(f.command.size()));
  out += f.batch_name;
  out += f.command;
  out.reserve(out.size() + f.rays.size() * (kRayFileRayBytes + (f.has_hits ? kRayFileHitBytes : 0)));
  for (const RsRay& r : f.rays) {
    for (float v : {r.o[0], r.o[1], r.o[2], r.d[0], r.d[1], r.d[2], r.tmin, r.tmax}) put_f32(out, v);
  }
  if (f.has_hits)
    for (const RsHit& h : f.hits) {
      put_f32(out, h.t);
      put_u32(out, h.tri);
    }
  return out;
}

RayFile parse_ray_file(const std::string& in, const std::string& path) {
  auto refuse = [&](const std::string& what) { return Error(fmt::format("ray file {}: {}; {}", path, what, kExportAgain)); };
  if (in.size() < sizeof kRayFileMagic || std::memcmp(in.data(), kRayFileMagic, sizeof kRayFileMagic) != 0)
    throw refuse("not a raysort ray batch (bad magic: it must start with \"RSRAYS\\r\\n\")");
  if (in.size() < kRayFileHeaderBytes)
    throw refuse(fmt::format("truncated: {} bytes, shorter than the {}-byte header", in.size(), kRayFileHeaderBytes));
  const std::uint32_t version = get_u32(in, 8);
  if (version != kRayFileVersion)
    throw refuse(fmt::format("format version {}, this raysort reads version {}", version, kRayFileVersion));
  const std::uint32_t flags = get_u32(in, 12);
  if (flags & ~(kRayFileHasHits | kRayFileAnyHit)) throw refuse(fmt::format("unknown flags 0x{:x} in the header", flags));
  const std::uint64_t n = get_le(in, 16, 8);
  const std::uint32_t name_bytes = get_u32(in, 56), command_bytes = get_u32(in, 60);
  if (n > kRayFileMaxRays || name_bytes > kRayFileMaxText || command_bytes > kRayFileMaxText)
    throw refuse(fmt::format("damaged header: {} rays, a {}-byte name, a {}-byte command", n, name_bytes, command_bytes));
  RayFile f;
  f.has_hits = flags & kRayFileHasHits;
  f.any_hit = flags & kRayFileAnyHit;
  const std::size_t rays_at = kRayFileHeaderBytes + name_bytes + command_bytes;
  const std::uint64_t expected = rays_at + n * (kRayFileRayBytes + (f.has_hits ? kRayFileHitBytes : 0));
  if (in.size() < expected)
    throw refuse(fmt::format("truncated: {} bytes, but its header's {} rays{} need {}", in.size(), n,
                             f.has_hits ? " with hits" : "", expected));
  if (in.size() > expected)
    throw refuse(fmt::format("{} bytes, but its header's {} rays{} need {}: the ray count does not match the file",
                             in.size(), n, f.has_hits ? " with hits" : "", expected));
  std::memcpy(f.scene_sha256.data(), in.data() + 24, f.scene_sha256.size());
  f.batch_name = in.substr(kRayFileHeaderBytes, name_bytes);
  f.command = in.substr(kRayFileHeaderBytes + name_bytes, command_bytes);
  if (f.batch_name.empty()) throw refuse("the batch has no name in its header");
  f.rays.resize(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    const std::size_t at = rays_at + i * kRayFileRayBytes;
    RsRay& r = f.rays[i];
    for (int k = 0; k < 3; ++k) r.o[k] = get_f32(in, at + 4 * k), r.d[k] = get_f32(in, at + 12 + 4 * k);
    r.tmin = get_f32(in, at + 24);
    r.tmax = get_f32(in, at + 28);
  }
  if (f.has_hits) {
    f.hits.resize(n);
    const std::size_t hits_at = rays_at + n * kRayFileRayBytes;
    for (std::uint64_t i = 0; i < n; ++i)
      f.hits[i] = RsHit{get_f32(in, hits_at + i * kRayFileHitBytes), get_u32(in, hits_at + i * kRayFileHitBytes + 4), 0.0f, 0.0f};
  }
  return f;
}

RayFile read_ray_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw Error(fmt::format("ray file {} {}; give the path of a file that `raysort rays --export` wrote (docs/rays-format.md)",
                            path, std::filesystem::exists(path, ec) ? "is not a regular file" : "does not exist"));
  return parse_ray_file(read_file(path), path);
}

void write_ray_file(const std::string& path, const RayFile& f) { write_file_atomically(path, ray_file_bytes(f)); }

std::array<std::uint8_t, 32> sha256_bytes(const std::string& hex) {
  std::array<std::uint8_t, 32> out{};
  auto digit = [&](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    throw Error(fmt::format("'{}' is not a SHA-256 (64 lowercase hex digits)", hex));
  };
  if (hex.size() != 64) throw Error(fmt::format("'{}' is not a SHA-256 (64 lowercase hex digits)", hex));
  for (std::size_t i = 0; i < 32; ++i) out[i] = static_cast<std::uint8_t>(digit(hex[2 * i]) * 16 + digit(hex[2 * i + 1]));
  return out;
}

std::string sha256_hex(const std::array<std::uint8_t, 32>& bytes) {
  std::string out;
  for (std::uint8_t b : bytes) out += fmt::format("{:02x}", b);
  return out;
}

}  // namespace raysort
