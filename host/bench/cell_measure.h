#pragma once
// A batch's cells: encode → radix sort → [permute] → trace, timed against NoSort in rounds the
// batch's cells share (bench/protocol.h, "Shared rounds"), checked bit for bit, and summarised in
// CellRecords. The runner (bench/runner.cpp) decides which cells to measure; this file decides how
// they are measured (docs/measurement.md tells the same story with the figures behind it).
//
// A batch's measurement: the common arms run every round, for every cell (issue 42: one NoSort and
// one A/A per round for the whole batch, not per cell):
//   nosort          the batch in generation order: the baseline of every speedup
//   aa              the same NoSort trace once more: the A/A check (nosort / aa should be 1)
//   embree:<path>:nosort   Embree tracing the batch in generation order (run --embree-paths)
// and one group per encoder × key length × top-k, with its access modes side by side: its prologue
// (encode + sort into the group's own order buffer) and its arms,
//   trace:gather    the rays traced through the sorted order (access mode gather)
//   permute         the rays moved into sorted order, then traced (access mode permute; stages
//                   "permute" and "trace:permute")
//   embree:<path>:gather   Embree tracing the rays through the sorted order (a packet or stream
//                   holds consecutive entries of it)
//   embree:<path>:permute  Embree tracing the rays moved into sorted order (on the host, once,
//                   outside the timed arm) in identity order
// The NoSort cell is a group without arms whose target is the A/A ratio. Each group retires on its
// own stopping rule; its cells' figures pair its arms with the common arms of its rounds. Each arm
// checks its hits the first time it runs (the warm-up round, untimed): the groups share the hit
// buffers, so nothing is left to check after the rounds but the order each group's sort gave.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bench/metrics.h"
#include "bench/protocol.h"
#include "bench/record.h"
#include "bvh/bvh.h"
#include "runtime/runtime.h"
#include "embree/embree_reference.h"
#include "encode/encode.h"
#include "render/rays.h"
#include "sort/permute.h"
#include "sort/radix_sort.h"
#include "scene/scene.h"
#include "trace/tracer.h"

namespace raysort {

// What every cell of one batch and trace variant shares: the rays on the device, the buffers the
// stages write, the NoSort hits every sorted trace must reproduce, and the NoSort SIMT model.
class BatchBench {
 public:
  struct Stages {
    Runtime& rt;
    DeviceEncoder& encoder;
    RadixSort& sorter;
    RayPermuter& permuter;
    Tracer& tracer;
    const GpuProfile* gpu = nullptr;  // the GPU cost model's profile; null: off
    // The scene's triangles: the exact oracle judges the rays of a packet class whose hit differs
    // from NoSort's (null: such a ray fails the cell).
    const Scene::Flat* tris = nullptr;
    // Embree's scene of the same triangles and the paths that trace every cell's rays as well
    // (run --embree-paths; null or no path: none). Only a build with Embree sets it.
    const EmbreeScene* embree = nullptr;
    std::vector<EmbreePath> embree_paths;
    // The sort's warp group (MatrixSpec::sort_warp_group; 0: the full sort).
    unsigned sort_warp_group = 0;
  };
  // Uploads the batch, traces it once in generation order (untimed) and checks those hits against
  // `reference` (the host traversal of the same variant). A device fault or a mismatch does not
  // throw: it is kept in setup_error() and fails every cell of the batch.
  BatchBench(const Stages& stages, const Bvh& bvh, const RayBatch& batch, const std::vector<RsHit>& reference);

  const std::string& setup_error() const { return setup_error_; }
  const RayBatch& batch() const { return batch_; }

  // The inputs an encoder learns (bench/scene_bench.h): readied before the rounds, for every group
  // at once; returns the host ms it took (CellRecord::cut_ms), or < 0 when there is none.
  using PrepareEncoder = std::function<double(Encoder, unsigned bits)>;
  // Every cell of the batch in shared rounds: `groups` holds, in the plan's order, the NoSort cell
  // (encoder nosort, alone in its group) and the cells of each encoder × key length × top-k, one per
  // access mode (identity fields set). Returns the cells with their figures, in the same order.
  // The sorted groups share rounds in consecutive chunks of at most groups_per_round(), each chunk
  // with the common arms (the first one with the NoSort cell).
  std::vector<CellRecord> measure_batch(const std::vector<std::vector<CellRecord>>& groups,
                                        const ProtocolSettings& settings, const PrepareEncoder& prepare);
  // A round's sorted groups: at most kGroupsPerRound, and as many orders (4 bytes per ray each) as
  // fit beside the frame (half the device memory the frame estimate leaves; on a CPU device a
  // quarter of the host's free memory), at least 1.
  //
  // Why a bound at all: a paired figure cancels the drift of the machine between the two arms it
  // compares, and two arms of a round lie a third of the round apart on average; a round of every
  // group of a batch (47 in paper-1spp's sibenik bounce1) spans minutes. Eight groups keep a round
  // within a few times an unshared cell's (encode + sort + 3 to 4 traces) while the NoSort and A/A
  // traces fall from 2 per group to 2 per 8 (docs/measurement.md, "Shared rounds").
  static constexpr std::size_t kGroupsPerRound = 8;
  std::size_t groups_per_round() const;

 private:
  // One encoder × key length × top-k of the batch: its cells (one per access mode), its own order
  // buffer (the sort's values, kept from its prologue to its arms), and the checks its arms made.
  struct SortedGroup {
    std::vector<CellRecord> cells;
    Encoder encoder{};
    RadixSortConfig cfg;
    double cut_ms = -1.0;
    cl::Buffer order;                       // the sorted order, on the device
    std::vector<std::uint64_t> unsorted;    // the keys in generation order (fingerprint, ANC)
    std::vector<std::uint32_t> first_order;  // the order of the first sort (downloaded once)
    std::map<std::string, std::size_t> bad;  // by access mode: rays whose hits disagree with NoSort
    std::vector<RsRay> embree_permuted;     // the rays in sorted order, for Embree's permute arms
    // Embree's sorted-order hits against its NoSort-order ones, by "path:access": "" or why the
    // cells fail, and the rays that met the other triangle of a tie.
    struct EmbreeCheck {
      std::string error;
      std::size_t ties = 0;
    };
    std::map<std::string, EmbreeCheck> embree_checked;
    std::string error;                      // why its cells fail before any round
  };

  cl::Event trace(const cl::Buffer& rays, const cl::Buffer& order, const cl::Buffer& hits);
  double timed_trace(const cl::Buffer& rays, const cl::Buffer& order, const cl::Buffer& hits, const char* doing);
  const cl::Buffer& permuted_rays();
  // The common arms: "nosort" (the baseline), "aa" (the same trace again, the A/A check), and per
  // Embree path its NoSort-order arm.
  std::vector<Arm> common_arms();
  // Readies a group before the rounds (prepare, keys in generation order, the repeat check for an
  // encoder without a host twin); a failure is kept in g.error.
  void ready_group(SortedGroup& g, const PrepareEncoder& prepare);
  // One untimed run of g's prologue (encode + sort) and, if g permutes, of the permute: the batch's
  // kernels and their buffers warmed before the rounds (the order of g's first sort is kept).
  void warm_sort_and_permute(SortedGroup& g);
  // A group's prologue (encode + sort into its order) and arms (one trace per access mode, Embree's).
  MeasurementGroup sorted_group(SortedGroup& g);
  // The measurement of the NoSort group (if any) and `sorted` sharing their rounds.
  std::vector<Outcome> measure_chunk(bool with_nosort, const std::vector<SortedGroup*>& sorted,
                                     const ProtocolSettings& settings);
  // An encoder without a host twin (an encoder from a file) is checked against itself: "" when a
  // second launch over the rays gives `first` (the keys of the first) again, else why the cells fail.
  std::string unrepeated_keys(Encoder encoder, unsigned bits, const cl::Buffer& keys,
                              const std::vector<std::uint64_t>& first);
  // A sorted trace's hits (in sorted order) against NoSort's: the rays that disagree (the rule of
  // docs/trace.md, "Trace classes": bit for bit, or for a packet class up to what an order may change).
  std::size_t disagreeing_rays(const std::vector<RsHit>& hits, const std::vector<std::uint32_t>& order);
  // What the group's sort left after the rounds: the order, whether it is a permutation and the
  // identity, and its ANC and SIMT model.
  struct SortedOrder {
    std::vector<std::uint32_t> order;
    bool permutation = false, identity = false;
    double anc = 0.0;
    SimtModel simt;
    GpuCounts gpu;
  };
  // "" or why the group's cells fail (an order that is no permutation, changed between rounds, or
  // does not sort the keys).
  std::string check_order(const SortedGroup& g, SortedOrder& so);
  // The cells of a group from its rounds and checks.
  void finish_group(SortedGroup& g, const Outcome& o, const ProtocolSettings& settings);
  // The NoSort cell from its rounds.
  void finish_nosort(CellRecord& c, const Outcome& o, const ProtocolSettings& settings);
  // The figures of a checked cell from its rounds.
  void fill_sorted_cell(CellRecord& c, const Outcome& o, const SortedOrder& so, const ProtocolSettings& settings);

  // Embree's paths (Stages::embree_paths): each traces the batch in generation order once before the
  // rounds (untimed), for the checks; the arms keep no hits.
  struct EmbreeArm {
    EmbreePath path;
    std::string key;
    std::vector<RsHit> nosort_hits;  // ray order
    std::string agreement_error;     // "" or why Embree's NoSort hits disagree with ours
    double agreement = 1.0;
  };
  void ready_embree();
  void add_embree_arms(MeasurementGroup& m, SortedGroup& g);
  // Each path's figures of cell `c` from the rounds; "" or why the cell fails.
  std::string fill_embree(CellRecord& c, const Outcome& o, const SortedOrder* so, const SortedGroup* g,
                          const ProtocolSettings& settings);

  Stages s_;
  const Bvh& bvh_;
  const RayBatch& batch_;
  const std::uint32_t n_;
  std::string setup_error_;
  cl::Buffer rays_, identity_, keys32_, keys64_, nosort_hits_, gather_hits_, permute_hits_, permuted_;
  std::vector<RsHit> nosort_hits_host_;
  std::vector<EmbreeArm> embree_arms_;
  bool embree_ready_ = false;
  SimtModel nosort_simt_;
  GpuCounts nosort_gpu_;
  RayTrails trails_;  // every ray's trail, recorded by the NoSort model for the sorted orders' models
};

}  // namespace raysort
