/* raysort — encode kernels: the sort keys of every encoder of docs/design.md, "Encoders", one kernel per
 * family (spatial codes, box-set codes, two-level cut code, prefix path code, no key).
 *
 * Conventions shared with trace.cl: the ray of work-item i is rays[order[i]]; the global size is
 * padded to a multiple of the local size and every kernel guards on count, except the spatial
 * kernels (below). Each kernel writes keys[i] and values[i] = i, ready for the key-value radix
 * sort. The key layouts themselves live in keys.h (what they share) and keys_spatial.h,
 * keys_cut.h, keys_ppc.h (one per family), shared with the host twin (host/encode/), so both give
 * the same bits.
 *
 * Which kernels exist comes from the encoder list (encoders.h): one per spatial encoder, one set per
 * family. Every kernel exists twice: *_k32 writes uint keys (key bits ≤ 32), *_k64 ulong keys.
 * Cut nodes (HCC, RegularGrid cells, MLHCC top nodes) come as sixteen-box SoA groups (RsCutGroup,
 * keys_cut.h) in __constant memory: every work-item reads the same boxes, which GPUs broadcast
 * from the constant cache, and PoCL needs no per-group copy or barrier (Xiang et al. Alg. 1, line 1, keeps
 * them in shared memory; the constant cache plays that part here). MLHCC's low-level rows (one per
 * ray, chosen by its first top-level hit) stay in global memory.
 */
#include "keys_cut.h"
#include "keys_ppc.h"
#include "keys_spatial.h"

/* The code bits a key of this width can hold: a key of at most 32 bits comes from bits 63..32 of the
 * code. Masking the rest lets the compiler drop the low half of the cut-bit accumulation
 * (keys_cut.h, rs_cut_bits) in the 32-bit kernels. */
#define RS_CODE_MASK_k32 0xFFFFFFFF00000000UL
#define RS_CODE_MASK_k64 0xFFFFFFFFFFFFFFFFUL

/* rays[index], read as floats at a signed 32-bit offset: PoCL's vectoriser then gathers each field
 * with vgatherdps on eight 32-bit offsets instead of vgatherqps on eight 64-bit addresses (a
 * zero-extended index). The host keeps batches below 2^28 rays, so the offset fits. */
static inline RsRay rs_load_ray(__global const RsRay* rays, uint index) {
  __global const float* f = (__global const float*)rays;
  const int at = (int)(index * 8u);
  RsRay r;
  r.o[0] = f[at], r.o[1] = f[at + 1], r.o[2] = f[at + 2], r.tmin = f[at + 3];
  r.d[0] = f[at + 4], r.d[1] = f[at + 5], r.d[2] = f[at + 6], r.tmax = f[at + 7];
  return r;
}

/* One kernel per spatial encoder (encode_origin_k32, ...): a straight-line body PoCL can vectorise
 * across work-items (a single kernel switching on the encoder did not vectorise).
 * Two things keep PoCL's vectoriser from gathering what it could load:
 *  - The frame comes by value. Read through a pointer after the count guard, each of its six
 *    fields was a masked gather of one address per ray (the loads are conditional, so they are not
 *    hoisted as uniform).
 *  - No count guard: a guarded body makes every load a masked one. The host launches whole
 *    work-groups over rays [0, full) and the rest, one work-item per group, from `first` on
 *    (DeviceEncoder::enqueue), so every work-item has a ray.
 * Measured on breakfast_room's shadow rays (results/history/encoder-kernels.md): 0.7–0.9x the time. */
#define RS_DEFINE_SPATIAL_KERNEL(NAME, SUFFIX, KEY_T)                                                    \
  __kernel void encode_##NAME##_##SUFFIX(const RsEncodeFrame frame, __global const RsRay* rays,           \
                                         __global const uint* order, uint first, uint bits,             \
                                         __global KEY_T* keys, __global uint* values) {                 \
    const uint i = first + (uint)get_global_id(0);                                                       \
    RS_STORE_KEY_##SUFFIX(keys, i, rs_key_from_code(rs_##NAME##_code(&frame, rs_load_ray(rays, order[i])), bits)); \
    values[i] = i;                                                                                       \
  }

/* HCC, RegularGrid, HCC_DIR (keys_cut.h, rs_box_set_code); the _or form for HCC_DIR's second pass. */
#define RS_DEFINE_BOX_SET_KERNEL(NAME, CODE, STORE, SUFFIX, KEY_T)                                        \
  __kernel void encode_##NAME##_##SUFFIX(__constant const RsCutGroup* set, uint box_count, uint field,    \
                                         uint dir_bits, __global const RsRay* rays,                      \
                                         __global const uint* order, uint count, uint bits,              \
                                         __global KEY_T* keys, __global uint* values) {                  \
    uint i = get_global_id(0);                                                                           \
    if (i >= count) return;                                                                              \
    rs_u64 code = CODE(rays[order[i]], set, box_count, field, dir_bits) & RS_CODE_MASK_##SUFFIX;          \
    keys[i] STORE (KEY_T)rs_key_from_code(code, bits);                                                   \
    values[i] = i;                                                                                       \
  }

/* HCC_DIR with d > 1 direction bits, in two passes: encode_direction_* writes the direction bits
 * (below a box field of `field` bits), then encode_box_set_or_* ORs in the box bits (called with
 * dir_bits = 0). The direction field (atan2, acos) is what such an HCC_DIR spends its time on; in a
 * kernel of its own PoCL runs it 8 rays at a time, which it cannot in the box-set kernel (its
 * float16 cut tests are vector-typed). The key is the same: key_from_code(a | b) =
 * key_from_code(a) | key_from_code(b). With d = 1 (the default) the box-set kernel reads the bit
 * from the signs of dx and dy (keys_spatial.h, rs_direction_top_bit), one pass. */
#define RS_DEFINE_DIRECTION_KERNEL(SUFFIX, KEY_T)                                                          \
  __kernel void encode_direction_##SUFFIX(__global const RsRay* rays, __global const uint* order,        \
                                          uint count, uint field, uint dir_bits, uint bits,              \
                                          __global KEY_T* keys, __global uint* values) {                 \
    uint i = get_global_id(0);                                                                           \
    if (i >= count) return;                                                                              \
    rs_u64 code = rs_direction_bits(rays[order[i]], dir_bits) << (64u - field - dir_bits);               \
    RS_STORE_KEY_##SUFFIX(keys, i, rs_key_from_code(code, bits));                                        \
    values[i] = i;                                                                                       \
  }

/* The kernels of each family of the encoder list (encoders.h): RS_DEFINE_<family>_KERNELS(SUFFIX,
 * KEY_T) defines encode_<family>_<SUFFIX> (and any second-pass kernels the family launches); a new
 * family defines its own in its kernel header. The spatial family's kernels are one per SPATIAL row. */
#define RS_DEFINE_nosort_KERNELS(SUFFIX, KEY_T)                                                          \
  __kernel void encode_nosort_##SUFFIX(uint count, __global KEY_T* keys, __global uint* values) {        \
    uint i = get_global_id(0);                                                                           \
    if (i >= count) return;                                                                              \
    keys[i] = 0;                                                                                         \
    values[i] = i;                                                                                       \
  }

#define RS_SPATIAL_KERNEL_k32(ID, HOST, NAME, CODE, WEIGHT, ALIASES) RS_DEFINE_SPATIAL_KERNEL(CODE, k32, uint)
#define RS_SPATIAL_KERNEL_k64(ID, HOST, NAME, CODE, WEIGHT, ALIASES) RS_DEFINE_SPATIAL_KERNEL(CODE, k64, ulong)
#define RS_DEFINE_spatial_KERNELS(SUFFIX, KEY_T) RS_ENCODERS(RS_NO_ROW, RS_SPATIAL_KERNEL_##SUFFIX)

#define RS_DEFINE_box_set_KERNELS(SUFFIX, KEY_T)                                                         \
  RS_DEFINE_BOX_SET_KERNEL(box_set, rs_box_set_code, =, SUFFIX, KEY_T)                                   \
  RS_DEFINE_BOX_SET_KERNEL(box_set_or, rs_box_set_code, |=, SUFFIX, KEY_T)                               \
  RS_DEFINE_DIRECTION_KERNEL(SUFFIX, KEY_T)

#define RS_DEFINE_two_level_KERNELS(SUFFIX, KEY_T)                                                       \
  __kernel void encode_two_level_##SUFFIX(__constant const RsCutGroup* top, uint top_count,              \
                                          __global const RsCutGroup* low, __global const uint* low_count,\
                                          uint half_bits, __global const RsRay* rays,                    \
                                          __global const uint* order, uint count, uint bits,             \
                                          __global KEY_T* keys, __global uint* values) {                 \
    const uint i = RS_TWO_LEVEL_RAYS * get_global_id(0); /* rays i, i + 1 (rs_two_level_cut_code2) */    \
    if (i >= count) return;                                                                              \
    const uint j = i + 1u < count ? i + 1u : i;                                                          \
    rs_u64 code_i, code_j;                                                                               \
    rs_two_level_cut_code2(rays[order[i]], rays[order[j]], top, top_count, low, low_count, half_bits,    \
                           &code_i, &code_j);                                                            \
    keys[i] = (KEY_T)rs_key_from_code(code_i & RS_CODE_MASK_##SUFFIX, bits);                             \
    values[i] = i;                                                                                       \
    keys[j] = (KEY_T)rs_key_from_code(code_j & RS_CODE_MASK_##SUFFIX, bits);                             \
    values[j] = j;                                                                                       \
  }

/* MLHCC_COST (keys_cut.h, rs_cost_cut_code): MLHCC's tables with rows of low_bits boxes, and the
 * per-bin cost field (RS_COST_BINS words) in global memory. One ray per work-item: two, as
 * MLHCC's kernel takes, measured 5-8 % slower here (sibenik bounce1, 960x540, PoCL). */
#define RS_DEFINE_cost_cut_KERNELS(SUFFIX, KEY_T)                                                        \
  __kernel void encode_cost_cut_##SUFFIX(const RsEncodeFrame frame, __constant const RsCutGroup* top,     \
                                         uint top_count, __global const RsCutGroup* low,                 \
                                         __global const uint* low_count, uint top_bits, uint low_bits,   \
                                         __global const uint* cost, __global const RsRay* rays,          \
                                         __global const uint* order, uint count, uint bits,              \
                                         __global KEY_T* keys, __global uint* values) {                  \
    uint i = get_global_id(0);                                                                           \
    if (i >= count) return;                                                                              \
    rs_u64 code = rs_cost_cut_code(rays[order[i]], &frame, top, top_count, low, low_count, top_bits,     \
                                   low_bits, cost, bits) & RS_CODE_MASK_##SUFFIX;                        \
    keys[i] = (KEY_T)rs_key_from_code(code, bits);                                                       \
    values[i] = i;                                                                                       \
  }

/* HCC_REGION (keys_cut.h, rs_region_cut_code): the region cells in __constant memory, as HCC's
 * cut boxes (the same for every ray); the regions' cuts (one row per region) in global memory:
 * rays of one work-group may read different rows. */
#define RS_DEFINE_region_cut_KERNELS(SUFFIX, KEY_T)                                                      \
  __kernel void encode_region_cut_##SUFFIX(__constant const RsRegionCells* cells, uint region_bits,      \
                                           __global const RsCutGroup* cuts, __global const uint* cut_count,\
                                           uint row_size, __global const RsRay* rays,                    \
                                           __global const uint* order, uint count, uint bits,            \
                                           __global KEY_T* keys, __global uint* values) {                 \
    uint i = get_global_id(0);                                                                           \
    if (i >= count) return;                                                                              \
    rs_u64 code = rs_region_cut_code(rays[order[i]], cells, region_bits, cuts, cut_count, row_size) &     \
                  RS_CODE_MASK_##SUFFIX;                                                                 \
    keys[i] = (KEY_T)rs_key_from_code(code, bits);                                                       \
    values[i] = i;                                                                                       \
  }

#define RS_DEFINE_prefix_path_KERNELS(SUFFIX, KEY_T)                                                     \
  __kernel void encode_prefix_path_##SUFFIX(__global const RsBvhNode* nodes,                             \
                                            __global const RsTriangle* tris, __global const RsRay* rays, \
                                            __global const uint* order, uint count, uint bits,           \
                                            __global KEY_T* keys, __global uint* values) {               \
    uint i = get_global_id(0);                                                                           \
    if (i >= count) return;                                                                              \
    keys[i] = (KEY_T)rs_key_from_code(rs_prefix_path_code(nodes, tris, rays[order[i]], bits), bits);     \
    values[i] = i;                                                                                       \
  }

/* Every family's kernels, *_k32 (uint keys) and *_k64 (ulong keys). */
#define RS_DEFINE_FAMILY_KERNELS(FAMILY) \
  RS_DEFINE_##FAMILY##_KERNELS(k32, uint) RS_DEFINE_##FAMILY##_KERNELS(k64, ulong)
RS_ENCODER_FAMILIES(RS_DEFINE_FAMILY_KERNELS)
