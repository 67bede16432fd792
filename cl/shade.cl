/* raysort — the wavefront path tracer's kernels, one per stage (Laine et al. 2013, "Megakernels
 * Considered Harmful"; the seed paper's pipeline, Xiang et al. section 6.1): generate, shade,
 * accumulate, and the stream compaction that removes terminated paths between batches. Tracing is
 * cl/trace.cl's (host/trace/tracer.h). The arithmetic lives in shade.h, shared with the host twin
 * (host/render/pathtrace.cpp), so both produce the same rays and radiance bit for bit.
 *
 * Compaction is deterministic and stable (the order of valid slots is kept): count valid slots per
 * block of RS_COMPACT_BLOCK, scan the block counts in one work-item, then give each valid slot its
 * destination by walking each block in order. No atomics, no barriers (PoCL 3.1, docs/design.md, "Device facts").
 * Every kernel guards on its count: global sizes are padded to the local size.
 */
#include "shade.h"

#define RS_COMPACT_BLOCK 256u

__kernel void generate_primary(RsCamera cam, __global const RsShadeParams* params, uint count,
                               __global RsRay* rays, __global RsPathState* states) {
  uint i = get_global_id(0);
  if (i >= count) return;
  RsShadeParams p = params[0];
  rays[i] = rs_primary_ray(cam, p, i);
  RsPathState s;
  s.weight[0] = 1.0f;
  s.weight[1] = 1.0f;
  s.weight[2] = 1.0f;
  s.path = i;
  states[i] = s;
}

__kernel void shade(__global const RsShadeTriangle* tris, __global const RsMaterial* materials,
                    __global const RsSphereLight* lights, __global const RsShadeParams* params, uint bounce, uint count,
                    __global const RsRay* rays, __global const RsPathState* states, __global const RsHit* hits,
                    __global float* radiance, __global RsRay* shadow_rays, __global RsPathState* shadow_states,
                    __global uint* shadow_valid, __global RsRay* bounce_rays, __global RsPathState* bounce_states,
                    __global uint* bounce_valid) {
  uint i = get_global_id(0);
  if (i >= count) return;
  rs_shade(tris, materials, lights, params[0], bounce, i, rays[i], states[i], hits[i], radiance, shadow_rays,
           shadow_states, shadow_valid, bounce_rays, bounce_states, bounce_valid);
}

__kernel void accumulate_shadow(__global const RsShadeParams* params, uint count, __global const RsPathState* states,
                                __global const uint* shadow_valid, __global const uint* shadow_dest,
                                __global const RsPathState* shadow_states, __global const RsHit* shadow_hits,
                                __global float* radiance) {
  uint i = get_global_id(0);
  if (i >= count) return;
  rs_accumulate_shadow(params[0], i, states[i].path, shadow_valid, shadow_dest, shadow_states, shadow_hits, radiance);
}

/* Per-path BVH node visits of a closest-hit batch, for the traversal-cost heatmap. */
__kernel void accumulate_visits(uint count, __global const RsPathState* states, __global const uint* visits,
                                __global uint* path_visits) {
  uint i = get_global_id(0);
  if (i >= count) return;
  path_visits[states[i].path] += visits[i];
}

/* Compaction 1/3: valid slots per block. */
__kernel void compact_count(__global const uint* valid, uint n, __global uint* block_counts, uint blocks) {
  uint b = get_global_id(0);
  if (b >= blocks) return;
  uint end = min(n, (b + 1u) * RS_COMPACT_BLOCK), c = 0;
  for (uint s = b * RS_COMPACT_BLOCK; s < end; ++s) c += valid[s] != 0u;
  block_counts[b] = c;
}

/* Compaction 2/3: exclusive scan of the block counts; total[0] = the number of valid slots. */
__kernel void compact_scan(__global uint* block_counts, uint blocks, __global uint* total) {
  if (get_global_id(0) != 0) return;
  uint sum = 0;
  for (uint b = 0; b < blocks; ++b) {
    uint c = block_counts[b];
    block_counts[b] = sum;
    sum += c;
  }
  total[0] = sum;
}

/* Compaction 3/3: dest[slot] = the slot's index among the valid ones, then the copy. */
__kernel void compact_dest(__global const uint* valid, uint n, __global const uint* block_offsets, uint blocks,
                           __global uint* dest) {
  uint b = get_global_id(0);
  if (b >= blocks) return;
  uint end = min(n, (b + 1u) * RS_COMPACT_BLOCK), o = block_offsets[b];
  for (uint s = b * RS_COMPACT_BLOCK; s < end; ++s)
    if (valid[s]) dest[s] = o++;
}

__kernel void compact_copy(__global const uint* valid, __global const uint* dest, uint n, __global const RsRay* rays,
                           __global const RsPathState* states, __global RsRay* out_rays,
                           __global RsPathState* out_states) {
  uint s = get_global_id(0);
  if (s >= n || !valid[s]) return;
  out_rays[dest[s]] = rays[s];
  out_states[dest[s]] = states[s];
}
