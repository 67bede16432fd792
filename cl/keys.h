/* raysort — ray sort keys: the one definition of every key layout, shared by cl/encode.cl and
 * the host twin (host/encode/). Bit diagrams: docs/encoders.md.
 *
 * Every encoder builds a 64-bit code, most significant bit first; a key of b bits is the code's
 * top b bits, code >> (64 − b) (DESIGN.md section 3; this is how Meister et al. 2020's reference
 * kernels truncate). Keys of up to 32 bits are stored in 32-bit words, 64-bit keys in 64-bit words.
 *
 * Spatial encoders (Meister et al. 2020, "On Ray Reordering Techniques for Faster GPU Ray
 * Tracing"; Xiang et al., "Faster Ray Tracing through Hierarchy Cut Code", section 3.2):
 *   Origin    3-D Morton code of the origin (22 levels, truncated to 64 bits)
 *   Reis      22 origin bits (7 Morton levels + 1), then 21 levels of (φ, θ) interleaved
 *   Costa     4 levels of (φ, θ), then 15 Morton levels of the origin, then 11 zero bits
 *   Aila      3 Morton levels of the origin, then 9 groups [origin level i xyz | direction level xyz]
 *   TwoPoint  6-D Morton code of origin a and estimated termination point b (11 levels, truncated)
 * Box-set encoders (Xiang et al. sections 4.2–4.3, 5): bit i (from the top) = the ray segment
 * [tmin, tmax] overlaps box i. HCC (cut nodes by descending HAD), RegularGrid (grid cells),
 * HCC_DIR (appendix: b − d cut bits, then d direction bits), MLHCC (two-level cut),
 * PPC (section 4.1: the first b box tests of a traversal in fixed left-first order).
 *
 * Quantization is in the scene's box: q = clamp(floor(t·2^n), 0, 2^n − 1) with
 * t = (p − box.min)·inv_extent; a flat axis has inv_extent = 0 (t = 0). The clamp keeps points on
 * the max face, and points outside the box, inside their field.
 * Directions are normalised here (rays need not carry unit directions); φ = atan2(dy, dx)/2π + ½,
 * θ = acos(dz)/π with dz clamped to [−1, 1]; atan2/acos come from encode_math.h (no library
 * transcendentals). The ray segment tests use the ray's own parameterisation (t units).
 */
#ifndef RAYSORT_KEYS_H
#define RAYSORT_KEYS_H

#include "encode_math.h"
#include "shared.h"
#include "traverse.h"

#ifdef __OPENCL_VERSION__
#define RS_LOCAL __local
#define RS_U64(x) ((ulong)(x))
#else
#define RS_LOCAL
#define RS_U64(x) ((rs_u64)(x))
#endif

/* Encoder ids: the values of the host's enum class Encoder (host/encode/encode.h). */
#define RS_ENC_NOSORT 0
#define RS_ENC_ORIGIN 1
#define RS_ENC_REIS 2
#define RS_ENC_COSTA 3
#define RS_ENC_AILA 4
#define RS_ENC_TWOPOINT 5
#define RS_ENC_REGULAR_GRID 6
#define RS_ENC_HCC 7
#define RS_ENC_MLHCC 8
#define RS_ENC_PPC 9
#define RS_ENC_HCC_DIR 10

/* The most boxes a box-set key reads per ray: one per key bit. */
#define RS_MAX_KEY_BITS 64

/* An axis-aligned box, 24 bytes: [bmin.x bmin.y bmin.z bmax.x bmax.y bmax.z]. Cut nodes and grid
 * cells go to the device as arrays of these (bit order = array order). */
typedef struct {
  float bmin[3];
  float bmax[3];
} RsBox;

/* Per-scene encode constants, 48 bytes, computed once on the host and uploaded as is:
 * [box_min xyz | twopoint_length | box_max xyz | pad | inv_extent xyz | pad].
 * inv_extent[a] = 1 / (box_max[a] − box_min[a]), or 0 on a flat axis.
 * twopoint_length = TwoPoint's fixed ray length (fraction · largest extent of the box). */
typedef struct {
  float box_min[3];
  float twopoint_length;
  float box_max[3];
  float pad0;
  float inv_extent[3];
  float pad1;
} RsEncodeFrame;

/* ---------------------------------------------------------------------------------------------
 * Quantization and bit assembly.
 * ------------------------------------------------------------------------------------------- */

/* clamp(floor(t·2^n), 0, 2^n − 1) for n ≤ 24 (2^n exact in float). NaN maps to 0. */
RS_INLINE rs_u32 rs_quantize(float t, rs_u32 n) {
  float cells = (float)(1u << n);
  float q = rs_floor(t * cells);
  q = rs_max(0.0f, rs_min(q, cells - 1.0f));
  return (rs_u32)q;
}

/* The n-bit cell of coordinate p on axis a of the scene box. */
RS_INLINE rs_u32 rs_quantize_axis(const RsEncodeFrame* f, int a, float p, rs_u32 n) {
  return rs_quantize((p - f->box_min[a]) * f->inv_extent[a], n);
}

/* A 64-bit code filled from its most significant bit down. */
typedef struct {
  rs_u64 code;
  rs_u32 used;
} RsBitWriter;

RS_INLINE RsBitWriter rs_bit_writer(void) {
  RsBitWriter w;
  w.code = 0;
  w.used = 0;
  return w;
}

/* Appends the low n bits of v (n ≤ 32), most significant first; bits past 64 are dropped. */
RS_INLINE void rs_put_bits(RsBitWriter* w, rs_u32 v, rs_u32 n) {
  if (w->used >= 64u || n == 0u) return;
  rs_u64 bits = RS_U64(v) & ((RS_U64(1) << n) - 1u);
  rs_u32 room = 64u - w->used;
  if (n <= room) {
    w->code |= bits << (room - n);
    w->used += n;
  } else {
    w->code |= bits >> (n - room);
    w->used = 64u;
  }
}

/* Bit `level` (0 = most significant) of an n-bit quantized coordinate. */
RS_INLINE rs_u32 rs_level_bit(rs_u32 q, rs_u32 n, rs_u32 level) { return (q >> (n - 1u - level)) & 1u; }

/* The key of b bits (1 ≤ b ≤ 64): the code's top b bits. */
RS_INLINE rs_u64 rs_key_from_code(rs_u64 code, rs_u32 bits) { return bits >= 64u ? code : code >> (64u - bits); }

/* ---------------------------------------------------------------------------------------------
 * Ray fields.
 * ------------------------------------------------------------------------------------------- */

#define RS_ORIGIN_LEVELS 22u    /* 3·22 = 66 ≥ 64: enough levels for every origin field */
#define RS_DIRECTION_LEVELS 21u /* 2·21 = 42: Reis's direction field */
#define RS_AILA_DIR_LEVELS 9u
#define RS_TWOPOINT_LEVELS 11u  /* 6·11 = 66 ≥ 64 */

/* Origin cells (n bits per axis). */
RS_INLINE void rs_quantize_point(const RsEncodeFrame* f, RsVec3 p, rs_u32 n, rs_u32 q[3]) {
  q[0] = rs_quantize_axis(f, 0, p.x, n);
  q[1] = rs_quantize_axis(f, 1, p.y, n);
  q[2] = rs_quantize_axis(f, 2, p.z, n);
}

/* The unit direction: d / |d| (a zero direction stays zero). */
RS_INLINE RsVec3 rs_unit_direction(RsRay r) { return rs_normalize(rs_vec3(r.d[0], r.d[1], r.d[2])); }

/* Spherical direction cells: q[0] = φ = atan2(dy, dx)/2π + ½, q[1] = θ = acos(dz)/π, n bits each. */
RS_INLINE void rs_quantize_spherical(RsVec3 d, rs_u32 n, rs_u32 q[2]) {
  float phi = rs_atan2(d.y, d.x) * RS_INV_2PI_F + 0.5f;
  float theta = rs_acos(d.z) * RS_INV_PI_F;
  q[0] = rs_quantize(phi, n);
  q[1] = rs_quantize(theta, n);
}

/* Appends Morton levels [first, first + levels) of the 3 coordinates q (n bits each), x y z. */
RS_INLINE void rs_put_morton3(RsBitWriter* w, const rs_u32 q[3], rs_u32 n, rs_u32 first, rs_u32 levels) {
  for (rs_u32 l = first; l < first + levels; ++l)
    rs_put_bits(w, (rs_level_bit(q[0], n, l) << 2) | (rs_level_bit(q[1], n, l) << 1) | rs_level_bit(q[2], n, l), 3u);
}

/* Appends `levels` levels of the spherical cells (φ, θ), φ first. */
RS_INLINE void rs_put_spherical(RsBitWriter* w, const rs_u32 q[2], rs_u32 n, rs_u32 levels) {
  for (rs_u32 l = 0; l < levels; ++l) rs_put_bits(w, (rs_level_bit(q[0], n, l) << 1) | rs_level_bit(q[1], n, l), 2u);
}

/* Far end of a ray's segment inside the scene box: the slab-test exit distance (same reciprocal
 * as traversal), capped by tmax. */
RS_INLINE float rs_scene_exit(const RsEncodeFrame* f, RsTraversalRay r) {
  float tx0 = (f->box_min[0] - r.o.x) * r.inv_d.x, tx1 = (f->box_max[0] - r.o.x) * r.inv_d.x;
  float ty0 = (f->box_min[1] - r.o.y) * r.inv_d.y, ty1 = (f->box_max[1] - r.o.y) * r.inv_d.y;
  float tz0 = (f->box_min[2] - r.o.z) * r.inv_d.z, tz1 = (f->box_max[2] - r.o.z) * r.inv_d.z;
  return rs_min(rs_min(rs_max(tx0, tx1), rs_max(ty0, ty1)), rs_min(rs_max(tz0, tz1), r.tmax));
}

/* ---------------------------------------------------------------------------------------------
 * Spatial codes (Meister et al. 2020, section 3; Xiang et al. section 3.2 and section 5).
 * ------------------------------------------------------------------------------------------- */

/* Origin: the 3-D Morton code of the origin, x y z per level. */
RS_INLINE rs_u64 rs_origin_code(const RsEncodeFrame* f, RsRay r) {
  rs_u32 q[3];
  rs_quantize_point(f, rs_load3(r.o), RS_ORIGIN_LEVELS, q);
  RsBitWriter w = rs_bit_writer();
  rs_put_morton3(&w, q, RS_ORIGIN_LEVELS, 0u, RS_ORIGIN_LEVELS);
  return w.code;
}

/* Reis et al. 2017 (origin → direction): 22 origin Morton bits, then 21 levels of (φ, θ). */
RS_INLINE rs_u64 rs_reis_code(const RsEncodeFrame* f, RsRay r) {
  rs_u32 q[3], s[2];
  rs_quantize_point(f, rs_load3(r.o), RS_ORIGIN_LEVELS, q);
  rs_quantize_spherical(rs_unit_direction(r), RS_DIRECTION_LEVELS, s);
  RsBitWriter w = rs_bit_writer();
  rs_put_morton3(&w, q, RS_ORIGIN_LEVELS, 0u, 7u);
  rs_put_bits(&w, rs_level_bit(q[0], RS_ORIGIN_LEVELS, 7u), 1u);
  rs_put_spherical(&w, s, RS_DIRECTION_LEVELS, RS_DIRECTION_LEVELS);
  return w.code;
}

/* Costa et al. 2015 (direction → origin): 4 levels of (φ, θ), 15 origin Morton levels, 11 zeros. */
RS_INLINE rs_u64 rs_costa_code(const RsEncodeFrame* f, RsRay r) {
  rs_u32 q[3], s[2];
  rs_quantize_point(f, rs_load3(r.o), 15u, q);
  rs_quantize_spherical(rs_unit_direction(r), 4u, s);
  RsBitWriter w = rs_bit_writer();
  rs_put_spherical(&w, s, 4u, 4u);
  rs_put_morton3(&w, q, 15u, 0u, 15u);
  return w.code;
}

/* Aila & Karras 2010 ("Aila_Compact" of Meister et al.): 3 origin Morton levels, then 9 groups of
 * [origin level 3+i: x y z | direction level i: x y z of (d + 1)/2]; the last bit is 0. */
RS_INLINE rs_u64 rs_aila_code(const RsEncodeFrame* f, RsRay r) {
  const rs_u32 on = 12u, dn = RS_AILA_DIR_LEVELS;
  rs_u32 q[3], dq[3];
  rs_quantize_point(f, rs_load3(r.o), on, q);
  RsVec3 d = rs_unit_direction(r);
  dq[0] = rs_quantize((d.x + 1.0f) * 0.5f, dn);
  dq[1] = rs_quantize((d.y + 1.0f) * 0.5f, dn);
  dq[2] = rs_quantize((d.z + 1.0f) * 0.5f, dn);
  RsBitWriter w = rs_bit_writer();
  rs_put_morton3(&w, q, on, 0u, 3u);
  for (rs_u32 i = 0; i < dn; ++i) {
    rs_put_morton3(&w, q, on, 3u + i, 1u);
    rs_put_morton3(&w, dq, dn, i, 1u);
  }
  return w.code;
}

/* TwoPoint (Moon et al. 2010; Meister et al. 2020, fixed-length estimate): 6-D Morton code of the
 * origin a and b = a + L·d, L = max(0, min(twopoint_length, tmax, scene-box exit)); b is clamped
 * to the box by the quantization. Per level: a.x a.y a.z b.x b.y b.z. */
RS_INLINE rs_u64 rs_twopoint_code(const RsEncodeFrame* f, RsRay ray) {
  const rs_u32 n = RS_TWOPOINT_LEVELS;
  RsTraversalRay r = rs_prepare_ray(ray);
  float len = rs_max(0.0f, rs_min(f->twopoint_length, rs_scene_exit(f, r)));
  RsVec3 b = rs_add(r.o, rs_scale(r.d, len));
  rs_u32 qa[3], qb[3];
  rs_quantize_point(f, r.o, n, qa);
  rs_quantize_point(f, b, n, qb);
  RsBitWriter w = rs_bit_writer();
  for (rs_u32 l = 0; l < n; ++l) {
    rs_put_morton3(&w, qa, n, l, 1u);
    rs_put_morton3(&w, qb, n, l, 1u);
  }
  return w.code;
}

/* d direction bits (HCC_DIR): the top d bits of the Reis direction field, (φ, θ) interleaved. */
RS_INLINE rs_u64 rs_direction_bits(RsRay r, rs_u32 d) {
  rs_u32 s[2];
  rs_quantize_spherical(rs_unit_direction(r), RS_DIRECTION_LEVELS, s);
  RsBitWriter w = rs_bit_writer();
  rs_put_spherical(&w, s, RS_DIRECTION_LEVELS, RS_DIRECTION_LEVELS);
  return rs_key_from_code(w.code, d);
}

RS_INLINE rs_u64 rs_spatial_code(int encoder, const RsEncodeFrame* f, RsRay r) {
  switch (encoder) {
    case RS_ENC_ORIGIN: return rs_origin_code(f, r);
    case RS_ENC_REIS: return rs_reis_code(f, r);
    case RS_ENC_COSTA: return rs_costa_code(f, r);
    case RS_ENC_AILA: return rs_aila_code(f, r);
    case RS_ENC_TWOPOINT: return rs_twopoint_code(f, r);
    default: return 0;
  }
}

/* ---------------------------------------------------------------------------------------------
 * Box-set codes (Xiang et al. Alg. 1).
 * ------------------------------------------------------------------------------------------- */

/* Does the segment [tmin, tmax] of r overlap box b? The same slab arithmetic, in the same order,
 * as rs_intersect_box in traverse.h (which takes a __global node; this takes a box by value so it
 * works on local-memory cut nodes): a cut-node bit is 1 exactly when traversal would enter it. */
RS_INLINE int rs_segment_overlaps_box(RsTraversalRay r, RsBox b) {
  float tx0 = (b.bmin[0] - r.o.x) * r.inv_d.x, tx1 = (b.bmax[0] - r.o.x) * r.inv_d.x;
  float ty0 = (b.bmin[1] - r.o.y) * r.inv_d.y, ty1 = (b.bmax[1] - r.o.y) * r.inv_d.y;
  float tz0 = (b.bmin[2] - r.o.z) * r.inv_d.z, tz1 = (b.bmax[2] - r.o.z) * r.inv_d.z;
  float tnear = rs_max(rs_max(rs_min(tx0, tx1), rs_min(ty0, ty1)), rs_max(rs_min(tz0, tz1), r.tmin));
  float tfar = rs_min(rs_min(rs_max(tx0, tx1), rs_max(ty0, ty1)), rs_min(rs_max(tz0, tz1), r.tmax));
  return tnear <= tfar;
}

/* HCC / RegularGrid / HCC_DIR: bit 63 − i = overlap with boxes[i], i < n (n ≤ 64 − dir_bits);
 * then dir_bits direction bits right below the box field of `field` bits (HCC_DIR). */
RS_INLINE rs_u64 rs_box_set_code(RsRay ray, RS_LOCAL const RsBox* boxes, rs_u32 n, rs_u32 field, rs_u32 dir_bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  rs_u64 code = 0;
  for (rs_u32 i = 0; i < n; ++i)
    if (rs_segment_overlaps_box(r, boxes[i])) code |= RS_U64(1) << (63u - i);
  if (dir_bits > 0u) code |= rs_direction_bits(ray, dir_bits) << (64u - field - dir_bits);
  return code;
}

/* MLHCC (Xiang et al. section 4.3): the top `half_bits` bits are the HCC of the top-level cut; the
 * representative top node is the first one hit (top nodes are in descending HAD order); the next
 * `half_bits` bits are the HCC of its low-level cut: low[rep·half_bits + j], j < low_count[rep]. No top node
 * hit: the low bits are 0. */
RS_INLINE rs_u64 rs_two_level_cut_code(RsRay ray, RS_LOCAL const RsBox* top, rs_u32 n_top, RS_GLOBAL const RsBox* low,
                                       RS_GLOBAL const rs_u32* low_count, rs_u32 half_bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  rs_u64 code = 0;
  rs_u32 rep = 0xFFFFFFFFu;
  for (rs_u32 i = 0; i < n_top; ++i) {
    if (rs_segment_overlaps_box(r, top[i])) {
      code |= RS_U64(1) << (63u - i);
      if (rep == 0xFFFFFFFFu) rep = i;
    }
  }
  if (rep != 0xFFFFFFFFu) {
    rs_u32 m = low_count[rep];
    for (rs_u32 j = 0; j < m; ++j)
      if (rs_segment_overlaps_box(r, low[rep * half_bits + j])) code |= RS_U64(1) << (63u - half_bits - j);
  }
  return code;
}

/* PPC (Xiang et al. section 4.1): the first `bits` box-test results of a closest-hit traversal
 * that visits children in fixed order, left first: the root's test, then at each inner node the
 * left and the right child's tests (rs_intersect_box, the trace kernels' test, against the
 * current closest hit); leaves test their triangles, which shortens the segment as in a trace.
 * 1 = hit, most significant first; a traversal that ends early leaves 0s. */
RS_INLINE rs_u64 rs_prefix_path_code(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                     rs_u32 bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  float tmax = ray.tmax;
  RsBitWriter w = rs_bit_writer();
  int hit;
  rs_intersect_box(r, &nodes[0], tmax, &hit);
  rs_put_bits(&w, (rs_u32)hit, 1u);
  if (!hit) return w.code;
  rs_u32 stack[RS_STACK_SIZE];
  int sp = 0;
  rs_u32 node = 0;
  while (w.used < bits) {
    RS_GLOBAL const RsBvhNode* n = &nodes[node];
    if (n->count > 0) {
      for (rs_u32 i = n->first; i < n->first + n->count; ++i) {
        float t, u, v;
        if (rs_intersect_triangle(r, &tris[i], tmax, &t, &u, &v)) tmax = t;
      }
    } else {
      rs_u32 left = n->first;
      int hit_l, hit_r;
      rs_intersect_box(r, &nodes[left], tmax, &hit_l);
      rs_intersect_box(r, &nodes[left + 1], tmax, &hit_r);
      rs_put_bits(&w, (rs_u32)hit_l, 1u);
      rs_put_bits(&w, (rs_u32)hit_r, 1u);
      if (hit_l) {
        if (hit_r) stack[sp++] = left + 1;
        node = left;
        continue;
      }
      if (hit_r) {
        node = left + 1;
        continue;
      }
    }
    if (sp == 0) break;
    node = stack[--sp];
  }
  /* Drop results past the key (the last pair may overrun it by one). */
  return bits >= 64u ? w.code : w.code & ~((~RS_U64(0)) >> bits);
}

#endif /* RAYSORT_KEYS_H */
