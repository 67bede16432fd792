#pragma once
// The Embree anchor (issue 9): the same triangles in an Embree 3 scene (build quality high), the
// same rays traced with rtcIntersect1 (closest hit) / rtcOccluded1 (shadow rays, any hit) on every
// host thread, and the agreement of its hits with ours. Compiled into raysort_core only when CMake
// found Embree (RAYSORT_HAVE_EMBREE; option RAYSORT_EMBREE=AUTO|ON|OFF); see docs/trace.md,
// "Embree anchor".
//
// Ray semantics (cl/shared.h): RsRay's (o, tmin, d, tmax) become Embree's (org, tnear, dir, tfar);
// both intersectors are two-sided (Debian's Embree is built without backface culling, and the scene
// sets no culling flag). Ours accepts tmin < t < tmax, Embree tnear <= t <= tfar: the two differ
// only on rays whose hit lies exactly on an interval end. Triangle ids: one Embree geometry holds
// the flattened triangles in order, so Embree's primID is our RsHit::tri.
#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "shared.h"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace raysort {

// What rtcOccluded1 reports for an occluded shadow ray: occluded, triangle unknown.
inline constexpr std::uint32_t kEmbreeOccluded = 0xFFFFFFFEu;

// One Embree device and the scene of one triangle list. Not copyable.
class EmbreeScene {
 public:
  // threads 0: std::thread::hardware_concurrency(). Used for Embree's own build threads (TBB) and
  // for the trace threads. Throws Error when Embree reports one.
  explicit EmbreeScene(const Scene::Flat& tris, unsigned threads = 0);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  unsigned threads() const { return threads_; }
  double build_ms() const { return build_ms_; }  // rtcCommitScene (BVH build), wall clock
  static std::string version();                  // "3.13.5"

  // Traces every ray (closest hit, or any hit when any_hit) on threads() threads, each taking
  // contiguous chunks of the batch. Closest: hits[i] = (tfar, primID, u, v) or tri = RS_NO_HIT.
  // Any hit: tri = kEmbreeOccluded (t = 0) or RS_NO_HIT.
  // Timed traces go through the measurement protocol (bench/protocol.h), by wall clock.
  std::vector<RsHit> trace(const std::vector<RsRay>& rays, bool any_hit) const;

 private:
  RTCDeviceTy* device_ = nullptr;
  RTCSceneTy* scene_ = nullptr;
  unsigned threads_ = 1;
  double build_ms_ = 0.0;
};

// How our hits and Embree's compare, ray by ray (both in ray order).
struct HitAgreement {
  bool any_hit = false;
  std::size_t rays = 0;
  std::size_t same = 0;         // same triangle (or both missed); any hit: same occluded/free answer
  // Closest: both hit, different triangles at the same distance (|Δt| <= kTieRelT · max(t, 1)).
  std::size_t tie_edge = 0;     // ... with a hit within kEdgeBary of an edge: a tie on a shared edge/vertex
  std::size_t tie_overlap = 0;  // ... inside both triangles: coplanar overlapping (duplicated) faces
  std::size_t other_tri = 0;    // closest: both hit, different triangle, farther apart
  std::size_t ours_only = 0;    // ours hit (occluded), Embree missed (free)
  std::size_t embree_only = 0;  // Embree hit (occluded), ours missed (free)
  double max_rel_dt = 0.0;      // closest: max |Δt| / max(t, 1) over same-triangle hits
  static constexpr double kTieRelT = 1e-4;
  static constexpr float kEdgeBary = 1e-3f;  // min(u, v, 1-u-v) below this: on an edge or vertex
  std::size_t ties() const { return tie_edge + tie_overlap; }
  // Same triangle: the figure the anchor requires (kEmbreeMinAgreement).
  double fraction() const { return rays ? static_cast<double>(same) / static_cast<double>(rays) : 1.0; }
  // Same triangle or the same surface point (a tie): the hits agree as far as geometry decides.
  double fraction_with_ties() const {
    return rays ? static_cast<double>(same + ties()) / static_cast<double>(rays) : 1.0;
  }
  std::size_t differences() const { return rays - same; }
  // "3 ties on a shared edge, 1 ours hit / Embree missed" (empty when none differ).
  std::string describe() const;
};

// The agreement the anchor requires, of fraction_with_ties() in `raysort trace` (real scenes have
// coplanar duplicated faces, where the triangle of a tie is arbitrary) and of fraction() in the
// tests on the procedural scenes.
inline constexpr double kEmbreeMinAgreement = 0.999;

HitAgreement compare_with_embree(const std::vector<RsHit>& ours, const std::vector<RsHit>& embree, bool any_hit);

}  // namespace raysort
