#pragma once
// The Embree anchor (issue 9): the same triangles in an Embree 3 scene (build quality high), the
// same rays traced by one of Embree's CPU paths (single rays, ray streams, ray packets: EmbreePath)
// on every host thread, and the agreement of its hits with ours. Compiled into raysort_core only
// when CMake found Embree (RAYSORT_HAVE_EMBREE; option RAYSORT_EMBREE=AUTO|ON|OFF); see
// docs/trace.md, "Embree anchor".
//
// Ray semantics (cl/shared.h): RsRay's (o, tmin, d, tmax) become Embree's (org, tnear, dir, tfar);
// both intersectors are two-sided (Debian's Embree is built without backface culling, and the scene
// sets no culling flag). Ours accepts tmin < t < tmax, Embree tnear <= t <= tfar: the two differ
// only on rays whose hit lies exactly on an interval end. Triangle ids: one Embree geometry holds
// the flattened triangles in order, so Embree's primID is our RsHit::tri.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "shared.h"
#include "util/error.h"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace raysort {

// What rtcOccluded1 reports for an occluded shadow ray: occluded, triangle unknown.
inline constexpr std::uint32_t kEmbreeOccluded = 0xFFFFFFFEu;

// How Embree is asked to trace a batch: which API call, how many rays per call, which context
// flag. Every path traces the same rays in the order given (a permutation, when one is given), on
// threads() threads that each take contiguous chunks of 4096 rays; a packet is consecutive rays of
// that order, a stream a thread's whole chunk.
enum class EmbreePath {
  Single,            // rtcIntersect1 / rtcOccluded1, ray by ray (the anchor since issue 9)
  StreamIncoherent,  // rtcIntersect1M / rtcOccluded1M over the chunk, RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT
  StreamCoherent,    // the same with RTC_INTERSECT_CONTEXT_FLAG_COHERENT (Embree's coherent stream traversal)
  Packet4,           // rtcIntersect4/8/16 / rtcOccluded4/8/16 on consecutive rays, incoherent flag
  Packet8,
  Packet16,
  Packet4Coherent,   // the same packets with the coherent flag (Embree's frustum packet traversal)
  Packet8Coherent,
  Packet16Coherent,
};

// One row per path: the only list of them (the parser, names and trace() all read it).
struct EmbreePathInfo {
  EmbreePath path;
  const char* key;        // its name on the command line (--embree-paths)
  const char* intersect;  // the closest-hit call
  const char* occluded;   // the any-hit call
  unsigned packet;        // rays per call: 1 single, 4/8/16 a packet, 0 a stream (the thread's chunk)
  bool coherent;          // context flag RTC_INTERSECT_CONTEXT_FLAG_COHERENT, else _INCOHERENT
};

inline constexpr EmbreePathInfo kEmbreePaths[] = {
    {EmbreePath::Single, "1", "rtcIntersect1", "rtcOccluded1", 1, false},
    {EmbreePath::StreamIncoherent, "1M", "rtcIntersect1M", "rtcOccluded1M", 0, false},
    {EmbreePath::StreamCoherent, "1M-coherent", "rtcIntersect1M", "rtcOccluded1M", 0, true},
    {EmbreePath::Packet4, "4", "rtcIntersect4", "rtcOccluded4", 4, false},
    {EmbreePath::Packet8, "8", "rtcIntersect8", "rtcOccluded8", 8, false},
    {EmbreePath::Packet16, "16", "rtcIntersect16", "rtcOccluded16", 16, false},
    {EmbreePath::Packet4Coherent, "4-coherent", "rtcIntersect4", "rtcOccluded4", 4, true},
    {EmbreePath::Packet8Coherent, "8-coherent", "rtcIntersect8", "rtcOccluded8", 8, true},
    {EmbreePath::Packet16Coherent, "16-coherent", "rtcIntersect16", "rtcOccluded16", 16, true},
};

const EmbreePathInfo& embree_path_info(EmbreePath path);
// The call and its flag: "rtcIntersect1" (the single path keeps its name of issue 9; its context
// has the default flag, incoherent), "rtcIntersect1M incoherent", "rtcOccluded16 coherent".
std::string embree_path_name(EmbreePath path, bool any_hit);
// "rtcIntersect8 incoherent / rtcOccluded8 incoherent": both calls, for a header.
std::string embree_path_calls(EmbreePath path);
// A comma-separated list of keys ("1,1M,16-coherent"), or "all" for every path in table order;
// repeated keys count once. Throws Error naming the unknown key and listing the valid ones.
std::vector<EmbreePath> parse_embree_paths(const std::string& list);

// The instruction sets Embree may be held to (trace and run --embree-isa): "native" lets Embree
// choose the widest this CPU runs; any other asks rtcNewDevice for that one ("isa=avx2"), so that a
// CPU with AVX-512 runs the kernels an AVX2 CPU would (docs/trace.md, "Embree anchor": with PoCL
// held to the same set, a same-ISA comparison on one machine). The only list of them.
inline constexpr const char* kEmbreeIsas[] = {"native", "sse2", "sse4.2", "avx", "avx2", "avx512"};
// Throws Error naming the value and listing kEmbreeIsas when isa is not one of them (inline: a build
// without Embree checks a matrix's --embree-isa too).
inline void check_embree_isa(const std::string& isa) {
  std::string list;
  for (const char* known : kEmbreeIsas) {
    if (isa == known) return;
    list += (list.empty() ? "" : ", ") + std::string(known);
  }
  throw Error("unknown Embree instruction set '" + isa + "' in --embree-isa; the sets are " + list);
}

// One Embree device and the scene of one triangle list. Not copyable.
class EmbreeScene {
 public:
  // threads 0: std::thread::hardware_concurrency(). Used for Embree's own build threads (TBB) and
  // for the trace threads. isa: one of kEmbreeIsas. Throws Error when Embree reports one (an ISA
  // this CPU does not run among them).
  explicit EmbreeScene(const Scene::Flat& tris, unsigned threads = 0, const std::string& isa = "native");
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  unsigned threads() const { return threads_; }
  const std::string& isa() const { return isa_; }  // as asked: "native" or the set Embree was held to
  double build_ms() const { return build_ms_; }  // rtcCommitScene (BVH build), wall clock
  static std::string version();                  // "3.13.5"

  // Traces every ray (closest hit, or any hit when any_hit) with rtcIntersect1 / rtcOccluded1 on
  // threads() threads, each taking contiguous chunks of the batch. Closest: hits[i] = (tfar,
  // primID, u, v), or (tmax, RS_NO_HIT, 0, 0) for a miss. Any hit: (0, kEmbreeOccluded, 0, 0) or
  // (tmax, RS_NO_HIT, 0, 0). Timed traces go through the measurement protocol (bench/protocol.h),
  // by wall clock.
  std::vector<RsHit> trace(const std::vector<RsRay>& rays, bool any_hit) const;
  // The same with any path, its hits reported exactly as above. With an order (as many entries as
  // rays, each below rays.size(); Error otherwise), hits[i] is the hit of rays[order[i]] and the
  // rays are traced in that order: a packet or stream holds consecutive entries of it.
  std::vector<RsHit> trace(const std::vector<RsRay>& rays, bool any_hit, EmbreePath path,
                           std::span<const std::uint32_t> order = {}) const;
  // Whether this CPU runs packets of `width` rays (4, 8, 16) natively; otherwise Embree splits
  // them (16 rays without AVX-512). RTC_DEVICE_PROPERTY_NATIVE_RAY{4,8,16}_SUPPORTED.
  bool native_packets(unsigned width) const;

 private:
  RTCDeviceTy* device_ = nullptr;
  RTCSceneTy* scene_ = nullptr;
  unsigned threads_ = 1;
  std::string isa_ = "native";
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
