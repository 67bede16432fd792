// raysort render: what the benchmark traces, as pictures.
//   1. the converged image of the scene's light transport: the wavefront path tracer
//      (render/pathtrace.h, cl/shade.cl) on the device, or its host twin with --host, sample passes
//      averaged per pixel; written as EXR (linear radiance) and PNG (exposure, sRGB);
//   2. a traversal-cost heatmap: BVH nodes visited per pixel and sample by the closest-hit rays of
//      every depth (primary and bounces), as a PNG;
//   3. with --overlay, the boxes that the box-set encoders put their key bits on, drawn as orange
//      wireframes like the "cut node boundaries" figure of Xiang et al. ("Faster Ray Tracing through
//      Hierarchy Cut Code", section 6) over a simple preview shading of primary hits (host
//      reference traversal), albedo x (ambient + |cos|), so the boxes read clearly.
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>

#include "app/commands.h"
#include "app/options.h"
#include "bvh/prepared_scene.h"
#include "bvh/cut.h"
#include "encode/encode.h"
#include "render/pathtrace.h"
#include "render/rays.h"
#include "scene/load.h"
#include "trace/tracer.h"
#include "util/error.h"

namespace raysort {

namespace {

struct RenderArgs {
  std::string scene;
  std::string overlay = "none";  // none | hcc | mlhcc | grid
  unsigned bits = 32;
  std::string out;
  float exposure = 0.0f;  // PNG only: radiance x 2^exposure before sRGB encoding
  bool host = false;      // the host twin instead of the device
  CommonOptions common;   // device, scene root, resolution, spp, seed
};

// A linear RGB image, row-major from the top-left pixel.
struct Image {
  std::uint32_t width = 0, height = 0;
  std::vector<float> rgb;
  void set(int x, int y, const Vec3& c) {
    if (x < 0 || y < 0 || x >= static_cast<int>(width) || y >= static_cast<int>(height)) return;
    float* p = &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
    p[0] = c[0], p[1] = c[1], p[2] = c[2];
  }
};

// 1. Primary hits, shaded by albedo × (0.15 + 0.85·|cos θ|) against the view ray; misses are the
// sky colour when the scene has a sky, else dark grey.
Image shade_primary(const Scene& scene, const Scene::Flat& tris, const Bvh& bvh, const RsCamera& cam) {
  Image img{cam.width, cam.height, std::vector<float>(static_cast<std::size_t>(cam.width) * cam.height * 3, 0.0f)};
  std::vector<RsRay> rays;
  rays.reserve(static_cast<std::size_t>(cam.width) * cam.height);
  for (std::uint32_t y = 0; y < cam.height; ++y)
    for (std::uint32_t x = 0; x < cam.width; ++x) rays.push_back(rs_camera_ray(cam, x, y, 0.5f, 0.5f));
  const auto hits = trace_reference(bvh, rays, nullptr, false);
  const Vec3 background = scene.sky.enabled ? scene.sky.horizon : Vec3{0.05f, 0.05f, 0.05f};
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const int x = static_cast<int>(i % cam.width), y = static_cast<int>(i / cam.width);
    if (hits[i].tri == RS_NO_HIT) {
      img.set(x, y, background);
      continue;
    }
    const auto t = hits[i].tri;
    const RsVec3 d = rs_load3(rays[i].d);
    const RsVec3 n = rs_facing_normal(rs_load3(tris.v0[t].data()), rs_load3(tris.v1[t].data()),
                                      rs_load3(tris.v2[t].data()), d);
    const float cosine = std::fabs(rs_dot(n, d));
    const std::int32_t m = tris.material.empty() ? 0 : tris.material[t];
    const Vec3 albedo = m >= 0 && static_cast<std::size_t>(m) < scene.materials.size() ? scene.materials[m].albedo
                                                                                        : Vec3{0.7f, 0.7f, 0.7f};
    const float s = 0.15f + 0.85f * cosine;
    img.set(x, y, {albedo[0] * s, albedo[1] * s, albedo[2] * s});
  }
  return img;
}

// 2. Wireframes: each edge is clipped to the space in front of the camera, projected with the
// camera's pinhole model (the inverse of rs_camera_ray) and drawn 2 pixels wide. No depth test:
// boxes behind walls show through, as in the paper's figure.
void draw_segment(Image& img, const RsCamera& cam, RsVec3 a, RsVec3 b, const Vec3& color, float near) {
  const RsVec3 pos = rs_load3(cam.pos), fwd = rs_load3(cam.forward), right = rs_load3(cam.right), up = rs_load3(cam.up);
  auto to_camera = [&](RsVec3 p) {
    RsVec3 v = rs_sub(p, pos);
    return rs_vec3(rs_dot(v, right), rs_dot(v, up), rs_dot(v, fwd));
  };
  RsVec3 ca = to_camera(a), cb = to_camera(b);
  if (ca.z < near && cb.z < near) return;
  if (ca.z < near || cb.z < near) {
    const float t = (near - ca.z) / (cb.z - ca.z);
    RsVec3 c = rs_add(ca, rs_scale(rs_sub(cb, ca), t));
    (ca.z < near ? ca : cb) = c;
  }
  auto project = [&](RsVec3 c, float& px, float& py) {
    const float sx = c.x / c.z / (cam.tan_half_fov_y * cam.aspect), sy = c.y / c.z / cam.tan_half_fov_y;
    px = (sx + 1.0f) * 0.5f * static_cast<float>(cam.width);
    py = (1.0f - sy) * 0.5f * static_cast<float>(cam.height);
  };
  float x0, y0, x1, y1;
  project(ca, x0, y0);
  project(cb, x1, y1);
  // Keep far-off endpoints from making the loop huge: clamp the parameter range to the image.
  const float len = std::max(std::fabs(x1 - x0), std::fabs(y1 - y0));
  if (!(len < 1e7f)) return;
  const int steps = std::max(1, static_cast<int>(std::ceil(len)));
  for (int s = 0; s <= steps; ++s) {
    const float t = static_cast<float>(s) / static_cast<float>(steps);
    const int x = static_cast<int>(std::floor(x0 + (x1 - x0) * t)), y = static_cast<int>(std::floor(y0 + (y1 - y0) * t));
    if (x < -1 || y < -1 || x > static_cast<int>(img.width) || y > static_cast<int>(img.height)) continue;
    img.set(x, y, color);
    img.set(x + 1, y, color);
    img.set(x, y + 1, color);
  }
}

void overlay_boxes(Image& img, const RsCamera& cam, const std::vector<Aabb>& boxes, float near) {
  const Vec3 orange{1.0f, 0.45f, 0.0f};
  for (const Aabb& b : boxes) {
    auto corner = [&](int i) {
      return rs_vec3((i & 1) ? b.max[0] : b.min[0], (i & 2) ? b.max[1] : b.min[1], (i & 4) ? b.max[2] : b.min[2]);
    };
    for (int i = 0; i < 8; ++i)
      for (int axis = 0; axis < 3; ++axis)
        if (!(i & (1 << axis))) draw_segment(img, cam, corner(i), corner(i | (1 << axis)), orange, near);
  }
}

// PNG (or any format OpenImageIO knows by the file's extension), sRGB-encoded 8 bits.
void write_png(const Image& img, const std::string& path, float scale = 1.0f) {
  std::vector<unsigned char> bytes(img.rgb.size());
  for (std::size_t i = 0; i < img.rgb.size(); ++i) {
    const float c = std::clamp(img.rgb[i] * scale, 0.0f, 1.0f);
    const float srgb = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
    bytes[i] = static_cast<unsigned char>(std::lround(srgb * 255.0f));
  }
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error(fmt::format("cannot write '{}': {} (use a .png path)", path, OIIO::geterror()));
  OIIO::ImageSpec spec(static_cast<int>(img.width), static_cast<int>(img.height), 3, OIIO::TypeDesc::UINT8);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) || !out->close())
    throw Error(fmt::format("writing '{}' failed: {}", path, out->geterror()));
}

// Linear radiance as 32-bit float RGB (OpenEXR through OpenImageIO).
void write_exr(const Image& img, const std::string& path) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error(fmt::format("cannot write '{}': {}", path, OIIO::geterror()));
  OIIO::ImageSpec spec(static_cast<int>(img.width), static_cast<int>(img.height), 3, OIIO::TypeDesc::FLOAT);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, img.rgb.data()) || !out->close())
    throw Error(fmt::format("writing '{}' failed: {}", path, out->geterror()));
}

// Heatmap colours: black -> purple -> orange -> yellow -> white (an inferno-like ramp), t in [0, 1].
Vec3 heat_color(float t) {
  static const Vec3 stops[] = {{0.0f, 0.0f, 0.02f}, {0.33f, 0.06f, 0.43f}, {0.87f, 0.32f, 0.23f},
                               {0.99f, 0.75f, 0.2f}, {1.0f, 1.0f, 0.9f}};
  t = std::clamp(t, 0.0f, 1.0f) * 4.0f;
  const int i = std::min(3, static_cast<int>(t));
  const float f = t - static_cast<float>(i);
  Vec3 c;
  for (int a = 0; a < 3; ++a) c[a] = stops[i][a] + (stops[i + 1][a] - stops[i][a]) * f;
  return c;
}

// 1.-2. The path-traced image and the per-pixel traversal cost, in sample passes of at most
// ~2 M paths (bounded device memory at any resolution and spp).
struct Rendered {
  Image image;
  std::vector<double> cost;  // nodes visited per pixel and sample
  std::vector<BatchCount> first_pass;
  std::size_t rays = 0;
  double ms = 0.0;
};

Rendered path_trace(const RenderArgs& args, const Scene& scene, const Scene::Flat& tris, const Bvh& bvh,
                    const RayGenOptions& gen) {
  const ShadeInputs in = make_shade_inputs(scene, tris, gen);
  const std::size_t pixels = std::size_t{in.width} * in.height;
  const auto per_pass = static_cast<std::uint32_t>(std::max<std::size_t>(1, (std::size_t{2} << 20) / pixels));
  std::unique_ptr<Runtime> rt;
  std::unique_ptr<DevicePathTracer> device;
  if (args.host) {
    fmt::print("device   host twin (--host)\n");
  } else {
    rt = std::make_unique<Runtime>(select_device(args.common.device));
    fmt::print("device   {} ({})\n", rt->info().name, rt->info().platform_name);
    device = std::make_unique<DevicePathTracer>(*rt, bvh, in);
  }
  Rendered r;
  r.image = {in.width, in.height, std::vector<float>(pixels * 3, 0.0f)};
  r.cost.assign(pixels, 0.0);
  std::vector<double> sum(pixels * 3, 0.0);
  const auto t0 = std::chrono::steady_clock::now();
  for (std::uint32_t s = 0; s < in.spp; s += per_pass) {
    FrameOptions fo;
    fo.sample_begin = s;
    fo.sample_count = per_pass;
    fo.count_visits = true;
    Frame f = device ? device->trace_frame(fo) : trace_frame_host(in, bvh, fo);
    if (s == 0) r.first_pass = f.batches;
    for (const auto& b : f.batches) r.rays += b.rays;
    for (std::size_t path = 0; path < f.visits.size(); ++path) {
      const std::size_t pixel = path / f.spp;
      for (int c = 0; c < 3; ++c) sum[3 * pixel + c] += f.radiance[3 * path + c];
      r.cost[pixel] += f.visits[path];
    }
  }
  r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  for (std::size_t i = 0; i < sum.size(); ++i) r.image.rgb[i] = static_cast<float>(sum[i] / in.spp);
  for (double& c : r.cost) c /= in.spp;
  return r;
}

// The colour ramp spans the 1st to the 99th percentile of the cost, so a few extreme pixels do not
// flatten the picture.
Image heatmap(const std::vector<double>& cost, std::uint32_t width, std::uint32_t height, double& low, double& top) {
  std::vector<double> sorted(cost);
  std::sort(sorted.begin(), sorted.end());
  auto percentile = [&](std::size_t p) { return sorted.empty() ? 0.0 : sorted[std::min(sorted.size() - 1, sorted.size() * p / 100)]; };
  low = percentile(1);
  top = std::max(low + 1.0, percentile(99));
  Image img{width, height, std::vector<float>(cost.size() * 3)};
  for (std::size_t i = 0; i < cost.size(); ++i) {
    const Vec3 c = heat_color(static_cast<float>((cost[i] - low) / (top - low)));
    img.rgb[3 * i] = c[0], img.rgb[3 * i + 1] = c[1], img.rgb[3 * i + 2] = c[2];
  }
  return img;
}

int run_render(const RenderArgs& args) {
  const PreparedScene prepared = prepare_scene(args.scene, args.common.scene_options());
  const Scene& scene = prepared.scene;
  const Scene::Flat& tris = prepared.tris;
  const Bvh& bvh = prepared.bvh;
  const RayGenOptions gen = args.common.raygen_options();
  const std::uint32_t w = scene.camera.width, h = scene.camera.height;
  const RsCamera cam = make_camera(scene.camera, w, h);
  fmt::print("scene    {}: {} triangles, bvh {} nodes, {} leaves\n", scene.name, tris.size(), bvh.nodes.size(),
             bvh.leaf_count);
  // Output names: <base>.png / .exr / -cost.png [/ -<overlay>.png], base = --out without extension.
  std::string base = scene.name;
  if (!args.out.empty()) {
    const std::filesystem::path out(args.out), dir = out.parent_path();
    base = (dir / out.stem()).string();
    std::error_code ec;
    if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  }
  std::optional<Encoder> encoder;
  if (args.overlay != "none") {
    encoder = parse_encoder(args.overlay);
    if (!encoder || !encoder_info(*encoder).overlay) {
      std::string names = "none";
      for (const EncoderInfo& info : encoder_table())
        if (info.overlay) names += fmt::format(", {}", info.name);
      throw Error(fmt::format("--overlay '{}': expected {}", args.overlay, names));
    }
  }

  const Rendered r = path_trace(args, scene, tris, bvh, gen);
  const std::uint32_t spp = scene.effects.samples_per_pixel;
  fmt::print("frame    {}x{}, {} spp: {} rays in {:.0f} ms ({:.2f} MRays/s incl. shading and compaction)\n", w, h, spp,
             r.rays, r.ms, r.ms > 0 ? static_cast<double>(r.rays) / r.ms / 1e3 : 0.0);
  for (const auto& b : r.first_pass) fmt::print("  {:<10} {:>10} rays\n", b.name, b.rays);
  write_exr(r.image, base + ".exr");
  write_png(r.image, base + ".png", std::exp2(args.exposure));
  double low = 0.0, top = 1.0;
  write_png(heatmap(r.cost, w, h, low, top), base + "-cost.png");
  double mean = 0.0;
  for (double c : r.cost) mean += c;
  mean /= std::max<std::size_t>(1, r.cost.size());
  fmt::print("wrote    {0}.exr, {0}.png ({1}x{2}, exposure {3:+g})\n", base, w, h, args.exposure);
  fmt::print("wrote    {}-cost.png: BVH nodes visited per pixel and sample, closest-hit rays of every depth; "
             "mean {:.1f}; black = {:.0f} (1st percentile) and below, white = {:.0f} (99th) and above\n",
             base, mean, low, top);
  if (!encoder) return 0;

  Image img = shade_primary(scene, tris, bvh, cam);
  std::vector<Aabb> boxes;
  {
    EncodeScene es(bvh, bvh.bounds());
    check_key_bits(*encoder, args.bits, es.params());
    if (*encoder == Encoder::RegularGrid) {
      boxes = regular_grid_cells(bvh.bounds(), args.bits);
      auto shape = regular_grid_shape(bvh.bounds(), args.bits);
      fmt::print("grid     {} x {} x {} cells of the scene box\n", shape[0], shape[1], shape[2]);
    } else {
      const bool two_level = *encoder == Encoder::MLHCC;
      const auto& cut = two_level ? es.two_level(args.bits).cut.top : es.hcc_cut(args.bits);
      fmt::print("{} cut ({} nodes{}); bit = key bit from the top\n", encoder_name(*encoder), cut.size(),
                 two_level ? ", top level" : "");
      fmt::print("{:>4} {:>8} {:>12} {:>8}  box\n", "bit", "node", "HAD", "tris");
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
    }
    overlay_boxes(img, cam, boxes, 1e-4f * std::max(1e-30f, bvh.bounds().largest_extent()));
  }
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
  cmd->add_option("--scene,--scenes", args->scene, "scene name, .toml or .obj path (one)")->required();
  cmd->add_option("--overlay", args->overlay,
                  "boxes to draw on <base>-<overlay>.png: none, hcc (cut nodes), mlhcc (top-level), grid")
      ->capture_default_str();
  cmd->add_option("--bits", args->bits, "key length the cut is chosen for (one box per bit)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 64u));
  cmd->add_option("--out", args->out,
                  "base of the output names: <base>.png, <base>.exr, <base>-cost.png (default: the scene's name)");
  cmd->add_option("--exposure", args->exposure, "PNG exposure in stops (radiance x 2^exposure)")->capture_default_str();
  cmd->add_flag("--host", args->host, "run the host twin of the path tracer instead of the OpenCL device");
  add_common_options(*cmd, args->common);
  cmd->callback([args] { set_command_exit_code(run_render(*args)); });
}

}  // namespace raysort
