// raysort trace: load a scene, build its BVH, generate the batches its effects imply, trace each
// on the device and check every hit against the host reference (the same traversal source).
// --variant robust|fast picks the traversal arithmetic (docs/trace.md); --variant both runs the two
// back to back on every batch and prints the robust/fast speed ratio and how many hits differ.
// --reference embree traces every batch with Embree 3 as well, side by side in this process, and
// prints its MRays/s, ours/Embree, and how many hits agree (docs/trace.md, "Embree anchor").
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <numeric>
#include <optional>

#include "app/commands.h"
#include "app/options.h"
#include "bvh/bvh.h"
#include "cl/runtime.h"
#ifdef RAYSORT_HAVE_EMBREE
#include "embree/embree_reference.h"
#endif
#include "render/batches.h"
#include "scene/load.h"
#include "trace/tracer.h"
#include "util/error.h"

namespace raysort {

namespace {

struct TraceArgs {
  std::vector<std::string> scenes;
  CommonOptions common;
  unsigned reps = 3;
  unsigned warmup = 1;
  std::string variant = "robust";
  std::string layout = "wide";
  std::string reference;  // "" or "embree"
};

#ifdef RAYSORT_HAVE_EMBREE
// Embree's run of one batch, timed as ours is (warmup, then the median over reps).
struct EmbreeRun {
  EmbreeScene::Run run;
  double mrays = 0.0;
  std::vector<HitAgreement> agreement;  // one per variant run, in the same order
};

EmbreeRun trace_embree(const EmbreeScene& embree, const ReferencedBatch& rb, const std::vector<Tracer::Run*>& ours,
                       const TraceArgs& args) {
  const RayBatch& b = rb.batch;
  EmbreeRun e;
  e.run = embree.run(b.rays, b.any_hit(), args.warmup, args.reps);
  e.mrays = e.run.median_ms > 0 ? static_cast<double>(b.size()) / (e.run.median_ms * 1e3) : 0.0;
  for (const Tracer::Run* r : ours) e.agreement.push_back(compare_with_embree(r->hits, e.run.hits, b.any_hit()));
  return e;
}
#endif

struct VariantRun {
  Tracer::Run run;
  std::size_t mismatches = 0;  // device vs the host reference of the same variant
  std::size_t hit_count = 0;
  double mrays = 0.0;
};

VariantRun trace_variant(Tracer& tracer, const Bvh& bvh, const ReferencedBatch& rb, const TraceArgs& args) {
  const RayBatch& b = rb.batch;
  VariantRun v;
  v.run = tracer.run(b.rays, nullptr, b.any_hit(), args.warmup, args.reps);
  // generate_batches' reference hits come from the fast variant on the wide layout; other
  // variants and layouts trace their own.
  const bool fast = tracer.variant() == TraceVariant::Fast && tracer.layout() == TraceLayout::Wide;
  std::vector<RsHit> own;
  if (!fast) own = trace_reference(bvh, b.rays, nullptr, b.any_hit(), nullptr, tracer.variant(), tracer.layout());
  const std::vector<RsHit>& ref = fast ? rb.reference_hits : own;
  v.mismatches = count_hit_mismatches(v.run.hits, ref);
  v.hit_count = std::count_if(ref.begin(), ref.end(), [](const RsHit& x) { return x.tri != RS_NO_HIT; });
  v.mrays = v.run.median_ms > 0 ? static_cast<double>(b.size()) / (v.run.median_ms * 1e3) : 0.0;
  return v;
}

// Rays whose hit triangle (or hit/miss) differs between two runs.
std::size_t count_triangle_differences(const std::vector<RsHit>& a, const std::vector<RsHit>& b) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) n += a[i].tri != b[i].tri;
  return n;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

int run_trace(const TraceArgs& args) {
  const bool with_embree = args.reference == "embree";
#ifndef RAYSORT_HAVE_EMBREE
  if (with_embree) throw Error("this build has no Embree: install libembree-dev and reconfigure");
#endif
  Runtime rt(select_device(args.common.device));
  fmt::print("device   {} ({}, {})\n", rt.info().name, rt.info().platform_name, rt.info().driver_version);
  std::size_t total_mismatches = 0;
  std::size_t disagreeing_batches = 0;
  for (const auto& scene_name : args.scenes) {
    auto t0 = std::chrono::steady_clock::now();
    Scene scene = load_scene(scene_name, args.common.scene_options());
    Scene::Flat tris = scene.flatten();
    double load_ms = ms_since(t0);
    Bvh bvh = build_bvh(tris);
    RayGenOptions gen = args.common.raygen_options();
    const std::uint32_t w = gen.width ? gen.width : scene.camera.width;
    const std::uint32_t h = gen.height ? gen.height : scene.camera.height;
    const std::uint32_t spp = gen.spp ? gen.spp : scene.effects.samples_per_pixel;
    fmt::print("\nscene    {}: {} triangles, loaded in {:.0f} ms; {}x{} x {} spp\n", scene.name, tris.size(), load_ms, w, h,
               spp);
    fmt::print("bvh      {} nodes, {} leaves, depth {}, built in {:.0f} ms\n", bvh.nodes.size(), bvh.leaf_count, bvh.depth,
               bvh.build_ms);
    const bool both = args.variant == "both";
    std::vector<TraceVariant> variants;
    if (both)
      variants = {TraceVariant::Fast, TraceVariant::Robust};
    else
      variants = {parse_trace_variant(args.variant)};
    double build_before = rt.build_ms();
    std::vector<Tracer> tracers;
    const TraceLayout layout = parse_trace_layout(args.layout);
    for (TraceVariant v : variants) tracers.emplace_back(rt, bvh, v, layout);
    fmt::print("kernels  built in {:.0f} ms (reported apart from trace times)\n", rt.build_ms() - build_before);
#ifdef RAYSORT_HAVE_EMBREE
    std::optional<EmbreeScene> embree;
    if (with_embree) {
      embree.emplace(tris);
      fmt::print("embree   Embree {}, {} threads, rtcIntersect1 / rtcOccluded1, build quality high: BVH built in {:.0f} ms "
                 "(ours {:.0f} ms = {:.2f}x Embree's)\n",
                 EmbreeScene::version(), embree->threads(), embree->build_ms(), bvh.build_ms,
                 embree->build_ms() > 0 ? bvh.build_ms / embree->build_ms() : 0.0);
    }
    const char* emb_head = with_embree ? "   emb ms  emb MR/s" : "";
#else
    const char* emb_head = "";
#endif
    if (both) {
      fmt::print("variant  fast and robust, back to back on each batch ({} BVH)\n", trace_layout_name(layout));
      fmt::print("{:<10} {:>10} {:>9} {:>9} {:>9} {:>9} {:>8} {:>10} {:>8} {:>11}{}{}\n", "batch", "rays", "fast ms",
                 "fast MR/s", "rob ms", "rob MR/s", "rob/fast", "hits", "tri diff", "mismatches", emb_head,
                 with_embree ? " fast/emb  rob/emb  same %  +ties %" : "");
    } else {
      fmt::print("variant  {} ({} BVH)\n", trace_variant_name(variants[0]), trace_layout_name(layout));
      fmt::print("{:<10} {:>10} {:>10} {:>10} {:>10} {:>11}{}{}\n", "batch", "rays", "ms", "MRays/s", "hits", "mismatches",
                 emb_head, with_embree ? " ours/emb  same %  +ties %" : "");
    }

    // The pipeline of DESIGN.md section 1, as far as the scene's effects ask.
    for (const ReferencedBatch& rb : generate_batches(scene, tris, bvh, gen)) {
      const RayBatch& b = rb.batch;
      std::vector<VariantRun> runs;
      for (Tracer& tracer : tracers) runs.push_back(trace_variant(tracer, bvh, rb, args));
      std::size_t mismatches = 0;
      for (const VariantRun& r : runs) mismatches += r.mismatches;
      // Embree's columns: its median ms and MRays/s, ours/Embree per variant, the lowest agreement.
      std::string emb_cols;
      std::vector<std::string> emb_notes;
#ifdef RAYSORT_HAVE_EMBREE
      if (embree) {
        std::vector<Tracer::Run*> ours;
        for (VariantRun& r : runs) ours.push_back(&r.run);
        EmbreeRun e = trace_embree(*embree, rb, ours, args);
        emb_cols = fmt::format(" {:>8.2f} {:>9.2f}", e.run.median_ms, e.mrays);
        double worst = 1.0, worst_ties = 1.0;
        bool below = false;
        for (std::size_t i = 0; i < runs.size(); ++i) {
          emb_cols += fmt::format(" {:>8.3f}", e.mrays > 0 ? runs[i].mrays / e.mrays : 0.0);
          const HitAgreement& a = e.agreement[i];
          worst = std::min(worst, a.fraction());
          worst_ties = std::min(worst_ties, a.fraction_with_ties());
          below = below || a.fraction_with_ties() < kEmbreeMinAgreement;
          if (a.differences())
            emb_notes.push_back(fmt::format("{:<10} {}{} of {} rays differ from Embree: {}", "",
                                            both ? fmt::format("{}: ", trace_variant_name(tracers[i].variant())) : "",
                                            a.differences(), a.rays, a.describe()));
        }
        emb_cols += fmt::format(" {:>7.3f} {:>7.3f}", 100.0 * worst, 100.0 * worst_ties);
        if (below) {
          ++disagreeing_batches;
          emb_notes.push_back(fmt::format("{:<10} below the required {:.1f} % agreement with Embree (same triangle or a tie)",
                                          "", 100.0 * kEmbreeMinAgreement));
        }
      }
#endif
      if (both) {
        const VariantRun &f = runs[0], &r = runs[1];
        fmt::print("{:<10} {:>10} {:>9.2f} {:>9.2f} {:>9.2f} {:>9.2f} {:>8.3f} {:>10} {:>8} {:>11}{}\n", b.name, b.size(),
                   f.run.median_ms, f.mrays, r.run.median_ms, r.mrays, f.mrays > 0 ? r.mrays / f.mrays : 0.0,
                   r.hit_count, count_triangle_differences(f.run.hits, r.run.hits), mismatches, emb_cols);
      } else {
        const VariantRun& r = runs[0];
        fmt::print("{:<10} {:>10} {:>10.2f} {:>10.2f} {:>10} {:>11}{}\n", b.name, b.size(), r.run.median_ms, r.mrays,
                   r.hit_count, mismatches, emb_cols);
      }
      for (const auto& note : emb_notes) fmt::print("{}\n", note);
      std::fflush(stdout);
      total_mismatches += mismatches;
    }
  }
  int code = 0;
  if (total_mismatches > 0) {
    fmt::print(stderr, "raysort: {} hits differ from the host reference\n", total_mismatches);
    code = 1;
  }
  if (disagreeing_batches > 0) {
    fmt::print(stderr, "raysort: {} batches agree with Embree on fewer than 99.9 % of rays (same triangle or a tie)\n",
               disagreeing_batches);
    code = 1;
  }
  return code;
}

}  // namespace

void register_trace_command(CLI::App& app) {
  auto args = std::make_shared<TraceArgs>();
  auto* cmd = app.add_subcommand("trace", "trace a scene's ray batches on the device and verify every hit");
  cmd->add_option("--scene", args->scenes, "scene name, .toml or .obj path (comma-separated for several)")
      ->required()
      ->delimiter(',');
  add_common_options(*cmd, args->common);
  cmd->add_option("--reps", args->reps, "timed repetitions per batch (median reported)")->check(CLI::Range(1u, 1000u));
  cmd->add_option("--warmup", args->warmup, "untimed runs before timing");
  cmd->add_option("--variant", args->variant,
                  "traversal arithmetic: robust (watertight), fast (Moller-Trumbore), or both side by side")
      ->check(CLI::IsMember({"robust", "fast", "both"}))
      ->capture_default_str();
  cmd->add_option("--layout", args->layout,
                  "BVH the kernels walk: wide (4-wide, the default) or binary (to measure what the wide layout gains)")
      ->check(CLI::IsMember({"wide", "binary"}))
      ->capture_default_str();
  cmd->add_option("--reference", args->reference,
                  "also trace every batch with this CPU reference, side by side: embree (Embree 3, all host threads; "
                  "needs a build with libembree-dev)")
      ->check(CLI::IsMember({"embree"}));
  cmd->callback([args] { set_command_exit_code(run_trace(*args)); });
}

}  // namespace raysort
