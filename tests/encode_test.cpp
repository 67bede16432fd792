// Encoders: kernel keys equal host keys bit for bit (every encoder × 16/32/64 bits, every batch of
// two procedural scenes), hand-computed keys on a tiny scene, and the numerical hard cases of
// issue 3 (signed zeros, acos domain, box faces and corner, clamping, rays inside cut nodes,
// rays that miss everything, a single-leaf BVH, a flat scene, 1e6 and 1e-4 scene scales).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>

#include "bvh/prepared_scene.h"
#include "encode/encode.h"
#include "render/batches.h"
#include "scene/load.h"
#include "test_util.h"
#include "trace/tracer.h"

namespace raysort {

namespace {

const unsigned kBits[] = {16, 32, 64};

using testing::ray;

Aabb unit_box() { return Aabb{{0, 0, 0}, {1, 1, 1}}; }

// A hand-made BVH over four flat triangles in z-planes (leaf boxes have zero z extent):
//   node 0 root, children 1 (T0, T1) and 2 (T2, T3); leaves 3 = T0, 4 = T1, 5 = T2, 6 = T3.
//   T0 x,y ∈ [0, .4]² z = .1     T1 x ∈ [.6, .9], y ∈ [0, .3] z = .2
//   T2 x ∈ [0, .2], y ∈ [.6, .8] z = .3    T3 x,y ∈ [.6, .7]² z = .4
// HAD (λ = 1/8): leaves .32 .18 .08 .02; node 1: .5 + .98/8 = .6225; node 2: .1 + .46/8 = .1575.
Bvh four_leaf_bvh() {
  Bvh b;
  auto tri = [](float x0, float y0, float x1, float y1, float x2, float y2, float z, rs_u32 id) {
    RsTriangle t{};
    t.v0[0] = x0, t.v0[1] = y0, t.v0[2] = z;
    t.v1[0] = x1, t.v1[1] = y1, t.v1[2] = z;
    t.v2[0] = x2, t.v2[1] = y2, t.v2[2] = z;
    t.id = id;
    return t;
  };
  b.triangles = {tri(0, 0, .4f, 0, 0, .4f, .1f, 0), tri(.6f, 0, .9f, 0, .6f, .3f, .2f, 1),
                 tri(0, .6f, .2f, .6f, 0, .8f, .3f, 2), tri(.6f, .6f, .7f, .6f, .7f, .7f, .4f, 3)};
  auto node = [](float x0, float y0, float z0, float x1, float y1, float z1, rs_u32 first, rs_u32 count) {
    RsBvhNode n{};
    n.bmin[0] = x0, n.bmin[1] = y0, n.bmin[2] = z0, n.first = first;
    n.bmax[0] = x1, n.bmax[1] = y1, n.bmax[2] = z1, n.count = count;
    return n;
  };
  b.nodes = {node(0, 0, .1f, .9f, .8f, .4f, 1, 0),     node(0, 0, .1f, .9f, .4f, .2f, 3, 0),
             node(0, .6f, .3f, .7f, .8f, .4f, 5, 0),   node(0, 0, .1f, .4f, .4f, .1f, 0, 1),
             node(.6f, 0, .2f, .9f, .3f, .2f, 1, 1),   node(0, .6f, .3f, .2f, .8f, .3f, 2, 1),
             node(.6f, .6f, .4f, .7f, .7f, .4f, 3, 1)};
  b.depth = 2;
  b.leaf_count = 4;
  return b;
}

// Kernel keys and values against the host twin, bit for bit; keys fit in `bits`.
void expect_device_equals_host(DeviceEncoder& dev, Encoder e, unsigned bits, const std::vector<RsRay>& rays,
                               const std::string& what) {
  auto host = encode_on_host(e, bits, dev.scene(), rays);
  auto run = dev.run(e, bits, rays);
  ASSERT_EQ(run.keys.size(), rays.size());
  std::size_t bad = 0, first_bad = 0, overflow = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (run.keys[i] != host[i] && bad++ == 0) first_bad = i;
    if (bits < 64 && (host[i] >> bits) != 0) ++overflow;
  }
  EXPECT_EQ(bad, 0u) << what << " " << encoder_name(e) << "/" << bits << ": first mismatch at ray " << first_bad
                     << " device " << std::hex << run.keys[first_bad] << " host " << host[first_bad];
  EXPECT_EQ(overflow, 0u) << what << " " << encoder_name(e) << "/" << bits;
  for (std::size_t i = 0; i < run.values.size(); ++i) {
    if (run.values[i] != i) {
      ADD_FAILURE() << what << " " << encoder_name(e) << ": values[" << i << "] = " << run.values[i];
      break;
    }
  }
}

void expect_all_encoders_bit_exact(DeviceEncoder& dev, const std::vector<RsRay>& rays, const std::string& what) {
  for (Encoder e : all_encoders())
    for (unsigned bits : kBits) expect_device_equals_host(dev, e, bits, rays, what);
}

std::uint64_t key1(Encoder e, unsigned bits, const EncodeScene& s, const RsRay& r) {
  return encode_on_host(e, bits, s, {r})[0];
}

}  // namespace

TEST(EncodeMath, AtanAndAcosAreCloseToLibm) {
  double worst_atan = 0, worst_acos = 0;
  for (int i = -200; i <= 200; ++i)
    for (int j = -200; j <= 200; ++j) {
      const float y = i * 0.013f, x = j * 0.0171f;
      if (x == 0 && y == 0) continue;
      worst_atan = std::max(worst_atan, std::abs(static_cast<double>(rs_atan2(y, x)) - std::atan2(double(y), double(x))));
    }
  for (int i = -10000; i <= 10000; ++i) {
    const float x = i * 1e-4f;
    worst_acos = std::max(worst_acos, std::abs(static_cast<double>(rs_acos(x)) - std::acos(double(x))));
  }
  EXPECT_LT(worst_atan, 1e-6);
  EXPECT_LT(worst_acos, 1e-6);
  EXPECT_EQ(rs_acos(1.0f), 0.0f);
  EXPECT_EQ(rs_acos(1.5f), 0.0f);  // clamped
  EXPECT_NEAR(rs_acos(-1.0f), 3.14159265f, 1e-6f);
  EXPECT_EQ(rs_atan2(0.0f, 0.0f), 0.0f);
  EXPECT_EQ(rs_atan2(-0.0f, -1.0f), rs_atan2(0.0f, -1.0f));  // −0 counts as +0
}

// rs_atan2 reads |y| as (y < 0 ? −y : y), not fabs, so that PoCL's SLP pass does not pair the x
// and y chains into a 2-lane vector (which stops it vectorising the encode kernels across rays).
// The two differ only for y = −0 (−0 instead of +0), which must not change a single result bit:
// compare with the fabs formulation on special values and 2 M random bit patterns.
TEST(EncodeMath, Atan2BitsEqualTheFabsFormulation) {
  auto fabs_atan2 = [](float y, float x) {
    float ax = rs_abs(x), ay = rs_abs(y);
    float hi = rs_max(ax, ay), lo = rs_min(ax, ay);
    if (hi == 0.0f) return 0.0f;
    float a = rs_atan_unit(lo / hi);
    if (ay > ax) a = 1.57079632679490f - a;
    if (x < 0.0f) a = RS_PI_F - a;
    return y < 0.0f ? -a : a;
  };
  std::vector<float> values = {0.0f, -0.0f, 1e-45f, -1e-45f, 1e-38f, -1e-38f, 0.5f, -0.5f, 1.0f, -1.0f, 3e38f, -3e38f};
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint32_t> bits;
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (int i = 0; i < 1000; ++i) values.push_back(unit(rng));
  auto same = [&](float y, float x) {
    const float a = fabs_atan2(y, x), b = rs_atan2(y, x);
    return std::memcmp(&a, &b, sizeof a) == 0;
  };
  for (float y : values)
    for (float x : values) ASSERT_TRUE(same(y, x)) << "y=" << y << " x=" << x;
  for (int i = 0; i < 2000000; ++i) {
    std::uint32_t a = bits(rng), b = bits(rng);
    float y, x;
    std::memcpy(&y, &a, sizeof y);
    std::memcpy(&x, &b, sizeof x);
    if (std::isnan(y) || std::isnan(x)) continue;
    ASSERT_TRUE(same(y, x)) << "y=" << y << " x=" << x;
  }
}

// rs_scene_exit picks each axis's far plane by the sign of inv_d and writes one axis negated (to
// keep PoCL's SLP pass from packing the axes, cl/keys.h). It must give the value of the plain slab
// form, max of the two plane distances per axis and min over the axes (a zero's sign aside), for
// rays from inside, outside and on the box, with zero direction components and short segments.
TEST(EncodeMath, SceneExitEqualsTheMinMaxForm) {
  RsEncodeFrame f{};
  const float lo[3] = {-1.5f, 0.25f, -3.0f}, hi[3] = {2.0f, 0.25f, 1.0f};  // y is flat
  for (int a = 0; a < 3; ++a) {
    f.box_min[a] = lo[a], f.box_max[a] = hi[a];
    f.inv_extent[a] = hi[a] > lo[a] ? 1.0f / (hi[a] - lo[a]) : 0.0f;
  }
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-4.0f, 4.0f);
  for (int k = 0; k < 200000; ++k) {
    RsRay ray{};
    for (int a = 0; a < 3; ++a) {
      ray.o[a] = k % 13 == 0 ? (k % 2 ? lo[a] : hi[a]) : u(rng);
      ray.d[a] = k % 7 == a ? (k % 2 ? 0.0f : -0.0f) : u(rng);
    }
    ray.tmin = 0.0f;
    ray.tmax = k % 5 == 0 ? 0.5f : RS_T_FAR;
    const RsTraversalRay r = rs_prepare_ray(ray);
    float far = r.tmax;
    for (int a = 0; a < 3; ++a) {
      const float o = a == 0 ? r.o.x : a == 1 ? r.o.y : r.o.z, inv = a == 0 ? r.inv_d.x : a == 1 ? r.inv_d.y : r.inv_d.z;
      far = rs_min(far, rs_max((f.box_min[a] - o) * inv, (f.box_max[a] - o) * inv));
    }
    ASSERT_EQ(rs_scene_exit(&f, r), far) << "ray " << k;  // == treats -0 and +0 as equal
  }
}

// TwoPoint's scene exit prepares its ray with rs_exit_ray, a select where rs_safe_rcp moves the sign
// bit with integer operations (so PoCL vectorises the kernel, cl/keys.h). Every field must have
// rs_prepare_ray's bits (−(o · 1/d): its value, a NaN's payload aside): directions around the ±tiny
// threshold, ±0, denormals, ±inf, NaN, and random bit patterns.
TEST(EncodeMath, ExitRayIsThePreparedRay) {
  const auto bits = [](float x) { return std::bit_cast<std::uint32_t>(x); };
  std::vector<float> ds = {0.0f, -0.0f, 1e-30f, -1e-30f, 1.0f, -1.0f, std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN(),
                           -std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::denorm_min(),
                           -std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max()};
  for (float t : {1e-30f, -1e-30f})
    for (int k = -64; k <= 64; ++k) ds.push_back(std::bit_cast<float>(static_cast<std::uint32_t>(bits(t) + k)));
  std::mt19937 rng(42);
  for (int i = 0; i < 300000; ++i) ds.push_back(std::bit_cast<float>(static_cast<std::uint32_t>(rng())));
  for (std::size_t i = 0; i < ds.size(); ++i) {
    RsRay ray{};
    for (int a = 0; a < 3; ++a) ray.o[a] = ds[(i + 5 * a) % ds.size()], ray.d[a] = ds[(i + a) % ds.size()];
    ray.tmin = ds[(i + 7) % ds.size()];
    ray.tmax = ds[(i + 11) % ds.size()];
    const RsTraversalRay want = rs_prepare_ray(ray), got = rs_exit_ray(ray);
    const float w[14] = {want.o.x, want.o.y, want.o.z, want.d.x, want.d.y, want.d.z, want.inv_d.x,
                         want.inv_d.y, want.inv_d.z, want.o_inv_d.x, want.o_inv_d.y, want.o_inv_d.z, want.tmin, want.tmax};
    const float g[14] = {got.o.x, got.o.y, got.o.z, got.d.x, got.d.y, got.d.z, got.inv_d.x,
                         got.inv_d.y, got.inv_d.z, got.o_inv_d.x, got.o_inv_d.y, got.o_inv_d.z, got.tmin, got.tmax};
    for (int f = 0; f < 14; ++f) {
      // −(o · 1/d) of a NaN origin and a NaN reciprocal: which payload the product keeps depends on the
      // operand order the compiler chose, and no test reads it (every comparison with NaN is false).
      if (f >= 9 && f < 12 && std::isnan(g[f]) && std::isnan(w[f])) continue;
      ASSERT_EQ(bits(g[f]), bits(w[f])) << "ray " << i << " field " << f << " d=" << ray.d[f % 3];
    }
  }
}

TEST(Encode, NamesRoundTrip) {
  EXPECT_EQ(all_encoders().size(), 14u);
  for (Encoder e : all_encoders()) {
    auto p = parse_encoder(encoder_name(e));
    ASSERT_TRUE(p.has_value()) << encoder_name(e);
    EXPECT_EQ(*p, e);
  }
  EXPECT_EQ(parse_encoder("Aila_Compact"), Encoder::Aila);
  EXPECT_EQ(parse_encoder("HCC_DIR"), Encoder::HCC_DIR);
  EXPECT_EQ(parse_encoder("regular-grid"), Encoder::RegularGrid);
  EXPECT_EQ(parse_encoder("HCC_REGION"), Encoder::HCC_REGION);
  EXPECT_EQ(parse_encoder("hcc-traffic"), Encoder::HCC_TRAFFIC);
  EXPECT_EQ(parse_encoder("MLHCC_COST"), Encoder::MLHCC_COST);
  EXPECT_FALSE(parse_encoder("zorder").has_value());
  EXPECT_NE(key_bits_problem(Encoder::MLHCC, 17, {}), "");
  EXPECT_NE(key_bits_problem(Encoder::HCC, 65, {}), "");
  EXPECT_NE(key_bits_problem(Encoder::HCC_DIR, 1, {}), "");
  EXPECT_EQ(key_bits_problem(Encoder::HCC_DIR, 16, {}), "");
  // mlhcc-cost: even, at least 4; its cost bits fewer than half the key (a low-level cut remains).
  EXPECT_NE(key_bits_problem(Encoder::MLHCC_COST, 17, {}), "");
  EXPECT_NE(key_bits_problem(Encoder::MLHCC_COST, 2, {}), "");
  EXPECT_EQ(key_bits_problem(Encoder::MLHCC_COST, 4, {}), "");
  EncoderParams cost;
  cost.cost_bits = 16;
  EXPECT_NE(key_bits_problem(Encoder::MLHCC_COST, 32, cost), "");
  EXPECT_EQ(key_bits_problem(Encoder::MLHCC_COST, 34, cost), "");
  EXPECT_EQ(cost_split(32, {}).top_bits, 16u);
  EXPECT_EQ(cost_split(32, {}).low_bits, 12u);
  EXPECT_EQ(cost_split(32, {}).cost_bits, 4u);
  EXPECT_EQ(cost_split(4, {}).cost_bits, 1u);  // at least one cost bit
  EXPECT_EQ(cost_split(64, cost).low_bits, 16u);
  EXPECT_THROW(check_key_bits(Encoder::Origin, 0, {}), Error);
}

// Keys worked out by hand (docs/encoders.md has the layouts). Scene box [0,1]³.
// Issue 41: the encoder list (cl/encoders.h) is the one place an encoder is named. The kernel ids,
// the host's enum, the table with each row's family, kernel and aliases, and the kernels themselves
// all come from it.
TEST(EncoderList, IdsTableFamiliesAndKernelsComeFromTheList) {
  const auto& table = encoder_table();
  ASSERT_EQ(table.size(), static_cast<std::size_t>(RS_ENC_COUNT));
  EXPECT_EQ(static_cast<int>(Encoder::MLHCC_COST), RS_ENC_MLHCC_COST);
  for (std::size_t i = 0; i < table.size(); ++i) {
    const EncoderInfo& info = table[i];
    EXPECT_EQ(static_cast<std::size_t>(info.id), i) << info.name;
    EXPECT_EQ(&encoder_family(info.id), info.family) << info.name;
    // A spatial encoder has a kernel of its own; any other its family's.
    if (info.family_name != "spatial") {
      EXPECT_EQ(info.kernel, "encode_" + std::string(info.family_name)) << info.name;
    }
  }
  EXPECT_EQ(encoder_info(Encoder::Aila).kernel, "encode_aila");
  EXPECT_EQ(encoder_info(Encoder::HCC_TRAFFIC).family_name, "box_set");
  EXPECT_EQ(parse_encoder("nosorting"), Encoder::NoSort);
  EXPECT_EQ(parse_encoder("hierarchy-cut-code"), Encoder::HCC);
  EXPECT_EQ(parse_encoder("aila_compact"), Encoder::Aila);
  EXPECT_TRUE(encoder_info(Encoder::Origin).aliases.empty());
  // Every kernel the table and the families name exists (DeviceEncoder creates them all).
  const Bvh bvh = four_leaf_bvh();
  EXPECT_NO_THROW(DeviceEncoder(testing::runtime(), bvh, unit_box()));
}

TEST(Encode, HandComputedSpatialKeys) {
  Bvh bvh = four_leaf_bvh();
  EncodeScene s(bvh, unit_box());
  // Origin (.75, .25, .5) = x .11, y .01, z .1 in binary; direction +z: φ = ½ (atan2(0,0) = 0),
  // θ = 0; Aila's (d+1)/2 = (.5, .5, 1).
  const RsRay r = ray(.75f, .25f, .5f, 0, 0, 1);
  // Morton levels: 101, 110, then 000...
  EXPECT_EQ(key1(Encoder::Origin, 16, s, r), 0xB800u);
  EXPECT_EQ(key1(Encoder::Origin, 64, s, r), 0xB800000000000000ull);
  // Reis: 22 origin bits (101110 + 16 zeros), then (φ,θ) levels 10 00 00 ...
  EXPECT_EQ(key1(Encoder::Reis, 16, s, r), 0xB800u);
  EXPECT_EQ(key1(Encoder::Reis, 32, s, r), 0xB8000200u);
  // Costa: (φ,θ) 10 00 00 00, then origin 101 110 00...
  EXPECT_EQ(key1(Encoder::Costa, 16, s, r), 0x80B8u);
  // Aila: origin 101 110 000, [origin level 3: 000 | direction level 0: 111], origin level 4: 0...
  EXPECT_EQ(key1(Encoder::Aila, 16, s, r), 0xB80Eu);
  // TwoPoint: L = min(.25, exit .5) → b = (.75, .25, .75); levels a|b: 101|101, 110|111, 000|0
  EXPECT_EQ(key1(Encoder::TwoPoint, 16, s, r), 0xB770u);
  // NoSort: no key.
  EXPECT_EQ(key1(Encoder::NoSort, 32, s, r), 0u);
  // RegularGrid of a cube: 16 cells = 4×2×2 (x most significant), 32 = 4×4×2. The ray from
  // (.6, .3, .1) up +z crosses cells (2,0,0), (2,0,1) of 16 and (2,1,0), (2,1,1) of 32.
  const RsRay g = ray(.6f, .3f, .1f, 0, 0, 1);
  EXPECT_EQ(key1(Encoder::RegularGrid, 16, s, g), 0x00C0u);
  EXPECT_EQ(key1(Encoder::RegularGrid, 32, s, g), 0x00003000u);
}

TEST(Encode, HandComputedCutKeys) {
  Bvh bvh = four_leaf_bvh();
  EncodeScene s(bvh, unit_box());
  // The 16-node cut is all four leaves, by HAD: T0, T1, T2, T3 (bits 15, 14, 13, 12).
  ASSERT_EQ(s.hcc_cut(16), (std::vector<std::uint32_t>{3, 4, 5, 6}));
  const RsRay r1 = ray(.1f, .1f, 0, 0, 0, 1);           // through T0 only
  const RsRay r2 = ray(.68f, .62f, 1, 0, 0, -1);        // through T3 only
  const RsRay r2_short = ray(.68f, .62f, 1, 0, 0, -1, .5f);  // stops at z = .5, above T3
  EXPECT_EQ(key1(Encoder::HCC, 16, s, r1), 0x8000u);
  EXPECT_EQ(key1(Encoder::HCC, 16, s, r2), 0x1000u);
  EXPECT_EQ(key1(Encoder::HCC, 16, s, r2_short), 0u);
  EXPECT_EQ(key1(Encoder::HCC, 64, s, r2), 0x1000000000000000ull);
  // HCC_DIR (d = 1): 15 cut bits (the same four leaves), then φ's top bit (φ = ½ → 1).
  EXPECT_EQ(key1(Encoder::HCC_DIR, 16, s, r1), 0x8001u);
  EXPECT_EQ(key1(Encoder::HCC_DIR, 16, s, r2), 0x1001u);
  // MLHCC 16: 4 leaves < 8, so the root is the only top node (bit 15); the low cut under it is
  // the four leaves (bits 7..4).
  EXPECT_EQ(key1(Encoder::MLHCC, 16, s, r1), 0x8080u);
  EXPECT_EQ(key1(Encoder::MLHCC, 16, s, r2), 0x8010u);
  // PPC: root 1; (node 1, node 2) = 10; (T0, T1) = 10; T0's leaf, stack empty → 11010.
  EXPECT_EQ(key1(Encoder::PPC, 16, s, r1), 0xD000u);
  // r2: root 1; (node 1, node 2) = 01; (T2, T3) = 01 → 10101.
  EXPECT_EQ(key1(Encoder::PPC, 16, s, r2), 0xA800u);
  EXPECT_EQ(key1(Encoder::PPC, 32, s, r2), 0xA8000000u);
  // PPC truncation: 2 bits of 11010 are 11.
  EXPECT_EQ(key1(Encoder::PPC, 2, s, r1), 3u);
  // The device agrees on all of these.
  DeviceEncoder dev(testing::runtime(), bvh, unit_box());
  expect_all_encoders_bit_exact(dev, {r1, r2, r2_short, ray(.75f, .25f, .5f, 0, 0, 1), ray(.6f, .3f, .1f, 0, 0, 1)},
                                "four-leaf");
}

TEST(Encode, SignedZeroDirectionsGiveTheSameKeys) {
  Bvh bvh = four_leaf_bvh();
  EncodeScene s(bvh, unit_box());
  const std::vector<std::pair<RsRay, RsRay>> pairs = {
      {ray(.35f, .35f, .35f, 0, 0, 1), ray(.35f, .35f, .35f, -0.0f, -0.0f, 1)},
      {ray(.35f, .35f, .35f, -1, 0, 0), ray(.35f, .35f, .35f, -1, -0.0f, 0)},   // atan2(±0, −1): π, not ±π
      {ray(.35f, .35f, .35f, 1, 0, 0), ray(.35f, .35f, .35f, 1, -0.0f, -0.0f)},
      {ray(.35f, .35f, .35f, 0, 1, 0), ray(.35f, .35f, .35f, -0.0f, 1, -0.0f)},
  };
  // (The origin lies on no box plane. A ray lying in a box's face plane with a ±0 component is
  // where the slab test itself, shared with traversal, sees the sign: there box-set keys follow
  // the trace's test; both sides still agree bit for bit, checked below.)
  std::vector<RsRay> all = {ray(.3f, .3f, .3f, 0, 1, 0), ray(.3f, .3f, .3f, -0.0f, 1, -0.0f)};
  for (Encoder e : {Encoder::Origin, Encoder::Reis, Encoder::Costa, Encoder::Aila, Encoder::TwoPoint})
    EXPECT_EQ(key1(e, 64, s, all[0]), key1(e, 64, s, all[1])) << encoder_name(e);
  for (const auto& [a, b] : pairs) {
    for (Encoder e : all_encoders())
      for (unsigned bits : kBits)
        EXPECT_EQ(key1(e, bits, s, a), key1(e, bits, s, b)) << encoder_name(e) << "/" << bits;
    all.push_back(a);
    all.push_back(b);
  }
  DeviceEncoder dev(testing::runtime(), bvh, unit_box());
  expect_all_encoders_bit_exact(dev, all, "signed zeros");
}

TEST(Encode, PolarDirectionsStayInTheAcosDomain) {
  Bvh bvh = four_leaf_bvh();
  EncodeScene s(bvh, unit_box());
  // dz = ±1 after normalisation, also from unnormalised and nearly polar directions.
  std::vector<RsRay> rays = {ray(.5f, .5f, .5f, 0, 0, 1),        ray(.5f, .5f, .5f, 0, 0, -1),
                             ray(.5f, .5f, .5f, 0, 0, 7.5f),     ray(.5f, .5f, .5f, 0, 0, -1e-3f),
                             ray(.5f, .5f, .5f, 1e-7f, 0, 1),    ray(.5f, .5f, .5f, -1e-7f, 1e-7f, -1),
                             ray(.5f, .5f, .5f, 1e-30f, 0, 1),   ray(.5f, .5f, .5f, 0, 0, 0)};
  // Reis 64: the low 42 bits are (φ,θ) × 21 levels; θ = 0 for +z and the top cell for −z.
  const std::uint64_t theta_mask = 0x15555555555ull;  // θ bits of the 42-bit field
  for (int i : {0, 2, 4, 6}) EXPECT_EQ(key1(Encoder::Reis, 64, s, rays[i]) & theta_mask, 0u) << i;
  for (int i : {1, 3, 5}) EXPECT_EQ(key1(Encoder::Reis, 64, s, rays[i]) & theta_mask, theta_mask) << i;
  DeviceEncoder dev(testing::runtime(), bvh, unit_box());
  expect_all_encoders_bit_exact(dev, rays, "polar directions");
}

TEST(Encode, OriginsOnTheBoxFacesStayInTheirField) {
  Bvh bvh = four_leaf_bvh();
  EncodeScene s(bvh, unit_box());
  const RsRay max_corner = ray(1, 1, 1, 1, 0, 0), min_corner = ray(0, 0, 0, -1, 0, 0);
  const RsRay x_face = ray(1, 0, 0, 0, 1, 0), y_face = ray(0.5f, 1, 0.5f, 1, 0, 0);
  EXPECT_EQ(key1(Encoder::Origin, 64, s, max_corner), ~0ull);
  EXPECT_EQ(key1(Encoder::Origin, 32, s, max_corner), 0xFFFFFFFFull);
  EXPECT_EQ(key1(Encoder::Origin, 16, s, max_corner), 0xFFFFull);
  EXPECT_EQ(key1(Encoder::Origin, 64, s, min_corner), 0u);
  EXPECT_EQ(key1(Encoder::Origin, 64, s, x_face), 0x9249249249249249ull);  // x bits all 1
  EXPECT_EQ(key1(Encoder::Origin, 64, s, y_face) & 0x4924924924924924ull, 0x4924924924924924ull);
  // TwoPoint from the max corner: a and b (clamped) are both the top cell.
  EXPECT_EQ(key1(Encoder::TwoPoint, 64, s, max_corner), ~0ull);
  // Aila: (d + 1)/2 = 1 for +x: the direction cell is clamped, not carried into the next group.
  const std::uint64_t aila = key1(Encoder::Aila, 64, s, max_corner);
  // 9 origin ones, [111|111], then 8 × [111|100] (dy, dz = 0 → .5 → 100...), last bit 0.
  EXPECT_EQ(aila, 0xFFFFE79E79E79E78ull) << std::hex << aila;
  DeviceEncoder dev(testing::runtime(), bvh, unit_box());
  expect_all_encoders_bit_exact(dev, {max_corner, min_corner, x_face, y_face}, "box faces");
}

TEST(Encode, TerminationPointsOutsideTheBoxAreClamped) {
  Bvh bvh = four_leaf_bvh();
  EncoderParams p;
  p.twopoint_length_fraction = 10.0f;  // L far beyond the box: b is limited by the box exit
  EncodeScene s(bvh, unit_box(), p);
  // From inside, a long fixed length is cut at the box exit (x = 1): b = (1, .25, .25).
  const RsRay inside = ray(.25f, .25f, .25f, 1, 0, 0);
  // From outside, pointing away: a and b both outside; both clamp to the max cell.
  const RsRay outside = ray(10, 10, 10, 1, 1, 1);
  // Behind the origin there is no segment (L = 0): b = a.
  const RsRay away = ray(2, .5f, .5f, 1, 0, 0);
  const std::uint64_t k = key1(Encoder::TwoPoint, 64, s, inside);
  // a = (.01, .01, .01) in binary, b = (1 → top cell, .01, .01): level 0 a|b = 000|100,
  // level 1 = 111|111.
  EXPECT_EQ(k >> 52, 0x13Fu) << std::hex << k;
  EXPECT_EQ(key1(Encoder::TwoPoint, 64, s, outside), ~0ull);
  const std::uint64_t ka = key1(Encoder::TwoPoint, 16, s, away);
  // a = b = (2 → top cell, .5, .5): level 0 = 111|111, levels 1, 2 = 100|100 → 111111 100100 1001.
  EXPECT_EQ(ka, 0xFE49u) << std::hex << ka;
  DeviceEncoder dev(testing::runtime(), bvh, unit_box(), p);
  expect_all_encoders_bit_exact(dev, {inside, outside, away}, "outside the box");
}

TEST(Encode, RaysThatMissEverythingGetZeroCutBits) {
  Bvh bvh = four_leaf_bvh();
  EncodeScene s(bvh, unit_box());
  const RsRay away = ray(5, 5, 5, 1, 0, 0);
  for (Encoder e : {Encoder::HCC, Encoder::MLHCC, Encoder::PPC, Encoder::RegularGrid})
    for (unsigned bits : kBits) EXPECT_EQ(key1(e, bits, s, away), 0u) << encoder_name(e) << "/" << bits;
  DeviceEncoder dev(testing::runtime(), bvh, unit_box());
  expect_all_encoders_bit_exact(dev, {away}, "misses");
}

// Procedural scenes: rays starting inside cut nodes set their bit; MLHCC rays that miss every top
// node have zero low bits; kernel == host on every batch.
namespace {

void check_scene(const std::string& name, std::uint32_t w, std::uint32_t h) {
  SceneOptions opts;
  opts.frame = {w, h, 1};
  const PreparedScene p = prepare_scene(name, opts);
  const Bvh& bvh = p.bvh;
  auto batches = generate_batches(p.scene, p.tris, bvh, {});
  ASSERT_GE(batches.size(), 3u) << name;
  DeviceEncoder dev(testing::runtime(), bvh, bvh.bounds());
  for (const auto& rb : batches) expect_all_encoders_bit_exact(dev, rb.batch.rays, name + " " + rb.batch.name);

  // Rays from the centre of each 32-bit cut node, in a few directions: that node's bit is 1.
  const auto& cut = dev.scene().hcc_cut(32);
  std::vector<RsRay> inside;
  for (std::size_t i = 0; i < cut.size(); ++i) {
    const RsBvhNode& n = bvh.nodes[cut[i]];
    float c[3];
    for (int a = 0; a < 3; ++a) c[a] = 0.5f * (n.bmin[a] + n.bmax[a]);
    for (const RsRay& r : {ray(c[0], c[1], c[2], 1, 0, 0), ray(c[0], c[1], c[2], -0.3f, 0.9f, -0.1f)}) {
      inside.push_back(r);
      EXPECT_NE(key1(Encoder::HCC, 32, dev.scene(), r) & (1ull << (31 - i)), 0u) << name << " cut node " << i;
    }
  }
  expect_all_encoders_bit_exact(dev, inside, name + " inside cut nodes");

  // MLHCC: whenever no top bit is set, no low bit is either.
  for (const auto& rb : batches)
    for (unsigned bits : kBits) {
      auto keys = encode_on_host(Encoder::MLHCC, bits, dev.scene(), rb.batch.rays);
      const unsigned half = bits / 2;
      for (auto k : keys)
        if ((k >> half) == 0) {
          ASSERT_EQ(k, 0u);
        }
    }
}

}  // namespace

TEST(Encode, CornellEveryBatchBitExact) { check_scene("cornell", 64, 36); }
TEST(Encode, DetailRoomEveryBatchBitExact) { check_scene("detail-room", 64, 36); }

TEST(Encode, ThroughAnOrderBuffer) {
  const auto cornell = testing::scene_batches("cornell", 32, 18);
  const Bvh& bvh = cornell.bvh;
  const auto& rays = cornell.batches.at(0).batch.rays;
  std::vector<std::uint32_t> reversed(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) reversed[i] = static_cast<std::uint32_t>(rays.size() - 1 - i);
  DeviceEncoder dev(testing::runtime(), bvh, bvh.bounds());
  for (Encoder e : {Encoder::Reis, Encoder::HCC, Encoder::MLHCC, Encoder::PPC}) {
    auto host = encode_on_host(e, 32, dev.scene(), rays);
    auto run = dev.run(e, 32, rays, &reversed);
    std::size_t bad = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) bad += run.keys[i] != host[reversed[i]] || run.values[i] != i;
    EXPECT_EQ(bad, 0u) << encoder_name(e);
  }
  // Odd and tiny counts: MLHCC's work-items take two rays each (cl/keys_cut.h, RS_TWO_LEVEL_RAYS);
  // mlhcc-cost's one (with a table from these rays' own step counts).
  std::vector<std::uint32_t> steps;
  trace_reference(bvh, rays, nullptr, false, &steps);
  set_cost_estimates(dev.scene(), cost_statistics(dev.scene().frame(), rays, steps));
  for (std::size_t n : {1u, 2u, 3u, 5u, 577u}) {
    std::vector<RsRay> some(rays.begin(), rays.begin() + static_cast<std::ptrdiff_t>(n));
    for (unsigned bits : {16u, 64u})
      for (Encoder e : {Encoder::MLHCC, Encoder::MLHCC_COST}) {
        const auto host = encode_on_host(e, bits, dev.scene(), some);
        const auto run = dev.run(e, bits, some);
        ASSERT_EQ(run.keys.size(), n);
        for (std::size_t i = 0; i < n; ++i) {
          EXPECT_EQ(run.keys[i], host[i]) << encoder_name(e) << " " << n << " rays, bits " << bits << ", ray " << i;
          EXPECT_EQ(run.values[i], i) << encoder_name(e) << " " << n << " rays, bits " << bits;
        }
      }
  }
}

// The spatial kernels have no count guard: the host launches whole work-groups and then the rest
// one work-item per group from `first` on (DeviceEncoder::enqueue). Counts below, at and around
// multiples of the local size, through a reversed order, must give every ray its key.
TEST(Encode, SpatialKernelsCoverEveryCount) {
  const auto cornell = testing::scene_batches("cornell", 24, 16);
  const Bvh& bvh = cornell.bvh;
  const auto& all = cornell.batches.at(0).batch.rays;
  DeviceEncoder dev(testing::runtime(), bvh, bvh.bounds());
  const std::size_t local = dev.local_size();
  ASSERT_GT(all.size(), 3 * local);
  for (std::size_t n : {std::size_t{1}, local - 1, local, local + 1, 2 * local, 3 * local - 5}) {
    std::vector<RsRay> rays(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(n));
    std::vector<std::uint32_t> reversed(n);
    for (std::size_t i = 0; i < n; ++i) reversed[i] = static_cast<std::uint32_t>(n - 1 - i);
    for (Encoder e : {Encoder::Origin, Encoder::Reis, Encoder::Costa, Encoder::Aila, Encoder::TwoPoint})
      for (unsigned bits : {32u, 64u}) {
        const auto host = encode_on_host(e, bits, dev.scene(), rays);
        const auto run = dev.run(e, bits, rays, &reversed);
        ASSERT_EQ(run.keys.size(), n);
        std::size_t bad = 0;
        for (std::size_t i = 0; i < n; ++i) bad += run.keys[i] != host[reversed[i]] || run.values[i] != i;
        EXPECT_EQ(bad, 0u) << encoder_name(e) << "/" << bits << ", " << n << " rays";
      }
  }
}

// A batch past the encode kernels' 32-bit float offsets is refused with a message, before any launch.
TEST(Encode, TooLargeABatchIsRefused) {
  Bvh bvh = four_leaf_bvh();
  DeviceEncoder dev(testing::runtime(), bvh, bvh.bounds());
  Runtime& rt = testing::runtime();
  cl::Buffer small = rt.buffer("small", 64);
  try {
    dev.enqueue(Encoder::Reis, 32, small, small, DeviceEncoder::kMaxRays, small, small);
    FAIL() << "no error";
  } catch (const Error& err) {
    EXPECT_NE(std::string(err.what()).find("too large to encode"), std::string::npos) << err.what();
  }
}

TEST(Encode, SingleLeafBvh) {
  Scene s;
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 1}};
  m.triangles = {{0, 1, 2}};
  s.meshes.push_back(m);
  Bvh bvh = build_bvh(s.flatten());
  ASSERT_EQ(bvh.nodes.size(), 1u);
  EncodeScene es(bvh, bvh.bounds());
  EXPECT_EQ(es.hcc_cut(32), std::vector<std::uint32_t>{0});
  const auto& t = two_level_inputs(es, 32);
  EXPECT_EQ(t.cut.top, std::vector<std::uint32_t>{0});
  ASSERT_EQ(t.cut.low.size(), 1u);
  EXPECT_EQ(t.cut.low[0], std::vector<std::uint32_t>{0});
  const RsRay hit = ray(.2f, .2f, -1, 0, 0, 1), miss = ray(5, 5, 5, 0, 1, 0);
  EXPECT_EQ(key1(Encoder::HCC, 16, es, hit), 0x8000u);
  EXPECT_EQ(key1(Encoder::MLHCC, 16, es, hit), 0x8080u);
  EXPECT_EQ(key1(Encoder::PPC, 16, es, hit), 0x8000u);
  EXPECT_EQ(key1(Encoder::PPC, 16, es, miss), 0u);
  DeviceEncoder dev(testing::runtime(), bvh, bvh.bounds());
  expect_all_encoders_bit_exact(dev, {hit, miss, ray(.1f, .1f, .1f, 0, 0, -1)}, "single leaf");
}

TEST(Encode, FlatSceneHasNoNanCells) {
  // Every triangle in the plane z = 2: the scene box has zero z extent.
  Scene s;
  Mesh m;
  for (int i = 0; i < 20; ++i) {
    const float x = static_cast<float>(i % 5), y = static_cast<float>(i / 5);
    const auto b = static_cast<std::uint32_t>(m.positions.size());
    m.positions.push_back({x, y, 2});
    m.positions.push_back({x + 0.9f, y, 2});
    m.positions.push_back({x, y + 0.9f, 2});
    m.triangles.push_back({b, b + 1, b + 2});
  }
  s.meshes.push_back(m);
  Bvh bvh = build_bvh(s.flatten());
  const Aabb box = bvh.bounds();
  ASSERT_EQ(box.min[2], box.max[2]);
  EncodeScene es(bvh, box);
  EXPECT_EQ(es.frame().inv_extent[2], 0.0f);
  std::vector<RsRay> rays;
  for (int i = 0; i < 64; ++i) {
    const float u = static_cast<float>(i) / 64.0f;
    rays.push_back(ray(5 * u, 4 * (1 - u), 3, 0.1f * u, -0.2f, -1));
    rays.push_back(ray(5 * u, 4 * u, 2, 1, 0, 0));  // in the plane
  }
  // z cells are all 0: Origin keys have no z bit set.
  for (const RsRay& r : rays) EXPECT_EQ(key1(Encoder::Origin, 64, es, r) & 0x2492492492492492ull, 0u);
  // Grid cells never split the flat axis.
  EXPECT_EQ(regular_grid_shape(box, 32)[2], 1u);
  DeviceEncoder dev(testing::runtime(), bvh, box);
  expect_all_encoders_bit_exact(dev, rays, "flat scene");
}

namespace {
Scene scaled(Scene s, float k) {
  for (auto& m : s.meshes)
    for (auto& p : m.positions)
      for (auto& c : p) c *= k;
  for (auto& inst : s.instances)
    for (int r = 0; r < 3; ++r) inst.transform.m[r * 4 + 3] *= k;
  for (auto& c : s.camera.position) c *= k;
  for (auto& c : s.camera.look_at) c *= k;
  for (auto& l : s.sphere_lights)
    for (auto& c : l.center) c *= k;
  return s;
}
}  // namespace

TEST(Encode, LargeAndSmallSceneScales) {
  SceneOptions opts;
  opts.frame = {48, 27, 1};
  Scene base = load_scene("cornell", opts);
  std::size_t base_distinct = 0;
  for (float k : {1.0f, 1e6f, 1e-4f}) {
    Scene scene = scaled(base, k);
    Scene::Flat tris = scene.flatten();
    Bvh bvh = build_bvh(tris);
    auto batches = generate_batches(scene, tris, bvh, {});
    ASSERT_GE(batches.size(), 2u);
    DeviceEncoder dev(testing::runtime(), bvh, bvh.bounds());
    for (const auto& rb : batches)
      expect_all_encoders_bit_exact(dev, rb.batch.rays, "scale " + std::to_string(k) + " " + rb.batch.name);
    // Sensible keys: the primary batch spreads over about as many TwoPoint cells at every scale.
    auto keys = encode_on_host(Encoder::TwoPoint, 32, dev.scene(), batches[0].batch.rays);
    const std::size_t distinct = std::set<std::uint64_t>(keys.begin(), keys.end()).size();
    if (k == 1.0f) base_distinct = distinct;
    EXPECT_GT(distinct, base_distinct / 2) << "scale " << k;
    EXPECT_GT(distinct, 10u) << "scale " << k;
  }
}

// The key code before the branch-free rewrite, kept as the reference: Morton levels appended one
// bit at a time through a bit writer (bits past 64 dropped), and one scalar slab test per cut box
// (rs_segment_overlaps_box) over AoS boxes. The rewritten code (magic-number bit spreading, eight
// boxes per SoA slab test) must give the same code for every ray.
namespace ref {

RsBitWriter writer() { return rs_bit_writer(); }
void put_morton3(RsBitWriter* w, const rs_u32 q[3], rs_u32 n, rs_u32 first, rs_u32 levels) {
  for (rs_u32 l = first; l < first + levels; ++l)
    rs_put_bits(w, (rs_level_bit(q[0], n, l) << 2) | (rs_level_bit(q[1], n, l) << 1) | rs_level_bit(q[2], n, l), 3u);
}
void put_spherical(RsBitWriter* w, const rs_u32 q[2], rs_u32 n, rs_u32 levels) {
  for (rs_u32 l = 0; l < levels; ++l) rs_put_bits(w, (rs_level_bit(q[0], n, l) << 1) | rs_level_bit(q[1], n, l), 2u);
}
RsVec3 unit_direction(const RsRay& r) { return rs_normalize(rs_vec3(r.d[0], r.d[1], r.d[2])); }
void spherical(RsVec3 d, rs_u32 n, rs_u32 q[2]) {
  q[0] = rs_quantize(rs_atan2(d.y, d.x) * RS_INV_2PI_F + 0.5f, n);
  q[1] = rs_quantize(rs_acos(d.z) * RS_INV_PI_F, n);
}
rs_u64 origin(const RsEncodeFrame* f, const RsRay& r) {
  rs_u32 q[3];
  rs_quantize_point(f, rs_load3(r.o), RS_ORIGIN_LEVELS, q);
  RsBitWriter w = writer();
  put_morton3(&w, q, RS_ORIGIN_LEVELS, 0u, RS_ORIGIN_LEVELS);
  return w.code;
}
rs_u64 reis(const RsEncodeFrame* f, const RsRay& r) {
  rs_u32 q[3], s[2];
  rs_quantize_point(f, rs_load3(r.o), RS_ORIGIN_LEVELS, q);
  spherical(unit_direction(r), RS_DIRECTION_LEVELS, s);
  RsBitWriter w = writer();
  put_morton3(&w, q, RS_ORIGIN_LEVELS, 0u, 7u);
  rs_put_bits(&w, rs_level_bit(q[0], RS_ORIGIN_LEVELS, 7u), 1u);
  put_spherical(&w, s, RS_DIRECTION_LEVELS, RS_DIRECTION_LEVELS);
  return w.code;
}
rs_u64 costa(const RsEncodeFrame* f, const RsRay& r) {
  rs_u32 q[3], s[2];
  rs_quantize_point(f, rs_load3(r.o), 15u, q);
  spherical(unit_direction(r), 4u, s);
  RsBitWriter w = writer();
  put_spherical(&w, s, 4u, 4u);
  put_morton3(&w, q, 15u, 0u, 15u);
  return w.code;
}
rs_u64 aila(const RsEncodeFrame* f, const RsRay& r) {
  const rs_u32 on = 12u, dn = RS_AILA_DIR_LEVELS;
  rs_u32 q[3], dq[3];
  rs_quantize_point(f, rs_load3(r.o), on, q);
  RsVec3 d = unit_direction(r);
  dq[0] = rs_quantize((d.x + 1.0f) * 0.5f, dn);
  dq[1] = rs_quantize((d.y + 1.0f) * 0.5f, dn);
  dq[2] = rs_quantize((d.z + 1.0f) * 0.5f, dn);
  RsBitWriter w = writer();
  put_morton3(&w, q, on, 0u, 3u);
  for (rs_u32 i = 0; i < dn; ++i) {
    put_morton3(&w, q, on, 3u + i, 1u);
    put_morton3(&w, dq, dn, i, 1u);
  }
  return w.code;
}
rs_u64 twopoint(const RsEncodeFrame* f, const RsRay& ray) {
  const rs_u32 n = RS_TWOPOINT_LEVELS;
  RsTraversalRay r = rs_prepare_ray(ray);
  float len = rs_max(0.0f, rs_min(f->twopoint_length, rs_scene_exit(f, r)));
  RsVec3 b = rs_add(r.o, rs_scale(r.d, len));
  rs_u32 qa[3], qb[3];
  rs_quantize_point(f, r.o, n, qa);
  rs_quantize_point(f, b, n, qb);
  RsBitWriter w = writer();
  for (rs_u32 l = 0; l < n; ++l) {
    put_morton3(&w, qa, n, l, 1u);
    put_morton3(&w, qb, n, l, 1u);
  }
  return w.code;
}
rs_u64 direction_bits(const RsRay& r, rs_u32 d) {
  rs_u32 s[2];
  spherical(unit_direction(r), RS_DIRECTION_LEVELS, s);
  RsBitWriter w = writer();
  put_spherical(&w, s, RS_DIRECTION_LEVELS, RS_DIRECTION_LEVELS);
  return rs_key_from_code(w.code, d);
}
rs_u64 box_set(const RsRay& ray, const RsBox* boxes, rs_u32 n, rs_u32 field, rs_u32 dir_bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  rs_u64 code = 0;
  for (rs_u32 i = 0; i < n; ++i)
    if (rs_segment_overlaps_box(r, boxes[i])) code |= rs_u64(1) << (63u - i);
  if (dir_bits > 0u) code |= direction_bits(ray, dir_bits) << (64u - field - dir_bits);
  return code;
}
rs_u64 two_level(const RsRay& ray, const RsBox* top, rs_u32 n_top, const RsBox* low, const rs_u32* low_count,
                 rs_u32 half_bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  rs_u64 code = 0;
  rs_u32 rep = 0xFFFFFFFFu;
  for (rs_u32 i = 0; i < n_top; ++i)
    if (rs_segment_overlaps_box(r, top[i])) {
      code |= rs_u64(1) << (63u - i);
      if (rep == 0xFFFFFFFFu) rep = i;
    }
  if (rep != 0xFFFFFFFFu)
    for (rs_u32 j = 0; j < low_count[rep]; ++j)
      if (rs_segment_overlaps_box(r, low[rep * half_bits + j])) code |= rs_u64(1) << (63u - half_bits - j);
  return code;
}

std::uint64_t key(Encoder e, unsigned bits, const EncodeScene& s, const RsRay& r) {
  const RsEncodeFrame* f = &s.frame();
  rs_u64 code = 0;
  switch (e) {
    case Encoder::Origin: code = origin(f, r); break;
    case Encoder::Reis: code = reis(f, r); break;
    case Encoder::Costa: code = costa(f, r); break;
    case Encoder::Aila: code = aila(f, r); break;
    case Encoder::TwoPoint: code = twopoint(f, r); break;
    case Encoder::RegularGrid:
    case Encoder::HCC:
    case Encoder::HCC_TRAFFIC:
    case Encoder::HCC_DIR: {
      const auto& boxes = box_set(s, e, bits);
      const unsigned dir = e == Encoder::HCC_DIR ? s.params().direction_bits : 0u;
      code = box_set(r, boxes.data(), static_cast<rs_u32>(boxes.size()), bits - dir, dir);
      break;
    }
    case Encoder::MLHCC: {
      const auto& t = two_level_inputs(s, bits);
      code = two_level(r, t.top.data(), static_cast<rs_u32>(t.top.size()), t.low.data(), t.low_count.data(), t.half);
      break;
    }
    case Encoder::HCC_REGION: {
      // The region: the one leaf of the split tree all of whose ancestors' conditions the origin
      // meets, found by testing every leaf bottom-up (the kernel walks down); then one scalar slab
      // test per cut node of that region.
      const auto& g = region_inputs(s, bits);
      const rs_u32 rb = g.region_bits;
      rs_u32 region = 0, matches = 0;
      for (rs_u32 leaf = 0; leaf < (1u << rb); ++leaf) {
        bool inside = true;
        for (rs_u32 k = leaf + (1u << rb) - 1u; k > 0; k = (k - 1) / 2) {
          const RsRegionSplit sp = g.splits.at((k - 1) / 2);
          inside = inside && ((k % 2 == 0) == (r.o[sp.axis] >= sp.at));  // even k: the second child
        }
        if (inside) region = leaf, ++matches;
      }
      EXPECT_EQ(matches, 1u);
      if (rb > 0) code = rs_u64(region) << (64u - rb);
      const RsTraversalRay tr = rs_prepare_ray(r);
      const auto& cut = g.cuts.at(region);
      for (std::size_t i = 0; i < cut.size(); ++i) {
        const RsBox box = to_rs_box(node_box(s.bvh().nodes[cut[i]]));
        if (rs_segment_overlaps_box(tr, box)) code |= rs_u64(1) << (63u - rb - i);
      }
      break;
    }
    case Encoder::MLHCC_COST: {
      // Scalar slab tests over the top nodes and the representative's low cut, then the table's
      // value for the bin worked out here: the origin's cell per axis, the octahedral cell from
      // the direction's octant (upper half: (x, y) / L1 norm; lower half: folded).
      const auto& t = cost_cut_inputs(s, bits);
      const RsTraversalRay tr = rs_prepare_ray(r);
      std::size_t rep = t.cut.top.size();
      for (std::size_t i = 0; i < t.cut.top.size(); ++i)
        if (rs_segment_overlaps_box(tr, t.top[i])) {
          code |= rs_u64(1) << (63u - i);
          rep = std::min(rep, i);
        }
      if (rep < t.cut.top.size())
        for (std::size_t j = 0; j < t.cut.low[rep].size(); ++j)
          if (rs_segment_overlaps_box(tr, to_rs_box(node_box(s.bvh().nodes[t.cut.low[rep][j]]))))
            code |= rs_u64(1) << (63u - t.split.top_bits - j);
      rs_u32 cell = 0;
      for (int a = 0; a < 3; ++a) cell = cell * 16u + rs_quantize_axis(f, a, r.o[a], 4);
      const float l1 = std::fabs(r.d[0]) + std::fabs(r.d[1]) + std::fabs(r.d[2]);
      float u = l1 > 0 ? r.d[0] * (1.0f / l1) : 0.0f, v = l1 > 0 ? r.d[1] * (1.0f / l1) : 0.0f;
      if (r.d[2] < 0.0f) {
        const float fu = std::signbit(u) && u != 0.0f ? -(1.0f - std::fabs(v)) : 1.0f - std::fabs(v);
        const float fv = std::signbit(v) && v != 0.0f ? -(1.0f - std::fabs(u)) : 1.0f - std::fabs(u);
        u = fu, v = fv;
      }
      const rs_u32 bin = cell * 64u + rs_quantize(u * 0.5f + 0.5f, 3) * 8u + rs_quantize(v * 0.5f + 0.5f, 3);
      code |= rs_u64(t.cost.at(bin)) << (64u - bits);
      break;
    }
    default: return encode_ray(e, bits, s, r);
  }
  return rs_key_from_code(code, bits);
}

}  // namespace ref

namespace {

// Rays on the edges: origins on box faces, corners and cut-box corners, inside and outside the
// scene box; directions along axes, with ±0 components, unnormalised, tiny and random; finite and
// short segments.
std::vector<RsRay> edge_rays(const EncodeScene& s, const Aabb& box, std::size_t random_count) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  // The origin first: a ray that starts there overlaps a zero box (all six planes at 0, so every
  // slab is [0, 0]), which is what the unused lanes of a cut row hold: its keys show whether a
  // kernel keeps bits past a row's count.
  std::vector<std::array<float, 3>> points = {{0.0f, 0.0f, 0.0f}};
  for (int c = 0; c < 8; ++c)
    points.push_back({c & 1 ? box.max[0] : box.min[0], c & 2 ? box.max[1] : box.min[1], c & 4 ? box.max[2] : box.min[2]});
  for (unsigned bits : {16u, 64u})
    for (const RsBox& b : box_set(s, Encoder::HCC, bits)) {
      points.push_back({b.bmin[0], b.bmin[1], b.bmin[2]});
      points.push_back({b.bmax[0], b.bmax[1], b.bmax[2]});
      points.push_back({b.bmin[0], 0.5f * (b.bmin[1] + b.bmax[1]), b.bmax[2]});
    }
  const std::vector<std::array<float, 3>> dirs = {
      {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {-0.0f, 0, 1}, {0, -0.0f, -1},
      {1, 1, 1}, {-3, 2, 0.5f}, {1e-20f, -1e-20f, 1}, {0, 0, 0}, {0.6f, -0.8f, 0}};
  std::vector<RsRay> rays;
  for (const auto& p : points)
    for (const auto& d : dirs) {
      rays.push_back(ray(p[0], p[1], p[2], d[0], d[1], d[2]));
      rays.push_back(ray(p[0], p[1], p[2], d[0], d[1], d[2], 0.01f * box.largest_extent()));
    }
  for (std::size_t i = 0; i < random_count; ++i) {
    float o[3], d[3];
    for (int a = 0; a < 3; ++a) {
      const float ext = box.max[a] - box.min[a];
      o[a] = box.min[a] + (1.4f * u(rng) - 0.2f) * ext;
      d[a] = 2.0f * u(rng) - 1.0f;
      if (u(rng) < 0.05f) d[a] = u(rng) < 0.5f ? 0.0f : -0.0f;
    }
    const float tmax = u(rng) < 0.3f ? u(rng) * box.largest_extent() : RS_T_FAR;
    rays.push_back(ray(o[0], o[1], o[2], d[0], d[1], d[2], tmax));
  }
  return rays;
}

}  // namespace

// The rewritten key code (branch-free Morton codes, SoA cut groups) equals the bitwise reference on
// edge and random rays, for every encoder but PPC (unchanged) at many key lengths; kernel == host
// on the same rays.
TEST(Encode, SameKeysAsTheBitwiseReference) {
  Scene scene = load_scene("detail-room");
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  const Aabb box = bvh.bounds();
  DeviceEncoder dev(testing::runtime(), bvh, box);
  const EncodeScene& s = dev.scene();
  const std::vector<RsRay> rays = edge_rays(s, box, 20000);
  for (Encoder e : all_encoders()) {
    if (e == Encoder::PPC || e == Encoder::NoSort) continue;
    for (unsigned bits : {2u, 7u, 13u, 16u, 24u, 31u, 32u, 33u, 40u, 50u, 63u, 64u}) {
      if (!key_bits_problem(e, bits, s.params()).empty()) continue;
      const auto keys = encode_on_host(e, bits, s, rays);
      std::size_t bad = 0, first = 0;
      for (std::size_t i = 0; i < rays.size(); ++i)
        if (keys[i] != ref::key(e, bits, s, rays[i]) && bad++ == 0) first = i;
      EXPECT_EQ(bad, 0u) << encoder_name(e) << "/" << bits << " first mismatch at ray " << first << ": "
                         << std::hex << keys[first] << " vs reference " << ref::key(e, bits, s, rays[first]);
      // The device at every width too: cut groups whose last group is full, more than half full or
      // at most half full (the device tests that one eight lanes wide, keys.h rs_cut_bits).
      expect_device_equals_host(dev, e, bits, rays, "edge rays");
    }
  }
  expect_all_encoders_bit_exact(dev, rays, "edge rays");  // PPC and NoSort too
}

// The row-based codes (MLHCC's and mlhcc-cost's low level, hcc-region's regions) test a whole row
// of cut boxes and keep the bits of the row's own boxes (cl/keys_cut.h, rs_row_kept). In a scene
// too small to fill hcc-region's rows, the unused lanes are zero boxes, which a ray starting at the
// origin overlaps: its keys must still be the bitwise reference's, on the host and the device.
TEST(Encode, ShortRowsKeepOnlyTheirOwnBoxes) {
  Scene scene;
  Mesh m;
  for (int i = 0; i < 24; ++i) {  // 24 triangles on a 4 x 6 grid around the origin
    const float x = static_cast<float>(i % 4) - 2.0f, y = static_cast<float>(i / 4) - 3.0f, z = 0.1f * static_cast<float>(i % 3);
    const auto b = static_cast<std::uint32_t>(m.positions.size());
    m.positions.push_back({x, y, z});
    m.positions.push_back({x + 0.9f, y, z + 0.2f});
    m.positions.push_back({x, y + 0.9f, z - 0.2f});
    m.triangles.push_back({b, b + 1, b + 2});
  }
  scene.meshes.push_back(m);
  Bvh bvh = build_bvh(scene.flatten());
  const Aabb box = bvh.bounds();
  for (unsigned r : {0u, 2u}) {
    EncoderParams p;
    p.region_bits = r;
    DeviceEncoder dev(testing::runtime(), bvh, box, p);
    const EncodeScene& s = dev.scene();
    std::vector<RsRay> rays = edge_rays(s, box, 500);
    for (const auto& d : std::vector<std::array<float, 3>>{{1, 0, 0}, {0, -1, 0}, {0.3f, 0.4f, -1}, {-1, -1, -1}})
      for (float tmax : {RS_T_FAR, 0.5f}) rays.push_back(ray(0, 0, 0, d[0], d[1], d[2], tmax));
    for (unsigned bits : {32u, 64u}) {
      // The precondition: hcc-region has rows shorter than their width here. (MLHCC's top nodes have
      // at least as many leaves as a row has boxes, so its rows are full; for it and mlhcc-cost the
      // kept bits matter to rays that hit no top node, whose low bits are 0.)
      const auto& counts = region_inputs(s, bits).counts;
      ASSERT_TRUE(std::any_of(counts.begin(), counts.end(), [&](rs_u32 n) { return n < bits - r; })) << bits;
      for (Encoder e : {Encoder::MLHCC, Encoder::MLHCC_COST, Encoder::HCC_REGION}) {
        const std::string what = std::string(encoder_name(e)) + "/" + std::to_string(bits) + " r " + std::to_string(r);
        const auto keys = encode_on_host(e, bits, s, rays);
        std::size_t bad = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) bad += keys[i] != ref::key(e, bits, s, rays[i]);
        EXPECT_EQ(bad, 0u) << what;
        expect_device_equals_host(dev, e, bits, rays, what);
      }
    }
  }
}

// HCC_DIR runs on the device in two passes (direction bits, then the box bits ORed in) when it has
// more than one direction bit, in one pass when d ≤ 1 (d = 1: the bit from the signs of dx and dy,
// rs_direction_top_bit); either way the keys equal the host twin's and the bitwise
// reference, for d from 0 to 12 and every key length that leaves room for a box field.
TEST(Encode, HccDirPassesMatchTheHostForEveryDirectionWidth) {
  Scene scene = load_scene("detail-room");
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  const Aabb box = bvh.bounds();
  for (unsigned d : {0u, 1u, 5u, 12u}) {
    EncoderParams p;
    p.direction_bits = d;
    DeviceEncoder dev(testing::runtime(), bvh, box, p);
    const std::vector<RsRay> rays = edge_rays(dev.scene(), box, 4000);
    for (unsigned bits : {8u, 16u, 33u, 64u}) {
      if (!key_bits_problem(Encoder::HCC_DIR, bits, p).empty()) continue;
      expect_device_equals_host(dev, Encoder::HCC_DIR, bits, rays, "d = " + std::to_string(d));
      const auto keys = encode_on_host(Encoder::HCC_DIR, bits, dev.scene(), rays);
      for (std::size_t i = 0; i < rays.size(); ++i)
        ASSERT_EQ(keys[i], ref::key(Encoder::HCC_DIR, bits, dev.scene(), rays[i])) << "d " << d << " bits " << bits;
    }
  }
}

// rs_cut_bits on the device, in each of its forms: the hit mask shifted into place (RS_MASK16_BITS 1,
// what PoCL builds on an AVX-512 CPU), one vmovmskps per eight lanes (2, an AVX2 CPU's; forced here
// with -DRS_AVX_MASK_BITS on an x86 CPU device) and the portable AND-and-fold of the lanes (0: GPUs,
// other CPUs; forced with -DRS_PORTABLE_MASK_BITS), against the host's, for group counts with a full,
// a more-than-half and an at-most-half last group, placed from the top of the code and from a first
// bit below it.
TEST(Encode, DeviceCutBitsInEveryFormEqualTheHost) {
  Runtime& rt = testing::runtime();
  const std::string src = kernel_source("cl/keys_cut.h") + R"(
__kernel void cut_bits(__global const RsCutGroup* g, uint n, uint first_bit, __global const RsRay* rays,
                       __global ulong* out, __global int* mask_form) {
  const uint i = get_global_id(0);
  const RsCutRay c = rs_cut_ray(rs_prepare_ray(rays[i]));
  out[i] = rs_cut_bits_g(&c, g, n, first_bit);
  if (i == 0) *mask_form = RS_MASK16_BITS;
}
)";
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<RsRay> rays;
  for (int k = 0; k < 1024; ++k)
    rays.push_back(ray(u(rng), u(rng), u(rng), u(rng), u(rng), k % 7 == 0 ? 0.0f : u(rng), k % 3 ? RS_T_FAR : 0.5f));
  cl::Buffer ray_buf = rt.upload("rays", rays);
  int forms_seen[3] = {0, 0, 0};
  const bool x86_cpu = rt.info().is_pocl() && rt.info().type == "CPU";
  for (const char* options : {"", "-DRS_PORTABLE_MASK_BITS", "-DRS_AVX_MASK_BITS"}) {
    if (std::string(options) == "-DRS_AVX_MASK_BITS" && !x86_cpu) continue;
    cl::Program program = rt.build_source(src, "cut_bits.cl", options);
    for (rs_u32 n : {1u, 7u, 8u, 9u, 16u, 17u, 24u, 25u, 40u, 63u, 64u}) {
      std::vector<RsBox> boxes(n);
      for (RsBox& b : boxes)
        for (int a = 0; a < 3; ++a) {
          const float x = u(rng), y = u(rng);
          b.bmin[a] = std::min(x, y), b.bmax[a] = std::max(x, y);
        }
      for (rs_u32 first : {0u, (64u - n) / 2u, 64u - n}) {
        const auto groups = rs_cut_groups(boxes.data(), boxes.size());
        cl::Buffer group_buf = rt.upload("cut groups", groups);
        cl::Buffer out = rt.buffer("codes", rays.size() * sizeof(rs_u64));
        cl::Buffer form = rt.buffer("mask form", sizeof(int));
        cl_call("cut_bits", [&] {
          cl::Kernel k(program, "cut_bits");
          k.setArg(0, group_buf);
          k.setArg(1, n);
          k.setArg(2, first);
          k.setArg(3, ray_buf);
          k.setArg(4, out);
          k.setArg(5, form);
          rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(rays.size()), cl::NDRange(64));
        });
        std::vector<rs_u64> codes;
        std::vector<int> f;
        rt.download("codes", out, codes, rays.size());
        rt.download("mask form", form, f, 1);
        ASSERT_TRUE(f[0] >= 0 && f[0] <= 2) << "RS_MASK16_BITS " << f[0];
        forms_seen[f[0]] = 1;
        std::size_t bad = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
          const RsCutRay c = rs_cut_ray(rs_prepare_ray(rays[i]));
          const rs_u64 host = rs_cut_bits_p(&c, groups.data(), n, first);
          if (codes[i] != host && bad++ == 0)
            ADD_FAILURE() << "options '" << options << "' n " << n << " first bit " << first << " ray " << i
                          << ": device " << std::hex << codes[i] << " host " << host;
        }
        EXPECT_EQ(bad, 0u) << "options '" << options << "' n " << n << " first bit " << first;
      }
    }
  }
  EXPECT_EQ(forms_seen[0], 1) << "the portable form was not built";
#if defined(__x86_64__) && defined(__GNUC__)
  // PoCL compiles for the host CPU: with AVX-512 (F and DQ) it must take the mask-bits form.
  if (rt.info().is_pocl() && rt.info().type == "CPU" && __builtin_cpu_supports("avx512f") &&
      __builtin_cpu_supports("avx512dq")) {
    EXPECT_EQ(forms_seen[1], 1) << "PoCL on this AVX-512 CPU should build the mask-bits form";
  }
  if (x86_cpu && __builtin_cpu_supports("avx")) {
    EXPECT_EQ(forms_seen[2], 1) << "the AVX form was not built";
  }
#endif
}

// HCC_DIR's single direction bit read from the signs of dx and dy (rs_direction_top_bit) is the
// definition's, rs_direction_bits(r, 1), φ ≥ ½: on both sides of the +x axis where φ = atan2/2π + ½
// rounds up to ½ (|dy|/dx from 2^-34 to 2^-10, densely, across 2^-19, the shortcut's bound), at
// magnitudes from denormal to 2^60 (past the shortcut's 2^±40 and 2^-80 guards), with ±0, inf and
// NaN components; and the kernel gives the host's HCC_DIR keys on the same rays.
TEST(Encode, DirectionTopBitIsTheDefinitions) {
  std::vector<RsRay> rays;
  std::vector<float> scales = {0x1p-140f, 0x1p-126f, 0x1p-90f, 0x1p-81f, 0x1p-80f, 0x1p-79f, 0x1p-41f, 0x1p-40f,
                               0x1p-39f,  1e-20f,    0.001f,   0.7f,     1.0f,     3.0f,     0x1p39f,  0x1p40f,
                               0x1p41f,   0x1p60f};
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t ones = 0, zeros = 0, near_axis_ones = 0, near_axis_zeros = 0;
  for (float sx : scales)
    for (float z : {0.0f, -0.0f, 1.0f, -0x1p-100f, 0x1p50f}) {
      // Around the +x axis: dy = −ratio·dx, ratio from 2^-34 to 2^-10 (and the same above the axis).
      for (int k = 0; k <= 2400; ++k) {
        const float ratio = std::ldexp(1.0f, -34) * std::pow(2.0f, k / 100.0f);
        rays.push_back(ray(0, 0, 0, sx, -ratio * sx, z));
        rays.push_back(ray(0, 0, 0, sx, ratio * sx, z));
      }
      // The shortcut's bound itself, a few ulps either side.
      float b = 0x1p-19f * sx;
      for (int k = 0; k < 4; ++k) b = std::nextafter(b, 0.0f);
      for (int k = 0; k < 8; ++k, b = std::nextafter(b, inf)) rays.push_back(ray(0, 0, 0, sx, -b, z));
      // Every sign of x, ±0, tiny and huge dy, inf and NaN.
      for (float x : {sx, -sx, 0.0f, -0.0f, 0x1p-149f, -0x1p-149f, inf, -inf, nan})
        for (float y : {sx, -sx, 0.0f, -0.0f, -0x1p-149f, -0x1p-130f, -0x1p-80f, -0x1p60f, -inf, nan})
          rays.push_back(ray(0, 0, 0, x, y, z));
    }
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < 20000; ++i) rays.push_back(ray(0, 0, 0, u(rng), u(rng), u(rng)));
  std::size_t bad = 0;
  for (const RsRay& r : rays) {
    const rs_u64 fast = rs_direction_top_bit(r), def = rs_direction_bits(r, 1u);
    if (fast != def && bad++ < 5)
      ADD_FAILURE() << "d = (" << r.d[0] << ", " << r.d[1] << ", " << r.d[2] << "): " << fast << " vs definition "
                    << def;
    (def ? ones : zeros)++;
    const bool near_axis = r.d[0] > 0 && r.d[1] < 0 && -r.d[1] < 0x1p-19f * r.d[0];
    if (near_axis) (def ? near_axis_ones : near_axis_zeros)++;
  }
  EXPECT_EQ(bad, 0u);
  // The rays straddle the boundary: both results occur, also just below the +x axis.
  EXPECT_GT(ones, 1000u);
  EXPECT_GT(zeros, 1000u);
  EXPECT_GT(near_axis_ones, 100u);
  EXPECT_GT(near_axis_zeros, 100u);

  Scene scene = load_scene("detail-room");
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  DeviceEncoder dev(testing::runtime(), bvh, bvh.bounds());
  std::vector<RsRay> finite;
  for (const RsRay& r : rays)
    if (std::isfinite(r.d[0]) && std::isfinite(r.d[1]) && std::isfinite(r.d[2])) finite.push_back(r);
  for (unsigned bits : {16u, 64u}) expect_device_equals_host(dev, Encoder::HCC_DIR, bits, finite, "near-axis rays");
}

// Cut groups: the sixteen-box test (near and far planes picked by the sign of 1/d) gives each box's
// scalar min/max slab test at the box's code bit, for box counts that do not fill the last group,
// from the top of the code and below a first bit; missing lanes never set bits.
// Also the box-set code (rs_box_set_code) on the same groups. The boxes are random, some flat;
// some rays are axis-parallel or start on a box corner, some segments are short.
TEST(Encode, CutGroupsMatchTheScalarSlabTest) {
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (rs_u32 n : {1u, 5u, 8u, 13u, 31u, 32u, 57u, 64u}) {
    std::vector<RsBox> boxes(n);
    for (RsBox& b : boxes)
      for (int a = 0; a < 3; ++a) {
        const float x = u(rng), y = u(rng);
        b.bmin[a] = std::min(x, y), b.bmax[a] = a == 2 && u(rng) < 0 ? b.bmin[a] : std::max(x, y);  // some flat
      }
    const auto groups = rs_cut_groups(boxes.data(), boxes.size());
    ASSERT_EQ(groups.size(), (n + 15) / 16);
    const rs_u32 first = 64 - n;  // the boxes' bits at the bottom of the code
    const auto& low_groups = groups;
    for (int k = 0; k < 2000; ++k) {
      RsRay r = ray(u(rng), u(rng), u(rng), u(rng), u(rng), k % 7 == 0 ? 0.0f : u(rng), k % 3 ? RS_T_FAR : 0.5f);
      if (k % 11 == 0) std::memcpy(r.o, boxes[k % n].bmin, sizeof r.o);  // on a box corner
      const RsTraversalRay tr = rs_prepare_ray(r);
      const RsCutRay c = rs_cut_ray(tr);
      rs_u64 expect = 0;
      for (rs_u32 i = 0; i < n; ++i)
        if (rs_segment_overlaps_box(tr, boxes[i])) expect |= rs_u64(1) << (63u - i);
      ASSERT_EQ(rs_cut_bits_p(&c, groups.data(), n, 0), expect) << "n " << n << " ray " << k;
      ASSERT_EQ(rs_cut_bits_p(&c, low_groups.data(), n, first), expect >> first)
          << "n " << n << " ray " << k;
      ASSERT_EQ(rs_box_set_code(r, groups.data(), n, n, 0), expect) << "n " << n << " ray " << k;
    }
  }
  // The sign-picked test needs lo <= hi: an empty or NaN box is refused, not silently mis-tested.
  RsBox empty{{0, 0, 1}, {1, 1, 0}}, nan{{0, 0, 0}, {1, std::nanf(""), 1}};
  EXPECT_THROW(rs_cut_groups(&empty, 1), Error);
  EXPECT_THROW(rs_cut_groups(&nan, 1), Error);
}

// ---------------------------------------------------------------------------------------------
// Beyond the paper (issue 21): hcc-region and hcc-traffic.
// ---------------------------------------------------------------------------------------------

TEST(Encode, NewEncoderKnobsAreValidated) {
  EncoderParams p;
  EXPECT_EQ(p.region_bits, 4u);
  EXPECT_EQ(p.traffic_blend, 0.5);
  EXPECT_EQ(key_bits_problem(Encoder::HCC_REGION, 16, p), "");
  EXPECT_NE(key_bits_problem(Encoder::HCC_REGION, 4, p).find("more than 4 bits"), std::string::npos);
  p.region_bits = 0;
  EXPECT_EQ(key_bits_problem(Encoder::HCC_REGION, 1, p), "");
  p.region_bits = kMaxRegionBits;
  EXPECT_EQ(key_bits_problem(Encoder::HCC_REGION, 64, p), "");
  p.region_bits = kMaxRegionBits + 1;
  EXPECT_NE(key_bits_problem(Encoder::HCC_REGION, 64, p).find("0 to 8 region bits"), std::string::npos);
  EXPECT_EQ(key_bits_problem(Encoder::HCC, 64, p), "");  // the knob is hcc-region's only
  for (double beta : {0.0, 0.25, 1.0}) {
    p.traffic_blend = beta;
    EXPECT_EQ(key_bits_problem(Encoder::HCC_TRAFFIC, 32, p), "") << beta;
  }
  for (double beta : {-0.1, 1.5, std::nan("")}) {
    p.traffic_blend = beta;
    EXPECT_NE(key_bits_problem(Encoder::HCC_TRAFFIC, 32, p).find("from 0 (HAD only) to 1"), std::string::npos) << beta;
  }
  EXPECT_THROW(check_key_bits(Encoder::HCC_TRAFFIC, 32, p), Error);
}

namespace {
struct DetailRoom {
  Bvh bvh;
  Aabb box;
  std::vector<ReferencedBatch> batches;
};
const DetailRoom& detail_room() {
  static const DetailRoom d = [] {
    SceneOptions opts;
    opts.frame = {64, 36, 1};
    PreparedScene p = prepare_scene("detail-room", opts);
    DetailRoom r;
    r.batches = generate_batches(p.scene, p.tris, p.bvh, {});
    r.bvh = std::move(p.bvh);
    r.box = r.bvh.bounds();
    return r;
  }();
  return d;
}

// hcc-region's keys on `rays` and on every batch of the detail room: kernel == host twin, and the
// host's keys on `rays` == the bitwise reference (ref::key).
void expect_region_keys_exact(DeviceEncoder& dev, unsigned bits, const std::vector<RsRay>& rays, const std::string& what) {
  expect_device_equals_host(dev, Encoder::HCC_REGION, bits, rays, what);
  for (const auto& rb : detail_room().batches) expect_device_equals_host(dev, Encoder::HCC_REGION, bits, rb.batch.rays, what);
  const auto keys = encode_on_host(Encoder::HCC_REGION, bits, dev.scene(), rays);
  for (std::size_t i = 0; i < rays.size(); ++i)
    ASSERT_EQ(keys[i], ref::key(Encoder::HCC_REGION, bits, dev.scene(), rays[i])) << what << " bits " << bits;
}
}  // namespace

// hcc-region without statistics: 2^r regions (each split halves its cell); each region's cut nodes
// all overlap it, are at most b − r and in descending HAD; a ray from inside region k has k in its
// top r bits, so rays from different regions get different top bits; with r = 0 the keys are HCC's.
TEST(Encode, RegionKeysStartWithTheOriginsRegion) {
  const DetailRoom& d = detail_room();
  for (unsigned r : {1u, 3u, 5u}) {
    EncoderParams p;
    p.region_bits = r;
    EncodeScene s(d.bvh, d.box, p);
    for (unsigned bits : kBits) {
      const auto& g = region_inputs(s, bits);
      ASSERT_EQ(g.boxes.size(), 1u << r);
      ASSERT_EQ(g.cuts.size(), 1u << r);
      EXPECT_EQ(g.groups.size(), (std::size_t(1) << r) * ((bits - r + 15) / 16));
      std::set<rs_u64> tops;
      for (std::size_t k = 0; k < g.boxes.size(); ++k) {
        const auto& cut = g.cuts[k];
        EXPECT_LE(cut.size(), bits - r);
        EXPECT_GT(cut.size(), 0u);
        EXPECT_EQ(g.counts[k], cut.size());
        for (std::size_t i = 0; i < cut.size(); ++i) {
          EXPECT_TRUE(boxes_overlap(node_box(d.bvh.nodes[cut[i]]), g.boxes[k])) << "region " << k << " node " << cut[i];
          if (i > 0) {
            EXPECT_GE(s.had()[cut[i - 1]], s.had()[cut[i]]);
          }
        }
        // No node twice, and no node below another one of the same cut.
        const std::set<std::uint32_t> unique(cut.begin(), cut.end());
        EXPECT_EQ(unique.size(), cut.size());
        const Aabb& c = g.boxes[k];
        const RsRay from_centre = ray(0.5f * (c.min[0] + c.max[0]), 0.5f * (c.min[1] + c.max[1]),
                                      0.5f * (c.min[2] + c.max[2]), 0.3f, -0.5f, 0.8f);
        const std::uint64_t key = key1(Encoder::HCC_REGION, bits, s, from_centre);
        EXPECT_EQ(key >> (bits - r), k) << "r " << r << " bits " << bits;
        tops.insert(key >> (bits - r));
      }
      EXPECT_EQ(tops.size(), g.boxes.size());
    }
  }
  // One region: HCC.
  EncoderParams p0;
  p0.region_bits = 0;
  EncodeScene s0(d.bvh, d.box, p0);
  for (unsigned bits : kBits) {
    EXPECT_EQ(region_inputs(s0, bits).cuts.at(0), s0.hcc_cut(bits));
    for (const auto& rb : d.batches)
      EXPECT_EQ(encode_on_host(Encoder::HCC_REGION, bits, s0, rb.batch.rays),
                encode_on_host(Encoder::HCC, bits, s0, rb.batch.rays))
          << rb.batch.name << " " << bits;
  }
}

// hcc-region's kernel equals the host twin for region counts 1 to 256, key lengths whose cut rows
// end in a full, a more-than-half and an at-most-half group, on edge rays and every batch.
TEST(Encode, RegionKernelMatchesTheHostForEveryRegionWidth) {
  const DetailRoom& d = detail_room();
  for (unsigned r : {0u, 1u, 4u, 8u}) {
    EncoderParams p;
    p.region_bits = r;
    DeviceEncoder dev(testing::runtime(), d.bvh, d.box, p);
    const std::vector<RsRay> rays = edge_rays(dev.scene(), d.box, 3000);
    for (unsigned bits : {9u, 16u, 25u, 32u, 33u, 50u, 64u}) {
      if (!key_bits_problem(Encoder::HCC_REGION, bits, p).empty()) continue;
      ASSERT_NO_FATAL_FAILURE(expect_region_keys_exact(dev, bits, rays, "r = " + std::to_string(r)));
    }
  }
}

// hcc-region's kernel finds a ray's region by testing the split tree's leaves as cells
// (cl/keys_cut.h, RsRegionCells) instead of walking the tree: the two agree for every origin, on
// the host and in the kernel. Trees: halving, and random ones whose splits may fall outside their
// cell (leaves no origin reaches) or repeat an axis; origins on every split plane and a float on
// either side, ±0, ±∞, NaN and the largest floats in each coordinate, and random ones.
TEST(Encode, RegionCellsAreTheWalk) {
  const DetailRoom& d = detail_room();
  std::mt19937 rng(2026);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN(),
              big = std::numeric_limits<float>::max();
  const std::vector<float> specials = {0.0f, -0.0f, inf, -inf, nan, big, -big, 1e-40f, -1e-40f};
  auto origins_for = [&](const std::vector<RsRegionSplit>& splits) {
    std::vector<std::array<float, 3>> points;
    for (const RsRegionSplit& sp : splits)
      for (float at : {sp.at, std::nextafter(sp.at, -inf), std::nextafter(sp.at, inf)}) {
        std::array<float, 3> p{u(rng), u(rng), u(rng)};
        p[sp.axis] = at;
        points.push_back(p);
        for (const RsRegionSplit& other : splits) {  // on two planes at once
          std::array<float, 3> q = p;
          if (other.axis != sp.axis) q[other.axis] = other.at, points.push_back(q);
        }
      }
    for (float a : specials)
      for (int axis = 0; axis < 3; ++axis) {
        std::array<float, 3> p{u(rng), u(rng), u(rng)};
        p[axis] = a;
        points.push_back(p);
        points.push_back({a, a, a});
      }
    for (int i = 0; i < 2000; ++i) points.push_back({u(rng), u(rng), u(rng)});
    return points;
  };
  auto random_splits = [&](unsigned r) {
    std::vector<RsRegionSplit> splits((std::size_t{1} << r) - 1);
    for (RsRegionSplit& sp : splits) {
      sp.axis = static_cast<rs_u32>(rng() % 3);
      sp.at = rng() % 4 == 0 ? 0.5f : u(rng);  // some ties between splits
    }
    return splits;
  };
  const Aabb unit{{-1, -1, -1}, {1, 1, 1}};
  std::size_t checked = 0;
  for (unsigned r = 0; r <= kMaxRegionBits; ++r)
    for (const auto& splits : {median_region_splits(unit, {}, r), random_splits(r), random_splits(r)}) {
      const std::vector<RsRegionCells> cells = region_cells(splits, r);
      ASSERT_EQ(cells.size(), rs_region_cell_groups(r));
      for (const auto& o : origins_for(splits)) {
        const RsRay x = ray(o[0], o[1], o[2], 1, 0, 0);
        ASSERT_EQ(rs_region_in_cells(cells.data(), r, x), rs_region_of(splits.data(), r, x))
            << "r " << r << " origin " << o[0] << " " << o[1] << " " << o[2];
        ++checked;
      }
    }
  EXPECT_GT(checked, 50000u);

  // The kernel: the key's top r bits are the walk's region, for the same trees and origins.
  for (unsigned r : {1u, 4u, 5u, 8u}) {
    EncoderParams p;
    p.region_bits = r;
    DeviceEncoder dev(testing::runtime(), d.bvh, d.box, p);
    RegionStatistics stats;
    stats.splits = random_splits(r);
    stats.visits.resize(std::size_t{1} << r);  // no traffic: every region gets HCC's cut
    set_region_statistics(dev.scene(), stats);
    std::vector<RsRay> rays;
    for (const auto& o : origins_for(stats.splits)) rays.push_back(ray(o[0], o[1], o[2], 0.6f, -0.8f, 0));
    for (unsigned bits : {32u, 64u}) {
      const auto run = dev.run(Encoder::HCC_REGION, bits, rays);
      std::size_t bad = 0;
      for (std::size_t i = 0; i < rays.size(); ++i)
        bad += (run.keys[i] >> (bits - r)) != rs_region_of(stats.splits.data(), r, rays[i]);
      EXPECT_EQ(bad, 0u) << "r " << r << " bits " << bits << " of " << rays.size() << " rays";
      // Where the origin is finite, the whole key is the host twin's.
      std::vector<RsRay> finite;
      for (const RsRay& x : rays)
        if (std::isfinite(x.o[0]) && std::isfinite(x.o[1]) && std::isfinite(x.o[2])) finite.push_back(x);
      expect_device_equals_host(dev, Encoder::HCC_REGION, bits, finite, "cells, r = " + std::to_string(r));
    }
  }

  // A split tree the cells cannot hold is refused, naming the split.
  for (const RsRegionSplit bad : {RsRegionSplit{nan, 0}, RsRegionSplit{inf, 1}, RsRegionSplit{0.0f, 3}}) {
    std::vector<RsRegionSplit> splits = median_region_splits(unit, {}, 2);
    splits[2] = bad;
    try {
      region_cells(splits, 2);
      ADD_FAILURE() << "accepted split " << bad.at << " on axis " << bad.axis;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("region split 2"), std::string::npos) << e.what();
    }
    EncoderParams p;
    p.region_bits = 2;
    EncodeScene s(d.bvh, d.box, p);
    RegionStatistics stats;
    stats.splits = splits;
    stats.visits.resize(4);
    EXPECT_THROW(set_region_statistics(s, stats), Error);
  }
  EXPECT_THROW(region_cells(median_region_splits(unit, {}, 2), 3), Error);  // too few splits
}

// hcc-region with a previous frame's statistics: the splits put half of the sample's origins on
// each side (up to ties), each region's cut is the HAD/traffic priority cut of the traffic of the
// rays that start in it (HCC's cut for a region none starts in), and the kernel equals the host twin
// and the bottom-up reference. Statistics of the wrong shape are refused.
TEST(Encode, RegionsFromAPreviousFrameSplitAtMedianOriginsAndCutByTraffic) {
  const DetailRoom& d = detail_room();
  const auto& sample = d.batches.back();  // the deepest bounce: origins spread over the room
  ASSERT_GT(sample.batch.size(), 100u);
  const std::vector<RsRay>& rays = sample.batch.rays;
  for (unsigned r : {0u, 2u, 3u}) {
    EncoderParams p;
    p.region_bits = r;
    DeviceEncoder dev(testing::runtime(), d.bvh, d.box, p);
    RegionStatistics stats;
    stats.splits = median_region_splits(d.box, rays, r);
    ASSERT_EQ(stats.splits.size(), (1u << r) - 1u);
    std::vector<std::vector<RsRay>> starting_in(1u << r);
    for (const RsRay& x : rays) starting_in[rs_region_of(stats.splits.data(), r, x)].push_back(x);
    std::size_t fewest = rays.size(), most = 0;
    for (const auto& group : starting_in) fewest = std::min(fewest, group.size()), most = std::max(most, group.size());
    EXPECT_LE(most - fewest, std::size_t{1} << r) << "r " << r;  // medians: equal shares up to one per split
    std::vector<std::vector<std::uint64_t>> dense;
    for (std::size_t k = 0; k < starting_in.size(); ++k) {
      // Region 0 gets no traffic in this test: a region no ray started in.
      dense.push_back(k == 0 && r > 0 ? std::vector<std::uint64_t>{} : node_traffic(d.bvh, starting_in[k], sample.batch.any_hit()));
      std::vector<std::pair<std::uint32_t, std::uint64_t>> sparse;
      for (std::size_t n = 0; n < dense.back().size(); ++n)
        if (dense.back()[n]) sparse.emplace_back(static_cast<std::uint32_t>(n), dense.back()[n]);
      stats.visits.push_back(sparse);
    }
    set_region_statistics(dev.scene(), stats);
    for (unsigned bits : {16u, 32u, 64u}) {
      const auto& g = region_inputs(dev.scene(), bits);
      for (std::size_t k = 0; k < starting_in.size(); ++k) {
        const std::vector<double> priority = traffic_priority(dev.scene().had(), dense[k], p.traffic_blend);
        EXPECT_EQ(g.cuts[k], priority_cut(d.bvh, priority, bits - r, 0, &dev.scene().had())) << "r " << r << " region " << k;
      }
      if (r > 0) {
        EXPECT_EQ(g.cuts[0], dev.scene().hcc_cut(bits - r));
      }
      const std::vector<RsRay> edges = edge_rays(dev.scene(), d.box, 1000);
      ASSERT_NO_FATAL_FAILURE(expect_region_keys_exact(dev, bits, edges, "with statistics, r = " + std::to_string(r)));
    }
    // Clearing the statistics returns to the halved cells and HAD's region cuts.
    set_region_statistics(dev.scene(), RegionStatistics{});
    EncodeScene plain(d.bvh, d.box, p);
    EXPECT_EQ(region_inputs(dev.scene(), 32).cuts, region_inputs(plain, 32).cuts);
  }
  EncoderParams p;
  p.region_bits = 2;
  EncodeScene s(d.bvh, d.box, p);
  RegionStatistics wrong;
  wrong.splits = median_region_splits(d.box, rays, 3);
  wrong.visits.resize(8);
  EXPECT_THROW(set_region_statistics(s, wrong), Error);  // 8 regions for a 4-region code
  RegionStatistics outside;
  outside.splits = median_region_splits(d.box, rays, 2);
  outside.visits.resize(4);
  outside.visits[1].emplace_back(static_cast<std::uint32_t>(d.bvh.nodes.size()), 1);
  EXPECT_THROW(set_region_statistics(s, outside), Error);  // a node the BVH does not have
}

// Node traffic: the root's count is the rays entering the scene box, and no node is entered by more
// rays than its parent; the order of the rays does not matter.
TEST(Encode, NodeTrafficCountsTheRaysEnteringEachNode) {
  const DetailRoom& d = detail_room();
  for (const auto& rb : d.batches) {
    const auto visits = node_traffic(d.bvh, rb.batch.rays, rb.batch.any_hit());
    ASSERT_EQ(visits.size(), d.bvh.nodes.size());
    std::uint64_t entering = 0;
    for (const RsRay& r : rb.batch.rays) {
      int hit = 0;
      rs_intersect_box_unfused(rs_prepare_ray(r), &d.bvh.nodes[0], r.tmax, &hit);  // node_traffic's box test
      entering += hit != 0;
    }
    EXPECT_EQ(visits[0], entering) << rb.batch.name;
    EXPECT_GT(visits[0], 0u) << rb.batch.name;
    for (std::uint32_t n = 0; n < d.bvh.nodes.size(); ++n) {
      if (d.bvh.is_leaf(n)) continue;
      for (std::uint32_t c = d.bvh.nodes[n].first; c < d.bvh.nodes[n].first + 2; ++c) {
        ASSERT_LE(visits[c], visits[n]);
      }
    }
    std::vector<RsRay> reversed(rb.batch.rays.rbegin(), rb.batch.rays.rend());
    EXPECT_EQ(node_traffic(d.bvh, reversed, rb.batch.any_hit()), visits) << rb.batch.name;
  }
}

// hcc-traffic: without traffic, or with β = 0, its cut is HCC's and so are its keys; with traffic and
// β = 1 its cut is in descending traffic (ties by HAD) and is a valid cut; the kernel equals the
// host twin for the cut of every batch's traffic, and setting new traffic changes the device's cut.
TEST(Encode, TrafficCutBlendsHadWithTheTraffic) {
  const DetailRoom& d = detail_room();
  const auto& frame = d.batches;
  ASSERT_GE(frame.size(), 3u);
  const std::vector<std::uint64_t> visits = node_traffic(d.bvh, frame[0].batch.rays, frame[0].batch.any_hit());
  for (unsigned bits : kBits) {
    EncoderParams p0;
    p0.traffic_blend = 0.0;
    EncodeScene s0(d.bvh, d.box, p0);
    EXPECT_EQ(traffic_cut(s0, bits), s0.hcc_cut(bits));  // no traffic yet
    set_node_traffic(s0, visits);
    EXPECT_EQ(traffic_cut(s0, bits), s0.hcc_cut(bits)) << "beta = 0";
    EXPECT_EQ(encode_on_host(Encoder::HCC_TRAFFIC, bits, s0, frame[1].batch.rays),
              encode_on_host(Encoder::HCC, bits, s0, frame[1].batch.rays));

    EncoderParams p1;
    p1.traffic_blend = 1.0;
    EncodeScene s1(d.bvh, d.box, p1);
    set_node_traffic(s1, visits);
    const auto& cut = traffic_cut(s1, bits);
    EXPECT_EQ(validate_cut(d.bvh, cut), "") << bits;
    for (std::size_t i = 1; i < cut.size(); ++i) {
      const auto a = visits[cut[i - 1]], b = visits[cut[i]];
      EXPECT_TRUE(a > b || (a == b && s1.had()[cut[i - 1]] >= s1.had()[cut[i]])) << "bit " << i;
    }
    EXPECT_NE(cut, s1.hcc_cut(bits)) << "detail-room's traffic should move some cut node, " << bits << " bits";
  }
  for (double beta : {0.5, 1.0}) {
    EncoderParams p;
    p.traffic_blend = beta;
    DeviceEncoder dev(testing::runtime(), d.bvh, d.box, p);
    for (std::size_t k = 0; k < frame.size(); ++k) {
      set_node_traffic(dev.scene(), k == 0 ? std::vector<std::uint64_t>{}
                                  : node_traffic(d.bvh, frame[k - 1].batch.rays, frame[k - 1].batch.any_hit()));
      const std::string what = "beta " + std::to_string(beta) + " " + frame[k].batch.name;
      for (unsigned bits : {16u, 32u, 33u, 64u}) {
        expect_device_equals_host(dev, Encoder::HCC_TRAFFIC, bits, frame[k].batch.rays, what);
        const auto keys = encode_on_host(Encoder::HCC_TRAFFIC, bits, dev.scene(), frame[k].batch.rays);
        for (std::size_t i = 0; i < keys.size(); ++i)
          ASSERT_EQ(keys[i], ref::key(Encoder::HCC_TRAFFIC, bits, dev.scene(), frame[k].batch.rays[i])) << what;
      }
    }
  }
  EncodeScene s(d.bvh, d.box);
  EXPECT_THROW(set_node_traffic(s, std::vector<std::uint64_t>(3, 1)), Error);  // not one count per node
}


// mlhcc-cost (issue 21): the octahedral direction cells of the axes and of ±0 components, worked out
// by hand (levels = 3: cells 0..7 per side, u in the high bits).
TEST(Encode, OctahedralCellsOfTheAxes) {
  auto cell = [](float x, float y, float z) { return rs_octahedral_cell(ray(0, 0, 0, x, y, z), 3); };
  EXPECT_EQ(cell(0, 0, 1), 4u * 8u + 4u);    // the upper pole: the centre (u = v = 0 -> 0.5)
  EXPECT_EQ(cell(0, 0, -1), 7u * 8u + 7u);   // the lower pole: folded to the corner (1, 1)
  EXPECT_EQ(cell(1, 0, 0), 7u * 8u + 4u);    // u = 1 clamps into the last cell
  EXPECT_EQ(cell(-1, 0, 0), 0u * 8u + 4u);
  EXPECT_EQ(cell(0, -1, 0), 4u * 8u + 0u);
  EXPECT_EQ(cell(3, 0, 0), cell(1, 0, 0));   // the direction need not be unit
  EXPECT_EQ(cell(1, -0.0f, 0), cell(1, 0, 0));
  EXPECT_EQ(cell(-0.0f, -0.0f, -1), cell(0, 0, -1));  // −0 counts as +0, also when folding
  EXPECT_EQ(cell(0, 0, 0), 4u * 8u + 4u);    // a zero direction: the centre
  EXPECT_EQ(cell(0.5f, 0.5f, -1), 7u * 8u + 7u);  // folded: (1 − |v|, 1 − |u|) = (0.75, 0.75)
  EXPECT_EQ(cell(-0.5f, 0.25f, -0.25f), 1u * 8u + 6u);  // folded: (−0.75, 0.5) -> (0.125, 0.75) of [0, 1]
}

// cost_statistics: the mean steps per bin in sixteenths, the origin cell's mean for a bin with no
// rays, the batch's mean for a cell with none; and the quantised table of cost_cut.
TEST(Encode, CostStatisticsMeansAndFallbacks) {
  RsEncodeFrame f{};
  for (int a = 0; a < 3; ++a) f.box_max[a] = 1.0f, f.inv_extent[a] = 1.0f;
  const RsRay up = ray(0.01f, 0.01f, 0.01f, 0, 0, 1), down = ray(0.01f, 0.01f, 0.01f, 0, 0, -1);
  const RsRay far_cell = ray(0.99f, 0.99f, 0.99f, 0, 0, 1);
  const std::vector<RsRay> rays{up, up, down, far_cell};
  const std::vector<std::uint32_t> steps{3, 6, 12, 21};
  const auto mean = cost_statistics(f, rays, steps);
  ASSERT_EQ(mean.size(), RS_COST_BINS);
  EXPECT_EQ(mean[rs_cost_bin(&f, up)], 72u);  // (3 + 6) / 2 steps, in sixteenths
  EXPECT_EQ(mean[rs_cost_bin(&f, down)], 12u * 16u);
  EXPECT_EQ(mean[rs_cost_bin(&f, far_cell)], 21u * 16u);
  // Another direction from the first cell: that cell's mean over its three rays, (3 + 6 + 12) / 3.
  EXPECT_EQ(mean[rs_cost_bin(&f, ray(0.01f, 0.01f, 0.01f, 1, 0, 0))], 7u * 16u);
  // A cell no ray started in: the batch's mean, 42 / 4 steps = 168 sixteenths.
  EXPECT_EQ(mean[rs_cost_bin(&f, ray(0.5f, 0.5f, 0.5f, 0, 0, 1))], 168u);
  EXPECT_THROW(cost_statistics(f, rays, {1, 2}), Error);
  EXPECT_EQ(cost_statistics(f, {}, {}), std::vector<std::uint64_t>(RS_COST_BINS, 0));

  // Quantised for a 32-bit key (4 cost bits by default): mean · 16 / (largest + 1), largest = 21 · 16.
  const DetailRoom& d = detail_room();
  EncodeScene s(d.bvh, d.box);
  EXPECT_EQ(cost_cut_inputs(s, 32).cost, std::vector<rs_u32>(RS_COST_BINS, 0u));  // no estimates: field 0
  set_cost_estimates(s, mean);
  const auto& t = cost_cut_inputs(s, 32);
  EXPECT_EQ(t.split.cost_bits, 4u);
  EXPECT_EQ(t.cost[rs_cost_bin(&f, far_cell)], 336u * 16u / 337u);  // 15: the top of the field
  EXPECT_EQ(t.cost[rs_cost_bin(&f, up)], 72u * 16u / 337u);         // 3
  EXPECT_THROW(set_cost_estimates(s, {1, 2, 3}), Error);
}

// mlhcc-cost's kernel equals the host twin and the bitwise reference with a real table (the
// detail room's previous frame, traced for its step counts), at every key length and cost width;
// the cost field is the table's value for the ray's bin.
TEST(Encode, CostKernelMatchesTheHostWithEstimates) {
  const DetailRoom& d = detail_room();
  SceneOptions opts;
  opts.frame = {64, 36, 1};
  const PreparedScene p = prepare_scene("detail-room", opts);
  RayGenOptions previous;
  previous.seed = 2;
  const auto frame = generate_batches(p.scene, p.tris, p.bvh, previous);
  for (unsigned cost_bits : {0u, 1u, 3u, 12u}) {
    EncoderParams params;
    params.cost_bits = cost_bits;
    DeviceEncoder dev(testing::runtime(), d.bvh, d.box, params);
    for (const auto& rb : d.batches) {
      const auto same = std::find_if(frame.begin(), frame.end(), [&](const ReferencedBatch& b) {
        return b.batch.name == rb.batch.name;
      });
      ASSERT_NE(same, frame.end()) << rb.batch.name;
      std::vector<std::uint32_t> steps;
      trace_reference(p.bvh, same->batch.rays, nullptr, same->batch.any_hit(), &steps);
      set_cost_estimates(dev.scene(), cost_statistics(dev.scene().frame(), same->batch.rays, steps));
      for (unsigned bits : {4u, 16u, 26u, 32u, 50u, 64u}) {
        if (!key_bits_problem(Encoder::MLHCC_COST, bits, params).empty()) continue;
        const std::string what = rb.batch.name + " cost bits " + std::to_string(cost_bits);
        expect_device_equals_host(dev, Encoder::MLHCC_COST, bits, rb.batch.rays, what);
        const auto keys = encode_on_host(Encoder::MLHCC_COST, bits, dev.scene(), rb.batch.rays);
        const CostSplit split = cost_cut_inputs(dev.scene(), bits).split;
        std::size_t nonzero_cost = 0;
        for (std::size_t i = 0; i < keys.size(); ++i) {
          ASSERT_EQ(keys[i], ref::key(Encoder::MLHCC_COST, bits, dev.scene(), rb.batch.rays[i])) << what << " ray " << i;
          // No top node overlapped: no low-level bits either (the cost field stays).
          if ((keys[i] >> (bits - split.top_bits)) == 0) {
            ASSERT_EQ(keys[i] >> split.cost_bits, 0u) << what << " ray " << i;
          }
          const std::uint64_t field = keys[i] & ((std::uint64_t{1} << split.cost_bits) - 1);
          ASSERT_EQ(field, cost_cut_inputs(dev.scene(), bits).cost[rs_cost_bin(&dev.scene().frame(), rb.batch.rays[i])]);
          nonzero_cost += field != 0;
        }
        if (split.cost_bits >= 3) {
          EXPECT_GT(nonzero_cost, 0u) << what << " bits " << bits;
        }
      }
    }
  }
}

}  // namespace raysort
