/* raysort — lane types: four, eight and sixteen floats or ints processed as one value. OpenCL's
 * vector types on the device; on the host, structs of the same layout with per-lane IEEE
 * operations, so the same source gives the same bits. The 4-wide BVH (bvh_layout.h,
 * traverse_wide.h) tests four boxes or triangles per operation; the cut keys (keys_cut.h) test
 * sixteen boxes. The mask-to-bits helpers turn a lane comparison into an int bit mask.
 */
#ifndef RAYSORT_LANES_H
#define RAYSORT_LANES_H

#include "shared.h"

/* ---------------------------------------------------------------------------------------------
 * Four-lane vectors for the 4-wide BVH (traverse_wide.h). OpenCL's float4/int4 on the device; on the
 * host a 16-byte struct with the same layout and per-lane IEEE operations, so the same source gives
 * the same bits. Comparisons give -1 (true) / 0 (false) per lane, as OpenCL's do. min/max are
 * selects (a < b ? a : b), not fmin/fmax: no NaN special case, one instruction on SSE.
 * ------------------------------------------------------------------------------------------- */
#ifdef __OPENCL_VERSION__
typedef float4 rs_f4;
typedef int4 rs_i4;
RS_LANE_INLINE rs_f4 rs4_splat(float x) { return (float4)(x); }
RS_LANE_INLINE rs_f4 rs4_min(rs_f4 a, rs_f4 b) { return select(b, a, a < b); }
RS_LANE_INLINE rs_f4 rs4_max(rs_f4 a, rs_f4 b) { return select(b, a, a > b); }
RS_LANE_INLINE rs_f4 rs4_select(rs_f4 if_false, rs_f4 if_true, rs_i4 m) { return select(if_false, if_true, m); }
RS_LANE_INLINE rs_f4 rs4_fma(rs_f4 a, rs_f4 b, rs_f4 c) { return fma(a, b, c); }
/* The lanes of a -1/0 mask as bits, lane i -> bit i. The traversal branches on these bits at every
 * node, so on x86 devices (PoCL) it is one movmskps; the portable form (AND with 1, 2, 4, 8, then OR
 * the lanes) put a shuffle-and-OR chain on that path, and the trace took 4-13 % longer (sibenik,
 * docs/trace.md). GPUs and other CPUs use the portable form; ClRuntime.MaskBitsFormsAgree compares
 * the two on the device for every mask. */
RS_LANE_INLINE int rs4_bits_portable(rs_i4 m) { return (m.s0 & 1) | (m.s1 & 2) | (m.s2 & 4) | (m.s3 & 8); }
#if defined(__x86_64__) && defined(__SSE__) && !defined(RS_PORTABLE_MASK_BITS)
#define RS_MASK_BITS_MOVMSK 1
RS_LANE_INLINE int rs4_bits(rs_i4 m) { return __builtin_ia32_movmskps(as_float4(m)); }
#else
#define RS_MASK_BITS_MOVMSK 0
RS_LANE_INLINE int rs4_bits(rs_i4 m) { return rs4_bits_portable(m); }
#endif
RS_LANE_INLINE void rs4_store(rs_f4 a, float* p) { vstore4(a, 0, p); }
/* Index of the lowest set bit of x != 0. OpenCL 1.2 has clz but no ctz: the portable form isolates
 * the bit and counts the zeros above it (three instructions); on x86 devices (PoCL) Clang's builtin is
 * one tzcnt, in every mask loop of the traversals (the stream's node loop runs one per ray and node). */
#if defined(__x86_64__) && !defined(RS_PORTABLE_MASK_BITS)
RS_LANE_INLINE int rs_lowest_bit(int x) { return __builtin_ctz((uint)x); }
RS_LANE_INLINE int rs_lowest_bit_u(uint x) { return __builtin_ctz(x); }
RS_LANE_INLINE int rs_lowest_bit_ul(ulong x) { return __builtin_ctzl(x); }
#else
RS_LANE_INLINE int rs_lowest_bit(int x) { return 31 - clz(x & -x); }
/* The same for a 32-bit mask whose top bit may be set (no signed overflow in the negation). */
RS_LANE_INLINE int rs_lowest_bit_u(uint x) { return 31 - (int)clz(x & (0u - x)); }
RS_LANE_INLINE int rs_lowest_bit_ul(ulong x) { return 63 - (int)clz(x & (0ul - x)); }
#endif
/* Index of the highest set bit of x != 0. */
RS_LANE_INLINE int rs_highest_bit(int x) { return 31 - clz(x); }
RS_LANE_INLINE int rs_popcount(int x) { return popcount(x); }
RS_LANE_INLINE rs_f4 rs4_load(const float* p) { return vload4(0, p); }
#else
typedef struct alignas(16) rs_f4 {
  float s[4];
} rs_f4;
typedef struct alignas(16) rs_i4 {
  rs_i32 s[4];
} rs_i4;
/* Per-lane operators of the host lane structs (N lanes; comparisons give -1 / 0 like OpenCL's).
 * Defined once here and used for the 8- and 16-lane structs below too. */
#define RS_LANES_BINARY(T, R, N, op)                         \
  RS_LANE_INLINE R operator op(T a, T b) {                        \
    R r;                                                     \
    for (int i = 0; i < N; ++i) r.s[i] = a.s[i] op b.s[i];   \
    return r;                                                \
  }
#define RS_LANES_COMPARE(F, I, N, op)                                          \
  RS_LANE_INLINE I operator op(F a, F b) {                                          \
    I r;                                                                       \
    for (int i = 0; i < N; ++i) r.s[i] = a.s[i] op b.s[i] ? -1 : 0;            \
    return r;                                                                  \
  }
#define RS4_COMPARE(op)                  \
  RS_LANES_COMPARE(rs_f4, rs_i4, 4, op) \
  RS_LANE_INLINE rs_i4 operator op(rs_f4 a, float b) { return a op rs_f4{{b, b, b, b}}; }
RS_LANES_BINARY(rs_f4, rs_f4, 4, +)
RS_LANES_BINARY(rs_f4, rs_f4, 4, -)
RS_LANES_BINARY(rs_f4, rs_f4, 4, *)
RS_LANES_BINARY(rs_f4, rs_f4, 4, /)
RS_LANES_BINARY(rs_i4, rs_i4, 4, &)
RS_LANES_BINARY(rs_i4, rs_i4, 4, |)
RS4_COMPARE(<)
RS4_COMPARE(>)
RS4_COMPARE(<=)
RS4_COMPARE(>=)
RS4_COMPARE(==)
RS4_COMPARE(!=)
#undef RS4_COMPARE
RS_LANE_INLINE rs_f4 rs4_splat(float x) { return rs_f4{{x, x, x, x}}; }
RS_LANE_INLINE rs_f4 operator*(rs_f4 a, float b) { return a * rs4_splat(b); }
RS_LANE_INLINE rs_f4 operator*(float a, rs_f4 b) { return rs4_splat(a) * b; }
RS_LANE_INLINE rs_f4 operator-(rs_f4 a, float b) { return a - rs4_splat(b); }
RS_LANE_INLINE rs_f4 operator-(float a, rs_f4 b) { return rs4_splat(a) - b; }
RS_LANE_INLINE rs_f4 rs4_select(rs_f4 if_false, rs_f4 if_true, rs_i4 m) {
  rs_f4 r;
  for (int i = 0; i < 4; ++i) r.s[i] = m.s[i] < 0 ? if_true.s[i] : if_false.s[i];
  return r;
}
RS_LANE_INLINE rs_f4 rs4_fma(rs_f4 a, rs_f4 b, rs_f4 c) {
  rs_f4 r;
  for (int i = 0; i < 4; ++i) r.s[i] = rs_fma(a.s[i], b.s[i], c.s[i]);
  return r;
}
RS_LANE_INLINE rs_f4 rs4_min(rs_f4 a, rs_f4 b) { return rs4_select(b, a, a < b); }
RS_LANE_INLINE rs_f4 rs4_max(rs_f4 a, rs_f4 b) { return rs4_select(b, a, a > b); }
RS_LANE_INLINE int rs4_bits(rs_i4 m) { return (m.s[0] & 1) | (m.s[1] & 2) | (m.s[2] & 4) | (m.s[3] & 8); }
RS_LANE_INLINE int rs_lowest_bit(int x) { return std::countr_zero(static_cast<unsigned>(x)); }
RS_LANE_INLINE int rs_lowest_bit_u(rs_u32 x) { return std::countr_zero(x); }
RS_LANE_INLINE int rs_lowest_bit_ul(rs_u64 x) { return std::countr_zero(x); }
RS_LANE_INLINE int rs_highest_bit(int x) { return 31 - std::countl_zero(static_cast<unsigned>(x)); }
RS_LANE_INLINE int rs_popcount(int x) { return std::popcount(static_cast<unsigned>(x)); }
RS_LANE_INLINE void rs4_store(rs_f4 a, float* p) {
  for (int i = 0; i < 4; ++i) p[i] = a.s[i];
}
RS_LANE_INLINE rs_f4 rs4_load(const float* p) { return rs_f4{{p[0], p[1], p[2], p[3]}}; }
#endif

/* |x| per lane, as max(x, 0 − x): the same bits on both sides (±0 gives +0). */
RS_LANE_INLINE rs_f4 rs4_abs(rs_f4 x) { return rs4_max(x, 0.0f - x); }

/* Sixteen-lane vectors in the same style (the encoders' cut-box tests, keys_cut.h): OpenCL's
 * float16/int16 on the device, a 64-byte struct with per-lane IEEE operations on the host. min/max
 * are selects, as rs4_min/rs4_max. Sixteen lanes because a CPU with AVX-512 runs them as one
 * instruction (PoCL turns float16 into zmm operations), which halves the instructions of a key
 * against eight-lane groups; elsewhere they are two eight-lane or sixteen scalar operations. */
#ifdef __OPENCL_VERSION__
typedef float16 rs_f16;
typedef int16 rs_i16;
RS_LANE_INLINE rs_f16 rs16_splat(float x) { return (float16)(x); }
RS_LANE_INLINE rs_f16 rs16_min(rs_f16 a, rs_f16 b) { return select(b, a, a < b); }
RS_LANE_INLINE rs_f16 rs16_max(rs_f16 a, rs_f16 b) { return select(b, a, a > b); }
/* The lanes of a sixteen- or eight-lane -1/0 mask as bits, lane i -> bit i (the cut-box tests,
 * keys_cut.h rs_cut_bits). On AVX-512 devices (PoCL on such CPUs) the compare's mask register is
 * the answer (kmovd, RS_MASK16_BITS = 1); on AVX devices without it, one vmovmskps per eight lanes
 * (RS_MASK16_BITS = 2; PoCL compiling for AVX2: HCC's, MLHCC's and the grid's keys 5-11 % faster
 * than with the portable form, results/history/encoder-kernels.md); elsewhere the lanes are ANDed
 * with their bits and ORed (with AVX-512, 1.2-1.6x slower box-set keys). -DRS_AVX_MASK_BITS takes
 * the AVX form on an AVX-512 device, -DRS_PORTABLE_MASK_BITS the portable one anywhere:
 * ClRuntime.MaskBitsFormsAgree and Encode.DeviceCutBitsInEveryFormEqualTheHost check all three. */
#if defined(__AVX512F__) && defined(__AVX512DQ__) && !defined(RS_PORTABLE_MASK_BITS) && !defined(RS_AVX_MASK_BITS)
#define RS_MASK16_BITS 1
RS_LANE_INLINE uint rs16_mask_bits(int16 m) { return (uint)__builtin_ia32_cvtd2mask512(m); }
RS_LANE_INLINE uint rs8_mask_bits(int8 m) { return (uint)__builtin_ia32_movmskps256(as_float8(m)); }
#elif defined(__x86_64__) && defined(__AVX__) && !defined(RS_PORTABLE_MASK_BITS)
#define RS_MASK16_BITS 2
RS_LANE_INLINE uint rs8_mask_bits(int8 m) { return (uint)__builtin_ia32_movmskps256(as_float8(m)); }
RS_LANE_INLINE uint rs16_mask_bits(int16 m) {
  return (uint)__builtin_ia32_movmskps256(as_float8(m.lo)) | ((uint)__builtin_ia32_movmskps256(as_float8(m.hi)) << 8);
}
#else
#define RS_MASK16_BITS 0
/* The lanes are ORed one by one, not folded by halves (.lo | .hi): the same bits, but Oclgrind's
 * uninitialised-value check reports the fold of a cut-box mask as uninitialised (a false positive
 * that would hide real findings). GPUs run both forms as the same scalar operations. */
RS_LANE_INLINE uint rs8_mask_bits(int8 m) {
  const int8 b = m & (int8)(1, 2, 4, 8, 16, 32, 64, 128);
  return (uint)(b.s0 | b.s1 | b.s2 | b.s3 | b.s4 | b.s5 | b.s6 | b.s7);
}
RS_LANE_INLINE uint rs16_mask_bits(int16 m) {
  const int16 b = m & (int16)(1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384, 32768);
  return (uint)(b.s0 | b.s1 | b.s2 | b.s3 | b.s4 | b.s5 | b.s6 | b.s7 | b.s8 | b.s9 | b.sa | b.sb | b.sc | b.sd |
                b.se | b.sf);
}
#endif
#else
typedef struct alignas(64) rs_f16 {
  float s[16];
} rs_f16;
typedef struct alignas(64) rs_i16 {
  rs_i32 s[16];
} rs_i16;
RS_LANES_BINARY(rs_f16, rs_f16, 16, +)
RS_LANES_BINARY(rs_f16, rs_f16, 16, -)
RS_LANES_BINARY(rs_f16, rs_f16, 16, *)
RS_LANES_BINARY(rs_i16, rs_i16, 16, &)
RS_LANES_BINARY(rs_i16, rs_i16, 16, |)
RS_LANES_COMPARE(rs_f16, rs_i16, 16, <)
RS_LANES_COMPARE(rs_f16, rs_i16, 16, >)
RS_LANES_COMPARE(rs_f16, rs_i16, 16, <=)
RS_LANE_INLINE rs_f16 rs16_splat(float x) {
  rs_f16 r;
  for (int i = 0; i < 16; ++i) r.s[i] = x;
  return r;
}
RS_LANE_INLINE rs_f16 rs16_min(rs_f16 a, rs_f16 b) {
  rs_f16 r;
  for (int i = 0; i < 16; ++i) r.s[i] = a.s[i] < b.s[i] ? a.s[i] : b.s[i];
  return r;
}
RS_LANE_INLINE rs_f16 rs16_max(rs_f16 a, rs_f16 b) {
  rs_f16 r;
  for (int i = 0; i < 16; ++i) r.s[i] = a.s[i] > b.s[i] ? a.s[i] : b.s[i];
  return r;
}
/* Lane i -> bit i (the device's rs16_mask_bits). */
RS_LANE_INLINE rs_u32 rs16_mask_bits(rs_i16 m) {
  rs_u32 b = 0;
  for (int i = 0; i < 16; ++i) b |= static_cast<rs_u32>(m.s[i] != 0) << i;
  return b;
}
#endif

/* ---------------------------------------------------------------------------------------------
 * Eight-lane vectors for the 8-wide BVH (bvh_layout.h RsWide8Node, traverse_wide8.h; also the
 * cut keys' half-full groups, keys_cut.h): OpenCL's float8/int8 on the device, which PoCL on an
 * AVX CPU runs as one ymm operation; on the host a 32-byte struct with per-lane IEEE operations,
 * the rs_f4 struct's twin, so the same source gives the same bits. min/max are selects.
 * ------------------------------------------------------------------------------------------- */
#ifdef __OPENCL_VERSION__
typedef float8 rs_f8;
typedef int8 rs_i8;
RS_LANE_INLINE rs_f8 rs8_splat(float x) { return (float8)(x); }
RS_LANE_INLINE rs_f8 rs8_min(rs_f8 a, rs_f8 b) { return select(b, a, a < b); }
RS_LANE_INLINE rs_f8 rs8_max(rs_f8 a, rs_f8 b) { return select(b, a, a > b); }
RS_LANE_INLINE rs_f8 rs8_select(rs_f8 if_false, rs_f8 if_true, rs_i8 m) { return select(if_false, if_true, m); }
RS_LANE_INLINE rs_f8 rs8_fma(rs_f8 a, rs_f8 b, rs_f8 c) { return fma(a, b, c); }
/* Lane i -> bit i: one vmovmskps on an AVX device (the traversal branches on it at every node, as
 * rs4_bits), the portable AND-and-OR of rs8_mask_bits elsewhere. */
#if defined(__x86_64__) && defined(__AVX__) && !defined(RS_PORTABLE_MASK_BITS)
RS_LANE_INLINE int rs8_bits(rs_i8 m) { return __builtin_ia32_movmskps256(as_float8(m)); }
#else
RS_LANE_INLINE int rs8_bits(rs_i8 m) { return (int)rs8_mask_bits(m); }
#endif
RS_LANE_INLINE void rs8_store(rs_f8 a, float* p) { vstore8(a, 0, p); }
RS_LANE_INLINE rs_f8 rs8_load(const float* p) { return vload8(0, p); }
RS_LANE_INLINE rs_i8 rs8_splati(int x) { return (int8)(x); }
RS_LANE_INLINE void rs8_storei(rs_i8 a, int* p) { vstore8(a, 0, p); }
#else
/* 16-byte aligned, not 32 as float8: a 32-byte-aligned struct passed by value has another x86-64
 * calling convention with and without AVX (GCC's -Wpsabi note on every operator). The layouts
 * holding these (RsWide8Node, RsTriPacket8) are the same, every field being a multiple of 32 bytes. */
typedef struct alignas(16) rs_f8 {
  float s[8];
} rs_f8;
typedef struct alignas(16) rs_i8 {
  rs_i32 s[8];
} rs_i8;
#define RS8_COMPARE(op)                  \
  RS_LANES_COMPARE(rs_f8, rs_i8, 8, op) \
  RS_LANE_INLINE rs_i8 operator op(rs_f8 a, float b) { return a op rs8_splat(b); }
RS_LANE_INLINE rs_f8 rs8_splat(float x) { return rs_f8{{x, x, x, x, x, x, x, x}}; }
RS_LANES_BINARY(rs_f8, rs_f8, 8, +)
RS_LANES_BINARY(rs_f8, rs_f8, 8, -)
RS_LANES_BINARY(rs_f8, rs_f8, 8, *)
RS_LANES_BINARY(rs_f8, rs_f8, 8, /)
RS_LANES_BINARY(rs_i8, rs_i8, 8, &)
RS_LANES_BINARY(rs_i8, rs_i8, 8, |)
RS8_COMPARE(<)
RS8_COMPARE(>)
RS8_COMPARE(<=)
RS8_COMPARE(>=)
RS8_COMPARE(==)
RS8_COMPARE(!=)
#undef RS8_COMPARE
RS_LANE_INLINE rs_f8 operator*(rs_f8 a, float b) { return a * rs8_splat(b); }
RS_LANE_INLINE rs_f8 operator*(float a, rs_f8 b) { return rs8_splat(a) * b; }
RS_LANE_INLINE rs_f8 operator-(rs_f8 a, float b) { return a - rs8_splat(b); }
RS_LANE_INLINE rs_f8 operator-(float a, rs_f8 b) { return rs8_splat(a) - b; }
RS_LANE_INLINE rs_f8 rs8_select(rs_f8 if_false, rs_f8 if_true, rs_i8 m) {
  rs_f8 r;
  for (int i = 0; i < 8; ++i) r.s[i] = m.s[i] < 0 ? if_true.s[i] : if_false.s[i];
  return r;
}
RS_LANE_INLINE rs_f8 rs8_fma(rs_f8 a, rs_f8 b, rs_f8 c) {
  rs_f8 r;
  for (int i = 0; i < 8; ++i) r.s[i] = rs_fma(a.s[i], b.s[i], c.s[i]);
  return r;
}
RS_LANE_INLINE rs_f8 rs8_min(rs_f8 a, rs_f8 b) { return rs8_select(b, a, a < b); }
RS_LANE_INLINE rs_f8 rs8_max(rs_f8 a, rs_f8 b) { return rs8_select(b, a, a > b); }
RS_LANE_INLINE int rs8_bits(rs_i8 m) {
  int b = 0;
  for (int i = 0; i < 8; ++i) b |= (m.s[i] & 1) << i;
  return b;
}
RS_LANE_INLINE void rs8_store(rs_f8 a, float* p) {
  for (int i = 0; i < 8; ++i) p[i] = a.s[i];
}
RS_LANE_INLINE rs_f8 rs8_load(const float* p) {
  rs_f8 r;
  for (int i = 0; i < 8; ++i) r.s[i] = p[i];
  return r;
}
RS_LANE_INLINE rs_i8 rs8_splati(int x) { return rs_i8{{x, x, x, x, x, x, x, x}}; }
RS_LANE_INLINE void rs8_storei(rs_i8 a, int* p) {
  for (int i = 0; i < 8; ++i) p[i] = a.s[i];
}
#undef RS_LANES_BINARY
#undef RS_LANES_COMPARE
#endif

/* |x| per lane, as rs4_abs. */
RS_LANE_INLINE rs_f8 rs8_abs(rs_f8 x) { return rs8_max(x, 0.0f - x); }

/* ---------------------------------------------------------------------------------------------
 * Lanes of any width for the host twin of the packet traversal (traverse_packet.h, whose width
 * RS_PACKET_W is 4, 8 or 16 per kernel build; packet_lanes.h names the width's types). The device
 * uses OpenCL's floatN/intN; the host these templates, per-lane IEEE operations in the same order,
 * so host and kernel give the same bits. Comparisons give -1 / 0 per lane, as OpenCL's do.
 * ------------------------------------------------------------------------------------------- */
#ifndef __OPENCL_VERSION__
template <int N>
struct alignas(16) rs_lanes_f {
  float s[N];
};
template <int N>
struct alignas(16) rs_lanes_i {
  rs_i32 s[N];
};
#define RS_LANES_T_BINARY(T, op)                            \
  template <int N>                                          \
  RS_LANE_INLINE T<N> operator op(T<N> a, T<N> b) {              \
    T<N> r;                                                 \
    for (int i = 0; i < N; ++i) r.s[i] = a.s[i] op b.s[i];  \
    return r;                                               \
  }
#define RS_LANES_T_COMPARE(T, op)                                       \
  template <int N>                                                      \
  RS_LANE_INLINE rs_lanes_i<N> operator op(T<N> a, T<N> b) {                 \
    rs_lanes_i<N> r;                                                    \
    for (int i = 0; i < N; ++i) r.s[i] = a.s[i] op b.s[i] ? -1 : 0;     \
    return r;                                                           \
  }
RS_LANES_T_BINARY(rs_lanes_f, +)
RS_LANES_T_BINARY(rs_lanes_f, -)
RS_LANES_T_BINARY(rs_lanes_f, *)
RS_LANES_T_BINARY(rs_lanes_f, /)
RS_LANES_T_BINARY(rs_lanes_i, &)
RS_LANES_T_BINARY(rs_lanes_i, |)
RS_LANES_T_BINARY(rs_lanes_i, -)
RS_LANES_T_COMPARE(rs_lanes_f, <)
RS_LANES_T_COMPARE(rs_lanes_f, >)
RS_LANES_T_COMPARE(rs_lanes_f, <=)
RS_LANES_T_COMPARE(rs_lanes_f, >=)
RS_LANES_T_COMPARE(rs_lanes_f, ==)
RS_LANES_T_COMPARE(rs_lanes_f, !=)
RS_LANES_T_COMPARE(rs_lanes_i, ==)
RS_LANES_T_COMPARE(rs_lanes_i, !=)
#undef RS_LANES_T_BINARY
#undef RS_LANES_T_COMPARE
/* A scalar on either side is splatted first, as OpenCL does (same bits). */
template <int N>
RS_LANE_INLINE rs_lanes_f<N> rs_lanes_splat(float x) {
  rs_lanes_f<N> r;
  for (int i = 0; i < N; ++i) r.s[i] = x;
  return r;
}
template <int N>
RS_LANE_INLINE rs_lanes_f<N> operator*(float a, rs_lanes_f<N> b) {
  return rs_lanes_splat<N>(a) * b;
}
template <int N>
RS_LANE_INLINE rs_lanes_f<N> operator*(rs_lanes_f<N> a, float b) {
  return a * rs_lanes_splat<N>(b);
}
template <int N>
RS_LANE_INLINE rs_lanes_f<N> operator+(rs_lanes_f<N> a, float b) {
  return a + rs_lanes_splat<N>(b);
}
template <int N>
RS_LANE_INLINE rs_lanes_f<N> operator-(float a, rs_lanes_f<N> b) {
  return rs_lanes_splat<N>(a) - b;
}
template <int N>
RS_LANE_INLINE rs_lanes_f<N> operator/(rs_lanes_f<N> a, float b) {
  return a / rs_lanes_splat<N>(b);
}
template <int N>
RS_LANE_INLINE rs_lanes_i<N> operator~(rs_lanes_i<N> a) {
  rs_lanes_i<N> r;
  for (int i = 0; i < N; ++i) r.s[i] = ~a.s[i];
  return r;
}
#endif

#endif /* RAYSORT_LANES_H */
