#pragma once
// What the host-only studies in tools/ share: the stable order of a batch's keys (the radix sort's:
// equal keys keep generation order), one printed row of SIMT ratios and ANC per order, and main's
// error handling.
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <numeric>
#include <string>
#include <vector>

#include "bench/metrics.h"
#include "bvh/bvh.h"
#include "render/batches.h"
#include "scene/load.h"
#include "util/error.h"

namespace raysort::study {

// A study's arguments: SCENE [WIDTHxHEIGHT] [BATCH], at 1 spp.
struct Args {
  std::string scene, batch;
  SceneOptions options;
};
inline Args parse_args(const char* tool, int argc, char** argv, const char* resolution) {
  if (argc < 2) throw Error(fmt::format("usage: {} SCENE [WIDTHxHEIGHT] [BATCH]   (default {} bounce1)", tool, resolution));
  Args a;
  a.scene = argv[1];
  a.options.frame = parse_resolution(argc > 2 ? argv[2] : resolution);
  a.options.frame.spp = 1;
  a.batch = argc > 3 ? argv[3] : "bounce1";
  return a;
}

// The batch of that name in a frame, or an error that names the scene.
inline const ReferencedBatch& find_batch(const std::vector<ReferencedBatch>& frame, const Args& a) {
  const auto it = std::find_if(frame.begin(), frame.end(), [&](const ReferencedBatch& b) { return b.batch.name == a.batch; });
  if (it == frame.end()) throw Error(fmt::format("scene {} has no batch {}", a.scene, a.batch));
  return *it;
}

inline std::vector<std::uint32_t> stable_order(const std::vector<std::uint64_t>& keys) {
  std::vector<std::uint32_t> order(keys.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
  return order;
}

// Prints, for keys of one batch, the SIMT lane-efficiency and distinct-nodes ratios of their stable
// order against the batch's generation order (NoSort), and the ANC of the sorted keys.
class OrderReport {
 public:
  OrderReport(const Bvh& bvh, const std::vector<RsRay>& rays, bool any_hit, int name_width)
      : bvh_(bvh), rays_(rays), any_hit_(any_hit), width_(name_width), nosort_(simt_model(bvh, rays, nullptr, any_hit)) {}
  void operator()(const std::string& name, const std::vector<std::uint64_t>& keys) const {
    const std::vector<std::uint32_t> order = stable_order(keys);
    const SimtModel m = simt_model(bvh_, rays_, order.data(), any_hit_);
    std::vector<std::uint64_t> sorted(keys.size());
    for (std::size_t i = 0; i < order.size(); ++i) sorted[i] = keys[order[i]];
    fmt::print("  {:{}} lane {:.3f}  distinct nodes {:.3f}  ANC {:6.2f}\n", name, width_,
               m.lane_efficiency / nosort_.lane_efficiency,
               m.distinct_nodes_per_visit / nosort_.distinct_nodes_per_visit, average_number_of_codes(sorted));
    std::fflush(stdout);
  }

 private:
  const Bvh& bvh_;
  const std::vector<RsRay>& rays_;
  bool any_hit_;
  int width_;
  SimtModel nosort_;
};

// main of a study: its errors as one line on stderr and exit status 2.
template <class Study>
int run(const char* tool, Study study, int argc, char** argv) {
  try {
    return study(argc, argv);
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}: {}\n", tool, e.what());
    return 2;
  }
}

}  // namespace raysort::study
