#include "render/preview.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "sampling.h"
#include "trace/tracer.h"

namespace raysort {

namespace {

void set(Image& img, int x, int y, const Vec3& c) { img.set(x, y, c[0], c[1], c[2]); }

// Heatmap colours: black -> purple -> orange -> yellow -> white, t in [0, 1].
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
  // Keep far-off endpoints from making the loop huge.
  const float len = std::max(std::fabs(x1 - x0), std::fabs(y1 - y0));
  if (!(len < 1e7f)) return;
  const int steps = std::max(1, static_cast<int>(std::ceil(len)));
  for (int s = 0; s <= steps; ++s) {
    const float t = static_cast<float>(s) / static_cast<float>(steps);
    const int x = static_cast<int>(std::floor(x0 + (x1 - x0) * t)), y = static_cast<int>(std::floor(y0 + (y1 - y0) * t));
    if (x < -1 || y < -1 || x > static_cast<int>(img.width) || y > static_cast<int>(img.height)) continue;
    set(img, x, y, color);
    set(img, x + 1, y, color);
    set(img, x, y + 1, color);
  }
}

// The shape every pass of plan_render_passes has (the last ones may be smaller).
struct PassShape {
  std::uint32_t samples = 0;
  std::uint64_t rows = 0;
};
PassShape render_pass_shape(std::uint32_t width, std::uint32_t height, std::uint32_t spp, std::uint64_t paths_per_pass) {
  const std::uint64_t pixels = std::uint64_t{width} * height;
  const std::uint64_t budget = std::max<std::uint64_t>(1, paths_per_pass);
  // Whole frames of several samples while they fit; else one sample of as many rows as fit.
  PassShape shape;
  const std::uint64_t fit = budget / std::max<std::uint64_t>(1, pixels);  // whole frames per pass
  shape.samples = static_cast<std::uint32_t>(std::clamp<std::uint64_t>(fit, 1, std::max(1u, spp)));
  shape.rows = pixels <= budget ? height : std::max<std::uint64_t>(1, budget / width);
  return shape;
}

}  // namespace

std::uint64_t largest_render_pass(std::uint32_t width, std::uint32_t height, std::uint32_t spp,
                                  std::uint64_t paths_per_pass) {
  const PassShape shape = render_pass_shape(width, height, spp, paths_per_pass);
  return std::min<std::uint64_t>(shape.rows, height) * width * shape.samples;
}

std::vector<RenderPass> plan_render_passes(std::uint32_t width, std::uint32_t height, std::uint32_t spp,
                                           std::uint64_t paths_per_pass) {
  std::vector<RenderPass> passes;
  if (std::uint64_t{width} * height == 0 || spp == 0) return passes;
  const auto [samples, rows] = render_pass_shape(width, height, spp, paths_per_pass);
  for (std::uint32_t s = 0; s < spp; s += samples)
    for (std::uint64_t y = 0; y < height; y += rows) {
      RenderPass pass;
      pass.sample_begin = s;
      pass.sample_count = std::min(samples, spp - s);
      pass.pixel_begin = static_cast<std::uint32_t>(y * width);
      pass.pixel_count = static_cast<std::uint32_t>(std::min<std::uint64_t>(rows, height - y) * width);
      passes.push_back(pass);
    }
  return passes;
}

RenderedFrame render_frame(const PreparedScene& p, const RayGenOptions& gen, Runtime* rt,
                           std::uint64_t paths_per_pass) {
  const ShadeInputs in = make_shade_inputs(p.scene, p.tris, gen);
  const std::size_t pixels = std::size_t{in.width} * in.height;
  std::unique_ptr<DevicePathTracer> device;
  if (rt) device = std::make_unique<DevicePathTracer>(*rt, p.bvh, in);
  RenderedFrame r;
  r.image = Image(in.width, in.height);
  r.cost.assign(pixels, 0.0);
  std::vector<double> sum(pixels * 3, 0.0);
  const auto t0 = std::chrono::steady_clock::now();
  for (const RenderPass& pass : plan_render_passes(in.width, in.height, in.spp, paths_per_pass)) {
    FrameOptions fo;
    fo.sample_begin = pass.sample_begin;
    fo.sample_count = pass.sample_count;
    fo.pixel_begin = pass.pixel_begin;
    fo.pixel_count = pass.pixel_count;
    fo.count_visits = true;
    Frame f = device ? device->trace_frame(fo) : trace_frame_host(in, p.bvh, fo);
    ++r.passes;
    for (const auto& b : f.batches) {
      r.rays += b.rays;
      if (pass.sample_begin != 0) continue;
      auto same = std::find_if(r.first_pass.begin(), r.first_pass.end(), [&](const BatchCount& c) { return c.name == b.name; });
      if (same == r.first_pass.end())
        r.first_pass.push_back(b);
      else
        same->rays += b.rays;
    }
    for (std::size_t path = 0; path < f.visits.size(); ++path) {
      const std::size_t pixel = f.pixel_begin + path / f.spp;
      for (int c = 0; c < 3; ++c) sum[3 * pixel + c] += f.radiance[3 * path + c];
      r.cost[pixel] += f.visits[path];
    }
  }
  // Trace order (primary, shadow0, bounce1, shadow1, ...), whichever row pass met a batch first.
  auto trace_rank = [](const BatchCount& c) { return 2 * c.bounce + (c.kind == BatchKind::Shadow ? 1 : 0); };
  std::stable_sort(r.first_pass.begin(), r.first_pass.end(),
                   [&](const BatchCount& a, const BatchCount& b) { return trace_rank(a) < trace_rank(b); });
  r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  for (std::size_t i = 0; i < sum.size(); ++i) r.image.rgb[i] = static_cast<float>(sum[i] / in.spp);
  for (double& c : r.cost) c /= in.spp;
  return r;
}

Image cost_heatmap(const std::vector<double>& cost, std::uint32_t width, std::uint32_t height, double& low,
                   double& top) {
  std::vector<double> sorted(cost);
  std::sort(sorted.begin(), sorted.end());
  auto percentile = [&](std::size_t q) {
    return sorted.empty() ? 0.0 : sorted[std::min(sorted.size() - 1, sorted.size() * q / 100)];
  };
  low = percentile(1);
  top = std::max(low + 1.0, percentile(99));
  Image img(width, height);
  for (std::size_t i = 0; i < cost.size(); ++i) {
    const Vec3 c = heat_color(static_cast<float>((cost[i] - low) / (top - low)));
    img.rgb[3 * i] = c[0], img.rgb[3 * i + 1] = c[1], img.rgb[3 * i + 2] = c[2];
  }
  return img;
}

Image shade_primary(const PreparedScene& p, const RsCamera& cam) {
  Image img(cam.width, cam.height);
  std::vector<RsRay> rays;
  rays.reserve(static_cast<std::size_t>(cam.width) * cam.height);
  for (std::uint32_t y = 0; y < cam.height; ++y)
    for (std::uint32_t x = 0; x < cam.width; ++x) rays.push_back(rs_camera_ray(cam, x, y, 0.5f, 0.5f));
  const auto hits = trace_reference(p.bvh, rays, nullptr, false);
  const Vec3 background = p.scene.sky.enabled ? p.scene.sky.horizon : Vec3{0.05f, 0.05f, 0.05f};
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const int x = static_cast<int>(i % cam.width), y = static_cast<int>(i / cam.width);
    if (hits[i].tri == RS_NO_HIT) {
      set(img, x, y, background);
      continue;
    }
    const auto t = hits[i].tri;
    const RsVec3 d = rs_load3(rays[i].d);
    const RsVec3 n = rs_facing_normal(rs_load3(p.tris.v0[t].data()), rs_load3(p.tris.v1[t].data()),
                                      rs_load3(p.tris.v2[t].data()), d);
    const float cosine = std::fabs(rs_dot(n, d));
    const std::int32_t m = p.tris.material.empty() ? 0 : p.tris.material[t];
    const Vec3 albedo = m >= 0 && static_cast<std::size_t>(m) < p.scene.materials.size()
                            ? p.scene.materials[m].albedo
                            : Vec3{0.7f, 0.7f, 0.7f};
    const float s = 0.15f + 0.85f * cosine;
    set(img, x, y, {albedo[0] * s, albedo[1] * s, albedo[2] * s});
  }
  return img;
}

void draw_boxes(Image& img, const RsCamera& cam, const std::vector<Aabb>& boxes, float near) {
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

}  // namespace raysort
