#pragma once
// One cell's life: encode → radix sort → [permute] → trace, timed against NoSort in the rounds of
// the measurement protocol (bench/protocol.h), checked bit for bit, and summarised in a
// CellRecord. The runner (bench/runner.cpp) decides which cells to measure; this file decides how
// one is measured (docs/measurement.md tells the same story with the figures behind it).
//
// The arms of a cell's rounds, run in a seeded random order after the prologue (encode + sort):
//   nosort          the batch in generation order: the baseline of the speedup
//   aa              the same NoSort trace once more: the A/A check (nosort / aa should be 1)
//   trace:gather    the rays traced through the sorted order (access mode gather)
//   permute         the rays moved into sorted order, then traced (access mode permute; stages
//                   "permute" and "trace:permute")
//   embree:<path>:nosort   Embree tracing the batch in generation order (run --embree-paths,
//                   one per path, in NoSort cells too)
//   embree:<path>:gather   Embree tracing the rays through the sorted order (a packet or stream
//                   holds consecutive entries of it)
//   embree:<path>:permute  Embree tracing the rays moved into sorted order (on the host, once,
//                   outside the timed arm) in identity order
// When a matrix asks for both access modes, the gather and permute cells of one encoder and key
// length share their rounds: one encode + sort feeds both, and both are paired with the same
// NoSort traces (ours and Embree's).
#include <cstdint>
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

  // The NoSort cell: rounds of the nosort and aa arms only. `cell` names the cell (its identity
  // fields are kept); the figures are filled in.
  CellRecord measure_nosort(CellRecord cell, const ProtocolSettings& settings);
  // The cells of one encoder × key length × top-k, one per access mode (identity fields set; all
  // with the same encoder, bits and top_bits), measured in shared rounds.
  std::vector<CellRecord> measure_sorted(std::vector<CellRecord> cells, Encoder encoder,
                                         const ProtocolSettings& settings);

 private:
  cl::Event trace(const cl::Buffer& rays, const cl::Buffer& order, const cl::Buffer& hits);
  double timed_trace(const cl::Buffer& rays, const cl::Buffer& order, const cl::Buffer& hits, const char* doing);
  const cl::Buffer& permuted_rays();
  // The two NoSort arms every cell's rounds hold: "nosort" (the baseline) and "aa" (the same trace
  // again, the A/A check).
  std::vector<Arm> baseline_arms();
  // The rounds of sorted cells: encode + sort as the prologue, the baseline arms, and one trace arm
  // per access mode.
  Measurement sorted_measurement(const std::vector<CellRecord>& cells, Encoder encoder, const cl::Buffer& keys,
                                 const RadixSortConfig& cfg);
  // An encoder without a host twin (an encoder from a file) is checked against itself: "" when a
  // second launch over the rays gives `first` (the keys of the first) again, else why the cells fail.
  std::string unrepeated_keys(Encoder encoder, unsigned bits, const cl::Buffer& keys,
                              const std::vector<std::uint64_t>& first);
  // What the sort left after the rounds: the order, whether it is a permutation and the identity,
  // and its ANC and SIMT model.
  struct SortedOrder {
    std::vector<std::uint32_t> order;
    bool permutation = false, identity = false;
    double anc = 0.0;
    SimtModel simt;
    GpuCounts gpu;
  };
  SortedOrder check_order(const cl::Buffer& keys, unsigned bits, unsigned top);
  // The figures of a checked cell from its rounds.
  void fill_sorted_cell(CellRecord& c, const Outcome& o, const SortedOrder& so, const ProtocolSettings& settings);

  // Embree's arms (Stages::embree_paths): per path, the NoSort-order arm, and in sorted rounds one
  // sorted-order arm per access mode. Each keeps the hits of its last run, for the checks.
  struct EmbreeArm {
    EmbreePath path;
    std::string key;
    std::vector<RsHit> nosort_hits;                      // ray order
    std::map<std::string, std::vector<RsHit>> sorted_hits;  // by access mode, sorted order
  };
  void add_embree_arms(Measurement& m, const std::vector<CellRecord>& sorted_cells);
  // The sorted order on the host and the rays in it, made by the first sorted Embree arm of a
  // measurement (after its round's sort, before its clock starts) and kept for the others.
  const std::vector<std::uint32_t>& embree_order();
  const std::vector<RsRay>& embree_permuted_rays();
  // Each path's figures of cell `c` from the rounds, and the checks: Embree's NoSort hits agree
  // with ours (as `trace --reference embree` requires), and its sorted-order hits, scattered back,
  // with its NoSort-order ones up to ties. "" or why the cell fails.
  std::string fill_embree(CellRecord& c, const Outcome& o, const SortedOrder* so, const ProtocolSettings& settings);

  Stages s_;
  const Bvh& bvh_;
  const RayBatch& batch_;
  const std::uint32_t n_;
  std::string setup_error_;
  cl::Buffer rays_, identity_, values_, keys32_, keys64_, nosort_hits_, gather_hits_, permute_hits_, permuted_;
  std::vector<RsHit> nosort_hits_host_;
  std::vector<EmbreeArm> embree_arms_;
  std::vector<std::uint32_t> embree_order_;
  std::vector<RsRay> embree_permuted_;
  bool embree_order_ready_ = false, embree_permuted_ready_ = false;
  SimtModel nosort_simt_;
  GpuCounts nosort_gpu_;
};

}  // namespace raysort
