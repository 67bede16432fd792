// raysort trace: load a scene, build its BVH, generate the batches its effects imply, trace each
// on the device and check every hit against the host reference (the same traversal source).
// --variant robust|fast picks the traversal arithmetic (docs/trace.md); --variant both runs the two
// back to back on every batch and prints the robust/fast speed ratio and how many hits differ.
// --reference embree traces every batch with Embree 3 as well, side by side in this process, and
// prints its MRays/s, ours/Embree, and how many hits agree (docs/trace.md, "Embree anchor").
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <optional>

#include "app/commands.h"
#include "app/options.h"
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

namespace raysort {

namespace {

struct TraceArgs {
  std::vector<std::string> scenes;
  CommonOptions common;
  ProtocolOptions protocol;
  std::string variant = "robust";
  std::string layout = "wide";
  std::string reference;  // "" or "embree"
  bool adjudicate = false;       // judge every ray the answers differ on, exactly (trace/adjudicate.h)
  std::string disagreements;     // with adjudicate: write those rays to DIR/<scene>.json
};

// One batch traced by each variant (and Embree), all arms of the same rounds of the measurement
// protocol (bench/protocol.h): their times and ratios are paired.
struct BatchRun {
  std::vector<std::vector<RsHit>> hits;  // per variant, ray order
  std::vector<Timing> ms;                // per variant
  std::vector<std::size_t> mismatches;   // per variant, against the host reference of that variant
  std::size_t hit_count = 0;             // hits of the first variant's reference
  Timing embree_ms;
  std::vector<RsHit> embree_hits;
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

BatchRun trace_batch(Runtime& rt, std::vector<Tracer>& tracers, const void* embree_scene, const Bvh& bvh,
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
  if (embree_scene) {
    const auto& embree = *static_cast<const EmbreeScene*>(embree_scene);
    m.arms.push_back({{"embree"}, [&] {
                        const auto t0 = std::chrono::steady_clock::now();
                        r.embree_hits = embree.trace(b.rays, b.any_hit());
                        return std::vector<double>{
                            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count()};
                      }});
    for (Tracer& t : tracers)
      m.targets.push_back([name = stage_of(t)](const Series& s) { return ratio_interval(s.at("embree"), s.at(name)); });
  }
#else
  (void)embree_scene;
#endif
  // Every other arm against the first: two variants' ratio, or each class against the first.
  for (std::size_t i = 1; i < tracers.size(); ++i)
    m.targets.push_back([a = stage_of(tracers[0]), b2 = stage_of(tracers[i])](const Series& s) {
      return ratio_interval(s.at(a), s.at(b2));
    });
  r.outcome = measure(m, settings);
  if (r.outcome.series.count("embree")) r.embree_ms = Timing::of(r.outcome.series.at("embree"));
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
  const bool several_classes = tracers.front().layout() != tracers.back().layout();
  for (std::size_t i = 0; i < tracers.size(); ++i)
    answers.push_back({several_classes ? arm_label(tracers[i]) : trace_variant_name(tracers[i].variant()), &run.hits[i]});
  if (!run.embree_hits.empty()) answers.push_back({"embree", &run.embree_hits});
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
// Embree's columns for one batch: its median ms, ours/Embree speed per variant (paired), the lowest
// agreement; notes on the rays that differ.
std::string embree_columns(const BatchRun& run, const std::vector<Tracer>& tracers, const RayBatch& b,
                           std::vector<std::string>& notes, TraceTotals& totals) {
  std::string cols = fmt::format(" {:>8.2f}", run.embree_ms.median_ms);
  double worst = 1.0, worst_ties = 1.0;
  bool below = false;
  for (std::size_t i = 0; i < tracers.size(); ++i) {
    cols += fmt::format(" {:>14}", ratio_text(ratio_interval(run.outcome.series.at("embree"),
                                                             run.outcome.series.at(stage_of(tracers[i])))));
    const HitAgreement a = compare_with_embree(run.hits[i], run.embree_hits, b.any_hit());
    worst = std::min(worst, a.fraction());
    worst_ties = std::min(worst_ties, a.fraction_with_ties());
    below = below || a.fraction_with_ties() < kEmbreeMinAgreement;
    if (a.differences())
      notes.push_back(fmt::format("{:<9} {}{} of {} rays differ from Embree: {}", "",
                                  tracers.size() > 1 ? fmt::format("{}: ", trace_variant_name(tracers[i].variant())) : "",
                                  a.differences(), a.rays, a.describe()));
  }
  cols += fmt::format(" {:>7.3f} {:>7.3f}", 100.0 * worst, 100.0 * worst_ties);
  if (below) {
    ++totals.disagreeing_batches;
    notes.push_back(fmt::format("{:<9} below the required {:.1f} % agreement with Embree (same triangle or a tie)", "",
                                100.0 * kEmbreeMinAgreement));
  }
  return cols;
}
// Several classes: per arm, its speed over Embree's (paired) and the share of rays whose hit agrees.
std::vector<std::string> embree_arm_columns(const BatchRun& run, const std::vector<Tracer>& tracers, const RayBatch& b) {
  std::vector<std::string> cols;
  for (std::size_t i = 0; i < tracers.size(); ++i) {
    const HitAgreement a = compare_with_embree(run.hits[i], run.embree_hits, b.any_hit());
    cols.push_back(fmt::format(" {:>16} {:>7.3f} {:>7.3f}",
                               ratio_text(ratio_interval(run.outcome.series.at("embree"),
                                                         run.outcome.series.at(stage_of(tracers[i])))),
                               100.0 * a.fraction(), 100.0 * a.fraction_with_ties()));
  }
  return cols;
}
#endif

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
// arm's (paired, in the same rounds) and its mismatches against its own host twin.
void print_class_header(const std::vector<Tracer>& tracers, bool with_embree) {
  fmt::print("timing   every arm of a batch in the same rounds (docs/measurement.md): ms = median [95 % interval]; "
             "ratios are paired estimates of the per-round ratios\n");
  fmt::print("classes  {} trace arms per batch; speed = the first arm's time over the arm's ({})\n", tracers.size(),
             arm_label(tracers[0]));
  fmt::print("{:<9} {:<17} {:>9} {:>24} {:>9} {:>24} {:>10}{}\n", "batch", "class variant", "rays", "ms", "MRays/s",
             "speed vs first", "mismatches", with_embree ? "   ours/emb speed  same %  +ties %" : "");
}

void print_class_rows(const BatchRun& run, const std::vector<Tracer>& tracers, const RayBatch& b,
                      const std::vector<std::string>& emb_cols) {
  const std::string rounds = fmt::format("{}{}", run.outcome.rounds, run.outcome.stop == StopReason::Noise ? "" : "*");
  fmt::print("{:<9} {} rays, {} hits, {} rounds\n", b.name, b.size(), run.hit_count, rounds);
  for (std::size_t i = 0; i < tracers.size(); ++i)
    fmt::print("{:<9} {:<17} {:>9} {:>24} {:>9.2f} {:>24} {:>10}{}\n", "", arm_label(tracers[i]), b.size(),
               ms_text(run.ms[i]), mrays(b.size(), run.ms[i]),
               i == 0 ? std::string("-")
                      : ratio_text(ratio_interval(run.outcome.series.at(stage_of(tracers[0])),
                                                  run.outcome.series.at(stage_of(tracers[i])))),
               run.mismatches[i], i < emb_cols.size() ? emb_cols[i] : "");
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

// One scene: its BVH and kernels, then every batch its effects imply, traced by each variant (and
// Embree) in the rounds of one measurement and checked against the host reference.
void trace_scene(Runtime& rt, const std::string& scene_name, const TraceArgs& args, TraceTotals& totals) {
  const PreparedScene p = prepare_scene(scene_name, args.common.scene_options());
  const FrameSize frame = p.frame();
  check_frame_memory(estimate_frame_memory(p.scene), &rt.info(),
                     fmt::format("scene {} at {}x{}, {} spp", p.scene.name, frame.width, frame.height, frame.spp));
  fmt::print("\nscene    {}: {} triangles, loaded in {:.0f} ms; {}x{} x {} spp\n", p.scene.name, p.tris.size(), p.load_ms,
             frame.width, frame.height, frame.spp);
  fmt::print("bvh      {} nodes, {} leaves, depth {}, built in {:.0f} ms\n", p.bvh.nodes.size(), p.bvh.leaf_count,
             p.bvh.depth, p.bvh.build_ms);
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
  fmt::print("kernels  built in {:.0f} ms (reported apart from trace times)\n", rt.build_ms() - build_before);
  const bool with_embree = args.reference == "embree";
  const void* embree_scene = nullptr;
#ifdef RAYSORT_HAVE_EMBREE
  std::optional<EmbreeScene> embree;
  if (with_embree) {
    embree.emplace(p.tris);
    embree_scene = &*embree;
    fmt::print("embree   Embree {}, {} threads, rtcIntersect1 / rtcOccluded1, build quality high: BVH built in {:.0f} ms "
               "(ours {:.0f} ms = {:.2f}x Embree's)\n",
               EmbreeScene::version(), embree->threads(), embree->build_ms(), p.bvh.build_ms,
               embree->build_ms() > 0 ? p.bvh.build_ms / embree->build_ms() : 0.0);
  }
#endif
  if (several_classes)
    print_class_header(tracers, with_embree);
  else
    print_batch_header(tracers, tracers[0].layout(), with_embree);
  std::optional<ExactOracle> oracle;
  nlohmann::json saved = {{"scene", scene_name}, {"resolution", fmt::format("{}x{}", frame.width, frame.height)},
                          {"spp", frame.spp}, {"seed", args.common.raygen_options().seed},
                          {"batches", nlohmann::json::array()}};
  if (args.adjudicate) oracle.emplace(p.tris, p.bvh);
  // The pipeline of docs/measurement.md, as far as the scene's effects ask.
  for (const ReferencedBatch& rb : generate_batches(p.scene, p.tris, p.bvh, args.common.raygen_options())) {
    const RayBatch& b = rb.batch;
    const BatchRun run = trace_batch(rt, tracers, embree_scene, p.bvh, rb,
                                     args.protocol.settings(protocol_seed(p.scene.name + "/" + b.name)));
    std::size_t mismatches = 0;
    for (std::size_t m : run.mismatches) mismatches += m;
    std::string emb_cols;
    std::vector<std::string> emb_notes, emb_arm_cols;
#ifdef RAYSORT_HAVE_EMBREE
    if (embree) {
      emb_cols = embree_columns(run, tracers, b, emb_notes, totals);
      if (several_classes) emb_arm_cols = embree_arm_columns(run, tracers, b);
    }
#endif
    if (several_classes) {
      print_class_rows(run, tracers, b, emb_arm_cols);
      if (!emb_cols.empty()) fmt::print("{:<9} {:<17} {:>9} {:>24} (median ms)\n", "", "embree", b.size(), run.embree_ms.median_ms);
    } else {
      print_batch_row(run, tracers, b, mismatches, emb_cols);
    }
    for (const auto& note : emb_notes) fmt::print("{}\n", note);
    if (oracle) adjudicate_batch(*oracle, run, tracers, b, saved, totals);
    std::fflush(stdout);
    totals.mismatches += mismatches;
  }
  fmt::print("rounds   * = stopped by --max-time before every interval was within --max-noise\n");
  if (oracle && !args.disagreements.empty()) {
    std::filesystem::create_directories(args.disagreements);
    const std::string file = (std::filesystem::path(args.disagreements) / (p.scene.name + ".json")).string();
    write_file_atomically(file, saved.dump(1) + "\n");
    fmt::print("saved    the adjudicated rays to {}\n", file);
  }
}

int run_trace(const TraceArgs& args) {
#ifndef RAYSORT_HAVE_EMBREE
  if (args.reference == "embree") throw Error("this build has no Embree: install libembree-dev and reconfigure");
#endif
  parse_trace_variants(args.variant);  // a bad --variant is refused before any work
  parse_trace_layouts(args.layout);
  if (args.adjudicate && parse_trace_variants(args.variant).size() < 2 && parse_trace_layouts(args.layout).size() < 2 &&
      args.reference.empty())
    throw Error("--adjudicate judges the rays on which answers differ: give two, with --variant both and/or "
                "--reference embree");
  if (!args.disagreements.empty() && !args.adjudicate) throw Error("--disagreements DIR goes with --adjudicate");
  Runtime rt(select_device(args.common.device));
  fmt::print("device   {} ({}, {})\n", rt.info().name, rt.info().platform_name, rt.info().driver_version);
  TraceTotals totals;
  for (const auto& scene_name : args.scenes) trace_scene(rt, scene_name, args, totals);
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
  add_scene_list_option(*cmd, args->scenes, "scene names, .toml or .obj paths (comma-separated)")->required();
  add_common_options(*cmd, args->common);
  add_protocol_options(*cmd, args->protocol);
  cmd->add_option("--variant", args->variant,
                  "traversal arithmetic: robust (watertight), fast (Moller-Trumbore), or both side by side "
                  "(robust,fast or both)")
      ->capture_default_str();
  cmd->add_option("--layout", args->layout,
                  "trace class (docs/trace.md): wide (one ray over the 4-wide BVH, the default), binary (one ray over "
                  "the binary BVH), packet4/packet8/packet16 (packets of consecutive rays over the 4-wide BVH, one "
                  "ray per vector lane) or packet (the device's preferred vector width, `raysort devices`); several, "
                  "comma-separated (or all), run side by side in the same rounds")
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
  cmd->add_flag("--adjudicate", args->adjudicate,
                "decide every ray on which the variants (and Embree) disagree with exact rational arithmetic, and "
                "count each answer right, tie (correct up to float precision) or wrong; exits 1 if a robust answer "
                "is wrong");
  cmd->add_option("--disagreements", args->disagreements,
                  "with --adjudicate: write the telling rays (answers judged differently) to DIR/<scene>.json, a "
                  "regression file");
  cmd->callback([args] { set_command_exit_code(run_trace(*args)); });
}

}  // namespace raysort
