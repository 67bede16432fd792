// EncodeCostBench: encodebench's measurement of one encoder on one batch (see encode_cost.h).
#include "bench/encode_cost.h"

#include <algorithm>
#include <numeric>

namespace raysort {

EncodeCostBench::EncodeCostBench(Runtime& rt, DeviceEncoder& encoder, Tracer& tracer, const RayBatch& batch)
    : rt_(rt), encoder_(encoder), tracer_(tracer), batch_(batch), n_(static_cast<std::uint32_t>(batch.size())) {
  std::vector<std::uint32_t> identity(n_);
  std::iota(identity.begin(), identity.end(), 0u);
  const std::size_t n = std::max<std::size_t>(1, n_);
  rays_ = rt.upload("rays of " + batch.name, batch.rays);
  order_ = rt.upload("identity order", identity);
  hits_ = rt.buffer("hits", n * sizeof(RsHit));
  keys_ = rt.buffer("keys", n * sizeof(std::uint64_t));
  values_ = rt.buffer("values", n * sizeof(std::uint32_t));
  versus_keys_ = rt.buffer("reference keys", n * sizeof(std::uint64_t));
  versus_values_ = rt.buffer("reference values", n * sizeof(std::uint32_t));
}

Arm EncodeCostBench::encode_arm(const char* stage, Encoder e, unsigned bits, const cl::Buffer& keys,
                                const cl::Buffer& values) {
  return {{stage}, [this, e, bits, &keys, &values] {
            const DeviceEncoder::Events ev = encoder_.enqueue(e, bits, rays_, order_, n_, keys, values);
            ev.wait();
            return std::vector<double>{ev.ms()};
          }};
}

EncodeCost EncodeCostBench::measure(Encoder e, unsigned bits, std::optional<Encoder> versus,
                                    const ProtocolSettings& settings) {
  encoder_.prepare(e, bits);
  Measurement m;
  m.arms = {encode_arm("encode", e, bits, keys_, values_),
            {{"trace"}, [this] {
               cl::Event ev = tracer_.enqueue(rays_, order_, n_, batch_.any_hit(), hits_);
               cl_call("waiting for the trace", [&] { ev.wait(); });
               return std::vector<double>{event_ms(ev)};
             }}};
  m.targets = {[](const Series& s) { return ratio_interval(s.at("encode"), s.at("trace")); }};
  const bool paired = versus && *versus != e && key_bits_problem(*versus, bits, encoder_.scene().params()).empty();
  if (paired) {
    encoder_.prepare(*versus, bits);
    m.arms.push_back(encode_arm("versus", *versus, bits, versus_keys_, versus_values_));
    m.targets.push_back([](const Series& s) { return ratio_interval(s.at("encode"), s.at("versus")); });
  }
  const Outcome o = raysort::measure(m, settings);
  EncodeCost c;
  c.encode = Timing::of(o.series.at("encode"));
  c.share = ratio_interval(o.series.at("encode"), o.series.at("trace"));
  if (paired) c.versus = ratio_interval(o.series.at("encode"), o.series.at("versus"));
  c.keys = DeviceEncoder::download_keys(rt_, keys_, bits, n_);
  c.rounds = o.rounds;
  c.stop = o.stop;
  return c;
}

}  // namespace raysort
