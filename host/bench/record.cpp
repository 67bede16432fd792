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

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A number that may be NaN (no interval): JSON null.
nlohmann::json number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }
double number_from(const nlohmann::json& j) { return j.is_null() ? kNaN : j.get<double>(); }

nlohmann::json estimate_json(const Estimate& e) {
  return {{"value", number(e.value)}, {"lo", number(e.lo)}, {"hi", number(e.hi)}, {"n", e.n}};
}
Estimate estimate_from(const nlohmann::json& j) {
  // Format version 1 stored a point figure.
  if (j.is_number()) return {j.get<double>(), kNaN, kNaN, 0};
  return {number_from(j.at("value")), number_from(j.at("lo")), number_from(j.at("hi")), j.at("n").get<std::size_t>()};
}

void timing_to_json(nlohmann::json& j, const char* name, const Timing& t) {
  j[std::string(name) + "_ms"] = {{"median", t.median_ms}, {"lo", number(t.lo_ms)}, {"hi", number(t.hi_ms)},
                                  {"min", t.min_ms},       {"max", t.max_ms},       {"n", t.n}};
}
void timing_from_json(const nlohmann::json& j, const char* name, Timing& t) {
  const std::string key = std::string(name) + "_ms";
  if (!j.contains(key)) return;  // version 1 has no permute or nosort_trace timing
  const auto& o = j.at(key);
  t.median_ms = o.at("median").get<double>();
  t.min_ms = o.at("min").get<double>();
  t.max_ms = o.at("max").get<double>();
  t.lo_ms = o.contains("lo") ? number_from(o.at("lo")) : kNaN;
  t.hi_ms = o.contains("hi") ? number_from(o.at("hi")) : kNaN;
  t.n = o.value("n", std::size_t{0});
}

}  // namespace

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
                     {"speedup", estimate_json(r.speedup)},
                     {"net_speedup", estimate_json(r.net_speedup)},
                     {"overhead_pct", estimate_json(r.overhead_pct)},
                     {"aa", estimate_json(r.aa)},
                     {"same_order_as_nosort", r.same_order_as_nosort},
                     {"rounds", r.rounds},
                     {"stopped_by", r.stopped_by},
                     {"noise", number(r.noise)},
                     {"samples", r.samples},
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
  timing_to_json(j, "permute", r.permute);
  timing_to_json(j, "trace", r.trace);
  timing_to_json(j, "nosort_trace", r.nosort_trace);
}

void from_json(const nlohmann::json& j, CellRecord& r) {
  int version = j.value("format_version", 0);
  if (version < kOldestReadableFormatVersion || version > kResultFormatVersion)
    throw std::runtime_error(fmt::format("cell record has format version {}, this raysort reads versions {} to {}",
                                         version, kOldestReadableFormatVersion, kResultFormatVersion));
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
  r.speedup = estimate_from(j.at("speedup"));
  r.net_speedup = estimate_from(j.at("net_speedup"));
  r.overhead_pct = estimate_from(j.at("overhead_pct"));
  if (version >= 2) {
    r.aa = estimate_from(j.at("aa"));
    j.at("same_order_as_nosort").get_to(r.same_order_as_nosort);
    j.at("rounds").get_to(r.rounds);
    j.at("stopped_by").get_to(r.stopped_by);
    r.noise = number_from(j.at("noise"));
    j.at("samples").get_to(r.samples);
  }
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
  timing_from_json(j, "permute", r.permute);
  timing_from_json(j, "trace", r.trace);
  timing_from_json(j, "nosort_trace", r.nosort_trace);
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

namespace {
// An empty CSV field for a missing figure (no interval).
std::string csv_number(double x, int decimals) { return std::isfinite(x) ? fmt::format("{:.{}f}", x, decimals) : ""; }
std::string csv_estimate(const Estimate& e, int decimals) {
  return csv_number(e.value, decimals) + "," + csv_number(e.lo, decimals) + "," + csv_number(e.hi, decimals);
}
std::string csv_timing(const Timing& t) {
  return fmt::format("{:.4f},{},{},{:.4f},{:.4f}", t.median_ms, csv_number(t.lo_ms, 4), csv_number(t.hi_ms, 4),
                     t.min_ms, t.max_ms);
}
}  // namespace

std::string csv_header() {
  std::string timing_cols;
  for (const char* t : {"encode", "sort", "permute", "trace", "nosort_trace"})
    timing_cols += fmt::format("{0}_ms,{0}_lo_ms,{0}_hi_ms,{0}_min_ms,{0}_max_ms,", t);
  return "id,scene,batch,encoder,bits,top_bits,variant,access,rays,status," + timing_cols +
         "trace_mrays,speedup,speedup_lo,speedup_hi,net_speedup,net_speedup_lo,net_speedup_hi,"
         "overhead_pct,overhead_pct_lo,overhead_pct_hi,aa,aa_lo,aa_hi,same_order_as_nosort,rounds,stopped_by,noise,"
         "anc,simt_lane_efficiency,simt_distinct_per_visit,simt_lane_efficiency_ratio,simt_distinct_per_visit_ratio,"
         "hits_match_nosort,order_is_permutation,keys_hash,order_hash,error";
}

std::string csv_row(const CellRecord& r) {
  std::string err = r.error;
  std::replace(err.begin(), err.end(), '"', '\'');
  std::replace(err.begin(), err.end(), '\n', ' ');
  std::string timings;
  for (const Timing* t : {&r.encode, &r.sort, &r.permute, &r.trace, &r.nosort_trace}) timings += csv_timing(*t) + ",";
  return fmt::format("{},{},{},{},{},{},{},{},{},{},{}{:.4f},{},{},{},{},{},{},{},{},{:.4f},{:.6f},{:.6f},{:.6f},{:.6f},{},{},{},{},\"{}\"",
                     r.id(), r.scene, r.batch, r.encoder, r.bits, r.top_bits, r.variant, r.access, r.rays, r.status,
                     timings, r.trace_mrays, csv_estimate(r.speedup, 4), csv_estimate(r.net_speedup, 4),
                     csv_estimate(r.overhead_pct, 3), csv_estimate(r.aa, 4), r.same_order_as_nosort, r.rounds,
                     r.stopped_by, csv_number(r.noise, 5), r.anc, r.simt_lane_efficiency, r.simt_distinct_per_visit,
                     r.simt_lane_efficiency_ratio, r.simt_distinct_per_visit_ratio, r.hits_match_nosort,
                     r.order_is_permutation, r.keys_hash, r.order_hash, err);
}

}  // namespace raysort
