#pragma once
// An exact oracle for the nearest hit (issue 23): which triangle a ray really hits first, decided
// with exact rational arithmetic (GMP), to judge the answers of the robust and fast variants and of
// Embree where they disagree.
//
// The ray and the triangles are what the tracers see: float origin, direction and [tmin, tmax] of
// RsRay (ours accepts tmin < t < tmax), float vertices of the scene's flat triangle list. A
// triangle is hit when the line o + t·d meets the closed triangle at tmin < t < tmax; the
// Möller–Trumbore quantities (det, u·det, v·det, t·det) are computed as exact rationals, so hit or
// miss and the order of two hits are decided without rounding. A zero-area triangle (det = 0 for
// every ray) and a ray in a triangle's plane (det = 0) do not hit it: the intersection has no area.
//
// An answer is judged against that truth:
//   right  the answer is the unique nearest triangle (or a miss, and nothing is hit);
//   tie    the answer is correct up to float precision: one of several triangles at exactly the
//          nearest t (a shared edge or vertex, coplanar duplicates), or a surface that lies within
//          kUlps float ulps (of the coordinates' magnitude) of the nearest hit: a hit grazing an
//          edge, a depth difference below float resolution, a hit on an end of [tmin, tmax];
//   wrong  anything else: a surface clearly in front was skipped, a clear miss was reported as a
//          hit, or a clear hit was missed. A point where two or more triangles meet at exactly the
//          nearest t (the ray goes through a shared edge or vertex) counts as clearly hit: slipping
//          through it is a leak, however thin the crack.
// Any-hit rays (shadow rays) are judged on occluded / free in the same terms.
#include <cstdint>
#include <string>
#include <vector>

#include "bvh/bvh.h"
#include "scene/scene.h"
#include "shared.h"

namespace raysort {

enum class Verdict { Right, Tie, Wrong };
const char* verdict_name(Verdict v);

// What exactly the ray meets: every triangle it hits, or nearly hits (within the tolerance), with
// its depth. Built by ExactOracle::truth.
struct ExactTruth {
  struct Surface {
    std::uint32_t tri = RS_NO_HIT;
    bool hit = false;      // exact: the closed triangle is met at tmin < t < tmax
    bool firm = false;     // hit, and farther than the tolerance from its edges and from tmin/tmax
    bool nearest = false;  // hit at exactly the smallest t of all hits
    double t = 0.0;        // the line's t at the triangle's plane (rounded from the exact value)
    double gap = 0.0;      // how far outside the triangle (or [tmin, tmax]) the point lies; 0 on a hit
  };
  bool any_hit = false;
  double tolerance = 0.0;          // the distance kUlps ulps stand for on this ray
  double dir_length = 1.0;         // |d|: a difference in t times this is a distance
  std::vector<Surface> surfaces;   // hits and near misses, nearest first
  std::size_t nearest_count() const;
  bool hit() const;                // any exact hit
  double nearest_t() const;        // t of the nearest exact hit (RS_T_FAR when none)
  // "tri 12 at t 3.25 (hit, nearest)" lines, for a report.
  std::string describe() const;
};

class ExactOracle {
 public:
  // The tolerance of a tie, in float ulps of the coordinates' magnitude along the ray.
  static constexpr double kUlps = 64.0;

  // `tris` is the scene's flat list (what hits report as tri); `bvh` was built from it (its binary
  // tree narrows the candidates: boxes are widened by far more than the tolerance).
  ExactOracle(const Scene::Flat& tris, const Bvh& bvh);
  ExactTruth truth(const RsRay& ray, bool any_hit) const;
  // Judges one answer: a closest hit (tri, or RS_NO_HIT), or for any-hit rays occluded (tri !=
  // RS_NO_HIT, whatever the id) or free.
  static Verdict judge(const ExactTruth& truth, const RsHit& answer);

  std::size_t exact_tests() const { return exact_tests_; }  // triangles decided in rational arithmetic

 private:
  const Scene::Flat& tris_;
  const Bvh& bvh_;
  mutable std::size_t exact_tests_ = 0;
};

// Verdict counts of one answer set over the rays judged.
struct VerdictCounts {
  std::size_t right = 0, tie = 0, wrong = 0;
  void add(Verdict v) { (v == Verdict::Right ? right : v == Verdict::Tie ? tie : wrong) += 1; }
  std::size_t total() const { return right + tie + wrong; }
};

}  // namespace raysort
