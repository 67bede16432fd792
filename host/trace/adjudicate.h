#pragma once
// Adjudication (issue 23): where the answers of the trace variants (and Embree) to a batch differ,
// the exact oracle (trace/exact_oracle.h) decides each ray, and each answer is counted right, tie
// or wrong. `raysort trace --adjudicate` prints the counts; the disagreement rays are saved for a
// regression test (tests/data/disagreements/, replayed by tests/adjudicate_test.cpp).
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "render/rays.h"
#include "trace/exact_oracle.h"

namespace raysort {

struct AnswerSet {
  std::string name;                // "robust", "fast", "embree"
  const std::vector<RsHit>* hits;  // in ray order; any-hit answers: tri != RS_NO_HIT is occluded
};

struct Adjudication {
  std::vector<std::uint32_t> rays;    // indices of the rays judged (where the answers differ)
  // Of those, the rays whose answers got different verdicts (one right and one tie, or one wrong):
  // the telling ones, kept as a regression file (all-tie rays, mostly coplanar duplicate faces, are
  // many and say little).
  std::vector<std::uint32_t> telling;
  std::vector<VerdictCounts> counts;  // per answer set, in the order given
  std::vector<std::string> wrong;     // the first few wrong answers, described (ray, answer, truth)
};

// Judges every ray of `batch` on which the answer sets do not all agree (closest: the same
// triangle or all missed; any hit: the same occluded/free answer).
Adjudication adjudicate(const ExactOracle& oracle, const RayBatch& batch, const std::vector<AnswerSet>& answers);

// Rays as exact text (hexadecimal floats: o, tmin, d, tmax), for a regression file.
nlohmann::json rays_to_json(const std::vector<RsRay>& rays);
std::vector<RsRay> rays_from_json(const nlohmann::json& j);  // throws Error on malformed input

}  // namespace raysort
