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
#include "traverse_stream.h"
#include "traverse_wide8.h"

namespace raysort {

// traverse_packet.h and traverse_coherent.h at the widest packet, in a namespace of their own as in
// host/trace/packet_twin.cpp.
namespace setup16 {
#define RS_PACKET_W 16
#include "traverse_packet.h"
#include "traverse_coherent.h"
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

// The coherent packets' frustum (cl/traverse_coherent.h) admits every child of an 8-wide node that
// some active lane's own slab test enters (rs_packet_box_unfused, rs_packet_box_robust, with the lane's
// closest hit so far as the far bound), and its entry bound for that child is at most the lane's
// entry distance: what lets it skip children, and lets a one-origin packet go by the frustum alone
// (its pushed entries carry that bound, and a lane is dropped at a pop only when its closest hit is
// nearer). Packets of one octant, with one origin or origins up to far apart; boxes random, flat,
// on the origin's planes, huge and tiny; directions with zero (of the octant's sign), tiny, huge and
// ordinary components; tmin 0 or not; closest hits near, far or 1e30. Both variants.
TEST(SharedMath, PacketFrustumAdmitsEveryChildALaneEnters) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), pos(0.05f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 7);
  // The robust variant calls a component below 1e-20 of the largest parallel (RS_PARALLEL_FRACTION),
  // and a packet with a parallel lane gets no frustum: its small components stay above that.
  const float magnitudes[2][5] = {{0.0f, 1e-36f, 1e-20f, 1e-6f, 1e20f}, {1e-18f, 1e-9f, 1e-6f, 1e-3f, 10.0f}};
  const float coordinates[] = {0.0f, -0.0f, 1e-30f, -1e-30f, 1e30f, -1e30f, 3e38f, -3e38f};
  long entered = 0, admitted_only = 0, lanes_checked = 0;
  int refused = 0, one_origin = 0;
  for (int round = 0; round < 20000; ++round) {
    const int robust = round & 1, octant = pick(rng);
    const bool shared_origin = (round & 2) != 0;
    const float spread = (round & 4) ? 0.01f : 3.0f;
    float o0[3];
    for (float& c : o0) c = pick(rng) == 0 ? coordinates[pick(rng)] : 2.0f * unit(rng);
    std::vector<RsRay> rays(16);
    std::vector<rs_u32> order(16);
    for (rs_u32 i = 0; i < 16; ++i) {
      RsRay& r = rays[i];
      for (int a = 0; a < 3; ++a) {
        r.o[a] = shared_origin ? o0[a] : o0[a] + spread * unit(rng);
        const int k = pick(rng);
        const float m = k < 5 ? magnitudes[robust][k] : pos(rng);
        r.d[a] = ((octant >> a) & 1) ? -m : m;  // -0 on a negative axis: 1/d keeps the octant's sign
      }
      r.tmin = pick(rng) == 0 ? 1e-3f : 0.0f;
      r.tmax = pick(rng) == 0 ? 1e30f : 10.0f * pos(rng);
      order[i] = i;
    }
    if (robust && round % 20 == 1) rays[3].d[1] = 0.0f;  // a parallel lane: no frustum
    setup16::RsRayPacket p;
    setup16::rs_pf tmax;
    RsRay lane_rays[16];
    const rs_u32 count = round % 7 == 0 ? 9u : 16u;
    const int live = setup16::rs_packet_load(rays.data(), order.data(), 0, count, robust, lane_rays, &p, &tmax);
    if (!live) continue;
    // Closest hits so far: the lane's tmax, or nearer.
    setup16::rs_pf hit_t = tmax;
    for (int i = 0; i < 16; ++i)
      if (pick(rng) < 3) hit_t.s[i] = tmax.s[i] * pos(rng);
    setup16::RsPacketFrustum f;
    if (!setup16::rs_packet_frustum(&p, live, robust, hit_t, &f)) {
      ++refused;
      continue;
    }
    one_origin += f.one_origin;
    RsWide8Node node;
    float* b = reinterpret_cast<float*>(&node);  // lo_x hi_x lo_y hi_y lo_z hi_z, eight each
    rs_i32* valid = reinterpret_cast<rs_i32*>(&node.valid);
    for (int c = 0; c < 8; ++c) {
      valid[c] = pick(rng) == 0 ? 0 : -1;
      node.child[c] = static_cast<rs_u32>(c);
      for (int a = 0; a < 3; ++a) {
        float lo, hi;
        switch (pick(rng)) {
          case 0: lo = hi = o0[a] + unit(rng); break;                     // flat
          case 1: lo = o0[a], hi = o0[a] + pos(rng); break;               // on the origin's plane
          case 2: lo = o0[a] - pos(rng), hi = o0[a]; break;
          case 3: lo = -1e30f, hi = 1e30f * pos(rng); break;              // huge
          case 4: lo = o0[a] + 1e-30f * unit(rng), hi = lo + 1e-30f; break;  // tiny
          default: {
            const float x = o0[a] + 4.0f * unit(rng), y = o0[a] + 4.0f * unit(rng);
            lo = std::min(x, y), hi = std::max(x, y);
          }
        }
        b[16 * a + c] = lo, b[16 * a + 8 + c] = hi;
      }
    }
    float fnear[8];
    const int admitted = setup16::rs_packet_frustum_children(&f, &node, robust, fnear);
    for (int c = 0; c < 8; ++c) {
      if (!valid[c]) {
        ASSERT_FALSE((admitted >> c) & 1) << "round " << round << ": an empty slot admitted";
        continue;
      }
      setup16::rs_pf tn;
      const setup16::rs_pi m =
          robust ? setup16::rs_packet_box_robust(&p, b[c], b[8 + c], b[16 + c], b[24 + c], b[32 + c], b[40 + c], hit_t, &tn)
                 : setup16::rs_packet_box_unfused(&p, b[c], b[8 + c], b[16 + c], b[24 + c], b[32 + c], b[40 + c], hit_t, &tn);
      const int lanes = setup16::rsp_bits(m) & live;
      if (!lanes) {
        admitted_only += (admitted >> c) & 1;
        continue;
      }
      ++entered;
      ASSERT_TRUE((admitted >> c) & 1) << "round " << round << " child " << c << ": lanes " << lanes
                                      << " enter it, the frustum (" << (robust ? "robust" : "fast") << ") refuses it";
      for (int i = 0; i < 16; ++i)
        if ((lanes >> i) & 1) {
          ASSERT_LE(fnear[c], tn.s[i]) << "round " << round << " child " << c << " lane " << i;
          ++lanes_checked;
        }
    }
  }
  std::printf("[ frustum  ] %ld children entered by a lane, all admitted (%ld lanes' entry distances above the bound); "
              "%ld admitted and entered by none; %d packets refused a frustum, %d of one origin\n",
              entered, lanes_checked, admitted_only, refused, one_origin);
  EXPECT_GT(entered, 10000);
  EXPECT_GT(one_origin, 2000);
  EXPECT_GE(refused, 500);  // every packet with a parallel lane, at least
  EXPECT_LT(refused, 2000);
}

// The stream's branch-free choice of a packet's nearest hit lane (traverse_stream.h) against the
// single-ray walk's scan (rs_wide8_keep_nearest): the same lane, t, u, v and answer on packets whose
// lanes tie often (t from five values, +0 and -0 among them), with the closest hit so far among them.
TEST(SharedMath, StreamKeepsTheNearestLaneAsTheScanDoes) {
  std::mt19937 rng(7);
  const float values[] = {0.0f, -0.0f, 0.5f, 1.0f, 2.0f};
  RsTriPacket8 p{};
  for (int i = 0; i < 8; ++i) p.id[i] = 100 + i;
  int kept = 0, ties = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    float t[8], u[8], v[8];
    for (int i = 0; i < 8; ++i) {
      t[i] = values[rng() % 5];
      u[i] = static_cast<float>(rng() % 1000) / 1000.0f;
      v[i] = static_cast<float>(rng() % 1000) / 1000.0f;
    }
    const int bits = static_cast<int>(rng() % 256);
    RsHit scan = rs_miss(rng() % 4 == 0 ? INFINITY : values[2 + rng() % 3]), branch_free = scan;
    const int a = rs_wide8_keep_nearest(bits, rs8_load(t), rs8_load(u), rs8_load(v), &p, &scan);
    const int b = rs_stream_keep_nearest(bits, rs8_load(t), rs8_load(u), rs8_load(v), &p, &branch_free);
    ASSERT_EQ(a, b) << "trial " << trial;
    ASSERT_EQ(std::memcmp(&scan, &branch_free, sizeof(RsHit)), 0) << "trial " << trial << ": triangle " << scan.tri
                                                                   << " against " << branch_free.tri;
    kept += a;
    int at_least = 0;
    for (int i = 0; i < 8; ++i) at_least += a && ((bits >> i) & 1) && t[i] == scan.t;
    ties += at_least > 1;
  }
  EXPECT_GT(kept, 5000);
  EXPECT_GT(ties, 1000) << "packets whose nearest t several lanes share";
}

}  // namespace raysort
