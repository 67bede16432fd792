/* raysort — trace kernels: closest hit and any hit (shadow) for a batch of rays, in two variants
 * (docs/trace.md): fast (Möller–Trumbore, plain slab test) and robust (watertight triangle test of
 * Woop et al. 2013, conservative slab test of Ize 2013), one kernel per variant so that each
 * compiles with its variant as a constant.
 *
 * One ray per work-item; the ray is read through an index buffer, ray[order[i]], so a sorted
 * order needs no copy of the rays, and its hit is written to hits[i] (trace order). The host
 * scatters hits back with the same order when it compares against NoSort.
 * The traversal itself lives in traverse.h, shared with the host reference.
 * The global size is padded to a multiple of the local size (PoCL 3.1 has no non-uniform
 * work-groups), so every kernel guards on count.
 */
#include "traverse.h"

__kernel void trace_closest(__global const RsBvhNode* nodes, __global const RsTriangle* tris,
                            __global const RsRay* rays, __global const uint* order, uint count,
                            __global RsHit* hits) {
  uint i = get_global_id(0);
  if (i >= count) return;
  uint ray_index = order[i];
  hits[i] = rs_traverse(nodes, tris, rays[ray_index], 0, 0);
}

__kernel void trace_any(__global const RsBvhNode* nodes, __global const RsTriangle* tris,
                        __global const RsRay* rays, __global const uint* order, uint count,
                        __global RsHit* hits) {
  uint i = get_global_id(0);
  if (i >= count) return;
  uint ray_index = order[i];
  hits[i] = rs_traverse(nodes, tris, rays[ray_index], 1, 0);
}

/* Instrumented closest hit: also writes the number of BVH nodes each ray fetched. */
__kernel void trace_closest_counted(__global const RsBvhNode* nodes, __global const RsTriangle* tris,
                                    __global const RsRay* rays, __global const uint* order, uint count,
                                    __global RsHit* hits, __global uint* visits) {
  uint i = get_global_id(0);
  if (i >= count) return;
  uint ray_index = order[i];
  uint v = 0;
  hits[i] = rs_traverse(nodes, tris, rays[ray_index], 0, &v);
  visits[i] = v;
}


__kernel void trace_closest_robust(__global const RsBvhNode* nodes, __global const RsTriangle* tris,
                                   __global const RsRay* rays, __global const uint* order, uint count,
                                   __global RsHit* hits) {
  uint i = get_global_id(0);
  if (i >= count) return;
  uint ray_index = order[i];
  hits[i] = rs_traverse_robust(nodes, tris, rays[ray_index], 0, 0);
}

__kernel void trace_any_robust(__global const RsBvhNode* nodes, __global const RsTriangle* tris,
                               __global const RsRay* rays, __global const uint* order, uint count,
                               __global RsHit* hits) {
  uint i = get_global_id(0);
  if (i >= count) return;
  uint ray_index = order[i];
  hits[i] = rs_traverse_robust(nodes, tris, rays[ray_index], 1, 0);
}

__kernel void trace_closest_counted_robust(__global const RsBvhNode* nodes, __global const RsTriangle* tris,
                                           __global const RsRay* rays, __global const uint* order, uint count,
                                           __global RsHit* hits, __global uint* visits) {
  uint i = get_global_id(0);
  if (i >= count) return;
  uint ray_index = order[i];
  uint v = 0;
  hits[i] = rs_traverse_robust(nodes, tris, rays[ray_index], 0, &v);
  visits[i] = v;
}
