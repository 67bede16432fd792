// The arithmetic in cl/shared.h and cl/sampling.h that host and kernels share: RNG, sin/cos, ray
// offsets; and the packet traversal's per-lane ray set-up against the single-ray one (intersect.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "intersect.h"
#include "lanes.h"
#include "sampling.h"
#include "shared.h"
#include "traverse_wide.h"

namespace raysort {

// traverse_packet.h at the widest packet, in a namespace of its own as in host/trace/packet_twin.cpp.
namespace setup16 {
#define RS_PACKET_W 16
#include "traverse_packet.h"
#undef RS_PACKET_W
}  // namespace setup16

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

// The robust packet kernels set up all sixteen lanes at once (rs_packet_prepare_robust); each lane
// must get exactly the bits rs_prepare_robust_ray gives its ray alone: 1/d and the parallel axes,
// the ray-space axes kx, ky, kz (as selectors), the permuted origin, the shear, and whether the
// direction is valid. Directions from components that make every branch matter: zeros of both
// signs, components under the parallel threshold, denormals, huge and infinite ones, NaN, ties.
TEST(SharedMath, PacketRaySetUpEqualsTheSingleRaySetUpInEveryLane) {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> special{0.0f,  -0.0f, 1.0f,   -1.0f,  0.5f,    -0.5f, 1e-21f, -1e-21f, 1e-30f,
                                   1e-40f, -1e-40f, 3e38f, -3e38f, 3.4028235e38f, inf, -inf,   nan,   2.0f};
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::size_t> pick(0, special.size() + 3);
  std::uniform_real_distribution<float> any(-2.0f, 2.0f);
  auto component = [&] {
    const std::size_t k = pick(rng);
    return k < special.size() ? special[k] : any(rng);  // a random value a quarter of the time
  };
  auto bits = [](float x) {
    std::uint32_t b;
    std::memcpy(&b, &x, 4);
    return b;
  };
  int compared = 0;
  for (int round = 0; round < 4000; ++round) {
    std::vector<RsRay> rays(16);
    std::vector<rs_u32> order(16);
    for (rs_u32 i = 0; i < 16; ++i) {
      rays[i] = RsRay{{any(rng), any(rng), any(rng)}, 0.0f, {component(), component(), component()}, 100.0f};
      order[i] = 15 - i;  // through an order, as the kernels load
    }
    setup16::RsRayPacket p;
    setup16::rs_pf tmax;
    RsRay lane_rays[16];
    const rs_u32 count = round % 5 == 0 ? 11u : 16u;  // some packets end early
    const int active = setup16::rs_packet_load(rays.data(), order.data(), 0, count, 1, lane_rays, &p, &tmax);
    int any_parallel = 0;
    for (int i = 0; i < 16; ++i) {
      const RsRay ray = i < static_cast<int>(count) ? rays[order[i]] : lane_rays[i];
      const RsRobustRay r = rs_prepare_robust_ray(ray);
      const bool in_range = i < static_cast<int>(count);
      SCOPED_TRACE(::testing::Message() << "round " << round << " lane " << i << " d = (" << ray.d[0] << ", "
                                        << ray.d[1] << ", " << ray.d[2] << ")");
      ASSERT_EQ((active >> i) & 1, in_range && r.valid ? 1 : 0);
      const float inv[3] = {p.ix.s[i], p.iy.s[i], p.iz.s[i]};
      const int par[3] = {p.par_x.s[i], p.par_y.s[i], p.par_z.s[i]};
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(bits(inv[a]), bits(r.inv_d[a])) << "axis " << a;
        ASSERT_EQ(par[a] != 0, r.parallel[a] != 0) << "axis " << a;
      }
      ASSERT_EQ(p.kx1.s[i] != 0, r.kx == 1);
      ASSERT_EQ(p.kx2.s[i] != 0, r.kx == 2);
      ASSERT_EQ(p.ky1.s[i] != 0, r.ky == 1);
      ASSERT_EQ(p.ky2.s[i] != 0, r.ky == 2);
      ASSERT_EQ(p.kz1.s[i] != 0, r.kz == 1);
      ASSERT_EQ(p.kz2.s[i] != 0, r.kz == 2);
      ASSERT_EQ(bits(p.okx.s[i]), bits(r.okx));
      ASSERT_EQ(bits(p.oky.s[i]), bits(r.oky));
      ASSERT_EQ(bits(p.okz.s[i]), bits(r.okz));
      ASSERT_EQ(bits(p.sx.s[i]), bits(r.sx));
      ASSERT_EQ(bits(p.sy.s[i]), bits(r.sy));
      ASSERT_EQ(bits(p.sz.s[i]), bits(r.sz));
      if (in_range && r.valid && !r.oblique) any_parallel = 1;
      ++compared;
    }
    ASSERT_EQ(p.any_parallel, any_parallel) << "round " << round;
  }
  EXPECT_EQ(compared, 4000 * 16);
}

}  // namespace raysort
