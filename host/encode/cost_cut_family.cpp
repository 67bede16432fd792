// The cost-cut family: mlhcc-cost (see cost_cut_family.h).
#include "encode/cost_cut_family.h"

#include <algorithm>
#include <map>

#include "trace/tracer.h"
#include "util/error.h"

namespace raysort {

namespace {

// mlhcc-cost's inputs: the estimates it learned, and its tables per key length.
struct CostCutState : EncoderState {
  std::vector<std::uint64_t> means;
  std::map<unsigned, CostCutInputs> by_bits;
};

class CostCutFamily final : public EncoderFamily {
 public:
  std::string key_bits_problem(Encoder, unsigned bits, const EncoderParams& params) const override {
    if (bits % 2 != 0 || bits < 4)
      return "mlhcc-cost keys need an even number of bits, at least 4 (half top-level cut, then low-level cut "
             "and cost estimate), not " + std::to_string(bits);
    const CostSplit split = cost_split(bits, params);
    if (split.low_bits == 0)
      return "mlhcc-cost with " + std::to_string(split.cost_bits) + " cost bits (--cost-bits) leaves no low-level "
             "cut in a " + std::to_string(bits) + "-bit key: take fewer than " + std::to_string(bits / 2);
    return "";
  }

  HostKey host_key(Encoder, unsigned bits, const EncodeScene& scene) const override {
    const CostCutInputs& t = cost_cut_inputs(scene, bits);
    const RsEncodeFrame* frame = &scene.frame();
    return [&t, frame, bits](const RsRay& ray) {
      return rs_key_from_code(rs_cost_cut_code(ray, frame, t.top_groups.data(), static_cast<rs_u32>(t.top.size()),
                                               t.low_groups.data(), t.low_count.data(), t.split.top_bits,
                                               t.split.low_bits, t.cost.data(), bits),
                              bits);
    };
  }

  std::vector<KernelArg> upload(Encoder, unsigned bits, const EncodeScene& scene, DeviceUploads& up) const override {
    const CostCutInputs& t = cost_cut_inputs(scene, bits);
    return {scene.frame(),
            up.buffer("top-level cut boxes", t.top_groups),
            static_cast<cl_uint>(t.top.size()),
            up.buffer("low-level cut boxes", t.low_groups),
            up.buffer("low-level cut sizes", t.low_count),
            t.split.top_bits,
            t.split.low_bits,
            up.buffer("cost estimates", t.cost)};
  }

  // The statistics for a batch come from the same batch of a previous frame, traced on the host
  // (trace_reference, fast variant, wide tree: each ray's node visits, the steps the kernel takes).
  LearnsFrom learns_from(Encoder) const override { return LearnsFrom::PreviousFrame; }
  std::shared_ptr<const LearnedInput> study(Encoder, const EncodeScene& scene, const RayBatch& before) const override {
    std::vector<std::uint32_t> steps;
    trace_reference(scene.bvh(), before.rays, nullptr, before.any_hit(), &steps);
    auto learned = std::make_shared<CostEstimates>();
    learned->mean_steps = cost_statistics(scene.frame(), before.rays, steps);
    return learned;
  }
  void use(Encoder, const LearnedInput* learned, EncodeScene& scene) const override {
    set_cost_estimates(scene, learned ? dynamic_cast<const CostEstimates&>(*learned).mean_steps
                                      : std::vector<std::uint64_t>{});
  }
};

}  // namespace

const EncoderFamily& encoder_family_cost_cut() {
  static const CostCutFamily family;
  return family;
}

CostSplit cost_split(unsigned bits, const EncoderParams& params) {
  CostSplit s;
  s.top_bits = bits / 2;
  // The default, an eighth of the key (4 of 32 bits): of the widths swept (4, 8, 12 of 32) the one
  // that gains lane efficiency without reading more distinct nodes than MLHCC (results/README.md).
  s.cost_bits = params.cost_bits > 0 ? params.cost_bits : std::max(1u, bits / 8);
  s.low_bits = bits - s.top_bits > s.cost_bits ? bits - s.top_bits - s.cost_bits : 0u;
  return s;
}

void set_cost_estimates(EncodeScene& scene, std::vector<std::uint64_t> mean_steps) {
  if (!mean_steps.empty() && mean_steps.size() != RS_COST_BINS)
    throw Error("cost estimates for " + std::to_string(mean_steps.size()) + " bins, mlhcc-cost has " +
                std::to_string(RS_COST_BINS));
  scene.renew_state<CostCutState>(Encoder::MLHCC_COST).means = std::move(mean_steps);
}

const CostCutInputs& cost_cut_inputs(const EncodeScene& scene, unsigned bits) {
  CostCutState& state = scene.state<CostCutState>(Encoder::MLHCC_COST);
  return cached_inputs(state.by_bits, bits, [&] {
    check_key_bits(Encoder::MLHCC_COST, bits, scene.params());
    CostCutInputs t;
    t.split = cost_split(bits, scene.params());
    t.cut = two_level_cut(scene.bvh(), scene.had(), t.split.top_bits, t.split.low_bits);
    static_cast<TwoLevelTables&>(t) = two_level_tables(scene.bvh(), t.cut, t.split.low_bits);
    // The estimate on cost_bits bits: scaled to the largest bin mean, so the field's range covers
    // this batch's estimates; integer arithmetic, the same on every machine.
    t.cost.assign(RS_COST_BINS, 0u);
    if (!state.means.empty()) {
      const std::uint64_t largest = *std::max_element(state.means.begin(), state.means.end());
      for (std::size_t b = 0; b < state.means.size(); ++b)
        t.cost[b] = static_cast<rs_u32>((state.means[b] << t.split.cost_bits) / (largest + 1));
    }
    return t;
  });
}

std::vector<std::uint64_t> cost_statistics(const RsEncodeFrame& frame, const std::vector<RsRay>& rays,
                                           const std::vector<std::uint32_t>& steps) {
  if (steps.size() != rays.size())
    throw Error("cost_statistics: " + std::to_string(steps.size()) + " step counts for " +
                std::to_string(rays.size()) + " rays");
  constexpr std::size_t kCells = std::size_t{1} << (3 * RS_COST_CELL_LEVELS);
  std::vector<std::uint64_t> bin_sum(RS_COST_BINS, 0), bin_count(RS_COST_BINS, 0);
  std::vector<std::uint64_t> cell_sum(kCells, 0), cell_count(kCells, 0);
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const rs_u32 bin = rs_cost_bin(&frame, rays[i]);
    bin_sum[bin] += steps[i], ++bin_count[bin];
    cell_sum[bin >> RS_COST_DIRECTION_BITS] += steps[i], ++cell_count[bin >> RS_COST_DIRECTION_BITS];
    sum += steps[i];
  }
  const std::uint64_t batch_mean = rays.empty() ? 0 : sum * 16 / rays.size();
  std::vector<std::uint64_t> mean(RS_COST_BINS);
  for (std::size_t b = 0; b < RS_COST_BINS; ++b) {
    const std::size_t cell = b >> RS_COST_DIRECTION_BITS;
    mean[b] = bin_count[b] > 0    ? bin_sum[b] * 16 / bin_count[b]
              : cell_count[cell] > 0 ? cell_sum[cell] * 16 / cell_count[cell]
                                     : batch_mean;
  }
  return mean;
}

}  // namespace raysort
