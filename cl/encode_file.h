/* raysort — the program around an encoder from a file (raysort run / encodebench --encoders
 * file:PATH; docs/encoders.md, "An encoder from a file"). The host builds it at run time from this
 * header (its includes inlined), then `#line 1 "PATH"` and the user's file, so the compiler reports
 * the user's errors at the file's own lines. The file defines one function:
 *
 *   rs_u64 rs_file_code(const RsEncodeFrame* frame, RsRay ray, uint bits, const RsFileScene* scene)
 *
 * and returns the ray's 64-bit code, most significant bit first; the key of `bits` bits is the
 * code's top bits (rs_key_from_code), as for every encoder of the list. It may call everything the
 * built-in keys are made of (keys.h: rs_quantize_point, rs_morton3, rs_unit_direction, ...;
 * keys_spatial.h: rs_origin_code, ...; keys_cut.h: rs_box_set_code, ...; keys_ppc.h:
 * rs_prefix_path_code) and read the scene inputs below. It has no host twin: the suite checks its
 * keys against themselves (the same keys on a second launch), not against a host copy.
 */
#ifndef RAYSORT_ENCODE_FILE_H
#define RAYSORT_ENCODE_FILE_H

#include "keys_cut.h"
#include "keys_ppc.h"
#include "keys_spatial.h"

/* What the suite uploads for every encoder from a file, whether the file reads it or not (an
 * argument the function ignores costs nothing per ray):
 *   cut, cut_boxes      HCC's cut of `bits` nodes (by descending HAD; fewer when the BVH has fewer
 *                       leaves), as sixteen-box groups in __constant memory: rs_box_set_code(ray,
 *                       scene->cut, scene->cut_boxes, bits, 0) is HCC's code
 *   nodes, node_count   the binary BVH (bvh_layout.h; node 0 is the root)
 *   triangles           its triangles in leaf order: rs_prefix_path_code(scene->nodes,
 *                       scene->triangles, ray, bits) is PPC's code */
typedef struct {
  __constant const RsCutGroup* cut;
  uint cut_boxes;
  __global const RsBvhNode* nodes;
  uint node_count;
  __global const RsTriangle* triangles;
} RsFileScene;

/* The user's function, defined in the file after this header. Declared here static and always
 * inlined, as the built-in keys are (keys.h, RS_KEY_INLINE), so a plain definition in the file takes
 * this linkage: called out of line, PoCL did not vectorise the kernel across work-items, and the
 * example (docs/examples/morton_zyx.cl) took 4.3x Origin's encode time on cornell's bounce1 (0.134
 * against 0.031 ms at 128x72); inlined, with keys.h's two-word 64-bit store, 1.02-1.03x Origin's
 * (encodebench --versus origin, paired, 32 and 64 bits). */
RS_KEY_INLINE rs_u64 rs_file_code(const RsEncodeFrame* frame, RsRay ray, uint bits, const RsFileScene* scene);

/* encode_file_k32 / _k64, the signature of a family kernel (the host's EncodeLaunch::set_args):
 * the inputs above, then rays, order, count, bits, keys, values. */
#define RS_DEFINE_FILE_KERNEL(SUFFIX, KEY_T)                                                             \
  __kernel void encode_file_##SUFFIX(const RsEncodeFrame frame, __constant const RsCutGroup* cut,        \
                                     uint cut_boxes, __global const RsBvhNode* nodes, uint node_count,   \
                                     __global const RsTriangle* triangles, __global const RsRay* rays,   \
                                     __global const uint* order, uint count, uint bits,                  \
                                     __global KEY_T* keys, __global uint* values) {                      \
    const uint i = get_global_id(0);                                                                     \
    if (i >= count) return;                                                                              \
    RsFileScene scene;                                                                                   \
    scene.cut = cut, scene.cut_boxes = cut_boxes, scene.nodes = nodes, scene.node_count = node_count;    \
    scene.triangles = triangles;                                                                         \
    const rs_u64 code = rs_file_code(&frame, rays[order[i]], bits, &scene);                              \
    RS_STORE_KEY_##SUFFIX(keys, i, rs_key_from_code(code, bits));                                        \
    values[i] = i;                                                                                       \
  }
RS_DEFINE_FILE_KERNEL(k32, uint)
RS_DEFINE_FILE_KERNEL(k64, ulong)

#endif /* RAYSORT_ENCODE_FILE_H */
