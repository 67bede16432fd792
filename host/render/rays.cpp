#include "render/rays.h"

#include <cmath>

#include "util/error.h"

namespace raysort {

namespace {

// RNG dimensions within a bounce (RS_DIM(bounce, dim)).
enum Dim : std::uint32_t {
  kPixelJitterX = 0,
  kPixelJitterY = 1,
  kBounceU1 = 2,
  kBounceU2 = 3,
  kRoulette = 4,
  kShadowBase = 8,  // + 3 per shadow ray: light choice, u1, u2
};

RsVec3 to_rs(const Vec3& v) { return rs_vec3(v[0], v[1], v[2]); }

float uniform(const RayGenOptions& o, std::uint32_t pixel, std::uint32_t sample, std::uint32_t bounce, std::uint32_t dim) {
  return rs_uniform(rs_hash4(o.seed, pixel, sample, RS_DIM(bounce, dim)));
}

RsRay make_ray(RsVec3 o, RsVec3 d, float tmax) {
  RsRay r;
  r.o[0] = o.x;
  r.o[1] = o.y;
  r.o[2] = o.z;
  r.tmin = 0.0f;
  r.d[0] = d.x;
  r.d[1] = d.y;
  r.d[2] = d.z;
  r.tmax = tmax;
  return r;
}

struct SurfacePoint {
  RsVec3 p, n;
};

SurfacePoint surface_point(const Scene::Flat& tris, const RsRay& ray, const RsHit& hit) {
  RsVec3 v0 = to_rs(tris.v0[hit.tri]), v1 = to_rs(tris.v1[hit.tri]), v2 = to_rs(tris.v2[hit.tri]);
  RsVec3 d = rs_vec3(ray.d[0], ray.d[1], ray.d[2]);
  return {rs_hit_point(v0, v1, v2, hit.u, hit.v), rs_facing_normal(v0, v1, v2, d)};
}

}  // namespace

RsCamera make_camera(const Camera& cam, std::uint32_t width, std::uint32_t height) {
  if (width == 0 || height == 0) throw Error("resolution must be at least 1x1");
  RsVec3 pos = to_rs(cam.position);
  RsVec3 forward = rs_normalize(rs_sub(to_rs(cam.look_at), pos));
  RsVec3 right = rs_normalize(rs_cross(forward, to_rs(cam.up)));
  RsVec3 up = rs_cross(right, forward);
  RsCamera c{};
  c.pos[0] = pos.x, c.pos[1] = pos.y, c.pos[2] = pos.z;
  c.forward[0] = forward.x, c.forward[1] = forward.y, c.forward[2] = forward.z;
  c.right[0] = right.x, c.right[1] = right.y, c.right[2] = right.z;
  c.up[0] = up.x, c.up[1] = up.y, c.up[2] = up.z;
  // Host-only setup value: every device receives the same float.
  c.tan_half_fov_y = static_cast<float>(std::tan(cam.fov_y_deg * 0.5 * 3.14159265358979323846 / 180.0));
  c.aspect = static_cast<float>(width) / static_cast<float>(height);
  c.width = width;
  c.height = height;
  return c;
}

RayBatch generate_primary(const Scene& scene, const RayGenOptions& o) {
  const std::uint32_t w = o.width ? o.width : scene.camera.width;
  const std::uint32_t h = o.height ? o.height : scene.camera.height;
  const std::uint32_t spp = o.spp ? o.spp : scene.effects.samples_per_pixel;
  RsCamera cam = make_camera(scene.camera, w, h);
  RayBatch b;
  b.name = "primary";
  b.kind = BatchKind::Primary;
  const std::size_t n = static_cast<std::size_t>(w) * h * spp;
  b.rays.reserve(n);
  b.pixel.reserve(n);
  b.sample.reserve(n);
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x)
      for (std::uint32_t s = 0; s < spp; ++s) {
        std::uint32_t pixel = y * w + x;
        b.rays.push_back(rs_camera_ray(cam, x, y, uniform(o, pixel, s, 0, kPixelJitterX), uniform(o, pixel, s, 0, kPixelJitterY)));
        b.pixel.push_back(pixel);
        b.sample.push_back(s);
      }
  return b;
}

RayBatch generate_shadow(const Scene& scene, const Scene::Flat& tris, const RayBatch& batch,
                         const std::vector<RsHit>& hits, const RayGenOptions& o) {
  RayBatch b;
  b.name = "shadow" + std::to_string(batch.bounce);
  b.kind = BatchKind::Shadow;
  b.bounce = batch.bounce;
  const std::uint32_t per_hit = scene.effects.shadow_rays_per_bounce;
  if (scene.sphere_lights.empty() || per_hit == 0) return b;

  // Light selection by power: a cumulative distribution over the sphere lights.
  std::vector<float> cdf;
  float total = 0.0f;
  for (const auto& l : scene.sphere_lights) {
    total += std::max(0.0f, l.power);
    cdf.push_back(total);
  }
  const float extent = scene.bounds().largest_extent();
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (hits[i].tri == RS_NO_HIT) continue;
    SurfacePoint sp = surface_point(tris, batch.rays[i], hits[i]);
    RsVec3 origin = rs_offset_ray_origin(sp.p, sp.n);
    for (std::uint32_t k = 0; k < per_hit; ++k) {
      const std::uint32_t pix = batch.pixel[i], smp = batch.sample[i], dim = kShadowBase + 3 * k;
      float pick = uniform(o, pix, smp, batch.bounce, dim) * total;
      std::size_t li = 0;
      while (li + 1 < cdf.size() && pick >= cdf[li]) ++li;
      const SphereLight& light = scene.sphere_lights[li];
      RsVec3 q = rs_add(to_rs(light.center), rs_scale(rs_sphere_point(uniform(o, pix, smp, batch.bounce, dim + 1),
                                                                        uniform(o, pix, smp, batch.bounce, dim + 2)),
                                                       light.radius(extent)));
      RsVec3 to_light = rs_sub(q, origin);
      float dist = rs_sqrt(rs_dot(to_light, to_light));
      if (!(dist > 0.0f) || rs_dot(to_light, sp.n) <= 0.0f) continue;  // light behind the surface
      b.rays.push_back(make_ray(origin, rs_scale(to_light, 1.0f / dist), dist));
      b.pixel.push_back(pix);
      b.sample.push_back(smp);
    }
  }
  return b;
}

RayBatch generate_bounce(const Scene& scene, const Scene::Flat& tris, const RayBatch& batch,
                         const std::vector<RsHit>& hits, const RayGenOptions& o) {
  RayBatch b;
  b.bounce = batch.bounce + 1;
  b.name = "bounce" + std::to_string(b.bounce);
  b.kind = BatchKind::Bounce;
  const bool roulette = b.bounce >= scene.effects.russian_roulette_start;
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (hits[i].tri == RS_NO_HIT) continue;
    const std::uint32_t pix = batch.pixel[i], smp = batch.sample[i];
    if (roulette && uniform(o, pix, smp, b.bounce, kRoulette) >= scene.effects.russian_roulette_survival) continue;
    SurfacePoint sp = surface_point(tris, batch.rays[i], hits[i]);
    RsVec3 d = rs_cosine_direction(sp.n, uniform(o, pix, smp, b.bounce, kBounceU1), uniform(o, pix, smp, b.bounce, kBounceU2));
    b.rays.push_back(make_ray(rs_offset_ray_origin(sp.p, sp.n), d, RS_T_FAR));
    b.pixel.push_back(pix);
    b.sample.push_back(smp);
  }
  return b;
}

}  // namespace raysort
