// The arithmetic in cl/shared.h and cl/sampling.h that host and kernels share: RNG, sin/cos, ray offsets.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "sampling.h"
#include "shared.h"

namespace raysort {

TEST(SharedMath, SinCosWithinStatedError) {
  double worst = 0.0;
  for (int i = 0; i < 100000; ++i) {
    float u = static_cast<float>(i) / 100000.0f;
    float s, c;
    rs_sincos_2pi(u, &s, &c);
    double a = 2.0 * M_PI * u;
    worst = std::max({worst, std::abs(s - std::sin(a)), std::abs(c - std::cos(a))});
  }
  EXPECT_LT(worst, 4e-7);
}

TEST(SharedMath, UniformIsInUnitIntervalAndVaries) {
  std::set<rs_u32> seen;
  for (rs_u32 p = 0; p < 1000; ++p) {
    rs_u32 h = rs_hash4(1, p, 0, RS_DIM(0, 0));
    float u = rs_uniform(h);
    EXPECT_GE(u, 0.0f);
    EXPECT_LT(u, 1.0f);
    seen.insert(h);
  }
  EXPECT_GT(seen.size(), 995u);
  EXPECT_EQ(rs_uniform(0xFFFFFFFFu), 16777215.0f / 16777216.0f);
  // Same counters, same value (the point of a counter-based RNG).
  EXPECT_EQ(rs_hash4(7, 11, 13, RS_DIM(2, 3)), rs_hash4(7, 11, 13, RS_DIM(2, 3)));
  EXPECT_NE(rs_hash4(7, 11, 13, RS_DIM(2, 3)), rs_hash4(7, 11, 13, RS_DIM(3, 2)));
}

TEST(SharedMath, CosineDirectionsAreUnitAndAboveTheSurface) {
  RsVec3 normals[] = {rs_vec3(0, 0, 1), rs_vec3(0, 0, -1), rs_vec3(1, 0, 0), rs_normalize(rs_vec3(1, -2, 3))};
  for (auto n : normals)
    for (int i = 0; i < 1000; ++i) {
      RsVec3 d = rs_cosine_direction(n, rs_uniform(rs_hash4(1, i, 0, 0)), rs_uniform(rs_hash4(1, i, 0, 1)));
      EXPECT_NEAR(rs_dot(d, d), 1.0f, 1e-5f);
      EXPECT_GE(rs_dot(d, n), -1e-6f);
    }
}

TEST(SharedMath, OffsetMovesAlongTheNormalAtAnyScale) {
  for (float scale : {1e-4f, 1.0f, 1e4f, 1e5f}) {
    RsVec3 p = rs_vec3(0.3f * scale, -0.7f * scale, 0.1f * scale);
    RsVec3 n = rs_normalize(rs_vec3(0.2f, 1.0f, -0.3f));
    RsVec3 q = rs_offset_ray_origin(p, n);
    RsVec3 moved = rs_sub(q, p);
    EXPECT_GT(rs_dot(moved, n), 0.0f) << "scale " << scale;
    // The offset is tiny relative to the coordinates' magnitude.
    EXPECT_LT(std::sqrt(rs_dot(moved, moved)), 1e-3f * std::max(1.0f, scale)) << "scale " << scale;
  }
}

}  // namespace raysort
