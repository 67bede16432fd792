/* raysort — the shading stage of the wavefront path tracer, shared by cl/shade.cl and the host twin
 * (host/render/pathtrace.cpp). Like shared.h it compiles as OpenCL C 1.2 and as C++ (with
 * -ffp-contract=off), so the device and the host compute the same rays and radiance bit for bit.
 *
 * The pipeline is the small-kernel wavefront of Laine et al. 2013 ("Megakernels Considered
 * Harmful"), which the seed paper's renderer follows (Xiang et al., section 6.1):
 *   generate primary -> trace closest -> shade -> compact -> trace shadow (any hit) -> accumulate
 *                    -> trace closest (next bounce) -> shade -> ...
 * shade writes every candidate ray of path i into fixed slots (shadow: i*shadow_per_hit + k,
 * bounce: i) with a valid flag; the compaction keeps the valid ones in slot order. So the order of
 * every batch is a pure function of the scene, never of thread timing.
 *
 * Light transport (docs/rendering.md):
 *  - Lambertian surfaces of albedo a (BRDF a/pi), or a perfect mirror tinted by a;
 *  - sphere lights: Lambertian emitters of radiant power `power` x `color`; they are not geometry in
 *    the BVH (only next-event estimation reaches them), so nothing is counted twice;
 *  - next-event estimation: shadow_per_hit rays per diffuse hit, the light chosen by power
 *    (a cumulative distribution), a uniform point on the chosen sphere;
 *  - the sky (constant or a zenith/horizon gradient) is what a path sees when its ray misses;
 *  - Russian roulette for bounce k >= rr_start: survive with probability rr_survival, weight / p.
 */
#ifndef RAYSORT_SHADE_H
#define RAYSORT_SHADE_H

#include "sampling.h"
#include "shared.h"

/* RNG dimensions within a bounce: rs_hash4(seed, pixel, sample, RS_DIM(bounce, dim)). */
#define RS_DIM_JITTER_X 0u
#define RS_DIM_JITTER_Y 1u
#define RS_DIM_BOUNCE_U1 2u
#define RS_DIM_BOUNCE_U2 3u
#define RS_DIM_ROULETTE 4u
#define RS_DIM_SHADOW_BASE 8u /* + 3 per shadow ray: light choice, u1, u2 */
#define RS_MAX_SHADOW_PER_HIT 64u /* keeps RS_DIM_SHADOW_BASE + 3k below 256 (one byte of RS_DIM) */

#define RS_PI 3.14159265358979323846f

/* A triangle in scene order (the ids hits report), 48 bytes: [v0 material | v1 pad | v2 pad]. */
typedef struct {
  float v0[3];
  rs_u32 material;
  float v1[3];
  rs_u32 pad0;
  float v2[3];
  rs_u32 pad1;
} RsShadeTriangle;

/* A material, 16 bytes: [albedo.rgb mirror]. mirror != 0: perfect mirror tinted by albedo. */
typedef struct {
  float albedo[3];
  rs_u32 mirror;
} RsMaterial;

/* A sphere light, 32 bytes: [center radius | color cdf]. radius is absolute (resolved from the
 * scene file's fraction of the largest extent); cdf = the sum of the powers of lights 0..i. */
typedef struct {
  float center[3];
  float radius;
  float color[3];
  float cdf;
} RsSphereLight;

/* What a frame's shading needs besides the arrays, 68 bytes. */
typedef struct {
  float sky_zenith[3];
  rs_u32 sky_enabled;
  float sky_horizon[3];
  rs_u32 light_count;
  float power_total;      /* sum of the lights' powers (the last cdf) */
  float rr_survival;      /* Russian roulette survival probability */
  rs_u32 rr_start;        /* first bounce that plays Russian roulette */
  rs_u32 shadow_per_hit;  /* shadow rays per diffuse hit (0 when there are no sphere lights) */
  rs_u32 max_bounces;     /* bounce batches after the primary one */
  rs_u32 seed;            /* of the counter-based RNG */
  rs_u32 spp;             /* samples per pixel of this frame (pass) */
  rs_u32 sample_begin;    /* first sample index of this pass */
  rs_u32 pixel_begin;     /* first pixel (y * width + x) of this pass: a render split into passes of rows */
} RsShadeParams;

/* A ray's path payload, 16 bytes: [weight.rgb path]. For a path ray, weight is the path
 * throughput; for a shadow ray, the radiance it adds to its path when nothing occludes it.
 * path = (pixel - pixel_begin) * spp + (sample - sample_begin): the index of the path's radiance. */
typedef struct {
  float weight[3];
  rs_u32 path;
} RsPathState;

RS_INLINE RsPathState rs_path_state(RsVec3 weight, rs_u32 path) {
  RsPathState st;
  st.weight[0] = weight.x;
  st.weight[1] = weight.y;
  st.weight[2] = weight.z;
  st.path = path;
  return st;
}

RS_INLINE rs_u32 rs_path_pixel(RsShadeParams p, rs_u32 path) { return p.pixel_begin + path / p.spp; }
RS_INLINE rs_u32 rs_path_sample(RsShadeParams p, rs_u32 path) { return p.sample_begin + path % p.spp; }

RS_INLINE float rs_random(RsShadeParams p, rs_u32 path, rs_u32 bounce, rs_u32 dim) {
  return rs_uniform(rs_hash4(p.seed, rs_path_pixel(p, path), rs_path_sample(p, path), RS_DIM(bounce, dim)));
}

/* Stage 1, generate: the primary ray of `path`, jittered within its pixel. */
RS_INLINE RsRay rs_primary_ray(RsCamera cam, RsShadeParams p, rs_u32 path) {
  rs_u32 pixel = rs_path_pixel(p, path);
  return rs_camera_ray(cam, pixel % cam.width, pixel / cam.width, rs_random(p, path, 0u, RS_DIM_JITTER_X),
                       rs_random(p, path, 0u, RS_DIM_JITTER_Y));
}

/* Sky radiance seen along unit direction d: horizon at and below y = 0, zenith straight up, linear
 * in d.y between (y is up in every scene file). */
RS_INLINE RsVec3 rs_sky_radiance(RsShadeParams p, RsVec3 d) {
  if (!p.sky_enabled) return rs_vec3(0.0f, 0.0f, 0.0f);
  float t = rs_min(1.0f, rs_max(0.0f, d.y));
  RsVec3 h = rs_load3(p.sky_horizon), z = rs_load3(p.sky_zenith);
  return rs_add(h, rs_scale(rs_sub(z, h), t));
}

RS_INLINE RsVec3 rs_mul(RsVec3 a, RsVec3 b) { return rs_vec3(a.x * b.x, a.y * b.y, a.z * b.z); }

/* Adds c to the radiance of a path (3 floats per path). Only one work-item touches a path's
 * radiance per stage, so no atomics are needed and the order of the additions is fixed. */
RS_INLINE void rs_add_radiance(RS_GLOBAL float* radiance, rs_u32 path, RsVec3 c) {
  radiance[3u * path + 0u] += c.x;
  radiance[3u * path + 1u] += c.y;
  radiance[3u * path + 2u] += c.z;
}

/* Stage 3, shade: ray i of a closest-hit batch of depth `bounce` (0 = primary) with its hit.
 * A miss adds the sky. A diffuse hit writes shadow_per_hit next-event rays into shadow slots
 * i*shadow_per_hit + k; any hit below max_bounces that survives Russian roulette writes the next
 * bounce ray into bounce slot i. Unused slots get valid = 0. */
RS_INLINE void rs_shade(RS_GLOBAL const RsShadeTriangle* tris, RS_GLOBAL const RsMaterial* materials,
                        RS_GLOBAL const RsSphereLight* lights, RsShadeParams p, rs_u32 bounce, rs_u32 i, RsRay ray,
                        RsPathState state, RsHit hit, RS_GLOBAL float* radiance, RS_GLOBAL RsRay* shadow_rays,
                        RS_GLOBAL RsPathState* shadow_states, RS_GLOBAL rs_u32* shadow_valid,
                        RS_GLOBAL RsRay* bounce_rays, RS_GLOBAL RsPathState* bounce_states,
                        RS_GLOBAL rs_u32* bounce_valid) {
  for (rs_u32 k = 0; k < p.shadow_per_hit; ++k) shadow_valid[i * p.shadow_per_hit + k] = 0u;
  bounce_valid[i] = 0u;
  RsVec3 d = rs_load3(ray.d);
  RsVec3 throughput = rs_load3(state.weight);
  if (hit.tri == RS_NO_HIT) {
    rs_add_radiance(radiance, state.path, rs_mul(throughput, rs_sky_radiance(p, d)));
    return;
  }
  RsShadeTriangle t = tris[hit.tri];
  RsVec3 v0 = rs_load3(t.v0), v1 = rs_load3(t.v1), v2 = rs_load3(t.v2);
  RsVec3 n = rs_facing_normal(v0, v1, v2, d);
  RsVec3 origin = rs_offset_ray_origin(rs_hit_point(v0, v1, v2, hit.u, hit.v), n);
  RsMaterial m = materials[t.material];
  RsVec3 albedo = rs_load3(m.albedo);

  /* Next-event estimation (diffuse hits only: a mirror's BRDF is a delta). A uniform point q on the
   * chosen sphere (area pdf 1/A), light chosen with probability power_l / total. A Lambertian sphere
   * of power P has radiance L = P color / (pi A), so the estimator
   *   (albedo/pi) L cos_s cos_l / d^2 / (power_l/total * 1/A) = albedo color total cos_s cos_l / (pi^2 d^2),
   * with cos_l = 0 for points on the far side of the sphere (their rays still exist: the batch is
   * the same whatever the light's orientation). Divided by the number of shadow rays. */
  if (!m.mirror) {
    for (rs_u32 k = 0; k < p.shadow_per_hit; ++k) {
      rs_u32 dim = RS_DIM_SHADOW_BASE + 3u * k;
      float pick = rs_random(p, state.path, bounce, dim) * p.power_total;
      rs_u32 li = 0;
      while (li + 1u < p.light_count && pick >= lights[li].cdf) ++li;
      RsSphereLight light = lights[li];
      RsVec3 s = rs_sphere_point(rs_random(p, state.path, bounce, dim + 1u), rs_random(p, state.path, bounce, dim + 2u));
      RsVec3 q = rs_add(rs_load3(light.center), rs_scale(s, light.radius));
      RsVec3 to_light = rs_sub(q, origin);
      float dist = rs_sqrt(rs_dot(to_light, to_light));
      if (!(dist > 0.0f) || rs_dot(to_light, n) <= 0.0f) continue; /* the light point is below the surface */
      RsVec3 w = rs_scale(to_light, 1.0f / dist);
      float cos_s = rs_dot(w, n);
      float cos_l = rs_max(0.0f, -rs_dot(w, s));
      float g = p.power_total * cos_s * cos_l / (RS_PI * RS_PI * dist * dist * (float)p.shadow_per_hit);
      RsVec3 c = rs_scale(rs_mul(rs_mul(throughput, albedo), rs_load3(light.color)), g);
      rs_u32 slot = i * p.shadow_per_hit + k;
      shadow_rays[slot] = rs_make_ray(origin, w, dist);
      shadow_states[slot] = rs_path_state(c, state.path);
      shadow_valid[slot] = 1u;
    }
  }

  /* The next bounce: cosine-weighted about the geometric normal (throughput x albedo: the cosine
   * and 1/pi cancel against the pdf), or the mirror direction. */
  if (bounce >= p.max_bounces) return;
  rs_u32 next = bounce + 1u;
  int roulette = next >= p.rr_start;
  if (roulette && rs_random(p, state.path, next, RS_DIM_ROULETTE) >= p.rr_survival) return;
  RsVec3 dir;
  if (m.mirror)
    dir = rs_normalize(rs_sub(d, rs_scale(n, 2.0f * rs_dot(d, n))));
  else
    dir = rs_cosine_direction(n, rs_random(p, state.path, next, RS_DIM_BOUNCE_U1),
                              rs_random(p, state.path, next, RS_DIM_BOUNCE_U2));
  RsVec3 tp = rs_mul(throughput, albedo);
  if (roulette) tp = rs_scale(tp, 1.0f / p.rr_survival);
  bounce_rays[i] = rs_make_ray(origin, dir, RS_T_FAR);
  bounce_states[i] = rs_path_state(tp, state.path);
  bounce_valid[i] = 1u;
}

/* Stage 5, accumulate: after the shadow batch is traced, path ray i adds the contribution of each
 * of its shadow rays that reached its light. dest[slot] is the slot's index in the compacted
 * shadow batch, whose hits say whether it was occluded. */
RS_INLINE void rs_accumulate_shadow(RsShadeParams p, rs_u32 i, rs_u32 path, RS_GLOBAL const rs_u32* shadow_valid,
                                    RS_GLOBAL const rs_u32* shadow_dest, RS_GLOBAL const RsPathState* shadow_states,
                                    RS_GLOBAL const RsHit* shadow_hits, RS_GLOBAL float* radiance) {
  for (rs_u32 k = 0; k < p.shadow_per_hit; ++k) {
    rs_u32 slot = i * p.shadow_per_hit + k;
    if (!shadow_valid[slot] || shadow_hits[shadow_dest[slot]].tri != RS_NO_HIT) continue;
    rs_add_radiance(radiance, path, rs_load3g(shadow_states[slot].weight));
  }
}

#endif /* RAYSORT_SHADE_H */
