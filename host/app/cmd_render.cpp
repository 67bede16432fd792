// raysort render: what the benchmark traces, as pictures (render/preview.h draws them,
// util/image.h writes them):
//   1. the converged image of the scene's light transport: the wavefront path tracer
//      (render/pathtrace.h, cl/shade.cl) on the device, or its host twin with --host, sample passes
//      averaged per pixel; written as EXR (linear radiance) and PNG (exposure, sRGB);
//   2. a traversal-cost heatmap: BVH nodes visited per pixel and sample by the closest-hit rays of
//      every depth (primary and bounces), as a PNG;
//   3. with --overlay, the boxes that the box-set encoders put their key bits on, drawn as orange
//      wireframes like the "cut node boundaries" figure of Xiang et al. ("Faster Ray Tracing through
//      Hierarchy Cut Code", section 6) over a simple preview shading of primary hits, with the
//      table of the cut nodes.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>

#include "app/commands.h"
#include "app/options.h"
#include "bvh/cut.h"
#include "bvh/prepared_scene.h"
#include "encode/encode.h"
#include "render/frame_memory.h"
#include "render/preview.h"
#include "util/error.h"
#include "util/image.h"
#include "util/output_name.h"

namespace raysort {

namespace {

struct RenderArgs {
  std::string scene;
  std::string overlay = "none";  // none, or one of kOverlays
  unsigned bits = 32;
  std::string out;
  float exposure = 0.0f;  // PNG only: radiance x 2^exposure before sRGB encoding
  bool host = false;      // the host twin instead of the device
  CommonOptions common;   // device, scene root, resolution, spp, seed
};

// The encoders whose boxes --overlay draws: the grid's cells, HCC's cut nodes, MLHCC's top level.
const Encoder kOverlays[] = {Encoder::RegularGrid, Encoder::HCC, Encoder::MLHCC};

// The encoder --overlay names; none for "none". Throws Error listing the encoders that have boxes.
std::optional<Encoder> overlay_encoder(const std::string& name) {
  if (name == "none") return std::nullopt;
  const auto e = parse_encoder(name);
  if (!e || std::find(std::begin(kOverlays), std::end(kOverlays), *e) == std::end(kOverlays)) {
    std::string names = "none";
    for (Encoder o : kOverlays) names += fmt::format(", {}", encoder_name(o));
    throw Error(fmt::format("--overlay '{}': expected {}", name, names));
  }
  return e;
}

// The boxes the encoder's key bits stand for, printing what they are: the grid's shape, or the cut
// nodes with their HAD and triangle counts, in key-bit order.
std::vector<Aabb> key_boxes(Encoder e, unsigned bits, const Bvh& bvh) {
  EncodeScene es(bvh, bvh.bounds());
  check_key_bits(e, bits, es.params());
  if (e == Encoder::RegularGrid) {
    const auto shape = regular_grid_shape(bvh.bounds(), bits);
    fmt::print("grid     {} x {} x {} cells of the scene box\n", shape[0], shape[1], shape[2]);
    return regular_grid_cells(bvh.bounds(), bits);
  }
  const bool two_level = e == Encoder::MLHCC;
  const auto& cut = two_level ? two_level_inputs(es, bits).cut.top : es.hcc_cut(bits);
  fmt::print("{} cut ({} nodes{}); bit = key bit from the top\n", encoder_name(e), cut.size(),
             two_level ? ", top level" : "");
  fmt::print("{:>4} {:>8} {:>12} {:>8}  box\n", "bit", "node", "HAD", "tris");
  std::vector<Aabb> boxes;
  for (std::size_t i = 0; i < cut.size(); ++i) {
    const RsBvhNode& n = bvh.nodes[cut[i]];
    std::uint32_t leaf_tris = 0;
    std::vector<std::uint32_t> stack{cut[i]};
    while (!stack.empty()) {
      const RsBvhNode& m = bvh.nodes[stack.back()];
      stack.pop_back();
      if (m.count > 0)
        leaf_tris += m.count;
      else
        stack.insert(stack.end(), {m.first, m.first + 1});
    }
    fmt::print("{:>4} {:>8} {:>12.5g} {:>8}  [{:.3g} {:.3g} {:.3g}] - [{:.3g} {:.3g} {:.3g}]\n", i, cut[i],
               es.had()[cut[i]], leaf_tris, n.bmin[0], n.bmin[1], n.bmin[2], n.bmax[0], n.bmax[1], n.bmax[2]);
    boxes.push_back(node_box(n));
  }
  return boxes;
}

// Output names: <base>.png / .exr / -cost.png [/ -<overlay>.png], base = --out without extension.
std::string output_base(const std::string& out, const std::string& scene_name) {
  if (out.empty()) return safe_file_name(scene_name);  // a scene's name is no path (util/output_name.h)
  const std::filesystem::path path(out), dir = path.parent_path();
  std::error_code ec;
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  return (dir / path.stem()).string();
}

int run_render(const RenderArgs& args) {
  const std::optional<Encoder> encoder = overlay_encoder(args.overlay);
  const PreparedScene prepared = prepare_scene(args.scene, args.common.scene_options());
  const Scene& scene = prepared.scene;
  const std::uint32_t w = scene.camera.width, h = scene.camera.height, spp = scene.effects.samples_per_pixel;
  fmt::print("scene    {}: {} triangles, bvh {} nodes, {} leaves\n", scene.name, prepared.tris.size(),
             prepared.bvh.nodes.size(), prepared.bvh.leaf_count);
  const std::string base = output_base(args.out, scene.name);

  std::unique_ptr<Runtime> rt;
  if (args.host) {
    fmt::print("device   host twin (--host)\n");
  } else {
    rt = std::make_unique<Runtime>(select_device(args.common.device));
    fmt::print("device   {} ({})\n", rt->info().name, rt->info().platform_name);
  }
  // Rays are traced in passes of at most kRenderPassPaths paths (render/preview.h): only the image's
  // per-pixel sums grow with the frame, so a render is refused by its resolution, never its spp.
  check_frame_memory(estimate_render_memory(scene), rt ? &rt->info() : nullptr,
                     fmt::format("scene {} at {}x{}, {} spp, rendered in passes of up to {} paths,", scene.name, w, h,
                                 spp, largest_render_pass(w, h, spp)),
                     "lower --resolution (a render keeps sums for every pixel; its rays are split into passes)");
  const RenderedFrame r = render_frame(prepared, args.common.raygen_options(), rt.get());
  fmt::print("frame    {}x{}, {} spp in {} pass{}: {} rays in {:.0f} ms ({:.2f} MRays/s incl. shading and compaction)\n",
             w, h, spp, r.passes, r.passes == 1 ? "" : "es", r.rays, r.ms,
             r.ms > 0 ? static_cast<double>(r.rays) / r.ms / 1e3 : 0.0);
  for (const auto& b : r.first_pass) fmt::print("  {:<10} {:>10} rays\n", b.name, b.rays);
  write_exr(r.image, base + ".exr");
  write_png(r.image, base + ".png", std::exp2(args.exposure));
  double low = 0.0, top = 1.0;
  write_png(cost_heatmap(r.cost, w, h, low, top), base + "-cost.png");
  double mean = 0.0;
  for (double c : r.cost) mean += c;
  mean /= static_cast<double>(std::max<std::size_t>(1, r.cost.size()));
  fmt::print("wrote    {0}.exr, {0}.png ({1}x{2}, exposure {3:+g})\n", base, w, h, args.exposure);
  fmt::print("wrote    {}-cost.png: BVH nodes visited per pixel and sample, closest-hit rays of every depth; "
             "mean {:.1f}; black = {:.0f} (1st percentile) and below, white = {:.0f} (99th) and above\n",
             base, mean, low, top);
  if (!encoder) return 0;

  const RsCamera cam = make_camera(scene.camera, w, h);
  Image img = shade_primary(prepared, cam);
  const float near = 1e-4f * std::max(1e-30f, prepared.bvh.bounds().largest_extent());
  draw_boxes(img, cam, key_boxes(*encoder, args.bits, prepared.bvh), near);
  const std::string out = base + "-" + args.overlay + ".png";
  write_png(img, out);
  fmt::print("wrote    {} ({}x{}, preview shading with the {} boxes)\n", out, w, h, args.overlay);
  return 0;
}

}  // namespace

void register_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand("render", "path-trace a scene (EXR + PNG) with a traversal-cost heatmap, optionally "
                                           "with the HCC cut boxes drawn on a preview");
  cmd->add_option("--scene,--scenes", args->scene, scene_option_help() + " (one)")->required();
  cmd->add_option("--overlay", args->overlay,
                  "boxes to draw on <base>-<overlay>.png: none, hcc (cut nodes), mlhcc (top-level), grid")
      ->capture_default_str();
  whole_number(cmd->add_option("--bits", args->bits, "key length the cut is chosen for (one box per bit)")
                   ->capture_default_str(),
               1, 64);
  cmd->add_option("--out", args->out,
                  "base of the output names: <base>.png, <base>.exr, <base>-cost.png (default: the scene's name)");
  // 2^1000 and beyond overflow a float's radiance scale.
  finite_number(cmd->add_option("--exposure", args->exposure, "PNG exposure in stops (radiance x 2^exposure)")
                    ->capture_default_str(),
                -100, 100);
  cmd->add_flag("--host", args->host, "run the host twin of the path tracer instead of the OpenCL device");
  add_common_options(*cmd, args->common);
  cmd->callback([args] { set_command_exit_code(run_render(*args)); });
}

}  // namespace raysort
