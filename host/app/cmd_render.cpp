// raysort render: a picture of a scene, optionally with the boxes that the box-set encoders put
// their key bits on, drawn as orange wireframes like the "cut node boundaries" figure of Xiang et
// al. ("Faster Ray Tracing through Hierarchy Cut Code", section 6), so a user can see where the
// bits go. The picture itself is a simple shading of primary hits (host reference traversal):
//   1. shade_primary  — one ray per pixel through the pixel centre, albedo × (ambient + |cos|)
//   2. overlay_boxes  — each box's 12 edges projected through the scene camera
//   3. write_png      — OpenImageIO
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "app/commands.h"
#include "app/options.h"
#include "bvh/bvh.h"
#include "bvh/cut.h"
#include "encode/encode.h"
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
  CommonOptions common;  // scene root and resolution
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

// 3. PNG (or any format OpenImageIO knows by the file's extension), sRGB-encoded 8 bits.
void write_png(const Image& img, const std::string& path) {
  std::vector<unsigned char> bytes(img.rgb.size());
  for (std::size_t i = 0; i < img.rgb.size(); ++i) {
    const float c = std::clamp(img.rgb[i], 0.0f, 1.0f);
    const float srgb = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
    bytes[i] = static_cast<unsigned char>(std::lround(srgb * 255.0f));
  }
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error(fmt::format("cannot write '{}': {} (use a .png path)", path, OIIO::geterror()));
  OIIO::ImageSpec spec(static_cast<int>(img.width), static_cast<int>(img.height), 3, OIIO::TypeDesc::UINT8);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) || !out->close())
    throw Error(fmt::format("writing '{}' failed: {}", path, out->geterror()));
}

int run_render(const RenderArgs& args) {
  Scene scene = load_scene(args.scene, args.common.scene_options());
  Scene::Flat tris = scene.flatten();
  Bvh bvh = build_bvh(tris);
  RayGenOptions gen = args.common.raygen_options();
  const std::uint32_t w = gen.width ? gen.width : scene.camera.width;
  const std::uint32_t h = gen.height ? gen.height : scene.camera.height;
  const RsCamera cam = make_camera(scene.camera, w, h);
  fmt::print("scene    {}: {} triangles, bvh {} nodes, {} leaves\n", scene.name, tris.size(), bvh.nodes.size(),
             bvh.leaf_count);
  Image img = shade_primary(scene, tris, bvh, cam);

  std::vector<Aabb> boxes;
  if (args.overlay != "none") {
    const auto encoder = parse_encoder(args.overlay);
    if (!encoder || (*encoder != Encoder::HCC && *encoder != Encoder::MLHCC && *encoder != Encoder::RegularGrid))
      throw Error(fmt::format("--overlay '{}': expected none, hcc, mlhcc or grid", args.overlay));
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
  const std::string out = args.out.empty() ? scene.name + (args.overlay == "none" ? "" : "-" + args.overlay) + ".png"
                                           : args.out;
  write_png(img, out);
  fmt::print("wrote    {} ({}x{})\n", out, w, h);
  return 0;
}

}  // namespace

void register_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand("render", "render a scene to a PNG, optionally with the HCC cut boxes drawn on it");
  cmd->add_option("--scene", args->scene, "scene name, .toml or .obj path")->required();
  cmd->add_option("--overlay", args->overlay, "boxes to draw: none, hcc (cut nodes), mlhcc (top-level), grid")
      ->capture_default_str();
  cmd->add_option("--bits", args->bits, "key length the cut is chosen for (one box per bit)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 64u));
  cmd->add_option("--out", args->out, "output image (default: <scene>[-<overlay>].png)");
  cmd->add_option("--resolution", args->common.resolution, "image size WxH (default: the scene's)");
  cmd->add_option("--scene-root", args->common.scene_root,
                  "folder the scene files' OBJ paths are relative to (env RAYSORT_SCENE_ROOT)");
  cmd->callback([args] { set_command_exit_code(run_render(*args)); });
}

}  // namespace raysort
