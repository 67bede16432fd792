#pragma once
// Ray batches out and in (issue 45, item 2): one batch in a little-endian binary file, so that
// another tracer can trace exactly the suite's rays (`raysort rays --export`), and the suite can
// encode, sort and trace a batch another renderer produced (`trace`, `run`, `encodebench --rays`).
// The layout is docs/rays-format.md; scripts/read_rays.py reads it in Python.
//
//   offset  size  field
//        0     8  magic "RSRAYS\r\n" (the \r\n catches a text-mode copy, as PNG's magic does)
//        8     4  u32 format version (kRayFileVersion)
//       12     4  u32 flags: bit 0 hits follow the rays, bit 1 an any-hit (shadow) batch
//       16     8  u64 ray count n
//       24    32  the scene's SHA-256, raw bytes (bench/scene_checksum.h)
//       56     4  u32 length N of the batch name, bytes
//       60     4  u32 length M of the generating command line, bytes
//       64     N  batch name, UTF-8 ("bounce1")
//     64+N     M  command line, UTF-8
//   64+N+M  32 n  per ray: origin x y z, direction x y z, tmin, tmax (float32)
//           8 n   with flag bit 0, per ray: hit t (float32), triangle id (u32, 0xFFFFFFFF = miss)
//
// No padding anywhere; the file ends after the last record, so its size follows from the header,
// and a file of another size is refused (truncated, or a count that does not match).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "shared.h"

namespace raysort {

inline constexpr char kRayFileMagic[8] = {'R', 'S', 'R', 'A', 'Y', 'S', '\r', '\n'};
inline constexpr std::uint32_t kRayFileVersion = 1;
inline constexpr std::uint32_t kRayFileHasHits = 1u << 0;
inline constexpr std::uint32_t kRayFileAnyHit = 1u << 1;
inline constexpr std::size_t kRayFileHeaderBytes = 64;  // before the name and the command
inline constexpr std::size_t kRayFileRayBytes = 32;
inline constexpr std::size_t kRayFileHitBytes = 8;
// A batch's rays are numbered by 32-bit ids on the device (orders, triangle-free hit records).
inline constexpr std::uint64_t kRayFileMaxRays = 0xFFFFFFFFull;
// The name and the command are short texts; a longer length is a damaged header.
inline constexpr std::uint32_t kRayFileMaxText = 1u << 20;

struct RayFile {
  std::string batch_name;                // as generated: "primary", "shadow<k>", "bounce<k>", or another renderer's
  bool any_hit = false;                  // shadow rays: the trace stops at the first hit
  std::array<std::uint8_t, 32> scene_sha256{};
  std::string command;                   // the command line that wrote it
  std::vector<RsRay> rays;
  bool has_hits = false;
  std::vector<RsHit> hits;               // with has_hits: t and tri as the trace reports them (u, v are 0)
};

// The file's bytes (the layout above).
std::string ray_file_bytes(const RayFile& f);
// Parses the bytes of `path` (named in messages). Throws Error, one line naming the file and the fix,
// for a bad magic, an unknown version or flag, a damaged header, a truncated file or one whose size
// does not match its ray count.
RayFile parse_ray_file(const std::string& bytes, const std::string& path);
// Reads and parses `path` (an unreadable file: Error naming it).
RayFile read_ray_file(const std::string& path);
// Writes `f` to `path` atomically (an existing file is replaced only once the new one is complete).
void write_ray_file(const std::string& path, const RayFile& f);

// 64 lowercase hex digits <-> the 32 raw bytes of a SHA-256 (Error for other text).
std::array<std::uint8_t, 32> sha256_bytes(const std::string& hex);
std::string sha256_hex(const std::array<std::uint8_t, 32>& bytes);

}  // namespace raysort
