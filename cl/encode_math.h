/* raysort — atan2 and acos from + − × ÷ and sqrt only, shared by the encode kernels and their host
 * twin (docs/design.md, "Determinism": OpenCL's and libm's atan2/acos may differ by ulps, which would move a
 * ray across a direction cell boundary on one side only).
 *
 * Both are evaluated in single precision in a fixed order; FP contraction is off on both sides
 * (cl/shared.h, host -ffp-contract=off), so host and device give the same bits.
 */
#ifndef RAYSORT_ENCODE_MATH_H
#define RAYSORT_ENCODE_MATH_H

#include "shared.h"

#define RS_PI_F 3.14159265358979f
#define RS_INV_PI_F 0.318309886183791f
#define RS_INV_2PI_F 0.159154943091895f

/* atan(z) for z in [0, 1]: Cephes atanf (S. L. Moshier): one reduction by π/4 above tan(π/8),
 * then an odd polynomial in z² on [0, tan(π/8)]. Absolute error ≈ 1e-7. */
RS_INLINE float rs_atan_unit(float z) {
  float base = 0.0f;
  if (z > 0.414213562373095f) {
    base = 0.785398163397448f;
    z = (z - 1.0f) / (z + 1.0f);
  }
  float z2 = z * z;
  float p = ((8.05374449538e-2f * z2 - 1.38776856032e-1f) * z2 + 1.99777106478e-1f) * z2 - 3.33329491539e-1f;
  return base + (p * z2 * z + z);
}

/* atan2(y, x) in [−π, π]. Signs are read with < 0, so −0 counts as +0: directions with a −0
 * component get the same angle (and key) as with +0. atan2(0, 0) = 0.
 * |y| is written (y < 0 ? −y : y), not fabs: with fabs on both, the x and y chains are identical
 * and PoCL's SLP pass packs them into a 2-lane vector, which keeps its work-group vectoriser from
 * running the encode kernels 8 rays at a time (3x slower). The value differs only for y = −0,
 * which gives the same result bits (tests/encode_test.cpp checks against the fabs form). */
RS_INLINE float rs_atan2(float y, float x) {
  float ax = rs_abs(x), ay = y < 0.0f ? -y : y;
  float hi = rs_max(ax, ay), lo = rs_min(ax, ay);
  if (hi == 0.0f) return 0.0f;
  float a = rs_atan_unit(lo / hi);
  if (ay > ax) a = 1.57079632679490f - a;
  if (x < 0.0f) a = RS_PI_F - a;
  return y < 0.0f ? -a : a;
}

/* acos(x) for x in [−1, 1] (clamped): Abramowitz & Stegun 4.4.46, acos(x) = sqrt(1 − x)·P7(x) on
 * [0, 1] (|error| ≤ 2e-8 in exact arithmetic), and acos(−x) = π − acos(x). */
RS_INLINE float rs_acos(float x) {
  x = rs_min(1.0f, rs_max(-1.0f, x));
  float ax = rs_abs(x);
  float p = -0.0012624911f;
  p = p * ax + 0.0066700901f;
  p = p * ax - 0.0170881256f;
  p = p * ax + 0.0308918810f;
  p = p * ax - 0.0501743046f;
  p = p * ax + 0.0889789874f;
  p = p * ax - 0.2145988016f;
  p = p * ax + 1.5707963050f;
  float r = rs_sqrt(1.0f - ax) * p;
  return x < 0.0f ? RS_PI_F - r : r;
}

#endif /* RAYSORT_ENCODE_MATH_H */
