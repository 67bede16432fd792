#pragma once
// `raysort trace --build-rounds N`: our BVH build (build_bvh, every host thread) and, with
// --reference embree, Embree 3's high-quality build (rtcCommitScene on its own threads), timed in
// N alternated rounds of the measurement protocol (bench/protocol.h: the two arms in a seeded
// random order each round), so the ratio of the two is paired and comes with its interval.
#include <cstdint>
#include <optional>
#include <string>

#include "bench/protocol.h"
#include "scene/scene.h"

namespace raysort {

struct BuildTiming {
  unsigned rounds = 0;
  unsigned threads = 0;          // ours (host_threads())
  Timing ours;                   // build_bvh's build_ms: SAH build, leaf order and 4-wide collapse
  double sah_cost = 0.0;         // of our tree (the same every round)
  std::optional<Timing> embree;  // rtcCommitScene, a fresh Embree scene each round
  unsigned embree_threads = 0;
  std::string embree_isa = "native";  // --embree-isa (embree/embree_reference.h kEmbreeIsas)
  Estimate ratio;                // ours / Embree per round, Hodges–Lehmann with its signed-rank interval
};

// Times the builds over `tris`, `rounds` timed rounds after one untimed warm-up round; Embree's
// arm only when with_embree (and this build has Embree: otherwise an Error), on the instruction set
// embree_isa.
BuildTiming time_builds(const Scene::Flat& tris, unsigned rounds, bool with_embree, std::uint64_t seed,
                        const std::string& embree_isa = "native");

// The lines trace prints for it: "build    7 rounds alternated: ours 41.20 [40.10, 44.00] ms on 2 threads, ...".
std::string build_timing_text(const BuildTiming& t);

}  // namespace raysort
