/* raysort — trace kernels: closest hit and any hit (shadow) for a batch of rays, in two variants
 * (docs/trace.md): fast (Möller–Trumbore, plain slab test) and robust (watertight triangle test of
 * Woop et al. 2013, conservative slab test of Ize 2013), one kernel per variant so that each
 * compiles with its variant as a constant.
 *
 * One ray per work-item; the ray is read through an index buffer, ray[order[i]] (the "gather"
 * access mode; the "permute" mode passes rays already moved into order, cl/permute.cl, and the
 * identity order), and its hit is written to hits[i] (trace order). The host scatters hits back
 * with the same order when it compares against NoSort.
 * The traversals themselves live in traverse_wide.h (rs_traverse_wide: the 4-wide BVH of
 * host/bvh/wide.cpp, the default), traverse_wide8.h (the 8-wide BVH of host/bvh/wide8.cpp),
 * traverse_packet.h, traverse_coherent.h, traverse_stream.h and traverse_binary.h, shared with the
 * host reference.
 * The global size is padded to a multiple of the local size (PoCL 3.1 has no non-uniform
 * work-groups), so every kernel guards on count.
 *
 * Gather on a CPU: a CPU runs a work-group's work-items one after another on one core, and a
 * sorted order sends each work-item's ray load to a random place in a batch of tens of MB: a cache
 * and TLB miss that nothing else hides, since the traversal before it is one long dependent chain
 * (on sibenik's bounce1 batch, 13 % of the kernel's samples sat on that one load). A GPU hides it
 * behind other warps. So on a CPU device the host defines RS_PREFETCH_AHEAD (runtime.cpp) and
 * each work-item prefetches the ray of the work-item that many places ahead, which runs a few
 * microseconds later (docs/trace.md, "Gather on a CPU"). A prefetch changes no result.
 */
#include "traverse_binary.h"
#include "traverse_wide.h"
#ifdef RS_TRACE_BINARY_WW
#include "traverse_binary_ww.h"
#endif
/* The kernel loader inlines a guarded header at its first #include (host/runtime/runtime.cpp), so
 * the 8-wide traversal comes first under either class that needs it. */
#if defined(RS_TRACE_WIDE8) || defined(RS_TRACE_STREAM) || defined(RS_TRACE_COHERENT)
#include "traverse_wide8.h"
#endif
#ifdef RS_TRACE_STREAM
#include "traverse_stream.h"
#endif
#ifdef RS_TRACE_CWBVH
#include "traverse_cwbvh.h"
#endif
#ifdef RS_TRACE_PACKET
#define RS_PACKET_W RS_TRACE_PACKET
#include "traverse_packet.h"
#ifdef RS_TRACE_COHERENT
#include "traverse_coherent.h"
#endif
/* The hybrid classes hand a subtree to lone rays when at most this many lanes reach it (0: never). */
#ifndef RS_PACKET_SINGLE_AT
#define RS_PACKET_SINGLE_AT 0
#endif
#endif

/* Prefetches the rays at order positions [from, from + n) that exist (see the top: CPU devices).
 * Oclgrind gets RS_PREFETCH_AHEAD too, without the x86 or Arm builtin (RS_PREFETCH, shared.h): its
 * unoptimised build still reads order[pf], so its bounds check covers the loop's guard. */
#ifdef RS_PREFETCH_AHEAD
#define RS_PREFETCH_RAYS(rays, order, from, n, count) \
  for (uint pf = (from); pf < (from) + (n) && pf < (count); ++pf) RS_PREFETCH(&(rays)[(order)[pf]])
#else
#define RS_PREFETCH_RAYS(rays, order, from, n, count)
#endif

/* Each variant gets the same three kernels: closest hit, any hit (shadow rays), and an
 * instrumented closest hit that also writes the number of BVH nodes each ray fetched.
 * ROBUST is 0 (fast) or 1 (watertight): a constant, so each kernel compiles one variant. */
#define RS_TRACE_KERNELS(SUFFIX, TRAVERSE)                                                                    \
  __kernel void trace_closest##SUFFIX(__global const NODE* nodes, __global const LEAF* tris,                    \
                                      __global const RsRay* rays, __global const uint* order, uint count,     \
                                      __global RsHit* hits) {                                                 \
    uint i = get_global_id(0);                                                                                \
    if (i >= count) return;                                                                                   \
    RS_PREFETCH_RAYS(rays, order, i + RS_PREFETCH_AHEAD, 1, count);                                           \
    hits[i] = TRAVERSE(nodes, tris, rays[order[i]], 0, 0);                                                    \
  }                                                                                                           \
  __kernel void trace_any##SUFFIX(__global const NODE* nodes, __global const LEAF* tris,                        \
                                  __global const RsRay* rays, __global const uint* order, uint count,         \
                                  __global RsHit* hits) {                                                     \
    uint i = get_global_id(0);                                                                                \
    if (i >= count) return;                                                                                   \
    RS_PREFETCH_RAYS(rays, order, i + RS_PREFETCH_AHEAD, 1, count);                                           \
    hits[i] = TRAVERSE(nodes, tris, rays[order[i]], 1, 0);                                                    \
  }                                                                                                           \
  __kernel void trace_closest_counted##SUFFIX(__global const NODE* nodes, __global const LEAF* tris,            \
                                              __global const RsRay* rays, __global const uint* order,         \
                                              uint count, __global RsHit* hits, __global uint* visits) {      \
    uint i = get_global_id(0);                                                                                \
    if (i >= count) return;                                                                                   \
    uint v = 0;                                                                                               \
    RS_PREFETCH_RAYS(rays, order, i + RS_PREFETCH_AHEAD, 1, count);                                           \
    hits[i] = TRAVERSE(nodes, tris, rays[order[i]], 0, &v);                                                   \
    visits[i] = v;                                                                                            \
  }

/* The same three kernels for the classes whose work-item traces RAYS consecutive rays of the order
 * at once (packets, streams), positions [first, first + RAYS): TRAVERSE(nodes, tris, rays, order,
 * first, count, robust, any_hit, hits, visits) writes their hits (and steps). */
#define RS_GROUP_KERNELS(NAME, NODE_T, LEAF_T, RAYS, TRAVERSE, ROBUST)                                         \
  __kernel void trace_closest##NAME(__global const NODE_T* nodes, __global const LEAF_T* tris,                 \
                                    __global const RsRay* rays, __global const uint* order, uint count,        \
                                    __global RsHit* hits) {                                                    \
    const uint first = get_global_id(0) * RAYS;                                                               \
    if (first >= count) return;                                                                                \
    RS_PREFETCH_RAYS(rays, order, first + RAYS, RAYS, count);                                                \
    TRAVERSE(nodes, tris, rays, order, first, count, ROBUST, 0, hits, 0);                                      \
  }                                                                                                            \
  __kernel void trace_any##NAME(__global const NODE_T* nodes, __global const LEAF_T* tris,                     \
                                __global const RsRay* rays, __global const uint* order, uint count,            \
                                __global RsHit* hits) {                                                        \
    const uint first = get_global_id(0) * RAYS;                                                               \
    if (first >= count) return;                                                                                \
    RS_PREFETCH_RAYS(rays, order, first + RAYS, RAYS, count);                                                \
    TRAVERSE(nodes, tris, rays, order, first, count, ROBUST, 1, hits, 0);                                      \
  }                                                                                                            \
  __kernel void trace_closest_counted##NAME(__global const NODE_T* nodes, __global const LEAF_T* tris,         \
                                            __global const RsRay* rays, __global const uint* order, uint count, \
                                            __global RsHit* hits, __global uint* visits) {                     \
    const uint first = get_global_id(0) * RAYS;                                                               \
    if (first >= count) return;                                                                                \
    RS_PREFETCH_RAYS(rays, order, first + RAYS, RAYS, count);                                                \
    TRAVERSE(nodes, tris, rays, order, first, count, ROBUST, 0, hits, visits);                                 \
  }

/* One trace class per build (host/trace/tracer.cpp passes -DRS_TRACE_BINARY for the binary BVH,
 * -DRS_TRACE_WIDE8 for the 8-wide one, -DRS_TRACE_PACKET=W for packets of W rays (with -DRS_TRACE_COHERENT
 * the coherent packets over the 8-wide BVH), -DRS_TRACE_STREAM
 * for streams, -DRS_TRACE_CWBVH for the compressed 8-wide BVH, -DRS_TRACE_BINARY_WW for the binary BVH in
 * the while-while loop form; the define of
 * each class is its row of host/trace/trace_class.cpp), so a run compiles only the kernels it
 * launches. */
#if !defined(RS_TRACE_BINARY) && !defined(RS_TRACE_PACKET) && !defined(RS_TRACE_WIDE8) && !defined(RS_TRACE_STREAM) && \
    !defined(RS_TRACE_CWBVH) && !defined(RS_TRACE_BINARY_WW)
/* The 4-wide BVH (the default layout). */
#define NODE RsWideNode
#define LEAF RsTriPacket
#define RS_WIDE_FAST(n, t, r, any, v) rs_traverse_wide(n, t, r, 0, any, v)
#define RS_WIDE_ROBUST(n, t, r, any, v) rs_traverse_wide(n, t, r, 1, any, v)
RS_TRACE_KERNELS(, RS_WIDE_FAST)
RS_TRACE_KERNELS(_robust, RS_WIDE_ROBUST)
#undef NODE
#undef LEAF

#elif defined(RS_TRACE_WIDE8)
/* The 8-wide BVH (the wide8 class): eight child boxes per float8 test, leaves of eight triangles. */
#define NODE RsWide8Node
#define LEAF RsTriPacket8
#define RS_WIDE8_FAST(n, t, r, any, v) rs_traverse_wide8(n, t, r, 0, any, v)
#define RS_WIDE8_ROBUST(n, t, r, any, v) rs_traverse_wide8(n, t, r, 1, any, v)
RS_TRACE_KERNELS(_wide8, RS_WIDE8_FAST)
RS_TRACE_KERNELS(_wide8_robust, RS_WIDE8_ROBUST)
#undef NODE
#undef LEAF

#elif defined(RS_TRACE_CWBVH)
/* The compressed 8-wide BVH (the cwbvh class, traverse_cwbvh.h): 80-byte nodes of 8-bit boxes. */
#define NODE RsCwbvhNode
#define LEAF RsTriangle
#define RS_CWBVH_FAST(n, t, r, any, v) rs_traverse_cwbvh(n, t, r, 0, any, v)
#define RS_CWBVH_ROBUST(n, t, r, any, v) rs_traverse_cwbvh(n, t, r, 1, any, v)
RS_TRACE_KERNELS(_cwbvh, RS_CWBVH_FAST)
RS_TRACE_KERNELS(_cwbvh_robust, RS_CWBVH_ROBUST)
#undef NODE
#undef LEAF

#elif defined(RS_TRACE_BINARY_WW)
/* The binary BVH in the while-while loop form (the binary-ww class, traverse_binary_ww.h). */
#define NODE RsBvhNode
#define LEAF RsTriangle
#define RS_WW_FAST(n, t, r, any, v) rs_traverse_binary_ww(n, t, r, 0, any, v)
#define RS_WW_ROBUST(n, t, r, any, v) rs_traverse_binary_ww(n, t, r, 1, any, v)
RS_TRACE_KERNELS(_binary_ww, RS_WW_FAST)
RS_TRACE_KERNELS(_binary_ww_robust, RS_WW_ROBUST)
#undef NODE
#undef LEAF

#elif defined(RS_TRACE_STREAM)
/* Ray streams over the 8-wide BVH (traverse_stream.h): work-item s deals rays
 * [s * RS_STREAM_CHUNK, (s + 1) * RS_STREAM_CHUNK) of the order into streams of one direction octant,
 * each traced node by node, each ray alone against a node's eight boxes (the stream class). */
RS_GROUP_KERNELS(_stream, RsWide8Node, RsTriPacket8, RS_STREAM_CHUNK, rs_traverse_stream, 0)
RS_GROUP_KERNELS(_stream_robust, RsWide8Node, RsTriPacket8, RS_STREAM_CHUNK, rs_traverse_stream, 1)

#elif defined(RS_TRACE_PACKET) && defined(RS_TRACE_COHERENT)
/* Coherent ray packets over the 8-wide BVH (traverse_coherent.h): work-item p traces rays
 * [p * RS_PACKET_W, (p + 1) * RS_PACKET_W) of the order as one packet, a node's children tested
 * against the packet's frustum before its lanes. */
RS_GROUP_KERNELS(_coherent, RsWide8Node, RsTriPacket8, RS_PACKET_W, rs_traverse_coherent, 0)
RS_GROUP_KERNELS(_coherent_robust, RsWide8Node, RsTriPacket8, RS_PACKET_W, rs_traverse_coherent, 1)

#elif defined(RS_TRACE_PACKET)
/* Ray packets over the 4-wide BVH (traverse_packet.h): work-item p traces rays
 * [p * RS_PACKET_W, (p + 1) * RS_PACKET_W) of the order as one packet, one ray per vector lane
 * (the hybrid classes: down to RS_PACKET_SINGLE_AT lanes, then each alone). */
#define RS_PACKET_TRAVERSE(n, t, r, o, first, count, robust, any, hits, visits) \
  rs_traverse_packet(n, t, r, o, first, count, robust, any, RS_PACKET_SINGLE_AT, hits, visits)
RS_GROUP_KERNELS(_packet, RsWideNode, RsTriPacket, RS_PACKET_W, RS_PACKET_TRAVERSE, 0)
RS_GROUP_KERNELS(_packet_robust, RsWideNode, RsTriPacket, RS_PACKET_W, RS_PACKET_TRAVERSE, 1)

#else
/* The binary BVH, kept to measure what the wide layout gains (raysort trace --layout binary). */
#define NODE RsBvhNode
#define LEAF RsTriangle
RS_TRACE_KERNELS(_binary, rs_traverse)
RS_TRACE_KERNELS(_binary_robust, rs_traverse_robust)
#undef NODE
#undef LEAF
#endif
