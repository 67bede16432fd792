/* raysort — the BVH as the kernels read it: the binary tree (RsBvhNode, RsTriangle: the reference
 * structure, which HCC cuts, PPC and the SIMT model work on), its 4-wide collapse (RsWideNode,
 * RsTriPacket: what the trace kernels walk by default) and its 8-wide collapse (RsWide8Node,
 * RsTriPacket8: the wide8 trace class), with the stack bounds that tree depth guarantees.
 * host/bvh/ builds them (build_sah.cpp, wide.cpp, wide8.cpp).
 */
#ifndef RAYSORT_BVH_LAYOUT_H
#define RAYSORT_BVH_LAYOUT_H

#include "lanes.h"
#include "shared.h"

/* Traversal stack entries per work-item (private memory). The BVH builder guarantees that the
 * tree depth stays below this bound (host/bvh/build_sah.cpp, kMaxDepth); nearest-child-first
 * traversal pushes at most one node per level, so the stack cannot overflow. */
#define RS_STACK_SIZE 64

/* A node of the flat binary BVH, 32 bytes: [bmin.x bmin.y bmin.z first | bmax.x bmax.y bmax.z count].
 * count == 0: inner node; its children are nodes[first] (left) and nodes[first + 1] (right).
 * count  > 0: leaf holding triangles [first, first + count) of the leaf-ordered triangle array.
 * Node 0 is the root. Children are stored next to each other so one index names both. */
typedef struct {
  float bmin[3];
  rs_u32 first;
  float bmax[3];
  rs_u32 count;
} RsBvhNode;

/* A triangle in leaf order, 48 bytes: [v0 id | v1 pad | v2 pad], id = the triangle's index in the
 * scene's flattened triangle list (what hits report). */
typedef struct {
  float v0[3];
  rs_u32 id;
  float v1[3];
  rs_u32 pad0;
  float v2[3];
  rs_u32 pad1;
} RsTriangle;

/* A node of the 4-wide BVH the trace kernels traverse, 128 bytes (two cache lines): the boxes of
 * up to four children, one axis bound per vector ("SoA", so one vector operation tests four
 * boxes), then per child: valid (-1 / 0) and a reference:
 *   RS_WIDE_LEAF clear: index of an inner node;
 *   RS_WIDE_LEAF set:   a leaf, packets [first, first + count) with first = (ref & ~RS_WIDE_LEAF) >> 2
 *                       and count = (ref & 3) + 1.
 * Node 0 is the root. host/bvh/wide.cpp collapses the binary BVH into this layout. */
#define RS_WIDE_LEAF 0x80000000u
/* A leaf reference's packets (RS_WIDE_LEAF set): the first, how many (1 to 4), and one past the last.
 * Macros, not functions: as functions PoCL compiled the kernels' leaf loops differently. */
#define RS_WIDE_LEAF_FIRST(ref) (((ref) & ~RS_WIDE_LEAF) >> 2)
#define RS_WIDE_LEAF_COUNT(ref) (((ref) & 3u) + 1u)
#define RS_WIDE_LEAF_END(ref) (RS_WIDE_LEAF_FIRST(ref) + ((ref) & 3u) + 1u)
/* The leaf's lanes of each packet, a bit per lane: all four (a 4-wide leaf has its packets to itself;
 * an 8-wide one may not: RS_WIDE8_LEAF_LANES). */
#define RS_WIDE_LEAF_LANES(ref) ((void)(ref), 0xf)
typedef struct {
  rs_f4 lo_x, hi_x, lo_y, hi_y, lo_z, hi_z;
  rs_i4 valid;
  rs_u32 child[4];
} RsWideNode;

/* Four triangles of a leaf, 192 bytes, one vertex coordinate per vector so one pass of the
 * intersection test serves four triangles. id[i] = the triangle's index in the scene's flat list
 * (RS_NO_HIT in an empty lane); valid = -1 for a real triangle; nondegenerate = -1 unless the
 * triangle has exactly zero area (its cross product is 0 in exact arithmetic), which the robust
 * test must reject and which is cheaper to decide once on the host. */
typedef struct {
  rs_f4 v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z;
  rs_i4 valid;
  rs_i4 nondegenerate;
  rs_u32 id[4];
} RsTriPacket;

/* Traversal stack entries for the 4-wide BVH. Every wide node spans two levels of the binary
 * tree (host/bvh/wide.cpp), so its depth is at most ceil(RS_STACK_SIZE / 2) = 32, and a node
 * pushes at most three children: 3 * 32 = 96 entries suffice. */
#define RS_WIDE_STACK_SIZE 96

/* A node of the 8-wide BVH (the wide8, stream and coherent trace classes: traverse_wide8.h,
 * traverse_stream.h, traverse_coherent.h), 256 bytes (four cache lines): RsWideNode with eight lanes,
 * so one float8 operation tests eight boxes (one ymm register on an AVX CPU). child[i] as in
 * RsWideNode, but a leaf reference names lanes as well as packets (RS_WIDE8_LEAF_*, below): the small
 * leaves of a node share packets. Node 0 is the root. host/bvh/wide8.cpp collapses the binary BVH into
 * this layout. */
typedef struct {
  rs_f8 lo_x, hi_x, lo_y, hi_y, lo_z, hi_z;
  rs_i8 valid;
  rs_u32 child[8];
} RsWide8Node;

/* Eight triangles of a leaf, 384 bytes: RsTriPacket with eight lanes (one vertex coordinate per
 * float8), so a leaf of up to eight triangles (the SAH builder's max_leaf_size) is one pass of
 * the intersection test. Same fields and meanings as RsTriPacket. */
typedef struct {
  rs_f8 v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z;
  rs_i8 valid;
  rs_i8 nondegenerate;
  rs_u32 id[8];
} RsTriPacket8;

/* An 8-wide leaf reference (RS_WIDE_LEAF set):
 *   RS_WIDE_LEAF | first << 8 | (lanes - 1) << 5 | lane << 2 | (packets - 1)
 * The leaf is lanes [lane, lane + lanes) of packets [first, first + packets): a leaf of up to eight
 * triangles lies in one packet, beside the node's other small leaves (host/bvh/wide_tree.h,
 * plan_leaves), and a larger one (max_leaf_size above 8) fills its own packets from lane 0 (lanes 8;
 * the last packet's valid lanes end it). Half the 8-wide leaves hold one or two triangles: one leaf to
 * a packet left 3.97 of its 8 lanes filled on sibenik, and the leaf packets were 84 % of the tree's
 * bytes; sharing them takes a third fewer packets (results/history/trace-kernels.md, "Leaves that
 * share a packet"). A triangle is tested in its lane with the arithmetic of every other lane, so a ray
 * hits what it hit with a packet of its own; RS_WIDE8_LEAF_LANES masks the lanes of the other leaves.
 * RS_WIDE8_LEAF_SLOT numbers a leaf by its first lane (8 * first + lane: no two leaves share it). */
#define RS_WIDE8_LEAF_REF(first, lane, lanes, packets) \
  (RS_WIDE_LEAF | (first) << 8 | ((lanes) - 1u) << 5 | (lane) << 2 | ((packets) - 1u))
#define RS_WIDE8_LEAF_FIRST(ref) (((ref) & ~RS_WIDE_LEAF) >> 8)
#define RS_WIDE8_LEAF_COUNT(ref) (((ref) & 3u) + 1u)
#define RS_WIDE8_LEAF_END(ref) (RS_WIDE8_LEAF_FIRST(ref) + RS_WIDE8_LEAF_COUNT(ref))
#define RS_WIDE8_LEAF_LANE(ref) (((ref) >> 2) & 7u)
#define RS_WIDE8_LEAF_LANE_COUNT(ref) ((((ref) >> 5) & 7u) + 1u)
#define RS_WIDE8_LEAF_LANES(ref) ((int)((0xffu >> (8u - RS_WIDE8_LEAF_LANE_COUNT(ref))) << RS_WIDE8_LEAF_LANE(ref)))
#define RS_WIDE8_LEAF_SLOT(ref) (8u * RS_WIDE8_LEAF_FIRST(ref) + RS_WIDE8_LEAF_LANE(ref))
/* The packets an 8-wide leaf reference can name (23 bits of first). */
#define RS_WIDE8_MAX_PACKETS (1u << 23)

/* Traversal stack entries for the 8-wide BVH. Every inner child of an 8-wide node lies at least
 * three binary levels below the node's binary node (host/bvh/wide8.cpp: the collapse opens every
 * inner slot to three levels, 2^3 = 8 lanes, before it opens any further), so an inner wide node
 * at depth d (root 1) stands for a binary inner node at depth >= 3 (d - 1); binary inner nodes lie
 * above depth RS_STACK_SIZE - 1, so d <= 22. A node pushes at most seven children: 7 * 22 = 154
 * entries suffice. */
#define RS_WIDE8_MAX_DEPTH 22
#define RS_WIDE8_STACK_SIZE (7 * RS_WIDE8_MAX_DEPTH)

/* A node of the compressed 8-wide BVH (the cwbvh trace class, traverse_cwbvh.h), 80 bytes: the
 * node of Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on GPUs Through Compressed
 * Wide BVHs" (HPG 2017), section 3.1. The eight child boxes are 8-bit offsets on a grid of the
 * node's own: child box = p + q * 2^(e - 127) per axis, q_lo rounded down and q_hi up so the box
 * always contains the child's exact box (host/bvh/cwbvh.cpp checks it in the kernels' float
 * arithmetic), which keeps the robust variant watertight.
 *   imask bit s: slot s holds an inner node, nodes[child_base + (inner slots below s)];
 *   meta[s] (not inner): 0 empty, else a leaf of (meta >> 5) triangles (1 to 3) at
 *                        triangles[triangle_base + (meta & 31)].
 * A node's inner children are contiguous, and so are its leaves' triangles (at most 8 x 3 = 24).
 * Children sit in slots by ray octant (the paper's assignment): a ray of octant o (bit a set when
 * d[a] < 0) visits the slots it enters in the order of s ^ o, which is near to far for most rays
 * without a sort. Node 0 is the root; RsTriangle is the binary tree's triangle. */
typedef struct {
  float p[3];
  rs_u8 e[3];
  rs_u8 imask;
  rs_u32 child_base;
  rs_u32 triangle_base;
  rs_u8 meta[8];
  rs_u8 q_lo_x[8], q_lo_y[8], q_lo_z[8];
  rs_u8 q_hi_x[8], q_hi_y[8], q_hi_z[8];
} RsCwbvhNode;

/* The cwbvh traversal's stack holds node groups only (a node's inner children not visited yet),
 * at most one per level; an inner child lies at least one binary level below its node, and a leaf
 * of more than three triangles adds one node of its own, so RS_STACK_SIZE + 1 levels suffice. */
#define RS_CWBVH_STACK_SIZE (RS_STACK_SIZE + 1)

#endif /* RAYSORT_BVH_LAYOUT_H */
