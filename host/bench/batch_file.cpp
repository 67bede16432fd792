// Batches to and from ray files (see batch_file.h).
#include "bench/batch_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <filesystem>

#include "bench/scene_checksum.h"
#include "trace/tracer.h"
#include "util/error.h"
#include "util/fnv.h"

namespace raysort {

std::string ray_file_batch_name(const std::string& path) {
  return "file:" + std::filesystem::path(path).stem().string();
}

RayFile ray_file_of(const ReferencedBatch& rb, const std::string& scene_sha256, const std::string& command,
                    bool with_hits) {
  RayFile f;
  f.batch_name = rb.batch.name;
  f.any_hit = rb.batch.any_hit();
  f.scene_sha256 = sha256_bytes(scene_sha256);
  f.command = command;
  f.rays = rb.batch.rays;
  f.has_hits = with_hits;
  if (with_hits) f.hits = rb.reference_hits;
  return f;
}

RayFile read_ray_file_for_scene(const std::string& path, const std::string& scene, const std::string& scene_root) {
  RayFile f = read_ray_file(path);
  const std::string expected = scene_sha256(scene, scene_root);
  if (sha256_hex(f.scene_sha256) != expected)
    throw Error(fmt::format("ray file {} was exported from another scene (scene sha256 {}, {} has {}); give the scene "
                            "it was made from (its command: {}), or export the batch again with `raysort rays --scene {} "
                            "--export {}`",
                            path, sha256_hex(f.scene_sha256).substr(0, 12), scene, expected.substr(0, 12),
                            f.command.empty() ? "not recorded" : f.command, scene, path));
  return f;
}

ReferencedBatch batch_from_ray_file(const RayFile& f, const std::string& path, const Bvh& bvh) {
  ReferencedBatch rb;
  rb.batch.name = ray_file_batch_name(path);
  rb.batch.kind = f.any_hit ? BatchKind::Shadow : BatchKind::Bounce;
  rb.batch.rays = f.rays;
  rb.batch.pixel.resize(f.rays.size());
  for (std::size_t i = 0; i < f.rays.size(); ++i) rb.batch.pixel[i] = static_cast<std::uint32_t>(i);
  rb.batch.sample.assign(f.rays.size(), 0u);
  rb.reference_hits = trace_reference(bvh, rb.batch.rays, nullptr, f.any_hit);
  return rb;
}

std::size_t ray_file_hit_differences(const RayFile& f, const std::vector<RsHit>& hits) {
  if (!f.has_hits) return 0;
  std::size_t n = f.hits.size() != hits.size() ? std::max(f.hits.size(), hits.size()) : 0;
  for (std::size_t i = 0; i < std::min(f.hits.size(), hits.size()); ++i)
    n += std::bit_cast<std::uint32_t>(f.hits[i].t) != std::bit_cast<std::uint32_t>(hits[i].t) || f.hits[i].tri != hits[i].tri;
  return n;
}

std::string hits_hash(const std::vector<RsHit>& hits) {
  std::uint64_t h = kFnv1aOffsetBasis;
  for (const RsHit& x : hits) {
    h = fnv1a_bytes(&x.t, sizeof x.t, h);
    h = fnv1a_bytes(&x.tri, sizeof x.tri, h);
  }
  return fmt::format("{:016x}", h);
}

std::string rays_hash(const std::vector<RsRay>& rays) {
  std::uint64_t h = kFnv1aOffsetBasis;
  for (const RsRay& r : rays)
    for (float v : {r.o[0], r.o[1], r.o[2], r.d[0], r.d[1], r.d[2], r.tmin, r.tmax}) h = fnv1a_bytes(&v, sizeof v, h);
  return fmt::format("{:016x}", h);
}

}  // namespace raysort
