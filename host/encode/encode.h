#pragma once
// Ray sort keys: every encoder of docs/design.md, "Encoders", on the device (cl/encode.cl) and on the host
// (a bit-exact twin running the same key code, cl/keys*.h). Layouts: docs/encoders.md.
//
//   EncodeScene   per-scene inputs of the keys: the scene box frame, HAD, cuts, grid cells
//   encode_on_host(encoder, bits, scene, rays)            host twin, keys as uint64
//   DeviceEncoder::enqueue(encoder, bits, rays, order, n, keys, values)   the kernels
//
// A key of b bits (1..64; the suite uses 16, 32, 64) is the top b bits of the encoder's 64-bit
// code. On the device, keys of up to 32 bits are uint32 words and wider keys uint64 words.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "bvh/bvh.h"
#include "runtime/runtime.h"
#include "bvh/cut.h"
// The key layouts shared with the kernels (cl/keys*.h).
#include "keys_cut.h"
#include "keys_ppc.h"
#include "keys_spatial.h"

namespace raysort {

enum class Encoder : int {
  NoSort = RS_ENC_NOSORT,
  Origin = RS_ENC_ORIGIN,
  Reis = RS_ENC_REIS,
  Costa = RS_ENC_COSTA,
  Aila = RS_ENC_AILA,
  TwoPoint = RS_ENC_TWOPOINT,
  RegularGrid = RS_ENC_REGULAR_GRID,
  HCC = RS_ENC_HCC,
  MLHCC = RS_ENC_MLHCC,
  PPC = RS_ENC_PPC,
  HCC_DIR = RS_ENC_HCC_DIR,
  HCC_REGION = RS_ENC_HCC_REGION,
  HCC_TRAFFIC = RS_ENC_HCC_TRAFFIC,
  MLHCC_COST = RS_ENC_MLHCC_COST,
};

// How an encoder computes its key; the family decides the kernel, the host twin and the per-scene
// data the key needs (docs/encoders.md).
enum class EncoderFamily {
  None,        // NoSort: no key, the generation order
  Spatial,     // a Morton-style code of origin, direction or termination point (frame only)
  BoxSet,      // one bit per box the ray segment overlaps: HCC cut nodes (HAD or traffic priority), grid
               // cells (+ direction bits)
  RegionCut,   // hcc-region: the origin's region, then the HCC of that region's own cut
  TwoLevel,    // MLHCC: a top-level cut, then the low-level cut under the first top node hit
  PrefixPath,  // PPC: the first box tests of a traversal (the BVH itself)
  CostCut,     // mlhcc-cost: MLHCC's cut with a shorter low level, then a traversal-cost estimate
};

// One row of the encoder table: everything the code knows about an encoder, in one place. Adding
// an encoder is a row here, its key code in cl/ (and, for a new family, a kernel and a host branch).
struct EncoderInfo {
  Encoder id;
  std::string_view name;                  // as the CLI and result sets spell it
  std::vector<std::string_view> aliases;  // other spellings parse_encoder accepts
  EncoderFamily family;
  std::string_view kernel;                // its cl/encode.cl kernel, without the _k32 / _k64 suffix
  unsigned cost_weight_pct;               // encode + sort on top of a trace, % (the shard planner's cost)
  bool overlay;                           // `raysort render --overlay NAME` draws its boxes
};

// Every encoder, NoSort first, in the order of the enum.
const std::vector<EncoderInfo>& encoder_table();
const EncoderInfo& encoder_info(Encoder e);

// "nosort", "origin", "reis", "costa", "aila", "twopoint", "grid", "hcc", "mlhcc", "ppc", "hcc-dir",
// "hcc-region", "hcc-traffic", "mlhcc-cost".
std::string_view encoder_name(Encoder e);
// Case-insensitive, ignoring '-', '_' and spaces; also accepts the table's aliases.
std::optional<Encoder> parse_encoder(std::string_view name);
// Every encoder, NoSort first, in the order of the enum.
const std::vector<Encoder>& all_encoders();
// A command line's encoder list: names or aliases, or {"all"}. Throws Error naming an unknown one
// and listing the encoders.
std::vector<Encoder> parse_encoders(const std::vector<std::string>& names);
// The widest key an encoder supports (64 for all of them today).
unsigned max_key_bits(Encoder e);

struct EncoderParams {
  float twopoint_length_fraction = 0.25f;  // TwoPoint ray length, × largest scene extent (paper §5)
  double had_lambda = 0.125;               // λ of HAD, Eq. 1 (paper §4.2.2)
  unsigned direction_bits = 1;             // HCC_DIR: d direction bits after b − d cut bits (appendix)
  unsigned region_bits = 4;                // hcc-region: r bits of the origin's region (2^r regions), 0..8
  double traffic_blend = 0.5;              // hcc-traffic, hcc-region: β of (1 − β)·HAD + β·traffic, in [0, 1]
  unsigned cost_bits = 0;                  // mlhcc-cost: bits of the cost estimate; 0: an eighth of the key
};

// mlhcc-cost's split of a key of `bits` bits (cl/keys_cut.h, rs_cost_cut_code): the top-level
// cut's bits (half the key, as MLHCC), the cost estimate's (params.cost_bits, or an eighth of the
// key and at least 1) and the low-level cut's (the rest).
struct CostSplit {
  unsigned top_bits = 0, low_bits = 0, cost_bits = 0;
};
CostSplit cost_split(unsigned bits, const EncoderParams& params);

// The most region bits hcc-region takes (256 regions).
inline constexpr unsigned kMaxRegionBits = 8;

// "" when `bits` is a valid key length for e with these parameters (1..64; MLHCC: even; HCC_DIR:
// more than d bits and d ≤ 42; hcc-region: more than r bits and r ≤ 8; hcc-traffic: 0 ≤ β ≤ 1;
// mlhcc-cost: even, at least 4, and fewer cost bits than half the key), else why not.
std::string key_bits_problem(Encoder e, unsigned bits, const EncoderParams& params);
// Throws Error with key_bits_problem's text.
void check_key_bits(Encoder e, unsigned bits, const EncoderParams& params);

// Rows of cut boxes as the kernels read them per ray (rs_cut_bits_g on row i, at groups + i ·
// ceil(row / 16)): for each cut, its nodes' boxes zero-padded to `row` boxes ([cuts × row]), the
// same as sixteen-box groups (rs_cut_groups), and its box count. MLHCC's and mlhcc-cost's low
// levels and hcc-region's regions are such rows.
struct CutRows {
  std::vector<RsBox> boxes;
  std::vector<RsCutGroup> groups;
  std::vector<rs_u32> counts;
};
CutRows cut_rows(const Bvh& bvh, const std::vector<std::vector<std::uint32_t>>& cuts, unsigned row);

// The tables the two-level kernels read (cl/keys_cut.h, rs_two_level_split_code) for a two-level
// cut: the top boxes, and boxes [top.size() × row] (row i: the low cut of top i, zero-padded to
// `row` boxes), both also as sixteen-box groups (rs_cut_groups: ceil(row / 16) groups per row);
// the low counts per top node. MLHCC's rows are half the key, mlhcc-cost's its low_bits.
struct TwoLevelTables {
  std::vector<RsBox> top, low;
  std::vector<rs_u32> low_count;
  std::vector<RsCutGroup> top_groups, low_groups;
};
TwoLevelTables two_level_tables(const Bvh& bvh, const TwoLevelCut& cut, unsigned row);

// hcc-region's regions (docs/encoders.md): a k-d tree of r levels over `box`, split k in heap order
// (cl/keys_cut.h, RsRegionSplit). median_region_splits places each split, along its cell's longest
// axis (ties: the lower axis), at the median origin of the rays in that cell (the upper median;
// rays with o[axis] ≥ at go to the second child, as rs_region_of sends them), or at the cell's
// middle when no ray is in it; with no rays every split halves its cell. Deterministic.
std::vector<RsRegionSplit> median_region_splits(const Aabb& box, const std::vector<RsRay>& rays, unsigned r);
// The 2^r cells of a split tree, in region order.
std::vector<Aabb> region_boxes(const Aabb& box, const std::vector<RsRegionSplit>& splits, unsigned r);
// The same cells unbounded by the scene box, as the key kernel tests them (cl/keys_cut.h,
// RsRegionCells: lo = −∞ and hi = NaN where the walk to a leaf passed no split on that side of an
// axis), sixteen to a group. Throws on a split that is not finite or names no axis, and on fewer
// than 2^r − 1 splits.
std::vector<RsRegionCells> region_cells(const std::vector<RsRegionSplit>& splits, unsigned r);

// hcc-region's input from a previous frame's batch (region_statistics, bench/runner.h): the splits
// at its rays' median origins, and per region the node traffic (trace/tracer.h, node_traffic) of
// the rays that start there, kept sparse: (node, visits) pairs of the visited nodes, by node.
struct RegionStatistics {
  std::vector<RsRegionSplit> splits;
  std::vector<std::vector<std::pair<std::uint32_t, std::uint64_t>>> visits;
  bool empty() const { return visits.empty(); }  // no statistics (visits has 2^r entries otherwise)
};

// What the keys of one scene depend on, computed on the host once and cached per key length.
// Holds a reference to the BVH: keep it alive as long as this.
class EncodeScene {
 public:
  EncodeScene(const Bvh& bvh, const Aabb& scene_box, const EncoderParams& params = {});

  const Bvh& bvh() const { return *bvh_; }
  const EncoderParams& params() const { return params_; }
  const Aabb& box() const { return box_; }  // the scene box the keys quantise and hcc-region splits
  const RsEncodeFrame& frame() const { return frame_; }
  const std::vector<double>& had() const { return had_; }

  // HCC cut of `size` nodes (node indices, bit order), cached.
  const std::vector<std::uint32_t>& hcc_cut(unsigned size) const;

  // hcc-traffic's input: node visit counts of an earlier batch (trace/tracer.h, node_traffic; indexed
  // like bvh.nodes). Empty (the default, and the first batch of a frame): no traffic, the cut is
  // HCC's. Setting it drops hcc-traffic's cached cuts; the other encoders' data stays.
  void set_node_traffic(std::vector<std::uint64_t> visits);
  const std::vector<std::uint64_t>& node_traffic() const { return traffic_; }
  // hcc-traffic's cut of `size` nodes: priority_cut by traffic_priority(HAD, traffic, β), ties by
  // HAD, then node index. Cached until the traffic changes.
  const std::vector<std::uint32_t>& traffic_cut(unsigned size) const;

  // hcc-region's input from a previous frame (region_statistics, bench/runner.h): the split tree
  // for params.region_bits and each region's node traffic. Without it (the default) each split
  // halves its cell and each region's cut is HAD's among the nodes overlapping it. Setting it drops
  // hcc-region's cached regions; the other encoders' data stays.
  void set_region_statistics(RegionStatistics stats);
  // hcc-region for keys of `bits` bits (cl/keys_cut.h, rs_region_cut_code): the split tree (2^r − 1
  // splits), its leaves as the kernel tests them (region_cells), each region's box (region_boxes),
  // its cut of row_size = bits − r nodes and the cuts as sixteen-box groups,
  // rs_cut_group_count(row_size) per region. With statistics a region's cut is priority_cut by
  // traffic_priority(HAD, the region's traffic, β), else region_cut.
  struct Regions {
    rs_u32 region_bits = 0;
    rs_u32 row_size = 0;
    std::vector<RsRegionSplit> splits;
    std::vector<RsRegionCells> cells;
    std::vector<Aabb> boxes;
    std::vector<std::vector<std::uint32_t>> cuts;
    std::vector<RsCutGroup> groups;
    std::vector<rs_u32> counts;
  };
  const Regions& regions(unsigned bits) const;
  // The boxes of a box-set encoder (HCC, RegularGrid, HCC_DIR) for keys of `bits` bits, bit order.
  const std::vector<RsBox>& box_set(Encoder e, unsigned bits) const;
  // The same boxes as rs_box_set_code reads them: sixteen-box groups (rs_cut_groups) and their
  // number of boxes, cached.
  struct CutSet {
    std::vector<RsCutGroup> groups;
    rs_u32 box_count = 0;
  };
  const CutSet& cut_set(Encoder e, unsigned bits) const;
  // MLHCC for keys of `bits` bits: its cut and tables (two_level_tables) with rows of half boxes.
  struct TwoLevel : TwoLevelTables {
    unsigned half = 0;
    TwoLevelCut cut;
  };
  const TwoLevel& two_level(unsigned bits) const;

  // mlhcc-cost's input: the mean traversal steps per cost bin (cl/keys_cut.h, rs_cost_bin) of a
  // previous frame's batch, in sixteenths of a step (cost_statistics). Empty (the default): no
  // estimate, the cost field is 0 and the key is the cut alone. Setting it drops mlhcc-cost's
  // cached tables; the other encoders' data stays.
  void set_cost_estimates(std::vector<std::uint64_t> mean_steps);
  // mlhcc-cost for keys of `bits` bits: the two-level cut of top_bits top nodes with low-level cuts
  // of low_bits nodes (two_level_cut), its tables (two_level_tables, rows of low_bits boxes), and
  // per bin the estimate quantised to cost_bits: mean · 2^cost_bits / (largest mean + 1).
  struct CostCut : TwoLevelTables {
    CostSplit split;
    TwoLevelCut cut;
    std::vector<rs_u32> cost;  // RS_COST_BINS entries
  };
  const CostCut& cost_cut(unsigned bits) const;

 private:
  const Bvh* bvh_;
  EncoderParams params_;
  RsEncodeFrame frame_{};
  Aabb box_;
  std::vector<double> had_;
  mutable std::map<unsigned, std::vector<std::uint32_t>> hcc_cuts_;
  mutable std::map<std::pair<int, unsigned>, std::vector<RsBox>> box_sets_;
  mutable std::map<std::pair<int, unsigned>, CutSet> cut_sets_;
  mutable std::map<unsigned, TwoLevel> two_levels_;
  std::vector<std::uint64_t> traffic_;
  mutable std::map<unsigned, std::vector<std::uint32_t>> traffic_cuts_;
  RegionStatistics region_stats_;
  mutable std::map<unsigned, Regions> regions_;
  std::vector<std::uint64_t> cost_means_;
  mutable std::map<unsigned, CostCut> cost_cuts_;
};

// mlhcc-cost's statistics of one batch (a previous frame's, the same batch name): per cost bin
// (rs_cost_bin in `frame`), the mean of `steps` (each ray's traversal steps, trace_reference's
// node_visits) in sixteenths of a step, rounded down; a bin no ray fell in takes its origin cell's
// mean over every direction, and a cell with no rays the batch's mean. Deterministic.
std::vector<std::uint64_t> cost_statistics(const RsEncodeFrame& frame, const std::vector<RsRay>& rays,
                                           const std::vector<std::uint32_t>& steps);

RsBox to_rs_box(const Aabb& b);
// Boxes [0, n ≤ 64) transposed into ceil(n / 16) RsCutGroups (cl/keys_cut.h): box i in lane 15 − i % 16
// of group i / 16 (rs_cut_bits places it at code bit 63 − first_bit − i); missing lanes are zero
// boxes. Throws Error for a box with lo > hi or NaN bounds.
std::vector<RsCutGroup> rs_cut_groups(const RsBox* boxes, std::size_t n);


// The key of one ray (host twin of the kernels; same source for the key arithmetic).
std::uint64_t encode_ray(Encoder e, unsigned bits, const EncodeScene& scene, const RsRay& ray);
// Keys of every ray (host threads), keys[i] of rays[i].
std::vector<std::uint64_t> encode_on_host(Encoder e, unsigned bits, const EncodeScene& scene,
                                          const std::vector<RsRay>& rays);
std::vector<std::uint64_t> encode_on_host(Encoder e, unsigned bits, const Bvh& bvh, const Aabb& scene_box,
                                          const EncoderParams& params, const std::vector<RsRay>& rays);

// The encode kernels of one scene on one device. Per-scene data (frame, BVH for PPC) is uploaded
// at construction; cut boxes per (encoder, bits) at their first use (or by prepare()), once.
class DeviceEncoder {
 public:
  DeviceEncoder(Runtime& rt, const Bvh& bvh, const Aabb& scene_box, const EncoderParams& params = {});

  // The kernels of one encode: HCC_DIR with d > 1 direction bits runs two (direction bits, then box
  // bits), the others one.
  struct Events {
    cl::Event first, last;
    void wait() const;
    double ms() const;  // first kernel's start to last kernel's end (profiling)
  };
  // keys[i], values[i] = i for the ray rays[order[i]], i < count < kMaxRays. keys holds uint32
  // (bits ≤ 32) or uint64 (bits > 32). Enqueues and returns the kernels' events without waiting.
  static constexpr std::uint32_t kMaxRays = 1u << 28;
  Events enqueue(Encoder e, unsigned bits, const cl::Buffer& rays, const cl::Buffer& order, std::uint32_t count,
                 const cl::Buffer& keys, const cl::Buffer& values);
  // Uploads what (e, bits) needs now, so a timed enqueue does no host work.
  void prepare(Encoder e, unsigned bits);
  // hcc-traffic's per-batch input (EncodeScene::set_node_traffic); its uploaded cuts are dropped,
  // the next prepare or enqueue builds and uploads the new ones.
  void set_node_traffic(std::vector<std::uint64_t> visits);
  // hcc-region's previous-frame input (EncodeScene::set_region_statistics); its uploads are dropped.
  void set_region_statistics(RegionStatistics stats);
  // mlhcc-cost's per-batch input (EncodeScene::set_cost_estimates); its uploaded tables are dropped.
  void set_cost_estimates(std::vector<std::uint64_t> mean_steps);
  // Runs every kernel once on a few rays (PoCL compiles kernels at their first launch). Returns ms.
  double warm_up();

  static std::size_t key_bytes(unsigned bits) { return bits > 32 ? 8 : 4; }

  struct Run {
    std::vector<std::uint64_t> keys;  // widened to 64 bits
    std::vector<std::uint32_t> values;
  };
  // Uploads rays (order null = identity), encodes them once and returns keys and values. Untimed:
  // timed encodes go through the measurement protocol (bench/protocol.h) with enqueue().
  Run run(Encoder e, unsigned bits, const std::vector<RsRay>& rays, const std::vector<std::uint32_t>* order = nullptr);

  const EncodeScene& scene() const { return scene_; }
  std::size_t local_size() const { return local_; }

 private:
  struct Uploaded {
    cl::Buffer a, b, c, d;
    std::uint32_t n = 0;
  };
  const Uploaded& uploaded(Encoder e, unsigned bits);
  // Forgets e's uploaded tables (its per-batch input changed); the next encode uploads them again.
  void drop_uploads(Encoder e);

  Runtime& rt_;
  EncodeScene scene_;
  cl::Buffer nodes_, triangles_;
  struct Kernels {
    std::map<Encoder, cl::Kernel> by_encoder;  // EncoderInfo::kernel of each encoder, _k32 / _k64
    cl::Kernel box_set_or, direction;          // HCC_DIR's two passes (more than one direction bit)
  } k32_, k64_;
  std::map<std::pair<int, unsigned>, Uploaded> uploads_;
  std::size_t local_ = 64;
};

}  // namespace raysort
