// The prefix path code (PPC) against the paper's own definition (Xiang et al., section 4.1,
// "Prefix Path Code"; issue 43 item 2), on a hand-built tree whose keys are worked out here bit by
// bit from the paper's sentences, not from the code. The sentences each step follows:
//   [S1] "The traversal path (represented by orange arrows) is recorded, and the prefix path code is
//        formed by setting each bit to 1 if the corresponding node intersection result is true, and 0
//        otherwise."
//   [S2] "This can be achieved by terminating the traversal after a certain number of bits have been
//        set."
//   [S3] "the first four intersection results of the rays are true, true, false, and false, resulting
//        in a 4-bit prefix code of 1100."
//   [S4] "This prefix path code represents the corresponding traversal path through the hierarchy when
//        the rays are forced to traverse the BVH in the same order."
//   [S5] "directly encoding the full BVH traversal path" — the path of the trace itself: a closest-hit
//        traversal, whose segment ends at the nearest hit found so far.
// Where the paper leaves a choice, ours (docs/encoders.md): the root's own test is the first bit; an
// inner node records its two children's tests, left then right, before descending (the Aila-Laine
// loop tests both child boxes of the node it is at); the fixed order of [S4] is left first.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "encode/device_encoder.h"
#include "encode/encode.h"
#include "test_util.h"

namespace raysort {
namespace {

using testing::ray;

// Four leaves in a row along x, in two bands of y (rays run along ±x at z = .25):
//   node 0 root [0,8]×[0,2]×[0,1], children 1 (x ∈ [0,4]) and 2 (x ∈ [4,8]);
//   node 1's leaves: 3 = T0 at x = 1, lower band (y ∈ [0,1]); 4 = T1 at x = 3, upper band (y ∈ [1,2]);
//   node 2's leaves: 5 = T2 at x = 5, lower band;              6 = T3 at x = 7, upper band.
// Each triangle lies in its plane x = c and covers (y − y0) + z ≤ 1 of its band; a leaf box is its
// triangle's box widened by .1 in x.
Bvh four_leaves_in_a_row() {
  auto tri = [](float x, float y0, rs_u32 id) {
    RsTriangle t{};
    t.v0[0] = x, t.v0[1] = y0, t.v0[2] = 0;
    t.v1[0] = x, t.v1[1] = y0 + 1, t.v1[2] = 0;
    t.v2[0] = x, t.v2[1] = y0, t.v2[2] = 1;
    t.id = id;
    return t;
  };
  auto node = [](float x0, float y0, float x1, float y1, rs_u32 first, rs_u32 count) {
    RsBvhNode n{};
    n.bmin[0] = x0, n.bmin[1] = y0, n.bmin[2] = 0, n.first = first;
    n.bmax[0] = x1, n.bmax[1] = y1, n.bmax[2] = 1, n.count = count;
    return n;
  };
  Bvh b;
  b.triangles = {tri(1, 0, 0), tri(3, 1, 1), tri(5, 0, 2), tri(7, 1, 3)};
  b.nodes = {node(0, 0, 8, 2, 1, 0),      node(0, 0, 4, 2, 3, 0),      node(4, 0, 8, 2, 5, 0),
             node(.9f, 0, 1.1f, 1, 0, 1), node(2.9f, 1, 3.1f, 2, 1, 1), node(4.9f, 0, 5.1f, 1, 2, 1),
             node(6.9f, 1, 7.1f, 2, 3, 1)};
  b.depth = 2;
  b.leaf_count = 4;
  return b;
}

const Aabb kBox{{0, 0, 0}, {8, 2, 1}};

// A key of `bits` bits from the bit string the paper's steps give, most significant first; [S2]:
// the traversal stops once `bits` results are set, and a path that ends sooner leaves 0s.
std::uint64_t key_from_path(const std::string& path, unsigned bits) {
  std::uint64_t key = 0;
  for (unsigned i = 0; i < bits; ++i) key = (key << 1) | (i < path.size() && path[i] == '1' ? 1u : 0u);
  return key;
}

struct HandCase {
  const char* what;
  RsRay ray;
  const char* path;  // every box-test result of the whole traversal, derived in the comment
};

std::vector<HandCase> hand_cases() {
  return {
      // [S3] the paper's own example. Upper band, +x from x = −1, segment ending at x = 3.5:
      // root true; node 1 true, node 2 (x ≥ 4) false; at node 1: leaf 3 (lower band) false, leaf 4
      // true; T1 is hit; the stack is empty. The first four results are true, true, false, false.
      {"the paper's example 1100", ray(-1, 1.5f, .25f, 1, 0, 0, 4.5f), "11001"},
      // [S5] closest hit. Lower band, +x from x = −1: root 1; nodes 1 and 2 both 1 (2 is kept for
      // later); at 1: leaf 3 1, leaf 4 0; T0 is hit at x = 1 and ends the segment; back at 2, leaves
      // 5 (x ≈ 5) and 6 lie beyond the hit: 0 0. Without the closest hit they would read 1 0.
      {"closest hit cuts the later tests", ray(-1, .5f, .25f, 1, 0, 0), "1111000"},
      // [S4] fixed order. The same line walked −x from x = 9: node 2 is nearer, but node 1 still
      // comes first: root 1; 1 1, 2 1; at 1: leaf 3 1, leaf 4 0; T0 hit at x = 1 (the far end);
      // back at 2: leaf 5 (x ≈ 5) lies before that hit: 1; leaf 6 0; T2 is hit.
      {"left first even when right is nearer", ray(9, .5f, .25f, -1, 0, 0), "1111010"},
      // [S1] a false result ends a branch, not the traversal. Lower band, +x from x = 2 (past T0):
      // root 1; 1 1, 2 1; at 1: leaf 3 (behind the origin) 0, leaf 4 0; back at 2: leaf 5 1,
      // leaf 6 0; T2 is hit.
      {"a branch of misses, then the kept node", ray(2, .5f, .25f, 1, 0, 0), "1110010"},
      // [S1] a ray that misses the root: one false result, nothing more to walk.
      {"misses the root", ray(-1, 5, .25f, 1, 0, 0), "0"},
  };
}

TEST(PrefixPathCode, HostKeysFollowThePapersDefinitionOnAHandBuiltTree) {
  const Bvh bvh = four_leaves_in_a_row();
  const EncodeScene scene(bvh, kBox);
  for (const HandCase& c : hand_cases())
    for (unsigned bits : {1u, 2u, 4u, 5u, 6u, 7u, 16u, 32u, 64u}) {
      const std::uint64_t host = encode_on_host(Encoder::PPC, bits, scene, {c.ray})[0];
      EXPECT_EQ(host, key_from_path(c.path, bits)) << c.what << ", " << bits << " bits: path " << c.path;
    }
}

// [S2] at its boundaries: a key of an odd length ends inside a pair of child tests (the second
// result is dropped), and the 4-bit key of the paper's example is exactly its printed 1100.
TEST(PrefixPathCode, TruncatesToThePapersPrefix) {
  const Bvh bvh = four_leaves_in_a_row();
  const EncodeScene scene(bvh, kBox);
  const std::vector<HandCase> cases = hand_cases();
  EXPECT_EQ(encode_on_host(Encoder::PPC, 4, scene, {cases[0].ray})[0], 0b1100u);
  // "1111000" cut at 2 bits keeps root and node 1, dropping node 2's result.
  EXPECT_EQ(encode_on_host(Encoder::PPC, 2, scene, {cases[1].ray})[0], 0b11u);
  // The 16-bit keys, written out once: 11001 then zeros, 1111010 then zeros.
  EXPECT_EQ(encode_on_host(Encoder::PPC, 16, scene, {cases[0].ray})[0], 0xC800u);
  EXPECT_EQ(encode_on_host(Encoder::PPC, 16, scene, {cases[2].ray})[0], 0xF400u);
}

// The kernel (cl/keys_ppc.h in encode.cl) gives the same keys as the host twin on these rays.
TEST(PrefixPathCode, KernelEqualsTheHandDerivedKeys) {
  const Bvh bvh = four_leaves_in_a_row();
  DeviceEncoder dev(testing::runtime(), bvh, kBox);
  std::vector<RsRay> rays;
  for (const HandCase& c : hand_cases()) rays.push_back(c.ray);
  for (unsigned bits : {16u, 32u, 64u}) {
    const auto run = dev.run(Encoder::PPC, bits, rays);
    ASSERT_EQ(run.keys.size(), rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i)
      EXPECT_EQ(run.keys[i], key_from_path(hand_cases()[i].path, bits)) << hand_cases()[i].what << ", " << bits;
  }
}

}  // namespace
}  // namespace raysort
