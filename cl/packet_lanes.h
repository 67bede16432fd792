/* raysort — the lane types of a ray packet of RS_PACKET_W rays (4, 8 or 16), one ray per lane
 * (traverse_packet.h). On the device OpenCL's floatN/intN, which PoCL maps to SSE, AVX or AVX-512
 * registers (float16 is one zmm register); on the host the rs_lanes_f/rs_lanes_i templates of
 * lanes.h, per-lane IEEE operations, so the host twin gives the kernel's bits.
 *
 * No include guard: the host twin includes traverse_packet.h (and so this file) once per width,
 * each time inside a namespace of its own (host/trace/packet_twin.cpp); a kernel build includes it
 * once, with the width its build options name (-DRS_TRACE_PACKET=W, host/trace/tracer.cpp).
 */
#ifndef RS_PACKET_W
#error "define RS_PACKET_W (4, 8 or 16) before including packet_lanes.h"
#endif
#if RS_PACKET_W != 4 && RS_PACKET_W != 8 && RS_PACKET_W != 16
#error "RS_PACKET_W must be 4, 8 or 16"
#endif

#define RS_PACKET_CAT_(a, b) a##b
#define RS_PACKET_CAT(a, b) RS_PACKET_CAT_(a, b)

#ifdef __OPENCL_VERSION__
typedef RS_PACKET_CAT(float, RS_PACKET_W) rs_pf;
typedef RS_PACKET_CAT(int, RS_PACKET_W) rs_pi;
RS_LANE_INLINE rs_pf rsp_splat(float x) { return (rs_pf)(x); }
RS_LANE_INLINE rs_pi rsp_splati(int x) { return (rs_pi)(x); }
RS_LANE_INLINE rs_pf rsp_select(rs_pf if_false, rs_pf if_true, rs_pi m) { return select(if_false, if_true, m); }
RS_LANE_INLINE rs_pi rsp_selecti(rs_pi if_false, rs_pi if_true, rs_pi m) { return select(if_false, if_true, m); }
RS_LANE_INLINE rs_pf rsp_fma(rs_pf a, rs_pf b, rs_pf c) { return fma(a, b, c); }
RS_LANE_INLINE rs_pf rsp_neg(rs_pf a) { return -a; }
RS_LANE_INLINE rs_pf rsp_load(const float* p) { return RS_PACKET_CAT(vload, RS_PACKET_W)(0, p); }
RS_LANE_INLINE rs_pi rsp_loadi(const int* p) { return RS_PACKET_CAT(vload, RS_PACKET_W)(0, p); }
RS_LANE_INLINE void rsp_store(rs_pf a, float* p) { RS_PACKET_CAT(vstore, RS_PACKET_W)(a, 0, p); }
RS_LANE_INLINE void rsp_storei(rs_pi a, int* p) { RS_PACKET_CAT(vstore, RS_PACKET_W)(a, 0, p); }
/* a's bits as integers, lane by lane. */
RS_LANE_INLINE rs_pi rsp_as_int(rs_pf a) { return RS_PACKET_CAT(as_int, RS_PACKET_W)(a); }
/* Lane i of a: a permute and a move (vpermd on x86), where a store and a load through private memory
 * took 4-5 % more of packet16's time on sibenik's primary rays (results/history/trace-kernels.md). */
RS_LANE_INLINE float rsp_lane(rs_pf a, int i) { return shuffle(a, (RS_PACKET_CAT(uint, RS_PACKET_W))((uint)i)).s0; }
/* The lanes of a -1/0 mask as bits, lane i -> bit i: one movmskps / vmovmskps / kmov on x86 (the
 * forms of lanes.h), the portable AND-and-OR elsewhere. */
#if RS_PACKET_W == 4
RS_LANE_INLINE int rsp_bits(rs_pi m) { return rs4_bits(m); }
RS_LANE_INLINE rs_pi rsp_lane_bits(void) { return (int4)(1, 2, 4, 8); }
#elif RS_PACKET_W == 8
RS_LANE_INLINE int rsp_bits(rs_pi m) { return (int)rs8_mask_bits(m); }
RS_LANE_INLINE rs_pi rsp_lane_bits(void) { return (int8)(1, 2, 4, 8, 16, 32, 64, 128); }
#else
RS_LANE_INLINE int rsp_bits(rs_pi m) { return (int)rs16_mask_bits(m); }
RS_LANE_INLINE rs_pi rsp_lane_bits(void) {
  return (int16)(1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384, 32768);
}
#endif
/* The largest and the smallest lane of a, by halves (the selects of rsp_max and rsp_min, exact, so
 * the host's loop gives the same value). */
RS_LANE_INLINE float rsp_max_lane(rs_pf a) {
#if RS_PACKET_W == 16
  const float8 m8 = select(a.hi, a.lo, a.lo > a.hi);
  const float4 m4 = select(m8.hi, m8.lo, m8.lo > m8.hi);
#elif RS_PACKET_W == 8
  const float4 m4 = select(a.hi, a.lo, a.lo > a.hi);
#else
  const float4 m4 = a;
#endif
  const float2 m2 = select(m4.hi, m4.lo, m4.lo > m4.hi);
  return m2.s0 > m2.s1 ? m2.s0 : m2.s1;
}
RS_LANE_INLINE float rsp_min_lane(rs_pf a) {
#if RS_PACKET_W == 16
  const float8 m8 = select(a.hi, a.lo, a.lo < a.hi);
  const float4 m4 = select(m8.hi, m8.lo, m8.lo < m8.hi);
#elif RS_PACKET_W == 8
  const float4 m4 = select(a.hi, a.lo, a.lo < a.hi);
#else
  const float4 m4 = a;
#endif
  const float2 m2 = select(m4.hi, m4.lo, m4.lo < m4.hi);
  return m2.s0 < m2.s1 ? m2.s0 : m2.s1;
}
#else
typedef rs_lanes_f<RS_PACKET_W> rs_pf;
typedef rs_lanes_i<RS_PACKET_W> rs_pi;
RS_LANE_INLINE rs_pf rsp_splat(float x) { return rs_lanes_splat<RS_PACKET_W>(x); }
RS_LANE_INLINE rs_pi rsp_splati(int x) {
  rs_pi r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = x;
  return r;
}
RS_LANE_INLINE rs_pf rsp_select(rs_pf if_false, rs_pf if_true, rs_pi m) {
  rs_pf r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = m.s[i] < 0 ? if_true.s[i] : if_false.s[i];
  return r;
}
RS_LANE_INLINE rs_pi rsp_selecti(rs_pi if_false, rs_pi if_true, rs_pi m) {
  rs_pi r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = m.s[i] < 0 ? if_true.s[i] : if_false.s[i];
  return r;
}
RS_LANE_INLINE rs_pf rsp_fma(rs_pf a, rs_pf b, rs_pf c) {
  rs_pf r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = rs_fma(a.s[i], b.s[i], c.s[i]);
  return r;
}
RS_LANE_INLINE rs_pf rsp_neg(rs_pf a) {
  rs_pf r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = -a.s[i];
  return r;
}
RS_LANE_INLINE rs_pf rsp_load(const float* p) {
  rs_pf r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = p[i];
  return r;
}
RS_LANE_INLINE rs_pi rsp_loadi(const int* p) {
  rs_pi r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = p[i];
  return r;
}
RS_LANE_INLINE void rsp_store(rs_pf a, float* p) {
  for (int i = 0; i < RS_PACKET_W; ++i) p[i] = a.s[i];
}
RS_LANE_INLINE void rsp_storei(rs_pi a, int* p) {
  for (int i = 0; i < RS_PACKET_W; ++i) p[i] = a.s[i];
}
RS_LANE_INLINE float rsp_lane(rs_pf a, int i) { return a.s[i]; }
RS_LANE_INLINE rs_pi rsp_as_int(rs_pf a) {
  rs_pi r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = rs_float_as_int(a.s[i]);
  return r;
}
RS_LANE_INLINE float rsp_max_lane(rs_pf a) {
  float m = a.s[0];
  for (int i = 1; i < RS_PACKET_W; ++i) m = a.s[i] > m ? a.s[i] : m;
  return m;
}
RS_LANE_INLINE float rsp_min_lane(rs_pf a) {
  float m = a.s[0];
  for (int i = 1; i < RS_PACKET_W; ++i) m = a.s[i] < m ? a.s[i] : m;
  return m;
}
RS_LANE_INLINE int rsp_bits(rs_pi m) {
  int b = 0;
  for (int i = 0; i < RS_PACKET_W; ++i) b |= (m.s[i] & 1) << i;
  return b;
}
RS_LANE_INLINE rs_pi rsp_lane_bits(void) {
  rs_pi r;
  for (int i = 0; i < RS_PACKET_W; ++i) r.s[i] = 1 << i;
  return r;
}
#endif

/* rs_popcount: lanes.h. */

/* min/max as selects, as rs4_min/rs4_max (lanes.h): the same bits on both sides. */
RS_LANE_INLINE rs_pf rsp_min(rs_pf a, rs_pf b) { return rsp_select(b, a, a < b); }
RS_LANE_INLINE rs_pf rsp_max(rs_pf a, rs_pf b) { return rsp_select(b, a, a > b); }
RS_LANE_INLINE rs_pf rsp_abs(rs_pf x) { return rsp_max(x, rsp_splat(0.0f) - x); }
/* Bits -> a -1/0 lane mask (the inverse of rsp_bits). */
RS_LANE_INLINE rs_pi rsp_mask(int bits) { return (rsp_splati(bits) & rsp_lane_bits()) != rsp_splati(0); }
