#pragma once
// The BVH: a binary tree over world-space triangles in the flat layout the kernels read
// (RsBvhNode / RsTriangle in cl/bvh_layout.h: children adjacent, triangles in leaf order).
// This binary tree is the reference structure: HCC cuts, PPC and the host reference traversal
// all work on it.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "bvh_layout.h"
#include "util/uninit_vector.h"

namespace raysort {

struct BvhBuildOptions {
  std::uint32_t bins = 16;           // SAH bins per axis (2 to 64)
  std::uint32_t max_leaf_size = 8;   // a leaf never holds more (forced split)
  float traversal_cost = 1.0f;       // SAH constants (relative to one triangle test)
  float intersection_cost = 1.0f;
  // Build threads; 0: host_threads(). The tree is the same, bit for bit, for every count.
  unsigned threads = 0;
};

// A wide leaf reference decoded, for either width (cl/bvh_layout.h): packets [first, end), and the
// leaf's lanes of each (a bit per lane; every lane of a 4-wide leaf's packets, an 8-wide leaf's own
// lanes of a packet it may share: RS_WIDE8_LEAF_*). The host's one reader of both encodings.
struct WideLeaf {
  std::uint32_t first = 0, end = 0;
  int lanes = 0;
  std::uint32_t count() const { return end - first; }
};
inline WideLeaf wide_leaf(std::uint32_t ref, bool wide8) {
  if (wide8) return {RS_WIDE8_LEAF_FIRST(ref), RS_WIDE8_LEAF_END(ref), RS_WIDE8_LEAF_LANES(ref)};
  return {RS_WIDE_LEAF_FIRST(ref), RS_WIDE_LEAF_END(ref), RS_WIDE_LEAF_LANES(ref)};
}

// The 4-wide form the trace kernels traverse (RsWideNode / RsTriPacket in cl/bvh_layout.h), collapsed
// from the binary tree: a wide node holds its binary node's grandchildren, or a child itself when
// that child is a leaf. Same boxes, same leaves; only the branching factor changes.
struct WideBvh {
  // Filled in place on all threads by the collapse: resize() leaves new elements unwritten.
  UninitVector<RsWideNode> nodes;     // node 0 is the root (always an inner node)
  UninitVector<RsTriPacket> packets;  // leaf triangles, four to a packet
  std::uint32_t depth = 0;           // inner wide nodes on the longest root-to-leaf path
  bool empty() const { return nodes.empty(); }
};

// The 8-wide form of the wide8 trace class (RsWide8Node / RsTriPacket8 in cl/bvh_layout.h), collapsed
// from the binary tree by host/bvh/wide8.cpp: every inner child at least three binary levels below
// its parent, leaves of up to eight triangles in one packet. Built on demand (collapse_to_wide8),
// not with the BVH: only the wide8 class walks it.
struct Wide8Bvh {
  UninitVector<RsWide8Node> nodes;     // as WideBvh's: resize() leaves new elements unwritten
  UninitVector<RsTriPacket8> packets;  // leaf triangles, eight to a packet
  std::uint32_t depth = 0;            // inner wide nodes on the longest root-to-leaf path
  bool empty() const { return nodes.empty(); }
};

// The compressed 8-wide form of the cwbvh trace class (RsCwbvhNode in cl/bvh_layout.h; Ylitie, Karras
// and Laine 2017), collapsed from the binary tree by host/bvh/cwbvh.cpp: 80-byte nodes with 8-bit
// child boxes, leaves of at most three triangles, each node's leaf triangles contiguous. Built on
// demand (collapse_to_cwbvh), not with the BVH: only the cwbvh class walks it.
struct CwBvh {
  std::vector<RsCwbvhNode> nodes;     // node 0 is the root
  std::vector<RsTriangle> triangles;  // in the nodes' leaf order; .id as in Bvh::triangles
  std::uint32_t depth = 0;            // nodes on the longest root-to-leaf path
  bool empty() const { return nodes.empty(); }
};

struct SplitTree;

// Where split_tree() keeps the tree it builds on first use. A copy of a Bvh starts with an empty
// slot (the copy may then be changed, and its split tree must be its own); a move takes it along.
class SplitTreeSlot {
 public:
  SplitTreeSlot();
  ~SplitTreeSlot();
  SplitTreeSlot(const SplitTreeSlot&) : SplitTreeSlot() {}
  SplitTreeSlot& operator=(const SplitTreeSlot&);
  SplitTreeSlot(SplitTreeSlot&&) noexcept;
  SplitTreeSlot& operator=(SplitTreeSlot&&) noexcept;
  struct State;
  std::unique_ptr<State> state_;
};

struct Bvh {
  // Filled in place on all threads by the build: resize() leaves new elements unwritten.
  UninitVector<RsBvhNode> nodes;       // node 0 is the root
  UninitVector<RsTriangle> triangles;  // leaf order; triangles[k].id = index in the scene's flat list
  std::uint32_t depth = 0;            // longest root-to-leaf path, in edges
  std::uint32_t leaf_count = 0;
  WideBvh wide;                       // the same tree, 4-wide (what the trace kernels read)
  double build_ms = 0.0;              // binned SAH build + collapse to 4-wide
  double sah_cost = 0.0;              // of the binary tree (sah_cost below), the build's figure of quality
  Aabb bounds() const;                // the root's box
  bool is_leaf(std::uint32_t n) const { return nodes[n].count > 0; }
  SplitTreeSlot split_tree_slot;      // split_tree(*this), once built
};

// The tree the 8-wide classes (wide8, stream, coherent) walk: the binary tree's triangles rebuilt
// with spatial splits (build_spatial_bvh), collapsed to 8 wide. Embree's best paths walk a tree
// with spatial splits too (RTC_BUILD_QUALITY_HIGH), and without them the stream only tied its
// shadow rays (results/history/trace-kernels.md, stop 75). The 4-wide and binary classes, HCC's
// cuts and the golden figures keep the plain tree.
struct SplitTree {
  Bvh binary;       // a triangle may be in several leaves: its parts on each side of a split plane
  Wide8Bvh wide8;   // its 8-wide collapse
  double build_ms = 0.0;  // both
};

// bvh's split tree, built on first use (on all threads) and then kept with bvh: the same tree, bit for
// bit, on every call and thread count. Safe to call from several threads.
const SplitTree& split_tree(const Bvh& bvh);

// Binned SAH build (Wald 2007, "On fast Construction of SAH-based Bounding Volume Hierarchies")
// over the flattened triangles, on opts.threads threads (host/bvh/build_sah.cpp says how).
// Deterministic: the same triangles give the same tree, nodes and triangle order, bit for bit,
// whatever the thread count. Depth stays below RS_STACK_SIZE: past kMaxSahDepth levels, nodes
// split at the object median.
Bvh build_bvh(const Scene::Flat& tris, const BvhBuildOptions& opts = {});

// The triangles of `plain` in a binary tree with spatial splits (SBVH; Stich, Friedrich and Dietrich
// 2009; host/bvh/build_spatial.cpp): a node splits by the binned SAH of build_bvh or, where cheaper,
// at a plane through its box, a triangle straddling it then referenced from both sides with a box
// around its part on each. `budget`: the references splits may add, as a share of the triangles
// (Embree's default, 1.2 references per triangle in all). Leaves then index `triangles`, in which a
// triangle appears once per reference (with its id). Deterministic as build_bvh; its `wide` is left
// empty (wide_of collapses it where needed).
inline constexpr double kSpatialSplitBudget = 0.2;
Bvh build_spatial_bvh(const Bvh& plain, const BvhBuildOptions& opts = {}, double budget = kSpatialSplitBudget);

// The tree's SAH cost (MacDonald and Booth 1990; the cost the builder minimises greedily, Wald
// 2007): over the root's surface area A, the sum of traversal_cost · A(n) over inner nodes and
// intersection_cost · count · A(n) over leaves, in double, in node order. The expected cost of a
// random ray through the root in units of one triangle test; lower is a better tree.
double sah_cost(const Bvh& bvh, const BvhBuildOptions& opts = {});

// Collapses a binary BVH to the 4-wide layout. Throws an Error if a leaf needs more than four
// packets (max_leaf_size > 16) or the stack bound RS_WIDE_STACK_SIZE could be exceeded. On `threads`
// threads (0: host_threads()), the same tree for every count.
WideBvh collapse_to_wide(const Bvh& bvh, unsigned threads = 0);

// Checks the wide tree against its binary source: each of a triangle's references in one valid packet lane
// (with its vertices and id), each child box equal to a binary node's box, every reference in
// range, every inner node reached once, and 3 * depth within RS_WIDE_STACK_SIZE. Returns an empty
// string when all hold, else a description of the first violation.
std::string validate_wide(const WideBvh& wide, const Bvh& bvh);

// Collapses a binary BVH to the 8-wide layout (host/bvh/wide8.cpp). Throws an Error if a leaf needs
// more than four packets (max_leaf_size > 32) or the stack bound RS_WIDE8_STACK_SIZE could be exceeded.
// On `threads` threads (0: host_threads()), the same tree for every count.
Wide8Bvh collapse_to_wide8(const Bvh& bvh, unsigned threads = 0);

// validate_wide's checks on the 8-wide tree, with its stack bound (7 * depth <= RS_WIDE8_STACK_SIZE).
std::string validate_wide8(const Wide8Bvh& wide, const Bvh& bvh);

// Collapses a binary BVH to the compressed 8-wide layout (host/bvh/cwbvh.cpp). Throws an Error if
// the stack bound RS_CWBVH_STACK_SIZE could be exceeded or a coordinate needs an exponent past 2^127.
CwBvh collapse_to_cwbvh(const Bvh& bvh);

// Checks the compressed tree against its binary source: every triangle once (vertices and id), every
// node reached once, leaves of 1 to 3 triangles within the node's 24, every dequantised child box
// containing all the triangles below it (in the kernels' float arithmetic), the depth within the
// stack. Returns an empty string when all hold, else a description of the first violation.
std::string validate_cwbvh(const CwBvh& cw, const Bvh& bvh);

// Zero area in exact arithmetic (differences and products of floats are exact in double): the
// robust triangle test's degenerate-triangle check (cl/intersect.h), which the wide layouts decide
// once per triangle on the host (the packets' nondegenerate lanes).
bool exactly_degenerate(const RsTriangle& t);

// bvh.wide, or a collapse of bvh when it has none (a binary tree built by hand in a test).
const WideBvh& wide_of(const Bvh& bvh, WideBvh& scratch);

// Checks the invariants the kernels rely on: every triangle in exactly one leaf, every child box
// inside its parent, leaf sizes within max_leaf_size, depth below the stack bound, children in
// range. Returns an empty string when all hold, else a description of the first violation.
std::string validate_bvh(const Bvh& bvh, std::size_t triangle_count, const BvhBuildOptions& opts = {});

// validate_bvh's checks on build_spatial_bvh(plain, opts, budget): every triangle of plain in at
// least one leaf, each copy exactly plain's (vertices and id), at most (1 + budget) references per
// triangle in all, and a leaf's box meeting each of its triangles' boxes (it holds their parts, not
// the whole; that the parts cover each triangle is tested by sampling, tests/spatial_bvh_test.cpp).
std::string validate_spatial_bvh(const Bvh& split, const Bvh& plain, double budget, const BvhBuildOptions& opts = {});

}  // namespace raysort
