/* raysort — the permute kernel of the "permute" access mode (docs/measurement.md, "Access modes").
 *
 * After the sort, a cell can trace its rays in two ways. "gather" reads each ray through the
 * sorted order, ray[order[i]], in the trace kernel itself: no copy, but the loads of a warp (or of
 * a CPU thread's consecutive rays) land wherever the rays happened to be generated. "permute" first
 * moves the rays into trace order with this kernel, out[i] = rays[order[i]], and then traces `out`
 * with the identity order, so the trace reads its rays contiguously. The copy is timed as a stage
 * of its own and counted in the net speedup.
 *
 * One work-item per ray; a ray is 32 bytes (RsRay, shared.h), copied as two float4 so that a GPU
 * issues two 16-byte loads and stores per ray. The global size is padded to a multiple of the
 * local size (PoCL 3.1 has no non-uniform work-groups), so the kernel guards on count.
 */
#include "shared.h"

__kernel void permute_rays(__global const RsRay* rays, __global const uint* order, uint count, __global RsRay* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  __global const float4* src = (__global const float4*)(rays + order[i]);
  __global float4* dst = (__global float4*)(out + i);
  dst[0] = src[0];
  dst[1] = src[1];
}
