// `raysort trace --build-rounds N` (build_timing.h).
#include "app/build_timing.h"

#include <fmt/format.h>

#include "app/options.h"
#include "bvh/bvh.h"
#include "util/error.h"
#include "util/parallel.h"
#ifdef RAYSORT_HAVE_EMBREE
#include "embree/embree_reference.h"
#endif

namespace raysort {

BuildTiming time_builds(const Scene::Flat& tris, unsigned rounds, bool with_embree, std::uint64_t seed,
                        const std::string& embree_isa) {
#ifndef RAYSORT_HAVE_EMBREE
  if (with_embree) throw Error("this build has no Embree: install libembree-dev and reconfigure");
#endif
  BuildTiming t;
  t.embree_isa = embree_isa;
  t.rounds = rounds;
  t.threads = host_threads();
  Measurement m;
  m.arms.push_back({{"ours"}, [&] {
                      const Bvh bvh = build_bvh(tris);
                      t.sah_cost = bvh.sah_cost;
                      return std::vector<double>{bvh.build_ms};
                    }});
#ifdef RAYSORT_HAVE_EMBREE
  if (with_embree)
    m.arms.push_back({{"embree"}, [&] {
                        const EmbreeScene scene(tris, 0, embree_isa);
                        t.embree_threads = scene.threads();
                        return std::vector<double>{scene.build_ms()};
                      }});
#endif
  ProtocolSettings s;
  s.warmup = 1;
  s.min_rounds = s.max_rounds = rounds;
  s.max_time_s = kMaxSeconds;
  s.seed = seed;
  const Outcome o = measure(m, s);
  t.ours = Timing::of(o.series.at("ours"));
  if (with_embree) {
    t.embree = Timing::of(o.series.at("embree"));
    t.ratio = ratio_interval(o.series.at("ours"), o.series.at("embree"));
  }
  return t;
}

std::string build_timing_text(const BuildTiming& t) {
  std::string text = fmt::format("build    {} rounds alternated, medians with 95 % intervals: ours {} ms on {} threads, SAH cost {:.4f}",
                                 t.rounds, interval_text(t.ours.estimate(), 2), t.threads, t.sah_cost);
  if (t.embree) {
#ifdef RAYSORT_HAVE_EMBREE
    text += fmt::format("\n         Embree {}{} build quality high, {} threads: {} ms; ours/Embree {}", EmbreeScene::version(),
                        t.embree_isa == "native" ? "" : " held to " + t.embree_isa + ",", t.embree_threads,
                        interval_text(t.embree->estimate(), 2), interval_text(t.ratio));
#endif
  }
  return text;
}

}  // namespace raysort
