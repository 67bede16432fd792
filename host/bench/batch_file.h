#pragma once
// A frame's batch to a ray file and a ray file to a batch (render/ray_file.h, docs/rays-format.md):
// `raysort rays --export` writes one, and `trace`, `run` and `encodebench --rays FILE` trace,
// encode and sort the batch it holds instead of generating one.
//
// Naming: a batch from a file is "file:<stem>" in every table, cell id and cell record (the file
// sibenik-bounce1.rays is batch file:sibenik-bounce1), as an encoder from a file is "file:<stem>";
// the name it was generated under ("bounce1") is in the file's header and in meta.json
// "ray_files" {"file:<stem>": {path, sha256, batch, rays, any_hit, scene_sha256, command}}, whose
// sha256 (of the whole file) makes a resume with a changed file refused.
//
// A batch from a file is the only batch of its frame: an encoder that learns from an earlier batch
// or a previous frame (bench/learned_inputs.h) has nothing to learn from, as on a frame's first batch.
#include <string>

#include "bvh/bvh.h"
#include "render/batches.h"
#include "render/ray_file.h"

namespace raysort {

// "file:<stem>" for the batch in `path`.
std::string ray_file_batch_name(const std::string& path);

// The file made from batch `rb` of scene `scene_sha256` (bench/scene_checksum.h), with its hits
// (t and triangle of the host reference, which every trace must match) when `with_hits`.
RayFile ray_file_of(const ReferencedBatch& rb, const std::string& scene_sha256, const std::string& command,
                    bool with_hits);

// Reads `path` and checks it belongs to `scene` (its SHA-256 against scene_sha256(scene, root)).
// Throws Error, one line naming the file and the fix, for a bad or damaged file (parse_ray_file)
// and for a batch exported from another scene.
RayFile read_ray_file_for_scene(const std::string& path, const std::string& scene, const std::string& scene_root);

// The batch of `f` (read from `path`) as the suite traces it: named ray_file_batch_name(path), an
// any-hit batch when the file says so, and its host reference hits traced here (fast variant, wide
// tree, as generate_batches' are). Pixel and sample are the ray's index and 0: a file does not say
// which pixel a ray came from.
ReferencedBatch batch_from_ray_file(const RayFile& f, const std::string& path, const Bvh& bvh);

// Rays of `f` whose (t, triangle) differ from `hits`: 0 when the file has no hits.
std::size_t ray_file_hit_differences(const RayFile& f, const std::vector<RsHit>& hits);

// FNV-1a 64 of (t, triangle) per ray, in ray order, as 16 hex digits: the hits hash `trace` prints
// and a batch's exported hits reproduce. On a little-endian host it is the hash of a ray file's
// hits section, byte for byte.
std::string hits_hash(const std::vector<RsHit>& hits);
// FNV-1a 64 of the rays as a ray file lays them out (origin, direction, tmin, tmax per ray): the
// hash of the file's rays section, which `raysort rays` prints for other readers to check.
std::string rays_hash(const std::vector<RsRay>& rays);

}  // namespace raysort
