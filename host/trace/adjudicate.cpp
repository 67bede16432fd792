#include "trace/adjudicate.h"

#include <fmt/format.h>

#include <cstdlib>

#include "util/error.h"

namespace raysort {

namespace {

bool agree(const RsHit& a, const RsHit& b, bool any_hit) {
  return any_hit ? (a.tri != RS_NO_HIT) == (b.tri != RS_NO_HIT) : a.tri == b.tri;
}

std::string ray_text(const RsRay& r) {
  return fmt::format("o ({:a}, {:a}, {:a}) d ({:a}, {:a}, {:a}) t ({:a}, {:a})", r.o[0], r.o[1], r.o[2], r.d[0],
                     r.d[1], r.d[2], r.tmin, r.tmax);
}

}  // namespace

Adjudication adjudicate(const ExactOracle& oracle, const RayBatch& batch, const std::vector<AnswerSet>& answers) {
  constexpr std::size_t kWrongShown = 5;
  Adjudication out;
  out.counts.resize(answers.size());
  const bool any_hit = batch.any_hit();
  for (std::size_t i = 0; i < batch.size(); ++i) {
    bool all_agree = true;
    for (std::size_t a = 1; a < answers.size() && all_agree; ++a)
      all_agree = agree((*answers[0].hits)[i], (*answers[a].hits)[i], any_hit);
    if (all_agree) continue;
    out.rays.push_back(static_cast<std::uint32_t>(i));
    const ExactTruth truth = oracle.truth(batch.rays[i], any_hit);
    bool differ = false;
    Verdict first = Verdict::Right;
    for (std::size_t a = 0; a < answers.size(); ++a) {
      const RsHit& h = (*answers[a].hits)[i];
      const Verdict v = ExactOracle::judge(truth, h);
      if (a == 0) first = v;
      differ = differ || v != first;
      out.counts[a].add(v);
      if (v == Verdict::Wrong && out.wrong.size() < kWrongShown)
        out.wrong.push_back(fmt::format("{} ray {} ({}): {} answered {}; exactly:\n{}", batch.name, i,
                                        ray_text(batch.rays[i]), answers[a].name,
                                        h.tri == RS_NO_HIT ? std::string("a miss")
                                        : any_hit          ? std::string("occluded")
                                                           : fmt::format("tri {} at t {:.9g}", h.tri, h.t),
                                        truth.describe()));
    }
    if (differ) out.telling.push_back(static_cast<std::uint32_t>(i));
  }
  return out;
}

nlohmann::json rays_to_json(const std::vector<RsRay>& rays) {
  nlohmann::json arr = nlohmann::json::array();
  for (const RsRay& r : rays)
    arr.push_back(fmt::format("{:a} {:a} {:a} {:a} {:a} {:a} {:a} {:a}", r.o[0], r.o[1], r.o[2], r.tmin, r.d[0], r.d[1],
                              r.d[2], r.tmax));
  return arr;
}

std::vector<RsRay> rays_from_json(const nlohmann::json& j) {
  if (!j.is_array()) throw Error("rays: expected a list of \"ox oy oz tmin dx dy dz tmax\" strings");
  std::vector<RsRay> rays;
  for (const auto& e : j) {
    if (!e.is_string()) throw Error("rays: expected a list of \"ox oy oz tmin dx dy dz tmax\" strings");
    const std::string s = e.get<std::string>();
    const char* p = s.c_str();
    float v[8];
    for (float& x : v) {
      char* end = nullptr;
      x = std::strtof(p, &end);
      if (end == p) throw Error(fmt::format("rays: '{}' is not 8 numbers", s));
      p = end;
    }
    RsRay r{};
    r.o[0] = v[0], r.o[1] = v[1], r.o[2] = v[2], r.tmin = v[3], r.d[0] = v[4], r.d[1] = v[5], r.d[2] = v[6], r.tmax = v[7];
    rays.push_back(r);
  }
  return rays;
}

}  // namespace raysort
