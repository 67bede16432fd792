/* raysort — traversal of the 8-wide BVH (bvh_layout.h, RsWide8Node / RsTriPacket8): the wide8
 * trace class (docs/trace.md, "Trace classes"), in the kernels (cl/trace.cl, -DRS_TRACE_WIDE8) and
 * the host twin (host/trace/tracer.cpp).
 */
#ifndef RAYSORT_TRAVERSE_WIDE8_H
#define RAYSORT_TRAVERSE_WIDE8_H

#include "intersect.h"
#include "lanes.h"

/* ---------------------------------------------------------------------------------------------
 * 8-wide BVH traversal: one ray per work-item, eight child boxes per float8 slab test and leaves of
 * up to eight triangles tested as one float8 packet — the single-ray BVH8 scheme of Embree (Wald et
 * al. 2014, Embree's AVX kernels), for rays too incoherent for ray packets. On an AVX CPU (PoCL's
 * native float width 8) each box or triangle step is one ymm operation where the 4-wide tree needs
 * one xmm operation per four children; the tree is about half as deep (host/bvh/wide8.cpp), so a
 * ray visits fewer nodes, each costing about as many instructions.
 *
 * The source is the 4-wide traversal's (traverse_wide_w.h) at eight lanes: the same fast and
 * robust box and triangle arithmetic per lane, the same nearest-first order (hit children sorted
 * by entry distance, ties by lane; any-hit rays in lane order), the same counted visits and
 * trails. So a triangle is hit or missed exactly as by the 4-wide and binary traversals; only
 * which of two equally near triangles wins may differ, because the visiting order differs.
 * Stack: RS_WIDE8_STACK_SIZE entries (bvh_layout.h: seven pushes per level, 22 levels).
 * ------------------------------------------------------------------------------------------- */

/* rs_wide8_boxes[_robust], rs_packet8_intersect[_robust], rs_traverse_wide8[_recorded|_subtree]. */
#define RS_WIDE_W 8
#include "traverse_wide_w.h"
#undef RS_WIDE_W

#endif /* RAYSORT_TRAVERSE_WIDE8_H */
