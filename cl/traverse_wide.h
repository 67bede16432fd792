/* raysort — traversal of the 4-wide BVH (bvh_layout.h, RsWideNode / RsTriPacket): what the trace
 * kernels (cl/trace.cl) and the host reference (host/trace/tracer.cpp) run by default.
 */
#ifndef RAYSORT_TRAVERSE_WIDE_H
#define RAYSORT_TRAVERSE_WIDE_H

#include "intersect.h"
#include "lanes.h"

/* ---------------------------------------------------------------------------------------------
 * 4-wide BVH traversal: what the trace kernels run (docs/trace.md, "Trace kernel").
 *
 * The binary BVH above stays the reference structure (HCC cuts, the SIMT model's trail); for
 * speed the kernels walk the same tree collapsed to four children per node (host/bvh/wide.cpp),
 * testing the four child boxes, and four triangles of a leaf, with one vector operation each —
 * the single-ray wide-BVH scheme of Embree (Wald et al. 2014) written with OpenCL vector types,
 * which PoCL maps to SSE/AVX and GPUs to plain scalar code. Per lane the arithmetic is that of
 * the binary traversal's tests (Möller–Trumbore / Woop et al. and the slab tests above), so a
 * triangle is hit or missed exactly as there; only which of two equally near triangles wins may
 * differ, because the visiting order differs.
 * ------------------------------------------------------------------------------------------- */

/* rs_wide_boxes[_robust], rs_packet_intersect[_robust] and rs_traverse_wide[_recorded|_subtree]:
 * the width-generic source (traverse_wide_w.h) at four lanes. */
#define RS_WIDE_W 4
#include "traverse_wide_w.h"
#undef RS_WIDE_W

#endif /* RAYSORT_TRAVERSE_WIDE_H */
