// raysort trace: load a scene, build its BVH, generate the batches its effects imply, trace each
// on the device and check every hit against the host reference (the same traversal source).
// --variant robust|fast picks the traversal arithmetic (docs/trace.md); --variant both runs the two
// back to back on every batch and prints the robust/fast speed ratio and how many hits differ.
// --reference embree traces every batch with Embree 3 as well, side by side in this process, and
// prints its MRays/s, ours/Embree, and how many hits agree (docs/trace.md, "Embree anchor");
// --embree-paths makes each of Embree's paths (single rays, streams, packets) an arm of its own.
// --build-rounds N times our BVH build (and Embree's, with --reference embree) in N alternated
// rounds and stops there (app/build_timing.h).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <optional>

#include "app/build_timing.h"
#include "app/commands.h"
#include "app/options.h"
#include "bench/batch_file.h"
#include "bench/protocol.h"
#include "bvh/prepared_scene.h"
#include "render/frame_memory.h"
#include "runtime/runtime.h"
#ifdef RAYSORT_HAVE_EMBREE
#include "embree/embree_reference.h"
#endif
#include "render/batches.h"
#include "trace/adjudicate.h"
#include "trace/tracer.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/output_name.h"
#include "util/parallel.h"

namespace raysort {

namespace {

struct TraceArgs {
  std::vector<std::string> scenes;
  CommonOptions common;
  ProtocolOptions protocol;
  std::string variant = "robust";
  std::string layout = "wide";
  std::string reference;  // "" or "embree"
  std::optional<std::string> embree_paths;  // --embree-paths; none: "1" (rtcIntersect1 alone, the columns of issue 9)
  std::optional<std::string> embree_isa;    // --embree-isa; none: native (embree/embree_reference.h kEmbreeIsas)
  bool adjudicate = false;       // judge every ray the answers differ on, exactly (trace/adjudicate.h)
  std::string disagreements;     // with adjudicate: write those rays to DIR/<scene>.json
  unsigned build_rounds = 0;     // > 0: time the BVH builds in this many rounds and stop
  std::string rays;              // --rays FILE: trace this batch (bench/batch_file.h) instead of the generated ones
};

#ifdef RAYSORT_HAVE_EMBREE
// Embree beside our kernels: its scene, and its paths, each an arm of every batch's rounds.
struct EmbreeReference {
  const EmbreeScene& scene;
  std::vector<EmbreePath> paths;
  // Only rtcIntersect1: the batch row keeps the Embree columns of issue 9, and no path lines follow.
  bool single_only() const { return paths.size() == 1 && paths[0] == EmbreePath::Single; }
};
#else
struct EmbreeReference {};
#endif

// One Embree path's arm on one batch.
struct EmbreeRun {
  std::string key;    // its --embree-paths name: "1M-coherent"
  std::string name;   // the call it makes on this batch, with its flag: "rtcIntersect1M coherent"
  std::string stage;  // its series in the measurement: "embree:1M-coherent"
  Timing ms;
  std::vector<RsHit> hits;  // ray order
};

// One batch traced by each variant (and Embree's paths), all arms of the same rounds of the
// measurement protocol (bench/protocol.h): their times and ratios are paired.
struct BatchRun {
  std::vector<std::vector<RsHit>> hits;  // per variant, ray order
  std::vector<Timing> ms;                // per variant
  std::vector<std::size_t> mismatches;   // per variant, against the host reference of that variant
  std::size_t hit_count = 0;             // hits of the first variant's reference
  std::vector<EmbreeRun> embree;         // per Embree path, in --embree-paths order
  Outcome outcome;
};

// An arm's name in the measurement: its variant, and its trace class when several run.
std::string stage_of(const Tracer& t) {
  return std::string("ours:") + trace_layout_name(t.layout()) + ":" + trace_variant_name(t.variant());
}
// "packet16 fast": how a row names an arm when several classes run.
std::string arm_label(const Tracer& t) {
  return std::string(trace_layout_name(t.layout())) + " " + trace_variant_name(t.variant());
}
// How a ratio column names arm i: its variant, or "packet16:fast" when several classes run.
std::string arm_name(const std::vector<Tracer>& tracers, std::size_t i) {
  const bool several_classes = tracers.front().layout() != tracers.back().layout();
  const Tracer& t = tracers[i];
  return several_classes ? std::string(trace_layout_name(t.layout())) + ":" + trace_variant_name(t.variant())
                         : trace_variant_name(t.variant());
}

BatchRun trace_batch(Runtime& rt, std::vector<Tracer>& tracers, const EmbreeReference* embree, const Bvh& bvh,
                     const ReferencedBatch& rb, const ProtocolSettings& settings) {
  const RayBatch& b = rb.batch;
  const auto n = static_cast<std::uint32_t>(b.size());
  std::vector<std::uint32_t> identity(n);
  std::iota(identity.begin(), identity.end(), 0u);
  cl::Buffer rays = rt.upload("rays of " + b.name, b.rays);
  cl::Buffer order = rt.upload("identity order", identity);
  std::vector<cl::Buffer> hit_bufs;
  Measurement m;
  for (Tracer& t : tracers) {
    hit_bufs.push_back(rt.buffer("hits", std::max<std::size_t>(1, n) * sizeof(RsHit)));
    m.arms.push_back({{stage_of(t)}, [&, buf = hit_bufs.back()] {
                        cl::Event ev = t.enqueue(rays, order, n, b.any_hit(), buf);
                        cl_call("waiting for a trace of " + std::to_string(n) + " rays", [&] { ev.wait(); });
                        return std::vector<double>{event_ms(ev)};
                      }});
    m.targets.push_back([name = stage_of(t)](const Series& s) { return median_interval(s.at(name)); });
  }
  BatchRun r;
#ifdef RAYSORT_HAVE_EMBREE
  if (embree) {
    r.embree.reserve(embree->paths.size());  // the arms hold references to their runs
    for (EmbreePath path : embree->paths) {
      const std::string key = embree_path_info(path).key;
      EmbreeRun& e = r.embree.emplace_back(EmbreeRun{key, embree_path_name(path, b.any_hit()), "embree:" + key, {}, {}});
      // Embree's time is the wall clock of the whole trace call: its threads' start and join included.
      m.arms.push_back({{e.stage}, [&, path] {
                          const auto t0 = std::chrono::steady_clock::now();
                          e.hits = embree->scene.trace(b.rays, b.any_hit(), path);
                          return std::vector<double>{
                              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count()};
                        }});
      for (Tracer& t : tracers)
        m.targets.push_back(
            [stage = e.stage, name = stage_of(t)](const Series& s) { return ratio_interval(s.at(stage), s.at(name)); });
    }
  }
#else
  (void)embree;
#endif
  // Every other arm against the first: two variants' ratio, or each class against the first.
  for (std::size_t i = 1; i < tracers.size(); ++i)
    m.targets.push_back([a = stage_of(tracers[0]), b2 = stage_of(tracers[i])](const Series& s) {
      return ratio_interval(s.at(a), s.at(b2));
    });
  r.outcome = measure(m, settings);
  for (EmbreeRun& e : r.embree) e.ms = Timing::of(r.outcome.series.at(e.stage));
  for (std::size_t i = 0; i < tracers.size(); ++i) {
    const Tracer& t = tracers[i];
    std::vector<RsHit> hits;
    rt.download("hits", hit_bufs[i], hits, n);
    // generate_batches' reference hits come from the fast variant on the wide layout; other
    // variants and layouts trace their own.
    const bool fast = t.variant() == TraceVariant::Fast && t.layout() == TraceLayout::Wide;
    std::vector<RsHit> own;
    if (!fast) own = trace_reference(bvh, b.rays, nullptr, b.any_hit(), nullptr, t.variant(), t.layout());
    const std::vector<RsHit>& ref = fast ? rb.reference_hits : own;
    r.mismatches.push_back(count_hit_mismatches(hits, ref));
    if (i == 0) r.hit_count = std::count_if(ref.begin(), ref.end(), [](const RsHit& x) { return x.tri != RS_NO_HIT; });
    r.ms.push_back(Timing::of(r.outcome.series.at(stage_of(t))));
    r.hits.push_back(std::move(hits));
  }
  return r;
}

// "12.34 [12.10, 12.60]": a median with its 95 % interval (just the median without one).
std::string ms_text(const Timing& t) { return interval_text(t.estimate(), 2); }
std::string ratio_text(const Estimate& e) { return e.has_value() ? interval_text(e) : "-"; }
double mrays(std::size_t rays, const Timing& t) { return t.median_ms > 0 ? static_cast<double>(rays) / (t.median_ms * 1e3) : 0.0; }

// Rays whose hit triangle (or hit/miss) differs between two runs.
std::size_t count_triangle_differences(const std::vector<RsHit>& a, const std::vector<RsHit>& b) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) n += a[i].tri != b[i].tri;
  return n;
}

// What the batches of all scenes found, for the exit code.
struct TraceTotals {
  std::size_t mismatches = 0;           // hits that differ from the host reference
  std::size_t disagreeing_batches = 0;  // batches below the Embree agreement
  std::size_t robust_wrong = 0;         // robust answers the exact oracle judged wrong
};

// --adjudicate: the exact verdicts on the rays where the answers differ, one line per batch, and
// the telling rays kept for --disagreements.
void adjudicate_batch(const ExactOracle& oracle, const BatchRun& run, const std::vector<Tracer>& tracers,
                      const RayBatch& b, nlohmann::json& saved, TraceTotals& totals) {
  std::vector<AnswerSet> answers;
  for (std::size_t i = 0; i < tracers.size(); ++i) answers.push_back({arm_name(tracers, i), &run.hits[i]});
  // Every Embree path's answers; the single path alone keeps its name of issue 9.
  for (const EmbreeRun& e : run.embree)
    answers.push_back({run.embree.size() == 1 && e.key == "1" ? "embree" : "embree:" + e.key, &e.hits});
  const Adjudication a = adjudicate(oracle, b, answers);
  std::string line = fmt::format("{:<9} adjudicated {} rays where the answers differ (exact rationals):", "", a.rays.size());
  for (std::size_t k = 0; k < answers.size(); ++k) {
    line += fmt::format(" {} {} right / {} tie / {} wrong;", answers[k].name, a.counts[k].right, a.counts[k].tie,
                        a.counts[k].wrong);
    if (k < tracers.size() && tracers[k].variant() == TraceVariant::Robust) totals.robust_wrong += a.counts[k].wrong;
  }
  fmt::print("{}\n", line);
  for (const auto& w : a.wrong) fmt::print("{:<9} WRONG {}", "", w);
  std::vector<RsRay> rays;
  for (std::uint32_t i : a.telling) rays.push_back(b.rays[i]);
  if (!rays.empty()) saved["batches"].push_back({{"name", b.name}, {"any_hit", b.any_hit()}, {"rays", rays_to_json(rays)}});
}

#ifdef RAYSORT_HAVE_EMBREE
// One Embree path's hits against each of our variants': the lowest agreement, and a note per
// variant whose hits differ ("... rays differ from <whom>: ...").
struct PathAgreement {
  double same = 1.0, with_ties = 1.0;  // lowest over our variants
  bool below = false;                  // some variant below kEmbreeMinAgreement (same triangle or a tie)
};
PathAgreement agreement_of(const EmbreeRun& e, const BatchRun& run, const std::vector<Tracer>& tracers,
                           const RayBatch& b, const std::string& whom, std::vector<std::string>& notes) {
  PathAgreement p;
  // One note per distinct difference, naming every arm that has it (several classes often agree).
  std::vector<std::pair<std::string, std::string>> differences;  // (what differs, the arms)
  for (std::size_t i = 0; i < tracers.size(); ++i) {
    const HitAgreement a = compare_with_embree(run.hits[i], e.hits, b.any_hit());
    p.same = std::min(p.same, a.fraction());
    p.with_ties = std::min(p.with_ties, a.fraction_with_ties());
    p.below = p.below || a.fraction_with_ties() < kEmbreeMinAgreement;
    if (!a.differences()) continue;
    const std::string what = fmt::format("{} of {} rays differ from {}: {}", a.differences(), a.rays, whom, a.describe());
    auto it = std::find_if(differences.begin(), differences.end(), [&](const auto& d) { return d.first == what; });
    if (it == differences.end())
      differences.emplace_back(what, arm_name(tracers, i));
    else
      it->second += ", " + arm_name(tracers, i);
  }
  for (const auto& [what, arms] : differences)
    notes.push_back(fmt::format("{:<9} {}{}", "", tracers.size() > 1 ? arms + ": " : "", what));
  if (p.below)
    notes.push_back(fmt::format("{:<9} below the required {:.1f} % agreement with {} (same triangle or a tie)", "",
                                100.0 * kEmbreeMinAgreement, whom));
  return p;
}

// The paired speed ratio of our arm `i` over an Embree arm: its time over ours per round.
Estimate speed_over(const BatchRun& run, const std::vector<Tracer>& tracers, std::size_t i, const std::string& stage) {
  return ratio_interval(run.outcome.series.at(stage), run.outcome.series.at(stage_of(tracers[i])));
}

// Embree's columns of the batch row when rtcIntersect1 is the only path (issue 9's layout): its
// median ms, ours/Embree speed per variant (paired), the lowest agreement; notes on the rays that differ.
std::string embree_columns(const BatchRun& run, const std::vector<Tracer>& tracers, const RayBatch& b,
                           std::vector<std::string>& notes, TraceTotals& totals) {
  const EmbreeRun& e = run.embree.at(0);
  std::string cols = fmt::format(" {:>8.2f}", e.ms.median_ms);
  for (std::size_t i = 0; i < tracers.size(); ++i) cols += fmt::format(" {:>14}", ratio_text(speed_over(run, tracers, i, e.stage)));
  const PathAgreement p = agreement_of(e, run, tracers, b, "Embree", notes);
  cols += fmt::format(" {:>7.3f} {:>7.3f}", 100.0 * p.same, 100.0 * p.with_ties);
  if (p.below) ++totals.disagreeing_batches;
  return cols;
}

constexpr int kPathKeyWidth = 13, kPathNameWidth = 26, kRatioWidth = 26;

// The header of the path lines, below the batch header.
void print_path_header(const std::vector<Tracer>& tracers) {
  std::string ratios;
  for (std::size_t i = 0; i < tracers.size(); ++i)
    ratios += fmt::format(" {:>{}}", tracers.size() > 1 ? fmt::format("{}/path speed", arm_name(tracers, i)) : "ours/path speed",
                          kRatioWidth);
  fmt::print("{:<{}} {:<{}} {:>7} {:>24} {:>9}{} {:>7} {:>7}\n", "  path", kPathKeyWidth, "Embree call and flag", kPathNameWidth,
             "threads", "ms", "MRays/s", ratios, "same %", "+ties %");
}

// After a batch's row, one line per Embree path (its call and flag, threads, median ms with its
// interval, MRays/s, each of our arms' paired speed over it, agreement), the notes on rays that
// differ, and the path with the lowest median against our fastest arm.
void print_path_lines(const BatchRun& run, const std::vector<Tracer>& tracers, const RayBatch& b, unsigned threads,
                      TraceTotals& totals) {
  bool below = false;
  const EmbreeRun* best = nullptr;
  for (const EmbreeRun& e : run.embree) {
    std::vector<std::string> notes;
    const PathAgreement p = agreement_of(e, run, tracers, b, "Embree " + e.name, notes);
    below = below || p.below;
    std::string ratios;
    for (std::size_t i = 0; i < tracers.size(); ++i)
      ratios += fmt::format(" {:>{}}", ratio_text(speed_over(run, tracers, i, e.stage)), kRatioWidth);
    fmt::print("{:<{}} {:<{}} {:>7} {:>24} {:>9.2f}{} {:>7.3f} {:>7.3f}\n", "  " + e.key, kPathKeyWidth, e.name,
               kPathNameWidth, threads, ms_text(e.ms), mrays(b.size(), e.ms), ratios, 100.0 * p.same, 100.0 * p.with_ties);
    for (const auto& note : notes) fmt::print("{}\n", note);
    if (!best || e.ms.median_ms < best->ms.median_ms) best = &e;
  }
  if (below) ++totals.disagreeing_batches;
  if (!best) return;
  std::size_t ours = 0;  // our fastest arm (lowest median)
  for (std::size_t i = 1; i < tracers.size(); ++i)
    if (run.ms[i].median_ms < run.ms[ours].median_ms) ours = i;
  fmt::print("{:<{}} {} ({}) has the lowest median of Embree's paths; {}/{} speed {}\n", "  best", kPathKeyWidth, best->name,
             best->key, tracers.size() > 1 ? arm_name(tracers, ours) : "ours", best->key,
             ratio_text(speed_over(run, tracers, ours, best->stage)));
}
#endif

// with_embree: the Embree columns of issue 9 on the batch row (rtcIntersect1 the only path).
void print_batch_header(const std::vector<Tracer>& tracers, TraceLayout layout, bool with_embree) {
  fmt::print("timing   every arm of a batch in the same rounds (docs/measurement.md): ms = median [95 % interval]; "
             "ratios are paired estimates of the per-round ratios\n");
  if (tracers.size() == 2) {
    fmt::print("variant  fast and robust, in the same rounds on each batch (trace class {})\n", trace_layout_name(layout));
    fmt::print("{:<9} {:>9} {:>24} {:>9} {:>24} {:>9} {:>24} {:>9} {:>8} {:>10} {:>7}{}\n", "batch", "rays", "fast ms",
               "fast MR/s", "robust ms", "rob MR/s", "robust/fast time", "hits", "tri diff", "mismatches", "rounds",
               with_embree ? "   emb ms  fast/emb speed  rob/emb speed  same %  +ties %" : "");
  } else {
    fmt::print("variant  {} (trace class {})\n", trace_variant_name(tracers[0].variant()), trace_layout_name(layout));
    fmt::print("{:<9} {:>9} {:>24} {:>9} {:>9} {:>10} {:>7}{}\n", "batch", "rays", "ms", "MRays/s", "hits",
               "mismatches", "rounds", with_embree ? "   emb ms  ours/emb speed  same %  +ties %" : "");
  }
}

// Several trace classes: one line per batch, then one per arm, each arm's speed against the first
// arm's (paired, in the same rounds) and its mismatches against its own host twin. Embree's paths
// follow on lines of their own (print_path_lines).
void print_class_header(const std::vector<Tracer>& tracers) {
  fmt::print("timing   every arm of a batch in the same rounds (docs/measurement.md): ms = median [95 % interval]; "
             "ratios are paired estimates of the per-round ratios\n");
  fmt::print("classes  {} trace arms per batch; speed = the first arm's time over the arm's ({})\n", tracers.size(),
             arm_label(tracers[0]));
  fmt::print("{:<9} {:<17} {:>9} {:>24} {:>9} {:>24} {:>10}\n", "batch", "class variant", "rays", "ms", "MRays/s",
             "speed vs first", "mismatches");
}

void print_class_rows(const BatchRun& run, const std::vector<Tracer>& tracers, const RayBatch& b) {
  const std::string rounds = fmt::format("{}{}", run.outcome.rounds, run.outcome.stop == StopReason::Noise ? "" : "*");
  fmt::print("{:<9} {} rays, {} hits, {} rounds\n", b.name, b.size(), run.hit_count, rounds);
  for (std::size_t i = 0; i < tracers.size(); ++i)
    fmt::print("{:<9} {:<17} {:>9} {:>24} {:>9.2f} {:>24} {:>10}\n", "", arm_label(tracers[i]), b.size(),
               ms_text(run.ms[i]), mrays(b.size(), run.ms[i]),
               i == 0 ? std::string("-")
                      : ratio_text(ratio_interval(run.outcome.series.at(stage_of(tracers[0])),
                                                  run.outcome.series.at(stage_of(tracers[i])))),
               run.mismatches[i]);
}

void print_batch_row(const BatchRun& run, const std::vector<Tracer>& tracers, const RayBatch& b, std::size_t mismatches,
                     const std::string& emb_cols) {
  const std::string rounds = fmt::format("{}{}", run.outcome.rounds, run.outcome.stop == StopReason::Noise ? "" : "*");
  if (tracers.size() == 2) {
    fmt::print("{:<9} {:>9} {:>24} {:>9.2f} {:>24} {:>9.2f} {:>24} {:>9} {:>8} {:>10} {:>7}{}\n", b.name, b.size(),
               ms_text(run.ms[0]), mrays(b.size(), run.ms[0]), ms_text(run.ms[1]), mrays(b.size(), run.ms[1]),
               ratio_text(ratio_interval(run.outcome.series.at(stage_of(tracers[1])),
                                         run.outcome.series.at(stage_of(tracers[0])))),
               run.hit_count, count_triangle_differences(run.hits[0], run.hits[1]), mismatches, rounds, emb_cols);
  } else {
    fmt::print("{:<9} {:>9} {:>24} {:>9.2f} {:>9} {:>10} {:>7}{}\n", b.name, b.size(), ms_text(run.ms[0]),
               mrays(b.size(), run.ms[0]), run.hit_count, mismatches, rounds, emb_cols);
  }
}

// The batches to trace: the file's one batch (read and checked in run_trace), or those the scene's
// effects imply.
std::vector<ReferencedBatch> batches_to_trace(const PreparedScene& p, const TraceArgs& args, const RayFile* file) {
  if (!file) return generate_batches(p.scene, p.tris, p.bvh, args.common.raygen_options());
  std::vector<ReferencedBatch> one;
  one.push_back(batch_from_ray_file(*file, args.rays, p.bvh));
  fmt::print("rays     {} from {}: {} rays, generated as {} by `{}`{}\n", one[0].batch.name, args.rays, file->rays.size(),
             file->batch_name, file->command,
             file->has_hits ? fmt::format("; {} rays differ from the file's hits", ray_file_hit_differences(*file, one[0].reference_hits))
                            : "");
  return one;
}

// One scene: its BVH and kernels, then every batch its effects imply, traced by each variant (and
// Embree) in the rounds of one measurement and checked against the host reference.
void trace_scene(Runtime& rt, const std::string& scene_name, const TraceArgs& args, const RayFile* file,
                 TraceTotals& totals) {
  const PreparedScene p = prepare_scene(scene_name, args.common.scene_options());
  const FrameSize frame = p.frame();
  check_frame_memory(estimate_frame_memory(p.scene), &rt.info(),
                     fmt::format("scene {} at {}x{}, {} spp", p.scene.name, frame.width, frame.height, frame.spp));
  fmt::print("\nscene    {}: {} triangles, loaded in {:.0f} ms; {}x{} x {} spp\n", p.scene.name, p.tris.size(), p.load_ms,
             frame.width, frame.height, frame.spp);
  fmt::print("bvh      {} nodes, {} leaves, depth {}, built in {:.0f} ms on {} threads, SAH cost {:.4f}\n",
             p.bvh.nodes.size(), p.bvh.leaf_count, p.bvh.depth, p.bvh.build_ms, host_threads(), p.bvh.sah_cost);
  // Two variants are shown fast first, then robust, with their ratio.
  std::vector<TraceVariant> variants = parse_trace_variants(args.variant);
  if (variants.size() == 2) variants = {TraceVariant::Fast, TraceVariant::Robust};
  const double build_before = rt.build_ms();
  // Every class with every variant, class by class: all arms of one measurement.
  std::vector<Tracer> tracers;
  const std::vector<TraceLayout> layouts = parse_trace_layouts(args.layout);
  for (TraceLayout layout : layouts)
    for (TraceVariant v : variants) tracers.emplace_back(rt, p.bvh, v, layout);
  const bool several_classes = layouts.size() > 1;
  if (std::any_of(layouts.begin(), layouts.end(), [](TraceLayout l) { return tree_kind(l) == TreeKind::Wide8; })) {
    const SplitTree& split = split_tree(p.bvh);  // built by the first 8-wide class's Tracer
    fmt::print("split    the 8-wide classes' tree, with spatial splits: {} references to {} triangles (+{:.1f} %), {} nodes, "
               "depth {}, SAH cost {:.4f}; built and collapsed in {:.0f} ms\n",
               split.binary.triangles.size(), p.bvh.triangles.size(),
               100.0 * (static_cast<double>(split.binary.triangles.size()) / static_cast<double>(p.bvh.triangles.size()) - 1.0),
               split.binary.nodes.size(), split.binary.depth, split.binary.sah_cost, split.build_ms);
  }
  fmt::print("kernels  built in {:.0f} ms (reported apart from trace times)\n", rt.build_ms() - build_before);
  bool embree_columns_on_row = false;  // issue 9's columns: rtcIntersect1 alone
  const EmbreeReference* embree_ref = nullptr;
#ifdef RAYSORT_HAVE_EMBREE
  std::optional<EmbreeScene> embree_scene;
  std::optional<EmbreeReference> embree;
  if (args.reference == "embree") {
    embree_scene.emplace(p.tris, 0, args.embree_isa.value_or("native"));
    embree.emplace(EmbreeReference{*embree_scene, parse_embree_paths(args.embree_paths.value_or("1"))});
    embree_ref = &*embree;
    embree_columns_on_row = embree->single_only();
    std::string calls, native;
    for (EmbreePath path : embree->paths) calls += (calls.empty() ? "" : ", ") + embree_path_calls(path);
    // Whether this CPU has each packet width timed, or Embree splits the packet (16 rays without AVX-512).
    for (unsigned width : {4u, 8u, 16u})
      if (std::any_of(embree->paths.begin(), embree->paths.end(),
                      [&](EmbreePath path) { return embree_path_info(path).packet == width; }))
        native += fmt::format("{}{} {}", native.empty() ? "" : ", ", width, embree_scene->native_packets(width) ? "yes" : "no");
    fmt::print("embree   Embree {}{}, {} threads, {}, build quality high: BVH built in {:.0f} ms (ours {:.0f} ms = {:.2f}x "
               "Embree's){}\n",
               EmbreeScene::version(), embree_scene->isa() == "native" ? "" : " held to " + embree_scene->isa(),
               embree_scene->threads(), calls, embree_scene->build_ms(), p.bvh.build_ms,
               embree_scene->build_ms() > 0 ? p.bvh.build_ms / embree_scene->build_ms() : 0.0,
               native.empty() ? "" : "; native packets: " + native);
  }
#endif
  // Several classes: Embree's paths always on lines of their own, each naming every arm's ratio.
  [[maybe_unused]] const bool paths_on_lines = !embree_columns_on_row || several_classes;
  if (several_classes)
    print_class_header(tracers);
  else
    print_batch_header(tracers, tracers[0].layout(), embree_columns_on_row);
#ifdef RAYSORT_HAVE_EMBREE
  if (embree && paths_on_lines) print_path_header(tracers);
#endif
  std::optional<ExactOracle> oracle;
  nlohmann::json saved = {{"scene", scene_name}, {"resolution", fmt::format("{}x{}", frame.width, frame.height)},
                          {"spp", frame.spp}, {"seed", args.common.raygen_options().seed},
                          {"batches", nlohmann::json::array()}};
  if (args.adjudicate) oracle.emplace(p.tris, p.bvh);
  // The pipeline of docs/measurement.md, as far as the scene's effects ask.
  for (const ReferencedBatch& rb : batches_to_trace(p, args, file)) {
    const RayBatch& b = rb.batch;
    const BatchRun run = trace_batch(rt, tracers, embree_ref, p.bvh, rb,
                                     args.protocol.settings(protocol_seed(p.scene.name + "/" + b.name)));
    std::size_t mismatches = 0;
    for (std::size_t m : run.mismatches) mismatches += m;
    std::string emb_cols;
    std::vector<std::string> emb_notes;
#ifdef RAYSORT_HAVE_EMBREE
    if (!paths_on_lines) emb_cols = embree_columns(run, tracers, b, emb_notes, totals);
#endif
    if (several_classes) {
      print_class_rows(run, tracers, b);
    } else {
      print_batch_row(run, tracers, b, mismatches, emb_cols);
    }
    for (const auto& note : emb_notes) fmt::print("{}\n", note);
    fmt::print("{:<9} hits hash {} (FNV-1a of t and triangle per ray, {})\n", "", hits_hash(run.hits[0]), arm_label(tracers[0]));
#ifdef RAYSORT_HAVE_EMBREE
    if (embree && paths_on_lines) print_path_lines(run, tracers, b, embree_scene->threads(), totals);
#endif
    if (oracle) adjudicate_batch(*oracle, run, tracers, b, saved, totals);
    std::fflush(stdout);
    totals.mismatches += mismatches;
  }
  fmt::print("rounds   * = stopped by --max-time before every interval was within --max-noise\n");
  if (oracle && !args.disagreements.empty()) {
    std::filesystem::create_directories(args.disagreements);
    const std::string file = (std::filesystem::path(args.disagreements) / (safe_file_name(p.scene.name) + ".json")).string();
    write_file_atomically(file, saved.dump(1) + "\n");
    fmt::print("saved    the adjudicated rays to {}\n", file);
  }
}

// --build-rounds: each scene's builds timed side by side, nothing traced.
int run_build_timing(const TraceArgs& args) {
  if (args.adjudicate || !args.disagreements.empty() || args.embree_paths)
    throw Error("--build-rounds times the BVH builds alone: leave out --adjudicate, --disagreements and --embree-paths");
  for (const auto& scene_name : args.scenes) {
    const PreparedScene p = prepare_scene(scene_name, args.common.scene_options());
    fmt::print("\nscene    {}: {} triangles, loaded in {:.0f} ms\n", p.scene.name, p.tris.size(), p.load_ms);
    const BuildTiming t = time_builds(p.tris, args.build_rounds, args.reference == "embree",
                                      protocol_seed("build/" + p.scene.name), args.embree_isa.value_or("native"));
    fmt::print("{}\n", build_timing_text(t));
    std::fflush(stdout);
  }
  return 0;
}

int run_trace(const TraceArgs& args) {
  if (args.embree_paths && args.reference != "embree")
    throw Error("--embree-paths " + *args.embree_paths + " goes with --reference embree");
  if (args.embree_isa && args.reference != "embree")
    throw Error("--embree-isa " + *args.embree_isa + " goes with --reference embree");
#ifndef RAYSORT_HAVE_EMBREE
  if (args.reference == "embree") throw Error("this build has no Embree: install libembree-dev and reconfigure");
#else
  if (args.embree_paths) parse_embree_paths(*args.embree_paths);  // a bad list is refused before any work
  if (args.embree_isa) check_embree_isa(*args.embree_isa);
#endif
  parse_trace_variants(args.variant);  // a bad --variant is refused before any work
  parse_trace_layouts(args.layout);
  if (args.adjudicate && parse_trace_variants(args.variant).size() < 2 && parse_trace_layouts(args.layout).size() < 2 &&
      args.reference.empty())
    throw Error("--adjudicate judges the rays on which answers differ: give two, with --variant both and/or "
                "--reference embree");
  if (!args.disagreements.empty() && !args.adjudicate) throw Error("--disagreements DIR goes with --adjudicate");
  if (args.build_rounds > 0) return run_build_timing(args);
  // A ray file is read and checked against its scene before any work: a bad one costs nothing.
  std::optional<RayFile> file;
  if (!args.rays.empty()) {
    if (args.scenes.size() != 1)
      throw Error(fmt::format("--rays {} is a batch of one scene: give that scene alone with --scene", args.rays));
    const auto start = std::chrono::steady_clock::now();
    file = read_ray_file_for_scene(args.rays, args.scenes[0], resolve_scene_root(args.common.scene_options()));
    fmt::print("rays     read {} ({} bytes) and checked its scene in {:.0f} ms\n", args.rays,
               std::filesystem::file_size(args.rays),
               std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  Runtime rt(select_device(args.common.device));
  fmt::print("device   {} ({}, {})\n", rt.info().name, rt.info().platform_name, rt.info().driver_version);
  TraceTotals totals;
  for (const auto& scene_name : args.scenes) trace_scene(rt, scene_name, args, file ? &*file : nullptr, totals);
  int code = 0;
  if (totals.mismatches > 0) {
    fmt::print(stderr, "raysort: {} hits differ from the host reference\n", totals.mismatches);
    code = 1;
  }
  if (totals.robust_wrong > 0) {
    fmt::print(stderr, "raysort: the exact oracle judged {} robust answers wrong\n", totals.robust_wrong);
    code = 1;
  }
  if (totals.disagreeing_batches > 0) {
    fmt::print(stderr, "raysort: {} batches agree with Embree on fewer than 99.9 % of rays (same triangle or a tie)\n",
               totals.disagreeing_batches);
    code = 1;
  }
  return code;
}

}  // namespace

void register_trace_command(CLI::App& app) {
  auto args = std::make_shared<TraceArgs>();
  auto* cmd = app.add_subcommand("trace", "trace a scene's ray batches on the device and verify every hit");
  add_scene_list_option(*cmd, args->scenes, "scenes, comma-separated: each a " + scene_option_help())->required();
  add_common_options(*cmd, args->common);
  add_protocol_options(*cmd, args->protocol);
  cmd->add_option("--variant", args->variant,
                  "traversal arithmetic: robust (watertight), fast (Moller-Trumbore), or both side by side "
                  "(robust,fast or both)")
      ->capture_default_str();
  cmd->add_option("--layout", args->layout,
                  "trace class (docs/trace.md): " + trace_layouts_help() +
                      "; several, comma-separated (or all), run side by side in the same rounds")
      ->check([](const std::string& list) {
        try {
          parse_trace_layouts(list);
          return std::string();
        } catch (const Error& e) {
          return std::string(e.what());
        }
      })
      ->capture_default_str();
  cmd->add_option("--reference", args->reference,
                  "also trace every batch with this CPU reference, side by side: embree (Embree 3, all host threads; "
                  "needs a build with libembree-dev)")
      ->check(CLI::IsMember({"embree"}));
  cmd->add_option("--embree-paths", args->embree_paths,
                  "with --reference embree: Embree's paths to time, each an arm of every batch's rounds "
                  "(comma-separated): 1 (rtcIntersect1, the default), 1M and 1M-coherent (rtcIntersect1M streams), "
                  "4, 8, 16 and 4-coherent, 8-coherent, 16-coherent (packets of consecutive rays), or all");
  cmd->add_option("--embree-isa", args->embree_isa,
                  "with --reference embree: the instruction set Embree runs: native (the widest this CPU has, the "
                  "default), sse2, sse4.2, avx, avx2 or avx512; e.g. avx2 on an AVX-512 CPU, with PoCL held to AVX2 too "
                  "(docs/trace.md, \"Embree anchor\"), compares both at an AVX2 CPU's width");
  cmd->add_flag("--adjudicate", args->adjudicate,
                "decide every ray on which the variants (and Embree) disagree with exact rational arithmetic, and "
                "count each answer right, tie (correct up to float precision) or wrong; exits 1 if a robust answer "
                "is wrong");
  cmd->add_option("--disagreements", args->disagreements,
                  "with --adjudicate: write the telling rays (answers judged differently) to DIR/<scene>.json, a "
                  "regression file");
  cmd->add_option("--build-rounds", args->build_rounds,
                  "time our BVH build (and Embree's high-quality build, with --reference embree) in N alternated "
                  "rounds after one warm-up: medians with 95 % intervals and ours/Embree paired; then stop (no "
                  "kernels, no traces). 6 or more give intervals")
      ->check(CLI::Range(1u, 1000u));
  add_rays_option(*cmd, args->rays);
  cmd->callback([args] { set_command_exit_code(run_trace(*args)); });
}

}  // namespace raysort
