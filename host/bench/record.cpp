#include "bench/record.h"

#include <fmt/format.h>

#include <algorithm>

namespace raysort {

std::string CellRecord::id() const {
  std::string s = fmt::format("{}/{}/{}/{}", scene, batch, encoder, bits);
  if (top_bits) s += fmt::format("/top{}", top_bits);
  if (variant != "robust") s += "/" + variant;
  if (access != "gather") s += "/" + access;
  return s;
}

static void timing_to_json(nlohmann::json& j, const char* name, const Timing& t) {
  j[std::string(name) + "_ms"] = {{"median", t.median_ms}, {"min", t.min_ms}, {"max", t.max_ms}};
}
static void timing_from_json(const nlohmann::json& j, const char* name, Timing& t) {
  const auto& o = j.at(std::string(name) + "_ms");
  t.median_ms = o.at("median").get<double>();
  t.min_ms = o.at("min").get<double>();
  t.max_ms = o.at("max").get<double>();
}

void to_json(nlohmann::json& j, const CellRecord& r) {
  j = nlohmann::json{{"format_version", kResultFormatVersion},
                     {"id", r.id()},
                     {"scene", r.scene},
                     {"batch", r.batch},
                     {"encoder", r.encoder},
                     {"bits", r.bits},
                     {"top_bits", r.top_bits},
                     {"variant", r.variant},
                     {"access", r.access},
                     {"rays", r.rays},
                     {"status", r.status},
                     {"error", r.error},
                     {"trace_mrays", r.trace_mrays},
                     {"speedup", r.speedup},
                     {"net_speedup", r.net_speedup},
                     {"overhead_pct", r.overhead_pct},
                     {"anc", r.anc},
                     {"simt_lane_efficiency", r.simt_lane_efficiency},
                     {"simt_distinct_per_visit", r.simt_distinct_per_visit},
                     {"simt_lane_efficiency_ratio", r.simt_lane_efficiency_ratio},
                     {"simt_distinct_per_visit_ratio", r.simt_distinct_per_visit_ratio},
                     {"hits_match_nosort", r.hits_match_nosort},
                     {"order_is_permutation", r.order_is_permutation},
                     {"keys_hash", r.keys_hash},
                     {"order_hash", r.order_hash},
                     {"leaks_per_million", r.leaks_per_million}};
  timing_to_json(j, "encode", r.encode);
  timing_to_json(j, "sort", r.sort);
  timing_to_json(j, "trace", r.trace);
}

void from_json(const nlohmann::json& j, CellRecord& r) {
  int version = j.value("format_version", 0);
  if (version != kResultFormatVersion)
    throw std::runtime_error(fmt::format("cell record has format version {}, this raysort reads version {}", version,
                                         kResultFormatVersion));
  j.at("scene").get_to(r.scene);
  j.at("batch").get_to(r.batch);
  j.at("encoder").get_to(r.encoder);
  j.at("bits").get_to(r.bits);
  j.at("top_bits").get_to(r.top_bits);
  j.at("variant").get_to(r.variant);
  j.at("access").get_to(r.access);
  j.at("rays").get_to(r.rays);
  j.at("status").get_to(r.status);
  j.at("error").get_to(r.error);
  j.at("trace_mrays").get_to(r.trace_mrays);
  j.at("speedup").get_to(r.speedup);
  j.at("net_speedup").get_to(r.net_speedup);
  j.at("overhead_pct").get_to(r.overhead_pct);
  j.at("anc").get_to(r.anc);
  j.at("simt_lane_efficiency").get_to(r.simt_lane_efficiency);
  j.at("simt_distinct_per_visit").get_to(r.simt_distinct_per_visit);
  j.at("simt_lane_efficiency_ratio").get_to(r.simt_lane_efficiency_ratio);
  j.at("simt_distinct_per_visit_ratio").get_to(r.simt_distinct_per_visit_ratio);
  j.at("hits_match_nosort").get_to(r.hits_match_nosort);
  j.at("order_is_permutation").get_to(r.order_is_permutation);
  j.at("keys_hash").get_to(r.keys_hash);
  j.at("order_hash").get_to(r.order_hash);
  r.leaks_per_million = j.value("leaks_per_million", -1.0);  // added within format version 1
  timing_from_json(j, "encode", r.encode);
  timing_from_json(j, "sort", r.sort);
  timing_from_json(j, "trace", r.trace);
}

std::string fnv1a_hex(const void* data, std::size_t bytes) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  auto p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ull;
  }
  return fmt::format("{:016x}", h);
}

std::string csv_header() {
  return "id,scene,batch,encoder,bits,top_bits,variant,access,rays,status,"
         "encode_ms,encode_min_ms,encode_max_ms,sort_ms,sort_min_ms,sort_max_ms,trace_ms,trace_min_ms,trace_max_ms,"
         "trace_mrays,speedup,net_speedup,overhead_pct,anc,simt_lane_efficiency,simt_distinct_per_visit,"
         "simt_lane_efficiency_ratio,simt_distinct_per_visit_ratio,hits_match_nosort,order_is_permutation,"
         "keys_hash,order_hash,error";
}

std::string csv_row(const CellRecord& r) {
  std::string err = r.error;
  std::replace(err.begin(), err.end(), '"', '\'');
  std::replace(err.begin(), err.end(), '\n', ' ');
  return fmt::format(
      "{},{},{},{},{},{},{},{},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},"
      "{:.3f},{:.4f},{:.6f},{:.6f},{:.6f},{:.6f},{},{},{},{},\"{}\"",
      r.id(), r.scene, r.batch, r.encoder, r.bits, r.top_bits, r.variant, r.access, r.rays, r.status, r.encode.median_ms,
      r.encode.min_ms, r.encode.max_ms, r.sort.median_ms, r.sort.min_ms, r.sort.max_ms, r.trace.median_ms, r.trace.min_ms,
      r.trace.max_ms, r.trace_mrays, r.speedup, r.net_speedup, r.overhead_pct, r.anc, r.simt_lane_efficiency,
      r.simt_distinct_per_visit, r.simt_lane_efficiency_ratio, r.simt_distinct_per_visit_ratio, r.hits_match_nosort,
      r.order_is_permutation, r.keys_hash, r.order_hash, err);
}

}  // namespace raysort
